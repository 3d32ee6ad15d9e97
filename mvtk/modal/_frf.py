"""FRF matrices on the ``("response", "reference", "frequency")`` convention.

Built from measured time histories (one or several measurement sets, merged by
node/direction) through :func:`mvtk.signal.frf`, or adopted from what
:func:`mvtk.io.read` returns for UFF 58 FRF records; converted between receptance,
mobility and accelerance.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence

import numpy as np
import xarray as xr

from ..errors import (
    AccuracyWarning,
    DimensionError,
    DoubleHitError,
    FormatError,
    ParameterError,
    UnitsError,
)

__all__ = ["frf_matrix", "frf_of_sets", "merge_frf", "as_frf_matrix", "convert_frf", "reciprocal",
           "FRF_TYPES"]

#: FRF types and the power of ``i omega`` that turns a receptance into them.
FRF_TYPES = {"receptance": 0, "mobility": 1, "accelerance": 2}
_KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility",
                     "acceleration": "accelerance"}
_DIR_RE = re.compile(r"^([+-]?)(x|y|z|rx|ry|rz)$")
_DIMS = ("response", "reference", "frequency")
#: coordinates of measured FRF matrices kept by :func:`as_frf_matrix`: the coherence
#: ``(response, reference, frequency)``, the excitation level in dB of each
#: reference ``(reference, frequency)`` and the verdict of the sets behind each pair
#: ``pair_quality (response, reference)`` (from :func:`frf_matrix`).
_CARRIED = ("coherence", "reference_level_db", "pair_quality")


def _direction(value) -> str:
    """Direction label on the convention (``"+z"``, ``"-rx"``; ``""`` unknown)."""
    s = str(value).strip().lower()
    if s in ("", "none", "nan"):
        return ""
    m = _DIR_RE.match(s)
    if m is None:
        codes = {"1": "x", "2": "y", "3": "z", "4": "rx", "5": "ry", "6": "rz"}
        neg = s.startswith("-")
        c = s.lstrip("+-")
        if c in codes:
            return ("-" if neg else "+") + codes[c]
        return s
    return (m.group(1) or "+") + m.group(2)


def _coord(da, name, dim, default):
    if name in da.coords and da[name].dims == (dim,):
        return list(da[name].values)
    return [default] * da.sizes[dim]


def _parse_label(label: str) -> tuple[int, str]:
    """``"12:+z"`` / ``"12:z"`` / ``"12"`` (UFF labels of mvtk.io) -> (12, "+z")."""
    s = str(label)
    m = re.match(r"^\s*(\d+)\s*(?::\s*([+-]?\w+))?\s*$", s)
    if m is None:
        return -1, ""
    return int(m.group(1)), _direction(m.group(2) or "")


def _frf_type(quantity: str, ref_quantity: str) -> str:
    if ref_quantity not in ("force", ""):
        return "other"
    return _KIND_OF_QUANTITY.get(quantity, "other")


def _kind_from_units(units: str) -> str:
    """FRF type from an ordinate unit such as ``m/s^2/N`` or ``(1/N)*(m/s2)``."""
    u = units.replace(" ", "").lower().replace("**", "^")
    table = {"m/n": "receptance", "m/s/n": "mobility", "m/s^2/n": "accelerance",
             "m/s2/n": "accelerance", "g/n": "accelerance", "(m/s^2)/n": "accelerance",
             "(1/n)*(m/s2)": "accelerance", "(1/n)*(m/s^2)": "accelerance",
             "(m/s)/n": "mobility", "(1/n)*(m/s)": "mobility", "(1/n)*(m)": "receptance"}
    return table.get(u, "")


def _channel_spectra_as_frf(ds: xr.Dataset):
    """A Dataset with one complex ``(channel, frequency)`` variable (FRFs stored per
    channel, e.g. a text file of complex values) as responses x one reference."""
    cands = [v for v in ds.data_vars
             if ds[v].dims == ("channel", "frequency") and np.iscomplexobj(ds[v].values)]
    if len(cands) != 1:
        return ds
    da = ds[cands[0]]
    if "reference" in da.coords and len(set(map(str, da["reference"].values))) > 1:
        return ds
    ref = str(da["reference"].values[0]) if "reference" in da.coords else "reference"
    out = da.expand_dims(reference=[ref], axis=1).rename(channel="response")
    keep = {c: out[c] for c in ("node", "direction", "quantity", "units") if c in out.coords}
    out = out.drop_vars([c for c in out.coords if c not in ("response", "reference",
                                                              "frequency")])
    out = out.assign_coords({k: ("response", v.values) for k, v in keep.items()})
    out.attrs = {**ds.attrs, **da.attrs}
    return xr.Dataset({"frf": out}, attrs=out.attrs)


def as_frf_matrix(obj, *, frf_type: str | None = None) -> xr.DataArray:
    """Check or adopt an FRF matrix on the conventions of ``docs/conventions.md``.

    Parameters
    ----------
    obj : xarray.DataArray or xarray.Dataset
        Complex FRFs with dims ``("response", "reference", "frequency")`` (a Dataset
        must hold a variable ``frf``, as :func:`mvtk.io.read` returns for UFF 58 FRF
        records and :func:`mvtk.signal.frf` for time histories; a Dataset whose only
        complex variable has dims ``("channel", "frequency")``, e.g. a text file of
        complex FRF values, is taken as the FRFs of its channels to one reference).
    frf_type : str, optional
        ``receptance``, ``mobility``, ``accelerance`` or ``other`` when the object does
        not state it (``attrs["frf_type"]`` or ``attrs["kind"]``) and the channel
        quantities do not tell either.

    Returns
    -------
    xarray.DataArray
        Named ``frf`` with coordinates ``node``, ``direction``, ``quantity``, ``units``
        on ``response``; ``reference_node``, ``reference_direction``,
        ``reference_quantity``, ``reference_units`` on ``reference``; frequency in Hz
        ascending; ``attrs["frf_type"]`` (from the argument, the object's attrs, the
        channel quantities or the ordinate units such as ``m/s^2/N``, in that order).
        Node labels such as ``"12:z"`` written by the UFF reader are parsed into
        ``node=12, direction="+z"``; unknown nodes are -1. A ``coherence``
        ``(response, reference, frequency)`` and a ``reference_level_db``
        ``(reference, frequency)`` coordinate (or data variable of a Dataset, as
        :func:`mvtk.signal.frf` returns) are kept.

    Raises
    ------
    DimensionError
        The object does not have the three FRF dimensions.
    FormatError
        The frequencies are not ascending or the values not finite.

    Examples
    --------
    >>> from mvtk.modal import exact_frf
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25), [0, 1], [0])
    >>> m = as_frf_matrix(h)
    >>> m.name, m.attrs["frf_type"], [str(r) for r in m.response.values]
    ('frf', 'receptance', ['1+z', '2+z'])
    """
    if isinstance(obj, xr.Dataset) and "frf" not in obj.data_vars:
        obj = _channel_spectra_as_frf(obj)
    if isinstance(obj, xr.Dataset):
        if "frf" not in obj.data_vars:
            raise DimensionError(
                "expected a Dataset with an 'frf' variable of dims (response, reference, "
                f"frequency); found variables {sorted(map(str, obj.data_vars))}"
            )
        attrs = {**obj.attrs, **obj["frf"].attrs}
        da = obj["frf"]
    elif isinstance(obj, xr.DataArray):
        da, attrs = obj, dict(obj.attrs)
    else:
        raise DimensionError(
            "expected an xarray DataArray/Dataset FRF matrix with dims (response, "
            f"reference, frequency); got {type(obj).__name__}"
        )
    if set(da.dims) != set(_DIMS) or da.ndim != 3:
        raise DimensionError(
            f"an FRF matrix needs dims {_DIMS}; found {tuple(str(d) for d in da.dims)}"
        )
    da = da.transpose(*_DIMS)
    f = np.asarray(da["frequency"].values, dtype=float)
    if f.size < 2 or np.any(np.diff(f) <= 0):
        raise FormatError("FRF matrix: frequency must hold >= 2 ascending values in Hz")
    values = np.asarray(da.values)
    if not np.all(np.isfinite(values)):
        bad = np.argwhere(~np.isfinite(values))[0]
        raise FormatError(
            f"FRF matrix: non-finite value at response {da['response'].values[bad[0]]!s}, "
            f"reference {da['reference'].values[bad[1]]!s}, {f[bad[2]]:g} Hz"
        )
    resp = [str(v) for v in da["response"].values]
    ref = [str(v) for v in da["reference"].values]
    node = _coord(da, "node", "response", None)
    direc = _coord(da, "direction", "response", None)
    rnode = _coord(da, "reference_node", "reference", None)
    rdir = _coord(da, "reference_direction", "reference", None)
    for i, lab in enumerate(resp):
        n, d = _parse_label(lab)
        node[i] = int(node[i]) if node[i] is not None else n
        direc[i] = _direction(direc[i]) if direc[i] is not None else d
    for i, lab in enumerate(ref):
        n, d = _parse_label(lab)
        rnode[i] = int(rnode[i]) if rnode[i] is not None else n
        rdir[i] = _direction(rdir[i]) if rdir[i] is not None else d
    q = [str(v) for v in _coord(da, "quantity", "response", None)]
    if "response_quantity" in da.coords and "quantity" not in da.coords:
        q = [str(v) for v in da["response_quantity"].values]
    rq = [str(v) for v in _coord(da, "reference_quantity", "reference", "")]
    u = [str(v) for v in _coord(da, "units", "response", "")]
    if "response_units" in da.coords and not ("units" in da.coords
                                               and da["units"].dims == ("response",)):
        u = [str(v) for v in da["response_units"].values]
    ru = [str(v) for v in _coord(da, "reference_units", "reference", "")]
    q = ["" if v == "None" else v for v in q]
    kind = frf_type or attrs.get("frf_type") or attrs.get("kind") or ""
    if not kind:
        kinds = {_frf_type(a, b) for a in q for b in rq} if q and rq else set()
        kind = kinds.pop() if len(kinds) == 1 else ""
    if not kind or kind == "other":
        kind = _kind_from_units(str(attrs.get("units", ""))) or kind or "other"
    if kind not in (*FRF_TYPES, "other"):
        raise ParameterError(
            f"frf_type must be one of {(*FRF_TYPES, 'other')}, got {kind!r}"
        )
    out = xr.DataArray(
        values.astype(complex, copy=False),
        dims=_DIMS,
        coords={
            "response": resp, "reference": ref,
            "frequency": ("frequency", f, {"units": "Hz"}),
            "node": ("response", np.asarray(node, dtype=np.int64)),
            "direction": ("response", np.asarray(direc, dtype=object).astype(str)),
            "quantity": ("response", np.asarray(q, dtype=str)),
            "units": ("response", np.asarray(u, dtype=str)),
            "reference_node": ("reference", np.asarray(rnode, dtype=np.int64)),
            "reference_direction": ("reference", np.asarray(rdir, dtype=object).astype(str)),
            "reference_quantity": ("reference", np.asarray(rq, dtype=str)),
            "reference_units": ("reference", np.asarray(ru, dtype=str)),
        },
        name="frf",
    )
    # measurement evidence that follows the FRFs through band selection and conversion
    for name in _CARRIED:
        c = da.coords.get(name)
        if c is None and isinstance(obj, xr.Dataset) and name in obj.data_vars:
            c = obj[name]
        if c is not None and c.dims and set(c.dims) <= set(_DIMS) and (
                "frequency" in c.dims or name == "pair_quality"):
            order = [d for d in _DIMS if d in c.dims]
            out = out.assign_coords({name: c.transpose(*order).variable})
    keep = {k: v for k, v in attrs.items() if isinstance(v, (str, int, float))}
    keep.pop("kind", None)
    out.attrs = {**keep, "frf_type": kind}
    out.attrs.setdefault("estimator", "measured")
    return out


def convert_frf(frf, to: str) -> xr.DataArray:
    """Convert between receptance, mobility and accelerance.

    Multiplies by ``(i omega)^k`` with ``k`` the difference of the powers in
    :data:`FRF_TYPES` (omega = 2 pi f, rad/s) and updates ``frf_type``, the response
    ``quantity`` and ``units`` (``m/N`` <-> ``m/s/N`` <-> ``m/s^2/N`` when the response
    unit is metric; otherwise the unit is written as ``<unit>*(rad/s)^k``).

    Raises
    ------
    UnitsError
        The FRF type is ``other`` (e.g. acceleration per volt) or ``to`` is unknown.

    Examples
    --------
    Mobility = i w x receptance, line by line:

    >>> from mvtk.modal import exact_frf
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.0, 120.0, 0.25)
    >>> h = exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0])
    >>> v = convert_frf(h, "mobility")
    >>> v.attrs["frf_type"], str(v.units.values[0])
    ('mobility', 'm/s/N')
    >>> complex(v[0, 0, 40] / (1j * 2 * np.pi * f[40] * h[0, 0, 40]))
    (1+0j)
    """
    h = as_frf_matrix(frf)
    src = h.attrs["frf_type"]
    if to not in FRF_TYPES:
        raise UnitsError(f"convert_frf: 'to' must be one of {tuple(FRF_TYPES)}, got {to!r}")
    if src not in FRF_TYPES:
        raise UnitsError(
            f"convert_frf: the FRF type is {src!r}; only receptance, mobility and "
            "accelerance (response over force) can be converted"
        )
    k = FRF_TYPES[to] - FRF_TYPES[src]
    w = 2 * np.pi * h["frequency"].values
    with np.errstate(divide="ignore", invalid="ignore"):
        fac = (1j * w) ** k
    if k < 0 and w[0] == 0:
        fac[0] = 0.0
    out = h * fac
    metric = {"receptance": ("displacement", "m"), "mobility": ("velocity", "m/s"),
              "accelerance": ("acceleration", "m/s^2")}
    q_from, u_from = metric[src]
    q_to, u_to = metric[to]
    units = []
    for u in h["units"].values:
        u = str(u)
        if u.startswith(u_from + "/") and not u.startswith(u_from + "/s"):
            units.append(u_to + u[len(u_from):])
        elif k:
            units.append(f"{u}*(rad/s)^{k}" if u else "")
        else:
            units.append(u)
    out = out.assign_coords(quantity=("response", [q_to] * h.sizes["response"]),
                            units=("response", units))
    out.attrs = {**h.attrs, "frf_type": to}
    out.name = "frf"
    return out


def reciprocal(frf) -> xr.DataArray:
    """Swap responses and references (Maxwell-Betti reciprocity ``H_ij = H_ji``).

    A roving-hammer test (one sensor, hammer at every test point) gives a 1 x N matrix;
    its reciprocal is the N x 1 matrix whose response side carries the mode shapes. The
    force level of each hammer point (``reference_level_db``) goes with the point, to
    dims ``("response", "frequency")``, so that the excited band and the
    weak-excitation check of :func:`identify` still see it.

    Examples
    --------
    A roving-hammer row (1 x 2) becomes a column (2 x 1):

    >>> from mvtk.modal import exact_frf
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25), [0], [0, 1])
    >>> h.shape, reciprocal(h).shape
    ((1, 2, 480), (2, 1, 480))
    """
    h = as_frf_matrix(frf)
    vals = np.swapaxes(h.values, 0, 1)
    # the measurement evidence of each pair follows it (coherence, set verdicts), and
    # the excitation level of each hammer point follows the point to the response side
    pairs = {name: (tuple({"response": "reference", "reference": "response"}.get(d, d)
                          for d in h[name].dims), h[name].values)
             for name in ("coherence", "pair_quality", "reference_level_db")
             if name in h.coords}
    return as_frf_matrix(xr.DataArray(
        vals, dims=_DIMS,
        coords={
            "response": h["reference"].values, "reference": h["response"].values,
            "frequency": h["frequency"].values,
            "node": ("response", h["reference_node"].values),
            "direction": ("response", h["reference_direction"].values),
            "quantity": ("response", h["reference_quantity"].values),
            "units": ("response", h["reference_units"].values),
            "reference_node": ("reference", h["node"].values),
            "reference_direction": ("reference", h["direction"].values),
            "reference_quantity": ("reference", h["quantity"].values),
            "reference_units": ("reference", h["units"].values),
        }, attrs=dict(h.attrs)).assign_coords(
            {name: (dims, values) for name, (dims, values) in pairs.items()}))


def _one_set(x, reference, response, kwargs, index):
    from .. import signal

    th = signal.as_time_history(x)
    try:
        ds = signal.frf(th, reference, response, **kwargs)
    except DoubleHitError:
        raise
    except (ParameterError, FormatError, DimensionError) as err:
        raise type(err)(f"measurement set {index}: {err}") from err
    chans = [str(c) for c in th["channel"].values]

    def per(names, coord, default):
        vals = _coord(th, coord, "channel", default)
        return [vals[chans.index(n)] for n in names]

    rn = [str(v) for v in ds["response"].values]
    fn = [str(v) for v in ds["reference"].values]
    h = xr.DataArray(
        ds["frf"].values, dims=_DIMS,
        coords={
            "response": rn, "reference": fn, "frequency": ds["frequency"].values,
            "node": ("response", [int(v) for v in per(rn, "node", -1)]),
            "direction": ("response", [_direction(v) for v in per(rn, "direction", "")]),
            "quantity": ("response", [str(v) for v in per(rn, "quantity", "")]),
            "units": ("response", [str(v) for v in per(rn, "units", "")]),
            "reference_node": ("reference", [int(v) for v in per(fn, "node", -1)]),
            "reference_direction": ("reference",
                                    [_direction(v) for v in per(fn, "direction", "")]),
            "reference_quantity": ("reference", [str(v) for v in per(fn, "quantity", "")]),
            "reference_units": ("reference", [str(v) for v in per(fn, "units", "")]),
        },
    )
    level = (ds["reference_level_db"].values if "reference_level_db" in ds.data_vars
             else np.full((len(fn), ds.sizes["frequency"]), np.nan))
    return h, ds["coherence"].values, ds.attrs, level, ds


def _key(node, direction, name):
    return (int(node), str(direction)) if int(node) >= 0 else ("name", str(name))


def frf_matrix(
    sets,
    reference,
    response=None,
    *,
    estimator: str = "H1",
    excitation: str = "auto",
    **frf_options,
) -> xr.DataArray:
    """FRF matrix from measured time histories: one set, or several merged by node.

    Each measurement set is a time history ``("channel", "time")`` holding reference
    (force) and response channels. The FRFs of every set are estimated by
    :func:`mvtk.signal.frf` (H1 with several references, or H2; Welch averages for
    random excitation, one record per hit for impact) and the sets are merged on a
    grid keyed by ``(node, direction)`` of the responses and of the references:

    - roving sensor (fixed hammer/shaker, the accelerometers move): sets add responses;
    - roving hammer (fixed sensor, the hammer moves): sets add references (use
      :func:`reciprocal` to put the test points on the response side);
    - a pair measured in several sets (a fixed reference sensor present in every set)
      is averaged over the sets, weighted by each set's number of averages.

    Parameters
    ----------
    sets : DataArray/Dataset or sequence of them
        Time histories with ``node`` and ``direction`` channel coordinates (channels
        without a node, ``node=-1``, are keyed by channel name).
    reference, response
        Channel selection within each set, as in :func:`mvtk.signal.frf` (e.g.
        ``{"quantity": "force"}``).
    estimator, excitation, **frf_options
        Passed to :func:`mvtk.signal.frf` (``nperseg``, ``window``, ``trigger_level``,
        ``exponential_tau_s``, ``double_hit``...). All sets must give the same frequency
        lines. Impact tests get one policy for every set
        (:func:`mvtk.signal.impact_policy`): one record length, pretrigger, FFT length and
        one exponential window chosen from the slowest decay over the sets (values
        given here are kept), stated in ``attrs["window_policy"]``.
        ``excitation="auto"`` (default) detects impact, sweep or random excitation from
        each set's reference, as :func:`mvtk.signal.frf` does; every set must be found
        the same.

    Returns
    -------
    xarray.DataArray
        Complex FRFs ``("response", "reference", "frequency")`` (see
        :func:`as_frf_matrix`) with a ``coherence`` coordinate of the same dims (NaN for
        pairs that were not measured), a ``reference_level_db`` coordinate
        ``("reference", "frequency")`` (each reference's autospectrum in dB re its
        largest value above 0 Hz, averaged over the sets that share the reference: how
        strongly each line was excited; :func:`identify` marks modes it missed) and
        ``attrs`` ``estimator``, ``n_averages`` (sum over sets), ``n_sets``,
        ``exponential_window_tau_s`` (s, the window every set shares, when one was
        applied: its damping ``1/(tau omega_n)`` is in every pole), ``nperseg`` and
        ``nfft`` (samples, when every set shares them), ``window_policy``
        (impact) and ``set_quality``: the per-set quality table (double hits, clipped
        channels, coherence, excitation level; :func:`mvtk.signal.set_quality` reads it
        as a :class:`mvtk.signal.SetQuality`). A ``pair_quality`` coordinate
        ``(response, reference)`` holds, for each pair, the verdicts of the sets behind
        it that are not ``"ok"`` (``""`` when all are). A set whose every impact record
        holds a double hit is refused (left out, named in an
        :class:`~mvtk.errors.AccuracyWarning` and in the table).

    Raises
    ------
    DimensionError
        The sets give different frequency lines, or the merged grid misses pairs (the
        message lists them): every response must be measured with every reference.
    DoubleHitError
        Every set was refused for double hits.

    Examples
    --------
    Three simulated hammer hits (modes at 20 and 55 Hz), one sensor:

    >>> from mvtk import testing
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 256.0, 4.0, 3,
    ...                            np.random.default_rng(0))   # 256 Hz, 4 s per hit
    >>> h = frf_matrix([hits], reference="force")
    >>> h.dims, h.shape[:2]
    (('response', 'reference', 'frequency'), (1, 1))
    """
    if isinstance(sets, (xr.DataArray, xr.Dataset)):
        sets = [sets]
    if not isinstance(sets, Sequence) or not sets:
        raise ParameterError("frf_matrix: 'sets' must be a time history or a non-empty list")
    from .. import signal

    sources = [_source_of(x, k) for k, x in enumerate(sets)]
    kwargs = dict(estimator=estimator, excitation=excitation, **frf_options)
    kinds = [excitation if excitation != "auto" else signal.set_excitation(x, reference)
             for x in sets]
    for k, kind in enumerate(kinds):
        if kind != kinds[0]:
            raise ParameterError(
                f"measurement set {k + 1}: {kind} excitation, but set 1 is {kinds[0]}; "
                "pass excitation= explicitly to treat every set alike (set 1: "
                f"{sources[0]}, set {k + 1}: {sources[k]})")
    policy = None
    if kinds[0] == "impact":
        # one record, pretrigger, window and FFT length for the whole test (the values
        # given are kept)
        policy = signal.impact_policy(
            sets, reference, response,
            trigger_level=frf_options.get("trigger_level", 0.1),
            double_hit_fraction=frf_options.get("double_hit_fraction",
                                                signal.DOUBLE_HIT_FRACTION),
            names=sources, nperseg=frf_options.get("nperseg"),
            pretrigger=frf_options.get("pretrigger"),
            exponential_tau_s=frf_options.get("exponential_tau_s", "auto"),
            nfft=frf_options.get("nfft", "auto"))
        kwargs.update(policy.frf_options(), excitation="impact")
    parts, rows, refused = [], [], []
    for k, x in enumerate(sets):
        try:
            part = _one_set(x, reference, response, kwargs, k + 1)
        except DoubleHitError as err:
            text = str(err)
            refused.append(text if text.startswith(sources[k]) else f"{sources[k]}: {text}")
            rows.append((k, err, None))
            continue
        parts.append(part)
        rows.append((k, part[4], part[0]))
    if refused:
        warnings.warn(
            f"frf_matrix: {len(refused)} of {len(sets)} measurement set(s) refused "
            "(no clean impact record): " + "; ".join(refused), AccuracyWarning, stacklevel=2)
    if not parts:
        raise DoubleHitError("frf_matrix: every measurement set was refused: "
                             + "; ".join(refused))
    quality = signal.SetQuality(rows=tuple(
        signal._impact.quality_row(
            k + 1, sources[k], _peak_of(sets[k], reference), ds,
            *(_labels(h, True), _labels(h, False)) if h is not None
            else _channel_labels(sets[k], reference, response))
        for k, ds, h in rows))
    f0 = parts[0][0]["frequency"].values
    rkeys: dict = {}
    fkeys: dict = {}
    for k, (h, *_) in enumerate(parts):
        f = h["frequency"].values
        if f.shape != f0.shape or not np.allclose(f, f0):
            raise DimensionError(
                f"measurement set {k + 1}: {f.size} frequency lines up to {f[-1]:g} Hz; "
                f"expected the {f0.size} lines of set 1 (same fs and nperseg in every set)"
            )
        for i in range(h.sizes["response"]):
            key = _key(h["node"].values[i], h["direction"].values[i], h["response"].values[i])
            rkeys.setdefault(key, (k, i))
        for j in range(h.sizes["reference"]):
            key = _key(h["reference_node"].values[j], h["reference_direction"].values[j],
                       h["reference"].values[j])
            fkeys.setdefault(key, (k, j))
    nr, nf = len(rkeys), len(fkeys)
    acc = np.zeros((nr, nf, f0.size), complex)
    coh = np.zeros((nr, nf, f0.size))
    wsum = np.zeros((nr, nf))
    power = np.zeros((nf, f0.size))      # reference autospectrum re its maximum, linear
    psum = np.zeros(nf)
    rlist, flist = list(rkeys), list(fkeys)
    n_avg = 0
    flags = [[[] for _ in range(nf)] for _ in range(nr)]
    good = [r for r in quality.rows if r["usable"]]
    for (h, c, attrs, level, _), row in zip(parts, good):
        w = float(attrs.get("n_averages", 1))
        n_avg += int(attrs.get("n_averages", 1))
        ri = [rlist.index(_key(h["node"].values[i], h["direction"].values[i],
                               h["response"].values[i])) for i in range(h.sizes["response"])]
        fi = [flist.index(_key(h["reference_node"].values[j],
                               h["reference_direction"].values[j], h["reference"].values[j]))
              for j in range(h.sizes["reference"])]
        if row["verdict"] != "ok":
            for a in ri:
                for b in fi:
                    flags[a][b].append(f"set {row['set']}: {row['verdict']}")
        acc[np.ix_(ri, fi)] += w * h.values
        power[fi] += w * 10 ** (level / 10)
        psum[fi] += w
        coh[np.ix_(ri, fi)] += w * c
        wsum[np.ix_(ri, fi)] += w
    missing = np.argwhere(wsum == 0)
    if missing.size:
        def lab(keys, k):
            key = keys[k]
            return f"{key[0]}{key[1]}" if key[0] != "name" else key[1]
        pairs = ", ".join(f"({lab(rlist, a)}, {lab(flist, b)})" for a, b in missing[:8])
        raise DimensionError(
            f"frf_matrix: the merged sets do not measure {len(missing)} response/reference "
            f"pair(s): {pairs}; every response must be measured with every reference"
        )
    acc /= wsum[..., None]
    coh /= wsum[..., None]

    def side(keys, is_ref):
        rows = []
        for key in keys:
            k, i = (fkeys if is_ref else rkeys)[key]
            h = parts[k][0]
            if is_ref:
                rows.append((str(h["reference"].values[i]), int(h["reference_node"].values[i]),
                             str(h["reference_direction"].values[i]),
                             str(h["reference_quantity"].values[i]),
                             str(h["reference_units"].values[i])))
            else:
                rows.append((str(h["response"].values[i]), int(h["node"].values[i]),
                             str(h["direction"].values[i]), str(h["quantity"].values[i]),
                             str(h["units"].values[i])))
        return list(zip(*rows))

    rs, fs_ = side(rlist, False), side(flist, True)
    rnames = [f"{n}{d}" if n >= 0 else nm for nm, n, d in zip(rs[0], rs[1], rs[2])]
    fnames = [f"{n}{d}" if n >= 0 else nm for nm, n, d in zip(fs_[0], fs_[1], fs_[2])]
    da = xr.DataArray(
        acc, dims=_DIMS,
        coords={"response": rnames, "reference": fnames, "frequency": f0,
                "node": ("response", list(rs[1])), "direction": ("response", list(rs[2])),
                "quantity": ("response", list(rs[3])), "units": ("response", list(rs[4])),
                "reference_node": ("reference", list(fs_[1])),
                "reference_direction": ("reference", list(fs_[2])),
                "reference_quantity": ("reference", list(fs_[3])),
                "reference_units": ("reference", list(fs_[4]))},
    )
    a0 = parts[0][2]
    out = as_frf_matrix(da)
    with np.errstate(divide="ignore"):
        level = 10 * np.log10(power / psum[:, None])
    pair = np.array([["; ".join(v) for v in row] for row in flags], dtype=object).astype(str)
    out = out.assign_coords(coherence=(_DIMS, np.clip(coh, 0, 1)),
                            reference_level_db=(("reference", "frequency"), level,
                                                {"units": "dB"}),
                            pair_quality=(("response", "reference"), pair))
    out.attrs.update(estimator=estimator, excitation=kinds[0], n_averages=n_avg,
                     n_sets=len(parts), window=str(a0.get("window", "")),
                     df_hz=float(f0[1] - f0[0]), set_quality=quality.to_json())
    if policy is not None:
        out.attrs["window_policy"] = policy.reason
    # record and FFT length (samples) when every set shares them: identify needs them
    # to tell interpolated (zero-padded) lines from the record's own
    for key in ("nperseg", "nfft"):
        vals = {int(p[2][key]) for p in parts if key in p[2]}
        if len(vals) == 1 and all(key in p[2] for p in parts):
            out.attrs[key] = vals.pop()
    # the band every set excites and the coarsest resolution: the default analysis band
    # of mvtk.modal.identify starts from them (mvtk.signal.analysis_band)
    bands = [p[2].get("excitation_band_hz") for p in parts]
    if all(b is not None and len(b) == 2 for b in bands):
        out.attrs["excitation_band_hz"] = [max(float(b[0]) for b in bands),
                                           min(float(b[1]) for b in bands)]
    res = [p[2].get("resolution_hz") for p in parts]
    if all(r is not None for r in res):
        out.attrs["resolution_hz"] = max(float(r) for r in res)
    taus = {float(p[2]["exponential_window_tau_s"]) for p in parts
            if "exponential_window_tau_s" in p[2]}
    if len(taus) == 1 and len(parts) == sum("exponential_window_tau_s" in p[2]
                                            for p in parts):
        tau = taus.pop()
        out.attrs["exponential_window_tau_s"] = tau
        out.attrs["exp_window_tau_s"] = tau
    elif taus:
        warnings.warn(
            f"frf_matrix: the sets carry different exponential windows (tau = "
            f"{sorted(taus)} s); their added damping differs from set to set and no single "
            "correction removes it (leave exponential_tau_s, nperseg and nfft on 'auto' for "
            "one window over the test)", AccuracyWarning, stacklevel=2)
    return out


def _source_of(x, k: int) -> str:
    """The file a measurement set was read from (``attrs["source"]``), else ``set k``."""
    for obj in (x, x.get("time_history") if isinstance(x, xr.Dataset) else None):
        if obj is not None and obj.attrs.get("source"):
            return str(obj.attrs["source"])
    return f"set {k + 1}"


def _peak_of(x, reference) -> float:
    from .. import signal

    th = signal.as_time_history(x)
    try:
        values = th.sel(channel=signal._input.select_channels(
            th, reference, name="reference")["channel"].values).values[0]
    except (ParameterError, KeyError):
        return float("nan")
    return signal._impact.peak_force(values)


def _channel_labels(x, reference, response):
    """``node+direction`` (or names) of a set's reference and response channels."""
    from .. import signal

    th = signal.as_time_history(x)
    sel = signal._input.select_channels
    ref = sel(th, reference, name="reference")
    names = {str(c) for c in ref["channel"].values}
    resp = (th.isel(channel=[i for i, c in enumerate(th["channel"].values)
                             if str(c) not in names])
            if response is None else sel(th, response, name="response"))

    def lab(da):
        node = _coord(da, "node", "channel", -1)
        direc = _coord(da, "direction", "channel", "")
        return [f"{int(n)}{_direction(d)}" if int(n) >= 0 else str(c)
                for c, n, d in zip(da["channel"].values, node, direc)]
    return lab(ref), lab(resp)


def _labels(h, is_ref: bool) -> list[str]:
    if is_ref:
        return [f"{n}{d}" if int(n) >= 0 else str(nm) for nm, n, d in zip(
            h["reference"].values, h["reference_node"].values,
            h["reference_direction"].values)]
    return [f"{n}{d}" if int(n) >= 0 else str(nm) for nm, n, d in zip(
        h["response"].values, h["node"].values, h["direction"].values)]


def frf_of_sets(sets, reference=None, response=None, *, excitation: str = "auto",
                **frf_options) -> xr.DataArray:
    """FRF matrix of a test's measurement sets, test points on the response side.

    :func:`frf_matrix` of the sets (reference default: the force channels); with more
    references than responses (a roving hammer: one or a few fixed sensors, the hammer
    at every test point) the matrix is turned by reciprocity (:func:`reciprocal`,
    ``H_ij = H_ji``) so the mode shapes are estimated at the hammer points. Used by
    ``mvtk modal`` and by the study's ``[modal] sets``.

    Returns
    -------
    xarray.DataArray
        As :func:`frf_matrix`, with ``attrs["reciprocity"]`` saying whether and why the
        matrix was turned (``""`` if not).

    Examples
    --------
    The force channels are found as references; one response, one reference, so no
    reciprocity turn:

    >>> from mvtk import testing
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 256.0, 4.0, 3,
    ...                            np.random.default_rng(0))   # 256 Hz, 4 s per hit
    >>> h = frf_of_sets([hits])
    >>> h.shape[:2], h.attrs["reciprocity"]
    ((1, 1), '')
    """
    ref = reference if reference is not None else {"quantity": "force"}
    frf = frf_matrix(sets, ref, response, excitation=excitation, **frf_options)
    note = ""
    if frf.sizes["reference"] > frf.sizes["response"]:
        frf = reciprocal(frf)
        note = (f"roving hammer: {frf.sizes['response']} hammer points x "
                f"{frf.sizes['reference']} sensor(s), turned by reciprocity (H_ij = H_ji)")
    frf.attrs["reciprocity"] = note
    return frf


def merge_frf(mats, names=None) -> xr.DataArray:
    """One FRF matrix from several, merged by node/direction of responses and references.

    Each file of a test may hold one reference (a UFF 58 file per shaker or hammer
    position) or a group of responses: the pairs are placed on a grid keyed by
    ``(node, direction)`` of the response and of the reference (responses without a
    node, ``node=-1``, by name prefixed with the file's name; references without a node
    by name: the one unnamed reference of several files is the same excitation). A pair
    measured in several matrices is averaged.

    Parameters
    ----------
    mats : sequence of FRF matrices
        Anything :func:`as_frf_matrix` adopts, on the same frequency lines and of one
        FRF type.
    names : sequence of str, optional
        Names of the matrices (file names) for messages and unnamed channels.

    Raises
    ------
    DimensionError
        Different frequency lines, or the grid misses pairs (listed).
    UnitsError
        The matrices are of different FRF types (convert them first, :func:`convert_frf`).

    Examples
    --------
    Two files, one per reference (force on mass 1, then on mass 2), make a 2 x 2 matrix:

    >>> from mvtk.modal import exact_frf
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.25, 120.0, 0.25)
    >>> h1 = exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0])
    >>> h2 = exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [1])
    >>> m = merge_frf([h1, h2], names=["ref1.uff", "ref2.uff"])
    >>> m.shape, [str(r) for r in m.reference.values]
    ((2, 2, 479), ['1+z', '2+z'])
    """
    hs = [as_frf_matrix(m) for m in mats]
    names = list(names) if names is not None else [f"matrix {k + 1}" for k in range(len(hs))]
    if len(hs) == 1:
        return hs[0]
    f0 = hs[0]["frequency"].values
    kinds = {h.attrs["frf_type"] for h in hs}
    if len(kinds) > 1:
        found = ", ".join(f"{n}: {h.attrs['frf_type']}" for n, h in zip(names, hs))
        raise UnitsError(f"merge_frf: the matrices are of different FRF types ({found}); "
                         "convert them to one type first (mvtk.modal.convert_frf)")
    rkeys: dict = {}
    fkeys: dict = {}
    for k, h in enumerate(hs):
        f = h["frequency"].values
        if f.shape != f0.shape or not np.allclose(f, f0):
            raise DimensionError(f"{names[k]}: {f.size} lines up to {f[-1]:g} Hz; expected the "
                                 f"{f0.size} lines of {names[0]}")
        for i in range(h.sizes["response"]):
            key = _key(h["node"].values[i], h["direction"].values[i],
                       f"{names[k]}:{h['response'].values[i]}")
            rkeys.setdefault(key, (k, i))
        for j in range(h.sizes["reference"]):
            key = _key(h["reference_node"].values[j], h["reference_direction"].values[j],
                       str(h['reference'].values[j]))
            fkeys.setdefault(key, (k, j))
    rlist, flist = list(rkeys), list(fkeys)
    acc = np.zeros((len(rlist), len(flist), f0.size), complex)
    cnt = np.zeros((len(rlist), len(flist)))
    for k, h in enumerate(hs):
        ri = [rlist.index(_key(h["node"].values[i], h["direction"].values[i],
                               f"{names[k]}:{h['response'].values[i]}"))
              for i in range(h.sizes["response"])]
        fi = [flist.index(_key(h["reference_node"].values[j], h["reference_direction"].values[j],
                               str(h['reference'].values[j])))
              for j in range(h.sizes["reference"])]
        acc[np.ix_(ri, fi)] += h.values
        cnt[np.ix_(ri, fi)] += 1
    missing = np.argwhere(cnt == 0)
    if missing.size:
        lab = [f"{a}{b}" if a != "name" else b for a, b in rlist]
        flab = [f"{a}{b}" if a != "name" else b for a, b in flist]
        raise DimensionError(
            f"merge_frf: the files do not measure {len(missing)} response/reference pair(s): "
            + ", ".join(f"({lab[a]}, {flab[b]})" for a, b in missing[:8])
            + "; every response must be measured with every reference")
    acc /= cnt[..., None]

    def coords(keys, table, is_ref):
        cols = (("reference", "reference_node", "reference_direction", "reference_quantity",
                 "reference_units") if is_ref else
                ("response", "node", "direction", "quantity", "units"))
        out = {c: [] for c in cols}
        for key in keys:
            k, i = table[key]
            h = hs[k]
            for c in cols:
                v = h[c].values[i]
                out[c].append(v)
        label = [f"{n}{d}" if int(n) >= 0 else (str(nm) if is_ref
                                                 else f"{names[table[key][0]]}:{nm}")
                 for key, nm, n, d in zip(keys, out[cols[0]], out[cols[1]], out[cols[2]])]
        dim = cols[0]
        return {dim: label, **{c: (dim, out[c]) for c in cols[1:]}}

    da = xr.DataArray(acc, dims=_DIMS,
                      coords={**coords(rlist, rkeys, False), **coords(flist, fkeys, True),
                              "frequency": f0},
                      attrs={**hs[0].attrs, "n_files": len(hs)})
    return as_frf_matrix(da)
