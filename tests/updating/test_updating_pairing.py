"""MAC, mode-type labels and target/mode pairing."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from updating_helpers import NOMINAL, model_fn

from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import FEModel
from mvtk.updating import FrequencyTarget, classify_modes, mac, pair_modes, target_mac


def test_mac_closed_values():
    a = np.array([1.0, 2.0, 3.0])
    b = np.array([3.0, 0.0, -1.0])  # orthogonal to a
    m = mac(np.column_stack([a, b]), np.column_stack([-2 * a, b, np.zeros(3)]))
    assert np.allclose(m, [[1, 0, 0], [0, 1, 0]])
    c = np.array([1.0, 0.0, 0.0])
    assert mac(a, c)[0, 0] == pytest.approx(1 / 14)
    with pytest.raises(DimensionError, match=r"same sensors, got \(3, 1\) and \(2, 1\)"):
        mac(a, np.ones(2))


def _plate_model(nx=5, ny=4, inplane=False):
    x, y = np.meshgrid(np.linspace(0, 0.2, nx), np.linspace(0, 0.1, ny), indexing="ij")
    nodes = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    comps = [2, 0] if inplane else [2]
    dof_node = np.repeat(np.arange(len(nodes)), len(comps))
    dof_comp = np.tile(comps, len(nodes))
    n = dof_node.size
    return FEModel(nodes, sp.identity(n, format="csr"), sp.identity(n, format="csr"),
                   dof_node, dof_comp)


def test_classify_plate_modes_by_width_symmetry():
    m = _plate_model()
    x, y = m.nodes[:, 0], m.nodes[:, 1]
    bend = x**2
    tors = x * (y - 0.05)
    mixed = bend + 0.1 * tors / 0.05  # mostly symmetric
    assert classify_modes(m, np.column_stack([bend, tors, mixed])) == [
        "bending", "torsion", "bending"]


def test_classify_in_plane_and_line_models():
    m = _plate_model(inplane=True)
    v = np.zeros((m.n_dof, 1))
    v[m.dof_component == 0, 0] = 1.0  # ux only
    assert classify_modes(m, v) == ["in-plane"]
    f, eig, beam = model_fn(NOMINAL)
    kinds = classify_modes(beam, eig.vectors)
    # strip 50 mm wide: bending 9.9, 65 Hz, torsion 89 Hz, bending 189 Hz
    assert kinds[:4] == ["bending", "bending", "torsion", "bending"]
    with pytest.raises(DimensionError, match="expected 37 rows of mode shapes, got 3"):
        classify_modes(beam, np.ones((3, 1)))


def test_pair_by_order_and_by_kind():
    fn = np.array([10.0, 60.0, 90.0, 190.0])
    kinds = ["bending", "bending", "torsion", "bending"]
    t = [FrequencyTarget(11.0), FrequencyTarget(85.0)]
    assert pair_modes(t, fn).modes.tolist() == [0, 1]
    tk = [FrequencyTarget(11.0, kind="bending"), FrequencyTarget(85.0, kind="torsion")]
    p = pair_modes(tk, fn, kinds=kinds)
    assert p.modes.tolist() == [0, 2] and p.method == ("order", "order")
    assert np.isnan(p.mac).all()
    pf = pair_modes([FrequencyTarget(11.0), FrequencyTarget(85.0, mode=4)], fn)
    assert pf.modes.tolist() == [0, 3] and pf.method == ("order", "fixed")


def test_pair_by_mac_overrides_order():
    fn = np.array([10.0, 60.0, 90.0])
    rng = np.random.default_rng(1)
    shapes = rng.standard_normal((6, 3))
    model = FEModel(np.column_stack([np.arange(6.0), np.zeros(6), np.zeros(6)]),
                    sp.identity(6, format="csr"), sp.identity(6, format="csr"),
                    np.arange(6), np.full(6, 2))
    # target 1 carries the shape of model mode 3, target 2 that of mode 2
    t = [FrequencyTarget(60.0, shape={(i, "uz"): v for i, v in enumerate(shapes[:, 2])}),
         FrequencyTarget(95.0, shape={(i, "uz"): v for i, v in enumerate(shapes[:, 1])})]
    mm = target_mac(model, shapes, t)
    p = pair_modes(t, fn, mm)
    assert p.modes.tolist() == [2, 1] and p.method == ("mac", "mac")
    assert np.allclose(p.mac, 1.0)


def test_pairing_errors():
    fn = np.array([10.0, 60.0])
    with pytest.raises(ParameterError, match="3 targets need at least as many model modes, got 2"):
        pair_modes([FrequencyTarget(1.0)] * 3, fn)
    with pytest.raises(ParameterError, match="asks for model mode 5 but only 2 modes"):
        pair_modes([FrequencyTarget(1.0, mode=5)], fn)
    with pytest.raises(ParameterError, match="model mode 1 is requested by two targets"):
        pair_modes([FrequencyTarget(1.0, mode=1), FrequencyTarget(2.0, mode=1)], fn)
    with pytest.raises(ParameterError, match=r"\(85 Hz, torsion\) has no free model mode"):
        pair_modes([FrequencyTarget(85.0, kind="torsion")], fn, kinds=["bending", "bending"])
    t = [FrequencyTarget(1.0, shape={(0, "uz"): 1.0, (1, "uz"): 2.0})]
    with pytest.raises(ParameterError, match="no MAC matrix"):
        pair_modes(t, fn)
    _, eig, beam = model_fn(NOMINAL, n=3)
    bad = [FrequencyTarget(1.0, shape={(0, "uz"): 1.0, (1, "uz"): 2.0})]
    with pytest.raises(ParameterError, match="sensor DOF: DOF uz of node 0 is constrained"):
        target_mac(beam, eig.vectors, bad)


def test_strip_test_builder_matches_closed_forms():
    """The test builder is a real cantilever: Euler-Bernoulli and St-Venant torsion."""
    d = {**{k: v for k, v in NOMINAL.items() if k != "boundary"}, "tip_mass": 0.0}
    f, _, _ = model_fn(d, n=4)
    E, nu, rho = 2.1e11, 0.3, 7850.0
    L, b, t = 0.18, 0.05, 5e-4
    c = np.sqrt(E * b * t**3 / 12 / (rho * b * t * L**4)) / (2 * np.pi)
    assert f[0] == pytest.approx(1.875104069**2 * c, rel=1e-5)
    assert f[1] == pytest.approx(4.694091133**2 * c, rel=1e-4)
    G = E / (2 * (1 + nu))
    ft = np.sqrt(G * b * t**3 / 3 / (rho * (b * t**3 + t * b**3) / 12)) / (4 * L)
    assert f[2] == pytest.approx(ft, rel=2e-3)  # linear torsion elements, 12 of them

_finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(a=arrays(float, (6, 2), elements=_finite), b=arrays(float, (6, 3), elements=_finite),
       k=st.floats(-1e3, 1e3).filter(lambda v: abs(v) > 1e-3))
def test_mac_properties(a, b, k):
    m = mac(a, b)
    assert m.shape == (2, 3)
    assert np.all((m >= 0) & (m <= 1))
    np.testing.assert_allclose(m, mac(b, a).T, atol=1e-12)
    # invariant to scaling (and sign) of either shape
    np.testing.assert_allclose(mac(k * a, b), m, atol=1e-9)
    nz = np.einsum("ij,ij->j", a, a) > 1e-12
    np.testing.assert_allclose(np.diag(mac(a, a))[nz], 1.0, atol=1e-9)
