"""Benchmark of mvtk.scale: campaign PSD and Monte-Carlo modal study on 1 and 2 workers.

Run on demand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_scale.py                  # ~2 GB campaign, 200 samples
    .venv/bin/python benchmarks/bench_scale.py --size-gb 0.5 --mc-samples 40

Part 1 writes a synthetic campaign (netCDF4 files of 8 channels, float64) to a temp
dir, then computes the Welch PSD of every record with :func:`mvtk.scale.psd` on a
LocalCluster of 1 and 2 worker processes (memory limit per worker below the campaign
size). It prints throughput (MB of samples per s) and the peak RSS of the workers, and
a peer ratio against scipy.signal.welch on one record held in memory. The temp dir is
removed at the end.

Part 2 runs a Monte-Carlo of a CFFF aluminium plate meshed ``--mesh`` x ``--mesh``
MITC4 elements (40 x 40 -> 9840 DOF) with scattered E and rho on 1 and 2 workers, and
the in-process path on a subset as the peer (no dask overhead).
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _summary import write_result  # noqa: E402


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _warm() -> int:
    """Import what the tasks need (spawned workers start cold); returns the worker pid."""
    import mvtk.fe  # noqa: F401
    import mvtk.scale  # noqa: F401
    import mvtk.updating  # noqa: F401

    return os.getpid()


class RssPeak:
    """Polls the RSS of some processes every 50 ms and keeps the largest value per pid."""

    def __init__(self, pids):
        import psutil

        self.procs = [psutil.Process(p) for p in pids]
        self.peak = {p.pid: 0 for p in self.procs}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            for p in self.procs:
                try:
                    self.peak[p.pid] = max(self.peak[p.pid], p.memory_info().rss)
                except Exception:  # the process ended
                    pass
            self._stop.wait(0.05)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

    @property
    def max_mb(self) -> float:
        return max(self.peak.values()) / 2**20


def write_campaign(folder: Path, size_gb: float, n_channels: int, fs: float, rng) -> list[Path]:
    import mvtk.io

    per_file = 2**22  # samples per channel: 8 ch x 4 Mi x 8 B = 256 MiB per file
    n_files = max(1, round(size_gb * 2**30 / (per_file * n_channels * 8)))
    paths = []
    for i in range(n_files):
        x = rng.standard_normal((n_channels, per_file))
        x[0] += np.sin(2 * np.pi * 37.0 * np.arange(per_file) / fs)
        th = mvtk.io.time_history(x, fs, channels=[f"a{k}" for k in range(n_channels)],
                                  units="m/s^2")
        th.attrs["t0_s"] = i * per_file / fs
        path = folder / f"rec{i:03d}.nc"
        mvtk.io.write(th, path)
        paths.append(path)
        del x, th
    return paths


def bench_psd(folder: Path, n_workers: int, memory_limit: str, nperseg: int):
    from dask.distributed import Client, LocalCluster

    import mvtk.scale

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      memory_limit=memory_limit, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        pids = list(client.run(_warm).values())
        ds = mvtk.scale.open_campaign(folder / "*.nc", chunks=2**19)
        nbytes = ds["time_history"].nbytes
        with RssPeak(pids) as rss:
            t = time.perf_counter()
            p = mvtk.scale.psd(ds, nperseg=nperseg)
            dt = time.perf_counter() - t
    return nbytes, dt, rss.max_mb, p


def bench_mc(description, n: int, n_workers: int | None, seed: int):
    import mvtk.scale

    dist = {"materials.aluminium.E": ("normal", (70e9, 2.1e9)),
            "materials.aluminium.rho": ("normal", (2700.0, 27.0))}
    rng = np.random.default_rng(seed)
    t = time.perf_counter()
    if n_workers is None:
        res = mvtk.scale.monte_carlo(description, dist, n, rng, n_modes=6)
        return time.perf_counter() - t, res, _peak_rss_mb()
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        pids = list(client.run(_warm).values())
        with RssPeak(pids) as rss:
            t = time.perf_counter()
            res = mvtk.scale.monte_carlo(description, dist, n, rng, n_modes=6, client=client)
            dt = time.perf_counter() - t
    return dt, res, rss.max_mb


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size-gb", type=float, default=2.0, help="campaign size on disk (GB)")
    ap.add_argument("--mc-samples", type=int, default=200)
    ap.add_argument("--mesh", type=int, default=40, help="elements per side of the plate")
    ap.add_argument("--memory-limit", default="1GiB", help="per-worker limit for the PSD")
    ap.add_argument("--skip-psd", action="store_true")
    ap.add_argument("--skip-mc", action="store_true")
    ap.add_argument("--quick", action="store_true", help="0.3 GB campaign, 40 samples")
    args = ap.parse_args()
    if args.quick:
        args.size_gb, args.mc_samples = min(args.size_gb, 0.3), min(args.mc_samples, 40)
    figures, ratios = {}, {}
    import scipy.signal

    import mvtk.fe
    import mvtk.io
    import mvtk.signal

    fs, nperseg = 2048.0, 4096
    if not args.skip_psd:
        folder = Path(tempfile.mkdtemp(prefix="mvtk_bench_scale_"))
        try:
            t = time.perf_counter()
            paths = write_campaign(folder, args.size_gb, 8, fs, np.random.default_rng(7))
            size = sum(p.stat().st_size for p in paths)
            print(f"campaign: {len(paths)} files, {size / 1e9:.2f} GB on disk, "
                  f"written in {time.perf_counter() - t:.1f} s")
            # peer: scipy.signal.welch on one record in memory (read + welch)
            t = time.perf_counter()
            one = mvtk.io.read(paths[0])["time_history"]
            _, ref = scipy.signal.welch(one.values, fs=fs, nperseg=nperseg, axis=-1)
            dt_peer = time.perf_counter() - t
            peer_mbs = one.nbytes / 1e6 / dt_peer
            print(f"peer scipy.signal.welch, 1 record in memory: {peer_mbs:.0f} MB/s "
                  f"(read + welch {dt_peer:.2f} s)")
            results = {}
            for w in (1, 2):
                nbytes, dt, peak, p = bench_psd(folder, w, args.memory_limit, nperseg)
                results[w] = dt
                err = np.max(np.abs(p.isel(record=0).values - ref)) / np.max(ref)
                print(f"mvtk.scale.psd, {w} worker(s) (limit {args.memory_limit}): "
                      f"{nbytes / 1e6 / dt:.0f} MB/s ({nbytes / 1e9:.2f} GB in {dt:.1f} s), "
                      f"peak RSS per worker {peak:.0f} MB, ratio vs peer "
                      f"{nbytes / 1e6 / dt / peer_mbs:.2f}, max rel diff record 0 vs scipy "
                      f"{err:.1e}")
            print(f"PSD speed-up 2 vs 1 worker: {results[1] / results[2]:.2f}")
            figures.update(psd_gb=nbytes / 1e9, psd_1_worker_s=results[1],
                           psd_2_workers_s=results[2], peer_welch_mb_s=peer_mbs)
            ratios["psd_2_workers_over_peer_throughput"] = nbytes / 1e6 / results[2] / peer_mbs
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    if not args.skip_mc:
        desc = mvtk.fe.load_structure(ROOT / "data" / "structures" / "plate.toml")
        desc = mvtk.fe.set_by_path(desc, "mesh.nx", args.mesh)
        desc = mvtk.fe.set_by_path(desc, "mesh.ny", args.mesh)
        n_dof = mvtk.fe.build_model(desc).n_dof
        n_peer = max(2, args.mc_samples // 10)
        dt0, _, peak0 = bench_mc(desc, n_peer, None, 1)
        print(f"Monte Carlo, plate {args.mesh}x{args.mesh} ({n_dof} DOF): in-process peer "
              f"{n_peer / dt0:.2f} samples/s ({n_peer} samples in {dt0:.1f} s, "
              f"peak RSS of this process {peak0:.0f} MB)")
        times = {}
        for w in (1, 2):
            dt, res, peak = bench_mc(desc, args.mc_samples, w, 2)
            times[w] = dt
            tab = res.to_dataframe()
            print(f"  {w} worker(s): {args.mc_samples / dt:.2f} samples/s "
                  f"({args.mc_samples} in {dt:.1f} s), ratio vs in-process "
                  f"{args.mc_samples / dt / (n_peer / dt0):.2f}, "
                  f"peak RSS per worker {peak:.0f} MB, "
                  f"f1 mean {tab.mean_hz[0]:.3f} Hz CoV {tab['cov'][0]:.4f}")
        print(f"Monte Carlo speed-up 2 vs 1 worker: {times[1] / times[2]:.2f}")
        figures.update(mc_n_dof=n_dof, mc_samples=args.mc_samples,
                       mc_in_process_samples_per_s=n_peer / dt0,
                       mc_1_worker_s=times[1], mc_2_workers_s=times[2])
        ratios["mc_2_workers_over_in_process"] = args.mc_samples / times[2] / (n_peer / dt0)
        # f ~ sqrt(E / rho): first-order CoV(f) = sqrt((CoV_E / 2)^2 + (CoV_rho / 2)^2)
        print(f"closed-form first-order CoV(f): {np.hypot(0.03 / 2, 0.01 / 2):.4f}")
    write_result("scale", {"figures": figures,
                           "peer": "scipy.signal.welch in memory; in-process Monte Carlo",
                           "ratios": ratios})


if __name__ == "__main__":
    main()
