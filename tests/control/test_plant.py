"""Structural plant from a super element or FE model vs direct harmonic solves."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from mvtk.control import SecondOrderSystem, StateSpace
from mvtk.control import _plant as plant_module
from mvtk.control._plant import StructuralPlant, dof_load, structural_plant
from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import IsotropicMaterial, Ply
from mvtk.fe._beam import cantilever_beam
from mvtk.reduction import craig_bampton
from mvtk.reduction._examples import eb_beam_xz

ALPHA, BETA = 0.02955, 9.77e-6  # the paper's half-power Rayleigh pair (Table 3)
STEEL = IsotropicMaterial("steel", E=210e9, nu=0.3, rho=7900.0)


@pytest.fixture(scope="module")
def beam():
    return eb_beam_xz(n_el=40)


@pytest.fixture(scope="module")
def se(beam):
    return craig_bampton(beam, ["mid", "tip"], 6)


def harmonic(model, f, rows, freqs_hz, alpha=ALPHA, beta=BETA):
    """Direct solve (K - w^2 M + i w C) x = f of the full model; returns rows @ x."""
    K, M = model.K.toarray(), model.M.toarray()
    C = alpha * M + beta * K
    out = []
    for fk in freqs_hz:
        w = 2 * np.pi * fk
        out.append(rows @ np.linalg.solve(K - w**2 * M + 1j * w * C, f))
    return np.array(out).T


FREQS = np.array([0.0, 2.0, 6.0, 30.0, 45.0])  # away from resonances (10.41, 65.24 Hz)
RESONANCES = np.array([10.41085, 65.2437])


def second_order_frf(p, freqs_hz):
    """Cq (K - w^2 M + i w C)^-1 B + i w Cv (...)^-1 B evaluated from the plant matrices."""
    out = []
    for fk in freqs_hz:
        w = 2 * np.pi * fk
        x = np.linalg.solve(p.K - w**2 * p.M + 1j * w * p.C, p.B)
        out.append(p.Cq @ x + 1j * w * p.Cv @ x)
    return np.moveaxis(np.array(out), 0, -1)


def test_se_frequency_response_matches_full_harmonic_solve(beam, se):
    p = structural_plant(se, {"M_mid": (20, "ry")},
                         {"w_tip": (40, "uz"), "v_tip": (40, "uz", "velocity")},
                         alpha=ALPHA, beta=BETA)
    ss = p.to_state_space()
    H = ss.frequency_response(FREQS)
    f = dof_load(beam, 20, "ry")
    ref = harmonic(beam, f, np.eye(beam.n_dof)[[beam.dof_index(40, "uz")]], FREQS)[0]
    np.testing.assert_allclose(H[0, 0], ref, rtol=1e-4)
    np.testing.assert_allclose(H[1, 0], 2j * np.pi * FREQS * ref, rtol=1e-4, atol=1e-12)
    # DC exact for boundary input and output (constraint modes are statically exact)
    np.testing.assert_allclose(ss.dc_gain()[0, 0], ref[0], rtol=1e-9)


def test_se_with_all_modes_matches_at_resonance(beam):
    se_all = craig_bampton(beam, ["mid", "tip"], beam.n_dof - 4)
    p = structural_plant(se_all, [(20, "ry")], [(40, "uz")], alpha=ALPHA, beta=BETA)
    f = dof_load(beam, 20, "ry")
    ref = harmonic(beam, f, np.eye(beam.n_dof)[[beam.dof_index(40, "uz")]], RESONANCES)[0]
    np.testing.assert_allclose(second_order_frf(p, RESONANCES)[0, 0], ref, rtol=1e-6)


def test_full_model_plant_is_exact(beam):
    p = structural_plant(beam, [(20, "ry")], [(40, "uz"), (30, "ry", "velocity")],
                         alpha=ALPHA, beta=BETA)
    freqs = np.concatenate([FREQS, RESONANCES])
    f = dof_load(beam, 20, "ry")
    rows = np.eye(beam.n_dof)[[beam.dof_index(40, "uz"), beam.dof_index(30, "ry")]]
    ref = harmonic(beam, f, rows, freqs)
    ref[1] *= 2j * np.pi * freqs
    np.testing.assert_allclose(second_order_frf(p, freqs)[:, 0, :], ref, rtol=1e-10,
                               atol=1e-14)
    # through the state space: conditioning of A (M^-1 K up to ~1e12) costs digits
    H = p.to_state_space().frequency_response(freqs)
    np.testing.assert_allclose(H[:, 0, :], ref, rtol=1e-4)
    assert p.coords[:2] == ("n1:uz", "n1:ry")


def test_modal_form_all_modes_equals_physical(se):
    kw = dict(inputs={"M": (20, "ry")}, outputs={"w": (40, "uz")}, alpha=ALPHA, beta=BETA)
    phys = structural_plant(se, **kw).to_state_space()
    modal = structural_plant(se, form="modal", **kw)
    # Rayleigh damping is exactly diagonal in modal coordinates
    w2 = np.diag(modal.K)
    np.testing.assert_allclose(modal.C, np.diag(ALPHA + BETA * w2), atol=0)
    np.testing.assert_allclose(modal.M, np.eye(se.n_dof))
    np.testing.assert_allclose(np.sqrt(w2) / (2 * np.pi), modal.meta["fn_hz"])
    h1 = phys.frequency_response(FREQS)
    h2 = modal.to_state_space().frequency_response(FREQS)
    np.testing.assert_allclose(h2, h1, rtol=1e-7)
    assert modal.coords[0] == "mode1" and not modal.meta["static_correction"]


def test_truncation_with_static_correction_keeps_dc_gain(beam, se):
    kw = dict(inputs=[(20, "ry")], outputs=[(40, "uz"), (40, "uz", "velocity")],
              alpha=ALPHA, beta=BETA, form="modal", n_modes=2)
    corr = structural_plant(se, **kw)
    plain = structural_plant(se, static_correction=False, **kw)
    exact = np.linalg.solve(beam.K.toarray(), dof_load(beam, 20, "ry"))[
        beam.dof_index(40, "uz")]
    ss = corr.to_state_space()
    assert ss.D[0, 0] != 0 and ss.D[1, 0] == 0  # no static correction on velocity
    np.testing.assert_allclose(ss.dc_gain()[0, 0], exact, rtol=1e-9)
    err_plain = abs(plain.to_state_space().dc_gain()[0, 0] / exact - 1)
    assert err_plain > 1e-4
    # near mode 1 the corrected truncated model stays close to the full SE
    full = structural_plant(se, inputs=[(20, "ry")], outputs=[(40, "uz")],
                            alpha=ALPHA, beta=BETA).to_state_space()
    f = np.array([1.0, 10.0, 20.0])
    np.testing.assert_allclose(ss.frequency_response(f)[0], full.frequency_response(f)[0],
                               rtol=1e-3)
    assert isinstance(corr, SecondOrderSystem) and isinstance(corr, StructuralPlant)


def test_full_model_modal_form_static_correction(beam):
    p = structural_plant(beam, [(20, "ry")], [(40, "uz")], form="modal", n_modes=3)
    exact = np.linalg.solve(beam.K.toarray(), dof_load(beam, 20, "ry"))[
        beam.dof_index(40, "uz")]
    np.testing.assert_allclose(p.to_state_space().dc_gain()[0, 0], exact, rtol=1e-9)


def test_modal_damping_sets_pole_damping(se):
    p = structural_plant(se, [(40, "uz")], [(40, "uz")], modal_damping=0.02, form="modal")
    poles = p.to_state_space().poles()
    zeta = -poles.real / np.abs(poles)
    np.testing.assert_allclose(zeta, 0.02, rtol=1e-8)
    p2 = structural_plant(se, [(40, "uz")], [(40, "uz")], modal_damping=0.02)
    poles2 = np.sort_complex(p2.to_state_space().poles())
    np.testing.assert_allclose(np.sort_complex(poles), poles2, rtol=1e-7)
    zs = np.linspace(0.01, 0.02, 3)
    p3 = structural_plant(se, [(40, "uz")], [(40, "uz")], modal_damping=zs, form="modal",
                          n_modes=3)
    np.testing.assert_allclose(np.diag(p3.C), 2 * zs * np.sqrt(np.diag(p3.K)))


def test_pin_force_moment_pair_and_strain_output():
    """Patch as equal and opposite moments at its ends (Crawley & de Luis 1987); output
    the rotation difference over the patch (proportional to the mean surface strain)."""
    model = cantilever_beam(0.18, 0.02, [Ply(STEEL, 0.5e-3)], 36,
                            points={"p0": 0.005, "p1": 0.055, "sensor": 0.12})
    n0 = int(model.node_set("p0")[0])
    n1 = int(model.node_set("p1")[0])
    tip = int(model.node_set("tip")[0])
    load = dof_load(model, n1, "ry") - dof_load(model, n0, "ry")  # N m per unit input
    strain_row = dof_load(model, n1, "ry") - dof_load(model, n0, "ry")
    se = craig_bampton(model, ["p0", "p1", "sensor", "tip"], 10)
    p = structural_plant(se, {"V": load}, {"dtheta": strain_row, "w_tip": (tip, "uz")},
                         input_units=["V"], alpha=ALPHA, beta=BETA)
    ss = p.to_state_space()
    assert ss.inputs == ("V",) and ss.outputs == ("dtheta", "w_tip")
    assert ss.input_units == ("V",) and ss.output_units == ("", "m")
    x = np.linalg.solve(model.K.toarray(), load)
    np.testing.assert_allclose(ss.dc_gain()[:, 0],
                               [strain_row @ x, x[model.dof_index(tip, "uz")]], rtol=1e-8)
    f = np.array([5.0, 12.0, 40.0])
    ref = harmonic(model, load, np.vstack([strain_row, dof_load(model, tip, "uz")]), f)
    np.testing.assert_allclose(ss.frequency_response(f)[:, 0, :], ref, rtol=1e-3)


def test_scipy_and_control_interop(se):
    ss = structural_plant(se, [(20, "ry")], [(40, "uz")], alpha=ALPHA, beta=BETA,
                          form="modal", n_modes=3).to_state_space()
    f = np.array([3.0, 11.0])
    w, h = ss.to_scipy().freqresp(w=2 * np.pi * f)
    np.testing.assert_allclose(h, ss.frequency_response(f)[0, 0], rtol=1e-10)
    back = StateSpace.from_scipy(ss.to_scipy())
    np.testing.assert_allclose(back.D, ss.D)
    control = pytest.importorskip("control")
    sysc = ss.to_control()
    assert list(sysc.input_labels) == ["f:n20:ry"] and list(sysc.output_labels) == ["u:n40:uz"]
    np.testing.assert_allclose(control.dcgain(sysc), ss.dc_gain()[0, 0], rtol=1e-9)


def test_default_names_and_units(se):
    p = structural_plant(se, [(40, "uz"), (20, "ry")],
                         [(40, "ry"), (40, "uz", "velocity"), (20, "ry", "velocity")])
    assert p.inputs == ("f:n40:uz", "f:n20:ry")
    assert p.input_units == ("N", "N m")
    assert p.outputs == ("u:n40:ry", "v:n40:uz", "v:n20:ry")
    assert p.output_units == ("rad", "m/s", "rad/s")
    assert p.meta["source"] == "super_element" and p.meta["form"] == "physical"
    np.testing.assert_allclose(p.C, 0.0)


def test_bad_inputs(beam, se, monkeypatch):
    ok_in, ok_out = [(40, "uz")], [(40, "uz")]
    with pytest.raises(ParameterError, match="expected a SuperElement or an FEModel"):
        structural_plant(np.eye(2), ok_in, ok_out)
    with pytest.raises(ParameterError, match="form must be 'physical' or 'modal'"):
        structural_plant(se, ok_in, ok_out, form="balanced")
    with pytest.raises(ParameterError, match="Rayleigh coefficients must be >= 0"):
        structural_plant(se, ok_in, ok_out, alpha=-1.0)
    with pytest.raises(ParameterError, match="either Rayleigh alpha/beta or modal_damping"):
        structural_plant(se, ok_in, ok_out, beta=1e-5, modal_damping=0.01)
    with pytest.raises(ParameterError, match="quantity must be one of"):
        structural_plant(se, ok_in, [(40, "uz", "acceleration")])
    with pytest.raises(DimensionError, match=r"must have shape \(80,\)"):
        structural_plant(se, [np.ones(5)], ok_out)
    with pytest.raises(DimensionError, match=r"output 'y': a vector spec must have shape"):
        structural_plant(se, ok_in, {"y": np.ones(3)})
    with pytest.raises(ParameterError, match="a DOF input is \\(node, component\\)"):
        structural_plant(se, [(40, "uz", "velocity")], ok_out)
    with pytest.raises(ParameterError, match="n_modes applies to form='modal' only"):
        structural_plant(se, ok_in, ok_out, n_modes=2)
    with pytest.raises(ParameterError, match="needs n_modes"):
        structural_plant(beam, ok_in, ok_out, form="modal")
    with pytest.raises(ParameterError, match=r"n_modes must be in 1..10 \(SE modes of finite"):
        structural_plant(se, ok_in, ok_out, form="modal", n_modes=11)
    with pytest.raises(DimensionError, match="modal_damping must be one ratio or one per"):
        structural_plant(se, ok_in, ok_out, form="modal", n_modes=2, modal_damping=[0.1] * 3)
    with pytest.raises(ParameterError, match="damping ratios must be >= 0"):
        structural_plant(se, ok_in, ok_out, form="modal", modal_damping=-0.1)
    with pytest.raises(DimensionError, match="expected 1 input units, got 2"):
        structural_plant(se, ok_in, ok_out, input_units=["V", "V"])
    with pytest.raises(DimensionError, match="expected 1 output units, got 0"):
        structural_plant(se, ok_in, ok_out, output_units=[])
    with pytest.raises(ParameterError, match="at least one input is needed"):
        structural_plant(se, [], ok_out)
    with pytest.raises(ParameterError, match="mapping name -> spec or a sequence"):
        structural_plant(se, 3.0, ok_out)
    with pytest.raises(ParameterError, match="DOF uz of node 0 is constrained"):
        structural_plant(se, [(0, "uz")], ok_out)
    monkeypatch.setattr(plant_module, "MAX_DENSE_DOF", 50)
    with pytest.raises(ParameterError, match="physical form is limited to 50"):
        structural_plant(beam, ok_in, ok_out)
    free = eb_beam_xz(n_el=10, clamped=False)
    with pytest.raises(ParameterError, match="static correction needs a restrained"):
        structural_plant(free, [(5, "uz")], [(10, "uz")], form="modal",
                         n_modes=3)


def test_se_with_free_free_base_is_restrained_by_boundary():
    """A free-free model reduced with its base as boundary; constraining nothing leaves
    rigid-body modes, which the physical form accepts."""
    model = eb_beam_xz(n_el=10, clamped=False)
    se = craig_bampton(model, ["clamp", "tip"], 3)
    p = structural_plant(se, [(10, "uz")], [(10, "uz")])
    w2 = sla.eigh(p.K, p.M, eigvals_only=True)
    assert abs(w2[0]) < 1e-6 * w2[2] and abs(w2[1]) < 1e-6 * w2[2]


def test_piezo_patch_input_in_volts():
    """Volts in through the FE layer's piezo relation (paper eqs. 1-7, pin-force edges)."""
    piezo = pytest.importorskip("mvtk.fe._piezo")
    from mvtk.fe import PiezoMaterial

    pic151 = PiezoMaterial("pic151", E=66.667e9, nu=0.34, rho=7800.0, d31=-210e-12)
    epoxy = IsotropicMaterial("epoxy", E=3.546e9, nu=0.35, rho=1180.0)
    model = cantilever_beam(
        0.18, 0.03, [Ply(STEEL, 0.5e-3)], 36,
        patches=[{"name": "pzt", "x0": 0.005, "x1": 0.055,
                  "layers": (Ply(epoxy, 36e-6), Ply(pic151, 0.25e-3))}],
    )
    patch = piezo.PiezoPatch.on_beam(model, "pzt")
    se = craig_bampton(model, ["patch:pzt:x0", "patch:pzt:x1", "tip"], 8)
    tip = int(model.node_set("tip")[0])
    p = structural_plant(se, [patch], {"w_tip": (tip, "uz")}, alpha=ALPHA, beta=BETA,
                         form="modal", n_modes=4)
    ss = p.to_state_space()
    assert ss.inputs == ("pzt",) and ss.input_units == ("V",)
    single = structural_plant(se, patch, (tip, "uz"))  # one spec, not a list
    assert single.inputs == ("pzt",) and single.outputs == (f"u:n{tip}:uz",)
    x = np.linalg.solve(model.K.toarray(), patch.load_vector(model))
    w_tip = x[model.dof_index(tip, "uz")]
    np.testing.assert_allclose(ss.dc_gain()[0, 0], w_tip, rtol=1e-8)
    assert w_tip > 0  # d31 < 0, patch on top: positive volts bend the tip up (+z)


def test_shell_super_element_modal_form_and_massless_warning():
    """MITC4 plate SE (smart beam, coarse): boundary drilling rotations carry no inertia.
    The physical form warns; the truncated modal form keeps the DC gain and is not stiff."""
    import tomllib
    from pathlib import Path

    from mvtk.errors import AccuracyWarning
    from mvtk.fe import build_model, factorize

    text = (Path(__file__).resolve().parents[2] / "data" / "structures" /
            "smart_beam.toml").read_text().replace("element_size = 0.005",
                                                   "element_size = 0.01")
    model = build_model(tomllib.loads(text))
    nodes = [model.nearest_node(p) for p in
             ([0.005, 0.0665, 0], [0.055, 0.0665, 0], [0.18, 0.0665, 0])]
    se = craig_bampton(model, nodes, 10)
    f = dof_load(model, nodes[1], "ry") - dof_load(model, nodes[0], "ry")
    kw = dict(inputs={"M": f}, outputs={"w": (nodes[2], "uz")}, alpha=ALPHA, beta=BETA)
    with pytest.warns(AccuracyWarning, match="no inertia"):
        structural_plant(se, **kw)
    ss = structural_plant(se, form="modal", n_modes=8, **kw).to_state_space()
    static = factorize(model.K).solve(f)[model.dof_index(nodes[2], "uz")]
    np.testing.assert_allclose(ss.dc_gain()[0, 0], static, rtol=1e-8)
    assert np.abs(ss.poles()).max() < 2 * np.pi * 2000.0
    ref = harmonic(model, f, dof_load(model, nodes[2], "uz")[None, :], [5.0, 20.0])[0]
    np.testing.assert_allclose(ss.frequency_response([5.0, 20.0])[0, 0], ref, rtol=1e-3)


def test_static_correction_accepts_a_restrained_shell_super_element():
    """Regression: the restraint check used K_ii/M_ii as scale, which the nearly massless
    drilling coordinates of a shell super element inflate; mode 1 of a clamped plate
    strip was then taken for a rigid-body mode."""
    from mvtk.fe import plate_model

    model = plate_model(0.18, 0.04, [Ply(STEEL, 0.5e-3)], nx=12, ny=3, clamp="x0",
                        points={"tip": (0.18, 0.02)})
    tip = int(model.node_set("tip")[0])
    se = craig_bampton(model, ["tip"], 4)
    p = structural_plant(se, [(tip, "uz")], [(tip, "uz")], form="modal", n_modes=2,
                         static_correction=True)
    static = mvtk_static_tip(model, tip)
    np.testing.assert_allclose(p.to_state_space().dc_gain()[0, 0], static, rtol=1e-6)


def mvtk_static_tip(model, tip):
    from mvtk.fe import static_solve

    f = np.zeros(model.n_dof)
    f[model.dof_index(tip, "uz")] = 1.0
    return static_solve(model, f)[model.dof_index(tip, "uz")]
