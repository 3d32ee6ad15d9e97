"""Notebook tables of the main result objects use the report's formatting (issue 18)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mvtk.damping as md
from mvtk.fe import build_model, load_structure, modal_analysis, set_by_path


def test_result_objects_render_like_the_report():
    r = md.rayleigh_fit([13.26, 41.14], [5.84e-4, 1.32e-3])
    html = r._repr_html_()
    assert "<table" in html and "<style" in html and "RayleighFit" in html
    desc = load_structure(Path(__file__).resolve().parents[2] / "data" / "structures"
                          / "smart_beam.toml")
    desc = set_by_path(desc, "mesh.element_size", 0.02)
    modes = modal_analysis(build_model(desc), 3)
    html = modes._repr_html_()
    # frequencies formatted by quantity (5 significant digits), not the raw 17 digits
    f1 = f"{modes.fn_hz[0]:.5g}"
    assert f1 in html and repr(float(modes.fn_hz[0])) not in html
    assert np.isfinite(modes.fn_hz).all()
