"""Benchmark of mvtk.updating.update on the smart-beam plate (build_model).

Updates 2-4 parameters of the nominal smart beam (data/structures/smart_beam.toml,
MITC4 layered shells) to the measured 13.26 / 41.14 Hz and prints the timing breakdown
(model builds, eigen solves, sensitivity products) per iteration. The peer run is
scipy.optimize.least_squares on the same residuals with its own 2-point finite-difference
Jacobian (one build + one eigen solve per parameter per iteration), the usual way to
update a model without eigenvalue sensitivities.

Run:  .venv/bin/python benchmarks/bench_updating.py [--element-size 0.0028] [--n-params 2]
      [--difference forward|central] [--affine] [--no-peer]
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _summary import write_result  # noqa: E402

PARAMS = [  # path, lower, upper, log-scaled
    ("materials.steel.E", 1.5e11, 2.5e11, False),
    ("boundary.clamp_stiffness", 10.0, 1e6, True),
    ("materials.pic151.E", 3e10, 1e11, False),
    ("materials.epoxy.E", 1e9, 1e10, False),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--element-size", type=float, default=0.0028, help="m (0.0028: ~20k DOF)")
    ap.add_argument("--n-params", type=int, default=2, choices=(2, 3, 4))
    ap.add_argument("--difference", default="forward", choices=("forward", "central"))
    ap.add_argument("--affine", action="store_true",
                    help="assemble once: K(p) = K0 + sum dp dK/dp (moduli, springs)")
    ap.add_argument("--no-peer", action="store_true")
    a = ap.parse_args()

    from scipy.optimize import least_squares

    from mvtk.fe import build_model, eigsh_lowest
    from mvtk.updating import FrequencyTarget, Parameter, update, with_values

    d = tomllib.loads((ROOT / "data" / "structures" / "smart_beam.toml").read_text())
    d["mesh"] = {"element_size": a.element_size}
    d["boundary"]["clamp_stiffness"] = 1e4
    chosen = PARAMS[: a.n_params]
    params = [Parameter(p, lower=lo, upper=hi, log=lg) for p, lo, hi, lg in chosen]
    targets = [FrequencyTarget(13.26, label="f1"), FrequencyTarget(41.14, label="f2")]

    t0 = time.perf_counter()
    model = build_model(d)
    print(f"model: {model.n_dof} DOF, {model.n_elements} elements "
          f"(first build {time.perf_counter() - t0:.2f} s)")
    print(f"parameters: {[c[0] for c in chosen]}; matrix differences: {a.difference}; "
          f"affine: {a.affine}")

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = update(d, params, targets, builder=build_model, n_modes=6,
                   regularization=1e-4 if a.n_params > 2 else 0.0, difference=a.difference,
                   affine=a.affine)
    total = time.perf_counter() - t0
    for w in caught:
        print(f"  warning {w.category.__name__}: {str(w.message)[:150]}")
    tm = r.timing
    n_it = max(r.n_jacobians, 1)
    print(f"\nmvtk.updating.update: {total:.1f} s total, {r.n_evaluations} evaluations, "
          f"{r.n_jacobians} Jacobians, success={r.success}")
    print(f"  builds        {tm['build_s']:7.2f} s  ({tm['n_builds']} builds, "
          f"{tm['build_s'] / max(tm['n_builds'], 1):.2f} s each)")
    print(f"  eigen solves  {tm['eigen_s']:7.2f} s  ({tm['n_eigen']} solves, "
          f"{tm['eigen_s'] / max(tm['n_eigen'], 1):.2f} s each)")
    print(f"  sensitivities {tm['sensitivity_s']:7.2f} s  "
          f"({tm['sensitivity_s'] / n_it:.3f} s per Jacobian)")
    other = total - tm["build_s"] - tm["eigen_s"] - tm["sensitivity_s"]
    print(f"  other         {other:7.2f} s")
    print(f"  per iteration {total / n_it:7.2f} s")
    print(r.residual_table()[["target_hz", "initial_hz", "updated_hz", "error_pct"]]
          .to_string())
    print(r.parameter_table()[["initial", "updated", "change_pct"]].to_string())

    figures = {"n_dof": model.n_dof, "total_s": total, "n_evaluations": r.n_evaluations,
               "n_jacobians": r.n_jacobians, "build_s": tm["build_s"],
               "eigen_s": tm["eigen_s"], "n_eigen": tm["n_eigen"],
               "sensitivity_s": tm["sensitivity_s"]}
    if a.no_peer:
        write_result("updating", {"figures": figures})
        return
    # peer: least_squares with a 2-point finite-difference Jacobian, same residuals and
    # the same (log-)scaled variables
    scale = np.array([p.resolve(d)[1] for p in params])
    logs = np.array([c[3] for c in chosen])

    def to_x(v):
        return np.where(logs, np.log(v / scale), v / scale)

    def to_p(x):
        return np.where(logs, scale * np.exp(np.where(logs, x, 0.0)), scale * x)

    x0 = to_x(np.array([p.resolve(d)[0] for p in params]))
    lb = to_x(np.array([c[1] for c in chosen]))
    ub = to_x(np.array([c[2] for c in chosen]))
    ft = np.array([t.fn_hz for t in targets])
    n_eval = [0]

    def resid(x):
        n_eval[0] += 1
        m = build_model(with_values(d, {p.path: v for p, v in zip(params, to_p(x))}))
        eig = eigsh_lowest(m.K, m.M, 6, sigma=-0.1 * (2 * np.pi * 13.0) ** 2)
        f = np.sqrt(eig.omega2[: ft.size]) / (2 * np.pi)
        res = (f - ft) / ft
        if a.n_params > 2:
            res = np.concatenate([res, np.sqrt(1e-4) * (x - x0)])
        return res

    t0 = time.perf_counter()
    sol = least_squares(resid, x0, bounds=(lb, ub), jac="2-point", method="trf",
                        xtol=1e-10, ftol=1e-12, gtol=1e-12, max_nfev=50)
    peer = time.perf_counter() - t0
    print(f"\npeer least_squares(jac='2-point'): {peer:.1f} s, {n_eval[0]} model evaluations, "
          f"status {sol.status}; updated {[float(f'{v:.6g}') for v in to_p(sol.x)]}")
    print(f"ratio peer / mvtk: {peer / total:.2f}")
    figures["peer_s"] = peer
    write_result("updating", {"figures": figures,
                              "peer": "scipy.optimize.least_squares, 2-point Jacobian",
                              "ratios": {"peer_over_mvtk": peer / total}})


if __name__ == "__main__":
    main()
