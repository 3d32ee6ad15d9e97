"""Execute the notebooks in ``notebooks/`` (nbclient, kernel ``python3``).

Outputs are not written back; a cell that raises fails the test with the cell's error.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _execute(path: Path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    return nb


def _text(nb) -> str:
    out = []
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            out.append(o.get("text", "") or str(o.get("data", {}).get("text/plain", "")))
    return "\n".join(out)


def test_there_are_three_notebooks():
    assert [p.name[:2] for p in NOTEBOOKS if p.name[:2].isdigit()] == ["01", "02", "03"]
    assert "lvm_impact.ipynb" in [p.name for p in NOTEBOOKS]


def test_committed_notebooks_have_no_outputs():
    for p in NOTEBOOKS:
        nb = json.loads(p.read_text(encoding="utf-8"))
        code = [c for c in nb["cells"] if c["cell_type"] == "code"]
        assert code and all(not c.get("outputs") for c in code), p.name
        assert nb["metadata"]["kernelspec"]["name"] == "python3"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path):
    nb = _execute(path)
    text = _text(nb)
    if path.name.startswith("01"):
        assert "paper 5.84e-4" in text and "settling time" in text
    if path.name.startswith("02"):
        # runs without ../shared/data too, and then says so instead of analysing
        if (ROOT.parent / "shared" / "data" / "hdf5" / "view_0.hdf5").is_file():
            assert "found" in text and "zeta" in text and "NOT FOUND" not in text
        else:
            assert "NOT FOUND" in text
    if path.name == "lvm_impact.ipynb":
        import os

        shared = Path(os.environ.get("MVTK_SHARED_DATA", ROOT.parent / "shared" / "data"))
        if (shared / "lvm" / "camera.lvm").is_file():
            # issue 19: the two hits' identified frequencies agree within 0.1 %
            assert "agree within 0.1 %: True" in text and "NOT FOUND" not in text
            # the defaults path, no fallback: FRF and half_power with no options, only
            # physical peaks listed (not the 18-40 noise rows of before), accelerances
            assert "FRF with the defaults" in text and "default impact FRF failed" not in text
            import re

            # every peak of the excited band gets a row with a verdict (at most MAX_PEAKS
            # = 20); only the catalogued bending modes (PROVENANCE.md: six, 2779.7 Hz a
            # weak one) come out reliable
            rows = [(int(n), int(r)) for n, r in re.findall(
                r"with no options gives (\d+) rows, (\d+) reliable", text)]
            assert len(rows) == 2 and all(n <= 20 and 4 <= r <= 6 for n, r in rows), rows
            assert "FRF type {'accelerance'}" in text
            # pLSCF on the same default FRFs: the bending modes of both hits repeat
            import re as _re

            diffs = [abs(float(d)) for d in _re.findall(r"\(([+-]\d+\.\d+) %\)", text)]
            assert "pLSCF + LSFD" in text and len(diffs) >= 4 and max(diffs) < 0.1, diffs
        else:
            assert "NOT FOUND" in text
