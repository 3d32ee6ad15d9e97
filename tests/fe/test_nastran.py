"""Nastran bulk-data subset (mvtk.fe.read_nastran) against equivalent built-in models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from mvtk.errors import FormatError
from mvtk.fe import (
    BeamSet,
    IsotropicMaterial,
    Ply,
    PointMass,
    assemble_model,
    modal_analysis,
    plate_model,
    read_bulk_cards,
    read_nastran,
    rectangle_section,
    rectangular_plate_mesh,
)

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def _small(*fields) -> str:
    """One small-field line."""
    return "".join(f"{str(f):<8}"[:8] for f in fields).rstrip() + "\n"


def _plate_deck(fmt="small", cord=False) -> str:
    m = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    out = ["SOL 103\nCEND\nBEGIN BULK\n$ a comment\n"]
    if cord:  # a rotated, shifted rectangular system for every grid
        out.append(_small("CORD2R", 5, 0, 1.0, 2.0, 3.0, 1.0, 2.6, 3.8, "+C1"))
        out.append(_small("+C1", 1.6, 2.0, 3.0))
    for i, (x, y, z) in enumerate(m.nodes, start=1):
        cp = 5 if cord else ""
        if fmt == "free":
            out.append(f"GRID,{i},{cp},{x:.17g},{y:.17g},{z:.17g}\n")
        elif fmt == "large":
            out.append(f"{'GRID*':<8}{i:<16}{cp!s:<16}{x:<16.9e}{y:<16.9e}*G{i}\n")
            out.append(f"{'*G' + str(i):<8}{z:<16.9e}\n")
        else:
            out.append(_small("GRID", i, cp, f"{x:.5f}", f"{y:.5f}", f"{z:.5f}"))
    for e, q in enumerate(m.elements, start=1):
        out.append(_small("CQUAD4", e, 1, *(q + 1)))
    out.append(_small("PSHELL", 1, 7, "1.-3", 7))
    out.append("MAT1,7,2.1+11,,0.3,7850.\n")
    out.append(_small("SPC1", 1, 123456, *(m.node_sets["x0"] + 1)))
    out.append("ENDDATA\n")
    return "".join(out)


@pytest.mark.parametrize("fmt", ["small", "free", "large"])
def test_cquad4_plate_deck_matches_builtin_plate(tmp_path, fmt):
    path = tmp_path / "plate.bdf"
    path.write_text(_plate_deck(fmt))
    model = read_nastran(path)
    ref = plate_model(0.3, 0.2, [Ply(STEEL, 1e-3)], nx=6, ny=4, clamp="x0")
    np.testing.assert_allclose(modal_analysis(model, 5).fn_hz, modal_analysis(ref, 5).fn_hz,
                               rtol=1e-7)
    assert model.node_ids[0] == 1


def test_cord2r_grids_give_the_same_frequencies(tmp_path):
    (tmp_path / "a.bdf").write_text(_plate_deck())
    (tmp_path / "b.bdf").write_text(_plate_deck(cord=True))
    a, b = read_nastran(tmp_path / "a.bdf"), read_nastran(tmp_path / "b.bdf")
    assert not np.allclose(a.nodes, b.nodes)
    np.testing.assert_allclose(modal_analysis(b, 5).fn_hz, modal_analysis(a, 5).fn_hz,
                               rtol=1e-8)


def test_cbar_conm2_celas_rbe2_deck(tmp_path):
    mat = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    n = 10
    lines = ["BEGIN BULK\n"]
    for i in range(n + 1):
        lines.append(_small("GRID", i + 1, "", f"{0.1 * i:.3f}", "0.", "0."))
    for i in range(n):
        lines.append(_small("CBAR", i + 1, 2, i + 1, i + 2, "0.", "1.", "0."))
    lines.append(_small("PBARL", 2, 7, "", "BAR", "+P"))
    lines.append(_small("+P", "0.02", "0.01"))
    lines.append(_small("MAT1", 7, "2.1+11", "", "0.3", "7850."))
    lines.append(_small("SPC1", 1, 123456, 1))
    lines.append("ENDDATA\n")
    path = tmp_path / "beam.bdf"
    path.write_text("".join(lines))
    model = read_nastran(path)
    nodes = np.column_stack([0.1 * np.arange(n + 1), np.zeros((n + 1, 2))])
    els = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    ref = assemble_model(nodes, [BeamSet(els, rectangle_section(mat, 0.02, 0.01),
                                         orientation=(0, 1, 0))],
                         supports={"c": "clamped"}, node_sets={"c": [0]})
    np.testing.assert_allclose(modal_analysis(model, 6).fn_hz, modal_analysis(ref, 6).fn_hz,
                               rtol=1e-10)
    # a mass on a spring, tied by an RBE2 to a second grid: sqrt(k/m)
    deck = ("BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,0.5,0.,0.\n"
            "CONM2,10,2,,2.0,,,,,+,0.1,0.,0.1,0.,0.,0.1\nCELAS2,20,8.0+3,1,3\nCELAS2,21,1.0+9,1,1\n"
            "CELAS2,22,1.0+9,1,2\nCELAS2,23,1.0+9,1,4\nCELAS2,24,1.0+9,1,5\n"
            "CELAS2,25,1.0+9,1,6\nRBE2,30,1,123456,2\nENDDATA\n")
    (tmp_path / "m.bdf").write_text(deck)
    m2 = read_nastran(tmp_path / "m.bdf")
    assert m2.n_dof == 6
    f = modal_analysis(m2, 5).fn_hz[0]  # 5 of 6 DOFs: dense path
    # the rotational springs (1e9) are not rigid: k r^2 / k_rot = 2e-6
    assert f == pytest.approx(np.sqrt(8e3 / 2.0) / (2 * np.pi), rel=1e-5)


def test_bad_decks(tmp_path):
    p = tmp_path / "x.bdf"
    p.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nCHEXA,1,1,1,2,3,4,5,6\nCHEXA,2\n")
    with pytest.raises(FormatError, match=r"unsupported bulk-data cards \{'CHEXA': 2\}"):
        read_nastran(p)
    p.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.,3\n")
    with pytest.raises(FormatError, match=r"x.bdf line 2: coordinate system 3 is not "):
        read_nastran(p)
    p.write_text("BEGIN BULK\nGRID    1               0.      0.      0." + " " * 44
                 + "+       7\n")
    with pytest.raises(FormatError, match=r"line 2: characters beyond column 80"):
        read_nastran(p)
    p.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nGRDSET,,,,,,,3456\nPARAM,POST,-1\n")
    with pytest.raises(FormatError, match=r"unsupported bulk-data cards \{'GRDSET': 1\}"):
        read_nastran(p)
    p.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCBAR,1,9,1,2,0.,1.,0.\n")
    with pytest.raises(FormatError, match=r"line 4: CBAR 1: property 9 is not a PBAR"):
        read_nastran(p)
    p.write_text("BEGIN BULK\nGRID,1,,0.,abc,0.\n")
    with pytest.raises(FormatError, match=r"line 2: GRID field 5 .*expected a real number, "
                       r"got 'abc'"):
        read_nastran(p)
    with pytest.raises(FormatError, match="not found"):
        read_nastran(tmp_path / "missing.bdf")


def test_pcomp_ctria3_deck_and_structure_toml(tmp_path):
    from mvtk.fe import Laminate, OrthotropicMaterial, ShellSet, build_model

    m = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    tris = np.concatenate([m.elements[:, [0, 1, 2]], m.elements[:, [0, 2, 3]]])
    lines = ["BEGIN BULK\n"]
    lines += [f"GRID,{i},,{x:.17g},{y:.17g},{z:.17g}\n"
              for i, (x, y, z) in enumerate(m.nodes, start=1)]
    lines += [f"CTRIA3,{e},3,{a + 1},{b + 1},{c + 1}\n" for e, (a, b, c) in
              enumerate(tris, start=1)]
    lines.append("PCOMP,3,,,,,,,SYM,+\n,8,2.5-4,0.,,8,2.5-4,90.\n")
    lines.append("MAT8,8,1.4+11,1.0+10,0.3,5.0+9,5.0+9,3.5+9,1600.\n")
    lines.append("SPC1,1,123456," + ",".join(str(i + 1) for i in m.node_sets["x0"]) + "\n")
    (tmp_path / "c.bdf").write_text("".join(lines))
    deck = read_nastran(tmp_path / "c.bdf")
    cfrp = OrthotropicMaterial("cfrp", 140e9, 10e9, 5e9, 5e9, 3.5e9, 0.3, 1600.0)
    lam = Laminate(tuple(Ply(cfrp, 2.5e-4, a) for a in (0, 90, 90, 0)))
    # Nastran's material axis of a CTRIA3 is its G1-G2 edge: per element here
    axes = m.nodes[tris[:, 1]] - m.nodes[tris[:, 0]]
    ref = assemble_model(m.nodes, [ShellSet(tris, lam, material_axis=axes)],
                         supports={"x0": "clamped"}, node_sets=m.node_sets)
    np.testing.assert_allclose(modal_analysis(deck, 4).fn_hz, modal_analysis(ref, 4).fn_hz,
                               rtol=1e-9)
    toml = tmp_path / "c.toml"
    toml.write_text('[structure]\ntype = "mesh"\n[mesh]\nfile = "c.bdf"\n'
                    '[[points]]\nname = "tip"\nx = 0.3\ny = 0.1\nz = 0.0\n')
    model = build_model(toml)
    assert "tip" in model.node_sets
    np.testing.assert_allclose(modal_analysis(model, 2).fn_hz, modal_analysis(deck, 2).fn_hz,
                               rtol=1e-12)


def _line_of_grids(n: int) -> str:
    return "".join(f"GRID,{i + 1},,{0.1 * i:.17g},0.,0.\n" for i in range(n + 1))


def test_free_field_line_with_more_than_eight_data_fields_keeps_them(tmp_path):
    """SPC1 with 8 grids on one free-field line: the tenth field is a grid, not a marker
    (a reader that takes every field 10 for a marker drops it silently)."""
    p = tmp_path / "spc.bdf"
    p.write_text("BEGIN BULK\n" + _line_of_grids(9)
                 + "".join(f"CBAR,{i + 1},2,{i + 1},{i + 2},0.,1.,0.\n" for i in range(9))
                 + "PBAR,2,7,1.-4,1.-9,1.-9,2.-9\nMAT1,7,2.1+11,,0.3,7850.\n"
                 + "SPC1,1,123456,1,2,3,4,5,6,7,8\n")
    model = read_nastran(p)
    np.testing.assert_array_equal(model.node_ids[model.node_sets["spc:1"]], np.arange(1, 9))
    assert set(model.node_ids[model.dof_node]) == {9, 10}
    # a +-marker in field 10 is a marker: the fields after it continue the card
    p.write_text(p.read_text().replace("SPC1,1,123456,1,2,3,4,5,6,7,8",
                                       "SPC1,1,123456,1,2,3,4,5,6,+,7,8"))
    np.testing.assert_array_equal(read_nastran(p).node_sets["spc:1"], np.arange(8))


def test_short_free_field_line_is_padded_before_its_continuation(tmp_path):
    """PBARL and CONM2 with a short first free-field line: the continuation starts at
    field 2 of the next logical line (DIM1, I11), as the format defines."""
    mat = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    p = tmp_path / "b.bdf"
    p.write_text("BEGIN BULK\n" + _line_of_grids(10)
                 + "".join(f"CBAR,{i + 1},2,{i + 1},{i + 2},0.,1.,0.\n" for i in range(10))
                 + "PBARL,2,7,,BAR\n,0.02,0.01\nMAT1,7,2.1+11,,0.3,7850.\n"
                 + "CONM2,99,11,,2.0\n,0.1,0.,0.2,0.,0.,0.3\nSPC1,1,123456,1\n")
    model = read_nastran(p)
    nodes = np.column_stack([0.1 * np.arange(11), np.zeros((11, 2))])
    els = np.column_stack([np.arange(10), np.arange(1, 11)])
    ref = assemble_model(nodes, [BeamSet(els, rectangle_section(mat, 0.02, 0.01),
                                         orientation=(0, 1, 0)),
                                 PointMass(10, 2.0, (0.1, 0.2, 0.3))],
                         supports={"c": "clamped"}, node_sets={"c": [0]})
    np.testing.assert_allclose(model.M.toarray(), ref.M.toarray(), rtol=0, atol=1e-15)
    np.testing.assert_allclose(model.K.toarray(), ref.K.toarray(), rtol=1e-12)
    i = model.node_dofs(10, ["rx", "ry", "rz"])
    # the beam's own rotary inertia plus the CONM2 diagonal
    beam = ref.M.toarray()[np.ix_(i, i)] - np.diag([0.1, 0.2, 0.3])
    np.testing.assert_allclose(model.M.toarray()[np.ix_(i, i)] - beam,
                               np.diag([0.1, 0.2, 0.3]), atol=1e-15)


def test_small_large_and_free_field_forms_of_one_card_agree(tmp_path):
    """The same CONM2 (with products of inertia) in small field with explicit and
    implicit continuations, large field and free field."""
    forms = {
        "small": _small("CONM2", 5, 1, "", "3.0", "0.1", "0.", "0.", "", "+A")
        + _small("+A", "0.5", "0.01", "0.6", "0.02", "0.03", "0.7"),
        "implicit": _small("CONM2", 5, 1, "", "3.0", "0.1", "0.", "0.")
        + _small("", "0.5", "0.01", "0.6", "0.02", "0.03", "0.7"),
        "large": f"{'CONM2*':<8}{5:<16}{1:<16}{'':<16}{'3.0':<16}*X\n"
        f"{'*X':<8}{'0.1':<16}{'0.':<16}{'0.':<16}{'':<16}*Y\n"
        f"{'*Y':<8}{'0.5':<16}{'0.01':<16}{'0.6':<16}{'0.02':<16}\n"
        f"{'*':<8}{'0.03':<16}{'0.7':<16}\n",
        "free": "CONM2,5,1,,3.0,0.1,0.,0.,,+\n+,0.5,0.01,0.6,0.02,0.03,0.7\n",
        "free-long": "CONM2,5,1,,3.0,0.1,0.,0.,,,0.5,0.01,0.6,0.02,0.03,0.7\n",
    }
    for k, text in forms.items():
        p = tmp_path / f"{k}.bdf"
        p.write_text("BEGIN BULK\n" + text + "GRID,1,,0.,0.,0.\n")
        (c,) = [c for c in read_bulk_cards(p) if c.name == "CONM2"]
        vals = [c.int(0), c.int(1), c.real(3), c.real(4), c.real(5), c.real(6)] + [
            c.real(k) for k in range(8, 14)]
        assert vals == [5, 1, 3.0, 0.1, 0.0, 0.0, 0.5, 0.01, 0.6, 0.02, 0.03, 0.7], k
    # the products of inertia enter with Nastran's sign convention
    p = tmp_path / "m.bdf"
    p.write_text("BEGIN BULK\n" + forms["free"] + "GRID,1,,0.,0.,0.\n"
                 + "".join(f"CELAS2,{10 + j},1.+6,1,{j + 1}\n" for j in range(6)))
    M = read_nastran(p).M.toarray()
    J = np.array([[0.5, -0.01, -0.02], [-0.01, 0.6, -0.03], [-0.02, -0.03, 0.7]])
    e = np.array([0.1, 0.0, 0.0])
    X = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    np.testing.assert_allclose(M[3:, 3:], J + 3.0 * X.T @ X, atol=1e-14)


def _fv2_deck(R: np.ndarray, origin=(0.0, 0.0, 0.0)) -> str:
    """NAFEMS FV2 double cross written in a CORD2R rotated by R (rows = axes): grids in
    CP = CD = 5, the in-plane constraint (local 345) and the pins (local 12) in it."""
    o = np.asarray(origin)
    a, b, c = o, o + R[2], o + R[0]
    out = ["BEGIN BULK\n", "CORD2R,5,0," + ",".join(f"{v:.17g}" for v in (*a, *b))
           + ",+\n+," + ",".join(f"{v:.17g}" for v in c) + "\n"]
    L, gid, ends, els = 5.0, 1, [], []
    out.append("GRID,1,5,0.,0.,0.,5\n")
    for k in range(8):
        d = np.array([np.cos(k * np.pi / 4), np.sin(k * np.pi / 4), 0.0])
        prev = 1
        for s in range(1, 5):
            gid += 1
            x = d * L * s / 4
            out.append(f"GRID,{gid},5,{x[0]:.17g},{x[1]:.17g},{x[2]:.17g},5\n")
            els.append((prev, gid))
            prev = gid
        ends.append(gid)
    out += [f"CBAR,{e + 1},2,{p},{q},0.,0.,1.\n" for e, (p, q) in enumerate(els)]
    out.append("PBARL,2,7,,BAR\n,0.125,0.125\nMAT1,7,2.+11,,0.3,8000.\n")
    out.append(f"SPC1,1,345,1,THRU,{gid}\n")
    out.append("SPC1,1,12," + ",".join(map(str, ends)) + "\n")
    return "".join(out)


def test_fv2_double_cross_rotated_with_supports_in_the_rotated_system(tmp_path):
    """NAFEMS FV2 (TNSB rev. 3, 1990: f1 = 11.336, f2..f8 = 17.709, f9 = 45.345 Hz),
    rotated out of its plane and shifted: grids, orientation vectors and supports all in
    the rotated CORD2R (GRID CP and CD). The frequencies are those of the unrotated
    deck to 1e-8."""
    from scipy.spatial.transform import Rotation

    (tmp_path / "a.bdf").write_text(_fv2_deck(np.eye(3)))
    R = Rotation.from_euler("xyz", [35.0, -50.0, 20.0], degrees=True).as_matrix().T
    (tmp_path / "b.bdf").write_text(_fv2_deck(R, origin=(1.0, -2.0, 0.5)))
    a, b = read_nastran(tmp_path / "a.bdf"), read_nastran(tmp_path / "b.bdf")
    assert np.abs(b.nodes[:, 2]).max() > 1.0  # out of the xy plane
    fa, fb = modal_analysis(a, 9).fn_hz, modal_analysis(b, 9).fn_hz
    np.testing.assert_allclose(fb, fa, rtol=1e-8)
    assert fa[0] == pytest.approx(11.336, rel=2e-3)
    np.testing.assert_allclose(fa[1:8], 17.709, rtol=5e-3)
    assert fa[8] == pytest.approx(45.345, rel=5e-3)
    # CD rotated: the free DOFs of the model are the in-plane ones of the rotated system
    assert set(b.dof_component) == {0, 1, 5}


def test_cylindrical_and_spherical_grids_and_radial_cd(tmp_path):
    """GRID CP in CORD2C/CORD2S (positions) and CD = CORD2C: a radial spring (C1 = 1)
    at a grid on the y axis acts along global y."""
    deck = ("BEGIN BULK\nCORD2C,2,0,0.,0.,0.,0.,0.,1.,+\n+,1.,0.,0.\n"
            "CORD2S,3,0,0.,0.,1.,0.,0.,2.,+\n+,1.,0.,1.\n"
            "GRID,1,2,2.,90.,0.5,2\nGRID,2,3,1.,90.,90.\nGRID,3,,0.,0.,0.\n"
            "CONM2,10,1,,4.0\nCELAS2,11,100.,1,1\nCELAS2,12,1.+12,1,2\nCELAS2,13,1.+12,1,3\n"
            "CONM2,14,2,,1.0\nCELAS2,15,1.+12,2,1\nCELAS2,16,1.+12,2,2\nCELAS2,17,1.+12,2,3\n"
            "CONM2,18,3,,1.0\nCELAS2,19,1.+12,3,1\nCELAS2,20,1.+12,3,2\n"
            "CELAS2,21,1.+12,3,3\n")
    p = tmp_path / "c.bdf"
    p.write_text(deck)
    m = read_nastran(p)
    np.testing.assert_allclose(m.nodes, [[0, 2, 0.5], [0, 1, 1], [0, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(m.meta["node_frames"][0],
                               [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], atol=1e-15)
    w2 = scipy.linalg.eigh(m.K.toarray(), m.M.toarray(), eigvals_only=True)
    f = np.sqrt(w2[0]) / (2 * np.pi)
    assert f == pytest.approx(np.sqrt(100.0 / 4.0) / (2 * np.pi), rel=1e-12)


#: Ring of the radial-support tests: radius, CBARs, square side, E, rho, k_f (N/m/m).
RING = (0.5, 120, 0.01, 2.0e11, 7800.0, 2.0e4)


def _ring_deck(folder) -> Path:
    """The ring as a deck: CORD2C (shifted origin), GRID CP = CD = 7, CBARs, radial
    CELAS2 springs (C1 = 1), SPC1 345 (uz, r_r, r_theta) on every grid."""
    R, N, b, E, rho, kf = RING
    k = kf * 2 * np.pi * R / N
    lines = ["BEGIN BULK\n", "CORD2C,7,0,1.,2.,3.,1.,2.,4.,+\n+,2.,2.,3.\n"]
    lines += [f"GRID,{i + 1},7,{R},{360.0 * i / N:.17g},0.,7\n" for i in range(N)]
    lines += [f"CBAR,{i + 1},1,{i + 1},{(i + 1) % N + 1},0.,0.,1.\n" for i in range(N)]
    lines += [f"CELAS2,{1000 + i},{k:.17g},{i + 1},1\n" for i in range(N)]
    lines.append(f"PBARL,1,2,,BAR\n,{b},{b}\nMAT1,2,{E:.6g},,0.3,{rho}\n")
    lines.append(f"SPC1,1,345,1,THRU,{N}\n")
    p = Path(folder) / "ring.bdf"
    p.write_text("".join(lines))
    return p


def test_ring_on_radial_springs_in_a_cylindrical_system(tmp_path):
    """A thin ring of CBARs written in a CORD2C (GRID CP = CD = cylindrical), elastic
    radial supports CELAS2 C1 = 1 (radial) at every grid, out-of-plane motion fixed by
    SPC1 345 (uz, r_r, r_theta). Closed form (Rayleigh, inextensional modes of a ring on
    a radial foundation k_f per length; k_f = 0 is Hoppe's ring, Blevins 1979 table 9-2):
    omega_n^2 = (E I n^2 (n^2 - 1)^2 / R^4 + k_f n^2) / (rho A (n^2 + 1));
    n = 1 is the rigid translation on the springs, k_f / (2 rho A)."""
    R, N, b, E, rho, kf = RING
    A, I = b * b, b**4 / 12
    p = _ring_deck(tmp_path)
    model = read_nastran(p)
    f = modal_analysis(model, 7, sigma=-1.0).fn_hz

    def closed(n):
        w2 = (E * I * n**2 * (n**2 - 1) ** 2 / R**4 + kf * n**2) / (rho * A * (n**2 + 1))
        return np.sqrt(w2) / (2 * np.pi)

    assert f[0] < 1e-3  # rigid rotation about the ring axis: radial springs leave it free
    # n = 1 exact up to the extensional coupling, O(k_f R^2 / (E A)) = 2.5e-4
    np.testing.assert_allclose(f[1:3], closed(1), rtol=1e-4)
    np.testing.assert_allclose(f[3:5], closed(2), rtol=2e-3)
    np.testing.assert_allclose(f[5:7], closed(3), rtol=2e-3)


def test_material_errors_name_the_card_line():
    from pathlib import Path as _P

    deck = _P(__file__).parent / "data" / "nastran" / "pbarl_bar.bdf"  # MAT1 without RHO
    with pytest.raises(FormatError, match=r"pbarl_bar.bdf line 9: MAT1 1000: .*RHO is "
                       r"blank"):
        read_nastran(deck)
