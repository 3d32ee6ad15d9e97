"""One damping estimator per measurement: what ``mvtk damping FILE`` and a study both call.

:func:`estimate` picks the estimator from what the data hold (an FRF or spectrum ->
half-power; time histories with a force/reference channel -> H1 FRF with the record
and windows chosen from the data, then half-power; time histories without a reference
-> envelope fit of the free decay per channel) and returns the table with the settings
it used, so that the command line and a study give the same numbers for the same file
and options, and each can state how they were obtained.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..errors import ParameterError

__all__ = ["DampingEstimate", "estimate", "METHODS", "VARIANTS"]

#: Estimators of :func:`estimate` (``auto`` picks one from the data).
METHODS = ("auto", "half_power", "envelope", "log_decrement")
#: Variants of each estimator; the first is the default.
VARIANTS = {"half_power": ("fit", "interpolate"), "envelope": ("hilbert", "peaks")}
_SPECTRA = ("frf", "psd", "auto_spectrum", "spectrum")
_MOTION = ("displacement", "velocity", "acceleration")


@dataclass(frozen=True, eq=False)
class DampingEstimate:
    """The result of :func:`estimate`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per mode (half-power) or per channel and mode (decay fits), with the
        estimator's columns (``fn_hz`` in Hz, ``zeta`` as a ratio, ``reliable``,
        ``reason``, ...).
    method : str
        Estimator used (``half_power``, ``envelope`` or ``log_decrement``).
    variant : str or None
        Its variant (``fit``/``interpolate``, ``hilbert``/``peaks``; None for
        ``log_decrement``).
    notes : list of str
        How the input was prepared (method chosen, responses, FRF resolution).
    settings : dict
        Every setting that decided the numbers (method, variant, the FRF's excitation,
        record length ``nperseg`` and FFT length ``nfft`` in samples, resolution in Hz,
        force window in s, the frequencies searched in Hz, the decay band in Hz).
    frf : xarray.Dataset or None
        The FRF estimated from time histories (None when the input was a spectrum or a
        decay).

    Examples
    --------
    Returned by :func:`estimate`; ``table`` is a pandas DataFrame and ``settings`` records
    what decided the numbers:

    >>> from mvtk import testing
    >>> est = estimate(testing.sdof_free_decay(12.0, 0.01, 256.0, 10.0))
    >>> est.settings["method"], list(est.table["zeta"].round(4))
    ('envelope', [0.01])
    """

    table: Any
    method: str
    variant: str | None
    notes: list = field(default_factory=list)
    settings: dict = field(default_factory=dict)
    frf: Any = None


def _dataset(data):
    import xarray as xr

    if isinstance(data, xr.DataArray):
        name = data.name if data.name in _SPECTRA else "time_history"
        return data.to_dataset(name=name)
    return data


def _has_reference(ds, reference) -> bool:
    th = ds["time_history"]
    if reference is not None:
        return True
    return "quantity" in th.coords and "force" in [str(q) for q in th["quantity"].values]


def _half_power_input(ds, *, reference, channel, excitation, nperseg, force_window_s,
                      notes, settings):
    from .. import signal

    if "time_history" in ds.data_vars and not any(v in ds.data_vars for v in _SPECTRA):
        ref = reference if reference is not None else {"quantity": "force"}
        resp = channel
        th = ds["time_history"]
        if resp is None and "quantity" in th.coords:
            # a trigger or monitoring voltage is not a response: motion channels only
            motion = [str(c) for c, q in zip(th["channel"].values, th["quantity"].values)
                      if str(q) in _MOTION and str(c) != reference]
            if motion and len(motion) < th.sizes["channel"] - 1:
                resp = motion
                notes.append(f"responses: the motion channels {motion}")
        fr = signal.frf(ds, ref, response=resp, excitation=excitation, nperseg=nperseg,
                        force_window_s=force_window_s)
        notes.append(f"FRF: H1, {fr.attrs['excitation']} excitation, "
                     f"{fr.attrs['n_averages']} average(s); {fr.attrs['resolution_reason']}")
        for k in ("excitation", "nperseg", "nfft", "resolution_hz", "df_hz", "n_averages",
                  "force_window_s", "exponential_window_tau_s"):
            v = fr.attrs.get(k)
            if v is not None:
                settings[f"frf_{k}"] = v
        settings["force_window_s_requested"] = force_window_s
        return fr, fr
    if channel is not None:
        for name in _SPECTRA:
            if name in ds.data_vars:
                var = ds[name]
                dim = "response" if "response" in var.dims else "channel"
                return ds[[name]].sel({dim: channel}), None
    return ds, None


def estimate(data, *, method: str = "auto", variant: str | None = None, fn_hz=None,
             n_modes: int | None = None, fmin: float | None = None,
             fmax: float | None = None, channel=None, reference=None,
             excitation: str = "auto", nperseg: int | None = None,
             force_window_s="auto", band_hz=None, t_start_s: float | None = None,
             t_end_s: float | None = None) -> DampingEstimate:
    """Natural frequencies and damping of a measurement, right by default.

    This is the estimator of ``mvtk damping FILE`` and of a study's damping stage: both
    call it, with the same defaults, so they give the same table for the same data and
    options.

    Parameters
    ----------
    data : xarray.Dataset or xarray.DataArray
        What :func:`mvtk.io.read` returns (``time_history``, ``frf``, ``psd``, ...) or
        one of its variables.
    method : {"auto", "half_power", "envelope", "log_decrement"}
        ``auto``: half-power on an FRF/spectrum and on time histories with a reference
        (a ``force`` channel or ``reference``), envelope fit on free decays.
    variant : str, optional
        ``half_power``: ``fit`` (default) or ``interpolate``; ``envelope``: ``hilbert``
        (default) or ``peaks``.
    fn_hz : sequence of float, optional
        Approximate natural frequencies (Hz) to search (default: peak picking for
        half-power; the dominant frequency of each decay).
    n_modes, fmin, fmax
        Half-power peak picking: number of peaks, band (Hz).
    channel : str or list of str, optional
        Channels analysed (responses for an FRF, decays otherwise).
    reference : str, optional
        Reference channel of time histories (default: channels with quantity force).
    excitation : {"auto", "random", "impact", "sweep"}
        Excitation of the FRF from time histories (:func:`mvtk.signal.frf`).
    nperseg : int, optional
        FRF record/segment length in samples (default: chosen from the data).
    force_window_s : float, "auto" or None
        Impact force window (s) of :func:`mvtk.signal.frf`.
    band_hz : (float, float), optional
        Band-pass (Hz) before the decay fits.
    t_start_s, t_end_s : float, optional
        Time window of the decay fits (s).

    Returns
    -------
    DampingEstimate

    Raises
    ------
    ParameterError
        A variant that is not one of the method's.
    NoEstimateError
        The data support no estimate at all.

    Examples
    --------
    A free decay (no force channel) is fitted by the envelope method by default:

    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.01, 256.0, 10.0)   # 12 Hz, zeta 1 %
    >>> est = estimate(x)
    >>> est.method, est.variant
    ('envelope', 'hilbert')
    >>> est.table[["fn_hz", "zeta"]].round(4).values.tolist()
    [[12.0, 0.01]]
    """
    import pandas as pd

    from ._decay import envelope_fit, log_decrement
    from ._half_power import half_power

    if method not in METHODS:
        raise ParameterError(f"method must be one of {list(METHODS)}, got {method!r}")
    ds = _dataset(data)
    notes: list[str] = []
    if method == "auto":
        method = "half_power"
        if "time_history" in ds.data_vars and not _has_reference(ds, reference) and not any(
                v in ds.data_vars for v in _SPECTRA):
            method = "envelope"
        notes.append(f"method: {method} (auto)")
    if variant is not None and variant not in VARIANTS.get(method, ()):
        raise ParameterError(f"variant {variant!r} is not a variant of {method}; expected "
                             f"one of {list(VARIANTS.get(method, ()))}")
    variant = variant or (VARIANTS[method][0] if method in VARIANTS else None)
    settings: dict[str, Any] = {"method": method, "variant": variant,
                                "fn_hz": None if fn_hz is None else [float(f) for f in fn_hz]}
    frf = None
    if method == "half_power":
        spec, frf = _half_power_input(ds, reference=reference, channel=channel,
                                      excitation=excitation, nperseg=nperseg,
                                      force_window_s=force_window_s, notes=notes,
                                      settings=settings)
        settings.update(n_modes=n_modes, fmin_hz=fmin, fmax_hz=fmax)
        if fn_hz is None and (fmin is None or fmax is None):
            from ..signal import excited_band

            lo, hi, why = excited_band(spec)
            lo, hi = (lo if fmin is None else fmin), (hi if fmax is None else fmax)
            notes.append(f"peaks searched in {lo:.5g}..{hi:.5g} Hz ({why})")
        table = half_power(spec, fn_hz=fn_hz, n_modes=n_modes, fmin=fmin, fmax=fmax,
                           method=variant).to_dataframe()
    else:
        th = ds
        if "time_history" in ds.data_vars and channel is None \
                and "quantity" in ds["time_history"].coords:
            # a decay fit of the hammer or of a voltage makes no sense by default
            q = [str(v) for v in ds["time_history"]["quantity"].values]
            keep = [i for i, v in enumerate(q) if v != "force"]
            if keep and len(keep) < len(q):
                th = ds["time_history"].isel(channel=keep)
        kw = dict(channel=channel, band_hz=None if band_hz is None else tuple(band_hz),
                  t_start_s=t_start_s, t_end_s=t_end_s)
        settings.update(band_hz=kw["band_hz"], t_start_s=t_start_s, t_end_s=t_end_s)
        if method == "envelope":
            kw["method"] = variant
            est = envelope_fit
        else:
            est = log_decrement
        fns = list(fn_hz) if fn_hz is not None else [None]
        table = pd.concat([est(th, fn_hz=f, **kw).to_dataframe() for f in fns],
                          ignore_index=True)
    return DampingEstimate(table=table, method=method, variant=variant, notes=notes,
                           settings=settings, frf=frf)
