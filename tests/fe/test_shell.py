"""MITC4 layered shell element: rigid modes, patch tests, locking, plate benchmarks.

External truths used:
- Kirchhoff SSSS square plate: lambda = omega a^2 sqrt(rho h / D) = 2 pi^2, 5 pi^2, 8 pi^2
  (exact, Leissa, "Vibration of Plates", NASA SP-160, 1969, eq. 4.21).
- Leissa (1969) Table 4.50, CFFF square plate, nu = 0.3: 3.492, 8.525, 21.43, 27.33, 31.11
  (Ritz upper bounds; we accept up to 1 % below them).
- Leissa (1969) FFFF square plate, nu = 0.3: 13.468, 19.596, 24.270.
- Navier solution of FSDT for simply supported symmetric cross-ply and isotropic
  plates (Reddy, Mechanics of Laminated Composite Plates and Shells, 2004, section 6.3),
  computed here.
"""

import numpy as np
import pytest

from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import (
    IsotropicMaterial,
    Laminate,
    OrthotropicMaterial,
    Ply,
    assemble_shell_model,
    mitc4_matrices,
    modal_analysis,
    plate_model,
    rectangular_plate_mesh,
    static_solve,
)

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
SSSS = {e: "simply_supported" for e in ("x0", "x1", "y0", "y1")}


def navier_fsdt(lam: Laminate, a: float, b: float, m: int, n: int) -> float:
    """Lowest omega (rad/s) of mode (m, n) of a SS symmetric cross-ply FSDT plate."""
    al, be = m * np.pi / a, n * np.pi / b
    D, H = lam.D, lam.H
    s55, s44 = H[0, 0], H[1, 1]
    K = np.array([
        [s55 * al**2 + s44 * be**2, s55 * al, s44 * be],
        [s55 * al, D[0, 0] * al**2 + D[2, 2] * be**2 + s55, (D[0, 1] + D[2, 2]) * al * be],
        [s44 * be, (D[0, 1] + D[2, 2]) * al * be, D[2, 2] * al**2 + D[1, 1] * be**2 + s44],
    ])
    Mm = np.diag([lam.I0, lam.I2, lam.I2])
    import scipy.linalg as sla

    return float(np.sqrt(sla.eigh(K, Mm, eigvals_only=True)[0]))


def _lam_factor(h, a=1.0, E=210e9, nu=0.3, rho=7850.0):
    D = E * h**3 / (12 * (1 - nu**2))
    return a**2 * np.sqrt(rho * h / D)


def _single(xy, lam):
    return mitc4_matrices(xy[None], lam.ABD[None], lam.H[None],
                          np.array([[lam.I0, lam.I1, lam.I2]]))


@pytest.mark.parametrize("h", [0.2, 1e-3])
@pytest.mark.parametrize("distorted", [False, True])
def test_unconstrained_element_has_exactly_six_zero_energy_modes(h, distorted):
    xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    if distorted:
        xy = np.array([[0, 0], [1.3, 0.2], [1.0, 0.9], [-0.1, 1.2]])
    lam = Laminate((Ply(STEEL, h),))
    K, M = _single(xy, lam)
    w = np.linalg.eigvalsh(K[0])
    n_zero = int(np.sum(np.abs(w) < 1e-9 * w.max()))
    assert n_zero == 6
    np.testing.assert_allclose(K[0], K[0].T, rtol=0, atol=1e-9 * np.abs(K).max())
    assert np.linalg.eigvalsh(M[0]).min() > 0
    # total translational mass = I0 * area
    d1, d2 = xy[2] - xy[0], xy[3] - xy[1]
    area = 0.5 * abs(d1[0] * d2[1] - d1[1] * d2[0])
    ux = np.zeros(24)
    ux[0::6] = 1.0
    assert ux @ M[0] @ ux == pytest.approx(lam.I0 * area, rel=1e-12)


def test_rigid_body_field_gives_zero_force():
    xy = np.array([[0, 0], [1.3, 0.2], [1.0, 0.9], [-0.1, 1.2]])
    lam = Laminate((Ply(STEEL, 0.05),))
    K, _ = _single(xy, lam)
    # rotation about z by t: u = -t y, v = t x, rz = t; about x: w = t y, rx = t
    q = np.zeros((4, 6))
    q[:, 0], q[:, 1], q[:, 5] = -xy[:, 1], xy[:, 0], 1.0
    assert np.abs(K[0] @ q.ravel()).max() < 1e-8 * np.abs(K).max()
    q = np.zeros((4, 6))
    q[:, 2], q[:, 3] = xy[:, 1], 1.0
    assert np.abs(K[0] @ q.ravel()).max() < 1e-8 * np.abs(K).max()


def test_clockwise_element_rejected():
    lam = Laminate((Ply(STEEL, 1e-3),))
    xy = np.array([[0, 0], [0, 1], [1, 1], [1, 0.0]])
    with pytest.raises(ParameterError, match="clockwise"):
        _single(xy, lam)
    with pytest.raises(DimensionError, match="n_el, 4, 2"):
        mitc4_matrices(np.zeros((2, 3, 2)), lam.ABD, lam.H, [1, 0, 1])


def _distorted_patch():
    """The classic 5-element patch (MacNeal & Harder 1985) scaled to 0.24 x 0.12."""
    nodes = np.array([[0, 0], [0.24, 0], [0.24, 0.12], [0, 0.12],
                      [0.04, 0.02], [0.18, 0.03], [0.16, 0.08], [0.08, 0.08]])
    els = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]])
    return np.column_stack([nodes, np.zeros(8)]), els


def _patch_solve(exact):
    nodes, els = _distorted_patch()
    lam = Laminate((Ply(STEEL, 1e-3),))
    q_exact = exact(nodes[:, 0], nodes[:, 1])  # (8, 6)
    model = assemble_shell_model(nodes, els, np.zeros(5, int), [lam])
    K = model.K.toarray()
    inner = np.arange(4 * 6, 8 * 6)
    outer = np.arange(0, 4 * 6)
    q = q_exact.ravel()
    qi = np.linalg.solve(K[np.ix_(inner, inner)], -K[np.ix_(inner, outer)] @ q[outer])
    return qi, q[inner]


def test_membrane_patch_test():
    def exact(x, y):
        q = np.zeros((len(x), 6))
        q[:, 0] = 1e-3 * (x + y / 2)
        q[:, 1] = 1e-3 * (x / 2 + y)
        q[:, 5] = 0.5 * (1e-3 * 0.5 - 1e-3 * 0.5)  # in-plane rotation (v,x - u,y)/2 = 0
        return q

    qi, qe = _patch_solve(exact)
    np.testing.assert_allclose(qi, qe, atol=1e-12)


def test_bending_patch_test_constant_curvature():
    # w = (x^2 + x y + y^2)/2, zero transverse shear: ry = -w,x, rx = w,y
    def exact(x, y):
        q = np.zeros((len(x), 6))
        q[:, 2] = 1e-3 * (x**2 + x * y + y**2) / 2
        q[:, 4] = -1e-3 * (x + y / 2)
        q[:, 3] = 1e-3 * (x / 2 + y)
        return q

    qi, qe = _patch_solve(exact)
    # rotations (constant curvature) are reproduced exactly; w to a tiny fraction
    rot = np.r_[[3, 4]] + 6 * np.arange(4)[:, None]
    np.testing.assert_allclose(qi[rot.ravel()], qe[rot.ravel()], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(qi[2::6], qe[2::6], rtol=0, atol=1e-9)


@pytest.mark.parametrize("ratio", [5, 10, 20, 50, 100, 1000])
def test_no_shear_locking_ssss_plate(ratio):
    a = 1.0
    h = a / ratio
    lam = Laminate((Ply(STEEL, h),))
    model = plate_model(a, a, [Ply(STEEL, h)], nx=16, ny=16, supports=SSSS)
    f = modal_analysis(model, 1).fn_hz[0]
    ref = navier_fsdt(lam, a, a, 1, 1) / (2 * np.pi)
    assert f == pytest.approx(ref, rel=0.01)


def test_ssss_plate_thin_limit_and_convergence_rate():
    h = 1e-3
    errs = []
    for n in (4, 8, 16):
        model = plate_model(1.0, 1.0, [Ply(STEEL, h)], nx=n, ny=n, supports=SSSS)
        lam1 = 2 * np.pi * modal_analysis(model, 1).fn_hz[0] * _lam_factor(h)
        errs.append(abs(lam1 - 2 * np.pi**2) / (2 * np.pi**2))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(rates > 1.8)  # O(h^2) in frequency
    model = plate_model(1.0, 1.0, [Ply(STEEL, h)], nx=24, ny=24, supports=SSSS)
    lam_ = 2 * np.pi * modal_analysis(model, 4).fn_hz * _lam_factor(h)
    np.testing.assert_allclose(lam_[:3], np.pi**2 * np.array([2, 5, 5]), rtol=1e-2)
    assert lam_[3] == pytest.approx(8 * np.pi**2, rel=1e-2)
    assert lam_[0] == pytest.approx(2 * np.pi**2, rel=2e-3)


def test_cfff_square_plate_leissa():
    h = 1e-3
    model = plate_model(1.0, 1.0, [Ply(STEEL, h)], nx=24, ny=24, clamp="x0")
    res = modal_analysis(model, 5)
    lam_ = 2 * np.pi * res.fn_hz * _lam_factor(h)
    leissa = np.array([3.492, 8.525, 21.43, 27.33, 31.11])
    assert np.all(lam_ < leissa * 1.002)
    assert np.all(lam_ > leissa * 0.99)
    assert res.mode_type[:2] == ("bending", "torsion")


def test_free_free_plate_six_rigid_modes_and_leissa():
    h = 1e-3
    model = plate_model(1.0, 1.0, [Ply(STEEL, h)], nx=20, ny=20)
    res = modal_analysis(model, 9)
    assert res.rigid.sum() == 6
    assert res.mode_type[:6] == ("rigid",) * 6
    lam_ = 2 * np.pi * res.fn_hz[6:] * _lam_factor(h)
    np.testing.assert_allclose(lam_, [13.468, 19.596, 24.270], rtol=0.01)
    phi = res.shapes
    np.testing.assert_allclose(phi.T @ (model.M @ phi), np.eye(9), atol=1e-8)


def test_cross_ply_0_90_90_0_ssss_navier():
    # Reddy (2004) material: E1/E2 = 40, G12 = G13 = 0.6 E2, G23 = 0.5 E2, nu12 = 0.25
    E2 = 1e10
    mat = OrthotropicMaterial("gr", E1=40 * E2, E2=E2, G12=0.6 * E2, G13=0.6 * E2,
                              G23=0.5 * E2, nu12=0.25, rho=1500.0)
    a, h = 1.0, 0.1
    plies = [Ply(mat, h / 4, ang) for ang in (0, 90, 90, 0)]
    lam = Laminate(tuple(plies))
    w_ref = navier_fsdt(lam, a, a, 1, 1)
    # the Navier solution itself reduces to Kirchhoff's 2 pi^2 for a thin isotropic plate
    thin = Laminate((Ply(STEEL, 1e-4),))
    lam_thin = navier_fsdt(thin, 1.0, 1.0, 1, 1) * _lam_factor(1e-4)
    assert lam_thin == pytest.approx(2 * np.pi**2, rel=1e-6)
    model = plate_model(a, a, plies, nx=20, ny=20, supports=SSSS)
    f = modal_analysis(model, 1).fn_hz[0]
    assert 2 * np.pi * f == pytest.approx(w_ref, rel=0.01)


def _beam_strip(L, b, h, n, **kw):
    mat = IsotropicMaterial("nu0", 210e9, 0.0, 7850.0)  # nu = 0: the strip is a beam
    return mat, plate_model(L, b, [Ply(mat, h)], nx=n, ny=2, **kw)


def test_cantilever_strip_euler_bernoulli():
    L, b, h = 1.0, 0.05, 0.005
    mat, model = _beam_strip(L, b, h, 40, clamp="x0")
    res = modal_analysis(model, 6)
    fb = res.fn_hz[np.array(res.mode_type) == "bending"]
    EI = mat.E * b * h**3 / 12
    rhoA = mat.rho * b * h
    beta = np.array([1.875104, 4.694091, 7.854757])
    ref = beta**2 / (2 * np.pi * L**2) * np.sqrt(EI / rhoA)
    np.testing.assert_allclose(fb[:3], ref, rtol=5e-3)


def test_simply_supported_thick_strip_timoshenko():
    L, b, h = 0.5, 0.02, 0.1  # L/h = 5
    mat, model = _beam_strip(L, b, h, 40, supports={"x0": "simply_supported",
                                                    "x1": "simply_supported"})
    res = modal_analysis(model, 6)
    fb = res.fn_hz[np.array(res.mode_type) == "bending"]
    G = mat.G
    lam = Laminate((Ply(mat, h),))
    for k, f in zip((1, 2), fb[:2]):
        al = k * np.pi / L
        Kt = np.array([[5 / 6 * G * h * al**2, 5 / 6 * G * h * al],
                       [5 / 6 * G * h * al, lam.D[0, 0] * al**2 + 5 / 6 * G * h]])
        import scipy.linalg as sla

        w = np.sqrt(sla.eigh(Kt, np.diag([lam.I0, lam.I2]), eigvals_only=True)[0])
        assert 2 * np.pi * f == pytest.approx(w, rel=5e-3)
        eb = al**2 * np.sqrt(lam.D[0, 0] / lam.I0)
        assert w < 0.96 * eb  # shear deformation matters here: a real Timoshenko check


def test_static_cantilever_tip_load():
    L, b, h = 1.0, 0.05, 0.01
    mat, model = _beam_strip(L, b, h, 40, clamp="x0")
    tip = model.node_set("x1")
    f = np.zeros(model.n_dof)
    P = 10.0
    f[[model.dof_index(n, "uz") for n in tip]] = P / len(tip)
    u = model.expand(static_solve(model, f))
    EI = mat.E * b * h**3 / 12
    ref = P * L**3 / (3 * EI) + P * L / (5 / 6 * mat.G * b * h)
    assert u[tip, 2].mean() == pytest.approx(ref, rel=2e-3)
    with pytest.raises(DimensionError, match="load must have shape"):
        static_solve(model, np.zeros(3))


def test_reference_surface_offset_is_invariant():
    """Bottom-face reference (B and I1 non-zero) gives the mid-plane model's frequencies."""
    mesh = rectangular_plate_mesh(0.3, 0.05, nx=20, ny=4)
    h = 2e-3
    fixed = (mesh.node_sets["x0"][:, None] * 6 + np.arange(6)).ravel()
    out = []
    for zb in (-h / 2, 0.0):
        lam = Laminate((Ply(STEEL, h),), z_bottom=zb)
        m = assemble_shell_model(mesh.nodes, mesh.elements, np.zeros(len(mesh.elements), int),
                                 [lam], fixed_dofs=fixed)
        out.append(modal_analysis(m, 4).fn_hz)
    np.testing.assert_allclose(out[1], out[0], rtol=2e-3)


def test_static_tip_moment_constant_curvature_and_sign():
    """A moment +My at the free end: ry = My L / EI > 0, w = -My L^2 / (2 EI) (the
    right-hand rotation about +y lifts the +x side down; u = z ry, w,x = -ry)."""
    L, b, h = 0.5, 0.05, 0.002
    mat, model = _beam_strip(L, b, h, 20, clamp="x0")
    tip = model.node_set("x1")
    trib = np.full(len(tip), b / (len(tip) - 1))
    trib[[np.argmin(model.nodes[tip, 1]), np.argmax(model.nodes[tip, 1])]] /= 2
    My = 0.3  # N m total
    f = np.zeros(model.n_dof)
    f[[model.dof_index(n, "ry") for n in tip]] = My * trib / b
    u = model.expand(static_solve(model, f))
    EI = mat.E * b * h**3 / 12
    assert u[tip, 4].mean() == pytest.approx(My * L / EI, rel=1e-6)
    assert u[tip, 2].mean() == pytest.approx(-My * L**2 / (2 * EI), rel=1e-6)


def test_drilling_penalty_leaves_in_plane_bending_unchanged():
    """In-plane tip load on a strip: the drilling term (factor 1e-3) changes the
    deflection by < 1e-4; the bilinear membrane is within 4 % of Timoshenko beam theory
    at 4 elements across the depth (Q4 parasitic shear makes it slightly stiff)."""
    mat = IsotropicMaterial("nu0", 210e9, 0.0, 7850.0)
    L, d, t = 1.0, 0.1, 0.01
    out = []
    for df in (1e-7, 1e-3):
        m = plate_model(L, d, [Ply(mat, t)], nx=40, ny=4, clamp="x0", drill_factor=df)
        tip = m.node_set("x1")
        f = np.zeros(m.n_dof)
        f[[m.dof_index(n, "uy") for n in tip]] = 1.0 / len(tip)
        out.append(m.expand(static_solve(m, f))[tip, 1].mean())
    assert abs(out[1] / out[0] - 1) < 1e-4
    ref = L**3 / (3 * mat.E * t * d**3 / 12) + L / (5 / 6 * mat.G * t * d)
    assert 0.96 < out[1] / ref < 1.0


@pytest.mark.parametrize("shared_shapes", [32, 0])
def test_energy_split_parts_sum_to_the_modal_strain_energy(monkeypatch, shared_shapes):
    """An isotropic plate has no B, D16, D26 coupling: the four parts of energy_split
    sum to phi' K phi = omega^2 of each mass-normalised mode, whether the energies are
    summed per distinct element shape (structured mesh) or per element."""
    import mvtk.fe._modal as modal

    monkeypatch.setattr(modal, "_SHARED_SHAPES", shared_shapes)
    model = plate_model(0.3, 0.2, [Ply(STEEL, 2e-3)], nx=6, ny=5, clamp="x0")
    res = modal_analysis(model, 6)
    parts = modal.energy_split(model, res.shapes)
    np.testing.assert_allclose(parts.sum(axis=1), res.omega2, rtol=1e-9)
    assert res.mode_type[:2] == ("bending", "torsion")
    assert np.all(parts[:, 3] == 0)            # no beam axial part in a shell model
