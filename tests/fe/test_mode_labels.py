"""Mode labels on curved shells: flexural modes whose strain energy is mostly membrane."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtk.fe import build_model, energy_split, modal_analysis, mode_type
from mvtk.fe._mode_labels import normal_kinetic_fraction, shell_node_normals

PANEL = Path(__file__).resolve().parents[2] / "data" / "structures" / "curved_panel"


@pytest.fixture(scope="module")
def panel():
    return build_model(PANEL / "curved_panel.toml")


def _radial(nodes):
    # the example panel is a cylinder of radius 0.5 m about the x axis (curved_panel.geo)
    r = nodes.copy()
    r[:, 0] = 0.0
    return r / np.linalg.norm(r, axis=1)[:, None]


def test_node_normals_are_the_cylinder_radius(panel):
    n = shell_node_normals(panel)
    radial = _radial(panel.nodes)
    angle = np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", n, radial)), 0, 1))
    # facets of a swept cylinder: the area-weighted mean normal is exactly radial at
    # interior nodes (equal facets on both sides) and tilted by half the facet angle at
    # the straight edges (facets on one side only)
    theta = np.arctan2(panel.nodes[:, 1], panel.nodes[:, 2])
    facet = np.diff(np.unique(np.round(theta, 9))).max()
    edge = np.isclose(np.abs(theta), np.abs(theta).max())
    assert edge.sum() > 0 and (~edge).sum() > 0
    assert angle[~edge].max() < 1e-7  # arccos of 1 - 1e-16 (node placement ~4e-10 m)
    np.testing.assert_allclose(angle[edge], facet / 2, rtol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)


def test_normal_share_of_pure_radial_and_pure_axial_motion(panel):
    radial = _radial(panel.nodes)
    full = np.zeros((panel.n_nodes, 6, 2))
    full[:, :3, 0] = radial * np.sin(np.pi * panel.nodes[:, :1] / 0.4)  # along the normal
    full[:, 0, 1] = np.sin(np.pi * panel.nodes[:, 0] / 0.4)            # along the axis
    idx = panel.dof_node * 6 + panel.dof_component
    phi = full.reshape(-1, 2)[idx]
    share = normal_kinetic_fraction(panel, phi, shell_node_normals(panel))
    # radial exactly except at the two straight edges (normal tilted by half a facet)
    np.testing.assert_allclose(share, [1.0, 0.0], atol=1e-4)


def test_curved_panel_flexural_modes_are_not_in_plane(panel):
    res = modal_analysis(panel, 10)
    split = energy_split(panel, res.shapes)
    share = normal_kinetic_fraction(panel, res.shapes, shell_node_normals(panel))
    membrane_largest = split.argmax(axis=1) == 2
    # the premise: most of these flexural modes store the most strain energy in membrane
    assert membrane_largest.sum() >= 5
    # ... yet they move along the surface normal
    assert np.all(share > 0.95), share
    assert "in-plane" not in res.mode_type
    for i in range(10):
        expect = "bending" if split[i, 0] >= split[i, 1] else "torsion"
        if not membrane_largest[i]:
            expect = ["bending", "torsion", "in-plane", "axial"][int(split[i].argmax())]
        assert res.mode_type[i] == expect
        assert mode_type(panel, res.shapes[:, i]) == expect


def test_flat_plate_in_plane_mode_stays_in_plane():
    # a free flat square plate: its first in-plane mode (ux, uy only) is in-plane
    from mvtk.fe import IsotropicMaterial, Ply, plate_model

    mat = IsotropicMaterial("al", 70e9, 0.33, 2700.0)
    model = plate_model(0.3, 0.2, [Ply(mat, 2e-3)], nx=6, ny=4)
    v = np.zeros((model.n_dof, 1))
    x = model.nodes[model.dof_node, 0]
    v[model.dof_component == 0, 0] = x[model.dof_component == 0]  # stretching along x
    assert mode_type(model, v[:, 0]) == "in-plane"
