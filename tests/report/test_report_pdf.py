"""The printed report read back: title block, running header, page numbers, provenance.

Needs Debian's chromium (tests/report/install_chromium.sh); skipped with the reason
when it is absent. The PDF is read back with pypdf (a test dependency).
"""

from __future__ import annotations

import re

import pandas as pd
import pytest

from mvtk.report import Report, collect_provenance, find_chromium, to_pdf

pypdf = pytest.importorskip("pypdf", reason="pypdf is a test dependency (pip install pypdf)")


def _report(tmp_path):
    data = tmp_path / "study" / "impact.csv"
    data.parent.mkdir()
    data.write_text("time [s],force [N]\n0,1\n", encoding="utf-8")
    rep = Report("Validation report: plate lab test 7").set_document(
        document_number="VR-PL-007", revision="B", date="2026-12-03",
        author="A. Tester", reviewer="R. Checker")
    for i in range(3):   # enough pages for a running header on more than one
        rep.section(f"Section {i + 1}").table(
            pd.DataFrame({"mode": range(1, 41), "fn_hz": [10.0 + k for k in range(40)]}),
            f"t{i}", "Frequencies", passed_column=None)
    rep.add_provenance(collect_provenance([data], {"x": 1}, base=data.parent,
                                          command=["mvtk", "run", str(data.parent / "s.toml"),
                                                   "--out", str(tmp_path / "out")]))
    return rep


def test_pdf_has_signoff_header_footer_and_relative_provenance(tmp_path):
    if find_chromium() is None:
        pytest.skip("chromium not installed (run tests/report/install_chromium.sh as root)")
    rep = _report(tmp_path)
    page = rep.write(tmp_path / "out")
    pdf = to_pdf(page)
    reader = pypdf.PdfReader(str(pdf))
    n = len(reader.pages)
    assert n >= 3
    texts = [p.extract_text() for p in reader.pages]
    for i, text in enumerate(texts):
        # running header (title, document number and revision) and footer on every page
        assert f"Page {i + 1} of {n}" in text, text[:300]
        assert "VR-PL-007 rev. B" in text and "plate lab test 7" in text
    first = texts[0]
    for word in ("Document number", "Prepared by", "A. Tester", "Reviewed by",
                 "R. Checker", "Approved by", "Signature"):
        assert word in first, word
    everything = "\n".join(texts)
    assert "mvtk git commit" in everything
    assert re.search(r"command line\s*mvtk run s\.toml --out \.\./out", everything)
    assert str(tmp_path) not in everything.replace("\n", "")
    assert "impact.csv" in everything


def test_html_title_block_and_sidebar_without_chromium(tmp_path):
    html = _report(tmp_path).to_html()
    assert html.index('id="report-signoff"') < html.index("<h2>Section 1</h2>")
    assert '<nav class="toc">' in html and 'href="#s1"' in html
    assert '@bottom-right { content: "Page " counter(page) " of " counter(pages)' in html
    assert '@top-right { content: "VR-PL-007 rev. B"' in html
    with pytest.raises(Exception, match="unknown fields"):
        Report("x").set_document(author="a", checker="b")


def test_command_line_is_recorded_only_for_the_mvtk_command():
    from mvtk.report._provenance import command_line

    assert command_line(["/usr/bin/mvtk", "run", "/data/lab/s/study.toml", "--out",
                         "/data/lab/s/out"], "/data/lab/s") == "mvtk run study.toml --out out"
    assert command_line(["/venv/lib/mvtk/__main__.py", "run", "s.toml"]) == "mvtk run s.toml"
    # from another program (here pytest) only its name: its arguments are not the command
    assert command_line().startswith("mvtk called from Python (")
