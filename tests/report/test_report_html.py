import base64
import hashlib
import re
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest

from mvtk.errors import DimensionError, ParameterError
from mvtk.plot import figure_to_png, plot_frf
from mvtk.report import Report, collect_provenance, file_sha256, render_table
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
        if tag in ("script", "link") or (tag == "img" and not a["src"].startswith("data:")):
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
    png = base64.b64decode(p.imgs[0].split(",", 1)[1])
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
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
    with pytest.raises(ParameterError, match="PNG bytes or a matplotlib Figure, got str"):
        sec.figure("plot.png")
    with pytest.raises(ParameterError, match="missing PNG signature"):
        sec.figure(b"GIF89a....")
    with pytest.raises(ParameterError, match="note kind must be"):
        sec.note("x", kind="warning")


def test_render_table_index_and_nan():
    df = pd.DataFrame({"FE": [13.81, np.nan]}, index=pd.RangeIndex(1, 3, name="mode"))
    html = render_table(df, caption="T2")
    assert "<th>mode</th>" in html and "–" in html and "13.81" in html


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
    assert prov.inputs["sha256"].iloc[0] in text and '&quot;gain&quot;: 0.5' in text
    with pytest.raises(ParameterError, match="not an existing file"):
        file_sha256(tmp_path / "missing.csv")


def test_plot_bad_inputs():
    with pytest.raises(DimensionError, match="H has 3 values but f_hz has 4"):
        plot_frf([1, 2, 3, 4], [1, 2, 3])
    with pytest.raises(DimensionError, match="f_hz must be a 1-D array"):
        plot_frf([[1, 2]], [1, 2])
    assert figure_to_png(plot_frf([1, 2, 3], [1, 2, 3])).startswith(b"\x89PNG")
