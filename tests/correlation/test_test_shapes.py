"""Measured shapes from UFF 55 onto the sensors of a test geometry (mvtk correlate --shapes)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from mvtk.cli import main
from mvtk.correlation import read_test_geometry, read_test_shapes, shapes_at_sensors
from mvtk.errors import DimensionError, FormatError

ROOT = Path(__file__).resolve().parents[2]
BEAM = ROOT / "data" / "smart_beam"
GEOMETRY = BEAM / "SYNTHETIC_smart_beam_scan_geometry.csv"


def _node_shapes(nodes, rng, complex_=False):
    v = rng.standard_normal((2, len(nodes), 6))
    if complex_:
        v = v + 1j * rng.standard_normal(v.shape)
    return xr.DataArray(v, dims=("mode", "node", "component"),
                        coords={"mode": [1, 2], "node": nodes,
                                "component": ["ux", "uy", "uz", "rx", "ry", "rz"],
                                "fn_hz": ("mode", [10.0, 20.0]),
                                "damping_ratio": ("mode", [0.01, 0.02])})


@pytest.mark.parametrize("complex_", [False, True])
def test_values_are_projections_on_the_sensing_axes(rng, complex_):
    geo = read_test_geometry(GEOMETRY).with_sensors(
        [(101, "+z"), (102, "-x"), (103, "+ry"), (104, "s1", (1.0, 1.0, 0.0))])
    ms = _node_shapes(geo.node, rng, complex_)
    t = shapes_at_sensors(ms, geo)
    assert t.dims == ("mode", "dof") and list(t["dof"].values) == [
        "101+z", "102-x", "103+ry", "104s1"]
    u = ms.sel(node=[101, 102, 103, 104]).values
    expect = np.stack([u[:, 0, 2], -u[:, 1, 0], u[:, 2, 4],
                       (u[:, 3, 0] + u[:, 3, 1]) / np.sqrt(2)], axis=1)
    np.testing.assert_allclose(t.values, expect, rtol=1e-14)
    np.testing.assert_allclose(t["fn_hz"].values, [10.0, 20.0])


def test_missing_node_or_rotation_is_named(rng):
    geo = read_test_geometry(GEOMETRY).with_sensors([(101, "+z"), (113, "+z")])
    ms = _node_shapes(np.array([101, 102]), rng)
    with pytest.raises(DimensionError, match=r"m\.uff: sensor 113\+z: node 113 has no "
                       r"mode-shape values"):
        shapes_at_sensors(ms, geo, source="m.uff")
    geo = read_test_geometry(GEOMETRY).with_sensors([(101, "+rz")])
    with pytest.raises(DimensionError, match=r"sensor 101\+rz: the shapes have components "
                       r"\['ux', 'uy', 'uz'\]"):
        shapes_at_sensors(ms.isel(component=slice(0, 3)), geo)


def test_a_file_without_shapes_is_refused(tmp_path):
    geo = read_test_geometry(GEOMETRY)
    with pytest.raises(FormatError, match=r"no mode shapes .*expected UFF 55"):
        read_test_shapes(BEAM / "SYNTHETIC_smart_beam_decay.csv", geo)


def test_identified_modes_round_trip_to_correlation(tmp_path, capsys):
    # the chain a lab runs: mvtk modal on its FRFs, UFF 55 out, mvtk correlate against the
    # FE model. The FE modes of the nominal smart beam pair one to one with the six
    # identified modes (the synthetic specimen is a different beam, hence df ~ 2-8 %).
    uff = tmp_path / "modes.uff"
    assert main(["modal", str(BEAM / "SYNTHETIC_smart_beam_scan.uff"), "--fmin", "5",
                 "--fmax", "260", "--uff-modes", str(uff)]) == 0
    capsys.readouterr()
    assert main(["correlate", str(GEOMETRY), str(ROOT / "data" / "structures" /
                                                  "smart_beam.toml"), "-n", "8",
                 "--shapes", str(uff), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    pairs = [p for p in out["pairs"] if p["paired"]]
    assert [(p["test_mode"], p["fe_mode"]) for p in pairs] == [(i, i) for i in range(1, 7)]
    assert min(p["mac"] for p in pairs) > 0.9
