"""Test geometry readers (UFF 15/2411/18/82/2412, TOML, CSV) and sensor directions."""

from __future__ import annotations

import numpy as np
import pytest

from mvtk.correlation import (
    CoordinateSystem,
    Sensor,
    TestGeometry,
    direction_label,
    read_test_geometry,
)
from mvtk.errors import ConfigError, FormatError, ParameterError, UnsupportedFormatError

pyuff = pytest.importorskip("pyuff")


def _write_uff(path):
    u = pyuff.UFF(str(path))
    # cs 1: origin (1, 0, 0), local x along global y, local z along global z
    u.write_sets(pyuff.prepare_18(
        cs_num=[1, 2], cs_type=[0, 0], ref_cs_num=[0, 1], cs_name=["rot", "chained"],
        ref_o=np.array([[1.0, 0, 0], [0.0, 0, 0]]),
        x_point=np.array([[1.0, 1, 0], [1.0, 0, 0]]),
        xz_point=np.array([[1.0, 1, 1], [1.0, 0, 1]])), "add")
    u.write_sets(pyuff.prepare_15(
        node_nums=[1, 2, 3], def_cs=[0, 0, 1], disp_cs=[0, 1, 2], color=[1, 1, 1],
        x=[0.0, 1.0, 2.0], y=[0.0, 0.0, 0.0], z=[0.0, 0.0, 0.5]), "add")
    u.write_sets(pyuff.prepare_2411(
        node_nums=[4, 5], def_cs=[0, 0], disp_cs=[0, 0], color=[1, 1],
        x=[0.0, 1.0], y=[1.0, 1.0], z=[0.0, 0.0]), "add")
    u.write_sets(pyuff.prepare_82(trace_num=1, n_nodes=3, color=1, id="edge",
                                  nodes=np.array([1, 2, 3])), "add")
    with open(path, "a") as fh:  # a 2412 quad (fe_descriptor 94), written by hand
        fh.write("    -1\n  2412\n         1        94         1         1         1         4\n"
                 "         1         2         5         4\n    -1\n")


def test_uff_geometry_resolves_local_systems(tmp_path):
    p = tmp_path / "geo.uff"
    _write_uff(p)
    g = read_test_geometry(p)
    assert g.node.tolist() == [1, 2, 3, 4, 5]
    # node 3 is defined in cs 1: local (2, 0, 0.5) -> global (1, 2, 0.5)
    np.testing.assert_allclose(g.xyz[2], [1.0, 2.0, 0.5], atol=1e-12)
    R1 = g.coordinate_systems[1].rotation
    np.testing.assert_allclose(R1[:, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(R1[:, 2], [0, 0, 1], atol=1e-12)
    # cs 2 is defined in cs 1 with identity axes: same rotation as cs 1
    np.testing.assert_allclose(g.coordinate_systems[2].rotation, R1, atol=1e-12)
    g = g.with_sensors([(2, "+x"), (2, "-z"), (1, 3)])
    v = g.sensor_vectors()
    np.testing.assert_allclose(v[0], [0, 1, 0], atol=1e-12)  # local +x = global +y
    np.testing.assert_allclose(v[1], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(v[2], [0, 0, 1], atol=1e-12)  # UFF code 3 = +z
    assert g.dof_labels == ["2+x", "2-z", "1+z"]
    assert len(g.lines) == 2 and g.lines[1].tolist() == [1, 2, 5, 4, 1]
    assert g.edges().shape == (6, 2)


def test_toml_round_trip_with_skewed_and_triaxial(tmp_path):
    R = CoordinateSystem(7, np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]), [0, 0, 0], "r90")
    g = TestGeometry([10, 20], [[0, 0, 0], [0.1, 0, 0]], [0, 7], {7: R}, ([10, 20],),
                     (Sensor(10, "+z"), Sensor(20, "+x"),
                      Sensor(20, "s1", (0.0, 0.6, 0.8))))
    text = g.to_toml(tmp_path / "g.toml")
    assert "[[sensors]]" in text
    h = read_test_geometry(tmp_path / "g.toml")
    np.testing.assert_allclose(h.sensor_vectors(), g.sensor_vectors(), atol=1e-12)
    # +x of node 20 in the system rotated 90 deg about z reads global +y
    np.testing.assert_allclose(h.sensor_vectors()[1], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(h.sensor_vectors()[2], [-0.6, 0, 0.8], atol=1e-12)
    tri = read_test_geometry({"nodes": [{"node": 1, "x": 0, "y": 0, "z": 0}],
                              "sensors": [{"node": 1, "triaxial": True}]})
    assert tri.dof_labels == ["1+x", "1+y", "1+z"]


def test_csv_table(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("node,x,y,z,directions\n1,0,0,0,+z\n2,10,0,0,+x +y +z\n")
    g = read_test_geometry(p, units_scale=1e-3)
    np.testing.assert_allclose(g.xyz[1], [0.01, 0, 0])
    assert g.dof_labels == ["1+z", "2+x", "2+y", "2+z"]
    assert g.nodes_table().shape == (2, 5)


def test_direction_labels():
    assert direction_label(-5) == "-ry"
    assert direction_label("z") == "+z"
    with pytest.raises(ParameterError, match="expected 1..6"):
        direction_label(9)


@pytest.mark.parametrize("content, match", [
    ("node,x,y\n1,0,0\n", "header must have columns node, x, y, z"),
    ("node,x,y,z\n1,0,abc,0\n", r"line 2: expected an integer node"),
    ("node,x,y,z,directions\n1,0,0,0,+q\n", r"line 2: unknown direction '\+q'"),
    ("node,x,y,z\n1,0,0,0\n1,1,0,0\n", r"duplicated node labels \[1\]"),
    ("node,x,y,z,cs\n1,0,0,0,4\n", r"undefined coordinate systems \[4\]"),
])
def test_csv_errors(tmp_path, content, match):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    with pytest.raises(FormatError, match=match) as err:
        read_test_geometry(p)
    assert "bad.csv" in str(err.value)


def test_bad_inputs(tmp_path):
    with pytest.raises(UnsupportedFormatError, match="expected .uff, .unv, .toml or .csv"):
        (tmp_path / "g.xyz").write_text("x")
        read_test_geometry(tmp_path / "g.xyz")
    with pytest.raises(FormatError, match="not found"):
        read_test_geometry(tmp_path / "none.toml")
    with pytest.raises(ConfigError, match=r"nodes\[0\]: expected keys node, x, y, z"):
        read_test_geometry({"nodes": [{"node": 1, "x": 0}]})
    with pytest.raises(ConfigError, match=r"sensors\[0\]: a skewed sensor needs a name"):
        read_test_geometry({"nodes": [{"node": 1, "x": 0, "y": 0, "z": 0}],
                            "sensors": [{"node": 1, "direction": "+z", "vector": [0, 0, 1]}]})
    with pytest.raises(ParameterError, match="not a proper orthonormal"):
        CoordinateSystem(1, np.diag([1.0, 1.0, 2.0]))
    with pytest.raises(ParameterError, match="collinear"):
        CoordinateSystem.from_points(3, [0, 0, 0], [1, 0, 0], [2, 0, 0])
    with pytest.raises(ParameterError, match="sensor 9\\+z: node 9 is not a test node"):
        TestGeometry([1], [[0, 0, 0]], sensors=(Sensor(9, "+z"),))
    p = tmp_path / "nonodes.uff"
    u = pyuff.UFF(str(p))
    u.write_sets(pyuff.prepare_82(trace_num=1, n_nodes=2, color=1, id="x",
                                  nodes=np.array([1, 2])), "add")
    with pytest.raises(FormatError, match=r"no node dataset \(15 or 2411\)"):
        read_test_geometry(p)


def test_csv_comment_lines_are_skipped_and_lines_keep_their_numbers(tmp_path):
    p = tmp_path / "geo.csv"
    p.write_text("# test geometry of a plate (m)\nnode,x,y,z\n1,0,0,0\n# a note\n2,0.1,0,0\n"
                 "3,abc,0,0\n", encoding="utf-8")
    with pytest.raises(FormatError, match="line 6") as err:
        read_test_geometry(p)
    assert "geo.csv" in str(err.value)
    p.write_text("# test geometry\nnode,x,y,z\n1,0,0,0\n# a note\n2,0.1,0,0\n",
                 encoding="utf-8")
    g = read_test_geometry(p)
    assert list(g.node) == [1, 2]


def _write_curvilinear_uff(path, scale=1.0):
    """Cylindrical cs 1 (dataset 18), Cartesian cs 3 defined in cs 1's cylindrical
    coordinates (18) and spherical cs 2 (2420); lengths multiplied by ``1/scale``."""
    s = 1.0 / scale
    u = pyuff.UFF(str(path))
    # cs 1: origin (1, 2, 0), cylinder x axis along global +y, axis along global +z
    u.write_sets(pyuff.prepare_18(
        cs_num=[1, 3], cs_type=[1, 0], ref_cs_num=[0, 1], cs_name=["cyl", "in cyl"],
        ref_o=np.array([[1.0, 2, 0], [0.0, 0, 0]]) * s,
        x_point=np.array([[1.0 * s, 3 * s, 0], [1.0 * s, 90, 0]]),
        xz_point=np.array([[1.0 * s, 3 * s, 1 * s], [1.0 * s, 90, 1 * s]])), "add")
    # cs 2 (2420): rows = local axes in global (x = +y, y = -x, z = +z), then the origin
    T = np.array([[0.0, 1, 0], [-1.0, 0, 0], [0.0, 0, 1], [0.0, 0, 1 * s]])
    u.write_sets(pyuff.prepare_2420(Part_UID=1, Part_Name="part", CS_sys_labels=[2],
                                    CS_types=[2], CS_colors=[1], CS_names=["sph"],
                                    CS_matrices=[T]), "add")
    u.write_sets(pyuff.prepare_2411(
        node_nums=[10, 20, 30], def_cs=[1, 2, 3], disp_cs=[1, 2, 3], color=[1, 1, 1],
        x=[2.0 * s, 1.0 * s, 0.5 * s], y=[90.0, 90.0, 0.0], z=[0.5 * s, 90.0, 0.0]), "add")


@pytest.mark.parametrize("scale", [1.0, 1e-3])
def test_uff_cylindrical_and_spherical_systems(tmp_path, scale):
    """Known global positions and directions of nodes defined in cylindrical (UFF 18)
    and spherical (UFF 2420) systems, the file written by pyuff (in mm for 1e-3)."""
    p = tmp_path / "curv.uff"
    _write_curvilinear_uff(p, scale)
    g = read_test_geometry(p, units_scale=scale)
    assert [g.coordinate_systems[k].kind for k in (1, 2, 3)] == ["cylindrical", "spherical",
                                                                 "cartesian"]
    # node 10: (r, theta, z) = (2, 90 deg, 0.5) in cs 1 -> 2 along local y = global -x
    np.testing.assert_allclose(g.xyz[0], [-1.0, 2.0, 0.5], atol=1e-9)
    # node 20: (r, theta, phi) = (1, 90, 90) in cs 2 -> local +y = global -x, + origin
    np.testing.assert_allclose(g.xyz[1], [-1.0, 0.0, 1.0], atol=1e-9)
    # cs 3: origin at cs 1's origin, +x point at (r, theta) = (1, 90 deg) = global -x
    np.testing.assert_allclose(g.coordinate_systems[3].rotation,
                               [[-1, 0, 0], [0, -1, 0], [0, 0, 1]], atol=1e-9)
    np.testing.assert_allclose(g.xyz[2], [0.5, 2.0, 0.0], atol=1e-9)
    g = g.with_sensors([(10, "+x"), (10, "+y"), (10, "+z"), (20, "+x"), (20, "+y"),
                        (20, "-z"), (30, "+x")])
    v = g.sensor_vectors()
    # cylindrical at node 10: radial = global -x, tangential = global -y, axial = +z
    np.testing.assert_allclose(v[:3], [[-1, 0, 0], [0, -1, 0], [0, 0, 1]], atol=1e-9)
    # spherical at node 20 (on the local equator, azimuth 90 deg): e_r = global -x,
    # e_theta = -z (polar angle grows downwards), -e_phi = -(local -x) = global +y
    np.testing.assert_allclose(v[3:6], [[-1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-9)
    np.testing.assert_allclose(v[6], [-1, 0, 0], atol=1e-9)
    # a TOML round trip keeps the kinds and so the directions
    back = read_test_geometry(g.to_toml(tmp_path / "curv.toml") and tmp_path / "curv.toml")
    np.testing.assert_allclose(back.sensor_vectors(), v, atol=1e-12)


@pytest.mark.parametrize("kind", ["cylindrical", "spherical"])
def test_curvilinear_directions_are_the_coordinate_tangents(kind, rng):
    """Direction k at a point is the unit tangent of coordinate k there (finite
    differences of the coordinate map), for an arbitrary rotated, offset system."""
    from scipy.spatial.transform import Rotation

    R = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    cs = CoordinateSystem(5, R, rng.normal(size=3), kind=kind)
    for _ in range(5):
        c = np.array([rng.uniform(0.5, 2), rng.uniform(20, 160), rng.uniform(-170, 170)])
        p = cs.to_global(c)
        axes = cs.axes_at(p)
        np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
        assert np.linalg.det(axes) == pytest.approx(1.0)
        for k in range(3):
            h = np.zeros(3)
            h[k] = 1e-6
            d = (cs.to_global(c + h) - cs.to_global(c - h)) / 2e-6
            np.testing.assert_allclose(axes[:, k], d / np.linalg.norm(d), atol=1e-7)


def test_bad_coordinate_system_kinds(tmp_path):
    with pytest.raises(ParameterError, match="unknown kind 'polar'"):
        CoordinateSystem(1, np.eye(3), kind="polar")
    with pytest.raises(ConfigError, match=r"coordinate_systems\[0\].type: expected one of"):
        read_test_geometry({"coordinate_systems": [{"id": 1, "type": "conical",
                                                    "axes": np.eye(3).tolist()}],
                            "nodes": [{"node": 1, "x": 0, "y": 0, "z": 0}]})
    p = tmp_path / "bad.uff"
    u = pyuff.UFF(str(p))
    u.write_sets(pyuff.prepare_2420(Part_UID=1, Part_Name="part", CS_sys_labels=[4],
                                    CS_types=[1], CS_colors=[1], CS_names=["skew"],
                                    CS_matrices=[np.array([[1.0, 0, 0], [1.0, 1, 0],
                                                           [0, 0, 1], [0, 0, 0]])]), "add")
    u.write_sets(pyuff.prepare_2411(node_nums=[1], def_cs=[4], disp_cs=[4], color=[1],
                                    x=[1.0], y=[0.0], z=[0.0]), "add")
    with pytest.raises(FormatError, match=r"bad.uff, record 1 \(dataset 2420\): coordinate "
                                          r"system 4: rotation is not a proper"):
        read_test_geometry(p)
    p3 = tmp_path / "conical.uff"
    u = pyuff.UFF(str(p3))
    u.write_sets(pyuff.prepare_18(cs_num=[6], cs_type=[3], ref_cs_num=[0], cs_name=["c"],
                                  ref_o=np.zeros((1, 3)), x_point=np.array([[1.0, 0, 0]]),
                                  xz_point=np.array([[1.0, 0, 1]])), "add")
    u.write_sets(pyuff.prepare_2411(node_nums=[1], def_cs=[0], disp_cs=[6], color=[1],
                                    x=[1.0], y=[0.0], z=[0.0]), "add")
    with pytest.raises(FormatError, match=r"conical.uff, record 1 \(dataset 18\): coordinate "
                                          r"system 6 has type 3; expected 0 \(Cartesian\), 1"):
        read_test_geometry(p3)
    p2 = tmp_path / "twice.uff"
    u = pyuff.UFF(str(p2))
    for _ in range(2):
        u.write_sets(pyuff.prepare_2420(Part_UID=1, Part_Name="part", CS_sys_labels=[4],
                                        CS_types=[0], CS_colors=[1], CS_names=["a"],
                                        CS_matrices=[np.vstack([np.eye(3), np.zeros(3)])]),
                     "add")
    u.write_sets(pyuff.prepare_2411(node_nums=[1], def_cs=[0], disp_cs=[4], color=[1],
                                    x=[1.0], y=[0.0], z=[0.0]), "add")
    with pytest.raises(FormatError, match=r"record 2 \(dataset 2420\): coordinate system 4 "
                                          "is defined more than once"):
        read_test_geometry(p2)


def test_csv_without_directions_defaults_to_global_z(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("node,x,y,z\n1,0,0,0\n2,0.1,0,0\n")
    g = read_test_geometry(p)
    assert g.dof_labels == ["1+z", "2+z"]
    assert {s.source for s in g.sensors} == {"default +z"}
    np.testing.assert_allclose(g.sensor_vectors(), [[0, 0, 1], [0, 0, 1]])
    # with the column, its cells are used as given (an empty cell: no sensor)
    p.write_text("node,x,y,z,directions\n1,0,0,0,+x\n2,0.1,0,0,\n")
    g = read_test_geometry(p)
    assert g.dof_labels == ["1+x"] and g.sensors[0].source == "file"
