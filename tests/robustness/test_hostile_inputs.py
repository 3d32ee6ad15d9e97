"""Hostile or careless inputs end in one line naming what is wrong, never a traceback,
a hang or a silently partial result."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from mvtk.cli import main

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "smart_beam"
SCAN = DATA / "SYNTHETIC_smart_beam_scan.uff"


def _error(capsys, argv) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err.strip()


def _records(path: Path, values) -> Path:
    t = np.arange(len(values)) / 1024.0
    rows = "\n".join(f"{ti},{a},{b}" for ti, (a, b) in zip(t, values))
    path.write_text("time,a1,a2\n" + rows + "\n")
    return path


@pytest.fixture
def output_only(tmp_path):
    rng = np.random.default_rng(7)
    return [_records(tmp_path / f"oo{k}.csv", rng.standard_normal((2048, 2))) for k in (1, 2)]


def test_output_only_record_of_constant_channels(tmp_path, capsys):
    path = _records(tmp_path / "const.csv", np.tile([1.0, 2.0], (2048, 1)))
    err = _error(capsys, ["modal", path, "--units", "m/s^2", "m/s^2"])
    assert err.endswith("every channel is constant or not finite (a1, a2); no vibration to "
                        "identify")


def test_second_output_only_file_is_not_ignored(output_only, capsys):
    err = _error(capsys, ["modal", *output_only, "--units", "m/s^2", "m/s^2"])
    assert f"uses one record, got 2 files ({output_only[1]} would be ignored)" in err


def test_uff_frf_with_an_output_only_record(output_only, tmp_path, capsys):
    err = _error(capsys, ["modal", output_only[0], "--units", "m/s^2", "m/s^2",
                          "--uff-frf", tmp_path / "x.uff"])
    assert "--uff-frf: " in err and "gives no FRFs to write" in err
    assert not (tmp_path / "x.uff").exists()


def test_nperseg_one(capsys):
    err = _error(capsys, ["modal", DATA / "SYNTHETIC_smart_beam_impact.csv", "--nperseg", "1"])
    assert err == ("mvtk modal: error: --nperseg 1: expected at least 8 samples per segment "
                   "(N samples give N/2 + 1 frequency lines)")


def test_orders_beyond_the_data_or_the_runtime_cap(capsys):
    # 2401 lines in 100..400 Hz; 5000 is beyond both limits, 300 only beyond the lines
    err = _error(capsys, ["modal", SCAN, "--fmin", "100", "--orders", "5000"])
    assert "--orders 5000: above 400 poles per order" in err and err.endswith(
        "expected --orders <= 400")
    err = _error(capsys, ["modal", SCAN, "--fmin", "100", "--fmax", "150", "--orders", "300"])
    assert "the band 100..150 Hz holds 401 lines for 1 reference(s)" in err
    assert err.endswith("expected --orders <= 200")


def test_uff_modes_below_a_regular_file(tmp_path, capsys):
    (tmp_path / "notdir.csv").write_text("x")
    err = _error(capsys, ["modal", SCAN, "--uff-modes", tmp_path / "notdir.csv" / "m.uff"])
    assert err.endswith(f"the folder '{tmp_path / 'notdir.csv'}' is not a folder")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX named pipes")
def test_reading_a_fifo_is_refused_at_once(tmp_path, capsys):
    fifo = tmp_path / "data.csv"
    os.mkfifo(fifo)
    for argv, what in ((["read", fifo], "a named pipe (FIFO); expected a regular"),
                       (["modes", fifo], "is a named pipe (FIFO), expected a TOML file"),
                       (["run", fifo, "--out", tmp_path / "o"], "is a named pipe (FIFO)")):
        assert what in _error(capsys, argv)


def test_correlate_takes_a_uff_geometry_from_the_command_line(capsys):
    assert main(["correlate", str(SCAN), str(ROOT / "data" / "structures" /
                                               "smart_beam.toml"), "-n", "4"]) == 0
    out = capsys.readouterr().out
    # the 13 measured DOFs of the file's FRF records, at its 13 nodes
    assert out.startswith("13 sensors mapped (shape)")
    assert "101+z" in out and "113+z" in out and " file " in out


def test_units_scale_zero_and_an_unknown_geometry_key(tmp_path, capsys):
    geo = DATA / "SYNTHETIC_smart_beam_scan_geometry.csv"
    err = _error(capsys, ["correlate", geo, ROOT / "data" / "structures" / "smart_beam.toml",
                          "--units-scale", "0"])
    assert "units_scale: expected a positive factor (1 for m, 1e-3 for mm), got 0.0" in err
    toml = tmp_path / "g.toml"
    toml.write_text('[[nodes]]\nnode = 1\nx = 0.1\ny = 0.0\nz = 0.0\ndirection = "+z"\n')
    err = _error(capsys, ["correlate", toml, ROOT / "data" / "structures" / "smart_beam.toml"])
    assert "nodes[0]: unknown keys ['direction']; allowed: ['cs', 'node', 'x', 'y', 'z']" in err


def test_nan_in_a_shapes_file_is_named(tmp_path, capsys):
    import xarray as xr

    geo = tmp_path / "g.csv"
    geo.write_text("node,x,y,z,directions\n1,0.05,0.0125,0,+z\n2,0.25,0.0125,0,+z\n")
    vals = np.array([[1.0, 0.5], [0.3, np.nan]])
    xr.DataArray(vals, dims=("mode", "dof"), coords={"mode": [1, 2], "dof": ["1+z", "2+z"]},
                 name="shapes").to_netcdf(tmp_path / "s.nc")
    err = _error(capsys, ["correlate", geo, ROOT / "data" / "structures" / "smart_beam.toml",
                          "--shapes", tmp_path / "s.nc", "-n", "3"])
    assert "shape value of mode 2 at DOF 2+z is nan (1 non-finite value(s) in 1 mode(s))" in err


def test_envelope_fit_on_zeros_and_exact_frf_with_mismatched_nodes():
    import xarray as xr

    from mvtk.damping import envelope_fit
    from mvtk.damping._common import NoEstimateError
    from mvtk.errors import DimensionError, ParameterError
    from mvtk.modal._synthetic import exact_frf

    x = xr.DataArray(np.zeros((1, 4096)), dims=("channel", "time"),
                     coords={"channel": ["a"], "time": np.arange(4096) / 1000.0,
                             "quantity": ("channel", ["acceleration"]),
                             "units": ("channel", ["m/s^2"])}, attrs={"fs": 1000.0})
    with pytest.raises(NoEstimateError, match="'a': failed: the record is constant"):
        envelope_fit(x, 10.0)
    M, K = np.eye(3), np.diag([1e4, 2e4, 3e4])
    with pytest.raises(DimensionError, match="nodes has 2 entries; expected one per DOF"):
        exact_frf(M, 0.01 * K, K, [1.0, 2.0], [0, 1], [0], nodes=[1, 2])
    with pytest.raises(ParameterError, match=r"response_dofs must be DOF indices in 0..2, "
                                             r"got \[5\]"):
        exact_frf(M, 0.01 * K, K, [1.0, 2.0], [0, 5], [0])


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_during_the_stage_workers_is_one_line(clean_run, tmp_path):
    import signal
    import subprocess
    import time

    study = clean_run[0]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for delay in (1.0, 2.5):
        out = tmp_path / f"o{delay}"
        proc = subprocess.Popen([sys.executable, "-m", "mvtk", "run", str(study), "--out",
                                 str(out), "--quiet", "--no-cache"], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)
        time.sleep(delay)
        os.killpg(proc.pid, signal.SIGINT)   # what the terminal sends: the whole group
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 130, err
        assert err.strip().splitlines()[-1] == "mvtk run: interrupted", err
        assert "Traceback" not in err, err
    shutil.rmtree(tmp_path, ignore_errors=True)
