"""The report page in a real headless browser (Debian chromium).

Skips with a reason when chromium is not on PATH (``tests/report/install_chromium.sh``
installs it). Checks, through the DevTools protocol, that the page loads without console
errors or exceptions and that every figure is decoded (naturalWidth > 0); also checks
``--dump-dom`` and keeps a screenshot in ``tests/artifacts/``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from mvtk.plot import plot_decay, plot_frf, plot_mode_shapes, plot_spectra, plot_time_responses
from mvtk.report import Report, collect_provenance
from mvtk.validation import Check, check_table, frequency_table

_spec = importlib.util.spec_from_file_location(
    "mvtk_tests_chromium", Path(__file__).with_name("_chromium.py"))
cr = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cr)


@pytest.fixture(scope="module")
def chromium() -> str:
    exe = cr.find_chromium()
    if exe is None:
        pytest.skip("chromium not installed (run tests/report/install_chromium.sh as root)")
    return exe


@pytest.fixture(scope="module")
def report_page(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("report")
    rep = Report("mvtk browser test")
    f = np.linspace(5, 50, 901)
    w, wn = 2 * np.pi * f, 2 * np.pi * 13.26
    H = 1 / (wn**2 - w**2 + 2j * 0.01 * wn * w)
    t = np.arange(2000) / 200.0
    x = np.exp(-0.5 * t) * np.sin(2 * np.pi * 13.26 * t)
    gx, gy = np.meshgrid(np.linspace(0, 0.18, 13), np.linspace(0, 0.133, 9))
    nodes = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
    uz = np.c_[nodes[:, 0] ** 2, nodes[:, 0] * (nodes[:, 1] - 0.0665)]
    rep.section("Figures").figure(plot_frf(f, H, bands=[(13.1, 13.4, 13.26)]), "FRF") \
        .figure(plot_decay(t, x, fit=np.exp(-0.5 * t)), "decay") \
        .figure(plot_mode_shapes(nodes, uz, [13.26, 41.14]), "modes") \
        .figure(plot_time_responses(t, {"open": x, "ppf": x * np.exp(-t)}, zoom=(0, 1)), "tip") \
        .figure(plot_spectra(f, {"open": np.abs(H), "ppf": np.abs(H) / 3}), "spectra")
    rep.section("Tables").table(
        frequency_table({"test": [13.26, 41.14], "FE": [13.81, 42.67]}, "test"), "t2",
        "Table 2").table(check_table([Check("f1", 13.3, 13.26, 0.01, "Hz")]), "checks")
    rep.add_provenance(collect_provenance([], {"study": "browser test"}))
    return rep.write(out)


def test_dump_dom_and_screenshot(chromium, report_page, tmp_path):
    url = report_page.as_uri()
    dom = cr.run_cmd([chromium, *cr.FLAGS, f"--user-data-dir={tmp_path / 'ud1'}", "--dump-dom",
                      url])
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert dom.stdout.count('class="report-figure"') == 5
    assert "1 of 1 checks passed" in dom.stdout
    cr.ARTIFACTS.mkdir(exist_ok=True)
    shot = cr.ARTIFACTS / "report_screenshot.png"
    shot.unlink(missing_ok=True)
    res = cr.run_cmd([chromium, *cr.FLAGS, f"--user-data-dir={tmp_path / 'ud2'}",
                f"--screenshot={shot}", "--window-size=1280,2400", url])
    assert res.returncode == 0, res.stderr[-2000:]
    assert shot.read_bytes().startswith(b"\x89PNG") and shot.stat().st_size > 10_000


def test_devtools_no_console_errors_and_images_decoded(chromium, report_page, tmp_path):
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    images, errors = cr.inspect_page(chromium, report_page, tmp_path / "ud3")
    assert len(images) == 5
    assert all(done and width > 100 for done, width in images), images
    assert errors == []


def test_devtools_check_detects_a_broken_page(chromium, tmp_path):
    # negative control: the same inspection must see a console error and an undecodable image
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><img src="data:image/png;base64,AAAA">'
                   '<script>console.error("boom")</script></body></html>')
    images, errors = cr.inspect_page(chromium, bad, tmp_path / "ud4")
    assert images == [[True, 0]]
    assert any(ev.get("method") == "Runtime.consoleAPICalled" for ev in errors)
