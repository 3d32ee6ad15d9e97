"""Double hits and clipped channels of impact tests, on a known truth and real files."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from mvtk import io, signal
from mvtk.errors import AccuracyWarning, DoubleHitError

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import roving_hammer as RH  # noqa: E402

SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"


def _th(force, acc):
    return io.time_history(np.vstack([force, acc]), RH.FS, ["hammer", "acc"],
                           ["N", "m/s^2"], ["force", "acceleration"], node=[3, 7],
                           direction="z")


@pytest.mark.parametrize("delay_s", [0.0045, 0.012])
def test_early_rebound_is_a_named_refusal(delay_s):
    # a rebound 4.5 ms after the hit used to pass inside the force window (FRF 14 % off)
    t, force, acc = RH.hit(3, np.random.default_rng(1))
    force = force + RH._pulse(t, RH.HIT_S + delay_s, 1.5e-3, 0.3 * force.max())
    with pytest.warns(AccuracyWarning, match=rf"double hit: a second force pulse at "
                      rf"{RH.HIT_S + delay_s:.3f}\d* s \(\d\d% of the hit"), \
            pytest.raises(DoubleHitError, match="every impact record holds a double hit"):
        signal.frf(_th(force, acc), "hammer")


def test_late_double_hit_is_cut_and_the_frf_stays_right():
    rng = np.random.default_rng(2)
    t, force, acc = RH.hit(3, rng)
    clean = signal.frf(_th(force, acc), "hammer", exponential_tau_s=0.03, nfft=8192,
                       nperseg=1200, pretrigger=20)
    # a second hit at 0.25 s: the response windowed with tau = 30 ms is < 1 % there
    t2, f2, a2 = RH.hit(3, rng)
    shift = int(0.24 * RH.FS)
    force_d = force + np.r_[np.zeros(shift), f2[:-shift]]
    acc_d = acc + np.r_[np.zeros(shift), a2[:-shift]]
    with pytest.warns(AccuracyWarning, match=r"record cut at 0\.25\d* s"):
        d = signal.frf(_th(force_d, acc_d), "hammer", exponential_tau_s=0.03, nfft=8192,
                       nperseg=1200, pretrigger=20)
    assert d.attrs["double_hit_action"] == ["cut"]
    f = d["frequency"].values
    band = (f > 20) & (f < 700)
    err = np.abs(d["frf"].values[0, 0, band] / clean["frf"].values[0, 0, band] - 1)
    assert np.median(err) < 0.01


def test_clipping_detector_on_a_known_clip_and_real_files():
    t, force, acc = RH.hit(3, np.random.default_rng(3))
    found = signal.clipped_channels(np.vstack([np.minimum(force, 0.7 * force.max()), acc]),
                                    ["hammer", "acc"], RH.FS)
    assert [c["channel"] for c in found] == ["hammer"] and found[0]["n_samples"] >= 3
    assert signal.clipped_channels(np.vstack([force, acc]), ["hammer", "acc"], RH.FS) == []
    if not SHARED.is_dir():
        pytest.skip(f"external measurement corpus not found at {SHARED}")
    # camera.lvm: the accelerometer sits at +54.791435 g for 16 samples and at -54.677544 g
    # for 10 (the DAQ range), although the hit was 2.2x that of acceleration.lvm, whose
    # largest value (35.46 g) occurs once
    cam = io.read(SHARED / "lvm" / "camera.lvm")["time_history"]
    c = signal.clipped_channels(cam.values, [str(x) for x in cam["channel"].values], 5e4)
    assert [x["channel"] for x in c] == ["Acceleration (Trigger)"]
    assert c[0]["value"] == pytest.approx(54.791435)
    acc_file = io.read(SHARED / "lvm" / "acceleration.lvm")["time_history"]
    assert signal.clipped_channels(acc_file.values, list(acc_file["channel"].values), 5e4) == []
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        d = signal.frf(acc_file, {"quantity": "force"})
    assert d.attrs["double_hit_s"] == [] and d.attrs["clipped"] == ""
    assert not [w for w in rec if "double hit" in str(w.message) or "clipped" in str(w.message)]


def test_quality_table_of_averaged_sets_has_coherence(rng):
    from mvtk import modal
    from mvtk import testing as T

    # two hammer positions, 4 hits each (4 averages): coherence is defined
    a = T.impact_test([30.0, 75.0], [0.01, 0.01], 1024.0, 2.0, 4, rng)
    b = T.impact_test([30.0, 75.0], [0.01, 0.01], 1024.0, 2.0, 4, rng)
    b = b.copy(data=b.values + np.r_[0.0, 0.3][:, None] * np.std(b.values[1])
               * rng.standard_normal(b.shape))  # a noisy response: coherence drops
    a = a.assign_coords(node=("channel", [1, 9]), direction=("channel", ["+z", "+z"]))
    b = b.assign_coords(node=("channel", [2, 9]), direction=("channel", ["+z", "+z"]))
    h = modal.frf_matrix([a, b], {"quantity": "force"})
    q = signal.set_quality(h).to_dataframe()
    assert q["n_averages"].tolist() == [4, 4] and q["n_hits"].tolist() == [4, 4]
    assert q.loc[1, "coherence"] > 0.95 and q.loc[1, "verdict"] == "ok"
    assert q.loc[2, "coherence"] < signal.COHERENCE_MIN
    assert q.loc[2, "verdict"].startswith("mean coherence")
    assert q.loc[1, "peak_force"] == pytest.approx(np.max(np.abs(a.values[0])), rel=1e-6)


def test_window_policy_takes_the_slowest_decay_not_the_noise_floor(rng):
    from mvtk import testing as T

    def one(zeta, noise):
        x = T.impact_test(50.0, zeta, 2048.0, 0.5, 1, rng, pretrigger_s=0.02)
        y = x.values[1] + noise * np.max(np.abs(x.values[1])) * rng.standard_normal(
            x.sizes["time"])
        return x.copy(data=np.vstack([x.values[0], y]))

    slow = [one(0.002, 1e-4), one(0.004, 1e-4)]  # tails (end RMS / peak) ~ 23 %, 17 %
    noisy = one(0.05, 0.03)   # decayed to 0.02 % of its peak, under 3 % noise
    pol = signal.impact_policy(slow, "force")
    assert pol.slowest_set == 1 and pol.tail_ratio > 0.2
    both = signal.impact_policy([noisy, *slow], "force", names=["noisy", "a", "b"])
    assert both.exponential_tau_s == pytest.approx(pol.exponential_tau_s, rel=1e-12)
    assert both.slowest_set == 2 and "(a: tail" in both.reason
    assert "1 set(s) end in their noise floor" in both.reason
    alone = signal.impact_policy([noisy], "force")
    assert alone.exponential_tau_s is None and "no exponential window" in alone.reason
