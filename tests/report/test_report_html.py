import base64
import hashlib
import io
import re
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest

from mvtk.errors import DimensionError, ParameterError
from mvtk.plot import figure_to_png, minmax_decimate, plot_frf
from mvtk.report import (
    Report,
    collect_provenance,
    file_sha256,
    html_table,
    render_table,
    tolerance_used,
)
from mvtk.validation import Check, check_table


class _Collector(HTMLParser):
    def __init__(self):
        super().__init__()
        self.imgs, self.pass_cells, self.fail_cells, self.tags = [], 0, 0, []
        self.external = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        if tag == "img":
            self.imgs.append(a["src"])
        if tag == "td" and a.get("class") == "pass":
            self.pass_cells += 1
        if tag == "td" and a.get("class") == "fail":
            self.fail_cells += 1
        if (tag == "script" and "src" in a) or tag == "link" or (
                tag == "img" and not a["src"].startswith("data:")):
            self.external.append(tag)


def _small_report():
    rep = Report("Test <report>")
    f = np.linspace(1, 30, 300)
    sec = rep.section("FRF")
    sec.text("A & B").figure(plot_frf(f, 1 / (13**2 - f**2 + 0.5j * f)), "FRF")
    sec.table(check_table([Check("f1", 13.3, 13.26, 0.01, "Hz"),
                           Check("f2", 45.0, 41.14, 0.01, "Hz")]), "checks", "Checks")
    rep.section("Missing").unavailable("stage X is not in this version")
    return rep


def test_report_writes_self_contained_page_and_csv(tmp_path):
    rep = _small_report()
    page = rep.write(tmp_path)
    text = page.read_text(encoding="utf-8")
    p = _Collector()
    p.feed(text)
    assert p.external == []  # no script, stylesheet link or remote image: opens offline
    assert len(p.imgs) == 1
    head, b64 = p.imgs[0].split(",", 1)
    data = base64.b64decode(b64)
    assert (head == "data:image/png;base64" and data.startswith(b"\x89PNG\r\n\x1a\n")) or (
        head == "data:image/svg+xml;base64" and b"<svg" in data[:2000])
    assert (p.pass_cells, p.fail_cells) == (1, 1)
    assert "1 of 2 checks passed" in text
    assert "Test &lt;report&gt;" in text and "A &amp; B" in text
    assert "stage X is not in this version" in text
    csv = pd.read_csv(tmp_path / "tables" / "checks.csv")
    assert list(csv["passed"]) == [True, False]
    assert csv["value"].iloc[0] == pytest.approx(13.3)


def test_report_bad_inputs():
    rep = Report("r")
    sec = rep.section("s")
    with pytest.raises(ParameterError, match="not a safe file stem"):
        sec.table(pd.DataFrame({"a": [1]}), "../evil")
    sec.table(pd.DataFrame({"a": [1]}), "t1")
    with pytest.raises(ParameterError, match="used twice"):
        sec.table(pd.DataFrame({"a": [1]}), "t1")
    with pytest.raises(ParameterError, match="expected a pandas DataFrame, got list"):
        sec.table([1, 2], "t2")
    with pytest.raises(ParameterError, match="Figure or a function returning one, got str"):
        sec.figure("plot.png")
    with pytest.raises(ParameterError, match="missing PNG signature"):
        sec.figure(b"GIF89a....")
    with pytest.raises(ParameterError, match="no <svg> element"):
        sec.figure(b"<?xml version='1.0'?><html/>")
    with pytest.raises(ParameterError, match="image_format must be 'auto', 'png' or 'svg'"):
        sec.figure(plot_frf([1, 2, 3], [1, 2, 3]), image_format="jpg")
    with pytest.raises(ParameterError, match="table 't3': formats name columns not in"):
        sec.table(pd.DataFrame({"a": [1.0]}), "t3", formats={"b": 3})
    assert "t3" not in rep.tables  # a refused table is not half-added
    with pytest.raises(ParameterError, match="note kind must be"):
        sec.note("x", kind="warning")


def test_render_table_index_and_nan():
    df = pd.DataFrame({"FE": [13.81, np.nan]}, index=pd.RangeIndex(1, 3, name="mode"))
    html = render_table(df, caption="T2")
    assert "<th class=\"text\">mode</th>" in html and "–" in html and "13.81" in html
    assert html.startswith('<div class="mvtk-table-wrap">') and html.endswith("</div>")


def test_render_table_formats_by_quantity():
    # rows of the study's table5_fe_vs_se (raw CSV values)
    df = pd.DataFrame({"mode": [1, 2], "fe_hz": [13.277063487183465, 40.978549990103645],
                       "error_pct": [0.00027713670949780034, 2.5e-07],
                       "mac": [0.9999999992121509, 0.999999999594787]})
    html = render_table(df, passed_column=None)
    assert "<th>FE [Hz]</th>" in html and "<th>error [%]</th>" in html
    # a percent column in fixed notation (one notation per column)
    assert "<td>13.277</td>" in html and "<td>0.000277</td>" in html
    assert "<td>&lt; 1e-6</td>" in html and "<td>1.000</td>" in html
    assert "13.277063" not in html
    html = render_table(df, passed_column=None, formats={"fe_hz": 8})
    assert "<td>13.277063</td>" in html
    with pytest.raises(ParameterError, match="expects a pandas DataFrame, got dict"):
        render_table({"a": [1]})


def _checks():
    return check_table([
        Check("f1", 13.3, 13.26, 0.01, "Hz", source="paper Table 2"),
        Check("f2", 45.0, 41.14, 0.01, "Hz"),                 # fails, 9.4 %
        Check("f3", 78.7, 78.69, 0.01, "Hz"),
        Check("zeta1", 5.2e-4, 5.84e-4, 0.1),                  # fails, 11 %
        Check("f4", 137.0, 137.78, 0.01, "Hz"),                # passes, 0.57 %
    ])


def test_executive_summary_verdict_and_worst_checks():
    rep = Report("Smart beam")
    checks = _checks()
    rep.section("Checks").table(checks, "checks")
    rep.executive_summary(checks, validated="FE model and damping of the smart beam",
                          against="paper Tables 2-3", n_worst=3)
    text = rep.to_html()
    assert rep.summary_verdict == "FAIL: 2 of 5 checks failed"
    # at the top of the page, before the first section; the contents are a sidebar
    # (first in the page, fixed at the left on a wide screen) that links to it
    pos = text.index('id="executive-summary"')
    assert text.index('<nav class="toc">') < pos < text.index('<section id="s1">')
    assert 'href="#executive-summary"' in text
    summary = text[pos:text.index("</section>", pos)]
    assert "FE model and damping of the smart beam" in summary and "paper Tables 2-3" in summary
    # failed first, then the passing one closest to its limit; 3 rows only
    rows = re.findall(r"<tr><td class=\"text\">(\w+)</td>", summary)
    assert rows == ["f2", "zeta1", "f4"]  # 938 %, 110 %, 57 % of the tolerance used
    assert "<th>share of tolerance used [%]</th>" in summary and "<td>938</td>" in summary
    assert '<th class="text">check</th>' in summary  # text columns: headers left-aligned
    assert summary.count('class="fail"') == 2 and summary.count('class="pass"') == 1
    assert rep.n_checks == 5  # the summary does not count the checks twice

    ok = Report("ok")
    ok.executive_summary(checks[checks["passed"]], validated="x", against="y")
    assert ok.summary_verdict == "PASS: all 3 checks passed"
    none = Report("none")
    none.executive_summary(checks.iloc[:0], validated="x", against="y")
    assert none.summary_verdict.startswith("NO VERDICT") and "PASS" not in none.to_html()


def test_tolerance_used_matches_the_check_definitions():
    checks = [Check("f1", 13.3, 13.26, 0.01, "Hz"),                     # relative
              Check("x", 1.05, 1.0, 0.1, "m", kind="absolute"),
              Check("peak voltage", 93.52, 100.0, 0.0, "V", kind="upper"),
              Check("closed-loop zeta", 0.1038, 0.005, 0.0, kind="lower"),
              Check("zero ref", 0.1, 0.0, 0.5, kind="absolute")]
    used = tolerance_used(check_table(checks))
    expect = [abs(checks[0].relative_error) / 0.01, 0.05 / 0.1, 93.52 / 100.0, 0.005 / 0.1038,
              0.1 / 0.5]
    np.testing.assert_allclose(used, expect, rtol=1e-9)
    # a check at its limit uses 100 %; a failed one more
    at = check_table([Check("a", 1.01, 1.0, 0.01), Check("b", 1.02, 1.0, 0.01)])
    np.testing.assert_allclose(tolerance_used(at), [1.0, 2.0], rtol=1e-9)
    assert np.isnan(tolerance_used(pd.DataFrame({"tolerance": ["about right"]}))).all()
    assert np.isnan(tolerance_used(pd.DataFrame({"x": [1.0]}))).all()


def test_executive_summary_bad_inputs():
    rep = Report("r")
    with pytest.raises(ParameterError, match="checks as a DataFrame, got list"):
        rep.executive_summary([1], validated="x", against="y")
    with pytest.raises(ParameterError, match="no 'ok' column; columns are"):
        rep.executive_summary(_checks(), validated="x", against="y", passed_column="ok")
    with pytest.raises(ParameterError, match="n_worst must be an integer >= 1, got 0"):
        rep.executive_summary(_checks(), validated="x", against="y", n_worst=0)
    with pytest.raises(ParameterError, match=r"columns \['nope'\] are not in"):
        rep.executive_summary(_checks(), validated="x", against="y", columns=["nope"])


def test_html_table_for_notebook_reprs():
    df = pd.DataFrame({"mode": np.arange(1, 101), "fn_hz": np.linspace(10, 500, 100),
                       "zeta": np.full(100, 0.0012345678)})
    out = html_table(df, caption="Damping", max_rows=10)
    assert out.startswith("<div><style>") and "table.mvtk" in out
    assert out.count("<tr>") == 11  # header + 5 first + 5 last rows
    assert "90 of 100 rows not shown" in out and "<th>fn [Hz]</th>" in out
    assert "<td>0.001235</td>" in out
    # the same cells as in the report
    first5 = render_table(df.iloc[:5], passed_column=None).split("<tbody>")[1]
    assert first5.split("</tbody>")[0] in out
    with pytest.raises(ParameterError, match="max_rows must be >= 2"):
        html_table(df, max_rows=1)
    with pytest.raises(ParameterError, match="html_table expects a pandas DataFrame"):
        html_table([1])


def test_figure_format_auto_picks_the_smaller():
    import matplotlib
    from matplotlib.figure import Figure

    rep = Report("f")
    sec = rep.section("s")
    # a few vector strokes: smaller as SVG
    line = Figure(figsize=(7, 3))
    ax = line.add_axes((0, 0, 1, 1))
    ax.plot([0, 1, 2, 3], [0, 1, 0, 1])
    ax.axis("off")
    # a raster (e.g. a dense measured field): SVG would embed it as base64 PNG -> larger
    contour = Figure(figsize=(7, 3))
    contour.add_subplot().imshow(np.random.default_rng(1).random((150, 300)))
    sizes = {}
    for name, fig in (("line", line), ("contour", contour)):
        for fmt in ("png", "svg"):
            buf = io.BytesIO()
            with matplotlib.rc_context({"svg.fonttype": "none"}):
                fig.savefig(buf, format=fmt, **({"dpi": 100} if fmt == "png" else {}))
            sizes[name, fmt] = len(buf.getvalue())
        sec.figure(fig, name)
    assert sizes["line", "svg"] < sizes["line", "png"]  # both choices are exercised
    assert sizes["contour", "png"] < sizes["contour", "svg"]
    mimes = re.findall(r'src="data:([^;]+);base64', sec.render())
    expect = ["image/svg+xml" if sizes[n, "svg"] < sizes[n, "png"] else "image/png"
              for n in ("line", "contour")]
    assert mimes == expect
    sec.figure(line, image_format="png").figure(line, image_format="svg")
    mimes = re.findall(r'src="data:([^;]+);base64', sec.render())
    assert mimes[2:] == ["image/png", "image/svg+xml"]
    # a line plot whose SVG exceeds SVG_KEEP_BYTES: both rendered, the smaller (PNG) kept
    from mvtk.report._render import SVG_KEEP_BYTES
    from mvtk.report._render import render_figure as _figure_bytes

    dense = Figure(figsize=(7, 3))
    dense.add_subplot().plot(np.random.default_rng(2).random(20_000))
    mime, data = _figure_bytes(dense, "auto")
    buf = io.BytesIO()
    with matplotlib.rc_context({"svg.fonttype": "none"}):
        dense.savefig(buf, format="svg")
    assert len(buf.getvalue()) > SVG_KEEP_BYTES > len(data) and mime == "image/png"


def test_minmax_decimate_keeps_every_bin_extremum():
    t = np.arange(150 * 128) / 128.0          # the smart-beam decay: 150 s at 128 Hz
    x = np.exp(-0.0487 * t) * np.sin(2 * np.pi * 13.26 * t)
    td, xd = minmax_decimate(t, x, n_bins=500)
    assert td.size <= 1000 and np.all(np.diff(td) > 0)
    assert xd.max() == x.max() and xd.min() == x.min()
    # every sample kept is a sample of the signal, and each bin's extrema are kept
    idx = np.searchsorted(t, td)
    assert np.array_equal(t[idx], td) and np.array_equal(x[idx], xd)
    edges = np.searchsorted(t, np.linspace(t[0], t[-1], 501)[1:-1])
    for a, b in zip(np.r_[0, edges], np.r_[edges, t.size]):
        sel = (td >= t[a]) & (td <= t[b - 1])
        assert xd[sel].max() == x[a:b].max() and xd[sel].min() == x[a:b].min()
    short = np.arange(10.0)
    assert np.array_equal(minmax_decimate(short, short)[1], short)
    with pytest.raises(DimensionError, match="same 1-D shape"):
        minmax_decimate(t, x[:-1])
    with pytest.raises(ParameterError, match="n_bins must be an integer >= 1"):
        minmax_decimate(t, x, n_bins=0)


def test_decimated_line_draws_the_same_pixels():
    # external truth: matplotlib's own rendering of the full 19 200-point line
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = np.arange(150 * 128) / 128.0
    x = np.exp(-0.0487 * t) * np.sin(2 * np.pi * 13.26 * t) + 0.01 * np.sin(0.3 * t)

    def raster(tt, xx):
        fig = Figure(figsize=(7, 3), dpi=100)
        FigureCanvasAgg(fig)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.plot(tt, xx, lw=1, color="k", antialiased=False)
        ax.set_xlim(t[0], t[-1])
        ax.set_ylim(-1.05, 1.05)
        ax.axis("off")
        fig.canvas.draw()
        return np.asarray(fig.canvas.buffer_rgba())[..., 0] < 128

    full = raster(t, x)
    dec = raster(*minmax_decimate(t, x))
    assert full.sum() > 10_000
    assert np.mean(full != dec) < 0.01  # < 1 % of the pixels differ


def test_to_pdf_and_cli_bad_inputs(tmp_path, capsys):
    from mvtk.cli import main
    from mvtk.report import to_pdf

    with pytest.raises(ParameterError, match="no such HTML file"):
        to_pdf(tmp_path / "nowhere")
    assert main(["report", str(tmp_path / "nowhere")]) == 2
    assert "is not a report: no index.html there" in capsys.readouterr().err
    rep = Report("cli")
    rep.section("Checks").table(_checks(), "checks")
    page = rep.write(tmp_path / "rep")
    assert main(["report", str(page.parent)]) == 0
    out = capsys.readouterr().out
    assert f"report: {page}" in out and "verdict: 3 of 5 checks passed" in out


def test_provenance_hashes_and_versions(tmp_path):
    f = tmp_path / "a.csv"
    f.write_bytes(b"t,x\n0,1\n")
    prov = collect_provenance([f], {"gain": 0.5})
    assert prov.inputs["sha256"].iloc[0] == hashlib.sha256(b"t,x\n0,1\n").hexdigest()
    assert file_sha256(f) == prov.inputs["sha256"].iloc[0]
    v = dict(prov.to_dataframe().values)
    assert re.match(r"\d+\.\d+", v["numpy"]) and "mvtk" in v
    rep = Report("p")
    rep.add_provenance(prov)
    text = rep.to_html()
    assert prov.inputs["sha256"].iloc[0] in text
    # parameters as a key/value table (and CSV), not a JSON dump
    assert "<td class=\"text\">gain</td><td class=\"text\">0.5</td>" in text and "<pre>" not in text
    assert dict(rep.tables["provenance_parameters"].values) == {"gain": "0.5"}
    with pytest.raises(ParameterError, match="not an existing file"):
        file_sha256(tmp_path / "missing.csv")


def test_plot_bad_inputs():
    with pytest.raises(DimensionError, match="H has 3 values but f_hz has 4"):
        plot_frf([1, 2, 3, 4], [1, 2, 3])
    with pytest.raises(DimensionError, match="f_hz must be a 1-D array"):
        plot_frf([[1, 2]], [1, 2])
    assert figure_to_png(plot_frf([1, 2, 3], [1, 2, 3])).startswith(b"\x89PNG")


def test_pdf_refused_clearly_without_chromium(tmp_path, monkeypatch):
    from mvtk.errors import MissingDependencyError
    from mvtk.report import PdfExportError, to_pdf

    rep = Report("no browser")
    rep.section("Checks").table(_checks(), "checks")
    monkeypatch.setenv("MVTK_CHROMIUM", str(tmp_path / "no-such-chromium"))
    with pytest.raises(MissingDependencyError, match="install the Debian package 'chromium'"):
        rep.to_pdf(tmp_path / "out")
    assert (tmp_path / "out" / "index.html").is_file()  # the HTML report is still written
    # a "browser" that fails: the error names the exit code, no half-written PDF is left
    monkeypatch.setenv("MVTK_CHROMIUM", "false")
    with pytest.raises(PdfExportError, match=r"failed to print .* \(exit code 1\)"):
        to_pdf(tmp_path / "out")
    assert not (tmp_path / "out" / "report.pdf").exists()


def test_summary_ranks_graded_checks_and_lists_the_others_apart():
    from mvtk.report import classify_checks

    checks = check_table([
        Check("f5 prediction", 171.82, 176.36, 0.03, "Hz"),            # -2.57 % of ±3 %
        Check("f1", 13.26, 13.26, 0.005, "Hz"),                          # on the reference
        Check("MAC", 0.984, 0.9, 0.0, kind="lower"),                     # slack 9.3 %
        Check("peak voltage", 100.0, 100.0, 0.0, "V", kind="upper"),     # saturated
        Check("stable", 1.0, 1.0, 0.0, kind="lower"),                    # yes/no
        Check("SE >= FE", 13.28, 13.277, 1.3e-8, "Hz", kind="lower"),    # exact bound
    ])
    cls = classify_checks(checks)
    assert list(cls["category"]) == ["graded", "graded", "graded", "at limit", "yes/no",
                                     "exact bound"]
    # margin: distance to the nearest limit in % of it; 171.82 vs 0.97 * 176.36
    assert cls["margin_pct"][0] == pytest.approx(100 * (171.82 / (0.97 * 176.36) - 1))
    assert cls["margin_pct"][2] == pytest.approx(100 * (0.984 / 0.9 - 1))
    rep = Report("r")
    rep.executive_summary(checks, validated="x", against="y", n_worst=2,
                          warnings=["damping: 2 lines in the band"],
                          inconsistencies=["mode 1: zeta a factor 8.8 apart"])
    text = rep.to_html()
    worst = text[text.index('id="table-summary-worst"'):]
    worst = worst[:worst.index("</table>")]
    assert re.findall(r'<tr><td class="text">([^<]+)</td>', worst) == ["f5 prediction", "f1"]
    apart = text[text.index('id="table-summary-apart"'):]
    assert "peak voltage" in apart and "at limit" in apart and "≤ 100 V" in apart
    assert rep.summary_verdict == ("PASS WITH RESERVATIONS: all 6 checks passed, 1 met only "
                                   "at the limit, 1 warning, 1 inconsistency")
    assert "damping: 2 lines in the band" in text and "factor 8.8" in text
    failed = Report("f")
    failed.executive_summary(check_table([Check("f", 2.0, 1.0, 0.1)]), validated="x",
                             against="y", warnings=["w"])
    assert failed.summary_verdict == "FAIL: 1 of 1 checks failed"


def test_empty_columns_are_left_off_the_page_but_kept_in_the_csv(tmp_path):
    rep = Report("r")
    df = pd.DataFrame({"stage": ["fe", "modal"], "note": ["", ""],
                       "time_s": [0.5, float("nan")], "spare": [np.nan, np.nan]})
    rep.section("Stages").table(df, "stages", passed_column=None)
    page = rep.write(tmp_path).read_text(encoding="utf-8")
    table = page[page.index('id="table-stages"'):]
    table = table[:table.index("</table>")]
    assert "<th" in table and "note" not in table and "spare" not in table
    assert "time [s]" in table   # a column with one value stays
    csv = pd.read_csv(tmp_path / "tables" / "stages.csv")
    assert list(csv.columns) == ["stage", "note", "time_s", "spare"]
