"""End to end on files: mvtk.io.read -> mvtk.signal -> mvtk.damping."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from mvtk import damping as D
from mvtk import signal as S
from mvtk.errors import AccuracyWarning, ResolutionWarning

io = pytest.importorskip("mvtk.io")
BEAM = Path(__file__).resolve().parents[2] / "data" / "smart_beam"


@pytest.mark.shared_data
def test_hdf5_swept_sine_h1_peaks(shared_data):
    # PROVENANCE.md: H1 peaks near 77, 127, 214..226, 265, 350, 455..466 Hz
    ds = io.read(shared_data / "hdf5" / "view_0.hdf5", units=["N", "m/s^2", "V"],
                 quantity=["force", "acceleration", "voltage"])
    d = S.frf(ds, "force", response="acc", nperseg=25600)
    assert d.attrs["kind"] == "accelerance" and d.attrs["df_hz"] == 1.0
    pk = S.find_peaks(d, fmin=60, fmax=500, n_peaks=6)
    for target, tol in ((77, 1.5), (127, 1.5), (220, 6.5), (265, 1.5), (350, 1.5), (460, 6)):
        assert np.min(np.abs(pk.fn_hz - target)) <= tol, (target, pk.fn_hz)


@pytest.fixture(scope="module")
def beam_files():
    files = [BEAM / "SYNTHETIC_smart_beam_impact.csv", BEAM / "SYNTHETIC_smart_beam_decay.csv"]
    if not all(f.is_file() for f in files):
        pytest.skip("data/smart_beam SYNTHETIC files not present")
    return [io.read(f) for f in files]


def test_smart_beam_impact_frf_warns(beam_files):
    # 3 hits, 125 s records: mode 1 (band 0.0155 Hz) has < 2 lines; mode 2 is noisy
    impact, _ = beam_files
    d = S.frf(impact, "force", excitation="impact", nperseg=16000, pretrigger=64,
              force_window_s=None, detrend=False)
    assert d.attrs["n_averages"] == 3
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        r = D.half_power(d, fn_hz=[13.26, 41.14], method="interpolate", max_scatter=0.03)
    cats = {w.category: str(w.message) for w in rec}
    assert re.search(r"13\.26 Hz: 1\.\d lines", cats[ResolutionWarning])
    assert "41.14 Hz" in cats[AccuracyWarning]
    assert r.quality == ("coarse", "noisy")
    np.testing.assert_allclose(r.fn_hz, [13.26, 41.14], rtol=5e-4)


def test_smart_beam_time_domain_damping_and_rayleigh(beam_files):
    # README truth: zeta1 = 5.84e-4 @ 13.26 Hz, zeta2 = 1.32e-3 @ 41.14 Hz,
    # alpha = 0.02955 1/s, beta = 9.77e-6 s
    impact, decay = beam_files
    z1 = D.envelope_fit(decay, fn_hz=13.26)
    np.testing.assert_allclose(z1.zeta, 5.84e-4, rtol=0.01)
    z1b = D.log_decrement(decay, fn_hz=13.26)
    np.testing.assert_allclose(z1b.zeta, 5.84e-4, rtol=0.01)
    # mode 2 from the free ringing after the first hit, band-passed around 41 Hz
    th = impact["time_history"].sel(channel=["tip_accel"])
    fs = 128.0
    ring = th.isel(time=slice(int(2.5 * fs), int(120 * fs)))
    ring = ring.assign_coords(time=np.arange(ring.sizes["time"]) / fs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        z2 = D.envelope_fit(ring, band_hz=(30.0, 50.0))
    assert z2.zeta[0] == pytest.approx(1.32e-3, rel=0.02)
    assert z2.fn_hz[0] == pytest.approx(41.14, rel=1e-4)
    fit = D.rayleigh_fit([z1.fn_hz[0], z2.fn_hz[0]], [z1.zeta[0], z2.zeta[0]])
    assert fit.alpha == pytest.approx(0.02955, rel=0.03)
    assert fit.beta == pytest.approx(9.77e-6, rel=0.03)


def test_smart_beam_impact_force_window_cleans_the_frf(beam_files):
    # the force window removes the force channel's noise between hits: mode 2 is then
    # clean (quality ok) and both modes match the README truth; mode 1 stays "coarse"
    # (1.98 lines) although the exact interpolation on a rectangular record recovers it
    impact, _ = beam_files
    d = S.frf(impact, "force", response="tip_accel", excitation="impact", nperseg=16384,
              force_window_s=0.05)
    with pytest.warns(ResolutionWarning):
        r = D.half_power(d, fn_hz=[13.26, 41.14])
    assert r.quality == ("coarse", "ok")
    np.testing.assert_allclose(r.zeta, [5.84e-4, 1.32e-3], rtol=0.01)
    fit = D.rayleigh_fit(r.fn_hz, r.zeta)
    assert fit.alpha == pytest.approx(0.02955, rel=0.01)
    assert fit.beta == pytest.approx(9.77e-6, rel=0.01)
