"""Coordinate systems, node frames and load cases in structure descriptions.

External truths: the clamped plate under pressure of Timoshenko & Woinowsky-Krieger
(0.00126 q a^4 / D, table 35) and the ring on radial springs (closed form in
tests/fe/test_nastran.py), here written as structure TOML files over imported meshes;
the same model written as a Nastran deck and through the Python API gives the same
numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

from mvtk.errors import ConfigError
from mvtk.fe import (
    build_model,
    load_vector,
    modal_analysis,
    read_nastran,
    rectangular_plate_mesh,
    static_solve,
)

meshio = pytest.importorskip("meshio")


def _plate(tmp_path, nx=24):
    m = rectangular_plate_mesh(1.0, 1.0, nx=nx, ny=nx)
    edge = np.unique(np.concatenate([m.node_sets[k] for k in ("x0", "x1", "y0", "y1")]))
    meshio.Mesh(m.nodes, [("quad", m.elements)],
                cell_sets={"SKIN": [np.arange(len(m.elements))]},
                point_sets={"EDGE": edge, "X1": m.node_sets["x1"]}).write(tmp_path / "p.inp")
    return m


def _plate_desc(tmp_path, loads):
    return {"materials": {"steel": {"E": 210e9, "nu": 0.3, "rho": 7850.0}},
            "structure": {"type": "mesh"},
            "mesh": {"file": str(tmp_path / "p.inp"), "sections": {"SKIN": "skin"}},
            "sections": {"skin": {"layers": [{"material": "steel", "thickness": 0.01}]}},
            "boundary": {"supports": {"EDGE": "clamped"}},
            "points": [{"name": "centre", "x": 0.5, "y": 0.5, "z": 0.0}],
            "loads": loads}


def test_pressure_gravity_force_and_line_loads_from_the_structure_file(tmp_path):
    _plate(tmp_path)
    q = 1e3
    model = build_model(_plate_desc(tmp_path, [
        {"type": "pressure", "pressure": -q},
        {"case": "weight", "type": "gravity", "acceleration": [0.0, 0.0, -9.81]},
        {"case": "point", "type": "force", "node_set": "centre", "force": [0, 0, -100.0]},
        {"case": "edge", "type": "line", "node_set": "X1", "force": [0, 0, -50.0]},
        {"case": "edge", "type": "force", "node_set": "centre", "moment": [1.0, 0, 0]},
    ]))
    cases = model.meta["load_cases"]
    assert sorted(cases) == ["edge", "load", "point", "weight"]
    D = 210e9 * 0.01**3 / (12 * (1 - 0.3**2))
    u = static_solve(model, load_vector(model))
    c = model.node_sets["centre"][0]
    w = -u[model.dof_index(c, "uz")]
    assert w == pytest.approx(0.00126 * q / D, rel=1e-2)  # TWK table 35
    # self weight is a pressure rho h g: the same deflection per Pa
    uw = static_solve(model, load_vector(model, "weight"))
    assert -uw[model.dof_index(c, "uz")] == pytest.approx(w * 7850 * 0.01 * 9.81 / q,
                                                          rel=1e-12)
    # load totals: the line load over the 1 m edge, the point force
    np.testing.assert_allclose(cases["edge"][:, 2].sum(), -50.0, rtol=1e-12)
    np.testing.assert_allclose(cases["edge"][c, 3], 1.0)
    np.testing.assert_allclose(cases["point"][:, 2].sum(), -100.0)
    with pytest.raises(ConfigError, match="no load case 'wind'"):
        load_vector(model, "wind")


def test_bad_loads_and_systems(tmp_path):
    _plate(tmp_path, nx=2)
    bad = [
        ([{"type": "snow"}], r"loads\[0\].type: expected one of gravity"),
        ([{"type": "force", "node_set": "nope", "force": [0, 0, 1]}],
         r"loads\[0\].node_set: 'nope' not found"),
        ([{"type": "pressure", "pressure": 1.0, "element_set": "wing"}],
         r"loads\[0\]: no shell set 'wing'"),
        ([{"type": "gravity", "acceleration": [0, 0]}], r"loads\[0\].acceleration: expected"),
        ([{"type": "force", "node_set": "centre", "force": [0, 0, 1], "system": "cyl"}],
         r"loads\[0\].system: 'cyl' is not defined"),
    ]
    for loads, msg in bad:
        with pytest.raises(ConfigError, match=msg):
            build_model(_plate_desc(tmp_path, loads))
    d = _plate_desc(tmp_path, [])
    d["coordinate_systems"] = {"c": {"type": "conical"}}
    with pytest.raises(ConfigError, match="coordinate_systems.c"):
        build_model(d)
    d["coordinate_systems"] = {"c": {"type": "cylindrical"}}
    d["boundary"]["frames"] = {"EDGE": "k"}
    with pytest.raises(ConfigError, match="boundary.frames.EDGE: coordinate system 'k'"):
        build_model(d)
    d = {"materials": {}, "structure": {"type": "plate"}, "loads": []}
    with pytest.raises(ConfigError, match="loads: not applicable"):
        build_model(d)


def test_ring_with_radial_springs_in_a_cylindrical_frame_toml_equals_deck(tmp_path):
    """The ring of tests/fe/test_nastran.py written as a line mesh + structure TOML
    (cylindrical system, boundary.frames, radial springs, out-of-plane supports in the
    frame) gives the deck's frequencies."""
    from test_nastran import RING, _ring_deck  # tests/fe is on sys.path

    deck = read_nastran(_ring_deck(tmp_path))
    R, N, b, E, rho, kf = RING
    k = kf * 2 * np.pi * R / N
    nodes = np.array(deck.nodes)
    els = np.column_stack([np.arange(N), (np.arange(N) + 1) % N])
    meshio.Mesh(nodes, [("line", els)], cell_sets={"RING": [np.arange(N)]},
                point_sets={"ALL": np.arange(N)}).write(tmp_path / "ring.inp")
    # the section's local y axis: the orientation vector must be the cylinder axis
    desc = {"materials": {"st": {"E": E, "nu": 0.3, "rho": rho}},
            "structure": {"type": "mesh"},
            "mesh": {"file": str(tmp_path / "ring.inp"), "sections": {"RING": "bar"}},
            "sections": {"bar": {"shape": "rectangle", "material": "st", "width": b,
                                 "height": b, "orientation": [0.0, 0.0, 1.0]}},
            "coordinate_systems": {"cyl": {"type": "cylindrical", "origin": [1.0, 2.0, 3.0],
                                           "z_axis": [0, 0, 1], "x_axis": [1, 0, 0]}},
            "boundary": {"frames": {"ALL": "cyl"}, "supports": {"ALL": ["uz", "rx", "ry"]},
                         "springs": [{"node_set": "ALL", "dof": "ux", "k": k}]}}
    model = build_model(desc)
    np.testing.assert_allclose(modal_analysis(model, 7, sigma=-1.0).fn_hz[1:],
                               modal_analysis(deck, 7, sigma=-1.0).fn_hz[1:], rtol=1e-9)
