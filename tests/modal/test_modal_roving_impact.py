"""A roving-hammer test of 32 CSV files (0.3 s records: a window is needed) with one
double hit and one clipped hit: named, tabulated, and the modes right.

Truth: the modal model of ``tests/roving_hammer.py`` (five beam modes, fn = 40 k^2 Hz,
known zeta and shapes sin(k pi x / L)). The window's damping is removed with the exact
correction of Fladung & Rost (MSSP 11(1) 1997), mvtk.signal.exponential_window_correction.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from mvtk import io, modal, signal
from mvtk.errors import AccuracyWarning

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import roving_hammer as RH  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("roving")
    return RH.write(folder, np.random.default_rng(5))


def _corrected(fn, zeta, tau):
    """zeta without the window's added damping (a no-op if identify removed it)."""
    fn, zeta = np.asarray(fn), np.asarray(zeta)
    if np.all(zeta > 0.5 / (tau * 2 * np.pi * fn)):  # the window's 1/(tau wn) is still in
        return signal.exponential_window_correction(fn, zeta, tau)
    return fn, zeta


def test_double_hit_and_clipped_hit_are_named_and_tabulated(campaign):
    sets = [io.read(p) for p in campaign]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        h = modal.frf_matrix(sets, {"quantity": "force"})
    text = "\n".join(str(w.message) for w in caught)
    assert "hit_node10.csv: impact FRF: double hit: a second force pulse at 0.02222 s (40% " \
           "of the hit at 0.01025 s)" in text
    assert "record refused" in text
    assert "hit_node20.csv: impact FRF: clipped channel(s), a flat top at the ADC range: " \
           "'hammer' at 56.9581 for 3 samples" in text
    # one window for the whole test, stated; the refused set is not in the matrix
    assert h.shape[:2] == (1, 31) and 10 not in h["reference_node"].values.tolist()
    tau = h.attrs["exponential_window_tau_s"]
    assert 0.05 < tau < 0.2
    assert f"exponential window tau = {tau:.4g} s on every set" in h.attrs["window_policy"]
    q = signal.set_quality(h).to_dataframe()
    assert len(q) == 32 and (q["verdict"] != "ok").sum() == 2
    bad = q.loc[10]
    assert not bad["usable"] and bad["double_hit_action"] == "refused"
    assert bad["double_hit_s"] == pytest.approx(0.0222, abs=5e-4)
    assert bad["double_hit_ratio"] == pytest.approx(0.4, abs=0.02)
    assert bad["source"].endswith("hit_node10.csv") and bad["references"] == "10+z"
    clip = q.loc[20]
    assert clip["usable"] and clip["clipped"].startswith("hammer at 56.9")
    assert clip["verdict"].startswith("clipped")
    assert q.loc[1, "verdict"] == "ok" and q.loc[1, "n_averages"] == 1
    assert np.isnan(q.loc[1, "coherence"])  # one hit: coherence is 1 by construction
    # the pair measured with the clipped force carries the verdict (reciprocity swaps it)
    rec = modal.reciprocal(h)
    pq = rec["pair_quality"].sel(response="20+z").values[0]
    assert pq.startswith("set 20: clipped")
    assert rec["pair_quality"].sel(response="1+z").values[0] == ""
    # alone, each set would pick its own window: no single correction would fit them
    alone = set()
    for x in sets[:6]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            alone.add(round(signal.frf(x, {"quantity": "force"}).attrs[
                "exponential_window_tau_s"], 4))
    assert len(alone) > 1
    # the table and the pair verdicts survive io.write / io.read
    io.write(rec, Path(campaign[0]).parent / "frf.nc")
    back = modal.as_frf_matrix(io.read(Path(campaign[0]).parent / "frf.nc"))
    assert signal.set_quality(back).to_dataframe()["verdict"].tolist() == q["verdict"].tolist()
    assert back["pair_quality"].sel(response="20+z").values[0] == pq
    assert back.attrs["exponential_window_tau_s"] == tau
    # identification on the common window, its damping removed
    res = modal.identify(rec, 10.0, 800.0)
    tab = res.to_dataframe()
    k = [int(np.argmin(np.abs(tab["fn_hz"].values - f))) for f in RH.FN[:4]]
    fn, zeta = _corrected(tab["fn_hz"].values[k], tab["zeta"].values[k], tau)
    np.testing.assert_allclose(fn, RH.FN[:4], rtol=1e-3)
    np.testing.assert_allclose(zeta, RH.ZETA[:4], rtol=0.10)  # found: -0.3 % on mode 1


@pytest.mark.slow
def test_cli_and_study_give_the_same_modes(campaign, tmp_path, capsys):
    from mvtk.cli import main
    from mvtk.study import run

    files = [str(p) for p in campaign]
    assert main(["modal", *files, "--fmin", "10", "--fmax", "800", "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert "hit_node10.csv" in cap.err and "double hit" in cap.err
    assert "hit_node20.csv" in cap.err and "clipped" in cap.err
    rows = {r["set"]: r for r in out["set_quality"]}
    assert rows[10]["usable"] is False and rows[20]["clipped"].startswith("hammer")
    cli_fn = np.array([m["fn_hz"] for m in out["modes"]])
    cli_zeta = np.array([m["zeta"] for m in out["modes"]])
    # the study on the same files
    names = [Path(p).name for p in files]
    folder = Path(files[0]).parent
    (folder / "geometry.csv").write_text(
        "node,x,y,z\n" + "".join(f"{i},{i / 33:.6f},0,0\n" for i in range(1, 33)),
        encoding="utf-8")
    st = folder / "study.toml"
    st.write_text(
        f'[structure]\nfile = "{(ROOT / "data" / "structures" / "smart_beam.toml").as_posix()}"'
        f"\n[modal]\nsets = {json.dumps(names)}\n"
        'geometry = "geometry.csv"\nfmin_hz = 10.0\nfmax_hz = 800.0\n', encoding="utf-8")
    res = run(st, tmp_path / "out", stages=["modal"], progress=False, report=False)
    assert not res.failed, res.failed
    mod = res.results["modal"]
    assert "reciprocity" in mod["note"] and mod["n_responses"] == 31
    assert [r["verdict"] for r in mod["set_quality"]] == [r["verdict"]
                                                           for r in out["set_quality"]]
    assert any("hit_node10.csv" in w and "double hit" in w for w in mod["warnings"])
    np.testing.assert_allclose(mod["table"]["fn_hz"], cli_fn, rtol=1e-8)  # JSON keeps 10 digits
    np.testing.assert_allclose(mod["table"]["zeta"], cli_zeta, rtol=1e-7)
    assert len(cli_fn) == 4


def test_cli_on_the_double_hit_file_alone_is_a_named_refusal(campaign, capsys):
    from mvtk.cli import main

    assert main(["modal", str(campaign[9])]) == 2
    err = capsys.readouterr().err
    assert "hit_node10.csv: every impact record holds a double hit (second pulse at " \
           "0.02222 s, 40% of the hit at 0.01025 s)" in err
    assert "frequency lines" not in err and "Traceback" not in err


@pytest.fixture(scope="module")
def campaign11(tmp_path_factory):
    """A fresh campaign (rng seed 11) the defaults were not tuned on."""
    return RH.write(tmp_path_factory.mktemp("roving11"), np.random.default_rng(11))


def test_defaults_give_every_mode_within_10_percent_and_no_fault_pole(campaign11, capsys):
    """`mvtk modal` with defaults on the 32 files: mode 1 ends its 0.3 s record at ~5 % of
    its windowed amplitude, 80 % of its identified damping is the window's. On the
    record's own lines (no zero padding) the windowed mode is exactly a pole with
    damping ``sigma + 1 / tau`` and the refined damping is right; the clipped set's
    FRF holds a pole of its own (a zero of the clipped force's spectrum, 888 Hz)
    that no other FRF needs: not reliable, the set named."""
    from mvtk.cli import main

    assert main(["modal", *map(str, campaign11), "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    fn = np.array([m["fn_hz"] for m in modes])
    k = [int(np.argmin(np.abs(fn - f))) for f in RH.FN]
    for f0, z0, i in zip(RH.FN, RH.ZETA, k):
        m = modes[i]
        assert m["fn_hz"] == pytest.approx(f0, rel=1e-3)
        # found: -0.2 % on mode 1 (+16 % before, marked reliable with zeta_std 1e-4)
        assert m["zeta"] == pytest.approx(z0, rel=0.10), m
        assert abs(m["zeta"] - z0) < 4 * m["zeta_std"] + 1e-3 * z0, m   # the error bar covers it
        assert m["reliable"], m
    k1 = modes[k[0]]
    assert k1["zeta_window"] > 0.75 * (k1["zeta"] + k1["zeta_window"])   # window-dominated
    extra = [m for i, m in enumerate(modes) if i not in k]
    assert extra, "the clipped set's pole is no longer found: the test lost its point"
    for m in extra:
        assert not m["reliable"], m
        assert "needed only by FRFs of flagged sets" in m["reason"]
        assert "set 20: clipped" in m["reason"]


def test_zero_padded_windowed_lines_are_not_trusted(campaign11):
    """The same test on zero-padded lines (nfft given): mode 1's truncation ripple
    biases its damping (+30 %); the row says so instead of a confident number."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = modal.reciprocal(modal.frf_matrix([io.read(p) for p in campaign11],
                                              {"quantity": "force"}, nfft=8192))
    assert h.attrs["nfft"] == 8192 and h.attrs["nperseg"] < 8192 / 4
    t = modal.identify(h, 10.0, 800.0).to_dataframe()
    m1 = t.iloc[int(np.argmin(np.abs(t["fn_hz"].values - RH.FN[0])))]
    assert abs(m1["zeta"] / RH.ZETA[0] - 1) > 0.10      # the bias is real ...
    assert not m1["reliable"] and "zero-padded lines" in m1["reason"]   # ... and stated


@pytest.fixture(scope="module")
def plate20(tmp_path_factory):
    """A 20-point roving test of the aluminium plate (data/structures/plate.toml with E
    +5 %), 2 s records, zeta 0.8 %: the FE modes and the hit files."""
    import tomllib

    from mvtk import fe

    desc = tomllib.loads((ROOT / "data" / "structures" / "plate.toml").read_text())
    desc["materials"]["aluminium"]["E"] = 73.5e9
    model = fe.build_model(desc)
    modes = fe.modal_analysis(model, 8)
    pts = [model.nearest_node([x, y, 0.0]) for x in np.linspace(0.075, 0.3, 4)
           for y in np.linspace(0.0, 0.3, 5)]
    files = RH.write_fe_test(tmp_path_factory.mktemp("plate20"), model, modes, pts,
                             model.nearest_node([0.3, 0, 0]), zeta=0.008, fs=2048.0,
                             record_s=2.0, f_max_hz=700, seed=3)
    return modes, files


def test_unwindowed_padded_record_is_identified_on_its_own_lines(plate20):
    # the whole response decays to 1 %, so the impact policy uses no window and
    # interpolates (zero-pads 8 x); mode 1 (29 Hz, weak in the accelerance) still ends
    # the record at 4.4 % of its amplitude. On the padded lines its damping came out
    # +8.7 % with a standard deviation 14 x smaller than the error; on the record's own
    # lines (every 8th) the truncated decay is exactly a pole
    modes, files = plate20
    sets = [io.read(p) for p in files]
    h = modal.reciprocal(modal.frf_matrix(sets, {"quantity": "force"}))
    assert h.attrs.get("exponential_window_tau_s") is None
    assert h.attrs["nfft"] == 8 * h.attrs["nperseg"]
    # the own lines are the unpadded FRFs of the same records, value for value
    own = modal.own_lines(h)
    plain = modal.reciprocal(modal.frf_matrix(sets, {"quantity": "force"},
                                              nfft=h.attrs["nperseg"]))
    np.testing.assert_allclose(own["frequency"], plain["frequency"][: own.sizes["frequency"]],
                               rtol=1e-12)
    np.testing.assert_allclose(own.values, plain.values[..., : own.sizes["frequency"]],
                               rtol=1e-9, atol=1e-12 * np.abs(plain.values).max())
    res = modal.identify(h)
    assert "identified on the record's own lines (every 8th" in res.band_reason
    assert "29.08 Hz ends the record at 4.4% of its amplitude" in res.band_reason
    assert res.n_modes == 8
    np.testing.assert_allclose(res.fn_hz, modes.fn_hz[:8], rtol=1e-4)
    # every mode reliable, damping right within 0.05 %, the error inside 3 std
    assert res.reliable.all(), res.to_dataframe()
    np.testing.assert_allclose(res.zeta, 0.008, rtol=5e-4)
    assert np.all(np.abs(res.zeta - 0.008) < 3 * res.zeta_std)
    # what the padded lines would leave of each mode at the record's end (the rule)
    from mvtk.modal._identify import truncation

    padded = truncation(dataclasses.replace(res, frf=h))
    sigma_T = 0.008 * 2 * np.pi * modes.fn_hz[:8] / h.attrs["resolution_hz"]
    np.testing.assert_allclose(np.log(padded), -sigma_T, rtol=1e-3)   # 5.6 % for mode 1
    assert padded[0] > 0.05 and np.all(padded[1:] < 0.01)


def test_a_late_double_hit_set_does_not_shorten_the_pretrigger(plate20):
    """Set 7 hit a second time 0.5 s after the first (40 %): its whole record is 0.5 s,
    so it is left out of the record length; its pretrigger (1 % of that record) was
    still taken as the test's, so the 1.97 s record no longer fitted behind any other
    set's hit and `mvtk modal` failed on set 1. Now: the record and the pretrigger come
    from the same sets, set 7 alone is refused and named, the eight modes are found."""
    modes, files = plate20
    sets = [io.read(p) for p in files]
    th = sets[6]["time_history"]
    n0 = int(0.5 * 2048)
    late = th.values.copy()
    late[:, n0:] += 0.4 * th.values[:, :-n0]          # the whole test again, 40 %
    sets[6] = sets[6].copy()
    sets[6]["time_history"] = th.copy(data=late)
    pol = signal.impact_policy(sets, {"quantity": "force"})
    clean = signal.impact_policy(sets[:6] + sets[7:], {"quantity": "force"})
    assert (pol.nperseg, pol.pretrigger) == (clean.nperseg, clean.pretrigger)
    with pytest.warns(AccuracyWarning, match="1 of 20 measurement set"):
        h = modal.reciprocal(modal.frf_matrix(sets, {"quantity": "force"}))
    assert h.sizes["response"] == 19
    res = modal.identify(h)
    np.testing.assert_allclose(res.fn_hz, modes.fn_hz[:8], rtol=1e-4)
    assert res.reliable.all()
