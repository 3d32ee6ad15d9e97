"""``[[masses]]`` on every structure type (generated plate and beam, as on meshes), with
rotated inertia tensors, and ``FEModel.dof_index`` by node index or node ID.

External truths: the exact frequency equation of a cantilever with a tip mass
(Euler-Bernoulli; e.g. Blevins, "Formulas for natural frequency and mode shape", table
8-1, case 1), and the rotary inertia of a slender rod, m L^2 / 12 about any axis normal
to it, rotated to global axes by hand.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.optimize import brentq

from mvtk.errors import ConfigError, ParameterError
from mvtk.fe import build_model, modal_analysis

STEEL = {"E": 210e9, "nu": 0.3, "rho": 7850.0}
L, B, H = 0.4, 0.02, 0.003


def _beam(n=80) -> dict:
    return {"name": "beam", "materials": {"steel": dict(STEEL)},
            "structure": {"type": "beam", "length": L, "width": B,
                          "layers": [{"material": "steel", "thickness": H}]},
            "mesh": {"n_elements": n}, "boundary": {"clamp": "x0"},
            "points": [{"name": "tip", "x": L}]}


def _lambda_tip_mass(mu: float) -> float:
    """First root of 1 + cos l cosh l + mu l (cos l sinh l - sin l cosh l) = 0."""
    def g(x):
        return (1 + np.cos(x) * np.cosh(x)
                + mu * x * (np.cos(x) * np.sinh(x) - np.sin(x) * np.cosh(x)))
    return brentq(g, 0.3, 1.8751)


def test_tip_mass_on_a_generated_beam_matches_the_exact_frequency_equation():
    mass_beam = STEEL["rho"] * B * H * L
    f0 = modal_analysis(build_model(_beam()), 1).fn_hz[0]
    for mu in (0.2, 1.0):
        d = _beam()
        d["masses"] = [{"point": "tip", "mass": mu * mass_beam}]
        f = modal_analysis(build_model(d), 1).fn_hz[0]
        ratio = (_lambda_tip_mass(mu) / 1.8751040687) ** 2
        assert f / f0 == pytest.approx(ratio, rel=2e-3)


def _free_plate() -> dict:
    return {"name": "plate", "materials": {"steel": dict(STEEL)},
            "structure": {"type": "plate", "length": 0.3, "width": 0.2,
                          "layers": [{"material": "steel", "thickness": 2e-3}]},
            "mesh": {"nx": 6, "ny": 4},
            "points": [{"name": "sensor", "x": 0.15, "y": 0.1}]}


def _rigid_rotation(model, node: int, axis) -> np.ndarray:
    """Free-DOF vector of a unit rigid rotation about ``axis`` through ``node``."""
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.zeros(model.n_dof)
    r = model.nodes[model.dof_node] - model.nodes[node]
    for k in range(model.n_dof):
        c = int(model.dof_component[k])
        u[k] = np.cross(e, r[k])[c] if c < 3 else e[c - 3]
    return u


def test_rotated_inertia_of_a_rod_on_a_generated_plate():
    """A 20 g rod of 60 mm lying along (1, 1, 0)/sqrt(2): body inertia diag(0, J, J),
    J = m L^2 / 12; about global z J, about global x and y J / 2 (by hand)."""
    m, rod = 0.020, 0.060
    J = m * rod ** 2 / 12
    c = 1 / np.sqrt(2)
    axes = [[c, c, 0.0], [-c, c, 0.0], [0.0, 0.0, 1.0]]
    base = build_model(_free_plate())
    node = int(base.node_sets["sensor"][0])
    d = _free_plate()
    d["masses"] = [{"point": "sensor", "mass": m, "inertia": [0.0, J, J], "axes": axes}]
    model = build_model(d)
    for axis, want in (([0, 0, 1], J), ([1, 0, 0], J / 2), ([0, 1, 0], J / 2),
                       ([1, 1, 0], 0.0), ([1, -1, 0], J)):
        u = _rigid_rotation(model, node, axis)
        added = u @ (model.M @ u) - u @ (base.M @ u)
        assert added == pytest.approx(want, rel=1e-9, abs=1e-15)
    # the translation carries the mass; the same tensor as 6 entries gives the same M
    t = np.where(model.dof_component == 2, 1.0, 0.0)
    assert t @ (model.M @ t) - t @ (base.M @ t) == pytest.approx(m, rel=1e-12)
    d6 = copy.deepcopy(d)
    Jg = np.array(axes).T @ np.diag([0.0, J, J]) @ np.array(axes)
    d6["masses"][0].pop("axes")
    d6["masses"][0]["inertia"] = [Jg[0, 0], Jg[1, 1], Jg[2, 2], Jg[0, 1], Jg[1, 2], Jg[0, 2]]
    assert abs(build_model(d6).M - model.M).max() < 1e-15


def test_masses_refuse_a_bad_point_or_tensor():
    d = _free_plate()
    d["masses"] = [{"point": "nowhere", "mass": 0.01}]
    with pytest.raises(ConfigError, match=r"masses\[0\]\.point.*'nowhere'.*sensor"):
        build_model(d)
    d["masses"] = [{"point": "sensor", "mass": 0.01, "inertia": [1.0, 2.0]}]
    with pytest.raises(ConfigError, match=r"masses\[0\]\.inertia"):
        build_model(d)
    d["masses"] = [{"point": "sensor", "mass": 0.01, "inertia": [1, 1, 1],
                    "axes": [[1, 0, 0], [1, 0, 0], [0, 0, 1]]}]
    with pytest.raises(ConfigError, match=r"masses\[0\]\.axes.*orthonormal"):
        build_model(d)


def test_dof_index_by_index_or_by_id():
    model = build_model(_free_plate())
    node = int(model.node_sets["sensor"][0])
    node_id = int(model.node_ids[node]) if model.node_ids is not None else node + 1
    assert model.dof_index(node_id, "uz", by="id") == model.dof_index(node, "uz")
    assert model.node_index(node_id) == node
    with pytest.raises(ParameterError, match="no node has the ID"):
        model.dof_index(10 ** 6, "uz", by="id")
    with pytest.raises(ParameterError, match="by must be"):
        model.dof_index(node, "uz", by="label")
