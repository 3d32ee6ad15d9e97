"""correlate() (the study-stage call) and the ``mvtk correlate`` command."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from correlation_helpers import plate_setup

from mvtk import correlation as co
from mvtk.cli import main
from mvtk.errors import ParameterError

ROOT = Path(__file__).resolve().parents[2]


def test_correlate_tables_and_flags(rng):
    model, modal, geo, mp, fe = plate_setup(6)
    sens = list(geo.sensors)
    sens[6] = co.Sensor(7, "+x")  # mis-oriented in the "test"
    test = co.map_sensors(co.TestGeometry(geo.node, geo.xyz, sensors=tuple(sens)),
                          model).project(modal).isel(mode=slice(0, 6))
    amp = np.abs(test.values).max(axis=1, keepdims=True)
    test = test.copy(data=test.values + 0.005 * amp * rng.normal(size=test.shape))
    test = test.assign_coords(dof=fe.dof.values)
    res = co.correlate(geo, model, modal, test)
    dofs = res.dof_table()
    assert (dofs["direction_source"] == "user").all()
    assert dofs.loc[dofs["suspect"], "dof"].tolist() == ["7+z"]
    pairs = res.pairing_table()
    assert pairs["fe_mode"].tolist() == [1, 2, 3, 4, 5, 6] and pairs["paired"].all()
    d = res.to_dict()
    assert json.loads(json.dumps(d))["n_sensors"] == 20
    pre = co.correlate(geo, model, modal)
    assert pre.pairing is None and pre.mac.shape == (10, 10)
    with pytest.raises(ParameterError, match=r"lack sensor DOFs of the geometry: \['1\+z'\]"):
        co.correlate(geo, model, modal, test.isel(dof=slice(1, None)))


@pytest.mark.slow
def test_cli_correlate(tmp_path, capsys):
    geo = {"nodes": [{"node": i + 1, "x": x, "y": y, "z": 0.0}
                     for i, (x, y) in enumerate([(0.1, 0.05), (0.3, 0.05), (0.3, 0.25),
                                                 (0.2, 0.15)])],
           "lines": [{"nodes": [1, 2, 3]}],
           "sensors": [{"node": n, "direction": "+z"} for n in (1, 2, 3, 4)]}
    path = co.read_test_geometry(geo).to_toml(tmp_path / "geo.toml")
    assert path
    structure = ROOT / "data" / "structures" / "plate.toml"
    assert main(["correlate", str(tmp_path / "geo.toml"), str(structure), "-n", "4",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n_sensors"] == 4 and len(out["mac"]) == 4 and out["pairs"] == []
    # a CSV table without a directions column: one global +z sensor per node, said so
    csv = tmp_path / "plain.csv"
    csv.write_text("node,x,y,z\n1,0.1,0.05,0\n2,0.3,0.05,0\n3,0.3,0.25,0\n")
    assert main(["correlate", str(csv), str(structure), "-n", "3", "--json"]) == 0
    cap = capsys.readouterr()
    assert ("plain.csv has no 'directions' column: one global +z sensor assumed at each "
            "of its 3 nodes") in cap.err
    out = json.loads(cap.out)
    assert [d["dof"] for d in out["dofs"]] == ["1+z", "2+z", "3+z"]
    assert {d["direction_source"] for d in out["dofs"]} == {"default +z"}
    bad = tmp_path / "far.toml"
    bad.write_text('[[nodes]]\nnode = 1\nx = 1.0\ny = 0.0\nz = 0.0\n'
                   '[[sensors]]\nnode = 1\ndirection = "+z"\n')
    assert main(["correlate", str(bad), str(structure), "-n", "2"]) == 2
    assert "lie off the FE model" in capsys.readouterr().err


@pytest.mark.slow
def test_correlation_report_section(tmp_path):
    from mvtk.report import Report

    model, modal, geo, mp, fe = plate_setup(4)
    res = co.correlate(geo, model, modal, fe)
    rep = Report("correlation")
    res.add_to_report(rep.section("Correlation"), model=model, synthetic=True)
    assert {"correlation_pairs", "correlation_dofs"} <= set(rep.tables)
    assert rep.n_figures == 3
    html = rep.to_html()
    assert "synthetic" in html and "MAC matrix" in html
