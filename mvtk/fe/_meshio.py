"""Mesh import through meshio and result export (VTU via meshio, UFF via pyuff).

Import
------
:func:`read_mesh` reads any format meshio reads (Gmsh ``.msh``, Abaqus ``.inp``,
VTK/VTU, MED, ...) into an :class:`ImportedMesh`: node coordinates, first-order cells
(``tri3``, ``quad4``, ``line2``, ``vertex``), nine-node quadrilaterals (``quad9``: Gmsh
second order, Abaqus S9R5; MITC9 shells; three-node lines become two two-node beams)
and named sets:

- Gmsh physical groups (``$PhysicalNames``) and meshio ``cell_sets`` (Abaqus ``*ELSET``,
  MED families) become **element sets**; each element set also defines a **node set**
  of the same name (the nodes of its cells), so a physical line "clamp" can carry a
  support;
- meshio ``point_sets`` (Abaqus ``*NSET``) become node sets;
- any other integer cell data (VTU files, MED/medit references, Gmsh physical tags
  without names) gives one element set per value, named ``"<key>:<value>"``.

Node labels: meshio renumbers nodes 0..n-1 in file order; :attr:`FEModel.node_ids` of an
imported model are ``1..n`` in that order.

:func:`mesh_model` assembles an imported mesh with a section per element set
(:func:`mvtk.fe.assemble_model`).

Export
------
:func:`write_vtu` writes the mesh and mode shapes (displacement and rotation vectors
per mode) for ParaView; :func:`write_uff` writes UFF datasets 2411 (nodes, double
precision), 15 (nodes, single precision) and 55 (one per mode: the six nodal DOFs of the
normal mode with its frequency and modal mass 1).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._atomic import atomic_path, write_error, write_text
from ..errors import FormatError, MissingDependencyError, ParameterError
from ._beam import BeamSection
from ._general import BeamSet, ShellSet, assemble_model
from ._laminate import Laminate
from ._model import FEModel

__all__ = ["ImportedMesh", "read_mesh", "mesh_model", "write_vtu", "write_xdmf", "write_uff",
           "ShellSection", "BeamProperty"]

_KINDS = {"triangle": "tri3", "quad": "quad4", "quad9": "quad9", "line": "line2",
          "line3": "line2", "vertex": "vertex"}
_MESHIO_NAME = {v: k for k, v in _KINDS.items()}


@dataclass(frozen=True, eq=False)
class ImportedMesh:
    """A first-order mesh with named sets.

    Attributes
    ----------
    nodes : ndarray (n_nodes, 3)
        Coordinates (m; the file's units are taken as metres).
    cells : dict of str to ndarray
        Connectivity per kind: ``"tri3"`` (n, 3), ``"quad4"`` (n, 4), ``"quad9"`` (n, 9),
        ``"line2"`` (n, 2),
        ``"vertex"`` (n, 1).
    element_sets : dict of str to dict of str to ndarray
        Per set name, the indices into ``cells[kind]`` for each kind it holds.
    node_sets : dict of str to ndarray
    source : str

    Examples
    --------
    Returned by :func:`read_mesh` and :func:`from_meshio`:

    >>> import meshio
    >>> mesh = from_meshio(meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    >>> mesh.nodes.shape, list(mesh.cells)
    ((3, 3), ['tri3'])
    """

    nodes: np.ndarray
    cells: dict[str, np.ndarray]
    element_sets: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = ""


def _meshio():
    try:
        import meshio
    except ImportError as err:  # a base dependency, but keep the message clear
        raise MissingDependencyError(
            "mesh import/export needs meshio, which is not installed; install it with: "
            "pip install meshio"
        ) from err
    return meshio


def read_mesh(path: str | Path) -> ImportedMesh:
    """Read a mesh file through meshio (format from the extension).

    Raises
    ------
    FormatError
        If the file cannot be read, holds higher-order or volume cells, or no shell or
        beam cells (message names the file and the cell types found).

    Examples
    --------
    A mesh file written by meshio (any format it knows; here VTU):

    >>> import pathlib, tempfile
    >>> import meshio
    >>> from mvtk.fe import rectangular_plate_mesh
    >>> grid = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "plate.vtu"
    >>> meshio.write(path, meshio.Mesh(grid.nodes, [("quad", grid.elements)]))
    >>> mesh = read_mesh(path)
    >>> mesh.nodes.shape, {kind: cells.shape for kind, cells in mesh.cells.items()}
    ((35, 3), {'quad4': (24, 4)})
    """
    meshio = _meshio()
    path = Path(path)
    if not path.exists():
        raise FormatError(f"mesh file {str(path)!r} not found")
    import contextlib
    import io

    captured = io.StringIO()
    try:
        # meshio prints notes (and a blank line for Gmsh files) on stdout, which would
        # corrupt `mvtk modes --json`: capture them and pass them on as a warning
        with contextlib.redirect_stdout(captured), contextlib.redirect_stderr(captured):
            m = meshio.read(path)
    except Exception as err:  # meshio raises many types (ReadError, KeyError, ...)
        raise FormatError(f"mesh file {str(path)!r}: meshio could not read it "
                          f"({type(err).__name__}: {err})") from err
    except SystemExit as err:  # meshio's Gmsh reader calls sys.exit on some bad files
        detail = " ".join(captured.getvalue().split()) or f"exit status {err.code}"
        raise FormatError(f"mesh file {str(path)!r}: meshio could not read it "
                          f"({detail})") from None
    if captured.getvalue().strip():
        import warnings

        from ..errors import MvtkWarning

        warnings.warn(f"meshio reading {str(path)!r}: {captured.getvalue().strip()}",
                      MvtkWarning, stacklevel=2)
    return from_meshio(m, str(path))


def from_meshio(m: Any, source: str = "") -> ImportedMesh:
    """:class:`ImportedMesh` from a ``meshio.Mesh`` (see :func:`read_mesh`).

    Examples
    --------
    A meshio mesh of a 300 x 200 mm plate (6 x 4 quads) with an element set ``plate``
    and a node set ``root`` (the edge x = 0):

    >>> import meshio
    >>> from mvtk.fe import rectangular_plate_mesh
    >>> grid = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    >>> m = meshio.Mesh(grid.nodes, [("quad", grid.elements)],
    ...                 cell_sets={"plate": [np.arange(len(grid.elements))]},
    ...                 point_sets={"root": grid.node_sets["x0"]})
    >>> mesh = from_meshio(m)
    >>> mesh.nodes.shape, mesh.cells["quad4"].shape, list(mesh.element_sets)
    ((35, 3), (24, 4), ['plate'])
    """
    nodes = np.asarray(m.points, dtype=float)
    if nodes.shape[1] == 2:
        nodes = np.column_stack([nodes, np.zeros(len(nodes))])
    where = f"mesh {source!r}" if source else "mesh"
    block_kind, block_offset, block_split = [], [], []
    cells: dict[str, list[np.ndarray]] = {}
    counts: dict[str, int] = {}
    for block in m.cells:
        kind = _KINDS.get(block.type)
        split = block.type == "line3"  # three-node lines: two two-node beams each
        if split:
            kind = "line2"
        if kind is None:
            found = sorted({b.type for b in m.cells})
            raise FormatError(
                f"{where}: cell type {block.type!r} is not supported; mvtk takes first-order "
                f"shells and beams and nine-node quadrilaterals ({', '.join(_KINDS)}), "
                f"found {found}. Re-mesh with first-order elements (Gmsh: -order 1) or "
                "complete second-order quads (Gmsh: -order 2 with "
                "Mesh.SecondOrderIncomplete = 0, recombined), without volume cells"
            )
        data = np.asarray(block.data, dtype=np.int64)
        if split:  # meshio line3: end, end, middle
            data = np.stack([data[:, [0, 2]], data[:, [2, 1]]], axis=1).reshape(-1, 2)
        block_kind.append(kind)
        block_split.append(split)
        block_offset.append(counts.get(kind, 0))
        cells.setdefault(kind, []).append(data)
        counts[kind] = counts.get(kind, 0) + len(data)
    cells_c = {k: np.concatenate(v) for k, v in cells.items()}
    if not any(k in cells_c for k in ("tri3", "quad4", "quad9", "line2")):
        raise FormatError(f"{where}: no triangle, quad or line cells")

    element_sets: dict[str, dict[str, list[np.ndarray]]] = {}

    def add(name: str, b: int, local: np.ndarray) -> None:
        if len(local) == 0:
            return
        kind = block_kind[b]
        local = np.asarray(local, dtype=np.int64)
        if block_split[b]:
            local = np.stack([2 * local, 2 * local + 1], axis=1).ravel()
        element_sets.setdefault(name, {}).setdefault(kind, []).append(
            block_offset[b] + local)

    for name, per_block in (m.cell_sets or {}).items():
        if name.startswith("gmsh:"):
            continue
        for b, local in enumerate(per_block):
            if local is not None:
                add(str(name), b, local)
    phys = (m.cell_data or {}).get("gmsh:physical")
    if phys is not None and m.field_data:
        dims = {"vertex": 0, "line2": 1, "tri3": 2, "quad4": 2, "quad9": 2}
        for name, (tag, dim) in ((k, v[:2]) for k, v in m.field_data.items()):
            for b, tags in enumerate(phys):
                if dims[block_kind[b]] == int(dim):
                    add(str(name), b, np.flatnonzero(np.asarray(tags) == int(tag)))
    # other integer cell data (VTU files, MED/medit refs, unnamed physical tags): one set
    # per value, named "<key>:<value>"
    for key, per_block in (m.cell_data or {}).items():
        if key == "gmsh:geometrical" or (key == "gmsh:physical" and m.field_data):
            continue
        arrays = [np.asarray(a) for a in per_block]
        if not all(a.ndim == 1 and np.issubdtype(a.dtype, np.integer) for a in arrays):
            continue
        for b, a in enumerate(arrays):
            for v in np.unique(a):
                add(f"{key}:{int(v)}", b, np.flatnonzero(a == v))
    esets = {n: {k: np.unique(np.concatenate(v)) for k, v in d.items()}
             for n, d in element_sets.items()}
    node_sets = {str(n): np.unique(np.concatenate([np.asarray(a, dtype=np.int64).ravel()
                                                   for a in v]))
                 for n, v in (m.point_sets or {}).items()}
    for name, d in esets.items():
        if name not in node_sets:
            node_sets[name] = np.unique(np.concatenate([cells_c[k][i].ravel()
                                                        for k, i in d.items()]))
    return ImportedMesh(nodes=nodes, cells=cells_c, element_sets=esets, node_sets=node_sets,
                        source=source)


@dataclass(frozen=True)
class ShellSection:
    """Section of a shell element set: laminate, material axis, offset (see ShellSet).

    Examples
    --------
    The section of a shell element set with its ply angles measured from global y:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply
    >>> lam = Laminate((Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3),))
    >>> ShellSection(lam, material_axis=(0.0, 1.0, 0.0)).material_axis
    (0.0, 1.0, 0.0)
    """

    laminate: Laminate
    material_axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    offset: float = 0.0


@dataclass(frozen=True)
class BeamProperty:
    """Section of a beam element set: section, orientation vector, offset (see BeamSet).

    Examples
    --------
    A 20 x 2 mm steel strip whose width axis lies along global y:

    >>> from mvtk.fe import IsotropicMaterial, rectangle_section
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> prop = BeamProperty(rectangle_section(steel, 0.02, 0.002), orientation=(0.0, 1.0, 0.0))
    >>> round(prop.section.EIy, 6)
    2.8
    """

    section: BeamSection
    orientation: tuple[float, float, float] = (0.0, 0.0, 1.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


def mesh_model(
    mesh: ImportedMesh,
    sections: Mapping[str, ShellSection | BeamProperty | Laminate],
    *,
    members: Sequence[Any] = (),
    supports: Mapping[str, Any] | None = None,
    node_sets: Mapping[str, Sequence[int]] | None = None,
    name: str = "",
    meta: Mapping[str, Any] | None = None,
    node_frames: Mapping[int, Any] | None = None,
) -> FEModel:
    """Assemble an imported mesh, one section per element set.

    Parameters
    ----------
    mesh : ImportedMesh
    sections : mapping of element-set name to ShellSection, BeamProperty or Laminate
        Shell sets take a :class:`ShellSection` (or a bare Laminate), line sets a
        :class:`BeamProperty`. Every triangle and quad must belong to exactly one mapped
        set; line cells outside mapped sets are ignored (they usually only mark edges).
    members : sequence, optional
        Further members (PointMass, Spring, RigidLink) for :func:`mvtk.fe.assemble_model`.
    supports, node_sets, name, meta, node_frames
        As in :func:`mvtk.fe.assemble_model`; ``node_sets`` add to the mesh's.

    Raises
    ------
    ParameterError
        For an unknown set name, a set of the wrong cell kind for its section, or surface
        cells left without a section (the message gives their count and the sets).

    Examples
    --------
    The imported plate (6 x 4 quads, 2 mm steel) clamped on its node set ``root``: the
    same frequencies as :func:`mvtk.fe.plate_model` on the same mesh:

    >>> import meshio
    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Ply, modal_analysis, plate_model,
    ...                      rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> grid = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    >>> mesh = from_meshio(meshio.Mesh(grid.nodes, [("quad", grid.elements)],
    ...                                cell_sets={"plate": [np.arange(len(grid.elements))]},
    ...                                point_sets={"root": grid.node_sets["x0"]}))
    >>> model = mesh_model(mesh, {"plate": Laminate((Ply(steel, 2e-3),))},
    ...                    supports={"root": "clamped"})
    >>> np.round(modal_analysis(model, 2).fn_hz, 2)
    array([19.22, 65.17])
    >>> ref = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> np.round(modal_analysis(ref, 2).fn_hz, 2)
    array([19.22, 65.17])
    """
    out: list[Any] = []
    covered = {k: np.zeros(len(v), dtype=int) for k, v in mesh.cells.items()}
    for set_name, sec in sections.items():
        if set_name not in mesh.element_sets:
            raise ParameterError(
                f"element set {set_name!r} is not in {mesh.source or 'the mesh'}; available: "
                f"{sorted(mesh.element_sets)}"
            )
        parts = mesh.element_sets[set_name]
        if isinstance(sec, Laminate):
            sec = ShellSection(sec)
        if isinstance(sec, ShellSection):
            kinds = [k for k in ("tri3", "quad4", "quad9") if k in parts]
            if not kinds:
                raise ParameterError(f"element set {set_name!r} has no triangles or quads "
                                     f"(it holds {sorted(parts)}) but got a shell section")
            for k in kinds:
                covered[k][parts[k]] += 1
                out.append(ShellSet(mesh.cells[k][parts[k]], sec.laminate, sec.material_axis,
                                    sec.offset, name=f"{set_name}:{k}"))
        elif isinstance(sec, BeamProperty):
            if "line2" not in parts:
                raise ParameterError(f"element set {set_name!r} has no line cells (it holds "
                                     f"{sorted(parts)}) but got a beam section")
            covered["line2"][parts["line2"]] += 1
            out.append(BeamSet(mesh.cells["line2"][parts["line2"]], sec.section,
                               sec.orientation, sec.offset, name=set_name))
        else:
            raise ParameterError(f"section of element set {set_name!r} must be a "
                                 f"ShellSection, BeamProperty or Laminate, got "
                                 f"{type(sec).__name__}")
    for k in ("tri3", "quad4", "quad9", "line2"):
        if k in covered and np.any(covered[k] > 1):
            raise ParameterError(f"{int(np.sum(covered[k] > 1))} {k} cells belong to several "
                                 "mapped element sets; map each cell once")
        if k in ("tri3", "quad4", "quad9") and k in covered and np.any(covered[k] == 0):
            raise ParameterError(
                f"{int(np.sum(covered[k] == 0))} of {len(covered[k])} {k} cells of "
                f"{mesh.source or 'the mesh'} have no section; map their element sets "
                f"(available: {sorted(mesh.element_sets)})"
            )
    sets = dict(mesh.node_sets)
    sets.update({str(k): np.asarray(v, dtype=np.int64) for k, v in (node_sets or {}).items()})
    info = {"mesh_source": mesh.source}
    info.update(meta or {})
    return assemble_model(mesh.nodes, out + list(members), supports=supports, node_sets=sets,
                          name=name, meta=info, node_frames=node_frames)


def _shapes_full(model: FEModel, result) -> np.ndarray:
    """Nodal shapes (n_modes, n_nodes, 6) of a ModalResult on ``model``."""
    shapes = np.asarray(result.shapes)
    if shapes.shape[0] != model.n_dof:
        raise ParameterError(f"the modal result has {shapes.shape[0]} DOFs, the model "
                             f"{model.n_dof}: it belongs to another model")
    return np.moveaxis(model.expand(shapes), 2, 0)


def _cells(model: FEModel) -> list[tuple[str, np.ndarray]]:
    names = {"mitc4": "quad", "mitc3": "triangle", "mitc9": "quad9", "beam2": "line"}
    return [(names[k], v) for k, v in model.elements.items() if k in names and len(v)]


def _export_mesh(model: FEModel, result, fields):
    """meshio.Mesh of the model with mode shapes and static fields as point data."""
    meshio = _meshio()
    point_data = {"node_id": np.asarray(model.node_ids)}
    field_data = {}
    if result is not None:
        full = _shapes_full(model, result)
        for k, u in enumerate(full, start=1):
            point_data[f"mode_{k}_displacement"] = u[:, :3]
            point_data[f"mode_{k}_rotation"] = u[:, 3:]
        field_data["fn_hz"] = np.asarray(result.fn_hz, dtype=float)
    for key, x in (fields or {}).items():
        x = np.asarray(x, dtype=float)
        if x.shape != (model.n_dof,):
            raise ParameterError(f"field {key!r} must have shape ({model.n_dof},), got "
                                 f"{x.shape}")
        u = model.expand(x)
        point_data[f"{key}_displacement"] = u[:, :3]
        point_data[f"{key}_rotation"] = u[:, 3:]
    return meshio.Mesh(model.nodes, _cells(model), point_data=point_data,
                       field_data=field_data)


def write_vtu(model: FEModel, path: str | Path, result=None,
              fields: Mapping[str, np.ndarray] | None = None) -> Path:
    """Write the mesh and (optionally) mode shapes and static results to a VTU file.

    Point data per mode ``k`` (1-based): ``mode_k_displacement`` (n_nodes, 3, m) and
    ``mode_k_rotation`` (n_nodes, 3, rad), mass-normalised; field data ``fn_hz``. Each
    entry ``name -> x`` of ``fields`` (a free-DOF vector, e.g. from
    :func:`mvtk.fe.static_solve`) gives ``name_displacement`` and ``name_rotation``.
    Eliminated DOFs (supports) are zero, rigid-link dependents are recovered.

    Returns
    -------
    Path

    Examples
    --------
    Mode shapes of a clamped plate for ParaView:

    >>> import pathlib, tempfile
    >>> import meshio
    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> path = write_vtu(plate, pathlib.Path(tempfile.mkdtemp()) / "modes.vtu",
    ...                  modal_analysis(plate, 2))
    >>> sorted(meshio.read(path).point_data)[:3]
    ['mode_1_displacement', 'mode_1_rotation', 'mode_2_displacement']
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        _export_mesh(model, result, fields).write(tmp, file_format="vtu")
    return path


def write_xdmf(model: FEModel, path: str | Path, result=None,
               fields: Mapping[str, np.ndarray] | None = None) -> Path:
    """Write the mesh, mode shapes and static results to XDMF (ParaView, VisIt).

    The same point data as :func:`write_vtu` (``node_id``, ``mode_k_displacement``,
    ``mode_k_rotation``, ``name_displacement``, ``name_rotation``); the heavy data go to
    an HDF5 file next to ``path`` (same stem, ``.h5``), which must stay beside the
    ``.xdmf`` file. XDMF has no field data: the frequencies (Hz) are written as
    ``path`` with suffix ``.fn_hz.csv`` (one ``mode,fn_hz`` row per mode) when
    ``result`` is given.

    Returns
    -------
    Path
        The ``.xdmf`` file.

    Examples
    --------
    The mesh and modes go to ``modes.xdmf`` and ``modes.h5``, the frequencies to
    ``modes.fn_hz.csv``:

    >>> import pathlib, tempfile
    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = write_xdmf(plate, folder / "modes.xdmf", modal_analysis(plate, 2))
    >>> sorted(p.name for p in folder.iterdir())
    ['modes.fn_hz.csv', 'modes.h5', 'modes.xdmf']
    """
    path = Path(path)
    if path.suffix.lower() not in (".xdmf", ".xmf"):
        raise ParameterError(f"XDMF file name must end in .xdmf or .xmf, got {path.name!r}")
    mesh = _export_mesh(model, result, fields)
    mesh.field_data = {}
    # meshio writes the .xdmf and its .h5 under their final names (the .xdmf names the
    # .h5); write both in a private folder beside the target, then move each file over
    # its target in one step, so a failure leaves the previous pair as it was
    folder = path.parent if str(path.parent) else Path(".")
    heavy = path.with_suffix(".h5")
    try:
        scratch = tempfile.TemporaryDirectory(prefix=f".{path.name}.", dir=folder)
    except OSError as err:
        raise write_error(path, err) from err
    with scratch as tmpdir:
        with atomic_path(path) as tmp_xdmf:
            try:
                mesh.write(Path(tmpdir) / path.name, file_format="xdmf")
            except OSError as err:
                raise write_error(path, err) from err
            with atomic_path(heavy) as tmp_h5:
                os.replace(Path(tmpdir) / heavy.name, tmp_h5)
            os.replace(Path(tmpdir) / path.name, tmp_xdmf)
    if result is not None:
        fn = np.asarray(result.fn_hz, dtype=float)
        rows = "".join(f"{k},{float(f)!r}\n" for k, f in enumerate(fn, start=1))
        write_text(path.with_suffix(".fn_hz.csv"), "mode,fn_hz\n" + rows)
    return path


def write_uff(model: FEModel, path: str | Path, result=None) -> Path:
    """Write nodes (UFF 2411 and 15) and mode shapes (UFF 55, one per mode).

    Node labels are :attr:`FEModel.node_ids`; every dataset 55 holds the six DOFs of
    every node (rotations in rad), ``analysis_type`` 2 (normal mode), frequency in Hz and
    modal mass 1 (mass-normalised shapes). Rigid-body modes are written with 0 Hz.

    Examples
    --------
    Nodes and two mode shapes of a clamped plate as UFF 2411/15 and 55 records:

    >>> import pathlib, tempfile
    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> path = write_uff(plate, pathlib.Path(tempfile.mkdtemp()) / "modes.uff",
    ...                  modal_analysis(plate, 2))
    >>> path.suffix, path.stat().st_size > 0
    ('.uff', True)
    """
    import pyuff

    path = Path(path)
    with atomic_path(path) as tmp:
        _write_uff_sets(pyuff, pyuff.UFF(str(tmp)), model, result)
    return path


def _write_uff_sets(pyuff, uff, model: FEModel, result) -> None:
    ids = np.asarray(model.node_ids, dtype=int)
    zeros = np.zeros(model.n_nodes, dtype=int)
    uff.write_sets(pyuff.prepare_2411(node_nums=ids, def_cs=zeros, disp_cs=zeros,
                                      color=zeros + 1, x=model.nodes[:, 0],
                                      y=model.nodes[:, 1], z=model.nodes[:, 2],
                                      return_full_dict=True), mode="add")
    uff.write_sets(pyuff.prepare_15(node_nums=ids, def_cs=zeros, disp_cs=zeros, color=zeros,
                                    x=model.nodes[:, 0], y=model.nodes[:, 1],
                                    z=model.nodes[:, 2], return_full_dict=True), mode="add")
    if result is not None:
        full = _shapes_full(model, result)
        for k, u in enumerate(full, start=1):
            ds = pyuff.prepare_55(
                id1=f"mvtk mode {k}", id2=model.name or "mvtk FE model", model_type=1,
                analysis_type=2, data_ch=2, spec_data_type=8, data_type=2, n_data_per_node=6,
                r1=u[:, 0], r2=u[:, 1], r3=u[:, 2], r4=u[:, 3], r5=u[:, 4], r6=u[:, 5],
                node_nums=ids, load_case=1, mode_n=k, modal_m=1.0,
                freq=float(result.fn_hz[k - 1]), modal_damp_vis=0.0, modal_damp_his=0.0,
                return_full_dict=True)
            uff.write_sets(ds, mode="add")
