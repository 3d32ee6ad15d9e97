import numpy as np
import pytest
import scipy.signal
import xarray as xr

from mvtk import testing as T
from mvtk.damping import half_power
from mvtk.errors import (
    AccuracyWarning,
    DimensionError,
    FormatError,
    ParameterError,
    ResolutionWarning,
)
from mvtk.signal import csd, exponential_window_correction, find_peaks, frf, psd


@pytest.fixture
def random_test(rng):
    return T.random_excitation_test([20.0, 55.0], [0.02, 0.03], 512.0, 200.0, rng)


def test_psd_equals_scipy_welch(random_test):
    p = psd(random_test, nperseg=1024)
    f, ref = scipy.signal.welch(random_test.values, fs=512.0, nperseg=1024)
    np.testing.assert_allclose(p.values, ref, rtol=1e-12)
    np.testing.assert_allclose(p["frequency"].values, f)
    assert p.dims == ("channel", "frequency")
    assert list(p["units"].values) == ["(N)^2/Hz", "(m/s^2)^2/Hz"]
    assert p.attrs["spectrum"] == "psd" and p.attrs["df_hz"] == 0.5


def test_psd_parseval_white_noise(rng):
    # one-sided density integrates to the variance
    x = T.make_time_history(rng.standard_normal(2**16) * 3.0, 1000.0)
    p = psd(x, nperseg=1024)
    var = np.trapezoid(p.values[0], p["frequency"].values)
    assert var == pytest.approx(9.0, rel=0.03)


def test_csd_equals_scipy_csd(random_test):
    c = csd(random_test, reference="force", nperseg=512, noverlap=128, window="hamming")
    _, ref = scipy.signal.csd(random_test.values[0], random_test.values, fs=512.0,
                              nperseg=512, noverlap=128, window="hamming")
    np.testing.assert_allclose(c.values[:, 0], ref, rtol=1e-10, atol=1e-15 * np.abs(ref).max())
    assert c.dims == ("response", "reference", "frequency")


def test_dataset_input_accepted(random_test):
    ds = xr.Dataset({"time_history": random_test})
    np.testing.assert_allclose(psd(ds, nperseg=256).values, psd(random_test, nperseg=256).values)


def test_h1_recovers_modal_frf(random_test):
    d = frf(random_test, "force", nperseg=8192)
    f = d["frequency"].values
    exact = T.modal_frf(f, [20, 55], [0.02, 0.03], kind="accelerance").values[0, 0]
    sel = (f > 5) & (f < 100)
    err = np.abs(d["frf"].values[0, 0, sel] - exact[sel]) / np.abs(exact[sel])
    assert np.median(err) < 0.01 and np.max(err) < 0.05  # Hann leakage at the peaks
    assert d.attrs["kind"] == "accelerance"
    assert np.min(d["coherence"].values[0, 0, sel]) > 0.99
    assert str(d["units"].values[0, 0]) == "m/s^2/N"


def test_h1_h2_bias_with_reference_noise(rng):
    # noise on the force biases H1 low and leaves H2 unbiased (at resonance)
    x = T.random_excitation_test(30.0, 0.02, 256.0, 400.0, rng, kind="receptance")
    noisy = x.copy(data=x.values.copy())
    noisy.values[0] += 0.5 * rng.standard_normal(x.sizes["time"])
    h1 = frf(noisy, "force", nperseg=4096, estimator="H1")
    h2 = frf(noisy, "force", nperseg=4096, estimator="H2")
    f = h1["frequency"].values
    band = (f > 5) & (f < 15)  # off resonance: gamma^2 ~ 1 / (1 + 0.25)
    exact = np.abs(T.modal_frf(f[band], 30.0, 0.02).values[0, 0])
    r1 = np.median(np.abs(h1["frf"].values[0, 0, band]) / exact)
    r2 = np.median(np.abs(h2["frf"].values[0, 0, band]) / exact)
    assert r1 == pytest.approx(0.8, abs=0.04)
    assert r2 == pytest.approx(1.0, abs=0.04)


def test_multi_reference_h1(rng):
    n, fs = 2**17, 256.0
    f1, f2 = rng.standard_normal((2, n))
    fr = np.fft.rfftfreq(n, 1 / fs)
    ha = T.modal_frf(fr, 20.0, 0.05).values[0, 0]
    hb = T.modal_frf(fr, 40.0, 0.05, modal_constants=2.0).values[0, 0]
    y = np.fft.irfft(ha * np.fft.rfft(f1) + hb * np.fft.rfft(f2), n)
    x = T.make_time_history(np.vstack([f1, f2, y]), fs, quantity=["force", "force", "displacement"],
                            units=["N", "N", "m"], names=["fa", "fb", "y"])
    d = frf(x, {"quantity": "force"}, nperseg=2048)
    f = d["frequency"].values
    sel = (f > 5) & (f < 80)
    for j, h in enumerate((ha, hb)):
        exact = np.interp(f, fr, h.real) + 1j * np.interp(f, fr, h.imag)
        err = np.abs(d["frf"].values[0, j, sel] - exact[sel]) / np.abs(exact[sel])
        assert np.median(err) < 0.05


def test_impact_frf_and_half_power(rng):
    fn, zeta = 40.0, 0.01
    x = T.impact_test(fn, zeta, 1024.0, 8.0, 5, rng)
    d = frf(x, "force", excitation="impact", nperseg=7168, pretrigger=20, force_window_s=0.01)
    assert d.attrs["n_averages"] == 5 and d.attrs["window"] == "boxcar"
    hp = half_power(d, fn_hz=[fn])
    assert hp.fn_hz[0] == pytest.approx(fn, rel=1e-3)
    assert hp.zeta[0] == pytest.approx(zeta, rel=0.03)


def test_exponential_window_is_corrected(rng):
    # 2 s records of a lightly damped mode: truncated without a window; an exponential
    # window adds known damping that half_power removes again
    fn, zeta = 40.0, 0.002
    x = T.impact_test(fn, zeta, 1024.0, 2.0, 4, rng)
    tau = 0.3
    d = frf(x, "force", excitation="impact", nperseg=1900, pretrigger=20, exponential_tau_s=tau)
    assert d.attrs["exponential_window_tau_s"] == tau
    with pytest.warns(ResolutionWarning):  # 2.4 lines across the (window-widened) band
        hp = half_power(d, fn_hz=[fn], method="interpolate")
    assert hp.zeta[0] == pytest.approx(zeta, rel=0.03)
    with pytest.warns(ResolutionWarning):
        raw = half_power(d, fn_hz=[fn], exponential_tau_s=None)
    assert raw.zeta[0] > 2 * zeta


def test_exponential_window_correction_exact():
    fn, zeta, tau = 13.0, 0.004, 0.5
    w = 2 * np.pi * fn
    sig_m = zeta * w + 1 / tau
    wd = w * np.sqrt(1 - zeta**2)
    wm = np.hypot(sig_m, wd)
    f_back, z_back = exponential_window_correction(wm / (2 * np.pi), sig_m / wm, tau)
    assert f_back == pytest.approx(fn, rel=1e-12) and z_back == pytest.approx(zeta, rel=1e-10)
    with pytest.raises(ParameterError, match="tau_s"):
        exponential_window_correction(fn, zeta, 0.0)


def test_impact_double_hit_rejected(rng):
    x = T.impact_test(40.0, 0.01, 1024.0, 2.0, 4, rng)
    vals = x.values.copy()
    vals[0, 1024 + 300:1024 + 302] = 1.0  # a second hit 1.24 s after the first
    x2 = x.copy(data=vals)
    with pytest.warns(AccuracyWarning, match=r"double hit: a second force pulse at 1\.293 s "
                      r".* inside its record of 1\.758 s, record refused"):
        d = frf(x2, "force", excitation="impact", nperseg=1800)
    # the first record holds the spike; the spike's own record and that of the hit 0.76 s
    # after it start on a still ringing response: refused too
    assert d.attrs["n_averages"] == 2
    assert d.attrs["double_hit_action"] == ["refused"] * 3


def test_frf_errors(random_test):
    with pytest.raises(ParameterError, match="estimator must be 'H1' or 'H2', got 'H3'"):
        frf(random_test, "force", estimator="H3")
    with pytest.raises(ParameterError, match="channel 'hammer' not found"):
        frf(random_test, "hammer")
    with pytest.raises(ParameterError, match="every channel is a reference"):
        frf(random_test, ["force", "response"])
    with pytest.raises(ParameterError, match="exactly one reference"):
        frf(random_test, [0, 1], response=[1], estimator="H2")
    with pytest.raises(ParameterError, match="apply to excitation='impact' only"):
        frf(random_test, "force", exponential_tau_s=1.0)
    zero = random_test.copy(data=np.zeros_like(random_test.values))
    with pytest.raises(FormatError, match="all zeros"):
        frf(zero, "force", excitation="impact")
    with pytest.raises(ParameterError, match="nperseg must be in"):
        psd(random_test, nperseg=10**9)


def test_input_errors(random_test):
    with pytest.raises(ParameterError, match="disagrees with the time coordinate"):
        psd(random_test, fs=500.0)
    with pytest.raises(DimensionError, match=r"expected dims \('channel', 'time'\)"):
        psd(random_test.rename(time="t"))
    with pytest.raises(FormatError, match="'time_history' variable"):
        psd(xr.Dataset({"x": random_test}))
    with pytest.raises(ParameterError, match="expected an xarray.DataArray"):
        psd(np.zeros((2, 100)))
    vals = random_test.values.copy()
    vals[1, 100:103] = np.nan
    with pytest.raises(FormatError, match=r"channel\(s\) \['response'\] hold \[3\] missing"):
        frf(random_test.copy(data=vals), "force")
    t = random_test["time"].values.copy()
    t[50] += 1e-3
    with pytest.raises(FormatError, match="not uniformly sampled"):
        psd(random_test.assign_coords(time=t))


def test_find_peaks_frf():
    f = np.arange(0, 200, 0.05)
    h = T.modal_frf(f, [30.0, 75.0, 140.0], [0.01, 0.02, 0.01])
    pk = find_peaks(h, n_peaks=3)
    np.testing.assert_allclose(pk.fn_hz, [30, 75, 140], rtol=2e-3)
    assert list(pk.to_dataframe().columns) == ["fn_hz", "index", "amplitude", "prominence_db"]
    with pytest.raises(ParameterError, match="n_peaks must be >= 1"):
        find_peaks(h, n_peaks=0)
    with pytest.raises(ParameterError, match="f_hz"):
        find_peaks(h.values[0, 0])


@pytest.mark.shared_data
def test_find_peaks_free_free_beam(shared_data):
    # PROVENANCE.md: peaks near 52, 142, 279, 460, 687, 959 Hz
    h = np.loadtxt(shared_data / "uff" / "meas_point_1.txt", dtype=complex)
    pk = find_peaks(h, np.arange(h.size, dtype=float), n_peaks=6)
    np.testing.assert_allclose(pk.fn_hz, [52, 142, 279, 460, 687, 959], atol=1.0)


def test_psd_auto_segment_resolves_the_mode():
    # issue 14: a fixed 256-sample default gives 2 Hz lines for a 0.2 Hz wide mode
    rng = np.random.default_rng(2)
    x = T.random_excitation_test([20.0], [0.005], 512.0, 400.0, rng).isel(channel=[1])
    p = psd(x)
    band = 2 * 0.005 * 20.0
    assert band / p.attrs["df_hz"] >= 5 and p.attrs["n_averages"] >= 8
    assert "narrowest peak" in p.attrs["resolution_reason"]
    assert psd(x, nperseg=None).attrs["nperseg"] == 256  # scipy's default on request


def test_find_peaks_ignores_nan_lines():
    f = np.linspace(0, 100, 2001)
    h = np.abs(T.modal_frf(f, [40.0], [0.02]).values[0, 0])
    h[0] = np.nan  # 0/0 at 0 Hz of an H1 FRF
    assert find_peaks(h, f).fn_hz == pytest.approx([40.0], rel=1e-3)
    with pytest.raises(FormatError, match="no finite value"):
        find_peaks(np.full(10, np.nan), np.arange(10.0))
