"""The Nastran bulk-data reader against pyNastran, card by card, on pyNastran's decks.

Truth: pyNastran 1.4.1 (BSD), run on the unchanged decks of its own test models
(tests/fe/data/nastran, copied from the repository SteveDoyle2/pyNastran, folder models/;
licence in LICENSE-pyNastran.md); its values per card are frozen in
``pynastran_reference.json`` by ``make_reference.py`` (pyNastran needs numpy < 2, so it
runs in a separate environment). Every card of every deck is compared: names and counts,
and the values of GRID (basic position through CORD2R/C/S chains, CP, CD, PS), CORD2x
(origin and axes), CONM2 (mass, offset, inertia), PBARL/PBEAML (type, dimensions),
SPC1 (THRU ranges expanded), RBE2, RBE3 (weights, components, grids), CQUAD4/CTRIA3,
CBAR/CBEAM and MAT1.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from mvtk.fe import read_bulk_cards
from mvtk.fe._nastran import _frames

DATA = Path(__file__).parent / "data" / "nastran"
REF = json.loads((DATA / "pynastran_reference.json").read_text())
DECKS = sorted(d for d, v in REF.items() if "error" not in v)


def _by_name(cards):
    out: dict[str, list] = {}
    for c in cards:
        out.setdefault(c.name, []).append(c)
    return out


@pytest.mark.parametrize("deck", DECKS)
def test_deck_reads_card_for_card_as_pynastran(deck):
    ref = REF[deck]
    cards = read_bulk_cards(DATA / deck)
    counts = Counter(c.name for c in cards)
    expected = {k: v for k, v in ref["card_count"].items() if k != "ENDDATA"}
    assert dict(counts) == expected
    by = _by_name(cards)
    systems = _frames(by)
    for cid, r in ref["CORD"].items():
        s = systems[int(cid)]
        assert s.kind == r["type"][-1]
        np.testing.assert_allclose(s.origin, r["origin"], atol=1e-12)
        np.testing.assert_allclose(s.axes, r["axes"], atol=1e-12)
    grids = {c.int(0): c for c in by.get("GRID", [])}
    assert sorted(grids) == sorted(int(k) for k in ref["GRID"])
    for nid, r in ref["GRID"].items():
        c = grids[int(nid)]
        assert (c.int(1, 0), c.int(5, 0), c.text(6)) == (r["cp"], r["cd"], r["ps"])
        x = np.array([c.real(k, 0.0) for k in (2, 3, 4)])
        np.testing.assert_allclose(x, r["xyz"], atol=1e-14)
        np.testing.assert_allclose(systems[c.int(1, 0)].to_global(x), r["basic"], atol=1e-12)
    for c in by.get("CONM2", []):
        r = ref["CONM2"][str(c.int(0))]
        assert (c.int(1), c.int(2, 0), c.real(3)) == (r["nid"], r["cid"], r["mass"])
        assert [c.real(k, 0.0) for k in (4, 5, 6)] == r["X"]
        assert [c.real(k, 0.0) for k in range(8, 14)] == r["I"]
    for c in by.get("PBARL", []) + by.get("PBEAML", []):
        r = ref["PBARL"][str(c.int(0))]
        assert (c.name, c.int(1), c.text(3)) == (r["type"], r["mid"], r["Type"])
        if c.name == "PBARL":
            dims = [c.real(k) for k in range(8, 8 + len(r["dim"]))]
            assert dims == r["dim"]
            assert len(c) <= 9 + len(dims)  # nothing beyond NSM
        else:
            n = len(r["dim"][0])
            assert [c.real(k) for k in range(8, 8 + n)] == r["dim"][0]
    spc1 = []
    ids = sorted(grids)
    for c in by.get("SPC1", []):
        rest = [c.text(k) for k in range(2, len(c)) if c.text(k)]
        if len(rest) == 3 and rest[1] == "THRU":
            nodes = [g for g in ids if int(rest[0]) <= g <= int(rest[2])]
        else:
            nodes = sorted(int(g) for g in rest)
        spc1.append({"sid": c.int(0), "components": c.text(1), "nodes": nodes})
    key = lambda d: (d["sid"], d["components"], d["nodes"])  # noqa: E731
    assert sorted(spc1, key=key) == sorted(ref["SPC1"], key=key)
    for c in by.get("RBE2", []):
        r = ref["RIGID"][str(c.int(0))]
        assert (c.int(1), c.text(2)) == (r["gn"], r["cm"])
        assert [c.int(k) for k in range(3, len(c)) if not c.blank(k)] == r["Gmi"]
    for c in by.get("RBE3", []):
        r = ref["RIGID"][str(c.int(0))]
        assert (c.int(2), c.text(3)) == (r["refgrid"], r["refc"])
        groups, k = [], 4
        while k < len(c):
            if c.blank(k):
                k += 1
            elif not c.is_int(k):
                groups.append([c.real(k), c.text(k + 1), []])
                k += 2
            else:
                groups[-1][2].append(c.int(k))
                k += 1
        assert [g[0] for g in groups] == r["weights"]
        assert [g[1] for g in groups] == r["comps"]
        assert [g[2] for g in groups] == r["Gijs"]
    for c in by.get("CQUAD4", []) + by.get("CTRIA3", []):
        r = ref["SHELL"][str(c.int(0))]
        n = 4 if c.name == "CQUAD4" else 3
        assert (c.name, c.int(1)) == (r["type"], r["pid"])
        assert [c.int(2 + k) for k in range(n)] == r["nodes"]
        tm = c.int(2 + n) if c.is_int(2 + n) else c.real(2 + n, 0.0)
        assert tm == r["theta_mcid"]
        assert c.real(3 + n, 0.0) == r["zoffset"]
    for c in by.get("CBAR", []) + by.get("CBEAM", []):
        r = ref["BAR"][str(c.int(0))]
        assert (c.int(1), c.int(2), c.int(3)) == (r["pid"], r["ga"], r["gb"])
        if r["g0"] is not None:
            assert c.int(4) == r["g0"]
        else:
            assert [c.real(k, 0.0) for k in (4, 5, 6)] == r["x"]
        assert c.text(7) in ("", r["offt"] or "")
        assert [c.real(k, 0.0) for k in (10, 11, 12)] == r["wa"]
        assert [c.real(k, 0.0) for k in (13, 14, 15)] == r["wb"]
    for c in by.get("MAT1", []):
        r = ref["MAT1"][str(c.int(0))]
        assert c.real(1) == r["e"] and c.real(4, 0.0) == r["rho"]
        assert c.real(2, r["g"]) == r["g"] and c.real(3, r["nu"]) == r["nu"]


def test_load_cards_resultants_as_pynastran():
    """FORCE, MOMENT, PLOAD4 (single and THRU), PLOAD2 (list and THRU) and a LOAD
    combination of mvtk's loads.bdf: total force and moment about the origin equal
    pyNastran's sum_forces_moments (loads_reference.json); the case control's LOAD and
    SPC are found; a FORCE in a CORD2C acts along the local (r, theta, z) at its grid;
    GRAV is the gravity load of the model's mass."""
    from mvtk.fe import gravity_nodal, read_nastran

    ref = json.loads((DATA / "loads_reference.json").read_text())
    model = read_nastran(DATA / "loads.bdf")
    assert model.meta["nastran"]["load_id"] == 100 and model.meta["nastran"]["spc_id"] == 1
    cases = model.meta["load_cases"]
    for sid, r in ref.items():
        f = cases[sid]
        np.testing.assert_allclose(f[:, :3].sum(axis=0), r["force"], atol=1e-9)
        moment = (np.cross(model.nodes, f[:, :3]) + f[:, 3:]).sum(axis=0)
        np.testing.assert_allclose(moment, r["moment"], atol=1e-9)
    g = int(np.flatnonzero(model.node_ids == 12)[0])
    x = model.nodes[g] - [0.5, 0.3, 0.0]
    th = np.arctan2(x[1], x[0])
    e_r, e_t = np.array([np.cos(th), np.sin(th), 0]), np.array([-np.sin(th), np.cos(th), 0])
    np.testing.assert_allclose(cases["11"][g, :3], 50.0 * (e_r + 0.5 * e_t), atol=1e-12)
    np.testing.assert_allclose(cases["40"], gravity_nodal(model, (0, 0, -9.81)), atol=1e-12)
