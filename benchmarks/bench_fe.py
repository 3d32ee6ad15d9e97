"""FE benchmark: cantilevered 10 m x 10 m x 0.05 m steel plate, lowest 10 modes.

Run on demand (not part of the test suite)::

    .venv/bin/python benchmarks/bench_fe.py                 # 90x90 (49 140 DOF), 3 rounds
    .venv/bin/python benchmarks/bench_fe.py --repeats 1 --skip-opensees --skip-large
    .venv/bin/python benchmarks/bench_fe.py --million       # 1 M-DOF plate, 20 modes
    .venv/bin/python benchmarks/bench_fe.py --imported      # imported 200k-DOF curved shell

Each round runs, in fresh processes one after the other (interleaved, so both see the
same machine load), mvtk (``plate_model`` + ``modal_analysis``) and OpenSeesPy on the
same mesh (ShellMITC4, ElasticMembranePlateSection, its default eigen solver) when
``openseespy`` is importable. It prints per round and as medians: the wall and CPU
times, the speed ratio (OpenSees eigen / mvtk assembly + modal), the frequencies of both
against the thin-plate reference (Leissa, NASA SP-160, 1969, CFFF square plate,
nu = 0.3: lambda = 3.492, 8.525, 21.43, 27.33, 31.11 as Ritz upper bounds) and against
each other, and the limit of shift-invert Lanczos on this matrix: one factorisation plus
the solves this Lanczos made (each at the cost of one solve of the block width,
measured in the same process), with the ratio of mvtk's eigen step to it (the
iteration's own overhead) and the number of right-hand sides and solves used; beside it
the ratio to one factorisation plus 2 x n_modes single solves (fewer vectors than a
Lanczos needs at machine-precision residuals), the block variant of that (the
2 x n_modes right-hand sides in one solve) and the other Lanczos (ARPACK,
``method="arpack"``, when the default is the block method), and in the first round the
CPU per right-hand side of one solve with k = 1, 3, 10, 20 of them. The frequencies are
compared with OpenSees twice: mvtk with OpenSees' formulation on the same mesh
(drilling penalty A66, ``drill_factor=1``, and no shell rotary inertia, as ShellMITC4),
target 1e-4, and mvtk's default formulation (a modelling difference). The first round also
measures the fill ``nnz(L) + nnz(U)`` of SuperLU with the METIS ordering against
SuperLU's own MMD ordering, and the SuperLU-only (permissive default) eigen time when
the CHOLMOD backend is installed. ``--large`` adds a 200 000-DOF model in a child
process with its peak memory. ``--million`` builds a 1 000 000-DOF plate, predicts the
memory of its eigen step with :func:`mvtk.fe.estimate_eigen_memory` from the mesh graph
(no assembly), refuses up front when the prediction exceeds the available memory, and
otherwise runs ``modal_analysis`` for 20 modes and prints its time with the assembly's,
the child process's wall time, peak RSS and prediction. ``--imported`` writes
a cylindrical-panel quad mesh (33 000 nodes, 200 000 DOF) as a Gmsh file, imports it
through :func:`mvtk.fe.read_mesh` and :func:`mvtk.fe.mesh_model`, and prints read and
assembly time and peak RSS against the built-in rectangular path, per DOF.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _summary import write_result  # noqa: E402

E, NU, RHO, A, H = 210e9, 0.3, 7850.0, 10.0, 0.05
LEISSA = np.array([3.492, 8.525, 21.43, 27.33, 31.11])


def leissa_hz() -> np.ndarray:
    D = E * H**3 / (12 * (1 - NU**2))
    return LEISSA / (2 * np.pi * A**2) * np.sqrt(D / (RHO * H))


def _clock():
    return time.perf_counter(), time.process_time()


def _since(t):
    return time.perf_counter() - t[0], time.process_time() - t[1]


def child_mvtk(n: int, n_modes: int, fill: bool) -> dict:
    import mvtk.fe as fe
    from mvtk.fe._solvers import BLOCK_SIZE

    out: dict = {"load_before": os.getloadavg()[0]}
    steel = fe.IsotropicMaterial("steel", E, NU, RHO)
    t = _clock()
    model = fe.plate_model(A, A, [fe.Ply(steel, H)], nx=n, ny=n, clamp="x0")
    out["assembly_s"], out["assembly_cpu"] = _since(t)
    t = _clock()
    res = fe.modal_analysis(model, n_modes)
    out["modal_s"], out["modal_cpu"] = _since(t)
    out["fn_hz"] = res.fn_hz.tolist()
    out["n_dof"] = model.n_dof
    # the mode-type labels alone (energy split + labels, as modal_analysis makes them)
    from mvtk.fe._mode_labels import label_modes

    t = _clock()
    label_modes(model, res.shapes, fe.energy_split(model, res.shapes), fe.ENERGY_PARTS)
    out["labels_s"], out["labels_cpu"] = _since(t)
    # the limit: one factorisation + 2 n_modes solves of the same matrix
    t = _clock()
    lu = fe.factorize(model.K)
    out["factorize_s"], out["factorize_cpu"] = _since(t)
    out["backend"] = lu.backend
    b = np.random.default_rng(0).standard_normal((model.n_dof,))
    t = _clock()
    for _ in range(2 * n_modes):
        lu.solve(b)
    out["solves_2n_s"], out["solves_2n_cpu"] = _since(t)
    # one solve with as many right-hand sides as the block Lanczos of the default uses
    Bw = np.random.default_rng(0).standard_normal((model.n_dof, BLOCK_SIZE))
    t = _clock()
    for _ in range(10):
        lu.solve(Bw)
    out["width_solve_s"], out["width_solve_cpu"] = (x / 10 for x in _since(t))
    # the same 2 n_modes right-hand sides as one block (BLAS-3 in the factor's sweeps)
    B = np.random.default_rng(0).standard_normal((model.n_dof, 2 * n_modes))
    t = _clock()
    lu.solve(B)
    out["block_2n_s"], out["block_2n_cpu"] = _since(t)
    if fill:
        # CPU per right-hand side of one solve with k of them
        out["per_rhs_cpu"] = {}
        for k in (1, 3, 10, 20):
            Bk = B[:, :k] if k > 1 else B[:, 0]
            reps = max(1, 20 // k)
            t = _clock()
            for _ in range(reps):
                lu.solve(Bk)
            out["per_rhs_cpu"][k] = _since(t)[1] / (reps * k)
    del lu
    t = _clock()
    sol = fe.eigsh_lowest(model.K, model.M, n_modes)
    out["eigsh_s"], out["eigsh_cpu"] = _since(t)
    out["n_solves"] = sol.n_solves
    out["n_factorizations"] = sol.n_factorizations
    out["method"] = sol.method
    width = BLOCK_SIZE if sol.method == "block" else 1
    out["n_block_solves"] = -(-sol.n_solves // width)
    # the other Lanczos (ARPACK when the default is the block method), same accuracy
    out["alt_method"] = "arpack" if sol.method == "block" else "block"
    t = _clock()
    alt = fe.eigsh_lowest(model.K, model.M, n_modes, method=out["alt_method"])
    out["alt_eigsh_s"], out["alt_eigsh_cpu"] = _since(t)
    out["alt_n_solves"] = alt.n_solves
    out["alt_fn_rel_diff"] = float(np.max(np.abs(alt.omega2 / sol.omega2 - 1)))
    if fill:
        # OpenSees' formulation on the same mesh: its drilling penalty (gamma_d = A66,
        # drill_factor=1: K identical, tests/fe/test_opensees_stiffened.py) and no shell
        # rotary inertia (ShellMITC4 has none: the rx, ry rows and columns of M dropped)
        steel = fe.IsotropicMaterial("steel", E, NU, RHO)
        peer = fe.plate_model(A, A, [fe.Ply(steel, H)], nx=n, ny=n, clamp="x0",
                              drill_factor=1.0)
        keep = (~np.isin(peer.dof_component, (3, 4))).astype(float)
        import scipy.sparse as sp

        D = sp.diags(keep)
        Mp = (D @ peer.M @ D).tocsr()
        ps = fe.eigsh_lowest(peer.K, Mp, n_modes)
        out["fn_hz_opensees_formulation"] = (np.sqrt(ps.omega2) / (2 * np.pi)).tolist()
    if fill:
        for ordering in ("metis", "mmd"):
            t = _clock()
            f = fe.factorize(model.K, backend="superlu", ordering=ordering)
            out[f"superlu_{ordering}_factorize_s"] = _since(t)[0]
            out[f"superlu_{ordering}_fill"] = f.nnz_factor
            del f
        if out["backend"] != "superlu":
            os.environ["MVTK_SPARSE_BACKEND"] = "superlu"
            t = _clock()
            s2 = fe.eigsh_lowest(model.K, model.M, n_modes)
            out["superlu_eigsh_s"], out["superlu_eigsh_cpu"] = _since(t)
            out["superlu_fn_rel_diff"] = float(np.max(np.abs(s2.omega2 / sol.omega2 - 1)))
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out["load_after"] = os.getloadavg()[0]
    return out


def child_opensees(n: int, n_modes: int) -> dict | None:
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError) as err:  # RuntimeError: missing system BLAS
        return {"error": f"OpenSeesPy not usable: {err}"}
    out: dict = {"load_before": os.getloadavg()[0]}
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    xs = np.linspace(0, A, n + 1)

    def tag(i, j):
        return i * (n + 1) + j + 1

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
    out["build_s"] = time.perf_counter() - t0
    t = _clock()
    lam = np.array(ops.eigen(n_modes))
    out["eigen_s"], out["eigen_cpu"] = _since(t)
    out["fn_hz"] = (np.sqrt(lam) / (2 * np.pi)).tolist()
    ops.wipe()
    out["load_after"] = os.getloadavg()[0]
    return out


def _million_graph(n: int):
    """Node adjacency graph and free DOFs per node of an n x n plate clamped at x = 0."""
    import scipy.sparse as sp

    nn = (n + 1) ** 2
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    base = (i * (n + 1) + j).ravel()
    el = np.column_stack([base, base + n + 1, base + n + 2, base + 1])
    r = np.repeat(el, 4, axis=1).ravel()
    c = np.tile(el, (1, 4)).ravel()
    G = sp.csr_matrix((np.ones(len(r), dtype=np.float32), (r, c)), shape=(nn, nn))
    nfree = np.full(nn, 6)
    nfree[: n + 1] = 0          # clamped edge x = 0 (first column of nodes)
    return G, nfree


def _mem_available() -> int:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable"):
            return int(line.split()[1]) * 1024
    return 0


def child_million(n: int, n_modes: int) -> dict:
    import mvtk.fe as fe

    out: dict = {"n": n, "load_before": os.getloadavg()[0]}
    t = time.perf_counter()
    G, nfree = _million_graph(n)
    est = fe.estimate_eigen_memory(G, n_modes, dofs_per_vertex=nfree)
    out["estimate_s"] = time.perf_counter() - t
    # assembly holds the element matrices K_e, M_e and the pattern positions
    n_el = n * n
    assembly = n_el * 576 * (8 * 3 + 8)
    out.update(n_dof=est.n_dof, predicted_total_gib=est.total_gib,
               predicted_assembly_gib=assembly / 2**30,
               predicted_nnz_storage=est.nnz_factor,
               available_gib=_mem_available() / 2**30)
    need = max(est.total, assembly + est.matrices)
    if need > 0.8 * _mem_available():
        out["refused"] = (f"predicted {need / 2**30:.1f} GiB > 80 % of the "
                          f"{out['available_gib']:.1f} GiB available")
        return out
    steel = fe.IsotropicMaterial("steel", E, NU, RHO)
    t = _clock()
    model = fe.plate_model(A, A, [fe.Ply(steel, H)], nx=n, ny=n, clamp="x0")
    out["assembly_s"], out["assembly_cpu"] = _since(t)
    out["rss_after_assembly_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    # what a user runs: modal_analysis (eigen step, mass normalisation, mode labels)
    t = _clock()
    res = fe.modal_analysis(model, n_modes)
    out["modal_s"], out["modal_cpu"] = _since(t)
    out["total_s"] = out["assembly_s"] + out["modal_s"]
    out["total_cpu"] = out["assembly_cpu"] + out["modal_cpu"]
    out["backend"] = fe.sparse_backend(detail=True)
    out["fn_hz"] = res.fn_hz.tolist()
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out["load_after"] = os.getloadavg()[0]
    return out


def _run_child(*args: str, env: dict | None = None) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", *args], capture_output=True,
                          text=True, env=env)
    if proc.returncode:
        raise RuntimeError(f"child {args} failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=90, help="elements per side (90 -> 49 140 DOF)")
    ap.add_argument("--modes", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--skip-opensees", action="store_true")
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--large-repeats", type=int, default=3,
                    help="fresh runs of the 199 836-DOF case (the median one is reported)")
    ap.add_argument("--million", action="store_true", help="only the 1 M-DOF case")
    ap.add_argument("--million-n", type=int, default=408, help="408 -> 1 000 000 DOF")
    ap.add_argument("--quick", action="store_true", help="1 round, no 200k case")
    ap.add_argument("--imported", action="store_true",
                    help="only the imported 200k-DOF curved shell vs the built-in plate")
    ap.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.large_repeats < 1:
        ap.error(f"--large-repeats must be >= 1, got {args.large_repeats}")
    if args.child:
        kind, *rest = args.child
        if kind == "mvtk":
            r = child_mvtk(int(rest[0]), int(rest[1]), rest[2] == "1")
        elif kind == "opensees":
            r = child_opensees(int(rest[0]), int(rest[1]))
        elif kind == "imported":
            r = child_imported(rest[0], int(rest[1]), int(rest[2]))
        else:
            r = child_million(int(rest[0]), int(rest[1]))
        sys.stdout.write(json.dumps(r) + "\n")
        return
    if args.imported:
        run_imported()
        return
    if args.million:
        t = time.perf_counter()
        m = _run_child("million", str(args.million_n), "20")
        m["process_wall_s"] = time.perf_counter() - t
        print(json.dumps({k: v for k, v in m.items() if k != "fn_hz"}, indent=1))
        if "total_s" in m:
            print(f"1 M DOF plate ({m['n_dof']:,} DOF, 20 modes) [{m['backend']}]: assembly "
                  f"{m['assembly_s']:.1f} s + modal_analysis {m['modal_s']:.1f} s = "
                  f"{m['total_s']:.1f} s (cpu {m['total_cpu']:.1f} s; the child process "
                  f"with Python start, imports and the memory estimate of "
                  f"{m['estimate_s']:.1f} s: {m['process_wall_s']:.1f} s); peak "
                  f"{m['peak_rss_mib'] / 1024:.2f} GiB (target < 60 s, < 6 GiB); load "
                  f"{m['load_before']:.1f}")
        write_result("fe_million", {"figures": m})
        return
    if args.quick:
        args.repeats, args.skip_large = 1, True
    ref = leissa_hz()
    rounds = []
    for k in range(args.repeats):
        mv = _run_child("mvtk", str(args.n), str(args.modes), "1" if k == 0 else "0")
        op = None if args.skip_opensees else _run_child("opensees", str(args.n), str(args.modes))
        if op is not None and "error" in op:
            print(op["error"])
            op = None
        rounds.append((mv, op))
        total = mv["assembly_s"] + mv["modal_s"]
        limit = mv["factorize_s"] + mv["solves_2n_s"]
        blimit = mv["factorize_s"] + mv["block_2n_s"]
        line = (f"round {k + 1}: mvtk [{mv['backend']}] assembly {mv['assembly_s']:.2f} s + "
                f"modal {mv['modal_s']:.2f} s = {total:.2f} s (cpu "
                f"{mv['assembly_cpu'] + mv['modal_cpu']:.2f} s); eigsh [{mv['method']}] "
                f"{mv['eigsh_s']:.2f} s with {mv['n_solves']} right-hand sides in "
                f"{mv['n_block_solves']} solves, limit (1 factorisation "
                f"{mv['factorize_s']:.2f} s + {2 * args.modes} solves {mv['solves_2n_s']:.2f}"
                f" s) {limit:.2f} s -> {mv['eigsh_s'] / limit:.2f}x; block variant of the "
                f"limit (the {2 * args.modes} as one block solve {mv['block_2n_s']:.2f} s) "
                f"{blimit:.2f} s; {mv['alt_method']} {mv['alt_eigsh_s']:.2f} s with "
                f"{mv['alt_n_solves']} right-hand sides; load {mv['load_before']:.1f}")
        if op is not None:
            line += (f"\n         OpenSeesPy eigen {op['eigen_s']:.2f} s (cpu "
                     f"{op['eigen_cpu']:.2f} s), ratio {op['eigen_s'] / total:.1f}x wall, "
                     f"{op['eigen_cpu'] / (mv['assembly_cpu'] + mv['modal_cpu']):.1f}x cpu; "
                     f"load {op['load_before']:.1f}")
        print(line, flush=True)
        # partial record after every round (a long peer run may be cut short)
        write_result("fe", {"partial": True, "rounds": [{"mvtk": r[0], "opensees": r[1]}
                                                        for r in rounds]})
    mv0 = rounds[0][0]
    med = {key: float(np.median([r[0][key] for r in rounds]))
           for key in ("assembly_s", "modal_s", "factorize_s", "solves_2n_s", "eigsh_s",
                       "assembly_cpu", "modal_cpu", "factorize_cpu", "solves_2n_cpu",
                       "eigsh_cpu", "block_2n_s", "block_2n_cpu", "alt_eigsh_s",
                       "alt_eigsh_cpu", "labels_cpu")}
    total = med["assembly_s"] + med["modal_s"]
    # the limit of the issue: 1 factorisation + the solves this Lanczos needs (its block
    # solves, each at the measured cost of one solve of the block width); wall and CPU
    def own_limit(r, kind):
        per = (r[f"width_solve_{kind}"] if r["method"] == "block"
               else r[f"solves_2n_{kind}"] / (2 * args.modes))
        return r[f"factorize_{kind}"] + r["n_block_solves"] * per

    limit_ratio = float(np.median([r[0]["eigsh_s"] / own_limit(r[0], "s") for r in rounds]))
    own_cpu = float(np.median([r[0]["eigsh_cpu"] / own_limit(r[0], "cpu") for r in rounds]))
    # against 1 factorisation + 2 n_modes single solves (fewer vectors than any Lanczos
    # needs at machine-precision residuals: ARPACK's count is printed beside it)
    single_ratio = float(np.median([r[0]["eigsh_s"] / (r[0]["factorize_s"]
                                                        + r[0]["solves_2n_s"])
                                    for r in rounds]))
    single_ratio_cpu = float(np.median([r[0]["eigsh_cpu"] / (r[0]["factorize_cpu"]
                                                              + r[0]["solves_2n_cpu"])
                                        for r in rounds]))
    block_ratio = float(np.median([r[0]["eigsh_s"] / (r[0]["factorize_s"]
                                                       + r[0]["block_2n_s"])
                                   for r in rounds]))
    asm_share = med["assembly_s"] / (med["assembly_s"] + med["modal_s"])
    asm_share_cpu = med["assembly_cpu"] / (med["assembly_cpu"] + med["modal_cpu"])
    fn = np.array(mv0["fn_hz"])
    print(f"mvtk MITC4: {args.n}x{args.n} elements, {mv0['n_dof']} free DOF, backend "
          f"{mv0['backend']}, eigen solver {mv0['method']}, {mv0['n_solves']} right-hand "
          f"sides in {mv0['n_block_solves']} solves, {mv0['n_factorizations']} "
          "factorisation(s)")
    print(f"  median of {args.repeats}: assembly {med['assembly_s']:.2f} s, modal "
          f"{med['modal_s']:.2f} s, total {total:.2f} s")
    print(f"  eigen step / (1 factorisation + the {mv0['n_block_solves']} solves this Lanczos "
          f"made) = {limit_ratio:.2f} wall, {own_cpu:.2f} CPU (target <= 1.2); assembly "
          f"{100 * asm_share:.0f} % of the total wall time, {100 * asm_share_cpu:.0f} % of "
          "its CPU (target < 15 %)")
    print(f"  eigen step / (1 factorisation + {2 * args.modes} single solves) = "
          f"{single_ratio:.2f} wall, {single_ratio_cpu:.2f} CPU (no Lanczos reaches "
          f"machine-precision residuals with {2 * args.modes} vectors: this one used "
          f"{mv0['n_solves']}, {mv0['alt_method']} {mv0['alt_n_solves']}); "
          f"against one solve of {2 * args.modes} right-hand sides {block_ratio:.2f}")
    print(f"  {mv0['alt_method']} (method='{mv0['alt_method']}', not the default): eigen "
          f"step {med['alt_eigsh_s']:.2f} s (cpu {med['alt_eigsh_cpu']:.2f} s) with "
          f"{mv0['alt_n_solves']} right-hand sides vs {mv0['method']} {med['eigsh_s']:.2f} s "
          f"(cpu {med['eigsh_cpu']:.2f} s) with {mv0['n_solves']}; eigenvalues agree to "
          f"{mv0['alt_fn_rel_diff']:.1e}")
    print("  CPU per right-hand side, one solve with k of them: " + ", ".join(
        f"k={k}: {1e3 * v:.1f} ms" for k, v in mv0["per_rhs_cpu"].items()))
    # where the CPU goes (medians; a single solve costs solves_2n / 2 n_modes, a solve
    # with the block width of the default method width_solve_cpu)
    if mv0["method"] == "block":
        solves = float(np.median([r[0]["width_solve_cpu"] for r in rounds])) \
            * mv0["n_block_solves"]
    else:
        solves = med["solves_2n_cpu"] / (2 * args.modes) * mv0["n_solves"]
    print(f"  CPU breakdown: assembly {med['assembly_cpu']:.2f} s; eigen step "
          f"{med['eigsh_cpu']:.2f} s = factorisation {med['factorize_cpu']:.2f} s + "
          f"{mv0['n_block_solves']} solves {solves:.2f} s + Lanczos and M products "
          f"{med['eigsh_cpu'] - med['factorize_cpu'] - solves:.2f} s; modal_analysis "
          f"beyond the eigen step (mode labels, rigid-mode check) "
          f"{med['modal_cpu'] - med['eigsh_cpu']:.2f} s, of which mode labels alone "
          f"{med['labels_cpu']:.2f} s")
    print(f"  fill nnz(L)+nnz(U), SuperLU: METIS {mv0['superlu_metis_fill']:,} "
          f"({mv0['superlu_metis_factorize_s']:.2f} s), MMD {mv0['superlu_mmd_fill']:,} "
          f"({mv0['superlu_mmd_factorize_s']:.2f} s)")
    if "superlu_eigsh_s" in mv0:
        print(f"  SuperLU-only eigen step (permissive default install): "
              f"{mv0['superlu_eigsh_s']:.2f} s vs {mv0['backend']} {mv0['eigsh_s']:.2f} s; "
              f"eigenvalues agree to {mv0['superlu_fn_rel_diff']:.1e}")
    print("  fn_hz:", np.round(fn, 4).tolist())
    print("  mvtk / Leissa - 1:", np.round(fn[:5] / ref - 1, 4).tolist())
    payload = {"figures": {"n_dof": mv0["n_dof"], "backend": mv0["backend"],
                           "n_solves": mv0["n_solves"], **{f"median_{k}": v
                                                           for k, v in med.items()},
                           "median_total_s": total, "limit_ratio": limit_ratio,
                           "limit_ratio_cpu": own_cpu,
                           "single_solve_limit_ratio": single_ratio,
                           "single_solve_limit_ratio_cpu": single_ratio_cpu,
                           "assembly_share": asm_share, "assembly_share_cpu": asm_share_cpu,
                           "block_limit_ratio": block_ratio,
                           "per_rhs_cpu": mv0["per_rhs_cpu"],
                           "alt_method": mv0["alt_method"],
                           "alt_n_solves": mv0["alt_n_solves"],
                           "alt_fn_rel_diff": mv0["alt_fn_rel_diff"],
                           "fill_metis": mv0["superlu_metis_fill"],
                           "fill_mmd": mv0["superlu_mmd_fill"],
                           "superlu_eigsh_s": mv0.get("superlu_eigsh_s"),
                           "fn_hz": fn.tolist()},
               "rounds": [{"mvtk": r[0], "opensees": r[1]} for r in rounds]}
    ops = [r for r in rounds if r[1] is not None]
    if ops:
        ratios = [o["eigen_s"] / (m["assembly_s"] + m["modal_s"]) for m, o in ops]
        cratios = [o["eigen_cpu"] / (m["assembly_cpu"] + m["modal_cpu"]) for m, o in ops]
        ofn = np.array(ops[0][1]["fn_hz"])
        agree_default = float(np.max(np.abs(fn / ofn - 1)))
        pfn = np.array(mv0["fn_hz_opensees_formulation"])
        agree = float(np.max(np.abs(pfn / ofn - 1)))
        print(f"OpenSeesPy ShellMITC4: eigen({args.modes}) median "
              f"{np.median([o['eigen_s'] for _, o in ops]):.2f} s")
        print("  fn_hz:", np.round(ofn, 4).tolist())
        print(f"  mvtk with OpenSees' formulation (drilling penalty A66, no shell rotary "
              f"inertia) vs OpenSees, same model: max |rel diff| {agree:.1e} (target 1e-4)")
        print(f"  mvtk default formulation (drilling 1e-3 A66, rotary inertia kept) vs "
              f"OpenSees: max |rel diff| {agree_default:.1e} (a modelling difference, "
              "docs/guide/fe.md)")
        print(f"  speed ratio OpenSees eigen / mvtk (assembly + modal): per round "
              f"{[round(x, 1) for x in ratios]}, median {np.median(ratios):.1f}x wall "
              f"(target 50x), {np.median(cratios):.1f}x cpu")
        payload["peer"] = "OpenSeesPy ShellMITC4 eigen"
        payload["ratios"] = {"median_wall": float(np.median(ratios)),
                             "median_cpu": float(np.median(cratios)),
                             "per_round_wall": ratios}
        payload["figures"]["opensees_median_eigen_s"] = float(
            np.median([o["eigen_s"] for _, o in ops]))
        payload["figures"]["fn_max_rel_diff_vs_opensees"] = agree
        payload["figures"]["fn_max_rel_diff_default_vs_opensees"] = agree_default
    if not args.skip_large:
        # fresh processes, as the 49 140-DOF rounds; the median run by its limit ratio
        # is reported (one run moved between 1.10 and 1.23 on the shared machine)
        runs = []
        for _ in range(args.large_repeats):
            run = _run_child("mvtk", "182", str(args.modes), "0")
            run["limit_ratio"] = run["eigsh_s"] / own_limit(run, "s")
            run["limit_ratio_cpu"] = run["eigsh_cpu"] / own_limit(run, "cpu")
            runs.append(run)
        per_run = [r["limit_ratio"] for r in runs]
        big = runs[int(np.argsort(per_run)[len(runs) // 2])]
        big["limit_ratio_per_run"] = per_run
        big["single_solve_limit_ratio"] = big["eigsh_s"] / (big["factorize_s"]
                                                            + big["solves_2n_s"])
        big["assembly_share_cpu"] = big["assembly_cpu"] / (big["assembly_cpu"]
                                                           + big["modal_cpu"])
        print(f"200k case [{big['backend']}]: {big['n_dof']} DOF, wall: assembly "
              f"{big['assembly_s']:.2f} s, modal {big['modal_s']:.2f} s (cpu "
              f"{big['assembly_cpu']:.2f} + {big['modal_cpu']:.2f} s, assembly "
              f"{100 * big['assembly_share_cpu']:.0f} %); eigen step {big['eigsh_s']:.2f} s "
              f"(cpu {big['eigsh_cpu']:.2f} s) vs 1 factorisation {big['factorize_s']:.2f} s "
              f"+ the {big['n_block_solves']} solves made: {big['limit_ratio']:.2f}x wall, "
              f"{big['limit_ratio_cpu']:.2f}x CPU (target <= 1.2; median of "
              f"{len(per_run)} runs: {', '.join(f'{x:.2f}' for x in per_run)}; vs "
              f"{2 * args.modes} single solves {big['single_solve_limit_ratio']:.2f}x); peak "
              f"RSS {big['peak_rss_mib']:.0f} MiB; load {big['load_before']:.1f}")
        payload["figures"]["large_200k"] = {k: big[k] for k in (
            "n_dof", "assembly_s", "modal_s", "assembly_cpu", "modal_cpu", "eigsh_s",
            "eigsh_cpu", "factorize_s", "factorize_cpu", "solves_2n_s", "solves_2n_cpu",
            "limit_ratio", "limit_ratio_cpu", "single_solve_limit_ratio",
            "limit_ratio_per_run", "n_block_solves", "assembly_share_cpu", "peak_rss_mib",
            "backend", "load_before")}
    write_result("fe", payload)



# ------------------------------------------------------------------ imported curved shell
def _cylindrical_panel_msh(path: Path, n_theta: int, n_axial: int) -> int:
    """Gmsh 2.2 file of a cylindrical panel (R 2 m, 90 deg, 4 m long), quads + clamp line.

    Physical groups: "panel" (quads) and "clamp" (the lines of the straight edge at
    theta = 0, a node set after import). Returns the number of nodes.
    """
    import meshio

    R, span, length = 2.0, np.pi / 2, 4.0
    th = np.linspace(0.0, span, n_theta + 1)
    z = np.linspace(0.0, length, n_axial + 1)
    T, Z = np.meshgrid(th, z, indexing="ij")
    nodes = np.column_stack([R * np.cos(T).ravel(), R * np.sin(T).ravel(), Z.ravel()])
    i, j = np.meshgrid(np.arange(n_theta), np.arange(n_axial), indexing="ij")
    base = (i * (n_axial + 1) + j).ravel()
    quads = np.column_stack([base, base + n_axial + 1, base + n_axial + 2, base + 1])
    edge = np.arange(n_axial + 1)  # theta = 0
    lines = np.column_stack([edge[:-1], edge[1:]])
    phys = [np.full(len(quads), 1), np.full(len(lines), 2)]
    meshio.Mesh(nodes, [("quad", quads), ("line", lines)],
                cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                field_data={"panel": np.array([1, 2]), "clamp": np.array([2, 1])}
                ).write(path, file_format="gmsh22", binary=True)
    return len(nodes)


def child_imported(kind: str, n_a: int, n_b: int) -> dict:
    """Assembly of the imported curved panel (``kind="imported"``) or of the built-in
    rectangular plate (``kind="builtin"``, n_a x n_b elements), in a fresh process."""
    import tempfile

    import mvtk.fe as fe

    steel = fe.IsotropicMaterial("steel", E, NU, RHO)
    out: dict = {"kind": kind, "load_before": os.getloadavg()[0]}
    if kind == "builtin":
        t = _clock()
        model = fe.plate_model(A, A, [fe.Ply(steel, H)], nx=n_a, ny=n_b, clamp="x0")
        out["assembly_s"], out["assembly_cpu"] = _since(t)
        out["read_s"] = 0.0
    else:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "panel.msh"
            t = time.perf_counter()
            out["n_nodes"] = _cylindrical_panel_msh(path, n_a, n_b)
            out["write_s"] = time.perf_counter() - t
            out["file_mib"] = path.stat().st_size / 2**20
            rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            t = _clock()
            mesh = fe.read_mesh(path)
            out["read_s"], out["read_cpu"] = _since(t)
        t = _clock()
        model = fe.mesh_model(mesh, {"panel": fe.Laminate([fe.Ply(steel, 0.01)])},
                              supports={"clamp": "clamped"})
        out["assembly_s"], out["assembly_cpu"] = _since(t)
        out["rss_before_read_mib"] = rss_before
    out["n_dof"] = model.n_dof
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out["load_after"] = os.getloadavg()[0]
    return out


def run_imported(n_theta: int = 180, n_axial: int = 182, n_builtin: int = 182) -> dict:
    """Imported 200 000-DOF curved shell against the built-in rectangle, per DOF."""
    imp = _run_child("imported", "imported", str(n_theta), str(n_axial))
    ref = _run_child("imported", "builtin", str(n_builtin), str(n_builtin))
    per_imp = (imp["read_s"] + imp["assembly_s"]) / imp["n_dof"]
    per_ref = ref["assembly_s"] / ref["n_dof"]
    asm_ratio = (imp["assembly_s"] / imp["n_dof"]) / per_ref
    mem_ratio = (imp["peak_rss_mib"] / imp["n_dof"]) / (ref["peak_rss_mib"] / ref["n_dof"])
    print(f"imported curved shell (Gmsh .msh, {imp['n_nodes']} nodes, "
          f"{imp['file_mib']:.1f} MiB): {imp['n_dof']} free DOF; read {imp['read_s']:.2f} s, "
          f"assembly {imp['assembly_s']:.2f} s (cpu {imp['assembly_cpu']:.2f} s); peak RSS "
          f"{imp['peak_rss_mib']:.0f} MiB; load {imp['load_before']:.1f}")
    print(f"built-in rectangle {n_builtin}x{n_builtin}: {ref['n_dof']} free DOF; assembly "
          f"{ref['assembly_s']:.2f} s (cpu {ref['assembly_cpu']:.2f} s); peak RSS "
          f"{ref['peak_rss_mib']:.0f} MiB; load {ref['load_before']:.1f}")
    print(f"per DOF, imported / built-in: assembly {asm_ratio:.2f}x, read + assembly "
          f"{per_imp / per_ref:.2f}x, peak RSS {mem_ratio:.2f}x")
    figures = {"imported": imp, "builtin": ref, "assembly_ratio_per_dof": asm_ratio,
               "read_assembly_ratio_per_dof": per_imp / per_ref,
               "peak_rss_ratio_per_dof": mem_ratio}
    write_result("fe_imported", {"figures": figures})
    return figures


if __name__ == "__main__":
    main()
