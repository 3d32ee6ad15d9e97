"""MAT exports holding FRFs only, nested structs and current references (issue 14 item 5)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

import mvtk.io as mio
from mvtk.errors import FormatError, ParameterError

F = np.linspace(0.0, 100.0, 201)


def _frf(fn=40.0, zeta=0.02):
    w, wn = 2 * np.pi * F, 2 * np.pi * fn
    return -(w**2) / (wn**2 - w**2 + 2j * zeta * wn * w)  # accelerance of a unit-mass SDOF


@pytest.mark.parametrize("layout", ["complex", "magphase_deg", "magphase_rad", "realimag"])
def test_frf_only_layouts(tmp_path, layout):
    h = _frf()
    path = tmp_path / "frf.mat"
    if layout == "complex":
        scipy.io.savemat(path, {"H": h[:, None], "f": F[:, None]})
        spec = "H"
        extra = {}
    elif layout.startswith("magphase"):
        deg = layout.endswith("deg")
        phase = np.angle(h, deg=deg)
        scipy.io.savemat(path, {"Hmag": np.abs(h), "Hph": phase, "f": F})
        spec = {"magnitude": "Hmag", "phase": "Hph"}
        extra = {} if deg else {"phase_units": "rad"}
    else:
        scipy.io.savemat(path, {"Hr": h.real, "Hi": h.imag, "f": F})
        spec = {"real": "Hr", "imag": "Hi"}
        extra = {}
    ds = mio.read(
        path, frequency="f", spectra={"frf": spec}, spectrum_units={"frf": "m/s^2/N"}, **extra
    )
    frf = ds["frf"]
    assert frf.dims == ("response", "reference", "frequency") and frf.shape == (1, 1, 201)
    np.testing.assert_allclose(frf.values[0, 0], h, rtol=1e-12, atol=1e-12)
    assert frf.attrs["frf_type"] == "accelerance" and frf.attrs["estimator"] == "measured"
    assert str(frf.quantity.values[0]) == "acceleration"
    assert str(frf.reference_quantity.values[0]) == "force"


def test_nested_struct_paths_and_current_reference(tmp_path):
    h = np.stack([_frf(30.0), _frf(60.0)])  # two responses x lines
    acc = np.sin(np.arange(64) / 5.0)
    cur = np.cos(np.arange(64) / 7.0)
    scipy.io.savemat(
        tmp_path / "nested.mat",
        {"Fe": {"Out": {"Acc": acc, "I": cur}, "H": h, "f": F, "fs": 512.0}},
    )
    ds = mio.read(
        tmp_path / "nested.mat",
        data=["Fe.Out.Acc", "Fe.Out.I"],
        fs="Fe.fs",
        units=["m/s^2", "A"],
        channels=["acc", "coil current"],
        frequency="Fe.f",
        spectra={"frf": "Fe.H"},
        response=["p1", "p2"],
        reference="coil current",
        response_units="m/s^2",
    )
    th = ds["time_history"]
    assert list(th.quantity.values) == ["acceleration", "current"]
    np.testing.assert_array_equal(th.values[0], acc)
    frf = ds["frf"]
    assert frf.shape == (2, 1, 201)
    assert list(frf.reference_units.values) == ["A"]
    assert list(frf.reference_quantity.values) == ["current"]
    assert frf.attrs["frf_type"] == "other"  # acceleration over current
    assert frf.attrs["units"] == "m/s^2/A"
    np.testing.assert_allclose(frf.values[:, 0], h)
    with pytest.raises(FormatError, match=r"no variable 'Fe.Out.Vel'; the file holds: .*Fe.Out"):
        mio.read(tmp_path / "nested.mat", data="Fe.Out.Vel", fs=1.0, units="m/s")


def test_voltage_reference_and_messages_without_numpy_reprs(tmp_path):
    scipy.io.savemat(tmp_path / "v.mat", {"x": np.ones((2, 16)), "H": _frf(), "f": F})
    ds = mio.read(
        tmp_path / "v.mat", frequency="f", spectra={"frf": "H"}, reference_units="V",
        response_units="m/s^2",
    )
    assert list(ds["frf"].reference_quantity.values) == ["voltage"]
    with pytest.raises(FormatError) as err:
        mio.read(tmp_path / "v.mat", data="x", fs=10.0, units=np.array(["A", "V"]),
                 quantity=np.array(["voltage", "voltage"]))
    msg = str(err.value)
    assert "is voltage in 'A'; expected units V, mV, uV" in msg
    assert "np.str_" not in msg and "array(" not in msg


def test_frf_bad_inputs(tmp_path):
    scipy.io.savemat(tmp_path / "b.mat", {"H": _frf(), "P": np.zeros(5), "f": F})
    with pytest.raises(FormatError, match=r"spectra given without frequency="):
        mio.read(tmp_path / "b.mat", spectra={"frf": "H"})
    with pytest.raises(FormatError, match=r"frf variable 'P' has shape \(5,\); expected 201"):
        mio.read(tmp_path / "b.mat", frequency="f", spectra={"frf": "P"})
    with pytest.raises(FormatError, match=r"magnitude 'H' has shape .* phase 'P'"):
        mio.read(tmp_path / "b.mat", frequency="f",
                 spectra={"frf": {"magnitude": "H", "phase": "P"}})
    with pytest.raises(ParameterError, match=r"phase_units='grad'; expected 'deg' or 'rad'"):
        mio.read(tmp_path / "b.mat", frequency="f", phase_units="grad",
                 spectra={"frf": {"magnitude": "H", "phase": "H"}})
    with pytest.raises(ParameterError, match=r"spectra\['frf'\] = 3; expected a variable name"):
        mio.read(tmp_path / "b.mat", frequency="f", spectra={"frf": 3})
