import numpy as np
import pytest

from mvtk import testing as T
from mvtk.errors import ParameterError


@pytest.mark.parametrize("kind", ["receptance", "mobility", "accelerance"])
def test_impulse_response_transform_matches_frf_near_resonance(kind):
    fs = 1000.0
    h = T.impulse_response([50.0], [0.02], fs, 20.0, kind=kind)
    f = np.fft.rfftfreq(h.size, 1 / fs)
    H = np.fft.rfft(h) / fs
    exact = T.modal_frf(f, 50.0, 0.02, kind=kind).values[0, 0]
    sel = (f > 45) & (f < 55)
    assert np.max(np.abs(H[sel] - exact[sel]) / np.abs(exact[sel])) < 3e-3


def test_free_decay_closed_form():
    x = T.sdof_free_decay(10.0, 0.01, 100.0, 5.0, amplitude=2.0, phase=0.5)
    t = x["time"].values
    w = 2 * np.pi * 10.0
    exact = 2.0 * np.exp(-0.01 * w * t) * np.cos(w * np.sqrt(1 - 1e-4) * t + 0.5)
    np.testing.assert_allclose(x.values[0], exact, atol=1e-12)
    assert x.dims == ("channel", "time") and x["time"].values[1] == 0.01
    assert x.attrs["zeta"] == [0.01]


def test_mobility_is_i_omega_receptance():
    f = np.linspace(1, 100, 50)
    r = T.modal_frf(f, [20, 60], [0.01, 0.02]).values[0, 0]
    m = T.modal_frf(f, [20, 60], [0.01, 0.02], kind="mobility").values[0, 0]
    np.testing.assert_allclose(m, 2j * np.pi * f * r)


def test_add_noise_level(rng):
    x = T.make_time_history(np.sin(np.arange(100000) * 0.01), 100.0)
    y = T.add_noise(x, rng, snr_db=20.0)
    noise = y.values - x.values
    assert np.std(noise) / np.sqrt(np.mean(x.values**2)) == pytest.approx(0.1, rel=0.02)
    z = T.add_noise(x, np.random.default_rng(1), rms_fraction=0.05)
    assert z.attrs["noise_rms_fraction"] == 0.05
    # same seed, same noise
    a = T.add_noise(x, np.random.default_rng(5), snr_db=30)
    b = T.add_noise(x, np.random.default_rng(5), snr_db=30)
    np.testing.assert_array_equal(a.values, b.values)


def test_generator_errors(rng):
    with pytest.raises(ParameterError, match=r"zeta must be in \[0, 1\)"):
        T.sdof_free_decay(10.0, 5.0, 100.0, 1.0)
    with pytest.raises(ParameterError, match="fn_hz must be finite and > 0"):
        T.modal_frf([1.0, 2.0], -1.0, 0.01)
    with pytest.raises(ParameterError, match="kind must be one of"):
        T.modal_frf([1.0, 2.0], 1.0, 0.01, kind="inertance")
    with pytest.raises(ParameterError, match="exactly one of snr_db or rms_fraction"):
        T.add_noise(T.sdof_free_decay(10.0, 0.01, 100.0, 1.0), rng)
    with pytest.raises(ParameterError, match="numpy.random.Generator"):
        T.add_noise(T.sdof_free_decay(10.0, 0.01, 100.0, 1.0), 42, snr_db=10)
    with pytest.raises(ParameterError, match="names needs 2 entries"):
        T.make_time_history(np.zeros((2, 10)), 10.0, names=["a"])
    with pytest.raises(ParameterError, match="n_hits must be >= 1"):
        T.impact_test(10.0, 0.01, 100.0, 1.0, 0, rng)
