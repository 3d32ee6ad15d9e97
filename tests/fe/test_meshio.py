"""Mesh import (meshio), structure TOML with [mesh] file, VTU/UFF export, to_xarray."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError, FormatError, ParameterError
from mvtk.fe import (
    IsotropicMaterial,
    Laminate,
    Ply,
    build_model,
    modal_analysis,
    plate_model,
    rectangular_plate_mesh,
)
from mvtk.fe._meshio import mesh_model, read_mesh, write_uff, write_vtu, write_xdmf

meshio = pytest.importorskip("meshio")
DATA = Path(__file__).resolve().parents[2] / "data" / "structures"
STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def _write_gmsh(path, nx=12, ny=8, tri=False):
    """The built-in rectangle written as a Gmsh 2.2 file with physical groups."""
    m = rectangular_plate_mesh(0.3, 0.2, nx=nx, ny=ny)
    x0 = m.node_sets["x0"]
    lines = np.column_stack([x0[:-1], x0[1:]])
    els = m.elements
    kind = "quad"
    if tri:
        els, kind = np.concatenate([els[:, [0, 1, 2]], els[:, [0, 2, 3]]]), "triangle"
    phys = [np.full(len(els), 1), np.full(len(lines), 2)]
    mesh = meshio.Mesh(m.nodes, [(kind, els), ("line", lines)],
                       cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                       field_data={"plate": np.array([1, 2]), "clamp": np.array([2, 1])})
    mesh.write(path, file_format="gmsh22", binary=False)
    return m


def test_gmsh_rectangle_gives_builtin_frequencies_to_round_off(tmp_path, capsys):
    path = tmp_path / "plate.msh"
    _write_gmsh(path)
    capsys.readouterr()
    imported = read_mesh(path)
    assert capsys.readouterr().out == ""  # meshio's stdout notes would corrupt --json
    assert set(imported.element_sets) == {"plate", "clamp"}
    assert len(imported.node_sets["clamp"]) == 9
    model = mesh_model(imported, {"plate": Laminate((Ply(STEEL, 1e-3),))},
                       supports={"clamp": "clamped"})
    ref = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=12, ny=8, clamp="x0")
    np.testing.assert_allclose(modal_analysis(model, 8).fn_hz,
                               modal_analysis(ref, 8).fn_hz, rtol=1e-8)


def test_structure_toml_with_mesh_file(tmp_path):
    _write_gmsh(tmp_path / "part.msh", tri=True)
    toml = tmp_path / "part.toml"
    toml.write_text(
        '[materials.steel]\nE = 210e9\nnu = 0.3\nrho = 7850\n'
        '[structure]\ntype = "mesh"\n'
        '[mesh]\nfile = "part.msh"\nsections = { plate = "skin" }\n'
        '[sections.skin]\nlayers = [{ material = "steel", thickness = 1e-3 }]\n'
        '[boundary]\nsupports = { clamp = "clamped" }\n'
        '[[points]]\nname = "tip"\nx = 0.3\ny = 0.1\nz = 0.0\n')
    model = build_model(toml)
    assert "tip" in model.node_sets and "mitc3" in model.elements
    f = modal_analysis(model, 2).fn_hz
    ref = modal_analysis(plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=12, ny=8, clamp="x0"),
                         2).fn_hz
    np.testing.assert_allclose(f, ref, rtol=0.03)  # triangles vs quads, same nodes


def _cylinder_grid(radius=0.5, half_arc_deg=30.0, length=0.4, nx=20, na=16):
    """The curved panel's nodes written out analytically: (x_i, r sin t_j, r cos t_j)."""
    x, t = np.meshgrid(np.linspace(0.0, length, nx + 1),
                       np.radians(np.linspace(-half_arc_deg, half_arc_deg, na + 1)),
                       indexing="ij")
    return np.column_stack([x.ravel(), radius * np.sin(t.ravel()), radius * np.cos(t.ravel())])


def test_curved_panel_example_mesh_is_the_cylinder_its_geometry_file_describes():
    """data/structures/curved_panel: the committed mesh (written by Gmsh from
    curved_panel.geo) has exactly the nodes of the analytic 20 x 16 grid on the
    cylinder, its groups, and a model that builds and vibrates."""
    m = meshio.read(DATA / "curved_panel" / "curved_panel.msh")
    grid = _cylinder_grid()
    assert len(m.points) == len(grid)
    # every mesh node is one grid node and vice versa (Gmsh places points on its arcs to
    # ~4e-10 m, 1e-9 of the radius)
    from scipy.spatial import cKDTree

    dist, nearest = cKDTree(grid).query(m.points)
    assert dist.max() < 1e-9 and len(set(nearest)) == len(grid)
    assert {k: len(v) for k, v in m.cells_dict.items()} == {"quad": 320, "line": 52}
    assert set(m.field_data) == {"skin", "stiffener", "ends"}
    model = build_model(DATA / "curved_panel" / "curved_panel.toml")
    res = modal_analysis(model, 4)
    assert np.all(res.fn_hz > 50) and not res.rigid.any()
    assert model.elements["beam2"].shape == (20, 2)


def test_curved_panel_mesh_is_regenerated_identically_from_its_geometry_file(tmp_path):
    """make_mesh.py runs Gmsh on curved_panel.geo and reproduces the committed mesh
    byte for byte (Gmsh Python API from the test extra; skipped when it cannot load)."""
    import importlib.util

    try:
        import gmsh  # noqa: F401
    except (ImportError, OSError) as err:  # OSError: a shared library Gmsh needs
        pytest.skip(f"the Gmsh Python API is not available ({err}); pip install gmsh")
    spec = importlib.util.spec_from_file_location(
        "make_mesh", DATA / "curved_panel" / "make_mesh.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.generate(tmp_path / "p.msh")
    assert out.read_text() == (DATA / "curved_panel" / "curved_panel.msh").read_text()


def test_bad_mesh_inputs(tmp_path):
    with pytest.raises(FormatError, match="not found"):
        read_mesh(tmp_path / "missing.msh")
    # meshio's Gmsh reader ends the process (sys.exit) on a text file named .msh
    junk = tmp_path / "junk.msh"
    junk.write_text("this is not a mesh\n", encoding="utf-8")
    with pytest.raises(FormatError, match=r"junk.msh': meshio could not read it \(.*gmsh"):
        read_mesh(junk)
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 0], [0.5, 0.5, 0],
                    [0, 0.5, 0.0]])
    meshio.Mesh(pts, [("triangle6", np.array([[0, 1, 2, 3, 4, 5]]))]).write(
        tmp_path / "t6.vtu")
    with pytest.raises(FormatError, match=r"cell type 'triangle6' is not supported.*"
                       r"first-order"):
        read_mesh(tmp_path / "t6.vtu")
    _write_gmsh(tmp_path / "p.msh")
    m = read_mesh(tmp_path / "p.msh")
    lam = Laminate((Ply(STEEL, 1e-3),))
    with pytest.raises(ParameterError, match=r"element set 'skin' is not in .*available: "
                       r"\['clamp', 'plate'\]"):
        mesh_model(m, {"skin": lam})
    with pytest.raises(ParameterError, match="has no triangles or quads"):
        mesh_model(m, {"clamp": lam})
    toml = tmp_path / "bad.toml"
    toml.write_text('[materials.s]\nE = 1e9\nnu = 0.3\nrho = 1000\n[structure]\n'
                    'type = "plate"\nlength = 1\nwidth = 1\n'
                    'layers = [{ material = "s", thickness = 1e-3 }]\n'
                    '[mesh]\nfile = "p.msh"\n')
    with pytest.raises(ConfigError, match="mesh.file needs structure.type = 'mesh'"):
        build_model(toml)
    toml.write_text('[materials.s]\nE = 1e9\nnu = 0.3\nrho = 1000\n[structure]\n'
                    'type = "mesh"\n[mesh]\nfile = "p.msh"\nnx = 4\n'
                    'sections = { plate = "a" }\n[sections.a]\n'
                    'layers = [{ material = "s", thickness = 1e-3 }]\n')
    with pytest.raises(ConfigError, match=r"mesh.nx: not applicable here \(the mesh comes "
                       r"from mesh.file\); accepted keys: file, sections"):
        build_model(toml)


def test_vtu_and_uff_export_and_to_xarray(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    model = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=6, ny=4, clamp="x0")
    res = modal_analysis(model, 3)
    from mvtk.fe import static_solve

    f = np.zeros(model.n_dof)
    f[model.dof_index(model.node_set("x1")[0], "uz")] = 1.0
    x = static_solve(model, f)
    write_vtu(model, tmp_path / "m.vtu", res, fields={"tip_load": x})
    back = meshio.read(tmp_path / "m.vtu")
    np.testing.assert_allclose(back.point_data["tip_load_displacement"],
                               model.expand(x)[:, :3])
    full = model.expand(res.shapes)
    np.testing.assert_allclose(back.point_data["mode_2_displacement"], full[:, :3, 1])
    np.testing.assert_array_equal(back.point_data["node_id"], model.node_ids)
    write_uff(model, tmp_path / "m.uff", res)
    uff = pyuff.UFF(str(tmp_path / "m.uff"))
    assert list(uff.get_set_types()) == [2411, 15, 55, 55, 55]
    d55 = uff.read_sets(3)
    assert d55["freq"] == pytest.approx(res.fn_hz[1], rel=1e-5)
    np.testing.assert_allclose(d55["r3"], full[:, 2, 1], rtol=1e-5,
                               atol=1e-6 * np.abs(full[:, 2, 1]).max())
    da = res.to_xarray()
    assert da.dims == ("mode", "dof") and da.shape == (3, model.n_dof)
    assert list(da.mode.values) == [1, 2, 3]
    n, c = model.dof_node[0], model.dof_component[0]
    assert da.dof.values[0] == f"{model.node_ids[n]}{['+x', '+y', '+z', '+rx', '+ry', '+rz'][c]}"
    assert da.attrs["normalisation"] == "mass" and np.isnan(da.zeta).all()


def test_xdmf_export_round_trip_with_shells_and_beams(tmp_path):
    """XDMF (XML + HDF5) read back with meshio: mixed quad/line cells, shapes, fields."""
    from mvtk.fe import BeamSet, ShellSet, assemble_model, static_solve, tube_section

    mesh = rectangular_plate_mesh(0.3, 0.2, 6, 4)
    nodes, quads = mesh.nodes, mesh.elements
    on_y0 = np.flatnonzero(np.isclose(nodes[:, 1], 0.1))
    on_y0 = on_y0[np.argsort(nodes[on_y0, 0])]
    beams = np.column_stack([on_y0[:-1], on_y0[1:]])
    clamp = np.flatnonzero(np.isclose(nodes[:, 0], 0.0))
    model = assemble_model(
        nodes, [ShellSet(quads, Laminate([Ply(STEEL, 1e-3)])),
                BeamSet(beams, tube_section(STEEL, 0.004), offset=(0, 0, -0.005))],
        supports={"clamp": "clamped"}, node_sets={"clamp": clamp})
    res = modal_analysis(model, 3)
    f = np.zeros(model.n_dof)
    f[model.dof_index(int(on_y0[-1]), "uz")] = 1.0
    x = static_solve(model, f)
    out = write_xdmf(model, tmp_path / "m.xdmf", res, fields={"tip_load": x})
    assert out == tmp_path / "m.xdmf" and (tmp_path / "m.h5").exists()
    back = meshio.read(out)
    np.testing.assert_allclose(back.points, model.nodes)
    assert {c.type: len(c.data) for c in back.cells} == {"quad": len(quads),
                                                         "line": len(beams)}
    full = model.expand(res.shapes)
    for k in range(3):
        np.testing.assert_array_equal(back.point_data[f"mode_{k + 1}_displacement"],
                                      full[:, :3, k])
        np.testing.assert_array_equal(back.point_data[f"mode_{k + 1}_rotation"],
                                      full[:, 3:, k])
    np.testing.assert_array_equal(back.point_data["tip_load_displacement"],
                                  model.expand(x)[:, :3])
    np.testing.assert_array_equal(back.point_data["node_id"], model.node_ids)
    table = np.loadtxt(tmp_path / "m.fn_hz.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 1], res.fn_hz)
    with pytest.raises(ParameterError, match=r"must end in .xdmf or .xmf, got 'm.vtu'"):
        write_xdmf(model, tmp_path / "m.vtu", res)
    with pytest.raises(ParameterError, match=r"field 'bad' must have shape"):
        write_xdmf(model, tmp_path / "m.xdmf", fields={"bad": np.ones(3)})


def test_xdmf_failure_leaves_the_previous_pair_unchanged(tmp_path, monkeypatch):
    """The .xdmf and its .h5 are written in a private folder and moved over the old
    pair only when both are complete: a writer failing half-way (here an OSError from
    meshio) leaves the previous files byte-identical and no temporary file behind."""
    import meshio

    from mvtk.errors import OutputError

    model = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=4, ny=3, clamp="x0")
    res = modal_analysis(model, 2)
    write_xdmf(model, tmp_path / "m.xdmf", res)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert set(before) == {"m.xdmf", "m.h5", "m.fn_hz.csv"}

    def broken(self, path, *args, **kwargs):
        Path(path).with_suffix(".h5").write_bytes(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(meshio.Mesh, "write", broken)
    with pytest.raises(OutputError, match=r"m\.xdmf: could not be written: disk full"):
        write_xdmf(model, tmp_path / "m.xdmf", modal_analysis(model, 3))
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_matrix_market_round_trip_with_dof_table(tmp_path):
    import scipy.io

    from mvtk.fe import read_matrices

    model = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=6, ny=4, clamp="x0")
    scipy.io.mmwrite(tmp_path / "K.mtx", model.K)
    scipy.io.mmwrite(tmp_path / "M.mtx", model.M)
    names = ["ux", "uy", "uz", "rx", "ry", "rz"]
    (tmp_path / "dofs.csv").write_text("node,dof\n" + "".join(
        f"{model.node_ids[n]},{names[c] if i % 2 else c + 1}\n"
        for i, (n, c) in enumerate(zip(model.dof_node, model.dof_component))))
    (tmp_path / "nodes.csv").write_text("node,x,y,z\n" + "".join(
        f"{i},{x:.17g},{y:.17g},{z:.17g}\n" for i, (x, y, z) in zip(model.node_ids, model.nodes)))
    third = read_matrices(tmp_path / "K.mtx", tmp_path / "M.mtx", tmp_path / "dofs.csv",
                          tmp_path / "nodes.csv")
    np.testing.assert_allclose(modal_analysis(third, 4).fn_hz,
                               modal_analysis(model, 4).fn_hz, rtol=1e-9)
    np.testing.assert_array_equal(third.node_ids[third.dof_node],
                                  model.node_ids[model.dof_node])
    (tmp_path / "bad.csv").write_text("node,dof\n1,7\n")
    with pytest.raises(FormatError, match=r"DOF table row 1: dof '7' is not 1..6"):
        read_matrices(model.K[:1, :1], model.M[:1, :1], tmp_path / "bad.csv")
    with pytest.raises(Exception, match="the DOF table has 1 rows, the matrices 2"):
        read_matrices(model.K[:2, :2], model.M[:2, :2], tmp_path / "bad.csv")


def test_integer_cell_data_of_a_vtu_becomes_element_sets(tmp_path):
    m = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    region = (m.nodes[m.elements].mean(axis=1)[:, 0] > 0.15).astype(np.int64)
    meshio.Mesh(m.nodes, [("quad", m.elements)], cell_data={"region": [region]}).write(
        tmp_path / "r.vtu")
    imported = read_mesh(tmp_path / "r.vtu")
    assert sorted(imported.element_sets) == ["region:0", "region:1"]
    lam = Laminate((Ply(STEEL, 1e-3),))
    thick = Laminate((Ply(STEEL, 2e-3),))
    model = mesh_model(imported, {"region:0": lam, "region:1": thick})
    assert model.n_elements == len(m.elements)


def test_abaqus_inp_element_and_node_sets(tmp_path):
    m = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    left = np.flatnonzero(m.nodes[m.elements].mean(axis=1)[:, 0] < 0.15)
    right = np.setdiff1d(np.arange(len(m.elements)), left)
    meshio.Mesh(m.nodes, [("quad", m.elements)],
                cell_sets={"THIN": [left], "THICK": [right]},
                point_sets={"CLAMP": m.node_sets["x0"]}).write(tmp_path / "p.inp")
    imported = read_mesh(tmp_path / "p.inp")
    assert {"THIN", "THICK", "CLAMP"} <= set(imported.node_sets)
    np.testing.assert_array_equal(imported.node_sets["CLAMP"], m.node_sets["x0"])
    model = mesh_model(imported, {"THIN": Laminate((Ply(STEEL, 1e-3),)),
                                  "THICK": Laminate((Ply(STEEL, 1e-3),))},
                       supports={"CLAMP": "clamped"})
    ref = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=6, ny=4, clamp="x0")
    np.testing.assert_allclose(modal_analysis(model, 3).fn_hz, modal_analysis(ref, 3).fn_hz,
                               rtol=1e-8)


def test_mesh_file_is_found_relative_to_the_structure_file_from_any_directory(
        tmp_path, monkeypatch, capsys):
    """`mvtk modes data/structures/curved_panel/curved_panel.toml` from the repository
    root refused the project's own example (the mesh path was taken relative to the
    working directory)."""
    from pathlib import Path

    from mvtk.cli import main

    toml = (Path(__file__).resolve().parents[2] / "data" / "structures" / "curved_panel"
            / "curved_panel.toml")
    monkeypatch.chdir(tmp_path)
    assert main(["modes", str(toml), "-n", "2"]) == 0
    out = capsys.readouterr().out
    assert "in-plane" in out or "bending" in out, out


def test_modes_on_a_mesh_file_points_to_init(capsys):
    """A newcomer's `mvtk modes part.msh` gave "invalid TOML: Expected '=' after a key";
    it now says what a mesh lacks and which command writes the structure TOML."""
    from mvtk.cli import main

    msh = DATA / "curved_panel" / "curved_panel.msh"
    assert main(["modes", str(msh)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "is a mesh file, not a structure TOML" in err
    assert f"`mvtk init DIR --structure {msh}`" in err
