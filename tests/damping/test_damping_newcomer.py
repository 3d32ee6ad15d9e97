"""The newcomer path with defaults only, on the real records of ../shared/data (issues 14, 19).

LVM hammer hits (PROVENANCE.md): modes 695.8, 1898.1, 3670.8 Hz with Hilbert-envelope
damping 0.0045, 0.0031, 0.0020 in both files, "loose references (expect +-20 % between
methods)". Swept sine (view_0.hdf5): deterministic excitation, whole record.
"""

import argparse
import json
import re
import warnings

import numpy as np
import pytest
import scipy.signal as ss
import xarray as xr

from mvtk import damping as D
from mvtk import signal as S
from mvtk import testing as T
from mvtk.cli import damping as _cli

io = pytest.importorskip("mvtk.io")

# PROVENANCE.md: spectral peaks and Hilbert-envelope damping (+-20 % between methods)
LVM_MODES = ((695.8, 0.0045), (1898.1, 0.0031), (3670.8, 0.0020))
# PROVENANCE.md: every catalogued response-spectrum peak of both hits (Hz)
LVM_CATALOGUE = (695.8, 1898.1, 2779.7, 3670.8, 5975.0, 8747.5)


def _cli_json(argv, capsys):
    p = argparse.ArgumentParser()
    _cli.add_parser(p.add_subparsers(dest="command"))
    args = p.parse_args(["damping", *argv, "--json"])
    code = args.func(args)
    cap = capsys.readouterr()
    return code, json.loads(cap.out), cap.err


@pytest.fixture(scope="module")
def lvm(shared_data):
    out = {}
    for name in ("acceleration", "camera"):
        src = shared_data / "lvm" / f"{name}.lvm"
        if not src.is_file():
            pytest.skip(f"{src} not found")
        out[name] = (src, io.read(src)["time_history"])
    return out


@pytest.mark.shared_data
@pytest.mark.parametrize("name", ["acceleration", "camera"])
def test_lvm_frf_with_no_options(lvm, name):
    # the io engineer's report: the default impact FRF reserved a 1 % pre-trigger (499
    # samples) on records with 30 and failed. Now: whole record, 1 hit, pretrigger <= 31.
    _, th = lvm[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = S.frf(th, {"quantity": "force"})
    a = d.attrs
    assert a["excitation"] == "impact" and a["n_averages"] == 1
    assert a["pretrigger"] <= 31 and a["nperseg"] == th.sizes["time"]
    assert a["frf_type"] == "accelerance" and a["kind"] == "accelerance"
    # half_power reads the FRF type from the attrs (it used to report "mobility")
    da = d["frf"].drop_vars([c for c in d["frf"].coords if c != "frequency"])
    da.attrs = {"frf_type": "accelerance", "resolution_hz": a["resolution_hz"],
                "excitation_band_hz": a["excitation_band_hz"]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = D.half_power(da, fn_hz=[695.8])
    assert r.kind == ("accelerance",)


@pytest.mark.slow
@pytest.mark.shared_data
def test_lvm_cli_no_options_newcomer_path(lvm, capsys):
    # `mvtk damping FILE` with no option on both hits: the three bending modes reliable,
    # within the PROVENANCE spread; every catalogued peak has a row (at most the
    # documented 20); the two hits agree to 0.1 %
    found = {}
    for src, _ in lvm.values():
        code, rows, _ = _cli_json([str(src)], capsys)
        assert code == 0 and len(rows) <= S.MAX_PEAKS
        for fc in LVM_CATALOGUE:
            assert any(abs((r["fn_hz"] or 0) / fc - 1) < 2e-3 or f"{fc:.4g}"[:3] in
                       r["reason"] for r in rows), (src.name, fc)
        assert {r["kind"] for r in rows} == {"accelerance"}
        for fn, z in LVM_MODES:
            r = min((r for r in rows if r["fn_hz"] is not None),
                    key=lambda r: abs(r["fn_hz"] - fn))
            assert r["fn_hz"] == pytest.approx(fn, rel=1e-3)
            assert r["reliable"] and r["zeta"] == pytest.approx(z, rel=0.2), r
            found.setdefault(fn, []).append(r["fn_hz"])
        assert all(r["reason"] for r in rows if not r["reliable"])
    for fn, (a, b) in found.items():
        assert abs(a - b) / fn < 1e-3


# ----------------------------------------------------------------- swept sine
def _sweep_test(rng, f0=60.0, f1=500.0, fs=2560.0, dur=8.0):
    t = np.arange(int(dur * fs)) / fs
    force = ss.chirp(t, f0, dur, f1)
    acc = np.zeros_like(t)
    for fn, z in ((127.0, 0.01), (265.0, 0.02), (350.0, 0.005)):
        w = 2 * np.pi * fn
        acc += ss.lsim(ss.lti([1, 0, 0], [1, 2 * z * w, w * w]), force, t)[1]
    acc += 0.01 * acc.std() * rng.standard_normal(t.size)
    return T.make_time_history(np.vstack([force, acc]), fs, quantity=["force", "acceleration"],
                               units=["N", "m/s^2"], names=["force", "acc"])


def test_is_sweep_tells_sweeps_from_random_and_impact(rng):
    fs = 2560.0
    t = np.arange(8192) / fs
    assert S.is_sweep(ss.chirp(t, 60, t[-1], 500), fs)
    assert S.is_sweep(ss.chirp(t, 500, t[-1], 60, method="logarithmic"), fs)  # downward
    assert not S.is_sweep(rng.standard_normal(t.size), fs)
    assert not S.is_sweep(np.sin(2 * np.pi * 100 * t), fs)  # one sine does not move
    pulse = np.zeros(t.size)
    pulse[100:110] = 1.0
    assert not S.is_sweep(pulse, fs)


def test_sweep_frf_defaults_whole_record_exact_damping(rng):
    # the defaults engineer's report: a sweep was treated as random (Welch, Hann,
    # 8192-sample segments) and every mode came out coarse. Now: one rectangular record,
    # peaks searched in the swept band only; simulated modes recovered to 5 %.
    x = _sweep_test(rng)
    d = S.frf(x, "force")
    a = d.attrs
    assert a["excitation"] == "sweep" and a["window"] == "boxcar"
    assert a["nperseg"] == x.sizes["time"] and a["n_averages"] == 1
    lo, hi = a["excitation_band_hz"]
    assert 55 < lo <= 65 and 495 <= hi < 520
    r = D.half_power(d)
    # the three modes reliable; ripples of the sweep 3..6 dB high are listed as weak
    # peaks, never reliable
    ok = r.reliable
    assert ok.sum() == 3
    assert all(q.startswith("weak peak") for q, g in zip(r.reason, ok) if not g)
    np.testing.assert_allclose(r.fn_hz[ok], [127.0, 265.0, 350.0], rtol=2e-3)
    np.testing.assert_allclose(r.zeta[ok], [0.01, 0.02, 0.005], rtol=0.05)
    # Hann over the whole sweep weights input and response at different times: biased
    h = D.half_power(S.frf(x, "force", window="hann"), fn_hz=[127.0])
    assert abs(h.zeta[0] / 0.01 - 1) > 0.1


@pytest.mark.shared_data
def test_view0_sweep_cli_reader_options_only(shared_data, capsys):
    # 2 s sweep on a thin plate: detected as a sweep, the whole record (df 0.5 Hz), the
    # trigger channel is not a response; no mode is resolved/isolated well enough and
    # every row says why (exit 1)
    src = shared_data / "hdf5" / "view_0.hdf5"
    if not src.is_file():
        pytest.skip(f"{src} not found")
    argv = [str(src), "--units", "N", "m/s^2", "V", "--quantity", "force", "acceleration",
            "voltage"]
    p = argparse.ArgumentParser()
    _cli.add_parser(p.add_subparsers(dest="command"))
    args = p.parse_args(["damping", *argv])
    code = args.func(args)
    out = capsys.readouterr()
    assert code == 1 and "no reliable estimate" in out.err
    assert "sweep excitation" in out.out and "whole record" in out.out
    assert "df = 0.5 Hz" in out.out and "trigger/" not in out.out
    code, rows, _ = _cli_json(argv, capsys)
    assert code == 1 and rows and len(rows) <= S.MAX_PEAKS
    assert all(not r["reliable"] and r["reason"] for r in rows)
    # a failed row names the peak it is about (its fn_hz is NaN)
    assert all(" Hz" in r["reason"] for r in rows if r["quality"] == "failed")
    fns = [r["fn_hz"] for r in rows if r["fn_hz"] is not None]
    assert min(fns) > 55 and max(fns) < 470  # inside the swept band
    r127 = min(rows, key=lambda r: abs((r["fn_hz"] or 0) - 126.5))
    assert r127["quality"] == "coarse" and "needs a record of" in r127["reason"]


def test_find_peaks_default_band_from_attrs():
    # an FRF stating its excited band: no peak outside it by default
    f = np.linspace(0, 100, 2001)
    h = sum(1 / np.abs(fn**2 - f**2 + 2j * 0.01 * fn * f) for fn in (10.0, 40.0, 80.0))
    da = xr.DataArray(h[None, None], dims=("response", "reference", "frequency"),
                      coords={"frequency": f}, attrs={"excitation_band_hz": [20.0, 70.0]})
    np.testing.assert_allclose(S.find_peaks(da).fn_hz, [40.0], rtol=1e-3)
    explicit = S.find_peaks(da, fmin=30.0, fmax=95.0)
    np.testing.assert_allclose(explicit.fn_hz, [40.0, 80.0], rtol=1e-3)


@pytest.mark.shared_data
def test_lvm_every_catalogued_mode_has_a_verdict(lvm):
    """acceleration.lvm: 8747.5 Hz (force -31 dB, inside the hammer's excited band) is
    estimated, and 2779.7 Hz, a peak 5 dB above the flank it sits on, gets a row marked
    not reliable with the reason instead of none."""
    src, _ = lvm["acceleration"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = D.estimate(io.read(src))
    t = est.table
    k = int(np.argmin(np.abs(t["fn_hz"].fillna(0) - 8747.5)))
    assert abs(t["fn_hz"][k] / 8747.5 - 1) < 1e-3 and t["reliable"][k]
    weak = t[t["reason"].str.startswith("weak peak")]
    assert len(weak) == 1 and not weak["reliable"].any()
    assert re.match(r"weak peak at 278\d\.\d Hz: 5\.\d dB", weak["reason"].iloc[0])
    assert "peaks searched in" in " ".join(est.notes)
