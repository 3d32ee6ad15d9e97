"""Numbers formatted by quantity, on values taken from the smart-beam study's report tables
(``mvtk run data/smart_beam/study.toml``: tables/*.csv, written unformatted)."""

import numpy as np
import pandas as pd
import pytest

from mvtk.errors import ParameterError
from mvtk.report import ColumnFormat, dict_table, format_number, format_table, infer_format


@pytest.mark.parametrize(
    ("value", "digits", "floor", "text"),
    [
        (7.4790549255921475, 3, 1e-6, "7.48"),          # table2 "FE nominal error %"
        (7.82821e-21, 4, 1e-6, "< 1e-6"),               # mass fraction of a torsion mode
        (2.5e-07, 3, 1e-6, "< 1e-6"),                   # an error of 2.5e-07 %
        (-2.5e-07, 3, 1e-6, "< 1e-6"),
        (0.625521, 2, None, "0.63"),                    # a stage time in s
        (46.62479505200008, 2, None, "47"),
        (388.0, 2, None, "388"),                        # integer part is never rounded
        (13.259846436761057, 5, None, "13.260"),        # identified f1: 5 digits kept
        (13.26, 5, None, "13.26"),                      # exact value: no padding zeros
        (128.0, 5, None, "128"),
        (0.0005838561349670733, 4, None, "5.839e-4"),   # zeta1
        (0.0013206450556281395, 4, None, "0.001321"),   # zeta2
        (209630005213.62015, 4, None, "2.096e11"),      # updated E in Pa
        (9.777940998147692e-06, 4, None, "9.778e-6"),   # Rayleigh beta in s
        (0.9999999992121509, 4, None, "1.000"),         # MAC: rounded, precision kept
        (9.9996, 4, None, "10.00"),                     # carry into one more digit
        (-0.00015356323894266666, 3, None, "-1.54e-4"),
        (0.0, 3, 1e-6, "0"),
        (float("nan"), 4, None, "–"),
        (float("inf"), 4, None, "∞"),
        (True, 4, None, "yes"),
        (np.int64(49664), 4, None, "49664"),
        ("coarse", 4, None, "coarse"),
        (None, 4, None, "–"),
    ],
)
def test_format_number(value, digits, floor, text):
    assert format_number(value, digits=digits, floor=floor) == text


@pytest.mark.parametrize(
    ("name", "kind", "header", "value", "text"),
    [
        ("fn_hz (half-power)", "frequency", "fn (half-power) [Hz]", 13.259846436761057,
         "13.260"),
        ("fn_hz nominal", "frequency", "fn_hz nominal [Hz]".replace("_hz", ""),
         14.251722683133519, "14.252"),
        ("FE nominal error %", "percent", "FE nominal error %", 7.4790549255921475, "7.48"),
        ("error_pct", "percent", "error [%]", 0.00027713670949780034, "2.77e-4"),
        ("error_pct", "percent", "error [%]", 2.5e-07, "< 1e-6"),
        ("mass fraction uz", "ratio", "mass fraction uz", 7.82821e-21, "< 1e-6"),
        ("mass fraction uz", "ratio", "mass fraction uz", 0.6234866421163752, "0.6235"),
        ("rel_error_boundary", "error", "rel error boundary", 9.691850746146822e-11,
         "< 1e-6"),
        ("pairing error (rel)", "error", "pairing error (rel)", -0.003919845860620219,
         "-0.00392"),
        # an absolute error (unit per row) keeps its small values: zeta1 error
        ("error", "error", "error", -1.438650329266657e-07, "-1.44e-7"),
        ("time_s", "duration", "time [s]", 0.625521, "0.63"),
        ("settling_time_s", "duration", "settling time [s]", 0.336, "0.336"),
        ("zeta half-power", "damping", "zeta half-power", 0.0005838561349670733,
         "5.839e-4"),
        ("alpha [1/s]", "number", "alpha [1/s]", 0.029415881684096555, "0.02942"),
        ("beta [s]", "number", "beta [s]", 9.777940998147692e-06, "9.778e-6"),
        ("peak_voltage_V", "number", "peak voltage [V]", 93.52100852033372, "93.52"),
        ("peak_reduction_db", "number", "peak reduction [dB]", 29.711095683589672, "29.7"),
        # units of compound suffixes and registered fields (COLUMN_REGISTRY)
        ("max_real_pole_1_per_s", "number", "max real pole [1/s]", -0.3388, "-0.3388"),
        ("critical_pole_imag_rad_s", "number", "critical pole imag [rad/s]", 83.1, "83.1"),
        ("stability_count", "number", "stable orders", 45.0, "45"),
        ("second_mac", "ratio", "second-highest MAC", 0.245117, "0.2451"),
        ("fn_std_hz", "frequency", "std of fn [Hz]", 0.01234, "0.012"),
        ("zeta_std", "damping", "std of zeta", 1.234e-5, "1.2e-5"),
        ("mac", "ratio", "MAC", 0.999999999594787, "1.000"),
    ],
)
def test_infer_format_on_study_columns(name, kind, header, value, text):
    fmt = infer_format(name, pd.Series([value]))
    assert (fmt.kind, fmt.header(name), fmt(value)) == (kind, header, text)


def test_format_table_real_rows_and_overrides():
    # two rows of the study's run_stages and fe_modes tables
    df = pd.DataFrame({"stage": ["ingest", "fe"], "time_s": [9.702575629999956, 0.625521],
                       "n": [3, 4], "mass fraction uz": [0.6024903889031851,
                                                         8.758712784105905e-22]})
    headers, cells = format_table(df)
    assert headers == ["stage", "time [s]", "n", "mass fraction uz"]
    assert cells == [["ingest", "9.7", "3", "0.6025"], ["fe", "0.63", "4", "< 1e-6"]]
    # per-table overrides: a ColumnFormat, a number of digits, a callable
    headers, cells = format_table(df, formats={
        "time_s": 4, "mass fraction uz": ColumnFormat("ratio", 2, "", 1e-12),
        "stage": str.upper})
    assert headers[1] == "time [s]" and headers[3] == "mass fraction uz"
    assert cells[0][:2] == ["INGEST", "9.703"] and cells[1][3] == "< 1e-12"


def test_format_bad_inputs():
    with pytest.raises(ParameterError, match=r"formats name columns not in the table: "
                                             r"\['nope'\]"):
        format_table(pd.DataFrame({"a": [1.0]}), formats={"nope": 3})
    with pytest.raises(ParameterError, match="format of column 'a' must be a ColumnFormat"):
        format_table(pd.DataFrame({"a": [1.0]}), formats={"a": "%.3f"})
    with pytest.raises(ParameterError, match=r"duplicate column names \['a'\]"):
        format_table(pd.DataFrame([[1, 2]], columns=["a", "a"]))
    with pytest.raises(ParameterError, match="kind must be one of"):
        ColumnFormat("speed")
    with pytest.raises(ParameterError, match="digits must be an integer >= 1, got 0"):
        ColumnFormat(digits=0)
    with pytest.raises(ParameterError, match="floor must be a positive finite number"):
        ColumnFormat(floor=-1.0)
    with pytest.raises(ParameterError, match="dict_table expects a mapping .* got list"):
        dict_table([1, 2])


def test_dict_table_flattens_a_study_config():
    params = {"study": {"name": "smart beam", "damping": {"band_hz": [5.0, 250.0],
                                                          "tolerance": 0.1},
                        "tests": [{"file": "a.csv", "fs": 128.0}, {"file": "b.csv"}],
                        "empty": {}},
              "file_sha256": {"a.csv": "0" * 64}}
    df = dict_table(params)
    assert list(df.columns) == ["parameter", "value"]
    rows = dict(df.values)
    assert rows == {
        "file_sha256.a.csv": "0" * 64,
        "study.damping.band_hz": "5, 250",
        "study.damping.tolerance": "0.1",
        "study.empty": "{}",
        "study.name": "smart beam",
        "study.tests[0].file": "a.csv",
        "study.tests[0].fs": "128",
        "study.tests[1].file": "b.csv",
    }
