"""Evidence that a super element represents its FE model: the paper's Tables 4 and 5.

- :func:`compare_modes`: FE vs SE eigenfrequencies with % error and MAC (Table 5 shape).
- :func:`static_check`: static response to loads on boundary DOFs (exact by
  construction of the constraint modes).
- :func:`size_table`: nodes, elements and DOFs of the FE model and the SE (Table 4 shape).
- :func:`verify`: all three in one :class:`Verification`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._mac import mac_columns
from ..errors import DimensionError, ParameterError
from ..fe import FEModel, eigsh_lowest, factorize
from ._craig_bampton import SuperElement, reduced_modes, solve_columns

__all__ = [
    "ModeComparison",
    "StaticCheck",
    "SizeTable",
    "Verification",
    "mac",
    "compare_modes",
    "static_check",
    "size_table",
    "verify",
]


def mac(phi_a: np.ndarray, phi_b: np.ndarray, weight=None) -> np.ndarray:
    """Modal assurance criterion matrix between the columns of two mode sets.

    ``MAC_ij = |a_i' W b_j|^2 / ((a_i' W a_i)(b_j' W b_j))`` with ``W`` = identity or
    ``weight`` (e.g. the mass matrix).

    Parameters
    ----------
    phi_a : ndarray, shape (n, ka)
    phi_b : ndarray, shape (n, kb)
    weight : matrix, shape (n, n), optional

    Returns
    -------
    ndarray, shape (ka, kb), values in [0, 1] (0 for an all-zero shape; see
        :func:`mvtk._mac.mac_columns`)

    Examples
    --------
    Columns are modes; a scaled copy gives 1:

    >>> mac(np.array([[1.0], [2.0]]), np.array([[-2.0], [-4.0]]))
    array([[1.]])
    """
    a = np.asarray(phi_a)
    b = np.asarray(phi_b)
    a = a[:, None] if a.ndim == 1 else a
    b = b[:, None] if b.ndim == 1 else b
    if a.shape[0] != b.shape[0]:
        raise DimensionError(
            f"mode sets must have the same number of rows (DOFs), got {a.shape[0]} "
            f"and {b.shape[0]}"
        )
    return mac_columns(a, b, weight)


@dataclass(frozen=True)
class ModeComparison:
    """FE vs SE natural frequencies and mode shapes (paper Table 5 shape).

    Attributes
    ----------
    fe_hz, se_hz : ndarray, shape (n,)
        Natural frequencies in Hz, ascending.
    mac_matrix : ndarray, shape (n, m)
        MAC between FE modes (rows) and expanded SE modes (columns), mass-weighted;
        ``m >= n`` SE modes (a few extra, to find swapped partners).

    Examples
    --------
    Returned by :func:`compare_modes`; ``to_dataframe`` is the FE-vs-SE table:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> cmp = compare_modes(beam, craig_bampton(beam, [20], n_modes=4), n=2)
    >>> cmp.to_dataframe()[["fe_hz", "se_hz"]].round(2).values.tolist()
    [[18.57, 18.57], [116.33, 116.37]]
    """

    fe_hz: np.ndarray
    se_hz: np.ndarray
    mac_matrix: np.ndarray

    @property
    def error_pct(self) -> np.ndarray:
        """``100 (f_SE - f_FE) / f_FE``."""
        return 100.0 * (self.se_hz - self.fe_hz) / self.fe_hz

    @property
    def error_pct_of_se(self) -> np.ndarray:
        """``100 (f_SE - f_FE) / f_SE``: the convention the paper's Table 5 uses."""
        return 100.0 * (self.se_hz - self.fe_hz) / self.se_hz

    @property
    def mac_diagonal(self) -> np.ndarray:
        """MAC of each FE mode with the SE mode of the same number."""
        return np.diag(self.mac_matrix).copy()

    @property
    def se_match(self) -> np.ndarray:
        """1-based number of the SE mode with the largest MAC for each FE mode."""
        return np.argmax(self.mac_matrix, axis=1) + 1

    @property
    def mac_match(self) -> np.ndarray:
        """Largest MAC of each FE mode over the SE modes."""
        return np.max(self.mac_matrix, axis=1)

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self):
        """Columns mode, fe_hz, se_hz, error_pct, error_pct_of_se, mac, se_match,
        mac_match (rows paired by mode number as in the paper; ``se_match`` flags swaps)."""
        import pandas as pd

        return pd.DataFrame(
            {
                "mode": np.arange(1, self.fe_hz.size + 1),
                "fe_hz": self.fe_hz,
                "se_hz": self.se_hz,
                "error_pct": self.error_pct,
                "error_pct_of_se": self.error_pct_of_se,
                "mac": self.mac_diagonal,
                "se_match": self.se_match,
                "mac_match": self.mac_match,
            }
        )


def _se_modes(se: SuperElement, n: int) -> tuple[np.ndarray, np.ndarray]:
    modes = reduced_modes(se.K, se.M)
    if modes.omega2.size < n:
        raise ParameterError(
            f"the super element has only {modes.omega2.size} modes of finite frequency "
            f"({modes.n_massless} coordinates without inertia); asked for {n}"
        )
    return modes.omega2[:n], modes.vectors[:, :n]


def compare_modes(model: FEModel | None, se: SuperElement, n: int = 4) -> ModeComparison:
    """Compare the lowest ``n`` eigenfrequencies and mode shapes of FE model and SE.

    Parameters
    ----------
    model : FEModel or None
        Full model (``None``: ``se.model``).
    se : SuperElement
    n : int
        Number of modes (``1 <= n <= se.n_dof``).

    Returns
    -------
    ModeComparison

    Examples
    --------
    The tip-node super element with 4 modes against the full cantilever: the SE
    frequencies are upper bounds (Rayleigh-Ritz):

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> se = craig_bampton(beam, [int(beam.node_sets["tip"][0])], n_modes=4)
    >>> cmp = compare_modes(beam, se, n=3)
    >>> np.round(cmp.fe_hz, 2), bool(np.all(cmp.se_hz >= cmp.fe_hz))
    (array([ 18.57, 116.33, 185.02]), True)
    """
    model = se.model if model is None else model
    if model.n_dof != se.T.shape[0]:
        raise DimensionError(
            f"model has {model.n_dof} free DOFs but the super element expands to "
            f"{se.T.shape[0]}"
        )
    n = int(n)
    if not 1 <= n <= se.n_dof:
        raise ParameterError(
            f"number of modes to compare must be in 1..{se.n_dof} (SE size), got {n}"
        )
    fe = eigsh_lowest(model.K, model.M, n)
    w2_se, v_se = _se_modes(se, n)
    extra = reduced_modes(se.K, se.M)
    m = min(extra.omega2.size, n + 4)
    phi_se = se.expand(extra.vectors[:, :m])
    macm = mac(fe.vectors, phi_se, weight=model.M)
    to_hz = lambda w2: np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)  # noqa: E731
    return ModeComparison(fe_hz=to_hz(fe.omega2), se_hz=to_hz(w2_se), mac_matrix=macm)


@dataclass(frozen=True)
class StaticCheck:
    """Static responses of FE model and SE to the same loads.

    Attributes
    ----------
    labels : tuple of str
        Load case names (the loaded boundary DOF for unit loads).
    rel_error_boundary : ndarray, shape (n_cases,)
        ``|u_l,SE - u_l,FE| / |u_l,FE|`` on the boundary DOFs.
    rel_error_full : ndarray, shape (n_cases,)
        Same over all free DOFs after expansion ``T q``.

    Examples
    --------
    Returned by :func:`static_check`: one relative error per load case:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> chk = static_check(beam, craig_bampton(beam, [20], n_modes=4))
    >>> len(chk.labels), chk.rel_error_full.shape
    (6, (6,))
    """

    labels: tuple[str, ...]
    rel_error_boundary: np.ndarray
    rel_error_full: np.ndarray

    @property
    def max_rel_error(self) -> float:
        """Largest relative error over cases and DOFs."""
        both = np.concatenate([self.rel_error_boundary, self.rel_error_full])
        return float(both.max()) if both.size else 0.0

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self):
        """Columns load, rel_error_boundary, rel_error_full."""
        import pandas as pd

        return pd.DataFrame(
            {
                "load": list(self.labels),
                "rel_error_boundary": self.rel_error_boundary,
                "rel_error_full": self.rel_error_full,
            }
        )


def static_check(
    model: FEModel | None, se: SuperElement, loads: np.ndarray | None = None
) -> StaticCheck:
    """Static response of FE model and SE to loads (default: unit load per boundary DOF).

    Parameters
    ----------
    model : FEModel or None
        Full model (``None``: ``se.model``).
    se : SuperElement
    loads : ndarray, shape (n_dof,) or (n_dof, k), optional
        Free-DOF load vectors (N, N m). Loads on boundary DOFs only are reproduced
        exactly (to round-off); interior loads are not.

    Returns
    -------
    StaticCheck

    Examples
    --------
    Loads on the boundary DOFs are reproduced to round-off:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> chk = static_check(beam, craig_bampton(beam, [int(beam.node_sets["tip"][0])], n_modes=4))
    >>> chk.labels[:3], bool(chk.rel_error_boundary.max() < 1e-9)
    (('n20:ux', 'n20:uy', 'n20:uz'), True)
    """
    model = se.model if model is None else model
    nd = model.n_dof
    if loads is None:
        if se.n_boundary == 0:
            raise ParameterError("the super element has no boundary DOF to load")
        F = np.zeros((nd, se.n_boundary))
        F[se.boundary_dofs, np.arange(se.n_boundary)] = 1.0
        labels = tuple(se.labels[: se.n_boundary])
    else:
        F = np.asarray(loads, dtype=float)
        F = F[:, None] if F.ndim == 1 else F
        if F.ndim != 2 or F.shape[0] != nd:
            raise DimensionError(f"loads must have shape ({nd}, k), got {np.shape(loads)}")
        labels = tuple(f"load{i}" for i in range(F.shape[1]))
    x_fe = solve_columns(factorize(model.K), F)
    q = np.linalg.solve(se.K, se.T.T @ F)
    x_se = se.expand(q)
    b = se.boundary_dofs

    def rel(a, ref):
        den = np.linalg.norm(ref, axis=0)
        return np.linalg.norm(a - ref, axis=0) / np.where(den > 0, den, 1.0)

    return StaticCheck(
        labels=labels,
        rel_error_boundary=rel(x_se[b], x_fe[b]),
        rel_error_full=rel(x_se, x_fe),
    )


@dataclass(frozen=True)
class SizeTable:
    """Sizes of the FE model and the SE (paper Table 4 shape).

    ``dof`` counts free DOFs; ``dof_6_per_node`` counts 6 per node (the paper's count,
    which includes constrained DOFs; for the SE: 6 per retained node plus the modal
    coordinates). The SE counts as one element.

    Examples
    --------
    Returned by :func:`size_table`:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> t = size_table(beam, craig_bampton(beam, [20], n_modes=4))
    >>> t.fe_nodes, t.se_nodes, t.se_dof
    (21, 1, 10)
    """

    fe_nodes: int
    fe_elements: int
    fe_dof: int
    fe_dof_6_per_node: int
    se_nodes: int
    se_elements: int
    se_dof: int
    se_dof_6_per_node: int

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self):
        """Rows nodes, elements, DOF (free), DOF (6 per node); columns FE model, SE model."""
        import pandas as pd

        return pd.DataFrame(
            {
                "FE model": [self.fe_nodes, self.fe_elements, self.fe_dof,
                             self.fe_dof_6_per_node],
                "SE model": [self.se_nodes, self.se_elements, self.se_dof,
                             self.se_dof_6_per_node],
            },
            index=["Number of nodes", "Number of elements", "DOF (free)",
                   "DOF (6 per node)"],
        )


def size_table(model: FEModel | None, se: SuperElement) -> SizeTable:
    """FE/SE sizes: nodes, elements, DOFs (paper Table 4).

    Examples
    --------
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> t = size_table(beam, craig_bampton(beam, [int(beam.node_sets["tip"][0])], n_modes=4))
    >>> t.fe_dof, t.se_dof
    (120, 10)
    """
    model = se.model if model is None else model
    return SizeTable(
        fe_nodes=model.n_nodes,
        fe_elements=model.n_elements,
        fe_dof=model.n_dof,
        fe_dof_6_per_node=6 * model.n_nodes,
        se_nodes=se.n_nodes,
        se_elements=1,
        se_dof=se.n_dof,
        se_dof_6_per_node=6 * se.n_nodes + se.n_modes,
    )


@dataclass(frozen=True)
class Verification:
    """All FE-vs-SE evidence for one super element.

    Examples
    --------
    Returned by :func:`verify`: sizes, modes and the static check together:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> v = verify(beam, craig_bampton(beam, [20], n_modes=4), n=2)
    >>> type(v.sizes).__name__, type(v.modes).__name__, type(v.static).__name__
    ('SizeTable', 'ModeComparison', 'StaticCheck')
    """

    sizes: SizeTable
    modes: ModeComparison
    static: StaticCheck

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self):
        """The mode comparison table (the headline table; see the attributes for others)."""
        return self.modes.to_dataframe()

    def to_dict(self) -> dict:
        """Plain ``dict`` of the tables (lists of records), e.g. for JSON output."""
        sizes = self.sizes.to_dataframe()
        return {
            "sizes": [
                {"quantity": idx, "fe": int(row["FE model"]), "se": int(row["SE model"])}
                for idx, row in sizes.iterrows()
            ],
            "modes": self.modes.to_dataframe().to_dict(orient="records"),
            "static": self.static.to_dataframe().to_dict(orient="records"),
            "static_max_rel_error": self.static.max_rel_error,
        }


def verify(model: FEModel | None, se: SuperElement, n: int = 4) -> Verification:
    """Size table, mode comparison of ``n`` modes and static boundary-load check.

    Examples
    --------
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> v = verify(beam, craig_bampton(beam, [int(beam.node_sets["tip"][0])], n_modes=4), n=2)
    >>> v.sizes.se_dof, np.round(v.modes.fe_hz, 2)
    (10, array([ 18.57, 116.33]))
    """
    model = se.model if model is None else model
    return Verification(
        sizes=size_table(model, se),
        modes=compare_modes(model, se, n),
        static=static_check(model, se),
    )
