import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtk import testing as T
from mvtk.damping import envelope_fit, log_decrement
from mvtk.errors import DimensionError, FormatError, ParameterError, ResolutionWarning


def _decay(fn, zeta, rng, snr_db=40.0, fs=256.0, cycles_to_5pct=None, mdof=False):
    # record long enough for the envelope to fall to about 5 % (3 time constants) x 1.5
    dur = min(1.5 * 3.0 / (zeta * 2 * np.pi * fn), 600.0)
    if mdof:
        x = T.mdof_free_decay([fn, 3.1 * fn], [zeta, zeta], fs, dur, amplitudes=[1.0, 0.5])
    else:
        x = T.sdof_free_decay(fn, zeta, fs, dur, phase=0.3)
    return x if snr_db is None else T.add_noise(x, rng, snr_db=snr_db)


@pytest.mark.parametrize("zeta", [5e-4, 2e-3, 1e-2, 5e-2])
@pytest.mark.parametrize("estimator", [log_decrement, envelope_fit])
def test_sdof_accuracy_40db(zeta, estimator):
    rng = np.random.default_rng(11)
    x = _decay(13.26, zeta, rng)
    r = estimator(x)
    assert abs(r.zeta[0] / zeta - 1) < 0.02
    assert r.fn_hz[0] == pytest.approx(13.26, rel=1e-3)
    assert r.zeta_std[0] > 0


@pytest.mark.parametrize("zeta", [5e-4, 2e-3, 1e-2, 5e-2])
@pytest.mark.parametrize("estimator", [log_decrement, envelope_fit])
def test_two_mode_decay_band_passed_40db(zeta, estimator):
    # the second mode (3.1 fn, like the paper's torsion mode) is removed by the band-pass
    rng = np.random.default_rng(12)
    x = _decay(13.26, zeta, rng, mdof=True)
    r = estimator(x, fn_hz=13.26)
    assert abs(r.zeta[0] / zeta - 1) < 0.02
    assert r.band_hz == pytest.approx((6.63, 19.89))


def test_paper_mode1_long_record():
    # PHYSICS.md 2: mode 1 of the paper's beam, zeta 5.84e-4, time constant 20.5 s
    rng = np.random.default_rng(13)
    x = T.add_noise(T.sdof_free_decay(13.26, 5.84e-4, 256.0, 60.0), rng, snr_db=40)
    for est in (log_decrement, envelope_fit):
        r = est(x, fn_hz=13.26)
        assert r.zeta[0] == pytest.approx(5.84e-4, rel=0.02)


def test_uncertainty_is_consistent(rng):
    # the reported standard error is of the order of the scatter over noise realisations
    zeta = 2e-3
    zs, ses = [], []
    for _ in range(12):
        r = envelope_fit(_decay(20.0, zeta, rng, snr_db=30.0))
        zs.append(r.zeta[0])
        ses.append(r.zeta_std[0])
    scatter = np.std(zs, ddof=1)
    assert 0.1 * scatter < np.median(ses) < 10 * scatter


def test_peaks_envelope_and_dataframe(rng):
    x = _decay(13.26, 5e-3, rng, snr_db=None)
    r = envelope_fit(x, method="peaks")
    assert r.zeta[0] == pytest.approx(5e-3, rel=0.02)
    df = r.to_dataframe()
    assert list(df["channel"]) == ["decay"] and df["method"].iloc[0] == "envelope_peaks"


def test_dataset_and_multichannel(rng):
    a = T.sdof_free_decay(10.0, 0.01, 200.0, 20.0)
    b = T.sdof_free_decay(10.0, 0.02, 200.0, 20.0)
    x = T.make_time_history(np.vstack([a.values[0], b.values[0]]), 200.0, names=["a", "b"])
    r = log_decrement(xr.Dataset({"time_history": x}))
    np.testing.assert_allclose(r.zeta, [0.01, 0.02], rtol=0.01)
    r = envelope_fit(x, channel="b")
    assert r.channel == ("b",)


@settings(max_examples=12, deadline=None)
@given(fn=st.floats(2.0, 20.0), log_zeta=st.floats(np.log10(5e-4), np.log10(0.05)),
       amp=st.floats(1e-6, 1e6), phase=st.floats(0, 2 * np.pi))
def test_property_noise_free(fn, log_zeta, amp, phase):
    # >= 10 samples per period (fs = 200 Hz); fewer gives a ResolutionWarning (below)
    zeta = 10**log_zeta
    dur = min(4.5 / (zeta * 2 * np.pi * fn), 120.0)
    x = T.sdof_free_decay(fn, zeta, 200.0, dur, amplitude=amp, phase=phase)
    r = log_decrement(x)
    assert r.zeta[0] == pytest.approx(zeta, rel=0.01)
    assert r.fn_hz[0] == pytest.approx(fn, rel=1e-3)


def test_few_samples_per_period_warns():
    x = T.sdof_free_decay(39.5, 0.01, 200.0, 5.0)
    with pytest.warns(ResolutionWarning, match="5.1 samples per period"):
        log_decrement(x)


def test_errors(rng):
    x = _decay(13.26, 5e-3, rng)
    with pytest.raises(ParameterError, match="method must be 'hilbert' or 'peaks'"):
        envelope_fit(x, method="prony")
    with pytest.raises(ParameterError, match="threshold must be in"):
        log_decrement(x, threshold=1.5)
    with pytest.raises(ParameterError, match="trim must be in"):
        envelope_fit(x, trim=0.6)
    with pytest.raises(ParameterError, match=r"fn_hz must be in \(0, fs/2"):
        log_decrement(x, fn_hz=500.0)
    with pytest.raises(ParameterError, match="band_hz must satisfy"):
        envelope_fit(x, band_hz=(20.0, 10.0))
    with pytest.raises(DimensionError, match="at least 16 samples"):
        log_decrement(x.isel(time=slice(0, 10)))
    with pytest.raises(FormatError, match="'time_history'"):
        log_decrement(xr.Dataset({"x": x}))
    flat = T.make_time_history(np.ones(1000), 100.0)
    with pytest.raises(ParameterError, match="usable peaks"):
        log_decrement(flat)
