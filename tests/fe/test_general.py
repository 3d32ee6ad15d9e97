"""General 3-D shells, beams, masses, springs and rigid links (mvtk.fe.assemble_model).

External truths used (each test names its own):
- rigid-body modes and patch tests (exact fields);
- Navier FSDT solution of a simply supported plate (Reddy 2004, section 6.3, computed);
- Leissa, "Vibration of Plates", NASA SP-160 (1969), table 2.1: clamped circular plate
  lambda = omega a^2 sqrt(rho h / D) = 10.2158, 21.260 (n = 1), 34.877 (n = 2);
- in-plane flexural modes of a thin circular ring (Hoppe 1871; Blevins, "Formulas for
  Natural Frequency and Mode Shape", 1979, table 9-2):
  omega_n^2 = E I n^2 (n^2 - 1)^2 / (rho A R^4 (n^2 + 1));
- NAFEMS FV2 "pin-ended double cross, in-plane vibration" (NAFEMS, "The Standard NAFEMS
  Benchmarks", TNSB rev. 3, 1990): f1 = 11.336, f2..f8 = 17.709, f9 = 45.345 Hz; f1 and f9
  are the
  joint-rotation modes in which every arm vibrates as a pinned-pinned beam, which also
  gives them in closed form;
- simply supported Timoshenko beam (bending), torsion and axial rods: exact closed forms
  (e.g. Han, Benaroya & Wei, J. Sound Vib. 225 (1999) 935-988, for the Timoshenko
  frequency equation);
- spring-mass, rigid-body and composite-section (parallel axis theorem) closed forms.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import (
    BeamSet,
    IsotropicMaterial,
    Laminate,
    Ply,
    PointMass,
    RigidLink,
    ShellSet,
    Spring,
    assemble_model,
    box_section,
    generic_section,
    i_section,
    mitc4_matrices,
    modal_analysis,
    plate_model,
    rectangle_section,
    rectangular_plate_mesh,
    shell_element_matrices,
    tube_section,
)
from mvtk.fe._shell3d import mitc3_matrices


def navier_fsdt(lam: Laminate, a: float, b: float, m: int, n: int) -> float:
    """Lowest omega (rad/s) of mode (m, n) of a simply supported FSDT plate (Reddy 6.3)."""
    import scipy.linalg as sla

    al, be = m * np.pi / a, n * np.pi / b
    D, H = lam.D, lam.H
    s55, s44 = H[0, 0], H[1, 1]
    K = np.array([
        [s55 * al**2 + s44 * be**2, s55 * al, s44 * be],
        [s55 * al, D[0, 0] * al**2 + D[2, 2] * be**2 + s55, (D[0, 1] + D[2, 2]) * al * be],
        [s44 * be, (D[0, 1] + D[2, 2]) * al * be, D[2, 2] * al**2 + D[1, 1] * be**2 + s44],
    ])
    return float(np.sqrt(sla.eigh(K, np.diag([lam.I0, lam.I2, lam.I2]),
                                  eigvals_only=True)[0]))

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
ROT = Rotation.from_euler("zyx", [31.0, -47.0, 68.0], degrees=True).as_matrix()


def _lam(h, mat=STEEL):
    return Laminate((Ply(mat, h),))


def _single(xyz, lam):
    return shell_element_matrices(xyz[None], lam.ABD[None], lam.H[None],
                                  np.array([[lam.I0, lam.I1, lam.I2]]),
                                  np.array([lam.thickness]))


# ------------------------------------------------------------------ single elements
TRI = np.array([[0, 0, 0], [1.1, 0.1, 0], [0.2, 0.9, 0.0]])
QUAD = np.array([[0, 0, 0], [1.3, 0.2, 0], [1.0, 0.9, 0], [-0.1, 1.2, 0.0]])
WARPED = QUAD + np.array([[0, 0, 0.06], [0, 0, -0.06], [0, 0, 0.06], [0, 0, -0.06]])


@pytest.mark.parametrize("xyz", [TRI, QUAD, WARPED], ids=["tri", "quad", "warped-quad"])
@pytest.mark.parametrize("h", [0.2, 1e-3])
@pytest.mark.parametrize("rotated", [False, True])
def test_single_element_has_exactly_six_zero_energy_modes(xyz, h, rotated):
    x = xyz @ ROT.T + np.array([0.3, -2.0, 5.0]) if rotated else xyz
    K, M = _single(x, _lam(h))
    w = np.linalg.eigvalsh(K[0])
    assert int(np.sum(np.abs(w) < 1e-9 * w.max())) == 6
    np.testing.assert_allclose(K[0], K[0].T, atol=1e-10 * np.abs(K).max())
    assert np.linalg.eigvalsh(M[0]).min() > 0
    # rigid rotation about an arbitrary axis through an arbitrary point is zero-energy
    omega, p = np.array([0.3, -0.7, 0.2]), np.array([1.0, 2.0, -0.5])
    q = np.hstack([np.cross(omega, x - p), np.tile(omega, (len(x), 1))]).ravel()
    assert np.abs(K[0] @ q).max() < 1e-8 * np.abs(K).max()


def test_flat_quad_in_xy_equals_mitc4_and_rotation_is_a_similarity():
    lam = _lam(0.01)
    K, M = _single(QUAD, lam)
    K4, M4 = mitc4_matrices(QUAD[None, :, :2], lam.ABD, lam.H, [lam.I0, lam.I1, lam.I2])
    np.testing.assert_allclose(K, K4, atol=1e-12 * np.abs(K4).max())
    np.testing.assert_allclose(M, M4, atol=1e-12 * np.abs(M4).max())
    Kr, _ = _single(QUAD @ ROT.T, lam)
    T = np.kron(np.eye(8), ROT)
    np.testing.assert_allclose(Kr[0], T @ K[0] @ T.T, atol=1e-9 * np.abs(K).max())


def test_triangle_consistent_mass_total():
    lam = _lam(0.01)
    _, M = _single(TRI @ ROT.T, lam)
    area = 0.5 * np.linalg.norm(np.cross(TRI[1] - TRI[0], TRI[2] - TRI[0]))
    e = np.zeros(18)
    e[0::6] = ROT[0, 0]
    e[1::6] = ROT[1, 0]
    e[2::6] = ROT[2, 0]
    assert e @ M[0] @ e == pytest.approx(lam.I0 * area, rel=1e-12)


def test_degenerate_and_clockwise_elements_rejected():
    lam = _lam(0.01)
    with pytest.raises(ParameterError, match="degenerate"):
        _single(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), lam)
    with pytest.raises(ParameterError, match="clockwise"):
        mitc3_matrices(TRI[None, ::-1, :2], lam.ABD, lam.H, [1, 0, 1], [0.01])
    with pytest.raises(DimensionError, match="n_el, 3 or 4, 3"):
        _single(np.zeros((5, 3)), lam)


# ------------------------------------------------------------------ patch tests
def _tri_patch():
    """The 5-element MacNeal-Harder patch split into 10 triangles (distorted)."""
    nodes = np.array([[0, 0], [0.24, 0], [0.24, 0.12], [0, 0.12],
                      [0.04, 0.02], [0.18, 0.03], [0.16, 0.08], [0.08, 0.08]])
    quads = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]])
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return np.column_stack([nodes, np.zeros(8)]), quads, tris


def _patch_solve(els, field, rotate):
    nodes, _, _ = _tri_patch()
    x = nodes @ ROT.T if rotate else nodes
    model = assemble_model(x, [ShellSet(els, _lam(1e-3), material_axis=x[1] - x[0])])
    q_local = field(nodes[:, 0], nodes[:, 1])  # (8, 6) in the patch plane
    R = ROT if rotate else np.eye(3)
    q = np.hstack([q_local[:, :3] @ R.T, q_local[:, 3:] @ R.T]).ravel()
    K = model.K.toarray()
    inner, outer = np.arange(24, 48), np.arange(24)
    qi = np.linalg.solve(K[np.ix_(inner, inner)], -K[np.ix_(inner, outer)] @ q[outer])
    return qi, q[inner]


def _membrane(x, y):
    q = np.zeros((len(x), 6))
    q[:, 0] = 1e-3 * (x + y / 2)
    q[:, 1] = 1e-3 * (x / 3 + y)
    q[:, 5] = 0.5 * 1e-3 * (1 / 3 - 1 / 2)  # (v,x - u,y)/2
    return q


def _bending(x, y):
    q = np.zeros((len(x), 6))
    q[:, 2] = 1e-3 * (x**2 + x * y + y**2) / 2
    q[:, 4] = -1e-3 * (x + y / 2)
    q[:, 3] = 1e-3 * (x / 2 + y)
    return q


@pytest.mark.parametrize("kind", ["tri", "quad"])
@pytest.mark.parametrize("rotate", [False, True])
def test_membrane_and_bending_patch_tests(kind, rotate):
    _, quads, tris = _tri_patch()
    els = tris if kind == "tri" else quads
    qi, qe = _patch_solve(els, _membrane, rotate)
    np.testing.assert_allclose(qi, qe, atol=1e-12)
    qi, qe = _patch_solve(els, _bending, rotate)
    R = ROT if rotate else np.eye(3)
    rot_i = (qi.reshape(4, 6)[:, 3:] @ R)[:, :2]
    rot_e = (qe.reshape(4, 6)[:, 3:] @ R)[:, :2]
    np.testing.assert_allclose(rot_i, rot_e, rtol=1e-8, atol=1e-12)
    w_i = qi.reshape(4, 6)[:, :3] @ R[:, 2]
    w_e = qe.reshape(4, 6)[:, :3] @ R[:, 2]
    np.testing.assert_allclose(w_i, w_e, atol=1e-9)


# ------------------------------------------------------------------ plates
def _ssss(n, elements="tri", h=0.01, a=1.0, rotate=False):
    mesh = rectangular_plate_mesh(a, a, nx=n, ny=n)
    els = mesh.elements
    if elements == "tri":
        els = np.concatenate([els[:, [0, 1, 2]], els[:, [0, 2, 3]]])
    nodes = mesh.nodes @ ROT.T if rotate else mesh.nodes
    sup = {e: "simply_supported_hard" for e in ("x0", "x1", "y0", "y1")}
    return assemble_model(nodes, [ShellSet(els, _lam(h))], supports=sup,
                          node_sets=mesh.node_sets)


@pytest.mark.parametrize("ratio", [5, 10, 100, 1000])
def test_triangle_no_shear_locking_ssss_plate(ratio):
    h = 1.0 / ratio
    f = modal_analysis(_ssss(16, "tri", h), 1).fn_hz[0]
    ref = navier_fsdt(_lam(h), 1.0, 1.0, 1, 1) / (2 * np.pi)
    assert f == pytest.approx(ref, rel=0.012)


def test_plain_mitc3_locks_which_is_why_it_is_stabilised(monkeypatch):
    import mvtk.fe._shell3d as s3

    ref = navier_fsdt(_lam(1e-3), 1.0, 1.0, 1, 1) / (2 * np.pi)
    f_stab = modal_analysis(_ssss(8, "tri", 1e-3), 1).fn_hz[0]
    monkeypatch.setattr(s3.mitc3_matrices, "__defaults__",
                        s3.mitc3_matrices.__defaults__[:-1] + (0.0,))
    f_plain = modal_analysis(_ssss(8, "tri", 1e-3), 1).fn_hz[0]
    assert f_stab == pytest.approx(ref, rel=0.05)
    assert f_plain > 1.5 * ref  # span/thickness 1000: plain MITC3 locks on this mesh


def test_rotated_copy_gives_the_same_frequencies_plate_mixed_mesh():
    mesh = rectangular_plate_mesh(0.3, 0.2, nx=9, ny=6)
    quads = mesh.elements[:30]
    tris = np.concatenate([mesh.elements[30:, [0, 1, 2]], mesh.elements[30:, [0, 2, 3]]])

    def build(nodes, axis=(1.0, 0.0, 0.0)):
        return assemble_model(nodes, [ShellSet(quads, _lam(2e-3), axis, name="q"),
                                      ShellSet(tris, _lam(2e-3), axis, name="t")],
                              supports={"x0": "clamped"}, node_sets=mesh.node_sets)

    r0 = modal_analysis(build(mesh.nodes), 8)
    r1 = modal_analysis(build(mesh.nodes @ ROT.T + 1.0, ROT[:, 0]), 8)
    np.testing.assert_allclose(r1.fn_hz, r0.fn_hz, rtol=1e-9)
    assert r1.mode_type == r0.mode_type  # energy-split labels are frame independent
    # and the quads-only model equals the built-in generator
    ref = modal_analysis(plate_model(0.3, 0.2, [Ply(STEEL, 2e-3)], nx=9, ny=6, clamp="x0"),
                         8).fn_hz
    m = assemble_model(mesh.nodes, [ShellSet(mesh.elements, _lam(2e-3))],
                       supports={"x0": "clamped"}, node_sets=mesh.node_sets)
    np.testing.assert_allclose(modal_analysis(m, 8).fn_hz, ref, rtol=1e-10)


def _disc(radius, n_ring=8, n_theta=32):
    """Triangulated disc: centre node + rings of n_theta nodes (unstructured-like)."""
    pts = [np.zeros(3)]
    for i in range(1, n_ring + 1):
        r = radius * i / n_ring
        th = 2 * np.pi * (np.arange(n_theta) + 0.5 * (i % 2)) / n_theta
        pts.extend(np.column_stack([r * np.cos(th), r * np.sin(th), np.zeros(n_theta)]))
    nodes = np.array(pts)
    from scipy.spatial import Delaunay

    tri = Delaunay(nodes[:, :2]).simplices
    # counter-clockwise
    a, b, c = nodes[tri[:, 0], :2], nodes[tri[:, 1], :2], nodes[tri[:, 2], :2]
    cw = ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]) < 0
    tri[cw] = tri[cw][:, ::-1]
    rim = np.flatnonzero(np.isclose(np.linalg.norm(nodes[:, :2], axis=1), radius))
    return nodes, tri, rim


def test_clamped_circular_plate_triangles_leissa():
    """Non-rectangular domain: clamped circular plate, Leissa (1969) table 2.1."""
    a, h = 0.5, 1e-3
    nodes, tri, rim = _disc(a, 16, 64)
    model = assemble_model(nodes @ ROT.T, [ShellSet(tri, _lam(h))],
                           supports={"rim": "clamped"}, node_sets={"rim": rim})
    res = modal_analysis(model, 6)
    D = STEEL.E * h**3 / (12 * (1 - STEEL.nu**2))
    lam_ = 2 * np.pi * res.fn_hz * a**2 * np.sqrt(STEEL.rho * h / D)
    np.testing.assert_allclose(lam_[[0, 1, 2, 3, 4]],
                               [10.2158, 21.260, 21.260, 34.877, 34.877], rtol=0.012)
    # converges from above (12 x 48 facets: 10.275, 21.53, 35.58; 24 x 96: 10.230)
    assert np.all(lam_[:5] > [10.2158, 21.260, 21.260, 34.877, 34.877])


def test_ring_as_shell_strip_in_plane_modes():
    """Curved shell: a ring (shell strip of facets) against the thin-ring closed form."""
    R, t, b, n_c = 0.5, 5e-3, 0.02, 96
    mat = IsotropicMaterial("nu0", 200e9, 0.0, 8000.0)  # nu = 0: strip = beam exactly
    th = 2 * np.pi * np.arange(n_c) / n_c
    ring = np.column_stack([R * np.cos(th), R * np.sin(th)])
    nodes = np.vstack([np.column_stack([ring, np.zeros(n_c)]),
                       np.column_stack([ring, np.full(n_c, b)])])
    i = np.arange(n_c)
    j = (i + 1) % n_c
    quads = np.column_stack([i, j, j + n_c, i + n_c])
    model = assemble_model(nodes, [ShellSet(quads, _lam(t, mat), material_axis=(0, 0, 1))])
    res = modal_analysis(model, 14)
    assert res.rigid.sum() == 6
    E, I_, A = mat.E, b * t**3 / 12, b * t
    n = np.array([2, 3])
    f_ref = n * (n**2 - 1) / np.sqrt(n**2 + 1) * np.sqrt(E * I_ / (mat.rho * A * R**4)) / (
        2 * np.pi)
    ip = [f for f, k in zip(res.fn_hz, res.mode_type) if k == "in-plane" or k == "bending"]
    elastic = res.fn_hz[~res.rigid]
    # the n = 2 and n = 3 in-plane pairs
    for fr in f_ref:
        close = elastic[np.abs(elastic / fr - 1) < 0.01]
        assert len(close) == 2, (fr, elastic)
    assert ip


# ------------------------------------------------------------------ beams and frames
def _double_cross(angle_plane=None, n_per_arm=4):
    L = 5.0
    nodes = [np.zeros(3)]
    els, ends = [], []
    for k in range(8):
        phi = k * np.pi / 4
        d = np.array([np.cos(phi), np.sin(phi), 0.0])
        start = 0
        for s in range(1, n_per_arm + 1):
            nodes.append(d * L * s / n_per_arm)
            els.append([start, len(nodes) - 1])
            start = len(nodes) - 1
        ends.append(start)
    nodes = np.array(nodes)
    if angle_plane is not None:
        nodes = nodes @ angle_plane.T
    return nodes, np.array(els), np.array(ends)


def test_nafems_fv2_pin_ended_double_cross_in_plane():
    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    sec = rectangle_section(mat, 0.125, 0.125)
    nodes, els, ends = _double_cross()
    model = assemble_model(
        nodes, [BeamSet(els, sec, orientation=(0, 0, 1))],
        supports={"ends": "pinned", "all": "symmetry_z"},  # in-plane: uz = rx = ry = 0
        node_sets={"ends": ends, "all": np.arange(len(nodes))})
    f = modal_analysis(model, 10).fn_hz
    assert f[0] == pytest.approx(11.336, rel=2e-3)
    np.testing.assert_allclose(f[1:8], 17.709, rtol=5e-3)  # NAFEMS: 17.709 (x 7)
    assert f[8] == pytest.approx(45.345, rel=5e-3)
    # closed form of the joint-rotation modes: pinned-pinned Euler-Bernoulli arm
    EI, rhoA = sec.EIz, sec.rhoA
    assert f[0] == pytest.approx(np.pi / (2 * 25.0) * np.sqrt(EI / rhoA), rel=2e-3)


def test_rotated_frame_gives_the_same_frequencies():
    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    sec = i_section(mat, 0.2, 0.1, 0.012, 0.008)

    def build(R):
        nodes, els, ends = _double_cross(R, n_per_arm=3)
        return assemble_model(nodes, [BeamSet(els, sec, orientation=R @ [0, 0, 1.0])],
                              supports={"ends": "pinned"}, node_sets={"ends": ends})

    f0 = modal_analysis(build(np.eye(3)), 10).fn_hz
    f1 = modal_analysis(build(ROT), 10).fn_hz
    np.testing.assert_allclose(f1, f0, rtol=1e-8)


def _timoshenko_ss(n, L, EI, kGA, rhoA, rhoI):
    a = n * np.pi / L
    c2 = rhoI * rhoA / kGA
    c1 = -(rhoA + rhoI * a**2 + EI * a**2 * rhoA / kGA)
    c0 = EI * a**4
    return np.sqrt(min(np.roots([c2, c1, c0]).real)) / (2 * np.pi)


def test_simply_supported_deep_beam_bending_torsion_axial():
    """Deep beam (L/h = 5, the NAFEMS FV5 geometry) against exact closed forms."""
    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    L, a = 10.0, 2.0
    sec = rectangle_section(mat, a, a)
    n_el = 40
    x = np.linspace(0, L, n_el + 1)
    d = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])  # skew axis
    nodes = x[:, None] * d[None, :]
    els = np.column_stack([np.arange(n_el), np.arange(1, n_el + 1)])
    # both ends pinned (translations); the rotation about the beam axis is held at A by
    # a stiff torsional spring (else torsion would be a rigid mode)
    k_t = 1e14 * np.outer(d, d)
    k6 = np.zeros((6, 6))
    k6[3:, 3:] = k_t
    model = assemble_model(
        nodes, [BeamSet(els, sec, orientation=np.cross(d, [0, 0, 1.0])), Spring(0, k6)],
        supports={"A": "pinned", "B": "pinned"}, node_sets={"A": [0], "B": [n_el]})
    res = modal_analysis(model, 8)
    G = mat.G
    fb = [_timoshenko_ss(n, L, sec.EIy, sec.kGAz, sec.rhoA, sec.rhoIy) for n in (1, 2)]
    # torsion fixed (spring) at A, free at B; axial fixed-fixed
    ft = [(2 * n - 1) / (4 * L) * np.sqrt(sec.GJ / (sec.rhoIy + sec.rhoIz)) for n in (1, 2)]
    fa = 1 / (2 * L) * np.sqrt(mat.E / mat.rho)
    f = res.fn_hz
    assert np.all(np.diff(f) >= 0)
    for ref, count in ((fb[0], 2), (ft[0], 1), (fb[1], 2), (ft[1], 1), (fa, 1)):
        assert np.sum(np.abs(f / ref - 1) < 3e-3) == count, (ref, f)
    types = dict(zip(np.round(f, 3), res.mode_type))
    assert types[np.round(f[np.argmin(np.abs(f - ft[0]))], 3)] == "torsion"
    assert types[np.round(f[0], 3)] == "bending"
    assert types[np.round(f[np.argmin(np.abs(f - fa))], 3)] == "axial"
    del G


def test_axial_mode_of_rod_is_labelled_axial():
    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    sec = tube_section(mat, 0.3, 0.25)
    n_el = 20
    nodes = np.column_stack([np.linspace(0, 1.0, n_el + 1), np.zeros((n_el + 1, 2))])
    els = np.column_stack([np.arange(n_el), np.arange(1, n_el + 1)])
    model = assemble_model(nodes, [BeamSet(els, sec)], supports={"A": "clamped"},
                           node_sets={"A": [0]})
    res = modal_analysis(model, 12)
    fa = 1 / (4 * 1.0) * np.sqrt(mat.E / mat.rho)
    i = int(np.argmin(np.abs(res.fn_hz - fa)))
    assert res.fn_hz[i] == pytest.approx(fa, rel=2e-3)
    assert res.mode_type[i] == "axial"


def test_standard_sections_closed_forms():
    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    s = box_section(mat, 0.2, 0.1, 0.01, 0.01)
    assert s.EA == pytest.approx(mat.E * (0.02 - 0.08 * 0.18), rel=1e-12)
    assert s.EIy == pytest.approx(mat.E * (0.1 * 0.2**3 - 0.08 * 0.18**3) / 12, rel=1e-12)
    t = tube_section(mat, 0.05)
    assert t.GJ == pytest.approx(mat.G * np.pi * 0.05**4 / 2, rel=1e-12)
    assert t.kGAy / (mat.G * np.pi * 0.05**2) == pytest.approx(6 * 1.3 / (7 + 1.8), rel=1e-12)
    g = generic_section(mat, A=1e-3, Iy=2e-6, Iz=1e-6, J=5e-7)
    assert (g.EIy, g.EIz, g.GJ) == (mat.E * 2e-6, mat.E * 1e-6, mat.G * 5e-7)
    with pytest.raises(ParameterError, match="inner_radius"):
        tube_section(mat, 0.05, 0.06)
    with pytest.raises(ParameterError, match="A must be a positive"):
        generic_section(mat, A=-1, Iy=1, Iz=1, J=1)


def test_offset_stiffener_composite_section_closed_form():
    """Narrow strip + offset rectangular stiffener = T beam (parallel axis theorem)."""
    mat = IsotropicMaterial("nu0", 200e9, 0.0, 8000.0)
    L, b, t = 0.6, 0.02, 2e-3
    hs, bs = 0.01, 4e-3
    n = 30
    x = np.linspace(0, L, n + 1)
    nodes = np.vstack([np.column_stack([x, np.zeros(n + 1), np.zeros(n + 1)]),
                       np.column_stack([x, np.full(n + 1, b), np.zeros(n + 1)]),
                       np.column_stack([x, np.full(n + 1, b / 2), np.zeros(n + 1)])])
    i = np.arange(n)
    quads_a = np.column_stack([i, i + 1, 2 * (n + 1) + i + 1, 2 * (n + 1) + i])
    quads_b = np.column_stack([2 * (n + 1) + i, 2 * (n + 1) + i + 1, n + 1 + i + 1,
                               n + 1 + i])
    beams = np.column_stack([2 * (n + 1) + i, 2 * (n + 1) + i + 1])
    e = -(t / 2 + hs / 2)
    stiff = rectangle_section(mat, bs, hs)
    clamp = np.array([0, n + 1, 2 * (n + 1)])
    model = assemble_model(
        nodes, [ShellSet(np.vstack([quads_a, quads_b]), _lam(t, mat)),
                BeamSet(beams, stiff, orientation=(0, 1, 0), offset=(0, 0, e))],
        supports={"clamp": "clamped"}, node_sets={"clamp": clamp})
    f = modal_analysis(model, 1).fn_hz[0]
    A1, A2 = b * t, bs * hs
    zc = A2 * e / (A1 + A2)
    EI = mat.E * (b * t**3 / 12 + A1 * zc**2 + bs * hs**3 / 12 + A2 * (e - zc) ** 2)
    m = mat.rho * (A1 + A2)
    ref = 1.875104**2 / (2 * np.pi * L**2) * np.sqrt(EI / m)
    assert f == pytest.approx(ref, rel=0.01)


# ------------------------------------------------------------------ masses, links
def test_point_mass_on_grounded_springs_closed_form():
    k = np.array([1e4, 2e4, 3e4, 10.0, 20.0, 40.0])
    m, J = 2.0, np.array([0.01, 0.02, 0.04])
    model = assemble_model(np.zeros((1, 3)), [PointMass(0, m, J), Spring(0, k)])
    res = modal_analysis(model, 5)
    ref = np.sqrt(k / np.r_[m, m, m, J]) / (2 * np.pi)
    np.testing.assert_allclose(res.fn_hz, np.sort(ref)[:5], rtol=1e-10)


def test_offset_point_mass_two_node_spring_closed_form():
    # mass m at offset e (along x) from node 1; node 1 tied to node 0 by a two-node
    # spring (uz: k, ry: kr); node 0 clamped. 2-DOF closed form in (uz, ry).
    m, e, k, kr, Jy = 3.0, 0.2, 5e4, 2e3, 0.01
    model = assemble_model(
        np.array([[0, 0, 0], [0, 0, 0.0]]),
        [PointMass(1, m, (0.0, Jy, 0.0), offset=(e, 0, 0)),
         Spring(0, {"uz": k, "ry": kr}, node_b=1),
         Spring(1, {"ux": 1e9, "uy": 1e9, "rx": 1e9, "rz": 1e9})],
        supports={"ground": "clamped"}, node_sets={"ground": [0]})
    # uz of the mass = uz - e ry (theta x e, e along x): M = m [[1, -e], [-e, e^2]] + Jy
    import scipy.linalg as sla

    Mref = m * np.array([[1, -e], [-e, e**2]]) + np.diag([0, Jy])
    w2 = sla.eigh(np.diag([k, kr]), Mref, eigvals_only=True)
    res = modal_analysis(model, 2)
    np.testing.assert_allclose(res.fn_hz, np.sqrt(w2) / (2 * np.pi), rtol=1e-9)


def test_rbe2_rigid_body_with_masses_closed_form():
    pts = np.array([[0, 0, 0], [0.5, 0, 0], [-0.5, 0, 0], [0, 0.3, 0], [0, -0.3, 0.0]])
    m = np.array([0.0, 1.0, 1.0, 2.0, 2.0])
    k_uz, k_rx, k_ry = 1e4, 300.0, 700.0
    members = [PointMass(i, m[i]) for i in range(1, 5)]
    members += [RigidLink(0, [1, 2, 3, 4], "rbe2"),
                Spring(0, {"uz": k_uz, "rx": k_rx, "ry": k_ry, "ux": 1e9, "uy": 1e9,
                           "rz": 1e9})]
    model = assemble_model(pts, members)
    assert model.n_dof == 6
    res = modal_analysis(model, 3)
    Jx = np.sum(m * pts[:, 1] ** 2)
    Jy = np.sum(m * pts[:, 0] ** 2)
    ref = np.sort(np.sqrt([k_uz / m.sum(), k_rx / Jx, k_ry / Jy])) / (2 * np.pi)
    np.testing.assert_allclose(res.fn_hz, ref, rtol=1e-10)
    np.testing.assert_allclose((model.M - model.M.T).toarray(), 0, atol=1e-14)
    # recovered shapes move the dependent nodes rigidly
    u = model.expand(res.shapes[:, 0])
    np.testing.assert_allclose(u[1:, 2], u[0, 2] + u[0, 3] * pts[1:, 1]
                               - u[0, 4] * pts[1:, 0], atol=1e-12)


def test_rbe3_reference_mass_on_four_springs_closed_form():
    a = 0.4
    pts = np.array([[0, 0, 0.0], [a, a, 0], [-a, a, 0], [-a, -a, 0], [a, -a, 0.0]])
    k, m, J = 1e4, 5.0, 0.3
    members = [PointMass(0, m, (J, J, J)), RigidLink(0, [1, 2, 3, 4], "rbe3")]
    members += [Spring(i, {"ux": k, "uy": k, "uz": k}) for i in range(1, 5)]
    model = assemble_model(pts, members)
    res = modal_analysis(model, 6)
    # translations: 4 k / m; rocking about x: springs at |y| = a give 4 k a^2 / J
    f = res.fn_hz
    assert np.sum(np.isclose(f, np.sqrt(4 * k / m) / (2 * np.pi), rtol=1e-6)) >= 1
    assert np.any(np.isclose(f, np.sqrt(4 * k * a**2 / J) / (2 * np.pi), rtol=1e-6))
    assert np.any(np.isclose(f, np.sqrt(4 * k * 2 * a**2 / J) / (2 * np.pi), rtol=1e-6))


def test_bad_members_and_supports_rejected():
    nodes = np.zeros((2, 3))
    with pytest.raises(ParameterError, match="unknown support type 'glued'"):
        assemble_model(nodes, [Spring(0, np.ones(6))], supports={"a": "glued"},
                       node_sets={"a": [0]})
    with pytest.raises(ParameterError, match="unknown node set 'b'"):
        assemble_model(nodes, [Spring(0, np.ones(6))], supports={"b": "clamped"},
                       node_sets={"a": [0]})
    with pytest.raises(ParameterError, match="unknown DOF 'uq'"):
        assemble_model(nodes, [Spring(0, {"uq": 1.0})])
    with pytest.raises(ParameterError, match="collinear"):
        assemble_model(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]),
                       [RigidLink(0, [1, 2], "rbe3")])
    with pytest.raises(ParameterError, match="both supported and dependent"):
        assemble_model(np.array([[0, 0, 0], [1, 0, 0.0]]),
                       [Spring(0, np.ones(6)), RigidLink(0, [1])],
                       supports={"s": "pinned"}, node_sets={"s": [1]})
    with pytest.raises(DimensionError, match=r"shape \(n, 3\) or \(n, 4\)"):
        ShellSet(np.zeros((2, 5), int), _lam(1e-3))


def test_shell_offset_and_material_axis_on_a_rotated_cantilever():
    """Nodes on the bottom face (offset = t/2) give the mid-plane frequencies (2e-3, as
    for the flat plate test), and a 0/90 laminate follows its material axis."""
    from mvtk.fe import OrthotropicMaterial

    mesh = rectangular_plate_mesh(0.3, 0.05, nx=20, ny=4)
    h = 2e-3
    nodes = mesh.nodes @ ROT.T
    f = [modal_analysis(assemble_model(nodes, [ShellSet(mesh.elements, _lam(h), offset=o)],
                                       supports={"x0": "clamped"},
                                       node_sets=mesh.node_sets), 4).fn_hz
         for o in (0.0, h / 2)]
    np.testing.assert_allclose(f[1], f[0], rtol=2e-3)
    cfrp = OrthotropicMaterial("cfrp", 140e9, 10e9, 5e9, 5e9, 3.5e9, 0.3, 1600.0)
    lam = Laminate((Ply(cfrp, h),))
    along = [modal_analysis(assemble_model(
        nodes, [ShellSet(mesh.elements, lam, material_axis=ROT @ a)],
        supports={"x0": "clamped"}, node_sets=mesh.node_sets), 1).fn_hz[0]
        for a in ([1.0, 0, 0], [0, 1.0, 0])]
    # fibres along the strip: bending stiffness ratio ~ E1/E2 = 14
    assert along[0] / along[1] == pytest.approx(np.sqrt(14.0), rel=0.05)


def test_stiffened_plate_offset_beam_matches_shell_web_model():
    """Stiffened plate: offset beam stiffener vs the blade meshed as a shell web at 90
    degrees (an independent discretisation of the same structure: facets meeting at a
    right angle, drilling coupling). No open peer shell code was installable here, so
    the cross-check is against mvtk's own shell-only model."""
    L, B, t, hs, ts = 0.4, 0.3, 2e-3, 0.02, 3e-3
    nz = 4
    mesh = rectangular_plate_mesh(L, B, nx=32, ny=24)
    nodes = mesh.nodes
    line = np.flatnonzero(np.isclose(nodes[:, 1], B / 2))
    line = line[np.argsort(nodes[line, 0])]
    web = np.vstack([np.column_stack([nodes[line, 0], np.full(len(line), B / 2),
                                      np.full(len(line), -hs * k / nz)])
                     for k in range(1, nz + 1)])
    allnodes = np.vstack([nodes, web])
    rows = [line] + [len(nodes) + (k - 1) * len(line) + np.arange(len(line))
                     for k in range(1, nz + 1)]
    wq = np.array([[a[i], a[i + 1], b[i + 1], b[i]] for a, b in zip(rows[:-1], rows[1:])
                   for i in range(len(line) - 1)])
    shells = assemble_model(
        allnodes, [ShellSet(mesh.elements, _lam(t), name="plate"),
                   ShellSet(wq, _lam(ts), name="web")],
        supports={"clamp": "clamped"},
        node_sets={"clamp": np.flatnonzero(np.isclose(allnodes[:, 0], 0.0))})
    beams = np.column_stack([line[:-1], line[1:]])
    offset = assemble_model(
        nodes, [ShellSet(mesh.elements, _lam(t)),
                BeamSet(beams, rectangle_section(STEEL, ts, hs), orientation=(0, 1, 0),
                        offset=(0, 0, -hs / 2))],
        supports={"x0": "clamped"}, node_sets=mesh.node_sets)
    f_shell = modal_analysis(shells, 6).fn_hz
    f_beam = modal_analysis(offset, 6).fn_hz
    np.testing.assert_allclose(f_beam, f_shell, rtol=0.02)
    unstiffened = modal_analysis(plate_model(L, B, [Ply(STEEL, t)], nx=32, ny=24,
                                             clamp="x0"), 2).fn_hz
    assert f_beam[1] > 1.5 * unstiffened[0]  # the stiffener matters


@pytest.mark.parametrize("warp", [0.0, 2e-3])
def test_shared_shapes_and_block_rotation_equal_the_per_element_computation(warp):
    """Congruent elements share one local matrix; flat ones are rotated block by block.

    Truth: the same elements computed one by one with a per-element section (which
    disables the sharing) through the dense transformation T' K T.
    """
    from mvtk.fe import DRILL_FACTOR
    from mvtk.fe._shell3d import (
        _local_frames,
        _rotation_blocks,
        _warped_transform,
        mitc4_matrices,
        shell_element_matrices,
    )

    base = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.11, 0.09, warp], [-0.01, 0.12, 0.0]])
    n = 12
    rot = Rotation.random(n, random_state=3)
    xyz = np.stack([rot[i].apply(base) + i for i in range(n)])
    xyz[::3] = xyz[1]  # exact copies too
    lam = Laminate([Ply(STEEL, 2e-3), Ply(STEEL, 1e-3)])
    sec = (lam.ABD, lam.H, np.array([lam.I0, lam.I1, lam.I2]))
    K, M = shell_element_matrices(xyz, sec[0][None], sec[1][None], sec[2][None],
                                  np.full(n, lam.thickness), (0.3, 0.5, 0.8))
    local, R = _local_frames(xyz, (0.3, 0.5, 0.8))
    Kl, Ml = mitc4_matrices(local[:, :, :2], np.repeat(sec[0][None], n, 0),
                            np.repeat(sec[1][None], n, 0), np.repeat(sec[2][None], n, 0),
                            DRILL_FACTOR)
    T = _warped_transform(R, local[:, :, 2], 4) if warp else _rotation_blocks(R, 4)
    Tt = np.swapaxes(T, 1, 2)
    for got, ref in ((K, Tt @ Kl @ T), (M, Tt @ Ml @ T)):
        assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()


def test_shape_sharing_keeps_small_elements_of_a_graded_mesh_exact():
    """Two tiny elements that differ by 1e-8 of their size (1e-14 of the largest element)
    must not share a matrix."""
    from mvtk.fe._shell3d import shell_element_matrices

    unit = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    tiny = 1e-6 * unit
    tiny2 = tiny.copy()
    tiny2[2, :2] *= 1 + 1e-8
    xyz = np.stack([unit, tiny, tiny2])
    lam = Laminate([Ply(STEEL, 1e-7)])
    sec = (lam.ABD[None], lam.H[None], np.array([[lam.I0, lam.I1, lam.I2]]))
    K, _ = shell_element_matrices(xyz, *sec, np.full(3, lam.thickness))
    K1, _ = shell_element_matrices(xyz[1:2], *sec, np.full(1, lam.thickness))
    K2, _ = shell_element_matrices(xyz[2:3], *sec, np.full(1, lam.thickness))
    np.testing.assert_array_equal(K[1], K1[0])
    np.testing.assert_array_equal(K[2], K2[0])
    assert np.abs(K[2] - K[1]).max() > 0
