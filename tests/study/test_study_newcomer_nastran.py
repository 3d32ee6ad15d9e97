"""A newcomer's own Nastran deck and roving-hammer test through `mvtk init` and
`mvtk run` with no edit (tests/roving_hammer.write_nastran_panel_test: a cylindrical
panel, 4 x 4 points, 0.5 s windowed records, 1 % noise, point 6 hit twice, a double hit
at point 11). Truth: the deck's own FE modes."""

from __future__ import annotations

import sys
import tomllib
import warnings
from pathlib import Path

import pandas as pd
import pytest

from mvtk.study._init import _roving_groups

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import roving_hammer as RH  # noqa: E402


def _sets(folder, pairs):
    return [{"kind": "impact", "nodes": p, "file": str(folder / f"hit_{k:02d}.csv")}
            for k, p in enumerate(pairs, start=1)]


def test_a_point_hit_again_stays_in_its_test(tmp_path):
    """One point hit twice (a second file for it) is one roving test whose repeated pair
    frf_matrix averages; a whole test repeated (every pair twice) is two tests."""
    once = [(h, 6) for h in range(1, 7)] + [(6, 6)] + [(h, 6) for h in range(7, 12)]
    groups = _roving_groups(_sets(tmp_path, once))
    assert len(groups) == 1 and len(groups[0]) == 12
    twice = [(h, 6) for h in range(1, 5)] * 2
    groups = _roving_groups(_sets(tmp_path, twice))
    assert [[t["nodes"][0] for t in g] for g in groups] == [[1, 2, 3, 4], [1, 2, 3, 4]]
    # the second round in another order: still the j-th file of each pair in test j
    groups = _roving_groups(_sets(tmp_path, [(1, 6), (2, 6), (2, 6), (1, 6)]))
    assert [[t["file"][-6:-4] for t in g] for g in groups] == [["01", "02"], ["03", "04"]]


@pytest.mark.slow
def test_init_and_run_with_defaults_on_a_nastran_deck(tmp_path):
    from mvtk.study import run, study_checks
    from mvtk.study._init import init_study

    deck, truth, _, files = RH.write_nastran_panel_test(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = init_study(tmp_path / "study", structure=deck, measurements=files,
                         geometry=tmp_path / "test" / "geometry.csv")
    cfg = tomllib.loads(res.study.read_text(encoding="utf-8"))
    assert len(cfg["modal"]["sets"]) == 17              # hit_06b.csv in the same test
    assert not [k for k in cfg["measurements"] if k.startswith("roving_")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = run(res.study, tmp_path / "report", progress=False)
    assert not out.failed, out.failed
    checks = {c.name: c for c in study_checks(out)}
    assert all(c.passed for c in checks.values()), [n for n, c in checks.items()
                                                    if not c.passed]
    modes = pd.DataFrame(out.results["modal"]["table"])
    # every reliable mode is the deck's (known limit: the pair 269.97 / 270.72 Hz, a
    # third of a 2.2 Hz line apart, is one pole at 270.07 Hz, see the modal guide)
    good = modes[modes["reliable"] & ((modes["fn_hz"] - 270.3).abs() > 1.0)]
    assert len(good) >= 5
    for f, z in zip(good["fn_hz"], good["zeta"]):
        assert (abs(truth / f - 1)).min() < 2e-4 and abs(z / 0.005 - 1) < 0.03
    # a mode marked not reliable checks nothing; every MAC checked matches the deck
    for m in modes["mode"][~modes["reliable"]]:
        assert not [n for n in checks if n.startswith(f"MAC test mode {int(m)} ")]
    macs = [c for n, c in checks.items() if n.startswith("MAC test mode")]
    assert len(macs) >= 5 and all(c.value > 0.95 for c in macs)
    # the impact test's damping is compared both ways (no leakage bound on hit records)
    z = [c for n, c in checks.items() if n.startswith("zeta of mode")
         and "349.1 Hz" in n]
    assert z and "upper bound" not in z[0].name and z[0].kind == "relative"


def test_a_mode_marked_not_reliable_is_paired_but_checks_nothing():
    """The correlation checks skip a test mode the identification marked not reliable
    (e.g. "unresolved": one pole for a close pair, its shape a mixture of two)."""
    from types import SimpleNamespace

    from mvtk.study._report import _correlation_checks

    pairs = {"test_mode": [1, 2], "fe_mode": [1, 2], "fn_test_hz": [100.0, 200.0],
             "fn_fe_hz": [100.5, 201.0], "mac": [0.99, 0.6], "paired": [True, True]}
    res = SimpleNamespace(results={
        "correlation": {"pairs": pairs},
        "modal": {"file": "test.uff", "table": {"mode": [1, 2], "reliable": [True, False]}}})
    tol = {"mac_min": 0.9, "prediction_fn_rel": 0.05}
    names = [c.name for c in _correlation_checks(res, tol)]
    assert any(n.startswith("MAC test mode 1 ") for n in names)
    assert not any("test mode 2" in n for n in names)
    res.results["modal"]["table"]["reliable"] = [True, True]
    assert any(n.startswith("MAC test mode 2 ") for n in
               [c.name for c in _correlation_checks(res, tol)])
