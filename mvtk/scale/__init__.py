"""Scale beyond one machine: dask-backed measurement campaigns and parameter studies.

dask (``pip install "mvtk[scale]"``) is imported only inside the functions; without it
they raise :class:`mvtk.errors.MissingDependencyError` with the pip command.

Functions
---------
``open_campaign(paths_or_glob, *, format, concat, on_error, chunks, **read_options)``
    Many files -> one lazy Dataset (``record`` dim or joined in time), every bad file
    reported at once.
``psd(x, fs, window, nperseg, noverlap, detrend, scaling, *, combine_records, compute)``
    Chunked Welch PSD equal to :func:`mvtk.signal.psd` on the same data.
``csd(x, reference, fs, window, nperseg, noverlap, detrend, scaling, *, compute)``
    Chunked Welch cross-spectral matrix equal to :func:`mvtk.signal.csd`.
``frf(x, reference, response, *, estimator, fs, window, nperseg, noverlap, detrend)``
    H1/H2 FRFs and coherence (random excitation) equal to :func:`mvtk.signal.frf`.
``map_channels(func, x, *, output_dims, output_sizes, output_dtype, kwargs)``
    Per-channel estimators through ``xarray.apply_ufunc(dask="parallelized")``.
``parameter_study(description, samples, *, builder, n_modes, client, on_error)``
    FE modal analyses for many parameter sets, in process or on a dask cluster.
``monte_carlo(description, distributions, n, rng, ...) -> MonteCarloResult``
    Material/geometry scatter propagated to eigenfrequencies (statistics table).
``eigen_sensitivity(description, parameters, *, builder, n_modes, ..., client)``
    The updating Jacobian (:func:`mvtk.updating.eigen_sensitivity`), one task per column.
``plot_fn_histogram(result, modes=None, bins=30)`` (in :mod:`mvtk.scale._plot`)
    Histogram figure of the Monte-Carlo frequencies.

See ``docs/scaling.md`` for running the same code on a remote cluster.
"""

from ..io._campaign import DEFAULT_TIME_CHUNK, open_campaign
from ._jacobian import eigen_sensitivity
from ._plot import plot_fn_histogram
from ._spectral import csd, frf, map_channels, psd
from ._study import (
    DISTRIBUTION_KINDS,
    MonteCarloResult,
    draw_samples,
    monte_carlo,
    parameter_study,
)

__all__ = [
    "DEFAULT_TIME_CHUNK",
    "DISTRIBUTION_KINDS",
    "csd",
    "MonteCarloResult",
    "draw_samples",
    "eigen_sensitivity",
    "frf",
    "map_channels",
    "monte_carlo",
    "open_campaign",
    "parameter_study",
    "plot_fn_histogram",
    "psd",
]
