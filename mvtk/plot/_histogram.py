"""Histogram figure of Monte-Carlo natural frequencies (matplotlib imported when called).

Lives in :mod:`mvtk.plot` (re-exported by :mod:`mvtk.scale`) so that a report can draw
it without importing the dask-backed :mod:`mvtk.scale` and its signal-processing stack.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError

__all__ = ["plot_fn_histogram"]

#: Fixed margins of a grid of small panels (inches): left (tick labels and axis label),
#: right, bottom (tick labels and axis label), top (figure title and panel title), and
#: the gaps between columns (the next panel's tick and axis labels) and rows (axis
#: label below, panel title above). See :data:`mvtk.plot._figures.MARGIN_LEFT`.
GRID_MARGINS = {"left": 0.65, "right": 0.15, "bottom": 0.5, "top": 0.6, "wgap": 0.65,
                "hgap": 0.8}


def _grid_figure(nrow: int, ncol: int, panel_w: float, panel_h: float):
    """A figure of ``nrow`` x ``ncol`` panels of about ``panel_w`` x ``panel_h`` in."""
    from matplotlib.figure import Figure

    g = GRID_MARGINS
    width, height = panel_w * ncol, panel_h * nrow
    fig = Figure(figsize=(width, height))
    ax_w = (width - g["left"] - g["right"] - g["wgap"] * (ncol - 1)) / ncol
    ax_h = (height - g["bottom"] - g["top"] - g["hgap"] * (nrow - 1)) / nrow
    fig.subplots_adjust(left=g["left"] / width, right=1 - g["right"] / width,
                        bottom=g["bottom"] / height, top=1 - g["top"] / height,
                        wspace=g["wgap"] / ax_w, hspace=g["hgap"] / ax_h)
    return fig


def plot_fn_histogram(result, modes=None, bins: int = 30):
    """Histograms of the sampled natural frequencies, one panel per mode.

    Parameters
    ----------
    result : MonteCarloResult
        Output of :func:`mvtk.scale.monte_carlo` (any object with an ``fn_hz`` array
        of shape (n_samples, n_modes) in Hz).
    modes : sequence of int, optional
        1-based mode numbers to show (default: all, at most 6).
    bins : int
        Histogram bins per panel.

    Returns
    -------
    matplotlib.figure.Figure
        An Agg-backed figure (no pyplot state); each panel marks the mean and the 5 %
        and 95 % percentiles. Save it with ``fig.savefig`` or
        :func:`mvtk.plot.figure_to_png`.

    Examples
    --------
    Any object with an ``fn_hz`` array (n_samples, n_modes) in Hz, e.g. a Monte Carlo
    result:

    >>> import types
    >>> rng = np.random.default_rng(0)
    >>> result = types.SimpleNamespace(fn_hz=rng.normal([10.0, 30.0], [0.1, 0.3], (200, 2)))
    >>> fig = plot_fn_histogram(result)
    >>> len([ax for ax in fig.axes if ax.get_visible()])
    2
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fn = np.asarray(getattr(result, "fn_hz", None) if result is not None else None)
    if fn.ndim != 2:
        raise ParameterError(
            f"plot_fn_histogram: expected a MonteCarloResult, got {type(result).__name__}"
        )
    n_modes = fn.shape[1]
    modes = list(range(1, min(n_modes, 6) + 1)) if modes is None else [int(m) for m in modes]
    bad = [m for m in modes if not 1 <= m <= n_modes]
    if bad or not modes:
        raise ParameterError(
            f"plot_fn_histogram: modes must be 1-based numbers in 1..{n_modes}, got {modes}"
        )
    ok = np.isfinite(fn).all(axis=1)
    ncol = min(3, len(modes))
    nrow = -(-len(modes) // ncol)
    fig = _grid_figure(nrow, ncol, 3.2, 2.6)
    FigureCanvasAgg(fig)
    for k, m in enumerate(modes):
        ax = fig.add_subplot(nrow, ncol, k + 1)
        col = fn[ok, m - 1]
        ax.hist(col, bins=bins, color="C0", alpha=0.8)
        mean = float(np.mean(col))
        p5, p95 = np.percentile(col, [5, 95])
        ax.axvline(mean, color="k", lw=1.2, label="mean")
        ax.axvline(p5, color="C3", ls="--", lw=1, label="5 / 95 %")
        ax.axvline(p95, color="C3", ls="--", lw=1)
        cov = np.std(col, ddof=1) / mean if col.size > 1 else np.nan
        ax.set_title(f"mode {m}: {mean:.4g} Hz, CoV {100 * cov:.2g} %", fontsize=9,
                     y=1.0)  # at the top, as auto-placed; no re-layout per draw
        ax.set_xlabel("natural frequency (Hz)")
        ax.set_ylabel("samples")
        if k == 0:
            ax.legend(fontsize=7)
    fig.suptitle(f"Monte Carlo, {int(ok.sum())} samples", fontsize=10)
    return fig
