"""Reduced-basis (Rayleigh-Ritz) eigenvalues of a parameter study, with an error bound.

A parameter study solves the same model for many parameter values. Two facts make
most of that work avoidable:

1. **The matrices are polynomials in the parameters.** The shell element matrices are
   linear in the section's ABD, shear and inertia terms, which are linear in a modulus
   or density and polynomial (degree <= 3) in a ply thickness. :class:`Decomposition`
   does not assume this: it builds the model at the centre and at ``p0 +- w_i`` along
   each parameter, finds from these builds which of K and M depend on each parameter
   and whether affinely (second difference zero to round-off; otherwise taken as
   cubic), then builds a tensor grid of interpolation points (parameters that no
   matrix shares ride on one grid axis) and **checks** the interpolant against one
   more real build off the grid; any mismatch above :data:`CHECK_REL` (or a change of
   the DOFs) and the study falls back to solving every sample in full. Per sample,
   ``K(p) = sum_g w_g(p) K_g`` (Lagrange weights) replaces the build.
2. **The lowest eigenvectors move little.** :class:`ReducedBasis` solves the centre
   model in full and spans its lowest ``n_modes + 2`` eigenvectors ``phi_j`` and, per
   parameter, ``K0^-1 b`` and ``K0^-1 M0 K0^-1 b`` with ``b = (dK - lambda_j dM) phi_j``
   (the first terms of the Neumann series of the eigenvector derivative). A sample is
   the Rayleigh-Ritz solution on this basis (``V' K(p) V`` from the precomputed
   ``V' K_g V``) and costs one block solve with the centre factorisation ``K0``.

Error bound (Kato-Temple, in the ``K^-1`` inner product). With a Ritz pair
``(theta_j, x_j)``, ``x_j' M x_j = 1`` and residual ``r_j = K x_j - theta_j M x_j``, the
eigenvalue ``mu = 1/lambda`` of ``K^-1/2 M K^-1/2`` nearest to ``1/theta_j`` satisfies
``|lambda - theta_j| / lambda <= r_j' K^-1 r_j / (theta_j^2 delta_j)`` where ``delta_j``
is the distance of ``1/theta_j`` to the rest of that spectrum. The bound stored per
sample replaces ``K^-1`` by ``2 K0^-1`` (valid when ``K(p) >= K0 / 2``, i.e. no
stiffness direction of the sample below half the centre's; a sample whose Ritz values
moved by more than a factor 1.6 from the centre's is solved in full instead),
``delta_j`` by half its Ritz estimate (neighbouring Ritz values, the ``n_modes + 1``-th
included), and halves the result for a frequency (``f ~ sqrt(lambda)``). A sample
whose bound exceeds the tolerance gets one correction step (the basis plus
``K0^-1 r_j``, a second Rayleigh-Ritz and a new bound); if that also fails, the sample
is built and solved in full like every sample of the exact path.
"""

from __future__ import annotations

import hashlib
import itertools
import pickle
import threading
from collections import OrderedDict

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import MvtkError

__all__ = ["Decomposition", "ReducedBasis", "reduced_setup", "cached_box", "clear_cache",
           "CHECK_REL"]

#: Largest accepted mismatch (relative to the largest matrix entry) between the
#: interpolated K, M and a real build at the check point.
CHECK_REL = 1e-11
#: A parameter is "affine" when its second difference is below this fraction of its
#: first difference (round-off is ~1e-15 of it).
AFFINE_REL = 1e-9
#: Ritz values outside [1/RATIO_LIMIT, RATIO_LIMIT] x the centre eigenvalues: full solve.
RATIO_LIMIT = 1.6
#: Extra centre eigenvectors beyond ``n_modes`` (the Ritz value ``n_modes + 1`` bounds
#: the gap of the highest mode wanted).
EXTRA_MODES = 2
#: Neumann terms of the eigenvector derivatives in the basis.
NEUMANN_TERMS = 2

_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 1
_LOCK = threading.Lock()


class _NotReducible(Exception):
    """The study cannot use the reduced path (reason in the message)."""


def _canonical(A) -> sp.csr_matrix:
    A = sp.csr_matrix(A, dtype=float, copy=True)
    A.sum_duplicates()
    A.sort_indices()
    return A


def _max_abs(A) -> float:
    return float(np.abs(A.data).max()) if A.nnz else 0.0


def _lagrange(nodes: np.ndarray, s: float) -> np.ndarray:
    """Lagrange basis polynomials of ``nodes`` evaluated at ``s``."""
    out = np.ones(len(nodes))
    for k, xk in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != k:
                out[k] *= (s - xm) / (xk - xm)
    return out


#: Interpolation nodes (scaled parameter) per degree; 0 lets the probes serve the grid.
_NODES = {1: np.array([-1.0, 1.0]), 3: np.array([-1.0, 0.0, 0.5, 1.0])}


class Decomposition:
    """K(p) and M(p) as Lagrange interpolants on a tensor grid of real builds.

    Build with :meth:`from_builds`. ``s_i = (p_i - p0_i) / w_i`` is the scaled
    parameter; the grid spans ``s in [-1, 1]`` on every axis, so that every sample of the
    study lies inside the box of built (hence valid) models.
    """

    def __init__(self, p0, w, colors, degrees, depends, pattern_K, pattern_M, data_K,
                 data_M, n_builds, check_rel, dofs):
        self.p0, self.w = p0, w
        self.colors = colors            # list of lists of parameter indices
        self.degrees = degrees          # per colour: 1 or 3
        self.depends = depends          # {"K": bool array, "M": bool array}
        self.pattern_K, self.pattern_M = pattern_K, pattern_M
        self.data_K, self.data_M = data_K, data_M   # (n_grid, nnz)
        self.n_builds = n_builds
        self.check_rel = check_rel
        self.dofs = dofs

    # ------------------------------------------------------------------ grid
    @staticmethod
    def grid(colors, degrees) -> list[tuple[int, ...]]:
        return list(itertools.product(*[range(len(_NODES[d])) for d in degrees]))

    def weights(self, p: np.ndarray, which: str) -> np.ndarray:
        """Weights of the grid matrices of ``which`` ("K" or "M") at parameters ``p``."""
        s = (np.asarray(p, dtype=float) - self.p0) / self.w
        per_color = []
        for c, d in zip(self.colors, self.degrees):
            members = [i for i in c if self.depends[which][i]]
            sc = s[members[0]] if members else 0.0
            per_color.append(_lagrange(_NODES[d], sc))
        out = np.ones(1)
        for lc in per_color:
            out = np.multiply.outer(out, lc).ravel()
        return np.concatenate([[1.0], out])     # the centre, then the differences

    def matrices(self, p: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """Interpolated K(p), M(p)."""
        K = self.pattern_K.copy()
        K.data = self.weights(p, "K") @ self.data_K
        M = self.pattern_M.copy()
        M.data = self.weights(p, "M") @ self.data_M
        return K, M

    def grid_matrices(self, which: str):
        pat = self.pattern_K if which == "K" else self.pattern_M
        data = self.data_K if which == "K" else self.data_M
        for row in data:
            A = pat.copy()
            A.data = row.copy()
            yield A

    # ----------------------------------------------------------------- build
    @classmethod
    def from_builds(cls, build, p0: np.ndarray, w: np.ndarray) -> Decomposition:
        """Probe, grid and check; ``build(p) -> FEModel``. Raises _NotReducible."""
        n = len(p0)
        models = {}

        def at(s):
            key = tuple(float(v) for v in s)
            if key not in models:
                m = build(p0 + np.asarray(s) * w)
                if models:
                    ref = next(iter(models.values()))[2]
                    if (m.K.shape != ref.K.shape
                            or not np.array_equal(m.dof_node, ref.dof_node)
                            or not np.array_equal(m.dof_component, ref.dof_component)):
                        raise _NotReducible("the parameters change the model's DOFs")
                models[key] = (_canonical(m.K), _canonical(m.M), m)
            return models[key]

        K0, M0, m0 = at(np.zeros(n))
        depends = {"K": np.zeros(n, bool), "M": np.zeros(n, bool)}
        degree = np.zeros(n, dtype=int)
        derivs = []
        for i in range(n):
            e = np.zeros(n)
            e[i] = 1.0
            Kp, Mp, _ = at(e)
            Km, Mm, _ = at(-e)
            d_i = 0
            for name, X0, Xp, Xm in (("K", K0, Kp, Km), ("M", M0, Mp, Mm)):
                first = _max_abs(Xp - Xm)
                if first <= 1e-14 * _max_abs(X0):
                    continue
                depends[name][i] = True
                second = _max_abs(Xp + Xm - 2 * X0)
                d_i = max(d_i, 1 if second <= AFFINE_REL * first else 3)
            degree[i] = d_i
            derivs.append(((Kp - Km) / (2 * w[i]), (Mp - Mm) / (2 * w[i])))
        # colours: parameters that no matrix depends on together share a grid axis
        colors: list[list[int]] = []
        for i in np.argsort(-degree, kind="stable"):
            if degree[i] == 0:
                continue
            for c in colors:
                if not any(depends[X][i] and any(depends[X][j] for j in c) for X in "KM"):
                    c.append(int(i))
                    break
            else:
                colors.append([int(i)])
        degrees = [int(max(degree[i] for i in c)) for c in colors]
        points = cls.grid(colors, degrees)
        # a grid point needs K at the coordinates of the parameters K depends on and M
        # at those of M: a probe that matches both (a modulus probe gives K, a density
        # probe M, at the thickness node 0) saves a build
        dep = {X: np.flatnonzero(depends[X]) for X in "KM"}

        def known(X, s):
            for key, (Kb, Mb, _) in models.items():
                if np.array_equal(np.asarray(key)[dep[X]], s[dep[X]]):
                    return Kb if X == "K" else Mb
            return None

        mats = []
        for g in points:
            s = np.zeros(n)
            for c, d, k in zip(colors, degrees, g):
                s[c] = _NODES[d][k]
            Kg, Mg = known("K", s), known("M", s)
            if Kg is None or Mg is None:
                Kg, Mg, _ = at(s)
            mats.append((Kg, Mg))
        pattern_K = _union([K for K, _ in mats] + [K0])
        pattern_M = _union([M for _, M in mats] + [M0])
        # K(p) = K0 + sum_g w_g (K_g - K0) (the weights sum to one): the sample carries
        # the round-off of one build (the centre's), not of the sum of the grid's
        base_K, base_M = _on_pattern(K0, pattern_K), _on_pattern(M0, pattern_M)
        data_K = np.vstack([base_K] + [_on_pattern(K, pattern_K) - base_K for K, _ in mats])
        data_M = np.vstack([base_M] + [_on_pattern(M, pattern_M) - base_M for _, M in mats])
        # the entries of K that are round-off in every build (couplings that cancel,
        # see mvtk.updating._roundoff) are dropped, as the full solve drops them
        data_K[:, _roundoff_entries(pattern_K, np.vstack([_on_pattern(K, pattern_K)
                                                          for K, _ in mats]))] = 0.0
        dec = cls(p0, w, colors, degrees, depends, pattern_K, pattern_M, data_K, data_M,
                  0, 0.0, (m0.dof_node, m0.dof_component))
        # check off the grid (inside the box) against a real build
        s_chk = np.array([(0.61, -0.37, 0.83, -0.71)[i % 4] for i in range(n)])
        Kc, Mc, _ = at(s_chk)
        Ki, Mi = dec.matrices(p0 + s_chk * w)
        rel = max(_entry_rel(Ki, Kc), _entry_rel(Mi, Mc))
        if not rel <= CHECK_REL:
            raise _NotReducible(
                f"K, M are not polynomial of the detected degrees in the parameters "
                f"(interpolation off by {rel:.2e} of the largest entry at the check point)")
        dec.n_builds = len(models)
        dec.check_rel = rel
        dec.nominal = (K0, M0, m0)
        dec.derivs = derivs
        return dec


def _union(mats) -> sp.csr_matrix:
    """Zero matrix on the union of the patterns (canonical CSR)."""
    first = mats[0]
    if all(A.nnz == first.nnz and np.array_equal(A.indptr, first.indptr)
           and np.array_equal(A.indices, first.indices) for A in mats[1:]):
        U = first.copy()
        U.data[:] = 0.0
        return U
    U = abs(first)
    for A in mats[1:]:
        U = U + abs(A)
    U = _canonical(U)
    U.data[:] = 0.0
    return U


def _roundoff_entries(P: sp.csr_matrix, data: np.ndarray) -> np.ndarray:
    """Mask of the entries of pattern ``P`` below ROUNDOFF_REL sqrt(|K_ii K_jj|) in every
    row of ``data`` (values of several matrices on ``P``)."""
    from ..updating._roundoff import ROUNDOFF_REL

    n = P.shape[0]
    rows = np.repeat(np.arange(n), np.diff(P.indptr))
    diag = rows == P.indices
    mask = ~diag
    for row in data:
        d = np.zeros(n)
        d[rows[diag]] = np.abs(row[diag])
        mask &= np.abs(row) <= ROUNDOFF_REL * np.sqrt(d[rows] * d[P.indices])
    return mask


def _entry_rel(A: sp.csr_matrix, B: sp.csr_matrix) -> float:
    """Largest ``|A_ij - B_ij| / |B_ij|`` over the entries of B above 1e-12 of its
    largest (a relative error on each physical entry: the bending entries of a thin
    shell are 1e-8 of its membrane ones, so the largest-entry scale would hide them),
    and ``|A_ij - B_ij|`` relative to the largest entry elsewhere."""
    P = _union([A, B])
    a, b = _on_pattern(A, P), _on_pattern(B, P)
    scale = np.abs(b).max() if b.size else 0.0
    if scale == 0.0:
        return float(np.abs(a).max()) if a.size else 0.0
    big = np.abs(b) > 1e-12 * scale
    d = np.abs(a - b)
    return float(max((d[big] / np.abs(b[big])).max(initial=0.0),
                     d[~big].max(initial=0.0) / scale))


def _on_pattern(A: sp.csr_matrix, P: sp.csr_matrix) -> np.ndarray:
    """Values of ``A`` on the (superset) pattern ``P``."""
    if (A.nnz == P.nnz and np.array_equal(A.indptr, P.indptr)
            and np.array_equal(A.indices, P.indices)):
        return A.data.copy()
    n = P.shape[1]
    rows_p = np.repeat(np.arange(P.shape[0]), np.diff(P.indptr))
    keys_p = rows_p.astype(np.int64) * n + P.indices
    rows_a = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    keys_a = rows_a.astype(np.int64) * n + A.indices
    pos = np.searchsorted(keys_p, keys_a)
    out = np.zeros(P.nnz)
    out[pos] = A.data
    return out


class ReducedBasis:
    """Rayleigh-Ritz basis at the centre and the per-sample solution with its bound.

    Accuracy notes (measured): the Ritz problem is solved with all its eigenvalues
    (LAPACK ``gvd``): a subset driver's absolute tolerance ``~eps ||V' K V||`` cost the
    lowest Ritz value 1e-8 of its value, the basis holding stiff directions. The
    derivative vectors are solves ``K0^-1 c`` whose right-hand sides are first deflated
    against the centre modes (see :meth:`_deflate`); removing those modes from the
    solutions instead cancels a component 1/lambda_1 larger than the rest.
    """

    def __init__(self, dec: Decomposition, n_modes: int):
        from .._blas import blas_limits as _blas_limits
        from ..fe import eigsh_lowest, factorize

        self.dec = dec
        self.n_modes = n_modes
        _, M0, _ = dec.nominal
        K0 = dec.pattern_K.copy()
        K0.data = dec.data_K[0].copy()
        K0.eliminate_zeros()
        k = n_modes + EXTRA_MODES
        if 4 * (k + NEUMANN_TERMS * n_modes * len(dec.p0)) > K0.shape[0]:
            raise _NotReducible("the model is too small for a reduced basis")
        with _blas_limits():
            self.factor = factorize(K0)
            sol = eigsh_lowest(K0, M0, k, singular_shift=_raise_singular)
            lam = np.asarray(sol.omega2, dtype=float)
            if not (lam.min() > 0 and lam.min() >= 1e-4 * lam.max()):
                raise _NotReducible("the centre model has (near-)rigid-body modes")
            phi = sol.vectors
            ph, lw = phi[:, :n_modes], lam[:n_modes]
            rhs = [dK @ ph - (dM @ ph) * lw for dK, dM in dec.derivs]
            # the centre modes enter as K0^-1 M0 phi (= phi / lambda), the derivative
            # terms as solves of right-hand sides deflated against them
            Q, YQ = _m_orthonormal_pair(self.factor.solve(M0 @ phi), M0 @ phi, M0)
            self.Q, self.YQ = Q, YQ
            self.P = self.factor.solve(M0 @ Q)              # K0^-1 M0 Q
            S, Y = [Q], [YQ]
            if rhs:
                y = self._deflate(np.column_stack(rhs))
                for _ in range(NEUMANN_TERMS):
                    S.append(self.factor.solve(y))
                    Y.append(y)
                    y = self._deflate(M0 @ S[-1])
            S, Y = _m_orthonormal_pair(np.column_stack(S), np.column_stack(Y), M0)
            # K0 S by a direct product: measured more accurate for the lowest Ritz
            # value than S' K0 S = Y' S from the solves (the smart beam's f1 at the
            # centre: 8e-11 against 4.5e-9; the solve's backward error enters Y' S)
            self.K0 = K0
            self.S, self.Y = S, K0 @ S
            self.MS0 = M0 @ S
            G0 = S.T @ self.Y
            self.G0 = (G0 + G0.T) / 2                       # S' K0 S
            rows = list(dec.grid_matrices("K"))[1:]         # the differences K_g - K0
            self.DgS = np.stack([A @ S for A in rows])
            self.MgS = np.stack([A @ S for A in dec.grid_matrices("M")])
            self.SDS = np.stack([S.T @ A for A in self.DgS])
            self.SMS = np.stack([S.T @ A for A in self.MgS])
        self.lam0 = lam[: n_modes + 1]
        self.basis_size = S.shape[1]
        self.n_solves_setup = self.factor.n_solves

    # ------------------------------------------------------------------ sample
    def solve(self, p: np.ndarray, tol: float):
        """``(fn_hz, bound, path)`` of one sample, or ``(None, bound, reason)`` when the
        reduced path cannot give it within ``tol`` (then it is solved in full)."""
        from .._blas import blas_limits as _blas_limits

        dec = self.dec
        s = (p - dec.p0) / dec.w
        if np.any(np.abs(s) > 1.0 + 1e-12):
            return None, np.nan, "outside the built box"
        wK, wM = dec.weights(p, "K"), dec.weights(p, "M")
        k = self.n_modes + 1
        with _blas_limits():
            Kr = self.G0 + np.tensordot(wK[1:], self.SDS, axes=1)
            Mr = np.tensordot(wM, self.SMS, axes=1)
            theta, Yr = _ritz(Kr, Mr, k)
            if theta is None:
                return None, np.nan, "reduced matrices not definite"
            KS = self.Y + np.tensordot(wK[1:], self.DgS, axes=1)
            MS = np.tensordot(wM, self.MgS, axes=1)
            R = KS @ Yr[:, :-1] - (MS @ Yr[:, :-1]) * theta[:-1]
            Z = self.factor.solve(R)
            bound, why = self._bound(theta, R, Z)
            if why:
                return None, bound, why
            if bound <= tol:
                return np.sqrt(theta[:-1]) / (2 * np.pi), bound, "reduced"
            # one correction step: the basis plus K0^-1 r_j; only these few new
            # columns are multiplied by the sparse matrices
            dK = dec.pattern_K.copy()
            dK.data = wK[1:] @ dec.data_K[1:]
            _, M = dec.matrices(p)
            Z = Z - self.Q @ (self.P.T @ R)          # = K0^-1 of the deflated residual
            for _ in range(2):
                Z = Z - self.S @ (self.MS0.T @ Z)
            Z, _ = _m_orthonormal_pair(Z, Z, dec.nominal[1])
            KZ = self.K0 @ Z + dK @ Z
            MZ = M @ Z
            SKZ, SMZ = self.S.T @ KZ, self.S.T @ MZ
            ZKZ, ZMZ = Z.T @ KZ, Z.T @ MZ
            Kr = np.block([[Kr, SKZ], [SKZ.T, (ZKZ + ZKZ.T) / 2]])
            Mr = np.block([[Mr, SMZ], [SMZ.T, (ZMZ + ZMZ.T) / 2]])
            KW = np.column_stack([KS, KZ])
            MW = np.column_stack([MS, MZ])
            theta, Yr = _ritz(Kr, Mr, k)
            if theta is None:
                return None, np.nan, "reduced matrices not definite"
            R = KW @ Yr[:, :-1] - (MW @ Yr[:, :-1]) * theta[:-1]
            bound, why = self._bound(theta, R, self.factor.solve(R))
        if why:
            return None, bound, why
        if bound <= tol:
            return np.sqrt(theta[:-1]) / (2 * np.pi), bound, "reduced+correction"
        return None, bound, "bound above tol"

    def _deflate(self, c: np.ndarray) -> np.ndarray:
        """``c - K0 Q a`` such that ``K0^-1`` of it is M0-orthogonal to the centre
        modes ``Q``: the deflation is made on the right-hand side (``a = P' c``,
        ``P = K0^-1 M0 Q``), where nothing cancels, instead of removing from a solve
        its lowest-mode part, 1/lambda_1 larger than the rest, which would cost that
        ratio in precision."""
        return c - self.YQ @ (self.P.T @ c)

    def _bound(self, theta, R, Z):
        """Largest relative frequency error bound over the modes, or (bound, reason)."""
        ratio = theta / self.lam0
        if np.any(ratio > RATIO_LIMIT) or np.any(ratio < 1.0 / RATIO_LIMIT):
            return np.nan, "far from the centre"
        e = 2.0 * np.einsum("ij,ij->j", R, Z)             # r' K^-1 r <= 2 r' K0^-1 r
        mu = 1.0 / theta
        n = len(theta) - 1
        delta = np.array([np.min(np.abs(np.delete(mu, j) - mu[j])) for j in range(n)]) / 2
        th = theta[:n]
        # the Ritz value must be matched to its own eigenvalue: the linear (Weinstein)
        # bound in mu, sqrt(r' K^-1 r / theta^3), must stay inside half the gap
        if np.any(~(np.sqrt(np.maximum(e, 0) / th**3) < delta)):
            return np.inf, "Ritz values not separated"
        return float(np.max(np.maximum(e, 0) / (th**2 * delta) / 2)), ""


def _raise_singular():
    raise _NotReducible("the centre stiffness is singular")


def _ritz(Kr, Mr, k):
    Kr = (Kr + Kr.T) / 2
    Mr = (Mr + Mr.T) / 2
    try:
        # all eigenvalues (divide and conquer): the subset drivers' absolute tolerance
        # ~eps ||Kr|| costs the lowest Ritz value 1e-8 of its value when the basis
        # also holds stiff directions (measured: 3.6e-8 instead of 3e-9 on a strip)
        theta, Y = sla.eigh(Kr, Mr, driver="gvd")
    except (np.linalg.LinAlgError, ValueError):
        return None, None
    theta, Y = theta[:k], Y[:, :k]
    if not theta[0] > 0:
        return None, None
    return theta, Y


def _m_orthonormal_pair(S: np.ndarray, Y: np.ndarray, M) -> tuple[np.ndarray, np.ndarray]:
    """``(S T, Y T)`` with ``S T`` an M-orthonormal basis of ``span(S)`` (directions below
    1e-10 of the largest, columns first scaled to unit M-norm, are dropped); the same
    ``T`` applied to ``Y = K0 S`` keeps it ``K0`` times the basis."""
    G = S.T @ (M @ S)
    d = np.sqrt(np.abs(np.diag(G)))
    d[d == 0] = 1.0
    Gn = G / d[:, None] / d[None, :]
    w, E = np.linalg.eigh((Gn + Gn.T) / 2)
    keep = w > 1e-10 * max(w.max(), 1e-300)
    T = (E[:, keep] / np.sqrt(w[keep])) / d[:, None]
    return S @ T, Y @ T


def _key(description, paths, p0, n_modes, builder) -> bytes | None:
    try:
        blob = pickle.dumps((description, list(paths), np.asarray(p0).tobytes(),
                             int(n_modes), builder), protocol=4)
    except (pickle.PicklingError, TypeError, AttributeError):
        return None
    return hashlib.blake2b(blob, digest_size=20).digest()


def cached_box(description, paths, p0, n_modes, builder, values) -> np.ndarray | None:
    """Half-widths ``w`` of the cached setup with this centre when its box holds every
    row of ``values`` (so a study inside a previous one's box reuses its basis)."""
    key = _key(description, paths, p0, n_modes, builder)
    with _LOCK:
        entry = _CACHE.get(key) if key is not None else None
    if entry is None:
        return None
    w, _ = entry
    if np.all(np.abs(np.asarray(values) - p0) <= w * (1 + 1e-12)):
        return w
    return None


def clear_cache() -> None:
    """Drop the cached reduced basis (its grid matrices and centre factorisation)."""
    with _LOCK:
        _CACHE.clear()


def reduced_setup(description, paths, p0, w, n_modes, builder):
    """The :class:`ReducedBasis` of a study (or a str: why there is none).

    Deterministic in its arguments; the last one is kept (per process), keyed by the
    description, paths, centre, ``n_modes`` and builder, so the batches of a cluster
    run, and a later study inside the same box, reuse it.
    """
    from ..updating import with_values

    p0 = np.asarray(p0, dtype=float)
    w = np.asarray(w, dtype=float)
    key = _key(description, paths, p0, n_modes, builder)
    with _LOCK:
        if key is not None and key in _CACHE and np.array_equal(_CACHE[key][0], w):
            _CACHE.move_to_end(key)
            return _CACHE[key][1]

        def build(p):
            return builder(with_values(description, dict(zip(paths, map(float, p)))))

        try:
            out = ReducedBasis(Decomposition.from_builds(build, p0, w), n_modes)
        except _NotReducible as err:
            out = str(err)
        except (MvtkError, ArithmeticError, np.linalg.LinAlgError) as err:
            out = f"a build of the grid failed ({type(err).__name__}: {err})"
        if key is not None:
            _CACHE[key] = (w, out)
            _CACHE.move_to_end(key)
            while len(_CACHE) > _CACHE_SIZE:
                _CACHE.popitem(last=False)
        return out
