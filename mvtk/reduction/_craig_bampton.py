"""Craig-Bampton (and Guyan) reduction of an :class:`~mvtk.fe.FEModel`.

The boundary (retained) DOFs ``l`` keep their physical meaning; the interior DOFs ``f``
are represented by static constraint modes and a few fixed-interface normal modes::

    u = T q,   T = [[I, 0], [Psi, Phi]],   Psi = -K_ff^-1 K_fl,
    (K_ff - nu^2 M_ff) phi = 0,  phi' M_ff phi = 1.

References
----------
R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses",
AIAA Journal 6(7), 1313-1319, 1968. PHYSICS.md section 3.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import AccuracyWarning, ConvergenceError, DimensionError, ParameterError
from ..fe import DOF_NAMES, Factorization, FEModel, eigsh_lowest, factorize
from ..fe._solvers import _blas_limits
from ._retained import resolve_retained

__all__ = [
    "SuperElement",
    "craig_bampton",
    "guyan",
    "fixed_interface_modes",
    "reduced_modes",
    "ReducedModes",
]

#: Interior sizes up to this use a dense generalised eigen solver.
_DENSE_LIMIT = 600


@dataclass(frozen=True, eq=False)
class SuperElement:
    """A Craig-Bampton super element: reduced matrices, transformation and labels.

    Reduced coordinates are ``q = [u_l; eta]``: the physical boundary DOFs (m, rad)
    followed by the fixed-interface modal coordinates (sqrt(kg) m, mass-normalised).

    Attributes
    ----------
    M, K : ndarray, shape (n_r, n_r)
        Reduced mass and stiffness, ``T' M T`` and ``T' K T`` (symmetrised).
    T : ndarray, shape (n_dof, n_r)
        Transformation from reduced coordinates to the free DOFs of ``model``.
    boundary_dofs : ndarray of int, shape (n_boundary,)
        Free-DOF indices (in ``model``) of the boundary coordinates.
    interior_fn_hz : ndarray, shape (n_modes,)
        Fixed-interface natural frequencies in Hz.
    labels : tuple of str
        ``"n{node}:{component}"`` for boundary DOFs, ``"eta{i}"`` for modal coordinates.
    model : FEModel
        The full model the super element was reduced from.
    retained_nodes : ndarray of int
        Nodes named as boundary, including fully constrained ones (e.g. a clamp node,
        which has no free DOF and hence no coordinate). Used for the size table.
    meta : dict
        How it was built (criterion, requested fraction/cutoff, ...).

    Examples
    --------
    Returned by :func:`craig_bampton`: 6 boundary DOFs of the tip node and 4
    fixed-interface modes:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> se = craig_bampton(beam, [int(beam.node_sets["tip"][0])], n_modes=4)
    >>> se.K.shape, se.T.shape, np.round(se.interior_fn_hz, 1)
    ((10, 10), (120, 10), array([ 118.1,  325.5,  637.7, 1030.9]))
    """

    M: np.ndarray
    K: np.ndarray
    T: np.ndarray
    boundary_dofs: np.ndarray
    interior_fn_hz: np.ndarray
    labels: tuple[str, ...]
    model: FEModel
    retained_nodes: np.ndarray | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.retained_nodes is None:
            nodes = np.unique(self.model.dof_node[self.boundary_dofs])
        else:
            nodes = np.unique(np.asarray(self.retained_nodes, dtype=np.int64))
        object.__setattr__(self, "retained_nodes", nodes)

    # ----------------------------------------------------------------- sizes
    @property
    def n_boundary(self) -> int:
        """Number of boundary (physical) coordinates."""
        return int(self.boundary_dofs.size)

    @property
    def n_modes(self) -> int:
        """Number of fixed-interface modal coordinates (0 for Guyan)."""
        return int(self.interior_fn_hz.size)

    @property
    def n_dof(self) -> int:
        """Number of reduced coordinates ``n_boundary + n_modes``."""
        return self.M.shape[0]

    @property
    def boundary_nodes(self) -> np.ndarray:
        """Sorted unique node indices carrying boundary DOFs."""
        return np.unique(self.model.dof_node[self.boundary_dofs])

    @property
    def n_nodes(self) -> int:
        """Number of nodes of the super element (the retained nodes, incl. constrained)."""
        return int(self.retained_nodes.size)

    # --------------------------------------------------------------- methods
    def damping(
        self,
        alpha: float = 0.0,
        beta: float = 0.0,
        modal_damping: float | Iterable[float] | None = None,
    ) -> np.ndarray:
        """Reduced damping matrix (N s/m and consistent units).

        Parameters
        ----------
        alpha : float
            Rayleigh mass coefficient in 1/s.
        beta : float
            Rayleigh stiffness coefficient in s. ``alpha M_r + beta K_r`` equals the
            projection ``T' (alpha M + beta K) T`` of the full damping exactly.
        modal_damping : float or sequence of float, optional
            Damping ratio(s) of the super element's own eigenmodes (one value for all
            or one per mode with finite frequency, see :func:`reduced_modes`):
            ``C = M Phi diag(2 zeta omega) Phi' M``.
            Not combinable with non-zero ``alpha``/``beta``.

        Returns
        -------
        ndarray, shape (n_r, n_r)
        """
        return damping_matrix(self.M, self.K, alpha, beta, modal_damping)

    def expand(self, q: np.ndarray) -> np.ndarray:
        """Free-DOF vector(s) ``T q`` of the full model from reduced coordinates.

        Parameters
        ----------
        q : ndarray, shape (n_r,) or (n_r, k)

        Returns
        -------
        ndarray, shape (n_dof,) or (n_dof, k)
        """
        q = np.asarray(q)
        if q.shape[0] != self.n_dof:
            raise DimensionError(
                f"expected {self.n_dof} reduced coordinates (rows), got {q.shape[0]}"
            )
        return self.T @ q

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self):
        """Table of reduced coordinates: label, kind, node, component, fn_hz."""
        import pandas as pd

        nb = self.n_boundary
        nodes = self.model.dof_node[self.boundary_dofs]
        comps = [DOF_NAMES[c] for c in self.model.dof_component[self.boundary_dofs]]
        return pd.DataFrame(
            {
                "label": list(self.labels),
                "kind": ["boundary"] * nb + ["fixed_interface_mode"] * self.n_modes,
                "node": [int(n) for n in nodes] + [None] * self.n_modes,
                "component": comps + [None] * self.n_modes,
                "fn_hz": [np.nan] * nb + list(self.interior_fn_hz),
            }
        )


@dataclass(frozen=True)
class ReducedModes:
    """Eigenpairs of a small dense ``(K, M)`` whose ``M`` may be singular.

    Attributes
    ----------
    omega2 : ndarray, shape (k,)
        Finite eigenvalues in (rad/s)^2, ascending.
    vectors : ndarray, shape (n, k)
        Mass-normalised eigenvectors of the finite eigenvalues.
    n_massless : int
        Number of infinite eigenvalues (coordinates without inertia, e.g. shell drilling
        rotations); ``k + n_massless = n``.

    Examples
    --------
    Returned by :func:`reduced_modes`:

    >>> res = reduced_modes(np.array([[2e5, -1e5], [-1e5, 1e5]]), np.eye(2))
    >>> res.vectors.shape, res.n_massless
    ((2, 2), 0)
    """

    omega2: np.ndarray
    vectors: np.ndarray
    n_massless: int

    @property
    def fn_hz(self) -> np.ndarray:
        """Natural frequencies in Hz."""
        return np.sqrt(np.clip(self.omega2, 0, None)) / (2 * np.pi)


def reduced_modes(K: np.ndarray, M: np.ndarray) -> ReducedModes:
    """All eigenpairs of a small dense structural pencil, robust to a singular ``M``.

    Reduced shell models carry boundary coordinates with (almost) no inertia (drilling
    rotations), which makes ``M`` numerically singular; ``scipy.linalg.eigh(K, M)``
    factorises ``M`` and then loses accuracy (1e-4 relative on the fundamental of the
    smart-beam SE). The inverse pencil ``M v = mu (K - sigma M) v`` factorises the
    stiffness instead; ``lambda = sigma + 1 / mu``. ``sigma = 0`` when ``K`` is positive
    definite, otherwise a small negative shift (rigid-body modes).

    Parameters
    ----------
    K, M : ndarray, shape (n, n)
        Symmetric stiffness (positive semi-definite) and mass (positive semi-definite).

    Returns
    -------
    ReducedModes

    Examples
    --------
    The 2-mass chain (1 kg, 1e5 N/m): ``omega**2 = k (3 -+ sqrt(5)) / 2``:

    >>> res = reduced_modes(np.array([[2e5, -1e5], [-1e5, 1e5]]), np.eye(2))
    >>> np.round(res.omega2, 1), res.n_massless
    (array([ 38196.6, 261803.4]), 0)
    """
    K = 0.5 * (np.asarray(K, dtype=float) + np.asarray(K, dtype=float).T)
    M = 0.5 * (np.asarray(M, dtype=float) + np.asarray(M, dtype=float).T)
    n = K.shape[0]
    if n == 0:
        return ReducedModes(np.zeros(0), np.zeros((0, 0)), 0)
    sigma = 0.0
    try:
        mu, v = sla.eigh(M, K)
    except np.linalg.LinAlgError:
        sigma = -1e-6 * abs(np.trace(K)) / max(abs(np.trace(M)), np.finfo(float).tiny)
        try:
            mu, v = sla.eigh(M, K - sigma * M)
        except np.linalg.LinAlgError as err:
            raise ParameterError(
                "the reduced stiffness is not positive semi-definite (or the mass has no "
                "positive part): cannot compute its modes"
            ) from err
    finite = mu > 1e-12 * np.max(np.abs(mu))
    mu, v = mu[finite], v[:, finite]
    order = np.argsort(-mu)
    mu, v = mu[order], v[:, order]
    w2 = sigma + 1.0 / mu
    v = v / np.sqrt(np.einsum("ij,ij->j", v, M @ v))
    big = np.argmax(np.abs(v), axis=0)
    v = v * np.sign(v[big, np.arange(v.shape[1])])
    return ReducedModes(omega2=w2, vectors=v, n_massless=int(n - mu.size))


def damping_matrix(M, K, alpha=0.0, beta=0.0, modal_damping=None) -> np.ndarray:
    """Rayleigh ``alpha M + beta K`` or modal damping for dense ``M``, ``K``."""
    alpha, beta = float(alpha), float(beta)
    if alpha < 0 or beta < 0:
        raise ParameterError(
            f"Rayleigh coefficients must be >= 0, got alpha={alpha}, beta={beta}"
        )
    if modal_damping is None:
        return alpha * M + beta * K
    if alpha or beta:
        raise ParameterError(
            "give either Rayleigh alpha/beta or modal_damping, not both "
            f"(got alpha={alpha}, beta={beta}, modal_damping={modal_damping!r})"
        )
    modes = reduced_modes(K, M)
    n = modes.omega2.size
    zeta = np.asarray(modal_damping, dtype=float)
    zeta = np.full(n, float(zeta)) if zeta.ndim == 0 else zeta
    if zeta.shape != (n,):
        raise DimensionError(
            f"modal_damping must be one ratio or {n} ratios (one per mode), got {zeta.shape}"
        )
    if np.any(zeta < 0):
        raise ParameterError(f"damping ratios must be >= 0, got min {zeta.min()}")
    omega = np.sqrt(np.clip(modes.omega2, 0.0, None))
    mphi = M @ modes.vectors
    return (mphi * (2.0 * zeta * omega)) @ mphi.T


def solve_columns(lu, B, chunk: int = 64) -> np.ndarray:
    """``A^-1 B`` for a factorisation ``lu`` of ``A``, ``chunk`` columns of ``B`` per solve.

    Both backends solve a block of right-hand sides faster than its columns one by one
    (the factor is swept once per block): the 30 constraint modes of the 49 140-DOF plate
    of ``benchmarks/bench_reduction.py`` took 0.28 s of CPU in one CHOLMOD solve against
    0.72 s column by column, and 0.50 s against 1.11 s with SuperLU (METIS-ordered, as
    :func:`mvtk.fe.factorize` makes it; scipy 1.17). ``chunk`` bounds the dense copy of
    a sparse ``B``.

    Parameters
    ----------
    lu : mvtk.fe.Factorization or scipy.sparse.linalg.SuperLU
        Anything with ``solve(b)`` accepting ``b`` of shape (n,) and (n, k).
    B : ndarray or sparse matrix, shape (n,) or (n, k)
    chunk : int
        Columns per solve (>= 1).

    Returns
    -------
    ndarray, shape of ``B``
        Fortran-ordered when 2-D.
    """
    if sp.issparse(B):
        B = sp.csc_matrix(B)
    else:
        B = np.asarray(B, dtype=float)
        if B.ndim == 1:
            return lu.solve(B)
    n, k = B.shape
    out = np.empty((n, k), order="F")
    for j in range(0, k, chunk):
        block = B[:, j:j + chunk]
        block = block.toarray() if sp.issparse(block) else np.ascontiguousarray(block)
        out[:, j:j + chunk] = lu.solve(block).reshape(n, -1)
    return out


def _constraint_modes(lu, K_fl) -> np.ndarray:
    """``Psi = -K_ff^-1 K_fl``."""
    return -solve_columns(lu, K_fl)


def fixed_interface_modes(K_ff, M_ff, lu, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n`` modes of ``K_ff phi = nu^2 M_ff phi`` reusing the factorisation of K_ff.

    Parameters
    ----------
    K_ff, M_ff : sparse matrix, shape (n_f, n_f)
        Interior stiffness (N/m) and mass (kg).
    lu : mvtk.fe.Factorization or scipy.sparse.linalg.SuperLU
        Factorisation of ``K_ff`` (shift zero), the shift-invert operator of the block
        Lanczos of :func:`mvtk.fe.eigsh_lowest` (no second factorisation).
    n : int
        Number of modes (0 <= n <= n_f).

    Returns
    -------
    nu2 : ndarray, shape (n,)
        Eigenvalues in (rad/s)^2, ascending.
    phi : ndarray, shape (n_f, n)
        Mass-normalised modes, largest entry positive.

    Raises
    ------
    ConvergenceError
        If the Lanczos iteration does not converge.

    Notes
    -----
    Interiors up to :data:`_DENSE_LIMIT` DOFs (or ``n >= n_f - 1``) use a dense
    generalised eigen solver. Larger ones use :func:`mvtk.fe.eigsh_lowest` with
    ``factorization=lu`` (its default block Lanczos, Rayleigh-quotient eigenvalues and
    Sturm check for missed copies of repeated eigenvalues).
    """
    nf = K_ff.shape[0]
    if n == 0:
        return np.zeros(0), np.zeros((nf, 0))
    if nf <= _DENSE_LIMIT or n >= nf - 1:
        w2, v = sla.eigh(K_ff.toarray(), M_ff.toarray(), subset_by_index=[0, n - 1])
        v = v / np.sqrt(np.einsum("ij,ij->j", v, M_ff @ v))
        big = np.argmax(np.abs(v), axis=0)
        v = v * np.sign(v[big, np.arange(v.shape[1])])
        return w2, v
    if not isinstance(lu, Factorization):
        lu = Factorization("superlu", K_ff.shape, lu.solve)
    try:
        sol = eigsh_lowest(K_ff, M_ff, n, factorization=lu)
    except ConvergenceError as err:
        raise ConvergenceError(
            f"the {n} lowest fixed-interface modes of a {nf}-DOF interior: {err}"
        ) from err
    # eigsh_lowest mass-normalises and makes the largest entry positive
    return sol.omega2, sol.vectors


def _mode_count(nu2, mass_fraction, f_cut_hz, participation, total):
    """Number of leading modes meeting the criterion, or None if not met yet."""
    if f_cut_hz is not None:
        fn = np.sqrt(np.clip(nu2, 0, None)) / (2 * np.pi)
        if fn.size and fn[-1] > f_cut_hz:
            return int(np.searchsorted(fn, f_cut_hz, side="right"))
        return None
    cum = np.cumsum(participation**2) / total
    hit = np.nonzero(cum >= mass_fraction)[0]
    return int(hit[0]) + 1 if hit.size else None


def craig_bampton(
    model: FEModel,
    retained: Iterable | None = None,
    n_modes: int | None = None,
    *,
    retained_dofs: Iterable[int] | None = None,
    mass_fraction: float | None = None,
    f_cut_hz: float | None = None,
    direction: str = "uz",
) -> SuperElement:
    """Craig-Bampton super element of ``model`` with the given boundary.

    Parameters
    ----------
    model : FEModel
        Full model (M, K over its free DOFs; supports already removed).
    retained : iterable, optional
        Boundary nodes: node indices (int), node set names (str) or points
        ``[x, y, z]`` in m (nearest node). All free DOFs of each node are kept.
    n_modes : int, optional
        Number of fixed-interface modes (``0`` gives Guyan reduction). Default 10 when
        neither ``mass_fraction`` nor ``f_cut_hz`` is given; with a criterion it is the
        upper limit searched (default: all interior DOFs).
    retained_dofs : iterable of int, optional
        Explicit boundary free-DOF indices (added to ``retained``).
    mass_fraction : float, optional
        Keep the fewest fixed-interface modes whose cumulative effective mass fraction in
        ``direction`` reaches this value (the paper: 0.95). See :func:`effective_mass`
        for the influence vector used.
    f_cut_hz : float, optional
        Keep every fixed-interface mode with frequency <= ``f_cut_hz`` (Hz).
    direction : {"ux", "uy", "uz"}
        Translation direction for ``mass_fraction``.

    Returns
    -------
    SuperElement

    Raises
    ------
    ParameterError
        Bad boundary, negative or too many modes, both criteria given, or an interior
        that is not restrained (``K_ff`` singular).

    Notes
    -----
    ``K_ff`` is factorised once (:func:`mvtk.fe.factorize`); the factorisation gives the
    constraint modes ``Psi = -K_ff^-1 K_fl`` and serves as the shift-invert operator of
    the fixed-interface eigen solve. No dense inverse is formed. When a criterion is
    given, modes are computed in growing batches with the same factorisation until the
    criterion is met; if it is not met within the limit an :class:`AccuracyWarning` is
    issued and all modes found are kept.

    Examples
    --------
    A clamped plate reduced to its tip node and 6 fixed-interface modes: the super
    element's frequencies are upper bounds of the model's (Rayleigh-Ritz).

    >>> from mvtk.fe import IsotropicMaterial, Ply, plate_model
    >>> from mvtk.reduction import verify
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> model = plate_model(0.3, 0.3, [Ply(steel, 3e-3)], nx=12, ny=12, clamp="x0")
    >>> se = craig_bampton(model, retained=[model.nearest_node([0.3, 0.15, 0.0])],
    ...                    n_modes=6)
    >>> m = verify(model, se, n=3).modes.to_dataframe()
    >>> bool((m["se_hz"] >= m["fe_hz"]).all()), round(float(m["error_pct"].max()), 2)
    (True, 0.33)
    """
    if mass_fraction is not None and f_cut_hz is not None:
        raise ParameterError("give at most one of mass_fraction and f_cut_hz")
    if mass_fraction is not None and not 0 < mass_fraction <= 1:
        raise ParameterError(f"mass_fraction must be in (0, 1], got {mass_fraction}")
    if f_cut_hz is not None and not f_cut_hz > 0:
        raise ParameterError(f"f_cut_hz must be > 0 Hz, got {f_cut_hz}")
    lset, rnodes = resolve_retained(model, retained, retained_dofs)
    ndof = model.n_dof
    interior = np.ones(ndof, dtype=bool)
    interior[lset] = False
    fset = np.flatnonzero(interior)             # = setdiff1d(arange, lset), 30x faster
    nf = fset.size
    criterion = mass_fraction is not None or f_cut_hz is not None
    if n_modes is None:
        n_modes = nf if criterion else min(10, nf)
    n_modes = int(n_modes)
    if not 0 <= n_modes <= nf:
        raise ParameterError(
            f"n_modes must be in 0..{nf} (number of interior DOFs), got {n_modes}"
        )
    if lset.size + (n_modes if not criterion else 1) == 0:
        raise ParameterError("the super element would be empty: no boundary and no modes")

    K = model.K
    # M and the projections only multiply: without the stored zeros of uncoupled DOF
    # pairs (shells: 83 % of M's entries, 59 % of K's on a flat plate) the products are
    # 2-5x faster and bitwise the same
    M, K_nz = _without_zeros(model.M), _without_zeros(K)
    # K_ff keeps K's stored pattern: factorize() orders by the mesh's pattern, not values
    perm = np.concatenate([fset, lset])
    Kp = sp.csr_matrix(K[perm][:, perm])
    K_ff, K_fl = sp.csc_matrix(Kp[:nf, :nf]), sp.csc_matrix(Kp[:nf, nf:])
    M_ff = M[fset][:, fset]
    if nf:
        try:
            lu = factorize(K_ff)
        except ParameterError as err:
            raise ParameterError(
                f"interior stiffness K_ff ({nf} DOFs) is singular: the boundary "
                f"({lset.size} DOFs) plus supports do not restrain the structure"
            ) from err
        psi = _constraint_modes(lu, K_fl)
    else:
        lu, psi = None, np.zeros((0, lset.size))

    meta: dict[str, Any] = {"n_modes_limit": n_modes}
    if criterion and nf:
        r_full = None
        if mass_fraction is not None:
            r_full = _translation(model, direction)
            total = float(r_full @ (M @ r_full))
            if total <= 0:
                raise ParameterError(f"the model has no mass moving in {direction}")
            mr_f = (M @ r_full)[fset]
        n_try = min(n_modes, 10)
        while True:
            nu2, phi = fixed_interface_modes(K_ff, M_ff, lu, n_try)
            part = phi.T @ mr_f if mass_fraction is not None else None
            tot = total if mass_fraction is not None else None
            k = _mode_count(nu2, mass_fraction, f_cut_hz, part, tot)
            if k is not None or n_try >= n_modes:
                break
            n_try = min(2 * n_try, n_modes)
        if k is None:
            what = (
                f"cumulative effective mass fraction {mass_fraction} in {direction}"
                if mass_fraction is not None
                else f"cutoff {f_cut_hz} Hz"
            )
            warnings.warn(
                f"{what} not reached with {n_try} fixed-interface modes (limit); "
                "keeping them all",
                AccuracyWarning,
                stacklevel=2,
            )
            k = n_try
        nu2, phi = nu2[:k], phi[:, :k]
        meta.update(mass_fraction=mass_fraction, f_cut_hz=f_cut_hz, direction=direction)
    else:
        nu2, phi = fixed_interface_modes(K_ff, M_ff, lu, n_modes) if nf else (
            np.zeros(0), np.zeros((0, 0))
        )
    nm = nu2.size
    nl = lset.size
    T = np.zeros((ndof, nl + nm))
    T[lset, np.arange(nl)] = 1.0
    T[fset] = np.hstack([psi, phi])
    # single-threaded products (with two BLAS threads competing for a shared machine's
    # cores, T' (M T), 78 MFlop, took up to 1 s; measured); one n x n_r temporary at a
    # time, as T itself
    with _blas_limits():
        Mr = T.T @ (M @ T)
        Kr = T.T @ (K_nz @ T)
    Mr = 0.5 * (Mr + Mr.T)
    Kr = 0.5 * (Kr + Kr.T)
    labels = tuple(
        f"n{model.dof_node[i]}:{DOF_NAMES[model.dof_component[i]]}" for i in lset
    ) + tuple(f"eta{i}" for i in range(nm))
    meta["method"] = "guyan" if nm == 0 else "craig_bampton"
    return SuperElement(
        M=Mr,
        K=Kr,
        T=T,
        boundary_dofs=lset,
        interior_fn_hz=np.sqrt(np.clip(nu2, 0, None)) / (2 * np.pi),
        labels=labels,
        model=model,
        retained_nodes=rnodes,
        meta=meta,
    )


def guyan(
    model: FEModel, retained: Iterable | None = None, *, retained_dofs=None
) -> SuperElement:
    """Guyan (static) reduction: :func:`craig_bampton` with ``n_modes=0``.

    Examples
    --------
    A steel cantilever (300 x 20 x 2 mm) condensed to its tip node: static condensation
    is exact for static loads, so the tip flexibility is ``L**3 / (3 E I)`` = 3.214 mm/N:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> se = guyan(beam, [int(beam.node_sets["tip"][0])])
    >>> se.labels
    ('n20:ux', 'n20:uy', 'n20:uz', 'n20:rx', 'n20:ry', 'n20:rz')
    >>> round(float(np.linalg.inv(se.K)[2, 2]) * 1e3, 3)      # mm/N
    3.214
    """
    return craig_bampton(model, retained, 0, retained_dofs=retained_dofs)


def _without_zeros(A) -> sp.csr_matrix:
    """CSR ``A`` without its stored zeros (a copy; ``A`` itself when it has few)."""
    A = sp.csr_matrix(A)
    if A.nnz and np.count_nonzero(A.data) < 0.9 * A.nnz:
        A = A.copy()
        A.eliminate_zeros()
    return A


def _translation(model: FEModel, direction: str) -> np.ndarray:
    """Rigid unit translation in ``direction`` over the free DOFs of ``model``."""
    if direction not in ("ux", "uy", "uz"):
        raise ParameterError(
            f"direction must be a translation 'ux', 'uy' or 'uz', got {direction!r}"
        )
    return (model.dof_component == DOF_NAMES.index(direction)).astype(float)
