"""Craig-Bampton reduction of a ~50 000-DOF plate vs the full model's eigen solve.

Run::

    .venv/bin/python benchmarks/bench_reduction.py [--n 90] [--repeat 3]

Builds the CFFF benchmark plate of ``data/structures/plate.toml`` (MITC4 shells, 6 DOF
per node) with an ``n x n`` mesh (n = 90: 49 140 free DOFs), then times in the same run

- the full model's lowest 10 modes (``mvtk.fe.eigsh_lowest``: one factorisation of
  ``K - sigma M`` and shift-invert Lanczos), the reference;
- ``mvtk.reduction.craig_bampton`` with 5 boundary nodes x 6 DOF = 30 boundary DOFs and
  10 fixed-interface modes (one factorisation of ``K_ff`` for the constraint modes and
  the eigen solve, plus the projections ``T' M T``, ``T' K T``).

Target: Craig-Bampton under 2x the full eigen solve. Also prints the SE-vs-FE frequency
errors of the first 4 modes (the paper's Table 5 shape) so the speed is not bought with
accuracy. Best of ``--repeat`` runs, wall and CPU (``time.process_time``: the machine may
be shared, then wall time swings with its load, printed beside), the two solves
alternating so that both see the same load. The sparse backend is the one
:func:`mvtk.fe.factorize` picks (``MVTK_SPARSE_BACKEND=superlu`` as in CI).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from mvtk.fe import build_model, eigsh_lowest
from mvtk.reduction import compare_modes, craig_bampton

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _summary import write_result  # noqa: E402


def timed(fn):
    """``(wall_s, cpu_s, result)`` of one call."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - t0, time.process_time() - c0, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=90, help="elements per side (default 90)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    structure = tomllib.loads((ROOT / "data" / "structures" / "plate.toml").read_text())
    structure["mesh"] = {"nx": args.n, "ny": args.n}
    t0 = time.perf_counter()
    model = build_model(structure)
    t_build = time.perf_counter() - t0
    a = float(structure["structure"]["length"])
    b = float(structure["structure"]["width"])
    points = [[a / 3, b / 2, 0], [2 * a / 3, b / 4, 0], [2 * a / 3, 3 * b / 4, 0],
              [a, 0, 0], [a, b, 0]]
    print(f"plate {args.n} x {args.n}: {model.n_dof} free DOFs, {model.n_nodes} nodes, "
          f"{model.n_elements} elements (build {t_build:.2f} s)")

    load0 = os.getloadavg()[0]
    runs_full, runs_cb = [], []
    for _ in range(args.repeat):
        runs_full.append(timed(lambda: eigsh_lowest(model.K, model.M, 10)))
        runs_cb.append(timed(lambda: craig_bampton(model, points, 10)))
    full, se = runs_full[-1][2], runs_cb[-1][2]
    t_full, c_full = min(r[0] for r in runs_full), min(r[1] for r in runs_full)
    t_cb, c_cb = min(r[0] for r in runs_cb), min(r[1] for r in runs_cb)
    fe_hz = np.sqrt(full.omega2) / (2 * np.pi)
    print(f"sparse backend {full.backend}, load average {load0:.2f} -> "
          f"{os.getloadavg()[0]:.2f} ({os.cpu_count()} cores); best of {args.repeat}")
    print(f"full 10-mode eigen solve : {t_full:7.3f} s (cpu {c_full:6.3f} s)   f1..f4 = "
          + ", ".join(f"{f:.3f}" for f in fe_hz[:4]) + " Hz")
    print(f"Craig-Bampton ({se.n_boundary} boundary DOF + {se.n_modes} modes = {se.n_dof} DOF)"
          f" : {t_cb:7.3f} s (cpu {c_cb:6.3f} s)")
    print(f"ratio CB / full eigen    : {t_cb / t_full:7.2f} wall, {c_cb / c_full:5.2f} cpu"
          "   (target < 2)")
    write_result("reduction", {
        "figures": {"n_dof": model.n_dof, "full_eigen_s": t_full, "craig_bampton_s": t_cb,
                    "full_eigen_cpu_s": c_full, "craig_bampton_cpu_s": c_cb,
                    "target_ratio": 2.0, "backend": full.backend},
        "peer": "full-model eigen solve (same run)",
        "ratios": {"craig_bampton_over_full_eigen": t_cb / t_full,
                   "craig_bampton_over_full_eigen_cpu": c_cb / c_full}})
    cmp = compare_modes(model, se, 4)
    print("SE vs FE (Table 5 shape):")
    print(cmp.to_dataframe().to_string(index=False, float_format="{:.5g}".format))


if __name__ == "__main__":
    main()
