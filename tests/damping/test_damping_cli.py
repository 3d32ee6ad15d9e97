import argparse
import json
from pathlib import Path

import pytest

from mvtk.cli import damping as _cli

BEAM = Path(__file__).resolve().parents[2] / "data" / "smart_beam"


def _run(argv):
    p = argparse.ArgumentParser()
    _cli.add_parser(p.add_subparsers(dest="command"))
    args = p.parse_args(["damping", *argv])
    return args.func(args)


def test_cli_decay_envelope_json(capsys):
    f = BEAM / "SYNTHETIC_smart_beam_decay.csv"
    if not f.is_file():
        pytest.skip("data/smart_beam SYNTHETIC files not present")
    assert _run([str(f), "--method", "envelope", "--fn", "13.26", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["channel"] for r in rows] == ["tip_disp", "tip_accel"]
    assert rows[0]["zeta"] == pytest.approx(5.84e-4, rel=0.01)


def test_cli_impact_half_power_reports_warnings(capsys):
    f = BEAM / "SYNTHETIC_smart_beam_impact.csv"
    if not f.is_file():
        pytest.skip("data/smart_beam SYNTHETIC files not present")
    assert _run([str(f), "--impact", "--nperseg", "16000", "--fn", "13.26", "41.14"]) == 0
    out = capsys.readouterr()
    assert "coarse" in out.out and "ResolutionWarning" in out.err


def test_cli_bad_method():
    with pytest.raises(SystemExit):
        _run(["x.csv", "--method", "prony"])
