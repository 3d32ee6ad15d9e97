"""Metrics against closed forms, the controller comparison (paper section 4.3 shape) and
the study [control] section."""

import argparse
import math

import numpy as np
import pytest
import xarray as xr

from mvtk.cli.control import add_parser
from mvtk.control import (
    PPF,
    SRF,
    ComparisonResult,
    LyapunovBangBang,
    Scenario,
    cantilever_modal_plant,
    compare_controllers,
    controller_from_dict,
    modal_properties,
    peak_reduction_db,
    run_control_section,
    settling_time,
    srf_gain_limit,
    voltage_stats,
)
from mvtk.control._compare import switching_peak
from mvtk.control._stability import SUMMARY_COLUMNS
from mvtk.errors import ConfigError, DimensionError, ParameterError

F1 = 13.26


@pytest.mark.parametrize("band", [0.02, 0.05, 0.1])
def test_settling_time_of_exponential_decay(band):
    fs, f, sigma = 5000.0, 13.26, 3.0
    t = np.arange(int(3 * fs)) / fs
    y = np.exp(-sigma * t) * np.cos(2 * np.pi * f * t)
    ts = settling_time(y, t, band=band)
    exact = np.log(1 / band) / sigma  # envelope crossing
    assert exact - 0.5 / f - 1 / fs <= ts <= exact + 1 / fs


def test_settling_time_edge_cases():
    t = np.arange(100) / 100.0
    y = np.cos(2 * np.pi * 5 * t)
    assert settling_time(y, t) == math.inf  # never decays
    assert settling_time(0.01 * y, t, reference=1.0) == 0.0  # always inside
    da = xr.DataArray(np.exp(-5 * t) * y, dims="time", coords={"time": t})
    assert settling_time(da, band=0.05) == settling_time(da.values, t, band=0.05)


def test_settling_time_bad_input():
    t = np.arange(10) / 10.0
    with pytest.raises(ParameterError, match="band must be a fraction"):
        settling_time(np.ones(10), t, band=5)
    with pytest.raises(DimensionError, match="equal length"):
        settling_time(np.ones(10), t[:5])
    with pytest.raises(ParameterError, match="needs t"):
        settling_time(np.ones(10))
    with pytest.raises(ParameterError, match="reference amplitude"):
        settling_time(np.zeros(10), t)


def test_modal_properties_of_known_poles():
    w, z = 2 * np.pi * 10.0, 0.05
    lam = -z * w + 1j * w * np.sqrt(1 - z**2)
    mp = modal_properties([lam, np.conj(lam), -3.0])
    np.testing.assert_allclose(mp.fn_hz, [3.0 / (2 * np.pi), 10.0])
    np.testing.assert_allclose(mp.zeta, [1.0, 0.05])
    assert mp.stable
    assert list(mp.to_dataframe().columns) == ["fn_hz", "zeta", "real", "imag"]


def test_peak_reduction_of_scaled_sine():
    fs = 1000.0
    t = np.arange(2000) / fs
    y = np.sin(2 * np.pi * 13.0 * t)
    np.testing.assert_allclose(peak_reduction_db(y, 0.1 * y, fs, [13.0]), [20.0])
    with pytest.raises(ParameterError, match="no spectral line"):
        peak_reduction_db(y, y, fs, [0.01])
    with pytest.raises(DimensionError, match="equal length"):
        peak_reduction_db(y, y[:10], fs, [13.0])


def test_voltage_stats_of_sine():
    t = np.arange(1000) / 1000.0
    v = voltage_stats(40.0 * np.sin(2 * np.pi * 10 * t))
    assert v["peak"] == pytest.approx(40.0, rel=1e-3)
    assert v["rms"] == pytest.approx(40.0 / np.sqrt(2), rel=1e-9)
    with pytest.raises(DimensionError, match="empty"):
        voltage_stats([])


@pytest.fixture(scope="module")
def paper_comparison():
    """The paper's scenario on a 3-mode cantilever with the paper's Rayleigh damping:
    PPF tuned on mode 1 (wf = w1, zf = 0.5), SRF tuned above it, Lyapunov velocity law."""
    p = cantilever_modal_plant(3)
    sc = Scenario(output="tip", t_end=4.0, fs_out=1000.0, amplitude=1e-3, band=0.02)
    bound = srf_gain_limit(F1, 1.3 * F1, 0.5)
    ctrls = {
        "PPF": PPF([(F1, 0.5, 0.1)], sensor="tip"),
        "SRF": SRF([(1.3 * F1, 0.5, 0.16 * bound)], sensor="tip"),
        "Lyapunov": LyapunovBangBang(u_max=0.5, boundary_layer=0.05 * switching_peak(p, sc)),
    }
    return compare_controllers(p, ctrls, sc)


def test_paper_qualitative_result(paper_comparison):
    """PPF settles much faster than SRF and the Lyapunov law (paper: about 0.8 s vs about
    2 s with a 20 s open-loop time constant); voltages far below PIC 151 limits."""
    df = paper_comparison.to_dataframe()
    ts = df["settling_time_s"]
    assert ts["open loop"] == math.inf
    assert 0.6 < ts["PPF"] < 1.0
    assert 1.5 < ts["SRF"] < 2.6 and 1.5 < ts["Lyapunov"] < 2.6
    assert ts["PPF"] < 0.5 * min(ts["SRF"], ts["Lyapunov"])
    assert df.loc["PPF", "zeta1"] == pytest.approx(0.06, abs=0.01)
    assert df.loc["SRF", "zeta1"] == pytest.approx(0.022, abs=0.005)
    assert np.isnan(df.loc["Lyapunov", "zeta1"])
    assert df.loc["PPF", "peak_reduction_db"] > df.loc["SRF", "peak_reduction_db"] > 0
    assert df.loc["PPF", "peak_reduction_db"] > df.loc["Lyapunov", "peak_reduction_db"] > 0
    assert df["peak_voltage"].max() < 100.0
    assert df.loc["Lyapunov", "peak_voltage"] == pytest.approx(0.5)


def test_comparison_result_layout(paper_comparison):
    assert isinstance(paper_comparison, ComparisonResult)
    df = paper_comparison.to_dataframe()
    assert list(df.index) == ["open loop", "PPF", "SRF", "Lyapunov"]
    assert list(df.columns) == ["settling_time_s", "fn1_hz", "zeta1", "added_damping1",
                                "peak_reduction_db", "peak_voltage", "rms_voltage",
                                *SUMMARY_COLUMNS]
    assert df["stable"].all() and (df["verdict"] == "stable").all()
    d = paper_comparison.to_dict()
    assert d["rows"][0]["settling_time_s"] is None  # inf -> None for JSON
    assert set(paper_comparison.simulations) == set(df.index)


def test_run_control_section_with_the_study_schema():
    p = cantilever_modal_plant(2)
    section = {
        "actuator_nodes": ["a0", "a1"], "sensor_node": "tip",
        "initial_tip_displacement_m": 1e-3, "t_end_s": 1.0, "fs_out": 500.0,
        "settle_band": 0.05,
        "controllers": [
            {"name": "PPF", "type": "PPF", "f_hz": F1, "zeta_f": 0.3, "gain": 0.5},
            {"name": "Lyapunov", "type": "LyapunovBangBang", "u_max": 5.0,
             "boundary_layer_rel": 0.2, "method": "LSODA"},
        ],
    }
    res = run_control_section(p, section)
    df = res.to_dataframe()
    assert list(df.index) == ["open loop", "PPF", "Lyapunov"]
    assert res.simulations["Lyapunov"].attrs["method"] == "LSODA"
    assert res.simulations["PPF"].attrs["method"] == "zoh"
    assert df.loc["PPF", "settling_time_s"] < 0.5
    assert df.loc["Lyapunov", "peak_voltage"] == pytest.approx(5.0)


def test_controller_from_dict():
    c = controller_from_dict({"type": "srf", "targets": [[20.0, 0.5, 1e-3]], "sensor": "tip"})
    assert isinstance(c, SRF) and c.targets == ((20.0, 0.5, 1e-3),)
    with pytest.raises(ConfigError, match="unknown controller type 'PID'"):
        controller_from_dict({"type": "PID"})
    with pytest.raises(ConfigError, match="needs a 'type'"):
        controller_from_dict({"gain": 1.0})
    with pytest.raises(ConfigError, match="missing 'gain'"):
        controller_from_dict({"type": "PPF", "f_hz": 13.0, "zeta_f": 0.3})
    with pytest.raises(ConfigError, match="unexpected keyword"):
        controller_from_dict({"type": "PPF", "targets": [[13.0, 0.3, 0.5]], "colour": 1})
    with pytest.raises(ConfigError, match="switching peak"):
        controller_from_dict({"type": "LyapunovBangBang", "u_max": 1.0,
                              "boundary_layer_rel": 0.1})


def test_run_control_section_bad_input():
    p = cantilever_modal_plant(2)
    ok = {"sensor_node": "tip", "controllers": [{"type": "PPF", "f_hz": F1, "zeta_f": 0.3,
                                                 "gain": 0.5}]}
    with pytest.raises(ConfigError, match="unknown keys \\['gains'\\]"):
        run_control_section(p, {**ok, "gains": 1})
    with pytest.raises(ConfigError, match="at least one"):
        run_control_section(p, {"sensor_node": "tip", "controllers": []})
    with pytest.raises(ConfigError, match="needs 'sensor_node'"):
        run_control_section(p, {"controllers": ok["controllers"]})
    with pytest.raises(ParameterError, match="scenario output 'root'"):
        run_control_section(p, {**ok, "sensor_node": "root"})
    with pytest.raises(ConfigError, match="must be a table"):
        run_control_section(p, [1, 2])
    with pytest.raises(ParameterError, match="Scenario"):
        compare_controllers(p, {}, {"output": "tip"})


def test_cli_registers_control_subcommand():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    add_parser(sub)
    args = parser.parse_args(["control", "study.toml", "--json"])
    assert args.command == "control" and args.json and args.study == "study.toml"
    assert callable(args.func)
