"""A study of a structure of one's own gets a report about that structure only.

The study: the CFFF aluminium plate of data/structures/plate.toml (Leissa 1969, NASA
SP-160 Table 4.50: f1 = 28.4 Hz for this plate), an impact test simulated here with
mvtk.testing (two modes at the specimen's frequencies 28.1 / 68.9 Hz, damping 0.8 % /
0.5 %), the FE model updated on E, and a super element. No ``[references]``: not a word
of the example study's paper, its tests or its materials may appear in the report.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from mvtk import testing as T
from mvtk.study import run

ROOT = Path(__file__).resolve().parents[2]
# one study run (FE, damping, updating, super element, report): about 10 s
pytestmark = pytest.mark.slow
PLATE = ROOT / "data" / "structures" / "plate.toml"

#: text written for the smart-beam example (the seed paper, its tests and materials)
EXAMPLE_PHRASES = (
    "paper", "Table 2", "Table 3", "Table 4", "Table 5", "SAMCEF",
    "PIC 151", "steel/epoxy", "long impact test", "broadband test",
    "make_smart_beam_data", "smart_beam", "smart beam", "Ghareeb", "nodes 2 and 3",
    "data/smart_beam/README.md", "section 4.3", "eq. 7",
)
FN_TRUE = (28.1, 68.9)
ZETA_TRUE = (0.008, 0.005)
FS = 512.0


def _impact_csv(path: Path) -> None:
    rng = np.random.default_rng(30)
    x = T.impact_test(FN_TRUE, ZETA_TRUE, FS, 16.0, 3, rng, modal_constants=[1.0, 0.6])
    x = T.add_noise(x, rng, rms_fraction=1e-3)
    t = x["time"].values
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# SYNTHETIC impact test of an aluminium plate (mvtk.testing.impact_test)\n"
                 f"# sampling_rate_hz: {FS:g}\n# quantity: force, acceleration\n"
                 "time [s],force [N],corner [m/s^2]\n")
        np.savetxt(fh, np.column_stack([t, x.sel(channel="force").values,
                                        x.sel(channel="response").values]),
                   fmt="%.9g", delimiter=",")


@pytest.fixture(scope="module")
def plate_report(tmp_path_factory) -> tuple[Path, str]:
    lab = tmp_path_factory.mktemp("lab")
    folder = lab / "study"
    folder.mkdir()
    (lab / "structures").mkdir()
    (lab / "structures" / "plate.toml").write_bytes(PLATE.read_bytes())
    _impact_csv(folder / "impact.csv")
    study = folder / "study.toml"
    study.write_text("""
[study]
name = "Aluminium plate, lab test 7"
synthetic = true

[report]
document_number = "VR-PL-007"
revision = "B"
author = "A. Tester"
reviewer = "R. Checker"
organisation = "Structures lab"

[structure]
file = "../structures/plate.toml"

[measurements.impact]
file = "impact.csv"
reference = "force"
response = "corner"
record_s = 16.0
force_window_s = 0.02

[damping]
fn_hz = [28.1, 68.9]

[fe]
n_modes = 4

[updating]
targets_hz = [28.1, 68.9]

[[updating.parameters]]
path = "materials.aluminium.E"
lower = 50e9
upper = 90e9

[reduction]
n_modes = 4
n_compare = 2

[[reduction.retained]]
name = "root"
xyz = [0.0, 0.15, 0.0]

[[reduction.retained]]
name = "tip"
xyz = [0.3, 0.15, 0.0]
""", encoding="utf-8")
    assert run(study, folder / "out", progress=False).ok
    page = folder / "out" / "index.html"
    return folder / "out", page.read_text(encoding="utf-8") if page.is_file() else ""


def test_own_structure_report_has_no_example_phrase(plate_report):
    out, html = plate_report
    assert html, "no report written"
    text = re.sub(r"<[^>]+>", " ", re.sub(r'src="data:[^"]*"', "", html))
    found = [p for p in EXAMPLE_PHRASES if p.lower() in text.lower()]
    assert found == [], found
    # the report speaks about this study: its name, its test and its structure
    assert "Aluminium plate, lab test 7" in text and "impact.csv" in text
    assert "CFFF" in text or "plate.toml" in text


def test_own_structure_report_numbers_against_the_simulated_truth(plate_report):
    import pandas as pd

    out, _ = plate_report
    damping = pd.read_csv(out / "tables" / "damping_per_mode.csv")
    # the simulated specimen's frequencies and damping come back (half-power: a few %)
    np.testing.assert_allclose(damping["fn_hz (half-power)"], FN_TRUE, rtol=2e-3)
    np.testing.assert_allclose(damping["zeta half-power"], ZETA_TRUE, rtol=0.15)
    prm = pd.read_csv(out / "tables" / "updating_parameters.csv").set_index("parameter")
    # f ~ sqrt(E): the nominal plate (70 GPa) is 0.99 x too stiff in mode 1
    e = prm.loc["materials.aluminium.E", "updated"]
    assert 60e9 < e < 75e9


def test_own_structure_report_headers_and_notation(plate_report):
    from report_scan import problems

    _, html = plate_report
    assert problems(html) == []


def test_scan_finds_raw_headers_and_mixed_notation():
    """The scan itself on a page made to fail it (a test that cannot fail is worthless)."""
    from report_scan import problems

    page = ('<table class="mvtk" id="table-x"><thead><tr><th>max_real_pole</th>'
            "<th>zeta</th></tr></thead><tbody><tr><td>1</td><td>5.839e-4</td></tr>"
            "<tr><td>2</td><td>0.001321</td></tr></tbody></table>")
    found = problems(page)
    assert len(found) == 2 and "raw field name" in found[0] and "mixes" in found[1]


def test_own_structure_report_is_a_controlled_document(plate_report):
    """Title block from [report], provenance without a path of this machine."""
    out, html = plate_report
    sign = html[html.index('id="report-signoff"'):]
    sign = sign[:sign.index("</section>")]
    for text in ("VR-PL-007", "B", "A. Tester", "R. Checker", "Structures lab",
                 "Prepared by", "Reviewed by", "Approved by"):
        assert text in sign, text
    assert "Validation report: Aluminium plate, lab test 7" in html
    assert str(out.parent.parent) not in html and str(ROOT) not in html
    assert "mvtk git commit" in html and "command line" in html
    assert "../structures/plate.toml" in html   # relative to the study file
