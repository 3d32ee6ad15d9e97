# ruff: noqa: UP031  (UFF records are fixed-width Fortran formats)
"""Read throughput of mvtk.io against its peers, in one run.

1. CSV: a DAQ-style export (metadata lines, time column, units in the header) of
   16 channels x 10 min x 10 kHz (96 M samples, ~1.2 GB of text) read by
   ``mvtk.io.read`` and by ``pandas.read_csv`` (C parser) on the same file.
2. LVM: a LabVIEW Measurement file (tabs, decimal commas) read by ``mvtk.io.read`` and
   by ``pandas.read_csv`` with the header lines skipped.
3. UFF 58b: 16 binary float64 records read by ``mvtk.io.read`` and by plain
   ``pyuff.UFF(path).read_sets()``.

Every read runs in a fresh subprocess so its peak resident memory (ru_maxrss minus the
resident size after imports) is its own. Targets (issue 2): CSV within 1.2x of pandas
and peak memory under 2x the data size; UFF overhead under 1.2x.

Usage::

    .venv/bin/python benchmarks/bench_io.py                # the full 10-minute file
    .venv/bin/python benchmarks/bench_io.py --minutes 1    # a quicker look
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HEADER_LINES = 2  # metadata lines before the column-name line


def rss_mb() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def worker(kind: str, path: str) -> None:
    """Run one read in this process and print JSON with time and memory."""
    import pandas as pd  # noqa: F401  (imports outside the timed region)
    import pyuff

    import mvtk.io

    # warm-up: first-use costs (xarray imports dask on its first array, lazy imports in
    # pandas and pyuff) are paid by both sides before the timed read
    with tempfile.TemporaryDirectory() as tmp:
        small_csv, small_uff = Path(tmp) / "w.csv", Path(tmp) / "w.uff"
        write_csv(small_csv, 2, 100.0, 50, np.random.default_rng(0))
        write_uff58b(small_uff, 2, 50, 100.0, np.random.default_rng(0))
        mvtk.io.read(small_csv)
        pd.read_csv(small_csv, skiprows=HEADER_LINES, header=0)
        mvtk.io.read(small_uff)
        pyuff.UFF(str(small_uff)).read_sets()
    base = rss_mb()
    t0 = time.perf_counter()
    c0 = time.process_time()
    if kind == "csv-mvtk":
        ds = mvtk.io.read(path)
        n = ds["time_history"].size
    elif kind == "csv-pandas":
        df = pd.read_csv(path, skiprows=HEADER_LINES, header=0, engine="c")
        n = df.shape[0] * (df.shape[1] - 1)
    elif kind == "lvm-mvtk":
        ds = mvtk.io.read(path)
        n = ds["time_history"].size
    elif kind == "lvm-pandas":
        df = pd.read_csv(
            path, sep="\t", decimal=",", skiprows=LVM_HEADER_LINES, header=None, engine="c"
        )
        n = df.shape[0] * (df.shape[1] - 1)
    elif kind == "uff-mvtk":
        ds = mvtk.io.read(path)
        n = ds["time_history"].size
    elif kind == "uff-pyuff":
        sets = pyuff.UFF(path).read_sets()
        n = sum(s["data"].size for s in sets)
    else:
        raise SystemExit(f"unknown worker {kind}")
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - c0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps({"seconds": seconds, "cpu": cpu, "samples": n, "peak_mb": peak - base}))


def run(kind: str, path: Path) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, "--worker", kind, str(path)],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def write_csv(path: Path, n_ch: int, fs: float, n: int, rng: np.random.Generator) -> None:
    names = ",".join(f"acc{k + 1:02d} [m/s^2]" for k in range(n_ch))
    chunk = 200_000
    with open(path, "w") as fh:
        fh.write(f"# instrument: mvtk benchmark\n# sample rate: {fs:g} Hz\ntime [s],{names}\n")
        fmt = ",".join(["%.4f"] + ["%.6g"] * n_ch)
        for start in range(0, n, chunk):
            m = min(chunk, n - start)
            block = np.empty((m, n_ch + 1))
            block[:, 0] = (start + np.arange(m)) / fs
            block[:, 1:] = rng.standard_normal((m, n_ch))
            np.savetxt(fh, block, fmt=fmt)


LVM_HEADER_LINES = 23  # file header, blank line, segment header, column names


def write_lvm(path: Path, n_ch: int, fs: float, n: int, rng: np.random.Generator) -> None:
    """LabVIEW Measurement file as LabVIEW writes it: tabs, decimal commas, empty X column."""
    t = "\t"
    head = [
        "LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
        "Decimal_Separator\t,", "Multi_Headings\tYes", "X_Columns\tNo", "Time_Pref\tAbsolute",
        "Operator\tbench", "Date\t2026/01/01", "Time\t10:00:00", "***End_of_Header***\t", "\t",
        t.join(["Channels", str(n_ch)]) + t,
        t.join(["Samples"] + [str(n)] * n_ch) + t,
        t.join(["Date"] + ["2026/01/01"] * n_ch) + t,
        t.join(["Time"] + ["10:00:00"] * n_ch) + t,
        t.join(["Y_Unit_Label"] + ["g"] * n_ch) + t,
        t.join(["X_Dimension"] + ["Time"] * n_ch) + t,
        t.join(["X0"] + ["0,0000000000000000E+0"] * n_ch) + t,
        t.join(["Delta_X"] + [f"{1 / fs:.6E}".replace(".", ",")] * n_ch) + t,
        "***End_of_Header***" + t * (n_ch + 1),
        t.join(["X_Value"] + [f"acc{k + 1:02d}" for k in range(n_ch)] + ["Comment"]),
    ]
    assert len(head) == LVM_HEADER_LINES
    chunk = 200_000
    with open(path, "w") as fh:
        fh.write("\n".join(head) + "\n")
        for start in range(0, n, chunk):
            m = min(chunk, n - start)
            block = rng.standard_normal((m, n_ch))
            text = "\n".join(
                "\t" + "\t".join(f"{v:.6f}" for v in row) for row in block
            ).replace(".", ",")
            fh.write(text + "\n")


def write_uff58b(path: Path, n_rec: int, n: int, fs: float, rng: np.random.Generator) -> None:
    with open(path, "wb") as fh:
        for k in range(n_rec):
            payload = rng.standard_normal(n).astype("<f8").tobytes()
            head = [
                "    -1",
                "    58b     1     2          11%12i     0     0           0           0"
                % len(payload),
                f"acc{k + 1:02d}",
                "NONE",
                "NONE",
                "NONE",
                "NONE",
                "    1         0    0         0 acc%02d    %10i   3 NONE               0   0"
                % (k + 1, k + 1),
                "         4%10i         1  0.00000E+00%13.5e  0.00000E+00" % (n, 1 / fs),
                "        17    0    0    0 Time                 s                   ",
                "        12    0    0    0 Acceleration         m/s2                ",
                "         0    0    0    0 NONE                 NONE                ",
                "         0    0    0    0 NONE                 NONE                ",
            ]
            fh.write(("\n".join(head) + "\n").encode() + payload + b"\n    -1\n")


def best_pair(kind_a: str, kind_b: str, path: Path, repeats: int) -> tuple[dict, dict]:
    """Alternate the two readers ``repeats`` times; keep each one's fastest run."""
    runs: dict[str, list[dict]] = {kind_a: [], kind_b: []}
    for _ in range(repeats):
        for kind in (kind_a, kind_b):
            runs[kind].append(run(kind, path))
    out = []
    for kind in (kind_a, kind_b):
        res = runs[kind]
        out.append(
            {
                "seconds": min(r["seconds"] for r in res),
                "cpu": min(r["cpu"] for r in res),
                "samples": res[0]["samples"],
                "peak_mb": max(r["peak_mb"] for r in res),
            }
        )
    return out[0], out[1]


def report(label: str, r: dict, data_mb: float | None = None) -> None:
    line = (
        f"  {label:16s} wall {r['seconds']:7.2f} s  cpu {r['cpu']:7.2f} s  "
        f"{r['samples'] / r['seconds'] / 1e6:6.2f} M samples/s (wall)  peak +{r['peak_mb']:.0f} MiB"
    )
    if data_mb:
        line += f" ({r['peak_mb'] / data_mb:.2f}x data)"
    print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--channels", type=int, default=16)
    parser.add_argument("--fs", type=float, default=10_000.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--uff-samples", type=int, default=1_000_000)
    parser.add_argument("--worker", nargs=2, metavar=("KIND", "PATH"))
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker)
        return
    rng = np.random.default_rng(20261122)
    n = int(round(args.minutes * 60 * args.fs))
    with tempfile.TemporaryDirectory(prefix="mvtk-bench-") as tmp:
        csv = Path(tmp) / "big.csv"
        t0 = time.perf_counter()
        write_csv(csv, args.channels, args.fs, n, rng)
        size_mb = os.path.getsize(csv) / 2**20
        data_mb = args.channels * n * 8 / 2**20
        print(
            f"CSV: {args.channels} ch x {n} samples ({args.minutes:g} min at {args.fs:g} Hz), "
            f"{size_mb:.0f} MiB of text, {data_mb:.0f} MiB as float64 "
            f"(written in {time.perf_counter() - t0:.0f} s)"
        )
        m, p = best_pair("csv-mvtk", "csv-pandas", csv, args.repeats)
        report("mvtk.io.read", m, data_mb)
        report("pandas.read_csv", p, data_mb)
        print(
            f"  ratio mvtk/pandas: wall {m['seconds'] / p['seconds']:.3f}, "
            f"cpu {m['cpu'] / p['cpu']:.3f} (target <= 1.2)"
        )
        csv.unlink()

        lvm = Path(tmp) / "big.lvm"
        n_lvm = n // 4
        write_lvm(lvm, 4, args.fs, n_lvm, rng)
        print(
            f"LVM: 4 ch x {n_lvm} samples, decimal commas "
            f"({os.path.getsize(lvm) / 2**20:.0f} MiB of text)"
        )
        m, p = best_pair("lvm-mvtk", "lvm-pandas", lvm, args.repeats)
        report("mvtk.io.read", m)
        report("pandas.read_csv", p)
        print(
            f"  ratio mvtk/pandas: wall {m['seconds'] / p['seconds']:.3f}, "
            f"cpu {m['cpu'] / p['cpu']:.3f}"
        )
        lvm.unlink()

        uff = Path(tmp) / "big.uff"
        write_uff58b(uff, args.channels, args.uff_samples, args.fs, rng)
        print(
            f"UFF 58b: {args.channels} records x {args.uff_samples} float64 samples "
            f"({os.path.getsize(uff) / 2**20:.0f} MiB)"
        )
        m, p = best_pair("uff-mvtk", "uff-pyuff", uff, args.repeats)
        report("mvtk.io.read", m)
        report("pyuff read_sets", p)
        print(
            f"  ratio mvtk/pyuff: wall {m['seconds'] / p['seconds']:.3f}, "
            f"cpu {m['cpu'] / p['cpu']:.3f} (target <= 1.2)"
        )


if __name__ == "__main__":
    main()
