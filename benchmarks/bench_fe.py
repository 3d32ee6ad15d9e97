"""FE benchmark: cantilevered 10 m x 10 m x 0.05 m steel plate, lowest 10 modes.

Run on demand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_fe.py            # ~50 000 DOF + OpenSeesPy + 200 000 DOF
    .venv/bin/python benchmarks/bench_fe.py --skip-large --skip-opensees

Prints the assembly time, the time of one sparse factorisation of K, the modal-analysis
time, the frequencies against the thin-plate reference (Leissa, NASA SP-160, 1969,
CFFF square plate, nu = 0.3: lambda = 3.492, 8.525, 21.43, 27.33, 31.11 as Ritz upper
bounds), the same problem in OpenSeesPy (ShellMITC4, ElasticMembranePlateSection, same
mesh, its default eigen solver) when ``openseespy`` is importable, and the peak memory
of a 200 000-DOF model in a child process.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

E, NU, RHO, A, H = 210e9, 0.3, 7850.0, 10.0, 0.05
LEISSA = np.array([3.492, 8.525, 21.43, 27.33, 31.11])


def leissa_hz() -> np.ndarray:
    D = E * H**3 / (12 * (1 - NU**2))
    return LEISSA / (2 * np.pi * A**2) * np.sqrt(D / (RHO * H))


def run_mvtk(n: int) -> dict:
    import mvtk.fe as fe

    steel = fe.IsotropicMaterial("steel", E, NU, RHO)
    t0, c0 = time.perf_counter(), time.process_time()
    model = fe.plate_model(A, A, [fe.Ply(steel, H)], nx=n, ny=n, clamp="x0")
    t_asm, c_asm = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    lu = fe.factorize(model.K)
    t_fac, c_fac = time.perf_counter() - t0, time.process_time() - c0
    fill = lu.L.nnz + lu.U.nnz
    del lu
    t0, c0 = time.perf_counter(), time.process_time()
    res = fe.modal_analysis(model, 10)
    t_eig, c_eig = time.perf_counter() - t0, time.process_time() - c0
    return {"n_dof": model.n_dof, "assembly_s": t_asm, "factorize_s": t_fac,
            "modal_s": t_eig, "assembly_cpu": c_asm, "factorize_cpu": c_fac,
            "modal_cpu": c_eig, "lu_nnz": fill, "fn_hz": res.fn_hz.tolist(),
            "mode_type": list(res.mode_type)}


def run_opensees(n: int) -> dict | None:
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError) as err:  # RuntimeError: missing system BLAS
        print(f"OpenSeesPy not usable: {err}")
        return None
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    xs = np.linspace(0, A, n + 1)
    tag = lambda i, j: i * (n + 1) + j + 1  # noqa: E731
    t0 = time.perf_counter()
    for i, x in enumerate(xs):
        for j, y in enumerate(xs):
            ops.node(tag(i, j), float(x), float(y), 0.0)
            if i == 0:
                ops.fix(tag(i, j), 1, 1, 1, 1, 1, 1)
    ops.section("ElasticMembranePlateSection", 1, E, NU, H, RHO)
    e = 1
    for i in range(n):
        for j in range(n):
            ops.element("ShellMITC4", e, tag(i, j), tag(i + 1, j), tag(i + 1, j + 1),
                        tag(i, j + 1), 1)
            e += 1
    t_build = time.perf_counter() - t0
    t0, c0 = time.perf_counter(), time.process_time()
    lam = np.array(ops.eigen(10))
    t_eig, c_eig = time.perf_counter() - t0, time.process_time() - c0
    n_dof = 6 * (n + 1) ** 2
    ops.wipe()
    return {"n_dof": n_dof, "build_s": t_build, "eigen_s": t_eig, "eigen_cpu": c_eig,
            "fn_hz": (np.sqrt(lam) / (2 * np.pi)).tolist()}


def large_child(n: int) -> None:
    out = run_mvtk(n)
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    sys.stdout.write(json.dumps(out) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=90, help="elements per side (90 -> 49 140 DOF)")
    ap.add_argument("--skip-opensees", action="store_true")
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--large-child", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.large_child:
        large_child(args.large_child)
        return
    ref = leissa_hz()
    r = run_mvtk(args.n)
    print(f"mvtk MITC4: {args.n}x{args.n} elements, {r['n_dof']} free DOF")
    print(f"  wall: assembly {r['assembly_s']:.2f} s, one factorisation of K "
          f"{r['factorize_s']:.2f} s (nnz(L+U) = {r['lu_nnz']}), modal analysis (10 modes) "
          f"{r['modal_s']:.2f} s")
    print(f"  cpu:  assembly {r['assembly_cpu']:.2f} s, factorisation {r['factorize_cpu']:.2f} s, "
          f"modal {r['modal_cpu']:.2f} s (process CPU time; wall is inflated on a busy machine)")
    total = r["assembly_s"] + r["modal_s"]
    ctotal = r["assembly_cpu"] + r["modal_cpu"]
    print(f"  total wall {total:.2f} s = {total / r['factorize_s']:.2f} x one factorisation; "
          f"total cpu {ctotal:.2f} s = {ctotal / r['factorize_cpu']:.2f} x")
    print("  fn_hz:", np.round(r["fn_hz"], 4).tolist())
    print("  types:", r["mode_type"])
    print("  Leissa thin-plate reference (first 5, Ritz upper bounds):",
          np.round(ref, 4).tolist())
    print("  mvtk / Leissa - 1:", np.round(np.array(r["fn_hz"][:5]) / ref - 1, 4).tolist())
    if not args.skip_opensees:
        o = run_opensees(args.n)
        if o is None:
            print("OpenSeesPy not importable: comparison skipped (pip install openseespy)")
        else:
            print(f"OpenSeesPy ShellMITC4: {o['n_dof']} DOF (before fixities), build "
                  f"{o['build_s']:.2f} s, eigen(10) wall {o['eigen_s']:.2f} s, "
                  f"cpu {o['eigen_cpu']:.2f} s")
            print("  fn_hz:", np.round(o["fn_hz"], 4).tolist())
            print("  OpenSees / Leissa - 1:",
                  np.round(np.array(o["fn_hz"][:5]) / ref - 1, 4).tolist())
            print(f"  speed ratio (OpenSees eigen) / (mvtk assembly + modal): wall "
                  f"{o['eigen_s'] / total:.1f}, cpu {o['eigen_cpu'] / ctotal:.1f}")
    if not args.skip_large:
        n = 182  # 183^2 nodes x 6 - clamp = ~200 000 DOF
        proc = subprocess.run([sys.executable, __file__, "--large-child", str(n)],
                              capture_output=True, text=True, check=True)
        big = json.loads(proc.stdout.strip().splitlines()[-1])
        print(f"200k case: {big['n_dof']} DOF, wall: assembly {big['assembly_s']:.2f} s, "
              f"factorisation {big['factorize_s']:.2f} s, modal {big['modal_s']:.2f} s; cpu: "
              f"{big['assembly_cpu']:.2f} / {big['factorize_cpu']:.2f} / "
              f"{big['modal_cpu']:.2f} s; peak RSS {big['peak_rss_mib']:.0f} MiB")
        print("  fn_hz:", np.round(big["fn_hz"][:5], 4).tolist())


if __name__ == "__main__":
    main()
