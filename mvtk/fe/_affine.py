"""Affine parameterisation of third-party matrices: K = K0 + sum theta_i K_i, M likewise.

A model that exists only as assembled matrices (another FE code's export, see
:func:`mvtk.fe.read_matrices`) cannot be updated through a structure description: there
is no modulus or thickness to change. What such codes can export instead are the
matrices of **substructures** (element sets): the skin, the stiffeners, a joint. An
:class:`AffineModel` scales each substructure by a factor ``theta_i``::

    K(theta) = K0 + sum_i theta_i K_i,        M(theta) = M0 + sum_i theta_i M_i

(``K0, M0``: the part that is not updated; a part may carry only ``K_i`` (a stiffness
factor such as a modulus or a joint stiffness) or only ``M_i`` (a non-structural mass)).
Each matrix comes with its own DOF table (``node, dof`` per row, as for
:func:`~mvtk.fe.read_matrices`), so a substructure is given on its own DOFs only; the
model's DOFs are the union, in the order of the ``dof_table`` argument (or of first
appearance).

The model plugs into :func:`mvtk.updating.update` as the ``builder`` with the
description ``{"theta": {name: value}}`` (:meth:`AffineModel.description`) and
parameters ``"theta.<name>"``; it gives the exact matrix derivatives
``dK/dtheta_i = K_i``, ``dM/dtheta_i = M_i`` (:meth:`AffineModel.matrix_derivatives`),
which ``update(..., affine=True)`` then uses instead of differences of builds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError, DimensionError, FormatError, ParameterError
from ._matrices import _dof_table, _load_matrix, _node_table
from ._model import DOF_NAMES, FEModel

__all__ = ["AffineModel"]

_PART_KEYS = ("K", "M", "dof_table")


def _matrix(source, key: str, where: str) -> sp.csr_matrix:
    if isinstance(source, (str, Path)):
        A = _load_matrix(Path(source), key)
    else:
        try:
            A = sp.csr_matrix(source, dtype=float)
        except (TypeError, ValueError) as err:
            raise FormatError(f"{where}: {key} is not a matrix ({err})") from err
    if A.shape[0] != A.shape[1]:
        raise DimensionError(f"{where}: {key} must be square, got shape {A.shape}")
    if A.nnz and not np.all(np.isfinite(A.data)):
        raise FormatError(f"{where}: {key} has non-finite entries")
    asym = abs(A - A.T).max() if A.nnz else 0.0
    if asym > 1e-8 * max(abs(A).max() if A.nnz else 0.0, 1e-300):
        raise DimensionError(f"{where}: {key} is not symmetric (max |A - A'| = {asym:.3g})")
    return A


def _read_part(spec, where: str, default_table) -> tuple[dict, list[tuple[int, int]]]:
    """Matrices {"K": A, "M": A} (present ones) and the (node, comp) list of one part."""
    if isinstance(spec, (str, Path)):
        spec = {"K": spec, "M": spec}  # a .mat file holding variables K and M
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: expected a mapping with keys {', '.join(_PART_KEYS)} "
                          f"(or the path of a .mat file), got {type(spec).__name__}")
    unknown = sorted(set(map(str, spec)) - set(_PART_KEYS))
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {', '.join(map(repr, unknown))}; "
                          f"accepted: {', '.join(_PART_KEYS)}")
    mats = {k: _matrix(spec[k], k, where) for k in ("K", "M") if spec.get(k) is not None}
    if not mats:
        raise ConfigError(f"{where}: give at least one of K and M")
    sizes = {A.shape[0] for A in mats.values()}
    if len(sizes) != 1:
        raise DimensionError(f"{where}: K and M have different sizes "
                             f"{[A.shape for A in mats.values()]}")
    table = spec.get("dof_table", default_table)
    if table is None:
        raise ConfigError(f"{where}: no dof_table (give one for the part or for the model)")
    labels, comps = _dof_table(table, sizes.pop(), f"DOF table of {where}")
    dofs = list(zip(labels, comps))
    if len(set(dofs)) != len(dofs):
        seen: set = set()
        dup = next(d for d in dofs if d in seen or seen.add(d))
        raise FormatError(f"DOF table of {where}: node {dup[0]} dof {DOF_NAMES[dup[1]]} "
                          "appears twice")
    return mats, dofs


def _scatter(A: sp.csr_matrix, rows: np.ndarray, n: int) -> sp.csr_matrix:
    """A (on a part's DOFs) placed at rows/columns ``rows`` of an n x n matrix."""
    C = A.tocoo()
    return sp.csr_matrix((C.data, (rows[C.row], rows[C.col])), shape=(n, n))


@dataclass(frozen=True, eq=False)
class AffineModel:
    """Model whose matrices are affine in substructure factors theta.

    Build it with :meth:`from_files`. ``K(theta) = base.K + sum theta_i K_parts[i]``,
    ``M(theta) = base.M + sum theta_i M_parts[i]``.

    Parameters
    ----------
    base : FEModel
        ``K0, M0`` (N/m, kg; possibly all zero) over the model's DOFs, with the node table.
    names : tuple of str
        Part names; the updating parameters are ``"theta.<name>"``.
    K_parts, M_parts : tuple of scipy.sparse.csr_matrix
        Part matrices over the model's DOFs (zero where the part has none).
    theta0 : tuple of float
        Nominal factors (default 1: the matrices as exported).

    Examples
    --------
    The 2-mass chain with its springs as one substructure (factor ``theta.springs``) and
    the masses as the fixed base: scaling K by 4 doubles every frequency
    (``f ~ sqrt(k)``; 31.105 Hz nominal):

    >>> import scipy.sparse as sp
    >>> from mvtk.fe import modal_analysis
    >>> table = np.array([[1, 3], [2, 3]])                   # node, dof (3 = uz)
    >>> am = AffineModel.from_files(
    ...     {"springs": {"K": sp.csr_matrix([[2e5, -1e5], [-1e5, 1e5]]), "dof_table": table}},
    ...     base={"M": sp.identity(2, format="csr"), "dof_table": table})
    >>> np.round(modal_analysis(am.model({"springs": 1.0}), 1).fn_hz, 3)
    array([31.105])
    >>> np.round(modal_analysis(am.model({"springs": 4.0}), 1).fn_hz, 3)
    array([62.21])
    """

    base: FEModel
    names: tuple[str, ...]
    K_parts: tuple[sp.csr_matrix, ...]
    M_parts: tuple[sp.csr_matrix, ...]
    theta0: tuple[float, ...]

    # ----------------------------------------------------------------- building
    @classmethod
    def from_files(
        cls,
        parts: Mapping[str, Any],
        *,
        dof_table=None,
        base: Mapping[str, Any] | str | Path | None = None,
        nodes=None,
        theta0: Mapping[str, float] | None = None,
        name: str = "",
    ) -> AffineModel:
        """Read substructure matrices and their DOF tables.

        Parameters
        ----------
        parts : mapping of str to mapping (or path)
            Per part ``{"K": ..., "M": ..., "dof_table": ...}``: each matrix a Matrix
            Market ``.mtx`` / MATLAB ``.mat`` path (variable ``K`` or ``M``) or an
            in-memory matrix; either may be omitted (zero); ``dof_table`` (path or
            ``(n, 2)`` array of ``node, dof``) defaults to the ``dof_table`` argument. A
            plain path stands for a ``.mat`` file with both ``K`` and ``M``.
        dof_table : path or array (n_dof, 2), optional
            The model's DOFs and their order (default: the union of the parts' and the
            base's tables in order of first appearance). Every part DOF must be in it.
        base : mapping (same keys as a part) or path, optional
            The fixed part ``K0, M0``.
        nodes : path or array (n_nodes, 4), optional
            ``node, x, y, z`` (m) of the node labels in the DOF tables.
        theta0 : mapping of str to float, optional
            Nominal factors (default 1 for every part).
        name : str

        Returns
        -------
        AffineModel

        Raises
        ------
        ConfigError
            No parts, a part with unknown keys or without matrices, an unknown name in
            ``theta0``.
        FormatError
            Unreadable files, bad DOF codes (row named), a duplicated DOF, a part DOF
            missing from ``dof_table`` (node and dof named).
        DimensionError
            A matrix that is not square and symmetric or whose size differs from its
            DOF table.
        """
        if not isinstance(parts, Mapping) or not parts:
            raise ConfigError("an affine model needs at least one part: parts = {name: "
                              "{'K': ..., 'M': ..., 'dof_table': ...}}")
        read = {}
        if base is not None:
            read[None] = _read_part(base, "base", dof_table)
        for key, spec in parts.items():
            if not isinstance(key, str) or not key.isidentifier():
                raise ConfigError(f"part name {key!r} must be an identifier "
                                  "(it becomes the parameter path 'theta.<name>')")
            read[key] = _read_part(spec, f"part {key!r}", dof_table)
        if dof_table is not None:
            labels, comps = _dof_table(dof_table, None)
            order = list(zip(labels, comps))
            if len(set(order)) != len(order):
                raise FormatError("the model's DOF table lists a DOF twice")
        else:
            order = list(dict.fromkeys(d for _, dofs in read.values() for d in dofs))
        index = {d: i for i, d in enumerate(order)}
        n = len(order)
        scattered: dict = {}
        for key, (mats, dofs) in read.items():
            where = "base" if key is None else f"part {key!r}"
            missing = [d for d in dofs if d not in index]
            if missing:
                nd, c = missing[0]
                raise FormatError(f"{where}: node {nd} dof {DOF_NAMES[c]} is not in the "
                                  f"model's DOF table ({len(missing)} such DOFs)")
            rows = np.array([index[d] for d in dofs], dtype=np.int64)
            scattered[key] = {k: _scatter(A, rows, n) for k, A in mats.items()}
        zero = sp.csr_matrix((n, n))
        names = tuple(k for k in read if k is not None)
        b = scattered.get(None, {})
        labels = [d[0] for d in order]
        node_ids, xyz = _node_table(nodes, labels)
        pos = {int(v): i for i, v in enumerate(node_ids)}
        base_model = FEModel(
            nodes=xyz, K=b.get("K", zero), M=b.get("M", zero),
            dof_node=[pos[v] for v in labels], dof_component=[d[1] for d in order],
            node_ids=node_ids, name=name, meta={"source": "affine substructure matrices"})
        t0 = {k: 1.0 for k in names}
        if theta0 is not None:
            unknown = sorted(set(theta0) - set(names))
            if unknown:
                raise ConfigError(f"theta0: unknown part(s) {unknown}; parts: {list(names)}")
            t0.update({k: float(v) for k, v in theta0.items()})
        return cls(base=base_model, names=names,
                   K_parts=tuple(scattered[k].get("K", zero) for k in names),
                   M_parts=tuple(scattered[k].get("M", zero) for k in names),
                   theta0=tuple(t0[k] for k in names))

    # ----------------------------------------------------------------- evaluation
    def _theta(self, theta) -> np.ndarray:
        if theta is None:
            return np.array(self.theta0)
        if isinstance(theta, Mapping):
            unknown = sorted(set(map(str, theta)) - set(self.names))
            if unknown:
                raise ParameterError(f"theta: unknown part(s) {unknown}; parts: "
                                     f"{list(self.names)}")
            vals = dict(zip(self.names, self.theta0))
            vals.update(theta)
            out = np.array([vals[k] for k in self.names], dtype=float)
        else:
            out = np.asarray(theta, dtype=float).ravel()
            if out.size != len(self.names):
                raise DimensionError(f"theta: expected {len(self.names)} values "
                                     f"({', '.join(self.names)}), got {out.size}")
        if not np.all(np.isfinite(out)):
            raise ParameterError(f"theta must be finite, got {out.tolist()}")
        return out

    def model(self, theta: Mapping[str, float] | Sequence[float] | None = None) -> FEModel:
        """The :class:`~mvtk.fe.FEModel` at factors ``theta`` (default :attr:`theta0`).

        ``theta`` is a mapping ``{name: value}`` (missing names keep their nominal
        value) or a sequence in :attr:`names` order.
        """
        th = self._theta(theta)
        K, M = self.base.K, self.base.M
        for t, Ki, Mi in zip(th, self.K_parts, self.M_parts):
            K = K + t * Ki
            M = M + t * Mi
        meta = dict(self.base.meta)
        meta["theta"] = dict(zip(self.names, th.tolist()))
        return replace(self.base, K=K.tocsr(), M=M.tocsr(), meta=meta)

    def description(self, theta: Mapping[str, float] | None = None) -> dict:
        """``{"theta": {name: value}}``: the description :meth:`__call__` reads."""
        return {"theta": dict(zip(self.names, self._theta(theta).tolist()))}

    def __call__(self, description: Mapping[str, Any]) -> FEModel:
        """Builder for :func:`mvtk.updating.update`: the model at ``description["theta"]``.

        Raises
        ------
        ConfigError
            No ``theta`` table, or names in it that are not parts (all listed).
        """
        th = description.get("theta") if isinstance(description, Mapping) else None
        if not isinstance(th, Mapping):
            raise ConfigError("affine model description: expected a 'theta' table "
                              f"{{name: factor}} for the parts {list(self.names)}")
        unknown = sorted(set(map(str, th)) - set(self.names))
        if unknown:
            raise ConfigError(f"affine model description: unknown key(s) "
                              f"{', '.join('theta.' + k for k in unknown)}; accepted: "
                              f"{', '.join('theta.' + k for k in self.names)}")
        return self.model(th)

    def matrix_derivatives(self, path: str) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """Exact ``(dK/dtheta_i, dM/dtheta_i) = (K_i, M_i)`` of the parameter ``path``.

        Raises
        ------
        ParameterError
            ``path`` is not ``"theta.<part name>"``.
        """
        prefix, _, key = str(path).partition(".")
        if prefix != "theta" or key not in self.names:
            raise ParameterError(f"no affine parameter {path!r}; parameters: "
                                 f"{', '.join('theta.' + k for k in self.names)}")
        i = self.names.index(key)
        return self.K_parts[i], self.M_parts[i]
