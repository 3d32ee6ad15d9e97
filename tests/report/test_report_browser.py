"""The report page in a real headless browser (Debian chromium).

Skips with a reason when chromium is not on PATH (``tests/report/install_chromium.sh``
installs it). Checks, through the DevTools protocol, that the page loads without console
errors or exceptions, that every figure is decoded (naturalWidth > 0) and that no table
or figure overflows its container at 1024 px and 1400 px width (and in the print
layout); prints the page to PDF and reads it back (page count, verdict text); keeps
screenshots in ``tests/artifacts/``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mvtk.plot import plot_decay, plot_frf, plot_mode_shapes, plot_spectra, plot_time_responses
from mvtk.report import Report, collect_provenance
from mvtk.validation import Check, check_table, frequency_table

# a real browser per test (3-20 s each on a shared 2-core machine); still run by CI
pytestmark = pytest.mark.slow

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


def _wide_damping_table() -> pd.DataFrame:
    """The shape of the study's damping table (13 columns, long headers), real values."""
    zeta = [5.838561349670733e-4, 1.3206450556281395e-3, 2.4464448359956463e-3,
            4.247741385207394e-3, 6.923378404978055e-3]
    fn = [13.259846436761057, 41.13981171111625, 78.69454903693124, 137.7779607870092,
          224.5639825817017]
    df = pd.DataFrame({"mode": [1, 2, 3, 4, 5],
                       "test": ["impact", "impact", "broadband", "broadband", "broadband"],
                       "fn_hz (half-power)": fn, "zeta half-power": zeta,
                       "lines in band": [1.981915107031, 13.908880057541865, 3.0804421537,
                                         9.364767200537926, 24.881826307479514],
                       "quality": ["coarse", "ok", "coarse", "ok", "ok"]})
    for name in ("envelope fit", "log decrement", "Rayleigh (half_power)",
                 "Rayleigh (least_squares)", "Rayleigh (chowdhury)", "paper",
                 "SYNTHETIC truth"):
        df[f"zeta {name}"] = np.array(zeta) * (1 + 1e-3 * len(name))
    return df


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
    # a 150 s decay at 128 Hz sampling: drawn as its min/max envelope, not a grey block
    t_long = np.arange(150 * 128) / 128.0
    x_long = np.exp(-0.0487 * t_long) * np.sin(2 * np.pi * 13.26 * t_long)
    rep.section("Long decay").figure(plot_decay(t_long, x_long, fit=np.exp(-0.0487 * t_long)),
                                     "150 s decay")
    checks = check_table([Check("f1", 13.3, 13.26, 0.01, "Hz"),
                          Check("zeta1", 5.8386e-4, 5.84e-4, 0.1)])
    rep.section("Tables").table(
        frequency_table({"test": [13.26, 41.14], "FE": [13.81, 42.67]}, "test"), "t2",
        "Table 2").table(_wide_damping_table(), "damping_per_mode", "Damping per mode",
                         passed_column=None).table(checks, "checks")
    rep.executive_summary(checks, validated="browser-test beam model",
                          against="hand-written reference values")
    rep.add_provenance(collect_provenance([], {"study": {"name": "browser test", "damping": {
        "band_hz": [5.0, 250.0], "method": "half_power"}}, "file_sha256": {"a.csv": "0" * 64}}))
    return rep.write(out)


def test_dump_dom_and_screenshot(chromium, report_page, tmp_path):
    url = report_page.as_uri()
    dom = cr.run_cmd([chromium, *cr.FLAGS, f"--user-data-dir={tmp_path / 'ud1'}", "--dump-dom",
                      url])
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert dom.stdout.count('class="report-figure"') == 6
    assert "2 of 2 checks passed" in dom.stdout and "PASS: all 2 checks passed" in dom.stdout
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
    assert len(images) == 6
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


def _assert_fits(layout: dict, *, tables_fit: bool, overflow: str = "auto") -> None:
    W = layout["viewport"]
    assert layout["pageScrollWidth"] <= W, f"page scrolls horizontally: {layout}"
    assert layout["tables"] and all(t["wrapped"] for t in layout["tables"])
    for w in layout["wraps"]:
        assert w["left"] >= 0 and w["right"] <= W + 0.5, f"table box off the page: {w}"
        assert w["overflowX"] == overflow, w
        if tables_fit:
            assert w["scrollWidth"] <= w["clientWidth"], f"table {w['id']} overflows its box"
    for f in layout["figures"]:
        assert f["img"]["right"] <= f["figure"]["right"] + 0.5, f"figure overflows: {f}"
        assert f["img"]["right"] <= W and f["img"]["width"] >= 300, f
        assert f["complete"] and f["natural"] > 100, f


@pytest.fixture(scope="module")
def layouts(chromium, report_page, tmp_path_factory):
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    cr.ARTIFACTS.mkdir(exist_ok=True)
    shot = cr.ARTIFACTS / "report_first_page.png"
    shot.unlink(missing_ok=True)
    return cr.measure_layout(chromium, report_page, tmp_path_factory.mktemp("ud5"),
                             widths=(1024, 1400), screenshot=shot), shot


def test_nothing_overflows_at_1024_and_1400_px(layouts):
    measured, shot = layouts
    assert set(measured) == {1024, 1400}
    # at 1400 px every table fits without scrolling (the study's 13-column damping table
    # ran off the page before); at 1024 px a table may scroll, but only inside its box
    _assert_fits(measured[1400], tables_fit=True)
    _assert_fits(measured[1024], tables_fit=False)
    wide = next(w for w in measured[1400]["wraps"] if w["id"] == "table-damping_per_mode")
    assert wide["right"] - wide["left"] <= 1400
    assert shot.read_bytes().startswith(b"\x89PNG") and shot.stat().st_size > 10_000


def test_print_layout_has_no_scroll_box_cut_off(chromium, report_page, tmp_path):
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    # A4 at 96 dpi is 794 px wide; the print CSS must fit every table into it
    measured = cr.measure_layout(chromium, report_page, tmp_path / "ud6", widths=(794,),
                                 print_media=True)
    # printed, the boxes do not scroll (overflow visible), so every table must fit
    _assert_fits(measured[794], tables_fit=True, overflow="visible")


def test_layout_check_detects_an_overflowing_table(chromium, tmp_path):
    # negative control: a wide table outside any scroll box must be reported
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    bad = tmp_path / "wide.html"
    cells = "".join(f"<td>{'x' * 30}</td>" for _ in range(60))
    bad.write_text(f"<!DOCTYPE html><html><body><table id='t'><tr>{cells}</tr></table>"
                   "</body></html>")
    layout = cr.measure_layout(chromium, bad, tmp_path / "ud7", widths=(1024,))[1024]
    assert layout["pageScrollWidth"] > 1024
    with pytest.raises(AssertionError):
        _assert_fits(layout, tables_fit=False)


def test_pdf_export_reads_back(chromium, report_page, tmp_path):
    pypdf = pytest.importorskip("pypdf", reason="pypdf (test extra) reads the PDF back")
    from mvtk.cli import main

    assert main(["report", str(report_page.parent), "--pdf", "--output",
                 str(tmp_path / "r.pdf")]) == 0
    reader = pypdf.PdfReader(tmp_path / "r.pdf")
    text = "\n".join(p.extract_text() for p in reader.pages)
    # 6 figures + 4 tables + provenance on A4: more than one page, not one per element
    assert 3 <= len(reader.pages) <= 12, len(reader.pages)
    assert "PASS: all 2 checks passed" in text
    first = reader.pages[0].extract_text()
    assert "Executive summary" in first and "mvtk browser test" in first
    # the last column of the 13-column table is printed, not cut off at the page edge
    assert "SYNTHETIC" in text and "truth" in text
    w_pt = float(reader.pages[0].mediabox.width)
    assert abs(w_pt - 595.3) < 2  # A4 portrait from the page's @page rule

