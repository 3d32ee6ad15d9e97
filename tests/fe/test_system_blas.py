"""CHOLMOD on the system's OpenBLAS instead of the reference BLAS its wheel bundles.

Each case runs in a fresh interpreter, because the BLAS is chosen once per process, before
``sksparse_minimal`` is imported. The dynamic loader's own trace (``LD_DEBUG=bindings``) is
the truth for which library CHOLMOD's ``dgemm_`` and ``dpotrf_`` calls reach.
"""

from __future__ import annotations

import ctypes.util
import importlib.util
import json
import os
import subprocess
import sys

import pytest

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ELF symbol binding"),
    pytest.mark.skipif(importlib.util.find_spec("sksparse_minimal") is None,
                       reason="the cholmod extra (sksparse-minimal) is not installed"),
]

needs_openblas = pytest.mark.skipif(
    ctypes.util.find_library("openblas") is None,
    reason="no system OpenBLAS (Debian libopenblas0; scripts/system_packages.sh installs it)")

# a 2-D Laplacian (30 x 300 grid): large enough for supernodes that call dgemm_/dpotrf_
CHILD = r"""
import json, sys
import numpy as np, scipy.sparse as sp, scipy.sparse.linalg as spla
import mvtk.fe as fe
n1, n2 = 30, 300
T = lambda n: sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
K = (sp.kron(T(n2), sp.eye(n1)) + sp.kron(sp.eye(n2), T(n1)) + 1e-3 * sp.eye(n1 * n2)).tocsc()
b = np.random.default_rng(0).standard_normal(n1 * n2)
f = fe.factorize(K)
x = f.solve(b)
ref = spla.spsolve(K, b)
print(json.dumps({"backend": f.backend, "detail": fe.sparse_backend(detail=True),
                  "rel_diff": float(np.linalg.norm(x - ref) / np.linalg.norm(ref))}))
"""


def _run(env_extra: dict) -> tuple[dict, dict]:
    env = {**os.environ, "LD_DEBUG": "bindings", **env_extra}
    env.pop("MVTK_SPARSE_BACKEND", None)
    proc = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                          env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    # "binding file <cholmod extension> [0] to <library> [0]: normal symbol `dgemm_'"
    bound = {}
    for line in proc.stderr.splitlines():
        if "_cholespy_core" not in line.split(" to ")[0]:
            continue
        for sym in ("dgemm_", "dpotrf_"):
            if line.endswith(f"`{sym}'"):
                bound[sym] = line.split(" to ", 1)[1].split(" [")[0]
    return out, bound


@needs_openblas
def test_cholmod_calls_reach_the_system_openblas():
    out, bound = _run({})
    assert out["backend"] == "cholmod"
    assert "OpenBLAS" in out["detail"]
    assert set(bound) == {"dgemm_", "dpotrf_"}, bound
    for sym, lib in bound.items():
        assert "openblas" in lib and "sksparse_minimal" not in lib, (sym, lib)
    assert out["rel_diff"] < 1e-10


def test_bundled_blas_on_request_and_the_same_solution():
    out, bound = _run({"MVTK_CHOLMOD_BLAS": "bundled"})
    assert out["backend"] == "cholmod"
    assert "reference BLAS bundled" in out["detail"]
    assert bound and all("sksparse_minimal" in lib for lib in bound.values()), bound
    assert out["rel_diff"] < 1e-10


def test_a_bad_library_is_named():
    env = {**os.environ, "MVTK_CHOLMOD_BLAS": "/nonexistent/libnothing.so"}
    proc = subprocess.run(
        [sys.executable, "-c", "import mvtk.fe as fe; fe.sparse_backend()"],
        capture_output=True, text=True, env=env, timeout=60)
    assert proc.returncode != 0
    assert "MVTK_CHOLMOD_BLAS='/nonexistent/libnothing.so'" in proc.stderr
    assert "dgemm_" in proc.stderr


def test_report_provenance_names_the_sparse_solver():
    from mvtk.fe import sparse_backend
    from mvtk.report import collect_provenance

    versions = collect_provenance().versions
    assert versions["sparse solver (FE)"] == sparse_backend(detail=True)
    assert "/" not in versions["sparse solver (FE)"]     # no path of the machine
