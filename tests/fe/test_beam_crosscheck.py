"""Cross-check: Timoshenko beam vs the layered MITC4 plate model on a narrow strip.

With Poisson ratios set to zero a plate strip and a beam have the same bending physics,
so the beam (an independent formulation: exact Timoshenko element, section integrals)
and the shell model must agree on the bending modes and on the static piezo response.
"""

from __future__ import annotations

import numpy as np
import pytest

from mvtk.fe import IsotropicMaterial, PiezoMaterial, Ply
from mvtk.fe._beam import BeamPatch, cantilever_beam
from mvtk.fe._piezo import PiezoPatch

plate = pytest.importorskip("mvtk.fe._plate")
mesh = pytest.importorskip("mvtk.fe._mesh")
modal = pytest.importorskip("mvtk.fe._modal")

STEEL0 = IsotropicMaterial("steel nu=0", 210e9, 0.0, 7900.0)
EPOXY0 = IsotropicMaterial("epoxy nu=0", 3.546e9, 0.0, 1180.0)
PZT0 = PiezoMaterial("PIC151 nu=0", 66.667e9, 0.0, 7800.0, d31=-210e-12)
L, B = 0.2, 0.02
BASE = (Ply(STEEL0, 0.5e-3),)
EXTRA = (Ply(EPOXY0, 36e-6), Ply(PZT0, 0.25e-3))


@pytest.fixture(scope="module")
def models():
    pl = plate.plate_model(L, B, BASE, patches=[(mesh.Patch("p", 0.02, 0.07, 0.0, B), EXTRA)],
                           nx=40, ny=2, clamp="x0")
    bm = cantilever_beam(L, B, BASE, 40, patches=[BeamPatch("p", 0.02, 0.07, EXTRA)])
    return pl, bm


def test_bending_frequencies_agree_with_plate_strip(models):
    pl, bm = models
    fp = modal.modal_analysis(pl, 3).fn_hz
    fb = modal.modal_analysis(bm, 3).fn_hz
    # measured: 1e-4, 1.3e-3, 4.5e-3 (the plate mesh is coarser for the higher modes)
    rel = np.abs(fb - fp) / fp
    assert np.all(rel < [5e-4, 3e-3, 1e-2]), rel


def test_static_piezo_tip_deflection_agrees_with_plate_strip(models):
    pl, bm = models
    patch = PiezoPatch("p", BASE + EXTRA, 2, ("patch:p:x0", "patch:p:x1"), B)
    ub = modal.static_solve(bm, patch.load_vector(bm, 100.0))
    up = modal.static_solve(pl, patch.load_vector(pl, 100.0))
    w_beam = ub[bm.dof_index(bm.node_set("tip")[0], "uz")]
    w_plate = pl.expand(up)[pl.node_set("x1"), 2]
    assert w_beam > 0
    np.testing.assert_allclose(w_plate, w_beam, rtol=1e-3)  # measured 1e-5
