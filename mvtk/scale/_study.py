"""Parameter studies and Monte-Carlo propagation of FE modal analyses, optionally on dask."""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._optional import require_distributed
from ..errors import DataRepairWarning, MvtkError, ParameterError

__all__ = [
    "parameter_study",
    "monte_carlo",
    "draw_samples",
    "MonteCarloResult",
    "DISTRIBUTION_KINDS",
]

DISTRIBUTION_KINDS = {
    "normal": "(mean, std) of the value",
    "lognormal": "(mean, std) of the value (not of its logarithm); always positive",
    "uniform": "(low, high)",
}


#: Default ``tol`` of :func:`parameter_study`: relative error bound accepted for a
#: sample's frequencies on the reduced path.
DEFAULT_TOL = 1e-8
#: ``method="auto"`` takes the reduced path from this many samples on (its set-up
#: costs about 16 builds and one full solve), or inside the box of a cached basis.
REDUCED_MIN_SAMPLES = 16
METHODS = ("auto", "reduced", "exact")


def _default_builder(description):
    from ..fe import build_model

    return build_model(description)


class _Singular(Exception):
    """K is singular: the model has rigid-body modes (handled by modal_analysis)."""


def _singular_shift():
    raise _Singular


class _LowestFrequencies:
    """Lowest natural frequencies of models that differ only in parameter values.

    The first model goes through :func:`mvtk.fe.modal_analysis` (rigid-body detection
    and all). When it has no rigid-body mode, every model (the first one again, so that
    a sample's result does not depend on where a batch starts) is solved by the
    :func:`mvtk.fe.eigsh_lowest` call that ``modal_analysis`` makes (shift 0 for a
    non-singular K, the same start vector) on K without its round-off entries
    (:func:`mvtk.updating._roundoff.without_roundoff`: half the factorisation time of
    the smart beam, one fill-reducing ordering for all samples), and without the
    mode-type classification (strain-energy split, a quarter of the time of a
    ``modal_analysis`` of the smart beam) that a parameter study does not use: the
    frequencies of ``modal_analysis`` to the solver's round-off (5e-10 and below,
    measured). A model whose K is singular or
    whose lowest eigenvalue is below 1e-4 of the highest (near-rigid modes, which
    ``modal_analysis`` classifies) goes through ``modal_analysis`` again. (A warm start
    from the first model's shapes was measured: ARPACK still made 22 solves per model,
    its ``ncv`` Lanczos steps, and the results then depended at 1e-10 on which sample
    started a batch.)
    """

    def __init__(self, n_modes: int) -> None:
        self.n_modes = n_modes
        self.fast: bool | None = None

    def __call__(self, model) -> np.ndarray:
        from ..fe import eigsh_lowest, modal_analysis
        from ..updating._roundoff import without_roundoff

        if self.fast is None:
            res = modal_analysis(model, self.n_modes)
            w2 = np.asarray(res.omega2, dtype=float)
            self.fast = bool(self.n_modes >= 2 and not np.any(res.rigid)
                             and w2.min() > 0 and w2.min() >= 1e-4 * w2.max())
            if not self.fast:
                return np.asarray(res.fn_hz, dtype=float)
            # the first model is solved again on the fast path, so that every sample
            # gets the same arithmetic whichever sample starts a batch or a worker
        if self.fast:
            try:
                sol = eigsh_lowest(without_roundoff(model.K), model.M, self.n_modes,
                                   singular_shift=_singular_shift)
            except _Singular:
                sol = None
            if sol is not None:
                w2 = np.asarray(sol.omega2, dtype=float)
                if w2.min() > 0 and w2.min() >= 1e-4 * w2.max():
                    return np.sqrt(w2) / (2.0 * np.pi)
        return np.asarray(modal_analysis(model, self.n_modes).fn_hz, dtype=float)


def _evaluate_batch(description, paths, rows, builder, n_modes, on_error, lowest=None,
                    reduced=None, tol=DEFAULT_TOL):
    """fn_hz (len(rows), n_modes) for each parameter row; NaN rows and messages on error.

    ``lowest``: the :class:`_LowestFrequencies` of the batch (a new one by default).
    ``reduced``: None (every row solved in full) or ``(p0, w)``, the centre and
    half-widths of the reduced basis (:func:`mvtk.scale._reduced.reduced_setup`).
    Returns ``(fn, errors, taken, bounds)``: the path each row took (``"reduced"``,
    ``"reduced+correction"``, ``"full"``, ``""`` when it failed) and its relative
    frequency error bound (NaN for a full solve).
    """
    from ..updating import with_values

    fn = np.full((len(rows), n_modes), np.nan)
    bounds = np.full(len(rows), np.nan)
    errors, taken = [], []
    lowest = lowest or _LowestFrequencies(n_modes)
    basis = None
    if reduced is not None:
        from ._reduced import reduced_setup

        basis = reduced_setup(description, paths, reduced[0], reduced[1], n_modes, builder)
        if isinstance(basis, str):
            basis = None
    for i, row in enumerate(rows):
        if basis is not None:
            f, bound, path = basis.solve(np.asarray(row, dtype=float), tol)
            if f is not None:
                fn[i], bounds[i] = f, bound
                errors.append("")
                taken.append(path)
                continue
        try:
            model = builder(with_values(description, dict(zip(paths, map(float, row)))))
            fn[i] = lowest(model)
        except (MvtkError, ArithmeticError) as err:
            if on_error == "raise":
                raise
            errors.append(f"{type(err).__name__}: {err}")
            taken.append("")
            continue
        errors.append("")
        taken.append("full")
    return fn, errors, taken, bounds


def _as_table(samples) -> tuple[list[str], np.ndarray]:
    if hasattr(samples, "columns") and hasattr(samples, "to_numpy"):
        paths = [str(c) for c in samples.columns]
        values = samples.to_numpy(dtype=float)
    elif isinstance(samples, Mapping):
        paths = [str(k) for k in samples]
        cols = [np.atleast_1d(np.asarray(v, dtype=float)) for v in samples.values()]
        lengths = {p: c.shape for p, c in zip(paths, cols)}
        if any(c.ndim != 1 for c in cols) or len({c.size for c in cols}) > 1:
            raise ParameterError(
                f"samples: expected 1-D arrays of one common length per path, got shapes {lengths}"
            )
        values = np.column_stack(cols) if cols else np.empty((0, 0))
    else:
        raise ParameterError(
            "samples: expected a dict {path: array} or a pandas.DataFrame with one column per "
            f"path, got {type(samples).__name__}"
        )
    if not paths or values.shape[0] == 0:
        raise ParameterError(f"samples: need at least one path and one sample, got {values.shape}")
    bad = ~np.isfinite(values)
    if bad.any():
        rows, cols = np.nonzero(bad)
        where = list(zip(rows.tolist(), [paths[c] for c in cols]))[:5]
        raise ParameterError(f"samples: non-finite values at (sample, path) {where}")
    return paths, values


def _load_description(description) -> dict:
    if isinstance(description, (str, Path)):
        from ..fe import load_structure

        return load_structure(description)
    if not isinstance(description, Mapping):
        raise ParameterError(
            "description: expected a structure dict or a TOML path, got "
            f"{type(description).__name__}"
        )
    return dict(description)


def _check_paths(description: dict, paths: list[str]) -> None:
    from ..fe import get_by_path

    for p in paths:
        get_by_path(description, p)  # ConfigError naming the path


def _connect(client, n_workers):
    """(client, owned) for None / "local" / an address / a Client."""
    if client is None:
        return None, False
    distributed = require_distributed("parameter_study(client=...)")
    if isinstance(client, str):
        if client == "local":
            cluster = distributed.LocalCluster(
                n_workers=n_workers or min(2, os.cpu_count() or 1), threads_per_worker=1,
                processes=True, dashboard_address=":0",
            )
            return distributed.Client(cluster), True
        return distributed.Client(client), True
    if isinstance(client, distributed.Client):
        return client, False
    raise ParameterError(
        "client: expected None, 'local', a scheduler address ('tcp://host:8786') or a "
        f"dask.distributed.Client, got {type(client).__name__}"
    )


def parameter_study(
    description,
    samples,
    *,
    builder: Callable | None = None,
    n_modes: int = 6,
    client=None,
    n_workers: int | None = None,
    batch_size: int | None = None,
    on_error: str = "raise",
    method: str = "auto",
    tol: float = DEFAULT_TOL,
):
    """Natural frequencies of the FE model for many parameter sets.

    Each sample replaces the given dotted paths of the structure description
    (:func:`mvtk.updating.with_values`), builds the model and runs
    :func:`mvtk.fe.modal_analysis`. Without ``client`` the samples run one after the
    other in this process; with a client they run as tasks on the dask cluster. The
    description is scattered to every worker once (``client.scatter(...,
    broadcast=True)``); each task carries only its rows of parameter values, and only
    ``fn_hz`` comes back (no matrices cross the wire).

    Parameters
    ----------
    description : dict or path
        Structure description (schema of :func:`mvtk.fe.build_model`) or its TOML file.
    samples : dict {path: array} or pandas.DataFrame
        Parameter values in the field's SI unit, one column per dotted path
        (``"materials.steel.E"``, ``"structure.layers.0.thickness"``).
    builder : callable, optional
        ``builder(description) -> FEModel``; default :func:`mvtk.fe.build_model`. Must be
        picklable (a module-level function) for a process-based or remote cluster.
    n_modes : int
        Modes per sample.
    client : None, "local", str or dask.distributed.Client
        None: in process. ``"local"``: a LocalCluster of ``n_workers`` processes (default
        2) started and closed here. A ``"tcp://host:port"`` address: connect to that
        scheduler. A Client: use it (left open).
    n_workers : int, optional
        Workers of the ``"local"`` cluster.
    batch_size : int, optional
        Samples per task (default: about four tasks per worker thread).
    on_error : {"raise", "nan"}
        What to do when a sample cannot be built or solved: raise (the message names the
        sample and its values), or return NaN frequencies for it with a
        :class:`~mvtk.errors.DataRepairWarning` listing the failed samples.
    method : {"auto", "reduced", "exact"}
        ``"exact"``: every sample is built and solved in full (shift-invert Lanczos).
        ``"reduced"``: Rayleigh-Ritz on a reduced basis (:mod:`mvtk.scale._reduced`):
        K and M are interpolated from a tensor grid of real builds around the centre
        (the description's values; checked against one more build to 1e-11 of every
        entry), the basis is the centre's lowest ``n_modes + 2`` eigenvectors plus two
        Neumann terms of their parameter derivatives, and every sample gets a
        Kato-Temple bound on the relative error of its frequencies (one block solve
        with the centre's factorisation). A sample whose bound exceeds ``tol`` gets one
        correction step, then, if still above, a full solve; so does a sample outside
        the grid's box or whose frequencies moved by more than a factor 1.6. When the
        model does not allow it (rigid-body modes, DOFs that change, matrices that are
        not polynomial in the parameters, fewer than ~4x the basis size of DOFs), every
        sample is solved in full and ``attrs["reduced_note"]`` says why. ``"auto"``
        (default): ``"reduced"`` in process or on a cluster from
        :data:`REDUCED_MIN_SAMPLES` samples on, or when every sample lies inside the box
        of the last reduced basis built in this process for the same description,
        centre, builder and ``n_modes`` (it is kept; a second study reuses it).
        The bound is on the eigenvalues of the interpolated matrices, which equal the
        built ones to round-off; note that the lowest frequency of a thin shell moves by
        up to ~1e-8 for a round-off-sized change of its matrices (smart beam: a 1-ulp
        change of E moved f1 by 7.5e-9 in a full solve), so a full solve is no more
        precise than that either.
    tol : float
        Largest relative frequency error bound accepted on the reduced path (default
        1e-8).

    Returns
    -------
    xarray.Dataset
        ``fn_hz`` (dims ``("sample", "mode")``, Hz), ``mode`` = 1..n_modes, one
        coordinate per path on ``sample`` with its values, ``error`` (str per sample,
        ``""`` when it succeeded), ``path`` (str per sample: ``"reduced"``,
        ``"reduced+correction"``, ``"full"``, ``""`` for a failed sample) and
        ``error_bound`` (relative frequency error bound of a reduced sample, the largest
        over its modes; NaN for a full solve); ``attrs["scheduler"]`` says where it ran,
        ``attrs["method"]`` the method used (``"reduced"`` or ``"exact"``),
        ``attrs["reduced_note"]`` why the reduced path was not used (``""`` if it was),
        ``attrs["n_full"]`` how many samples were solved in full.
    """
    import xarray as xr

    if on_error not in ("raise", "nan"):
        raise ParameterError(f"on_error must be 'raise' or 'nan', got {on_error!r}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ParameterError(f"n_modes must be an integer >= 1, got {n_modes!r}")
    if batch_size is not None and (not isinstance(batch_size, (int, np.integer)) or batch_size < 1):
        raise ParameterError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    if method not in METHODS:
        raise ParameterError(f"method must be one of {METHODS}, got {method!r}")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1:
        raise ParameterError(f"tol must be a relative error in (0, 1), got {tol!r}")
    builder = builder or _default_builder
    desc = _load_description(description)
    paths, values = _as_table(samples)
    _check_paths(desc, paths)
    n = values.shape[0]
    reduced, note = _reduced_box(desc, paths, values, builder, int(n_modes), method)
    cl, owned = _connect(client, n_workers)
    try:
        if cl is None:
            scheduler = "in-process"
            fn, errors, taken, bounds = _run_local(desc, paths, values, builder,
                                                   int(n_modes), on_error, reduced, tol)
        else:
            scheduler = str(cl.scheduler.address)
            threads = max(1, sum(cl.nthreads().values()))
            size = batch_size or max(1, math.ceil(n / (4 * threads)))
            fn, errors, taken, bounds = _run_client(cl, desc, paths, values, builder,
                                                    int(n_modes), on_error, size, reduced,
                                                    tol)
    finally:
        if owned:
            cluster = getattr(cl, "cluster", None)
            cl.close()
            if cluster is not None:
                cluster.close()
    failed = [i for i, e in enumerate(errors) if e]
    if failed:
        warnings.warn(
            f"parameter_study: {len(failed)} of {n} samples failed and have NaN fn_hz: "
            + "; ".join(f"sample {i}: {errors[i]}" for i in failed[:10])
            + (" ..." if len(failed) > 10 else ""),
            DataRepairWarning, stacklevel=2,
        )
    coords = {"sample": np.arange(n), "mode": np.arange(1, n_modes + 1)}
    for j, p in enumerate(paths):
        coords[p] = ("sample", values[:, j])
    fn_da = xr.DataArray(fn, dims=("sample", "mode"), attrs={"units": "Hz"})
    if reduced is not None and not any(t.startswith("reduced") for t in taken):
        note = note or _reduced_note(desc, paths, reduced, int(n_modes), builder)
    return xr.Dataset(
        {"fn_hz": fn_da, "error": ("sample", np.array(errors, dtype=str)),
         "path": ("sample", np.array(taken, dtype=str)),
         "error_bound": ("sample", bounds, {"units": "1", "long_name":
                                           "relative frequency error bound (reduced path)"})},
        coords=coords,
        attrs={"scheduler": scheduler, "n_modes": int(n_modes), "n_failed": len(failed),
               "parameters": ",".join(paths),
               "method": "reduced" if reduced is not None else "exact",
               "reduced_note": note, "tol": float(tol),
               "n_full": int(sum(t == "full" for t in taken))},
    )


def _centre(desc: dict, paths, values) -> np.ndarray:
    """The description's values at the paths (the column medians when one is not a
    finite number)."""
    from ..fe import get_by_path

    try:
        p0 = np.array([float(get_by_path(desc, p)) for p in paths])
    except (TypeError, ValueError, MvtkError):
        p0 = np.full(len(paths), np.nan)
    bad = ~np.isfinite(p0)
    p0[bad] = np.median(values, axis=0)[bad]
    return p0


def _reduced_box(desc, paths, values, builder, n_modes, method):
    """``((p0, w) or None, note)``: centre and half-widths of the reduced basis."""
    from ._reduced import cached_box

    if method == "exact":
        return None, "method='exact'"
    p0 = _centre(desc, paths, values)
    w = cached_box(desc, paths, p0, n_modes, builder, values)
    if w is None:
        if method == "auto" and values.shape[0] < REDUCED_MIN_SAMPLES:
            return None, (f"{values.shape[0]} samples < REDUCED_MIN_SAMPLES = "
                          f"{REDUCED_MIN_SAMPLES} (method='auto')")
        w = np.abs(values - p0).max(axis=0)
        # a parameter that never moves gets a nominal box (its grid is not needed)
        w[w == 0] = np.where(p0[w == 0] != 0, 1e-3 * np.abs(p0[w == 0]), 1.0)
    return (p0, w), ""


def _reduced_note(desc, paths, reduced, n_modes, builder) -> str:
    from ._reduced import reduced_setup

    basis = reduced_setup(desc, paths, reduced[0], reduced[1], n_modes, builder)
    return basis if isinstance(basis, str) else ""


def _raise_for(err: Exception, index: int, paths, row):
    vals = ", ".join(f"{p}={float(v)!r}" for p, v in zip(paths, row))
    raise type(err)(f"parameter_study: sample {index} ({vals}) failed: {err}") from err


def _run_local(desc, paths, values, builder, n_modes, on_error, reduced=None,
               tol=DEFAULT_TOL):
    fn = np.full((values.shape[0], n_modes), np.nan)
    bounds = np.full(values.shape[0], np.nan)
    errors, taken = [], []
    lowest = _LowestFrequencies(n_modes)
    for i, row in enumerate(values):
        try:
            f, e, t, b = _evaluate_batch(desc, paths, row[None, :], builder, n_modes,
                                         on_error, lowest, reduced, tol)
        except (MvtkError, ArithmeticError) as err:
            _raise_for(err, i, paths, row)
        fn[i], bounds[i] = f[0], b[0]
        errors.extend(e)
        taken.extend(t)
    return fn, errors, taken, bounds


def _run_client(cl, desc, paths, values, builder, n_modes, on_error, size, reduced=None,
                tol=DEFAULT_TOL):
    desc_future = cl.scatter(desc, broadcast=True)
    starts = list(range(0, values.shape[0], size))
    futures = cl.map(
        _evaluate_batch, [desc_future] * len(starts), [paths] * len(starts),
        [values[s:s + size] for s in starts], builder=builder, n_modes=n_modes,
        on_error="nan", reduced=reduced, tol=tol, pure=False,
    )
    fn = np.full((values.shape[0], n_modes), np.nan)
    bounds = np.full(values.shape[0], np.nan)
    errors: list[str] = []
    taken: list[str] = []
    for s, (f, e, t, b) in zip(starts, cl.gather(futures)):
        fn[s:s + len(e)] = f
        bounds[s:s + len(e)] = b
        errors.extend(e)
        taken.extend(t)
    cl.cancel([desc_future])
    if on_error == "raise":
        for i, e in enumerate(errors):
            if e:
                vals = ", ".join(f"{p}={float(v)!r}" for p, v in zip(paths, values[i]))
                raise _error_class(e)(f"parameter_study: sample {i} ({vals}) failed: {e}")
    return fn, errors, taken, bounds


def _error_class(message: str) -> type:
    from .. import errors

    name = message.split(":", 1)[0]
    cls = getattr(errors, name, None)
    return cls if isinstance(cls, type) and issubclass(cls, Exception) else errors.MvtkError


def draw_samples(distributions: Mapping, n: int, rng):
    """Draw ``n`` parameter sets from independent distributions.

    Parameters
    ----------
    distributions : dict {path: (kind, params)}
        ``kind`` one of :data:`DISTRIBUTION_KINDS`: ``("normal", (mean, std))``,
        ``("lognormal", (mean, std))`` (moments of the value itself),
        ``("uniform", (low, high))``; in the field's SI unit.
    n : int
        Number of samples (>= 2).
    rng : numpy.random.Generator

    Returns
    -------
    pandas.DataFrame
        One column per path, ``n`` rows.
    """
    import pandas as pd

    if not isinstance(rng, np.random.Generator):
        raise ParameterError(
            f"rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
            f"got {type(rng).__name__}"
        )
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ParameterError(f"n: expected an integer >= 2 samples, got {n!r}")
    if not isinstance(distributions, Mapping) or not distributions:
        raise ParameterError(
            "distributions: expected a non-empty dict {path: (kind, params)}, got "
            f"{distributions!r}"
        )
    cols = {}
    for path, spec in distributions.items():
        try:
            kind, params = spec
            a, b = (float(v) for v in params)
        except (TypeError, ValueError):
            raise ParameterError(
                f"distributions[{path!r}]: expected (kind, (p1, p2)), got {spec!r}"
            ) from None
        if kind not in DISTRIBUTION_KINDS:
            raise ParameterError(
                f"distributions[{path!r}]: unknown kind {kind!r}; expected one of "
                + ", ".join(f"{k} {v}" for k, v in DISTRIBUTION_KINDS.items())
            )
        if kind == "uniform":
            if not (np.isfinite(a) and np.isfinite(b) and b > a):
                raise ParameterError(
                    f"distributions[{path!r}]: uniform needs low < high, got {params}"
                )
            cols[path] = rng.uniform(a, b, n)
            continue
        if not (np.isfinite(a) and np.isfinite(b) and b > 0):
            raise ParameterError(
                f"distributions[{path!r}]: {kind} needs a finite mean and std > 0, got {params}"
            )
        if kind == "normal":
            cols[path] = rng.normal(a, b, n)
        else:
            if a <= 0:
                raise ParameterError(
                    f"distributions[{path!r}]: lognormal needs mean > 0, got {a!r}"
                )
            s2 = math.log1p((b / a) ** 2)
            cols[path] = rng.lognormal(math.log(a) - s2 / 2, math.sqrt(s2), n)
    return pd.DataFrame(cols)


@dataclass(frozen=True)
class MonteCarloResult:
    """Scatter of natural frequencies from a Monte-Carlo parameter study.

    Attributes
    ----------
    samples : xarray.Dataset
        Output of :func:`parameter_study` (``fn_hz`` per sample and mode, parameter
        values as ``sample`` coordinates).
    distributions : dict
        The input distributions ``{path: (kind, params)}``.
    percentiles : tuple of float
        Percentiles reported by :meth:`to_dataframe` (in %).
    """

    samples: object
    distributions: dict
    percentiles: tuple[float, ...] = (5.0, 50.0, 95.0)

    @property
    def fn_hz(self) -> np.ndarray:
        """Frequencies (n_samples, n_modes) in Hz (NaN rows for failed samples)."""
        return np.asarray(self.samples["fn_hz"].values)

    def to_dataframe(self):
        """One row per mode: ``mode``, ``n`` (valid samples), ``mean_hz``, ``std_hz``
        (ddof=1), ``cov`` (std/mean), ``min_hz``, ``p<q>_hz`` per percentile, ``max_hz``."""
        import pandas as pd

        fn = self.fn_hz
        ok = np.isfinite(fn).all(axis=1)
        f = fn[ok]
        rows = []
        for j in range(fn.shape[1]):
            col = f[:, j]
            mean = float(np.mean(col)) if col.size else np.nan
            std = float(np.std(col, ddof=1)) if col.size > 1 else np.nan
            row = {"mode": j + 1, "n": int(col.size), "mean_hz": mean, "std_hz": std,
                   "cov": std / mean if mean else np.nan,
                   "min_hz": float(np.min(col)) if col.size else np.nan}
            for q in self.percentiles:
                row[f"p{q:g}_hz"] = float(np.percentile(col, q)) if col.size else np.nan
            row["max_hz"] = float(np.max(col)) if col.size else np.nan
            rows.append(row)
        return pd.DataFrame(rows)

    def parameters_dataframe(self):
        """The drawn parameter values, one column per path."""
        import pandas as pd

        return pd.DataFrame({p: self.samples[p].values for p in self.distributions})


def monte_carlo(
    description,
    distributions: Mapping,
    n: int,
    rng,
    *,
    builder: Callable | None = None,
    n_modes: int = 6,
    client=None,
    n_workers: int | None = None,
    batch_size: int | None = None,
    percentiles=(5.0, 50.0, 95.0),
    on_error: str = "raise",
    method: str = "auto",
    tol: float = DEFAULT_TOL,
) -> MonteCarloResult:
    """Propagate material/geometry scatter to natural frequencies by Monte Carlo.

    Draws ``n`` independent samples (:func:`draw_samples`) and evaluates them with
    :func:`parameter_study` (same ``builder``, ``client``, ``on_error``, ``method``,
    ``tol`` options).

    Parameters
    ----------
    description : dict or path
        Nominal structure description.
    distributions : dict {path: (kind, params)}
        See :func:`draw_samples`.
    n : int
        Number of samples.
    rng : numpy.random.Generator
        The only source of randomness: the same seed draws the same samples in process
        or on a cluster (frequencies then agree to eigensolver round-off, ~1e-14).
    percentiles : sequence of float
        Percentiles (in %, 0..100) for the statistics table.
    method, tol
        As in :func:`parameter_study` (default: the reduced basis with its per-sample
        error bound from 16 samples on; ``samples["path"]`` and
        ``samples["error_bound"]`` say which path each sample took and its bound).

    Returns
    -------
    MonteCarloResult
        ``to_dataframe()`` gives mean, std, CoV and percentiles per mode.
    """
    pct = tuple(float(q) for q in percentiles)
    if any(not 0 <= q <= 100 for q in pct):
        raise ParameterError(f"percentiles must lie in [0, 100] %, got {percentiles!r}")
    table = draw_samples(distributions, n, rng)
    ds = parameter_study(description, table, builder=builder, n_modes=n_modes, client=client,
                         n_workers=n_workers, batch_size=batch_size, on_error=on_error,
                         method=method, tol=tol)
    return MonteCarloResult(samples=ds, distributions=dict(distributions), percentiles=pct)
