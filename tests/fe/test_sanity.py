"""Sanity checks before any solve: each problem is named (entity, likely cause, factor).

External truths: the unit factors are exact (a millimetre geometry is 1000 x its SI
size; 70 000 MPa = 7e10 Pa); the mesh-density rule is the textbook one (about four linear
elements per bending half-wave; with one element across the Leissa CFFF plate the first
frequency is off by far more than that, shown below against the 24 x 24 mesh).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from mvtk.errors import ConfigError, FormatError, ModelWarning, ParameterError
from mvtk.fe import build_model, modal_analysis, read_matrices
from mvtk.fe._sanity import check_size

ROOT = Path(__file__).resolve().parents[2]
PLATE = (ROOT / "data" / "structures" / "plate.toml").read_text()


def _plate(tmp_path, *replace, extra=""):
    text = PLATE
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "p.toml"
    path.write_text(text + extra)
    return path


def _build(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = build_model(path)
    return model, [str(w.message) for w in caught if issubclass(w.category, ModelWarning)]


def test_the_example_structures_pass_without_a_word():
    for name in ("plate.toml", "smart_beam.toml", "smart_beam_beam.toml"):
        model, warned = _build(ROOT / "data" / "structures" / name)
        assert warned == [] and model.meta.get("sanity") is None, (name, warned)


def test_plate_in_millimetres_warns_with_the_factor(tmp_path):
    path = _plate(tmp_path, ("length = 0.3", "length = 300.0"), ("width = 0.3", "width = 300.0"),
                  ("thickness = 3e-3", "thickness = 3.0"), ("x = 0.3", "x = 300.0"),
                  ("y = 0.15", "y = 150.0"))
    model, warned = _build(path)
    assert len(warned) == 1 and "spans 300 m" in warned[0]
    assert "millimetres? (likely factor 1e-3: 0.3 m)" in warned[0]
    assert model.meta["sanity"] == warned          # the model carries it


def test_modulus_in_mpa_warns_with_the_factor(tmp_path):
    _, warned = _build(_plate(tmp_path, ("E = 70e9", "E = 70000")))
    assert warned == ["materials.aluminium.E = 70000 Pa is far below any structural "
                      "material: a value in MPa? (likely factor 1e6: 7e+10 Pa)"]


def test_one_element_across_the_plate_warns_and_is_far_off(tmp_path):
    model, warned = _build(_plate(tmp_path, ("nx = 24", "nx = 1"), ("ny = 24", "ny = 1")))
    assert len(warned) == 1 and "1 element(s) along x over 0.3 m" in warned[0]
    with pytest.warns(ModelWarning, match=r"mode\(s\) 3 \(260.4 Hz\) have fewer elements"):
        coarse = modal_analysis(model, 3).fn_hz
    fine = modal_analysis(build_model(ROOT / "data" / "structures" / "plate.toml"), 3).fn_hz
    assert np.max(np.abs(coarse / fine - 1)) > 0.2    # what the warning is about
    _, warned4 = _build(_plate(tmp_path, ("nx = 24", "nx = 4")))
    assert warned4 == []


def test_duplicate_point_names_are_refused(tmp_path):
    path = _plate(tmp_path, extra='\n[[points]]\nname = "tip"\nx = 0.1\ny = 0.1\n')
    with pytest.raises(ConfigError, match=r"points: the name 'tip' is given 2 times "
                                          r"\(points\[0\], points\[1\]\)"):
        build_model(path)


def _mesh_structure(tmp_path, nodes, quads, extra="", clamped=True):
    meshio = pytest.importorskip("meshio")
    clamp = [i for i, p in enumerate(nodes) if p[0] == 0.0]
    clamp = sorted(clamp, key=lambda i: nodes[i][1])
    lines = np.column_stack([clamp[:-1], clamp[1:]])
    phys = [np.full(len(quads), 1), np.full(len(lines), 2)]
    meshio.Mesh(np.asarray(nodes, float), [("quad", np.asarray(quads)), ("line", lines)],
                cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                field_data={"plate": np.array([1, 2]), "clamp": np.array([2, 1])}).write(
        tmp_path / "m.msh", file_format="gmsh22", binary=False)
    path = tmp_path / "m.toml"
    path.write_text('[materials.steel]\nE = 210e9\nnu = 0.3\nrho = 7850\n'
                    '[structure]\ntype = "mesh"\n'
                    '[mesh]\nfile = "m.msh"\nsections = { plate = "skin" }\n'
                    '[sections.skin]\nlayers = [{ material = "steel", thickness = 1e-3 }]\n'
                    + ('[boundary]\nsupports = { clamp = "clamped" }\n' if clamped else "")
                    + extra)
    return path


def _grid(x0, x1, nx, ny, width, offset):
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(0, width, ny + 1)
    nodes = [(x, y, 0.0) for x in xs for y in ys]
    idx = np.arange(len(nodes)).reshape(nx + 1, ny + 1) + offset
    quads = np.column_stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(),
                             idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()])
    return nodes, quads


def test_crack_of_coincident_unconnected_nodes_is_listed(tmp_path):
    a, qa = _grid(0.0, 0.15, 6, 4, 0.2, 0)
    b, qb = _grid(0.15, 0.3, 6, 4, 0.2, len(a))
    model, warned = _build(_mesh_structure(tmp_path, a + b, np.vstack([qa, qb])))
    assert len(warned) == 1 and "5 pair(s) of coincident nodes" in warned[0]
    # node labels 1-based in file order: the crack line is x = 0.15 of both grids
    assert "31/36 at [0.15, 0.0, 0.0]" in warned[0] and "35/40 at [0.15, 0.2, 0.0]" in warned[0]
    # the same mesh without the crack: no word
    c, qc = _grid(0.0, 0.3, 12, 4, 0.2, 0)
    assert _build(_mesh_structure(tmp_path, c, qc))[1] == []


def test_duplicated_element_is_refused_by_name(tmp_path):
    c, qc = _grid(0.0, 0.3, 12, 4, 0.2, 0)
    with pytest.raises(ConfigError, match=r"1 duplicated mitc4 element\(s\), e.g. elements "
                                          r"4, 49 on nodes"):
        build_model(_mesh_structure(tmp_path, c, np.vstack([qc, qc[3:4]])))


def test_point_far_off_the_mesh_is_refused(tmp_path):
    c, qc = _grid(0.0, 0.3, 12, 4, 0.2, 0)
    ok = _mesh_structure(tmp_path, c, qc, '[[points]]\nname = "tip"\nx = 0.3\ny = 0.1\nz = 0\n')
    assert "tip" in build_model(ok).node_sets
    far = _mesh_structure(tmp_path, c, qc, '[[points]]\nname = "tip"\nx = 14.3\ny = 0.1\n'
                                           'z = 0\n')
    with pytest.raises(ConfigError, match=r"points\[0\] \('tip'\): \[14.3, 0.1, 0.0\] m is "
                                          r"14 m from the nearest node 63 at \[0.3, 0.1, 0.0\]"
                                          r".* off the structure"):
        build_model(far)


def test_complex_or_indefinite_matrices_are_refused(tmp_path):
    K = sp.csr_matrix(np.array([[2.0, -1.0], [-1.0, 2.0]]) * 1e4)
    table = np.array([[1, 3], [2, 3]])
    with pytest.raises(ParameterError, match=r"K is complex \(max \|imag\| 400\)"):
        read_matrices(K * (1 + 0.02j), sp.eye(2), table)
    with pytest.raises(ParameterError, match=r"M has 2 negative diagonal term\(s\)"):
        read_matrices(K, -sp.eye(2), table)
    import scipy.io

    scipy.io.mmwrite(tmp_path / "K.mtx", K * (1 + 0.02j))
    with pytest.raises(FormatError, match=r"K.mtx: K is complex"):
        read_matrices(tmp_path / "K.mtx", sp.eye(2), table)


def test_huge_beam_and_mesh_are_refused_before_allocation(tmp_path):
    with pytest.raises(ParameterError, match=r"mesh.n_elements: the model would have "
                                             r"1000000001 nodes .* exceeds the limit"):
        check_size(10**9 + 1, 10**9, "mesh.n_elements", beam=True)
    beam = (ROOT / "data" / "structures" / "smart_beam_beam.toml").read_text()
    import re

    text, n = re.subn(r"(?m)^(n_elements|nx|element_size)\s*=.*$", "n_elements = 2000000000",
                      beam)
    assert n == 1, "the beam example sets its mesh with one key"
    (tmp_path / "b.toml").write_text(text)
    with pytest.raises(ParameterError, match=r"estimated assembly memory .* GB exceeds"):
        build_model(tmp_path / "b.toml")


def test_modes_too_fine_for_the_mesh_are_named_and_are_the_inaccurate_ones(tmp_path):
    """External truth: the same Leissa plate on a 72 x 72 mesh. Of the first 30 modes on
    the 24 x 24 mesh, the ones warned about are those more than 4 % off."""
    coarse_model = build_model(ROOT / "data" / "structures" / "plate.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        coarse = modal_analysis(coarse_model, 30).fn_hz
    msgs = [str(w.message) for w in caught if issubclass(w.category, ModelWarning)]
    assert len(msgs) == 1 and "fewer elements per half-wave" in msgs[0]
    named = [int(m.split(" (")[0]) for m in
             msgs[0].split("mode(s) ")[1].split(" have")[0].split(", ")]
    fine = modal_analysis(build_model(_plate(tmp_path, ("nx = 24", "nx = 72"),
                                             ("ny = 24", "ny = 72"))), 30).fn_hz
    err = np.abs(coarse / fine - 1)
    assert named == [int(k) + 1 for k in np.flatnonzero(err > 0.04)], (named, err)
    assert named == [29, 30]


def test_rigid_labels_of_a_cracked_free_plate_do_not_depend_on_n(tmp_path):
    """Two free pieces: 12 zero-energy modes, each labelled rigid at -n 6 as at -n 14."""
    a, qa = _grid(0.0, 0.15, 6, 4, 0.2, 0)
    b, qb = _grid(0.15, 0.3, 6, 4, 0.2, len(a))
    model, _ = _build(_mesh_structure(tmp_path, a + b, np.vstack([qa, qb]), clamped=False))
    six = modal_analysis(model, 6)
    fourteen = modal_analysis(model, 14)
    assert list(six.mode_type) == ["rigid"] * 6
    assert list(fourteen.mode_type[:12]) == ["rigid"] * 12
    assert "rigid" not in fourteen.mode_type[12:] and fourteen.fn_hz[12] > 1.0
