"""Benchmark of mvtk.signal / mvtk.damping (run on demand, not in the test suite).

    .venv/bin/python benchmarks/bench_damping.py            # full: 64 ch x 10 min x 10 kHz
    .venv/bin/python benchmarks/bench_damping.py --quick    # 8 ch x 1 min, for a smoke run

Part 1 times PSD (Welch) and H1 FRF + coherence through mvtk against raw
scipy.signal.welch / scipy.signal.csd on the same data in the same run, channel block by
channel block (so memory stays bounded), and prints the mvtk/scipy time ratio.
Part 2 prints the accuracy table of the damping estimators on seeded synthetic data with
known fn and zeta.
Part 3 (issue 14) compares the default choices: the old fixed 256-sample FRF default
against the data-driven one and the two half-power variants ("fit", now the default,
and "interpolate") on real files of ../shared/data (when present) and on simulated
12-average H1 measurements, and prints the calibration of the "noisy" flag.

    .venv/bin/python benchmarks/bench_damping.py --skip-speed --skip-accuracy   # part 3
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.signal

from mvtk import testing as T
from mvtk.damping import envelope_fit, half_power, log_decrement
from mvtk.signal import frf, psd


def bench_speed(n_channels: int, minutes: float, fs: float, block: int, nperseg: int) -> None:
    n = int(minutes * 60 * fs)
    rng = np.random.default_rng(1)
    force = rng.standard_normal(n)
    t_mvtk = {"psd": 0.0, "frf": 0.0}
    t_scipy = {"psd": 0.0, "frf": 0.0}
    max_dev = {"psd": 0.0, "frf": 0.0}
    done = 0
    while done < n_channels:
        nb = min(block, n_channels - done)
        # responses: force filtered by a second-order section + independent noise
        b, a = scipy.signal.iirpeak(200.0 + 10 * done, 30.0, fs=fs)
        y = scipy.signal.lfilter(b, a, force)[None, :] + 0.1 * rng.standard_normal((nb, n))
        data = np.vstack([force[None, :], y])
        x = T.make_time_history(data, fs, quantity=["force"] + ["acceleration"] * nb,
                                units=["N"] + ["m/s^2"] * nb,
                                names=["force"] + [f"a{done + i}" for i in range(nb)])
        # PSD of every channel; the call order alternates between blocks so that cache
        # and load effects do not favour one side
        first_mvtk = (done // block) % 2 == 0
        for side in (("mvtk", "scipy") if first_mvtk else ("scipy", "mvtk")):
            t0 = time.perf_counter()
            if side == "mvtk":
                p = psd(x, nperseg=nperseg)
            else:
                _, pref = scipy.signal.welch(data, fs=fs, nperseg=nperseg)
            (t_mvtk if side == "mvtk" else t_scipy)["psd"] += time.perf_counter() - t0
        max_dev["psd"] = max(max_dev["psd"], float(np.max(np.abs(p.values - pref) / pref.max())))
        # H1 FRF with coherence (force reference, nb responses)
        for side in (("mvtk", "scipy") if first_mvtk else ("scipy", "mvtk")):
            t0 = time.perf_counter()
            if side == "mvtk":
                d = frf(x, "force", nperseg=nperseg, window="hann")
            else:
                _, pff = scipy.signal.welch(force, fs=fs, nperseg=nperseg)
                _, pfy = scipy.signal.csd(force[None, :], y, fs=fs, nperseg=nperseg)
                _, pyy = scipy.signal.welch(y, fs=fs, nperseg=nperseg)
                h1 = pfy / pff
                coh = np.abs(pfy) ** 2 / (pff * pyy)
            (t_mvtk if side == "mvtk" else t_scipy)["frf"] += time.perf_counter() - t0
        dev = np.nanmax(np.abs(d["frf"].values[:, 0, 1:] - h1[:, 1:]) / np.abs(h1[:, 1:]))
        dev = max(dev, float(np.nanmax(np.abs(d["coherence"].values[:, 0, 1:] - coh[:, 1:]))))
        max_dev["frf"] = max(max_dev["frf"], float(dev))
        done += nb
        print(f"  block done: {done}/{n_channels} channels", flush=True)
        del data, y, x, p, pref, d, pfy, pyy
    print(f"speed: {n_channels} channels x {minutes:g} min x {fs:g} Hz = {n} samples/channel, "
          f"nperseg={nperseg}, blocks of {block} channels (+ force)")
    print(f"{'operation':<22}{'mvtk [s]':>10}{'scipy [s]':>11}{'ratio':>8}{'max rel dev':>14}")
    for key, label in (("psd", "PSD (Welch)"), ("frf", "H1 FRF + coherence")):
        ratio = t_mvtk[key] / t_scipy[key]
        print(f"{label:<22}{t_mvtk[key]:>10.2f}{t_scipy[key]:>11.2f}{ratio:>8.2f}"
              f"{max_dev[key]:>14.1e}")


def _row(name, cond, errs):
    errs = np.asarray(errs, dtype=float)
    ok = np.isfinite(errs)
    rms = np.sqrt(np.mean(errs[ok] ** 2)) * 100 if ok.any() else np.nan
    mx = np.max(np.abs(errs[ok])) * 100 if ok.any() else np.nan
    print(f"{name:<34}{cond:<34}{rms:>8.2f}{mx:>8.2f}{(~ok).sum():>6d}")


def bench_accuracy(reps: int) -> None:
    print("\naccuracy: zeta error in % of the true zeta (RMS and max over seeds; "
          "'nan' = no estimate)")
    print(f"{'estimator':<34}{'condition':<34}{'rms %':>8}{'max %':>8}{'fail':>6}")
    warnings.simplefilter("ignore")
    fn = 50.0
    for method in ("interpolate", "fit"):
        for zeta in (5e-4, 5e-3, 5e-2):
            for lines in (5, 20):
                for noise in (0.0, 0.01, 0.05):
                    rng = np.random.default_rng(3)
                    df = 2 * zeta * fn / lines
                    f = np.arange(max(fn * (1 - 40 * zeta), df), fn * (1 + 40 * zeta), df)
                    h0 = T.modal_frf(f, fn, zeta, kind="accelerance").values[0, 0]
                    errs = []
                    for _ in range(reps):
                        nz = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
                        h = h0 * (1 + noise * nz / np.sqrt(2))
                        r = half_power(h, f, fn_hz=[fn], kind="accelerance", method=method)
                        errs.append(r.zeta[0] / zeta - 1)
                    _row(f"half_power({method})",
                         f"z={zeta:.2%} {lines:>2} lines noise {noise:.0%}", errs)
    # H1 from a random test with output noise, then half-power (Hann leakage included)
    for zeta in (5e-3, 2e-2):
        for noise in (0.0, 0.05):
            errs = []
            for seed in range(max(reps // 5, 2)):
                rng = np.random.default_rng(seed)
                nps = int(2 ** np.ceil(np.log2(256.0 * 10 / (2 * zeta * fn))))  # >= 10 lines
                x = T.random_excitation_test(fn, zeta, 256.0, 40 * nps / 256.0, rng)
                if noise:
                    resp = T.add_noise(x.isel(channel=[1]), rng, rms_fraction=noise)
                    x = x.copy(data=np.vstack([x.values[0], resp.values[0]]))
                d = frf(x, "force", nperseg=nps)
                r = half_power(d, fn_hz=[fn])
                errs.append(r.zeta[0] / zeta - 1)
            _row("H1 (Hann, 79 avg) + half_power", f"z={zeta:.2%} >=10 lines noise {noise:.0%}",
                 errs)
    for est in (log_decrement, envelope_fit):
        for zeta in (5e-4, 2e-3, 1e-2, 5e-2):
            for snr in (None, 40.0):
                errs = []
                for seed in range(reps):
                    rng = np.random.default_rng(seed)
                    dur = min(4.5 / (zeta * 2 * np.pi * 13.26), 600.0)
                    x = T.sdof_free_decay(13.26, zeta, 256.0, dur, phase=0.3)
                    if snr is not None:
                        x = T.add_noise(x, rng, snr_db=snr)
                    errs.append(est(x).zeta[0] / zeta - 1)
                cond = f"SDOF z={zeta:.2%} SNR {'inf' if snr is None else f'{snr:g} dB'}"
                _row(est.__name__, cond, errs)
        for zeta in (5e-4, 2e-3, 1e-2, 5e-2):
            errs = []
            for seed in range(reps):
                rng = np.random.default_rng(seed)
                dur = min(4.5 / (zeta * 2 * np.pi * 13.26), 600.0)
                x = T.mdof_free_decay([13.26, 41.14], [zeta, zeta], 256.0, dur,
                                      amplitudes=[1.0, 0.5])
                x = T.add_noise(x, rng, snr_db=40.0)
                errs.append(est(x, fn_hz=13.26).zeta[0] / zeta - 1)
            _row(est.__name__, f"2 modes band-pass z={zeta:.2%} 40 dB", errs)


SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _lvm(path: Path):
    lines = path.read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("X_Value"))
    rows = [line.split("\t")[1:3] for line in lines[i + 1:] if line.strip()]
    data = np.array([[float(v.replace(",", ".")) for v in r] for r in rows]).T
    return T.make_time_history(data, 50000.0, quantity=["acceleration", "force"],
                               units=["g", "N"], names=["acc", "force"])


def bench_defaults(reps: int, shared: Path) -> None:
    warnings.simplefilter("ignore")
    print("\ndefaults on real files: zeta by estimator setting (expert = envelope fit of the "
          "decay band-passed +-10 % around the mode, 4th-order Butterworth)")
    print(f"{'file':<18}{'fn Hz':>8}{'expert':>10}{'old 256':>10}{'fit':>10}{'interp':>10}"
          f"{'fit err':>9}{'interp err':>11}")
    cases = []
    for name in ("acceleration", "camera"):
        if (shared / "lvm" / f"{name}.lvm").is_file():
            cases.append((f"{name}.lvm", _lvm(shared / "lvm" / f"{name}.lvm"), "force", "acc",
                          [695.7, 1898.1, 3671.0]))
    if (shared / "mat" / "case1.mat").is_file():
        import scipy.io

        m = scipy.io.loadmat(shared / "mat" / "case1.mat")
        x = T.make_time_history(np.vstack([m["Time_chan_1"].ravel(), m["Time_chan_2"].ravel()])
                                .astype(float), 1280.0, quantity=["force", "acceleration"],
                                units=["N", "m/s^2"], names=["force", "acc"])
        cases.append(("case1.mat", x, "force", "acc", [212.1]))
    if not cases:
        print(f"  (no files: {shared} not found)")
    for label, x, ref, resp, fns in cases:
        old = half_power(frf(x, ref, nperseg=256, excitation="random"), fn_hz=fns,
                         method="interpolate")
        new = {m: half_power(frf(x, ref), fn_hz=fns, method=m) for m in ("fit", "interpolate")}
        for k, fn in enumerate(fns):
            ex = envelope_fit(x, fn, channel=resp, band_hz=(0.9 * fn, 1.1 * fn), order=4).zeta[0]
            zf, zi = new["fit"].zeta[k], new["interpolate"].zeta[k]
            print(f"{label:<18}{fn:>8.1f}{ex:>10.3e}{old.zeta[k]:>10.3e}{zf:>10.3e}{zi:>10.3e}"
                  f"{(zf / ex - 1) * 100:>8.1f}%{(zi / ex - 1) * 100:>10.1f}%")
    print("\nhalf-power variants on simulated H1 (Hann, 8192-sample segments, 2 modes "
          "20/55 Hz, zeta 1 %/0.5 %): zeta error % (RMS over seeds) and the scatter that "
          "drives the 'noisy' flag (max_scatter = 5 %)")
    print(f"{'averages':>9}{'noise':>7}{'fit rms %':>11}{'interp rms %':>14}"
          f"{'scatter min..max':>20}{'flagged':>9}")
    for n_avg in (2, 4, 12):
        for noise in (0.05, 0.3):
            err = {"fit": [], "interpolate": []}
            sc = []
            for seed in range(max(reps // 2, 3)):
                rng = np.random.default_rng(100 + seed)
                x = T.random_excitation_test([20.0, 55.0], [0.01, 0.005], 512.0,
                                             8192 * (n_avg + 1) / 2 / 512.0, rng)
                x = T.add_noise(x, rng, rms_fraction=noise)
                d = frf(x, "force", nperseg=8192)
                for m in err:
                    r = half_power(d, fn_hz=[20.0, 55.0], method=m, max_scatter=1.0)
                    err[m] += list(r.zeta / np.array([0.01, 0.005]) - 1)
                sc += list(r.scatter)
            sc = np.asarray(sc)
            rms = {m: np.sqrt(np.nanmean(np.square(v))) * 100 for m, v in err.items()}
            print(f"{n_avg:>9d}{noise:>7.0%}{rms['fit']:>11.1f}{rms['interpolate']:>14.1f}"
                  f"{np.nanmin(sc):>10.3f}..{np.nanmax(sc):<8.3f}"
                  f"{np.mean(sc > 0.05):>9.0%}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channels", type=int, default=64)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--fs", type=float, default=10_000.0)
    ap.add_argument("--block", type=int, default=8)
    ap.add_argument("--nperseg", type=int, default=8192)
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="8 channels x 1 min, 5 repetitions")
    ap.add_argument("--skip-speed", action="store_true")
    ap.add_argument("--skip-accuracy", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.channels, args.minutes, args.reps = 8, 1.0, 5
    if not args.skip_speed:
        bench_speed(args.channels, args.minutes, args.fs, args.block, args.nperseg)
    if not args.skip_accuracy:
        bench_accuracy(args.reps)
    bench_defaults(args.reps, SHARED if SHARED.is_dir() else Path("/work/shared/data"))


if __name__ == "__main__":
    main()
