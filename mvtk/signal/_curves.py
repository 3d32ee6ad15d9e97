"""Turn FRFs and spectra (xarray or numpy) into amplitude curves for peak-based methods."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..errors import DimensionError, FormatError, ParameterError

__all__ = ["AmplitudeCurves", "amplitude_curves"]

# Dataset variables searched, in this order, by amplitude_curves
_VARIABLES = ("frf", "psd", "auto_spectrum", "spectrum")
_KINDS = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


@dataclass(frozen=True)
class AmplitudeCurves:
    """Amplitude (never power) curves on a common frequency axis.

    ``amplitude`` has shape (n_curves, n_freq): ``|H|`` of an FRF or ``sqrt(PSD)``.

    Examples
    --------
    Returned by :func:`amplitude_curves`: one row of ``|H|`` per response/reference pair:

    >>> from mvtk import testing
    >>> c = amplitude_curves(testing.modal_frf(np.arange(0.0, 100.0, 0.125), 20.0, 0.01))
    >>> c.amplitude.shape, c.labels
    ((1, 800), ('response/force',))
    """

    f_hz: np.ndarray
    amplitude: np.ndarray
    labels: tuple[str, ...]
    kinds: tuple[str, ...]
    attrs: dict
    #: The complex values behind ``amplitude`` when the input was complex (an FRF or a
    #: complex spectrum), same shape; None for power or real input.
    complex_values: np.ndarray | None = None


def _check_frequency(f: np.ndarray, where: str) -> np.ndarray:
    f = np.asarray(f, dtype=float)
    if f.ndim != 1 or f.size < 3:
        raise DimensionError(f"{where}: need a 1-D frequency axis of >= 3 lines, got {f.shape}")
    df = np.diff(f)
    if np.any(~np.isfinite(f)) or np.any(df <= 0):
        raise FormatError(f"{where}: frequency axis (Hz) must be finite and increasing")
    return f


def _frf_type(attrs: dict) -> str:
    t = attrs.get("frf_type", "")
    return t if t in ("receptance", "mobility", "accelerance") else ""


def amplitude_curves(spectrum, f_hz=None, *, power: bool | None = None,
                     kind: str = "auto") -> AmplitudeCurves:
    """Amplitude curves from an FRF or spectrum.

    Parameters
    ----------
    spectrum : xarray.Dataset, xarray.DataArray or array_like
        * Dataset with an ``"frf"`` variable (from :func:`mvtk.signal.frf` or
          ``mvtk.io.read``), else a ``"psd"`` or ``"auto_spectrum"`` variable (power),
          else a ``"spectrum"`` variable (complex: amplitude; real: power when
          ``attrs["spectrum_type"]`` is ``"psd"`` or ``"power"``);
        * DataArray FRF, dims ``("response", "reference", "frequency")``;
        * DataArray spectrum, dims ``("channel", "frequency")`` (``attrs["spectrum"] ==
          "psd"`` marks a power spectrum);
        * numpy array (n_freq,) or (n_curves, n_freq) with ``f_hz`` given.
    f_hz : array_like, optional
        Frequency lines in Hz for numpy input.
    power : bool, optional
        True if the values are a power quantity (PSD): the square root is taken.
        Default: from ``attrs["spectrum"]`` for xarray input, False for numpy input.
    kind : {"auto", "receptance", "mobility", "accelerance"}
        FRF type; ``"auto"`` reads ``attrs["kind"]`` or the response ``quantity``.

    Examples
    --------
    At resonance the receptance of a mode with unit modal constant is
    ``1 / (2 zeta w_n**2)`` (m/N):

    >>> from mvtk import testing
    >>> h = testing.modal_frf(np.arange(0.0, 100.0, 0.125), 20.0, 0.01)
    >>> c = amplitude_curves(h)
    >>> c.amplitude.shape, c.kinds
    ((1, 800), ('receptance',))
    >>> i = int(np.argmin(np.abs(c.f_hz - 20.0)))
    >>> round(float(c.amplitude[0, i]) * 2 * 0.01 * (2 * np.pi * 20.0) ** 2, 3)
    1.0
    """
    if kind not in ("auto", "receptance", "mobility", "accelerance"):
        raise ParameterError(
            f"kind must be 'auto', 'receptance', 'mobility' or 'accelerance', got {kind!r}"
        )
    attrs: dict = {}
    if isinstance(spectrum, xr.Dataset):
        name = next((v for v in _VARIABLES if v in spectrum.data_vars), None)
        if name is None:
            raise FormatError(
                f"expected a Dataset with one of the variables {list(_VARIABLES)} (an FRF or "
                f"a spectrum), found {sorted(map(str, spectrum.data_vars))}"
            )
        attrs = dict(spectrum.attrs)
        spectrum = spectrum[name]
        if name in ("psd", "auto_spectrum") and power is None:
            power = True  # PSD / auto spectrum from mvtk.io.read: a power quantity
    if isinstance(spectrum, xr.DataArray):
        attrs = {**attrs, **spectrum.attrs}
        if "frequency" not in spectrum.dims:
            raise DimensionError(
                f"expected a 'frequency' dimension, found dims {tuple(map(str, spectrum.dims))}"
            )
        f = _check_frequency(spectrum["frequency"].values, "spectrum")
        other = [d for d in spectrum.dims if d != "frequency"]
        da = spectrum.transpose(*other, "frequency")
        vals = np.asarray(da.values)
        if set(other) == {"response", "reference"}:
            da = spectrum.transpose("response", "reference", "frequency")
            vals = np.asarray(da.values)
            labels = [f"{a}/{b}" for a in da["response"].values for b in da["reference"].values]
            qty = [str(q) for q in da["response_quantity"].values] \
                if "response_quantity" in da.coords else [""] * da.sizes["response"]
            auto = [attrs.get("kind") or _frf_type(attrs) or _KINDS.get(q, "") for q in qty
                    for _ in range(da.sizes["reference"])]
        elif other == ["channel"]:
            labels = [str(c) for c in da["channel"].values]
            qty = [str(q) for q in da["quantity"].values] if "quantity" in da.coords \
                else [""] * len(labels)
            auto = [attrs.get("kind") or _frf_type(attrs) or _KINDS.get(q, "") for q in qty]
        elif other == []:
            labels = [str(spectrum.name or "spectrum")]
            auto = [attrs.get("kind", "")]
        else:
            raise DimensionError(
                "expected dims ('response', 'reference', 'frequency') or ('channel', "
                f"'frequency'), found {tuple(map(str, spectrum.dims))}"
            )
        vals = vals.reshape(-1, f.size)
        if power is None:
            power = (attrs.get("spectrum") in ("psd", "power")
                     or attrs.get("spectrum_type") in ("psd", "power")) \
                and not np.iscomplexobj(vals)
    else:
        if f_hz is None:
            raise ParameterError("f_hz (Hz) is required when the spectrum is a numpy array")
        f = _check_frequency(f_hz, "f_hz")
        vals = np.asarray(spectrum)
        if vals.ndim == 1:
            vals = vals[None, :]
        if vals.ndim != 2 or vals.shape[1] != f.size:
            raise DimensionError(
                f"spectrum must have shape (n_freq,) or (n_curves, n_freq) with n_freq = "
                f"{f.size} (len of f_hz), got {vals.shape}"
            )
        labels = [f"curve{i}" for i in range(vals.shape[0])]
        auto = [""] * vals.shape[0]
        power = bool(power)
    if np.iscomplexobj(vals):
        if power:
            raise ParameterError("a complex spectrum cannot be a power quantity (power=True)")
        amp = np.abs(vals)
    else:
        amp = np.asarray(vals, dtype=float)
        if power:
            if np.any(amp < 0):
                raise FormatError("a power spectrum (PSD) must be >= 0; found negative values")
            amp = np.sqrt(amp)
        else:
            amp = np.abs(amp)
    kinds = tuple(kind if kind != "auto" else (k or "mobility") for k in auto)
    return AmplitudeCurves(f, amp, tuple(labels), kinds, attrs,
                           vals if np.iscomplexobj(vals) else None)
