# ruff: noqa: UP031  (UFF records are fixed-width Fortran formats)
"""Read throughput of mvtk.io against its peers, in one run.

1. CSV: a DAQ-style export (metadata lines, time column, units in the header) of
   16 channels x 10 min x 10 kHz (96 M samples, ~1.2 GB of text) read by
   ``mvtk.io.read`` and by ``pandas.read_csv`` (C parser) on the same file.
2. LVM: a LabVIEW Measurement file (tabs, decimal commas) of the same size (16 channels x
   10 min x 10 kHz) read by ``mvtk.io.read`` and by ``pandas.read_csv`` with the header
   lines skipped.
3. UFF 58b: 16 binary float64 records read by ``mvtk.io.read`` and by plain
   ``pyuff.UFF(path).read_sets()``.

Every read runs in a fresh subprocess so its peak resident memory (ru_maxrss minus the
resident size after imports) is its own; the two readers of a pair alternate, and each
one's wall and CPU time (all threads) are kept beside the machine's load average.
Targets: CSV and LVM within 1.2x of pandas (wall and CPU), peak memory under 1.5x the
data size; UFF overhead under 1.2x.

Usage::

    .venv/bin/python benchmarks/bench_io.py                # the full 10-minute file
    .venv/bin/python benchmarks/bench_io.py --minutes 1    # a quicker look
    .venv/bin/python benchmarks/bench_io.py --only lvm     # one format
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
        small_lvm = Path(tmp) / "w.lvm"
        write_lvm(small_lvm, 2, 100.0, 50, np.random.default_rng(0))
        mvtk.io.read(small_lvm)
        pd.read_csv(small_lvm, sep="\t", decimal=",", skiprows=LVM_HEADER_LINES, header=None)
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
            fh.write(_lvm_lines(rng.standard_normal((m, n_ch))))


def _lvm_lines(block: np.ndarray) -> str:
    """Data lines ``\\t-0,123456\\t1,234567...`` of ``block`` (rows), as LabVIEW writes
    them with 6 decimals and decimal commas (values clipped to |v| < 10), built with
    array arithmetic (formatting a 10-minute record value by value takes minutes)."""
    m, n_ch = block.shape
    q = np.rint(np.clip(np.abs(block), 0, 9.999999) * 1e6).astype(np.int64)
    neg = (block < 0) & (q > 0)
    # per value: tab, sign (0 byte = none, removed below), digit, comma, 6 decimals
    out = np.zeros((m, n_ch, 10), dtype=np.uint8)
    out[:, :, 0] = ord("\t")
    out[:, :, 1] = np.where(neg, ord("-"), 0)
    out[:, :, 2] = ord("0") + q // 1_000_000
    out[:, :, 3] = ord(",")
    for k in range(6):
        out[:, :, 9 - k] = ord("0") + (q // 10**k) % 10
    lines = np.concatenate(
        [out.reshape(m, n_ch * 10), np.full((m, 1), ord("\n"), dtype=np.uint8)], axis=1
    ).ravel()
    return lines[lines != 0].tobytes().decode("ascii")


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


def pair(name: str, kinds: tuple[str, str], labels: tuple[str, str], path: Path,
         repeats: int, data_mb: float, out: dict) -> None:
    """Run one mvtk/peer pair, print it and keep its figures and ratios in ``out``."""
    m, p = best_pair(*kinds, path, repeats)
    report(labels[0], m, data_mb)
    report(labels[1], p, data_mb)
    wall, cpu = m["seconds"] / p["seconds"], m["cpu"] / p["cpu"]
    print(f"  ratio mvtk/{labels[1].split('.')[0].split()[0]}: wall {wall:.3f}, cpu {cpu:.3f} "
          f"(target <= 1.2)  [load {os.getloadavg()[0]:.2f}]")
    for who, r in (("mvtk", m), ("peer", p)):
        out["figures"][f"{name}_{who}_wall_s"] = r["seconds"]
        out["figures"][f"{name}_{who}_cpu_s"] = r["cpu"]
        out["figures"][f"{name}_{who}_peak_mib"] = r["peak_mb"]
        out["figures"][f"{name}_{who}_peak_x_data"] = r["peak_mb"] / data_mb
    out["figures"][f"{name}_load_avg_1min"] = os.getloadavg()[0]
    out["ratios"][f"{name}_mvtk_over_peer_wall"] = wall
    out["ratios"][f"{name}_mvtk_over_peer_cpu"] = cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--channels", type=int, default=16)
    parser.add_argument("--fs", type=float, default=10_000.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--uff-samples", type=int, default=1_000_000)
    parser.add_argument("--only", default="csv,lvm,uff", help="formats, comma-separated")
    parser.add_argument("--quick", action="store_true", help="1 minute instead of 10")
    parser.add_argument("--worker", nargs=2, metavar=("KIND", "PATH"))
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker)
        return
    if args.quick:
        args.minutes = min(args.minutes, 1.0)
    only = {x.strip() for x in args.only.split(",")}
    out: dict = {"figures": {}, "ratios": {}, "peer": "pandas.read_csv (C parser), pyuff"}
    rng = np.random.default_rng(20261122)
    n = int(round(args.minutes * 60 * args.fs))
    data_mb = args.channels * n * 8 / 2**20
    with tempfile.TemporaryDirectory(prefix="mvtk-bench-") as tmp:
        if "csv" in only:
            csv = Path(tmp) / "big.csv"
            t0 = time.perf_counter()
            write_csv(csv, args.channels, args.fs, n, rng)
            print(
                f"CSV: {args.channels} ch x {n} samples ({args.minutes:g} min at {args.fs:g} "
                f"Hz), {os.path.getsize(csv) / 2**20:.0f} MiB of text, {data_mb:.0f} MiB as "
                f"float64 (written in {time.perf_counter() - t0:.0f} s)"
            )
            pair("csv", ("csv-mvtk", "csv-pandas"), ("mvtk.io.read", "pandas.read_csv"), csv,
                 args.repeats, data_mb, out)
            csv.unlink()
        if "lvm" in only:
            lvm = Path(tmp) / "big.lvm"
            t0 = time.perf_counter()
            write_lvm(lvm, args.channels, args.fs, n, rng)
            print(
                f"LVM: {args.channels} ch x {n} samples, decimal commas "
                f"({os.path.getsize(lvm) / 2**20:.0f} MiB of text, {data_mb:.0f} MiB as "
                f"float64, written in {time.perf_counter() - t0:.0f} s)"
            )
            pair("lvm", ("lvm-mvtk", "lvm-pandas"), ("mvtk.io.read", "pandas.read_csv"), lvm,
                 args.repeats, data_mb, out)
            lvm.unlink()
        if "uff" in only:
            uff = Path(tmp) / "big.uff"
            write_uff58b(uff, args.channels, args.uff_samples, args.fs, rng)
            print(
                f"UFF 58b: {args.channels} records x {args.uff_samples} float64 samples "
                f"({os.path.getsize(uff) / 2**20:.0f} MiB)"
            )
            pair("uff", ("uff-mvtk", "uff-pyuff"), ("mvtk.io.read", "pyuff read_sets"), uff,
                 args.repeats, args.channels * args.uff_samples * 8 / 2**20, out)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _summary import write_result

    write_result("io", out)


if __name__ == "__main__":
    main()
