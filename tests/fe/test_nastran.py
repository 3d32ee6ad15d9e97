"""Nastran bulk-data subset (mvtk.fe.read_nastran) against equivalent built-in models."""

from __future__ import annotations

import numpy as np
import pytest

from mvtk.errors import FormatError
from mvtk.fe import (
    BeamSet,
    IsotropicMaterial,
    Ply,
    assemble_model,
    modal_analysis,
    plate_model,
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
    with pytest.raises(FormatError, match=r"x.bdf line 2: GRID 1: displacement system CD"):
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
