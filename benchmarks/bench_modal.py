"""Benchmark of mvtk.modal against sdypy-EMA's LSCF (run on demand, not in the test suite).

    .venv/bin/python benchmarks/bench_modal.py            # 60 responses x 3 refs x 4000 lines
    .venv/bin/python benchmarks/bench_modal.py --quick    # 12 x 3 x 1000, smoke run

Data: a seeded modal model (15 modes in 20..480 Hz, 0.5..2 % damping, random real
mass-normalised shapes) as accelerances, with 1 % output noise. Both libraries get the
same FRFs in the same run:

- mvtk: ``plscf`` over polynomial orders 1..80 (poly-reference: 3 poles per order,
  up to 240 poles), automatic selection, LSFD with residuals, quality
  table (:func:`mvtk.modal.identify`);
- sdypy-EMA: ``Model(...).get_poles()`` (its LSCF, all 180 FRFs, orders up to 80),
  ``select_closest_poles`` at the true frequencies, ``get_constants`` (its LSFD).

Prints wall-clock and CPU (process) times of both, the ratios, and the frequency and
damping errors of both against the truth. On a shared machine the CPU-time ratio is the
meaningful one (wall time swings with the other processes' load).
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

# single-threaded BLAS for both libraries (unless the caller sets it): the comparison
# then measures the algorithms, not thread scheduling on a shared machine
for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from mvtk import modal  # noqa: E402


def make_data(n_resp, n_ref, n_lines, seed=7):
    rng = np.random.default_rng(seed)
    fn = np.sort(rng.uniform(20, 480, 15))
    zeta = rng.uniform(0.005, 0.02, fn.size)
    phi = rng.standard_normal((fn.size, n_resp)) * 0.3
    f = np.linspace(0, 500, n_lines)
    w, wn = 2 * np.pi * f, 2 * np.pi * fn
    refs = np.linspace(0, n_resp - 1, n_ref).astype(int)
    den = wn[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta[:, None] * wn[:, None] * w
    H = -(w**2) * np.einsum("mo,mi,mf->oif", phi, phi[:, refs], 1 / den)
    rms = np.sqrt(np.mean(np.abs(H) ** 2, axis=-1, keepdims=True))
    H = H + 0.01 * rms * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    import xarray as xr

    da = xr.DataArray(
        H, dims=("response", "reference", "frequency"),
        coords={"response": [f"{k + 1}+z" for k in range(n_resp)],
                "reference": [f"{k + 1}+z" for k in refs], "frequency": f,
                "node": ("response", np.arange(1, n_resp + 1)),
                "direction": ("response", ["+z"] * n_resp),
                "reference_node": ("reference", refs + 1),
                "reference_direction": ("reference", ["+z"] * n_ref)},
        attrs={"frf_type": "accelerance"})
    return modal.as_frf_matrix(da), fn, zeta


def errors(found_fn, found_z, fn, zeta):
    j = [int(np.argmin(np.abs(np.asarray(found_fn) - f))) for f in fn]
    df = np.abs(np.asarray(found_fn)[j] - fn) / fn
    dz = np.abs(np.asarray(found_z)[j] - zeta) / zeta
    return df.max(), dz.max()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--max-order", type=int, default=80)
    args = ap.parse_args()
    n_resp, n_lines = (12, 1000) if args.quick else (60, 4000)
    h, fn, zeta = make_data(n_resp, 3, n_lines)
    band = (10.0, 490.0)
    print(f"data: {n_resp} responses x 3 references x {n_lines} lines; 15 modes; "
          f"orders up to {args.max_order}")

    t0, c0 = time.perf_counter(), time.process_time()
    d = modal.plscf(h, *band, orders=range(1, args.max_order + 1))
    t_stab, c_stab = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    res = modal.identify(h, *band, orders=range(1, args.max_order + 1))
    t_ident, c_ident = time.perf_counter() - t0, time.process_time() - c0
    e_f, e_z = errors(res.fn_hz, res.zeta, fn, zeta)
    print(f"mvtk  plscf (stabilisation, {d.pole.size} poles): wall {t_stab:7.2f} s, "
          f"cpu {c_stab:7.2f} s")
    print(f"mvtk  identify (plscf + selection + LSFD + quality): wall {t_ident:7.2f} s, "
          f"cpu {c_ident:7.2f} s; {res.n_modes} modes, max df/f {e_f:.1e}, "
          f"max dz/z {e_z:.1e}")
    try:
        from sdypy import EMA
    except ImportError:
        print("sdypy-EMA not installed (pip install sdypy-EMA): no comparison")
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0, c0 = time.perf_counter(), time.process_time()
        m = EMA.Model(frf=h.values.reshape(-1, n_lines), freq=h["frequency"].values,
                      lower=band[0], upper=band[1], pol_order_high=args.max_order,
                      frf_form="accelerance")
        m.get_poles(show_progress=False)
        t_pe, c_pe = time.perf_counter() - t0, time.process_time() - c0
        m.select_closest_poles(fn, f_window=4)
        m.get_constants(whose_poles="own")
        t_all, c_all = time.perf_counter() - t0, time.process_time() - c0
    p_f, p_z = errors(m.nat_freq, m.nat_xi, fn, zeta)
    print(f"sdypy-EMA get_poles (LSCF, orders up to {args.max_order}): wall {t_pe:7.2f} s, "
          f"cpu {c_pe:7.2f} s")
    print(f"sdypy-EMA get_poles + select + get_constants (LSFD): wall {t_all:7.2f} s, "
          f"cpu {c_all:7.2f} s; max df/f {p_f:.1e}, max dz/z {p_z:.1e}")
    # the same number of poles as sdypy-EMA at order 80: poly-reference order p gives
    # p * n_reference poles, so order 80 // 3 = 26 gives 78 poles per order
    n_ref = h.sizes["reference"]
    t0, c0 = time.perf_counter(), time.process_time()
    res_eq = modal.identify(h, *band, orders=range(1, args.max_order // n_ref + 1))
    t_eq, c_eq = time.perf_counter() - t0, time.process_time() - c0
    q_f, q_z = errors(res_eq.fn_hz, res_eq.zeta, fn, zeta)
    print(f"mvtk  identify with orders up to {args.max_order // n_ref} (<= {args.max_order} "
          f"poles per order, as sdypy-EMA): wall {t_eq:7.2f} s, cpu {c_eq:7.2f} s; "
          f"{res_eq.n_modes} modes, max df/f {q_f:.1e}, max dz/z {q_z:.1e}; speed-up wall "
          f"{t_all / t_eq:5.1f} x, cpu {c_all / c_eq:5.1f} x")
    print(f"speed-up (sdypy-EMA / mvtk), stabilisation: wall {t_pe / t_stab:5.1f} x, cpu "
          f"{c_pe / c_stab:5.1f} x;  stabilisation + LSFD: wall {t_all / t_ident:5.1f} x, "
          f"cpu {c_all / c_ident:5.1f} x  (target >= 3 x)")


if __name__ == "__main__":
    main()
