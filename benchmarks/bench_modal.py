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

Is it the same job? Both get all 180 FRFs over the same band and model orders 1..80,
with single-threaded BLAS; neither starts threads of its own (mvtk's pLSCF computes the
orders one after the other: each seeds the roots of the next, ``mvtk/modal/_polyroots``),
so ``process_time`` is one core's time for both. sdypy-EMA's LSCF is a common-denominator
estimator (order p gives p poles), mvtk's poly-reference pLSCF gives 3 p poles at order p
(denominators up to 240 x 240 companion size against 80 x 80): mvtk's job is the larger
one. sdypy-EMA is told the true frequencies for its pole selection; mvtk selects
automatically. The last line runs mvtk at the same number of poles per order as
sdypy-EMA.
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


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _run_mvtk(h, band, max_order):
    orders = range(1, max_order + 1)
    d, t_stab, c_stab = _timed(lambda: modal.plscf(h, *band, orders=orders))
    res, t_id, c_id = _timed(lambda: modal.identify(h, *band, orders=orders))
    return d, res, (t_stab, c_stab, t_id, c_id)


def _run_sdypy(EMA, h, band, max_order, fn):
    n_lines = h.sizes["frequency"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0, c0 = time.perf_counter(), time.process_time()
        m = EMA.Model(frf=h.values.reshape(-1, n_lines), freq=h["frequency"].values,
                      lower=band[0], upper=band[1], pol_order_high=max_order,
                      frf_form="accelerance")
        m.get_poles(show_progress=False)
        t_pe, c_pe = time.perf_counter() - t0, time.process_time() - c0
        m.select_closest_poles(fn, f_window=4)
        m.get_constants(whose_poles="own")
        t_all, c_all = time.perf_counter() - t0, time.process_time() - c0
    return m, (t_pe, c_pe, t_all, c_all)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--max-order", type=int, default=80)
    ap.add_argument("--repeat", type=int, default=3,
                    help="interleaved runs of both libraries (medians are reported)")
    args = ap.parse_args()
    n_resp, n_lines = (12, 1000) if args.quick else (60, 4000)
    h, fn, zeta = make_data(n_resp, 3, n_lines)
    band = (10.0, 490.0)
    print(f"data: {n_resp} responses x 3 references x {n_lines} lines; 15 modes; "
          f"orders up to {args.max_order}; {args.repeat} interleaved run(s)")
    try:
        from sdypy import EMA
    except ImportError:
        EMA = None
        print("sdypy-EMA not installed (pip install sdypy-EMA): mvtk timings only")
    mv, sd = [], []
    for k in range(max(1, args.repeat)):
        d, res, t = _run_mvtk(h, band, args.max_order)
        mv.append(t)
        line = (f"run {k + 1}: mvtk stabilisation wall {t[0]:5.2f} s cpu {t[1]:5.2f} s, "
                f"+ selection + LSFD + quality wall {t[2]:5.2f} s cpu {t[3]:5.2f} s")
        if EMA is not None:
            m, u = _run_sdypy(EMA, h, band, args.max_order, fn)
            sd.append(u)
            line += (f" | sdypy-EMA LSCF wall {u[0]:5.2f} s cpu {u[1]:5.2f} s, + LSFD wall "
                     f"{u[2]:5.2f} s cpu {u[3]:5.2f} s | ratio stab+LSFD wall "
                     f"{u[2] / t[2]:4.1f} x cpu {u[3] / t[3]:4.1f} x")
        print(line, flush=True)
    mv = np.median(np.array(mv), axis=0)
    e_f, e_z = errors(res.fn_hz, res.zeta, fn, zeta)
    print(f"mvtk  plscf (stabilisation, {d.pole.size} poles): median wall {mv[0]:6.2f} s, "
          f"cpu {mv[1]:6.2f} s")
    print(f"mvtk  identify (plscf + selection + LSFD + quality): median wall {mv[2]:6.2f} s, "
          f"cpu {mv[3]:6.2f} s; {res.n_modes} modes, max df/f {e_f:.1e}, max dz/z {e_z:.1e}")
    if EMA is None:
        return
    sd = np.median(np.array(sd), axis=0)
    p_f, p_z = errors(m.nat_freq, m.nat_xi, fn, zeta)
    print(f"sdypy-EMA get_poles (LSCF, orders up to {args.max_order}): median wall "
          f"{sd[0]:6.2f} s, cpu {sd[1]:6.2f} s")
    print(f"sdypy-EMA get_poles + select + get_constants (LSFD): median wall {sd[2]:6.2f} s, "
          f"cpu {sd[3]:6.2f} s; max df/f {p_f:.1e}, max dz/z {p_z:.1e}")
    # the same number of poles as sdypy-EMA at order 80: poly-reference order p gives
    # p * n_reference poles, so order 80 // 3 = 26 gives 78 poles per order
    n_ref = h.sizes["reference"]
    res_eq, t_eq, c_eq = _timed(lambda: modal.identify(
        h, *band, orders=range(1, args.max_order // n_ref + 1)))
    q_f, q_z = errors(res_eq.fn_hz, res_eq.zeta, fn, zeta)
    print(f"mvtk  identify with orders up to {args.max_order // n_ref} (<= {args.max_order} "
          f"poles per order, as sdypy-EMA): wall {t_eq:6.2f} s, cpu {c_eq:6.2f} s; "
          f"{res_eq.n_modes} modes, max df/f {q_f:.1e}, max dz/z {q_z:.1e}; speed-up wall "
          f"{sd[2] / t_eq:5.1f} x, cpu {sd[3] / c_eq:5.1f} x")
    print(f"speed-up of the medians (sdypy-EMA / mvtk), stabilisation: wall "
          f"{sd[0] / mv[0]:5.1f} x, cpu {sd[1] / mv[1]:5.1f} x;  stabilisation + LSFD: wall "
          f"{sd[2] / mv[2]:5.1f} x, cpu {sd[3] / mv[3]:5.1f} x  (target >= 3 x)")


if __name__ == "__main__":
    main()
