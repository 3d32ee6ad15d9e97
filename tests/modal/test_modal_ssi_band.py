"""SSI-cov's resolvable band: block rows, decimation and single-channel indicators.

External truth: the exact modes of a 5-DOF chain (``modal.exact_modes``) whose ambient
response is sampled 16x faster than its modes need, and the rule for the number of
block rows ``i >= fs / (2 f_0)`` (Rainieri & Fabbrocino, Operational Modal Analysis of
Civil Engineering Structures, Springer 2014, ch. 4).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.ndimage

from mvtk import io, modal
from mvtk.errors import AccuracyWarning, ParameterError, ResolutionWarning

FS_HIGH = 6400.0


def _shared_record(shared_data, relative):
    """The time history of a file of ../shared/data (the test is skipped without it)."""
    src = shared_data / relative
    if not src.is_file():
        pytest.skip(f"{src} not found")
    return io.read(src)["time_history"]


@pytest.fixture(scope="module")
def oversampled(msys):
    return msys.ambient(FS_HIGH, 2**19)[:3]


def test_block_rows_set_the_band_and_warn_about_what_lies_below(oversampled):
    th, fn, _ = oversampled
    # 20 block rows at 6400 Hz resolve >= 160 Hz; the chain's modes lie at 14-97 Hz
    with pytest.warns(ResolutionWarning,
                      match=r"lowest frequency 20 block rows resolve.*peak there: 14\.[2-4]"):
        d = modal.ssi_cov(th, orders=range(2, 41, 2), n_lags=20)
    assert d.band_hz[0] == pytest.approx(FS_HIGH / (2 * 20))
    assert np.all(np.abs(d.pole[d.status == "stable"]) / (2 * np.pi) >= d.band_hz[0])
    with pytest.raises(ParameterError, match="resolve only frequencies above"):
        modal.ssi_cov(th, fmax=1000.0, orders=range(2, 9, 2), n_lags=2)


def test_default_block_rows_resolve_the_lowest_spectral_peak(oversampled, msys):
    th, fn, z = oversampled
    # default: i = ceil(fs / (2 x 0.5 x 14.3 Hz)) = 448 block rows, capped at 2000
    # Toeplitz rows (400 block rows: the band starts at 8 Hz)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ResolutionWarning)
        res = modal.identify_output_only(th, orders=range(2, 41, 2))
    assert res.diagram.band_hz[0] == pytest.approx(FS_HIGH / (2 * 400))
    j = msys.match(res.fn_hz, fn)
    assert np.max(np.abs(res.fn_hz[j] - fn) / fn) < 2e-3


def _three_modes(first_amplitude, seed, fs=400.0, n=2**17):
    """Ambient response of three modes (10.0, 11.5, 30.0 Hz, zeta 1 %) by modal
    synthesis: independent white modal forces, the first ``first_amplitude`` times
    the others', 3 channels, 2 % sensor noise."""
    fn = np.array([10.0, 11.5, 30.0])
    amp = np.array([first_amplitude, 1.0, 1.0])
    phi = np.array([[1, 0.5, -0.3], [0.2, 1, 0.8], [-0.7, 0.4, 1.0]])
    rng = np.random.default_rng(seed)
    w, wn = 2 * np.pi * np.fft.rfftfreq(n, 1 / fs), 2 * np.pi * fn
    P = np.fft.rfft(rng.standard_normal((3, n)), axis=1) * (amp * wn**2)[:, None]
    Q = P / (wn[:, None] ** 2 - w**2 + 2j * 0.01 * wn[:, None] * w)
    y = np.fft.irfft(phi.T @ Q, n, axis=1)
    y += 0.02 * y.std(axis=1, keepdims=True) * rng.standard_normal(y.shape)
    return io.time_history(y, fs, ["a", "b", "c"], "m", "displacement", node=[1, 2, 3],
                           direction="z")


@pytest.mark.parametrize("seed", [0, 2])
def test_default_band_keeps_a_first_mode_near_the_lowest_peak(seed):
    """The first mode (10 Hz, a third of the others' modal force) is the record's lowest
    spectral peak and lies 13 % below a strong second mode. Block rows resolving 0.9 x
    that peak (23 rows: the band starts 13 % below it and the lags span 1.15 of its
    periods) missed it in 2 of 5 records (seeds 0-4; these two) and gave it twice the
    std in the others; the default, an octave below (41 rows), found it in all 5."""
    from mvtk.modal._ssi import _spectral_peaks

    th = _three_modes(0.3, seed)
    peaks = _spectral_peaks(th.values, 400.0)[0]
    assert peaks.min() == pytest.approx(10.0, rel=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        old = modal.identify_output_only(
            th, orders=range(2, 31, 2), n_lags=int(np.ceil(400.0 / (2 * 0.9 * peaks.min()))))
        res = modal.identify_output_only(th, orders=range(2, 31, 2))
    assert not np.any(np.abs(old.fn_hz - 10.0) < 0.1)
    assert res.diagram.band_hz[0] <= 0.5 * peaks.min()
    k = int(np.argmin(np.abs(res.fn_hz - 10.0)))
    assert abs(res.fn_hz[k] - 10.0) < 0.01 * 10.0 and res.reliable[k]
    assert abs(res.zeta[k] - 0.01) < 3 * res.zeta_std[k]
    assert abs(res.fn_hz[k] - 10.0) < 3 * res.fn_std_hz[k]


def test_fmax_decimates_and_recovers_the_modes(oversampled, msys):
    th, fn, z = oversampled
    res = modal.identify_output_only(th, 2, 150, orders=range(2, 41, 2))
    assert res.n_modes == 5
    j = msys.match(res.fn_hz, fn)
    assert np.max(np.abs(res.fn_hz[j] - fn) / fn) < 2e-3
    assert np.max(np.abs(res.zeta[j] - z) / z) < 0.3
    # 6400 Hz / 10 = 640 Hz keeps 150 Hz below 0.4 x the rate
    assert res.diagram.indicator_f_hz.max() == pytest.approx(150.0, abs=1.0)


def test_fmin_raises_the_block_rows(oversampled, msys):
    th, fn, _ = oversampled
    low = float(fn.min())
    d = modal.ssi_cov(th.isel(time=slice(0, 2**18)), fmin=0.8 * low, fmax=150.0,
                      orders=range(2, 41, 2))
    assert d.band_hz[0] == pytest.approx(0.8 * low)


def test_one_channel_has_no_shape_indicators(oversampled):
    th, fn, _ = oversampled
    res = modal.identify_output_only(th.isel(channel=[4]), 2, 150, orders=range(2, 21, 2))
    assert res.n_modes >= 1
    assert np.all(np.isnan(res.mpc)) and np.all(np.isnan(res.mpd))


@pytest.mark.shared_data
def test_ambient_microphone_record_states_what_it_cannot_see(shared_data):
    # Sample_UFF58_ascii.uff: 1.2 s of room sound at 65536 Hz, one microphone; about half
    # its power lies in lines at 24-42 Hz (largest at 32 Hz)
    th = _shared_record(shared_data, "uff/Sample_UFF58_ascii.uff")
    # 61 block rows (the model orders' minimum) see only >= 537 Hz, and say so
    with pytest.warns(ResolutionWarning, match=r"peak there: 3[0-4](\.\d+)? Hz"):
        res = modal.identify_output_only(th, n_lags=61)
    assert res.diagram.band_hz[0] == pytest.approx(65536.0 / (2 * 61), rel=1e-3)
    assert np.all(res.fn_hz >= res.diagram.band_hz[0])
    assert np.all(np.isnan(res.mpc))
    # by default the block rows reach an octave below the lowest spectral peak
    # (29.5 Hz), up to the 2000-row cap (16.4 Hz)
    res = modal.identify_output_only(th)
    assert res.diagram.band_hz[0] == pytest.approx(65536.0 / (2 * 2000), rel=1e-3)
    assert res.fn_hz.min() < 35.0


@pytest.mark.shared_data
@pytest.mark.slow
def test_wind_turbine_tower_against_pyoma2(shared_data):
    """good_tdms_1.tdms: 10 min of 8 tower accelerometers of an offshore wind turbine at
    30 Hz (PROVENANCE.md). The default block rows (81, an octave below the lowest
    spectral peak at 0.375 Hz) reach the first tower modes; the 20 rows of the model
    orders alone start the band at 0.75 Hz and miss them. Peer: pyOMA-2 SSIcov with 45
    block rows."""
    pytest.importorskip("pyoma2", reason="pyOMA-2 (test extra) is not installed")
    import logging

    from pyoma2.algorithms import SSI
    from pyoma2.setup import SingleSetup

    th = _shared_record(shared_data, "tdms/good_tdms_1.tdms")
    res = modal.identify_output_only(th)
    assert res.diagram.band_hz[0] == pytest.approx(30.0 / (2 * 81))
    ok = res.reliable
    fn = res.fn_hz[ok]
    assert fn.min() == pytest.approx(0.3725, abs=0.002)
    logging.disable(logging.WARNING)
    try:
        setup = SingleSetup(th.values.T.astype(float).copy(), fs=30.0)
        alg = SSI(name="ssicov", method="cov", br=45, ordmax=60)
        setup.add_algorithms(alg)
        setup.run_by_name("ssicov")
        setup.mpe("ssicov", sel_freq=list(fn), order_in=40)
    finally:
        logging.disable(logging.NOTSET)
    peer = np.asarray(alg.result.Fn)
    # measured: 0.3723/0.3734, 2.4071/2.4036, 3.2323/3.2230, 4.0100/4.0099,
    # 4.6421/4.6756 Hz (ours/peer); the 1.55 Hz pair differs by 4 %
    well = np.abs(fn - 1.55) > 0.1
    np.testing.assert_allclose(fn[well], peer[well], rtol=0.01)
    np.testing.assert_allclose(fn[~well], peer[~well], rtol=0.06)


def test_a_harmonic_is_told_from_the_modes_by_its_kurtosis(msys):
    # the chain's ambient response at 400 Hz plus a harmonic of a machine running at
    # 55 Hz whose speed wanders by about 0.3 % (a slow random walk of the frequency),
    # carrying about a quarter of the response's variance
    th, fn, _, _ = msys.ambient(400.0, 2**16)
    rng = np.random.default_rng(7)
    walk = np.cumsum(rng.standard_normal(th.sizes["time"]))
    walk = scipy.ndimage.gaussian_filter1d(walk, 2000.0)
    freq = 55.0 * (1 + 0.003 * walk / np.abs(walk).max())
    phase = 2 * np.pi * np.cumsum(freq) / 400.0
    y = th.values + 0.8 * th.values.std(axis=1, keepdims=True) * np.sin(phase)
    res = modal.identify_output_only(th.copy(data=y), 2, 150, orders=range(2, 41, 2))
    h = int(np.argmin(np.abs(res.fn_hz - 55.0)))
    assert abs(res.fn_hz[h] - 55.0) < 0.2 and res.zeta[h] < 5e-3   # found as a "mode"
    assert res.kurtosis[h] < 1.7
    assert not res.reliable[h] and res.reason[h].startswith("harmonic")
    j = msys.match(res.fn_hz, fn)
    assert np.all((res.kurtosis[j] > 2.5) & (res.kurtosis[j] < 3.5)), res.kurtosis[j]
    assert res.reliable[j].all(), [res.reason[k] for k in j]
    assert "kurtosis" in res.to_dataframe().columns


def test_a_strong_peak_without_a_mode_is_named(msys):
    # a constant-speed 55 Hz sinusoid: SSI-cov's poles there have zeta ~ 0 and do not
    # stabilise, so no mode is selected -- and the warning says what was left out
    th, fn, _, _ = msys.ambient(400.0, 2**16)
    t = np.arange(th.sizes["time"]) / 400.0
    y = th.values + 0.8 * th.values.std(axis=1, keepdims=True) * np.sin(2 * np.pi * 55.0 * t)
    with pytest.warns(AccuracyWarning, match=r"no selected mode: 55(\.\d+)? Hz \(band "
                      r"kurtosis 1\.[4-7]\d*: a harmonic\)"):
        res = modal.identify_output_only(th.copy(data=y), 2, 150, orders=range(2, 41, 2))
    assert np.all(np.abs(res.fn_hz - 55.0) > 0.5)


@pytest.mark.shared_data
def test_operational_record_names_its_harmonic(shared_data):
    # MPSTD_Set001: four accelerometers at 3200 Hz; the strongest lines are 181.7 Hz (a
    # clean sinusoid, band kurtosis 1.63) and 182.8 Hz. The default block rows (an octave
    # below the lowest peak) stabilise one lightly damped pole between them (182.14 Hz,
    # zeta 0.06 %) whose own band mixes both lines (kurtosis 2.25): the harmonic line it
    # explains marks it a harmonic
    th = _shared_record(shared_data, "uff/MPSTD_Set001_2024_10_08_10_27_07.uff")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = modal.identify_output_only(th)
    near = np.abs(res.fn_hz - 181.7) <= 0.01 * 181.7
    assert near.sum() == 1
    assert not res.reliable[near][0] and np.asarray(res.reason)[near][0].startswith("harmonic")
    assert res.kurtosis[near][0] == pytest.approx(1.63, abs=0.05)


def test_a_mode_without_uncertainty_is_not_reliable(shared_data):
    """good_tdms_1.tdms: the rows no model order gives a 2-std singular-value gap have
    no standard deviation; they were reliable (1.48/1.56 Hz, 4-6 % from pyOMA-2, and
    3.24 Hz beside the 3.223 Hz mode). Every reliable row now has its std."""
    th = _shared_record(shared_data, "tdms/good_tdms_1.tdms")
    res = modal.identify_output_only(th)
    none = ~np.isfinite(res.zeta_std)
    assert none.any() and (~none).any()
    assert not res.reliable[none].any()
    assert all("no uncertainty: at no model order" in r
               for r, n in zip(res.reason, none) if n)
    assert np.all(np.isfinite(res.fn_std_hz[res.reliable]))
    assert res.reliable.sum() >= 3


def test_a_record_too_short_for_the_block_covariance_says_so():
    """20 s at 256 Hz with 64 block rows: fewer than 10 blocks, no standard deviations,
    so no mode is reliable, and the reason says why."""
    from mvtk import testing

    x = testing.random_excitation_test([20.0, 55.0], [0.01, 0.02], 256.0, 20.0,
                                       np.random.default_rng(0))
    res = modal.identify_output_only(x.sel(channel=["response"]), 5.0, 100.0,
                                     orders=range(2, 21, 2), n_lags=64)
    assert res.n_modes >= 1 and not res.reliable.any()
    assert all("data blocks (< 10)" in r for r in res.reason), res.reason
