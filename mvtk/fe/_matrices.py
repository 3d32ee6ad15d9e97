"""Assembled third-party matrices (Matrix Market, MATLAB .mat, Nastran OP4) with DOF tables.

:func:`read_matrices` turns a stiffness and a mass matrix exported by another FE code
into an :class:`~mvtk.fe.FEModel`, so that modal analysis, reduction, control and
correlation run on it. The DOF table names the node label and component of every row:
a CSV file (or array) with columns ``node`` (int label) and ``dof`` (``1..6`` as in
Nastran/UFF, or a name ``ux uy uz rx ry rz``), one row per matrix row, in matrix order.
A Nastran OUTPUT4 file (``.op4``, :func:`mvtk.fe.read_op4`) gives its only matrix, the
only one whose name starts with ``K`` (or ``M``), or the one named after a colon:
``"model.op4:KAA"``. Node coordinates (CSV ``node, x, y, z``) are optional; without them
every node sits at the origin (the model then has no geometry for plots or mode labels
from energy).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

from ..errors import DimensionError, FormatError, ParameterError
from ._model import DOF_NAMES, FEModel

__all__ = ["read_matrices"]


def _op4_matrix(path: Path, key: str, name: str | None) -> sp.csr_matrix:
    """The matrix ``name`` of an OP4 file, or the only one, or the only one named key*."""
    from ._op4 import read_op4

    mats = read_op4(path)
    names = list(mats)
    if name is not None:
        hit = [n for n in names if n.upper() == name.upper()]
        if not hit:
            raise FormatError(f"{str(path)!r}: no matrix {name!r}; found {names}")
    elif len(names) == 1:
        hit = names
    else:
        hit = [n for n in names if n.upper().startswith(key.upper())]
        if len(hit) != 1:
            raise FormatError(f"{str(path)!r} holds the matrices {names}; name the {key} "
                              f"matrix as '{path.name}:NAME'")
    m = mats[hit[0]].matrix
    if np.iscomplexobj(m.data):
        raise FormatError(f"{str(path)!r}: matrix {hit[0]!r} is complex; expected a real "
                          f"{key} matrix")
    return sp.csr_matrix(m, dtype=float)


def _real(A, path: Path, key: str) -> sp.csr_matrix:
    """``A`` as a real matrix; a complex one is refused (never its imaginary part dropped)."""
    from ._sanity import check_matrices

    if np.iscomplexobj(A.data):
        try:
            check_matrices(A if key == "K" else sp.csr_matrix(A.shape),
                           A if key == "M" else sp.csr_matrix(A.shape), where=str(path))
        except ParameterError as err:
            raise FormatError(str(err)) from None
    return sp.csr_matrix(A, dtype=float)


def _load_matrix(path: Path, key: str):
    head, sep, tail = str(path).rpartition(":")
    name = None
    if sep and head.lower().endswith(".op4"):
        path, name = Path(head), tail  # "model.op4:KAA"
    if not path.exists():
        raise FormatError(f"matrix file {str(path)!r} not found")
    if path.suffix.lower() == ".op4":
        return _op4_matrix(path, key, name)
    try:
        if path.suffix.lower() == ".mat":
            data = scipy.io.loadmat(path)
            if key not in data:
                raise FormatError(f"{str(path)!r}: no variable {key!r}; found "
                                  f"{sorted(k for k in data if not k.startswith('__'))}")
            return _real(sp.csr_matrix(data[key]), path, key)
        return _real(sp.csr_matrix(scipy.io.mmread(path)), path, key)
    except FormatError:
        raise
    except (ValueError, OSError) as err:
        raise FormatError(f"{str(path)!r} is not a readable Matrix Market / .mat file: "
                          f"{err}") from err


def _read_table(source, columns: int, what: str) -> list[list[str]]:
    if isinstance(source, (str, Path)):
        path = Path(source)
        if not path.exists():
            raise FormatError(f"{what} file {str(path)!r} not found")
        rows = []
        for i, line in enumerate(path.read_text().splitlines(), start=1):
            text = line.split("#")[0].strip()
            if not text:
                continue
            parts = [p.strip() for p in text.replace(";", ",").split(",")]
            if i == 1 and not parts[0].lstrip("-").isdigit():
                continue  # header
            if len(parts) != columns:
                raise FormatError(f"{str(path)!r} line {i}: expected {columns} columns, got "
                                  f"{len(parts)}")
            rows.append(parts)
        return rows
    arr = np.asarray(source, dtype=object)
    if arr.ndim != 2 or arr.shape[1] != columns:
        raise DimensionError(f"{what} must have {columns} columns, got shape {arr.shape}")
    return [[str(v) for v in r] for r in arr]


def _int_label(text: str) -> int:
    """An integer label, also from an integral float ("12.0", from a float array)."""
    try:
        return int(text)
    except ValueError:
        v = float(text)  # ValueError for non-numbers
        if not v.is_integer():
            raise ValueError(f"{text!r} is not an integer") from None
        return int(v)


def _dof_table(source, n: int | None, what: str = "DOF table") -> tuple[list[int], list[int]]:
    """Node labels and component indices (0..5) of a DOF table with ``n`` rows."""
    rows = _read_table(source, 2, what)
    if n is not None and len(rows) != n:
        raise DimensionError(f"the {what} has {len(rows)} rows, the matrices {n}")
    labels, comps = [], []
    for i, (node, dof) in enumerate(rows, start=1):
        try:
            labels.append(_int_label(node))
        except ValueError:
            raise FormatError(f"{what} row {i}: node {node!r} is not an integer") from None
        if dof in DOF_NAMES:
            comps.append(DOF_NAMES.index(dof))
        elif dof.replace(".0", "", 1).isdigit() and 1 <= float(dof) <= 6:
            comps.append(int(float(dof)) - 1)
        else:
            raise FormatError(f"{what} row {i}: dof {dof!r} is not 1..6 or one of "
                              f"{', '.join(DOF_NAMES)}")
    return labels, comps


def _node_table(nodes, labels) -> tuple[np.ndarray, np.ndarray]:
    """Node labels and coordinates (n, 3); all at the origin without a node table."""
    ids = np.unique(labels)
    if nodes is None:
        return ids, np.zeros((len(ids), 3))
    table = _read_table(nodes, 4, "node table")
    try:
        node_ids = np.array([_int_label(r[0]) for r in table])
        xyz = np.array([[float(v) for v in r[1:]] for r in table])
    except ValueError as err:
        raise FormatError(f"node table: expected 'node, x, y, z' numbers ({err})") from err
    missing = np.setdiff1d(ids, node_ids)
    if missing.size:
        raise FormatError(f"nodes {missing[:5].tolist()} of the DOF table are not in the "
                          "node table")
    return node_ids, xyz


def read_matrices(K, M, dof_table, nodes=None, name: str = "") -> FEModel:
    """FE model from assembled matrices and a DOF table.

    Parameters
    ----------
    K, M : path or sparse matrix
        Stiffness (N/m) and mass (kg) matrices: ``.mtx`` (Matrix Market), ``.mat``
        (variables ``K`` and ``M``), ``.op4`` (Nastran OUTPUT4, ``"file.op4:NAME"`` to
        pick a matrix), or matrices in memory.
    dof_table : path or array (n_dof, 2)
        ``node, dof`` per matrix row (see the module notes).
    nodes : path or array (n_nodes, 4), optional
        ``node, x, y, z`` (m).
    name : str

    Raises
    ------
    FormatError
        Unreadable files, a bad DOF code (the message names the row), a node missing from
        the coordinate table.
    DimensionError
        Sizes that do not agree or a non-symmetric matrix.
    ParameterError
        A complex or non-finite matrix, or a negative diagonal term (names the DOF).

    Examples
    --------
    The 2-mass chain (1 kg masses, 1e5 N/m springs) from its matrices, both DOFs along z
    (dof 3); closed form ``f1 = sqrt(k (3 - sqrt(5)) / 2) / (2 pi)`` = 31.105 Hz:

    >>> from mvtk.fe import modal_analysis
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> model = read_matrices(K, np.eye(2), np.array([[1, 3], [2, 3]]))
    >>> model.n_dof, np.round(modal_analysis(model, 1).fn_hz, 3)
    (2, array([31.105]))
    """
    Km = _load_matrix(Path(K), "K") if isinstance(K, (str, Path)) else sp.csr_matrix(K)
    Mm = _load_matrix(Path(M), "M") if isinstance(M, (str, Path)) else sp.csr_matrix(M)
    from ._sanity import check_matrices

    check_matrices(Km, Mm, where=name or "assembled matrices")
    n = Km.shape[0]
    if Km.shape != (n, n) or Mm.shape != (n, n):
        raise DimensionError(f"K {Km.shape} and M {Mm.shape} must be square and equal")
    for label, A in (("K", Km), ("M", Mm)):
        asym = abs(A - A.T).max() if A.nnz else 0.0
        if asym > 1e-8 * max(abs(A).max(), 1e-300):
            raise DimensionError(f"{label} is not symmetric (max |A - A'| = {asym:.3g})")
    labels, comps = _dof_table(dof_table, n)
    node_ids, xyz = _node_table(nodes, labels)
    index = {int(v): i for i, v in enumerate(node_ids)}
    return FEModel(nodes=xyz, M=Mm, K=Km, dof_node=[index[v] for v in labels],
                   dof_component=comps, node_ids=node_ids, name=name,
                   meta={"source": "assembled matrices"})
