"""Animated 3-D mode shapes in the self-contained report page.

Truth: a rectangular grid of m x n points triangulates into (m-1) n + m (n-1) grid
edges and (m-1)(n-1) diagonals (Euler's formula for a triangulated rectangle); the
page loads nothing from elsewhere and, in Chromium, draws frames that change with time.
"""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ParameterError
from mvtk.plot import mesh_edges, mode_animation_html
from mvtk.report import Report

_spec = importlib.util.spec_from_file_location(
    "mvtk_tests_chromium_anim", Path(__file__).with_name("_chromium.py"))
cr = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cr)


def _plate(m=9, n=5):
    x, y = np.meshgrid(np.linspace(0, 0.3, m), np.linspace(0, 0.1, n), indexing="ij")
    xyz = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    # cantilever-like bending and torsion shapes (z)
    s = np.column_stack([(xyz[:, 0] / 0.3) ** 2, (xyz[:, 0] / 0.3) * (xyz[:, 1] - 0.05)])
    return xyz, s


@pytest.mark.parametrize(("m", "n"), [(4, 3), (9, 5)])
def test_mesh_edges_of_a_grid(m, n):
    xyz, _ = _plate(m, n)
    e = mesh_edges(xyz)
    assert len(e) == (m - 1) * n + m * (n - 1) + (m - 1) * (n - 1)
    assert len(np.unique(np.sort(e, axis=1), axis=0)) == len(e)
    # a line of points is a polyline
    line = np.column_stack([np.linspace(0, 1, 5), np.zeros(5), np.zeros(5)])
    assert sorted(map(tuple, np.sort(mesh_edges(line), axis=1))) == [(0, 1), (1, 2), (2, 3),
                                                                     (3, 4)]


def test_animation_html_is_self_contained_and_carries_the_shapes():
    xyz, s = _plate()
    test = xyz[::4]
    out = mode_animation_html(xyz, s, ["bending", "torsion"],
                              overlay={"xyz": test, "shapes": s[::4] * 3.0, "name": "test"})
    assert "http" not in out and "src=" not in out
    data = json.loads(re.search(r'type="application/json"[^>]*>(.*?)</script>', out,
                                re.S).group(1))
    fe, ov = data["layers"]
    assert len(fe["xyz"]) == len(xyz) and len(ov["xyz"]) == len(test)
    # each shape normalised to a largest displacement of 1 (drawn at one amplitude)
    u = np.array(fe["modes"][1]["u"])
    assert np.abs(u).max() == pytest.approx(1.0)
    # written with a resolution of 1e-3 of the largest value (half of it at most off)
    np.testing.assert_allclose(u[:, 2], s[:, 1] / np.abs(s[:, 1]).max(), atol=5.01e-4)
    with pytest.raises(ParameterError, match="2 shapes but 1 labels"):
        mode_animation_html(xyz, s, ["one"])
    with pytest.raises(ParameterError, match="shapes must have 45 rows"):
        mode_animation_html(xyz, s[:10], ["a", "b"])


def test_animation_plays_offline_in_chromium(tmp_path):
    exe = cr.find_chromium()
    if exe is None:
        pytest.skip("chromium not installed (run tests/report/install_chromium.sh as root)")
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    xyz, s = _plate()
    rep = Report("animation")
    rep.section("Shapes").mode_animation(xyz, s, ["mode 1", "mode 2"], "two modes",
                                         overlay={"xyz": xyz[::4], "shapes": s[::4]})
    page = rep.write(tmp_path / "out")
    snap = ("(() => { const c = document.getElementById('mode-animation-1');"
            " const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;"
            " let h = 0, ink = 0; for (let i = 0; i < d.length; i += 4) {"
            " if (d[i + 3]) { ink++; h = (h * 31 + d[i] + 7 * i) % 1000000007; } }"
            " return [+c.dataset.frames, ink, h]; })()")
    select = ("(() => { const s = document.getElementById('mode-animation-1-mode');"
              " s.value = '1'; s.dispatchEvent(new Event('change')); return s.value; })()")
    (a, b, _, c), errors = cr.evaluate_after(exe, page, tmp_path / "ud",
                                             [snap, snap, select, snap], wait_s=0.4)
    assert errors == []
    assert a[1] > 1000                       # the canvas is drawn
    assert b[0] > a[0] and b[2] != a[2]      # frames advance and the picture moves
    assert c[1] > 1000 and c[2] not in (a[2], b[2])
