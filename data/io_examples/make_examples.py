"""Write the small example measurement files in this folder (seeded; rerun to reproduce).

Each file holds the same two-channel free decay of a 12.5 Hz mode (an accelerometer in
m/s^2 and a force in N) sampled at 512 Hz for 0.25 s, in one format mvtk reads:

    daq_export.csv            comma-separated, metadata lines, time column, units in []
    daq_export_de.csv         semicolon + decimal comma, sample-rate header, units row
    accel_58.uff              UFF 58 ASCII, two records
    accel_58b.uff             UFF 58b binary (little-endian float64), two records
    matlab_v5.mat             MAT v5: 'y' (n x 2) and 'fs'
    recording.wav             16-bit PCM, calibration 1e-3 (m/s^2, N) per count
    example.nc                mvtk.io.write output

Usage: ``.venv/bin/python data/io_examples/make_examples.py``
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

SEED = 20261122
FS = 512.0
N = 128
HERE = Path(__file__).resolve().parent


def signals() -> np.ndarray:
    """The (2, N) example signals: acceleration [m/s^2] and force [N]."""
    rng = np.random.default_rng(SEED)
    t = np.arange(N) / FS
    acc = np.exp(-2.0 * t) * np.sin(2 * np.pi * 12.5 * t) + 0.01 * rng.standard_normal(N)
    force = 0.5 * np.exp(-40.0 * t) + 0.005 * rng.standard_normal(N)
    return np.round(np.vstack([acc, force]), 6)


def _uff_header(name: str, units: str, spec: int, node: int) -> list[str]:
    return [
        name,
        "NONE",
        "22-Nov-26 00:00:00",
        "NONE",
        "NONE",
        f"    1         0    0         0 {name:>10s}{node:10d}   3 NONE               0   0",
        f"         4{N:10d}         1  0.00000E+00{1 / FS:13.5e}  0.00000E+00",
        "        17    0    0    0 Time                 s                   ",
        f"{spec:10d}    0    0    0 {'Response':20s} {units:20s}",
        "         0    0    0    0 NONE                 NONE                ",
        "         0    0    0    0 NONE                 NONE                ",
    ]


def main() -> None:
    x = signals()
    t = np.arange(N) / FS
    rows = "\n".join(f"{t[k]:.9f},{x[0, k]:.6f},{x[1, k]:.6f}" for k in range(N))
    (HERE / "daq_export.csv").write_text(
        "# instrument: example DAQ\n# operator: mvtk\n"
        "time [s],acc_tip [m/s^2],force_hammer [N]\n" + rows + "\n"
    )
    rows = "\n".join(f"{x[0, k]:.6f};{x[1, k]:.6f}".replace(".", ",") for k in range(N))
    (HERE / "daq_export_de.csv").write_text(
        "Messung;Beispiel\nsample rate;512 Hz\nacc_tip;force_hammer\nm/s^2;N\n" + rows + "\n"
    )
    ascii_records, binary_records = [], b""
    for k, (name, units, spec) in enumerate((("acc_tip", "m/s2", 12), ("force", "N", 13))):
        head = _uff_header(name, units, spec, node=k + 1)
        lines = ["    -1", "    58", *head]
        for j in range(0, N, 4):
            lines.append("".join(f"{v:20.11e}" for v in x[k, j : j + 4]))
        lines.append("    -1")
        ascii_records.append("\n".join(lines))
        payload = struct.pack(f"<{N}d", *x[k])
        desc = (
            f"    58b     1     2          11{len(payload):12d}     0     0           0           0"
        )
        binary_records += ("\n".join(["    -1", desc, *head]) + "\n").encode()
        binary_records += payload + b"\n    -1\n"
    (HERE / "accel_58.uff").write_text("\n".join(ascii_records) + "\n")
    (HERE / "accel_58b.uff").write_bytes(binary_records)

    import scipy.io
    import scipy.io.wavfile

    scipy.io.savemat(HERE / "matlab_v5.mat", {"y": x.T, "fs": FS})
    counts = np.round(x / 1e-3).astype(np.int16)
    scipy.io.wavfile.write(HERE / "recording.wav", int(FS), counts.T.copy())

    import mvtk.io

    da = mvtk.io.time_history(
        x,
        FS,
        ["acc_tip", "force_hammer"],
        ["m/s^2", "N"],
        node=[1, 1],
        direction=["z", "-z"],
        attrs={"instrument": "example DAQ"},
    )
    mvtk.io.write(da, HERE / "example.nc")


if __name__ == "__main__":
    main()
