"""Figures of the validation workflow (matplotlib, Agg; never pyplot).

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so no
GUI backend is touched and nothing is kept in a global figure registry. Convert with
:func:`figure_to_png` or pass the figure to :meth:`mvtk.report.Section.figure`.
"""

from __future__ import annotations

import io
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import DimensionError, ParameterError

__all__ = [
    "figure_to_png",
    "minmax_decimate",
    "plot_frf",
    "plot_decay",
    "plot_mode_shapes",
    "plot_time_responses",
    "plot_spectra",
]


#: Width in inches of every report figure (one column of the page; same scale for all).
FIG_WIDTH = 7.0
#: Points kept per line by :func:`minmax_decimate` in the plots (two per pixel column of
#: a 7 in figure at 100 dpi, with margin).
MAX_POINTS = 2000


#: Fixed margins of the line plots in inches: room for tick labels (up to 7 characters
#: or a power of ten) and the axis label on the left, tick labels and axis label below,
#: a title above. A fixed layout draws the same elements as matplotlib's constrained
#: layout but does not lay out every text twice before drawing it (half the render time
#: of a report figure); ``tests/report`` checks that no text leaves the figure and no
#: panel overlaps another.
MARGIN_LEFT, MARGIN_RIGHT, MARGIN_BOTTOM = 0.9, 0.2, 0.55
#: Margin above the top panel with (without) a title, and the gap between stacked panels
#: (the upper panel's tick labels and axis label, the lower panel's title), inches.
MARGIN_TITLE, MARGIN_TOP, PANEL_GAP = 0.4, 0.15, 0.8
#: Titles are placed at the top of their axes (``set_title(..., y=1.0)``) where
#: matplotlib would place them too (no tick labels on top): given explicitly, matplotlib
#: does not lay out the y axis again to look for a collision at every draw.


def _constrained_figure(width: float = FIG_WIDTH, height: float = 4.0):
    """A figure laid out by matplotlib's constrained layout (colorbars, grids)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _figure(width: float = FIG_WIDTH, height: float = 4.0, *, n_rows: int = 1,
            title: bool = True):
    """A figure with fixed margins for ``n_rows`` stacked full-width panels."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    top = MARGIN_TITLE if title else MARGIN_TOP
    panel = (height - top - MARGIN_BOTTOM - PANEL_GAP * (n_rows - 1)) / n_rows
    fig.subplots_adjust(left=MARGIN_LEFT / width, right=1 - MARGIN_RIGHT / width,
                        bottom=MARGIN_BOTTOM / height, top=1 - top / height,
                        hspace=PANEL_GAP / panel if n_rows > 1 else 0.0)
    return fig


def minmax_decimate(x: Any, y: Any, n_bins: int = MAX_POINTS // 2):
    """Reduce a long line to the minimum and maximum of ``y`` in ``n_bins`` bins of ``x``.

    Plotted as a line, the result covers exactly the pixels the full signal covers when
    each bin is at most one pixel column wide: peaks (resonances, the first cycles of a
    decay) are kept, unlike plain subsampling, and a 150 s decay sampled at 1 kHz becomes
    ``2 n_bins`` points instead of a solid band of 150 000 segments.

    Parameters
    ----------
    x : array, shape (n,)
        Abscissa, ascending (time in s, frequency in Hz).
    y : array, shape (n,)
        Real ordinate; complex values are replaced by their modulus.
    n_bins : int
        Number of bins (>= 1). Inputs with ``n <= 2 n_bins`` are returned unchanged.

    Returns
    -------
    xd, yd : arrays, shape (m,), m <= 2 n_bins
        For each bin the (x, y) of its minimum and of its maximum, in the order they
        occur, so the polyline follows the signal.

    Examples
    --------
    150 s at 1 kHz become 2 x 1000 points that keep every peak (+-1):

    >>> t = np.arange(150_000) / 1000.0
    >>> xd, yd = minmax_decimate(t, np.sin(2 * np.pi * 7.3 * t), n_bins=1000)
    >>> xd.shape, round(float(yd.max()), 3), round(float(yd.min()), 3)
    ((2000,), 1.0, -1.0)
    """
    xx = np.asarray(x, dtype=float)
    yy = np.asarray(y)
    if np.iscomplexobj(yy):
        yy = np.abs(yy)
    yy = yy.astype(float)
    if xx.ndim != 1 or yy.shape != xx.shape:
        raise DimensionError(f"minmax_decimate needs x and y of the same 1-D shape, got "
                             f"{xx.shape} and {yy.shape}")
    if not isinstance(n_bins, int | np.integer) or n_bins < 1:
        raise ParameterError(f"n_bins must be an integer >= 1, got {n_bins!r}")
    n = xx.size
    if n <= 2 * n_bins:
        return xx, yy
    # equal-width bins in x (uniform sampling -> equal counts); empty bins skipped
    edges = np.searchsorted(xx, np.linspace(xx[0], xx[-1], n_bins + 1)[1:-1])
    starts = np.unique(np.r_[0, edges])
    starts = starts[starts < n]
    lens = np.diff(np.r_[starts, n])
    starts, lens = starts[lens > 0], lens[lens > 0]
    # per bin the first index of its minimum and of its maximum (NaN and inf ignored;
    # an all-NaN bin keeps its first sample), vectorised over the bins
    y_fin = np.where(np.isfinite(yy), yy, np.nan)
    with np.errstate(invalid="ignore"):
        lo = np.fmin.reduceat(y_fin, starts)
        hi = np.fmax.reduceat(y_fin, starts)
    pos = np.arange(n)
    imin = np.minimum.reduceat(np.where(y_fin == np.repeat(lo, lens), pos, n), starts)
    imax = np.minimum.reduceat(np.where(y_fin == np.repeat(hi, lens), pos, n), starts)
    imin = np.where(imin < n, imin, starts)
    imax = np.where(imax < n, imax, starts)
    idx = np.sort(np.unique(np.r_[imin, imax]))
    return xx[idx], yy[idx]


_SUPERSCRIPT = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075"
                                                 "\u2076\u2077\u2078\u2079")
_MATH_LABEL = re.compile(r"^\$\\mathdefault\{(-?)(?:([0-9.e+]+)\\times)?(?:10\^\{(-?\d+)\}|"
                         r"([0-9.e+-]+))\}\$$")


def _plain_log_label(label: str) -> str:
    """``$\\mathdefault{6\\times10^{3}}$`` -> ``6×10³`` (Unicode, no mathtext).

    The labels matplotlib's log formatter writes: ``10^{k}``, ``c\\times10^{k}`` and
    plain numbers. Anything else is returned unchanged (drawn as mathtext).
    """
    m = _MATH_LABEL.match(label)
    if not m:
        return label
    sign, coeff, exp, plain = m.groups()
    if plain is not None:
        return sign + plain
    power = "10" + exp.translate(_SUPERSCRIPT)
    return sign + (f"{coeff}\u00d7{power}" if coeff else power)


def _plain_log_axis(axis) -> None:
    """Label a log axis as matplotlib does, typeset as Unicode text, not mathtext.

    The same ticks get the same labels (matplotlib's own formatter decides which
    minor ticks are labelled); only the typesetting differs: ``10³`` instead of the
    mathtext ``10^{3}``, whose parsing is a third of the render time of a log plot.
    """
    from matplotlib.ticker import LogFormatterSciNotation

    class _Plain(LogFormatterSciNotation):
        def __call__(self, x, pos=None):
            return _plain_log_label(super().__call__(x, pos))

    major, minor = axis.get_major_formatter(), axis.get_minor_formatter()
    if isinstance(major, LogFormatterSciNotation) and isinstance(minor,
                                                                 LogFormatterSciNotation):
        axis.set_major_formatter(_Plain(labelOnlyBase=major.labelOnlyBase))
        axis.set_minor_formatter(_Plain(labelOnlyBase=minor.labelOnlyBase))


def _sparse_log_minor(ax, max_decades: float = 3.0) -> None:
    """Drop the minor ticks of a log y axis spanning more than ``max_decades`` decades.

    Beyond a few decades the eight unlabelled minor ticks per decade are a dense comb
    that carries no reading; they are also most of the ticks matplotlib creates and
    lays out for the axis (a fifth of the render time of a two-panel FRF figure).
    """
    from matplotlib.ticker import NullLocator

    lo, hi = ax.get_ylim()
    if lo > 0 and hi > 0 and abs(np.log10(hi / lo)) > max_decades:
        ax.yaxis.set_minor_locator(NullLocator())


def _bin_extrema(t: np.ndarray, y: np.ndarray, n_bins: int):
    """Bin centres, minimum and maximum of ``y`` in ``n_bins`` equal bins of ``t``."""
    edges = np.linspace(t[0], t[-1], n_bins + 1)
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, n_bins - 1)
    lo = np.full(n_bins, np.nan)
    hi = np.full(n_bins, np.nan)
    np.fmin.at(lo, k, y)
    np.fmax.at(hi, k, y)
    return 0.5 * (edges[:-1] + edges[1:]), lo, hi


def _crop(x: np.ndarray, ys: list[np.ndarray], x_range):
    """Keep the samples inside ``x_range`` (plus one on each side)."""
    if x_range is None:
        return x, ys
    lo = max(int(np.searchsorted(x, x_range[0])) - 1, 0)
    hi = min(int(np.searchsorted(x, x_range[1], side="right")) + 1, x.size)
    return x[lo:hi], [y[lo:hi] for y in ys]


#: zlib level of the PNG encoding of :func:`figure_to_png`. Measured on the study's
#: figures (7 x 5 and 7 x 14 in at 100 dpi): level 1 encodes in about 70 % of the time
#: of PIL's default 6 for files 5-8 % larger (9 is 2-3x slower for 3-4 % smaller).
PNG_COMPRESS_LEVEL = 1


def figure_to_png(fig: Any, dpi: int = 100) -> bytes:
    """PNG bytes of a matplotlib figure (fast zlib level, :data:`PNG_COMPRESS_LEVEL`).

    Examples
    --------
    >>> fig = plot_frf(np.linspace(1.0, 40.0, 400), np.ones(400), ylabel="|H| [m/N]")
    >>> figure_to_png(fig)[1:4]         # the PNG signature
    b'PNG'
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    return buf.getvalue()


def _vec(name: str, x: Any) -> np.ndarray:
    a = np.asarray(x)
    if a.ndim != 1 or a.size < 2:
        raise DimensionError(f"{name} must be a 1-D array of at least 2 values, got shape "
                             f"{a.shape}")
    return a


def plot_frf(
    f_hz: Sequence[float],
    H: Sequence[complex],
    *,
    bands: Sequence[tuple[float, float, float]] = (),
    f_range: tuple[float, float] | None = None,
    ylabel: str = "|H|",
    title: str = "",
    markers: bool = False,
    coherence: Sequence[float] | None = None,
):
    """FRF magnitude (log) with half-power bands marked, and its coherence below.

    Parameters
    ----------
    f_hz : array, shape (n,)
        Frequencies in Hz.
    H : array, shape (n,)
        Complex (or magnitude) FRF.
    bands : sequence of (f_low_hz, f_high_hz, fn_hz)
        Half-power band edges and resonance of each identified mode; shaded and
        annotated.
    f_range : (f_min, f_max), optional
        Plotted frequency range in Hz.
    markers : bool
        Mark every frequency line (shows the resolution across a half-power band).
    coherence : array, shape (n,), optional
        Ordinary coherence of the FRF estimate (0..1), drawn in a panel below: where it
        drops, the FRF is noise or leakage, not structure.

    Examples
    --------
    >>> f = np.linspace(1.0, 40.0, 400)
    >>> H = 1 / (13.0**2 - f**2 + 0.3j * f)
    >>> fig = plot_frf(f, H, ylabel="|H| [m/N]", coherence=np.full(400, 0.99))
    >>> len(fig.axes)
    2
    """
    f = _vec("f_hz", f_hz)
    h = np.abs(_vec("H", H))
    if h.shape != f.shape:
        raise DimensionError(f"H has {h.size} values but f_hz has {f.size}")
    coh = None
    if coherence is not None:
        coh = _vec("coherence", coherence)
        if coh.shape != f.shape:
            raise DimensionError(f"coherence has {coh.size} values but f_hz has {f.size}")
        f, (h, coh) = _crop(f, [h, coh], f_range)
    else:
        f, (h,) = _crop(f, [h], f_range)
    f_full = f
    if not markers:
        f, h = minmax_decimate(f, h)
    if coh is None:
        fig = _figure(title=bool(title))
        ax = fig.add_subplot()
    else:
        fig = _figure(height=5.2, title=bool(title))
        gs = fig.add_gridspec(2, 1, height_ratios=[2.6, 1.0],
                              hspace=0.12)
        ax = fig.add_subplot(gs[0])
        axc = fig.add_subplot(gs[1], sharex=ax)
        fc, cc = (f_full, coh) if markers else minmax_decimate(f_full, coh)
        axc.plot(fc, cc, lw=0.9, color="C2", marker="o" if markers else None, ms=2)
        axc.set_ylim(min(0.5, float(np.nanmin(coh)) - 0.02) if np.isfinite(coh).any()
                     else 0.0, 1.02)
        axc.set_ylabel("coherence")
        axc.set_xlabel("frequency [Hz]")
        axc.grid(True, alpha=0.3)
    ax.semilogy(f, h, lw=1.0, color="C0", label="FRF", marker="o" if markers else None,
                ms=3)
    _plain_log_axis(ax.yaxis)
    x0, x1 = (f_range if f_range is not None else (float(f[0]), float(f[-1])))
    last, level = -np.inf, 0
    for i, (lo, hi, fn) in enumerate(sorted(bands, key=lambda b: b[2])):
        ax.axvspan(lo, hi, color="C3", alpha=0.25, label="half-power band" if i == 0 else None)
        ax.axvline(fn, color="C3", lw=0.8, ls="--")
        # labels closer than 14 % of the axis width are staggered downwards
        pos = (fn - x0) / (x1 - x0) if x1 > x0 else 0.0
        level = (level + 1) % 3 if pos - last < 0.14 else 0
        last = pos
        ax.annotate(f"{fn:.3f} Hz", (fn, 1.0 - 0.08 * level),
                    xycoords=("data", "axes fraction"), ha="left", va="top", fontsize=9,
                    color="C3")
    if f_range is not None:
        ax.set_xlim(*f_range)
    if coh is None:
        ax.set_xlabel("frequency [Hz]")
    else:
        ax.tick_params(labelbottom=False)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    if title:
        ax.set_title(title, y=1.0)
    return fig


def plot_decay(
    t: Sequence[float],
    x: Sequence[float],
    *,
    envelope: Sequence[float] | None = None,
    fit: Sequence[float] | None = None,
    label_fit: str = "exponential fit",
    ylabel: str = "response",
    title: str = "",
    log_panel: bool = True,
):
    """Free decay with its envelope and the fitted exponential envelope.

    Long records are drawn as their min/max envelope per pixel column
    (:func:`minmax_decimate`), so a decay of thousands of cycles stays readable as a
    shaded band bounded by the signal's peaks instead of a solid block of lines. With
    ``log_panel`` a second panel shows the peak amplitude per pixel column on a log
    scale, where an exponential decay (and its fit) is a straight line.

    Parameters
    ----------
    t : array, shape (n,)
        Time in s.
    x : array, shape (n,)
        The (band-passed) decay signal.
    envelope : array, shape (n,), optional
        Measured envelope (e.g. the modulus of the Hilbert transform).
    fit : array, shape (n,), optional
        Fitted envelope A exp(-zeta omega t), plotted as +/- curves.
    log_panel : bool
        Add the log-amplitude panel (needs a positive signal or fit).

    Examples
    --------
    A 12 Hz free decay at 1 % damping (``exp(-zeta w t)`` envelope, 0.754 1/s): the
    signal panel and the log panel, where the envelope is a straight line:

    >>> t = np.arange(0.0, 10.0, 1 / 256)                                 # s
    >>> env = np.exp(-0.01 * 2 * np.pi * 12.0 * t)
    >>> fig = plot_decay(t, env * np.cos(2 * np.pi * 12.0 * t), envelope=env, fit=env,
    ...                  ylabel="tip displacement [m]")
    >>> len(fig.axes), fig.axes[1].get_yscale()
    (2, 'log')
    """
    tt = _vec("t", t)
    xx = _vec("x", x)
    if xx.shape != tt.shape:
        raise DimensionError(f"x has {xx.size} values but t has {tt.size}")
    for name, arr in (("envelope", envelope), ("fit", fit)):
        if arr is not None and np.shape(arr) != tt.shape:
            raise DimensionError(f"{name} has shape {np.shape(arr)} but t has {tt.shape}")
    fig = _figure(FIG_WIDTH, 6.0 if log_panel else 4.0, n_rows=2 if log_panel else 1,
                  title=bool(title))
    ax = fig.add_subplot(2 if log_panel else 1, 1, 1)
    # one bin per pixel column of the panel at 100 dpi (the report's PNG resolution;
    # an SVG is shown at about that width): the band, the fit and the log panel hold
    # what can be drawn and no more (the SVG of a 6400-sample decay 114 -> ~70 kB)
    n_bins = max(1, int(round(ax.get_position().width * FIG_WIDTH * 100)))
    long_record = tt.size > 2 * n_bins
    if long_record:
        # min/max per pixel column as a filled band bounded by the signal's peaks
        mid, lo, hi = _bin_extrema(tt, xx, n_bins)
        ax.fill_between(mid, lo, hi, color="0.6", lw=0, label="signal (min/max per pixel)")
    else:
        ax.plot(tt, xx, lw=0.6, color="0.45", label="signal")
    if envelope is not None:
        te, ee = minmax_decimate(tt, np.asarray(envelope, dtype=float), n_bins)
        ax.plot(te, ee, lw=1.0, color="C0", label="envelope")
    if fit is not None:
        tf, ff = minmax_decimate(tt, np.asarray(fit, dtype=float), n_bins)
        ax.plot(tf, ff, lw=1.5, color="C3", ls="--", label=label_fit)
        ax.plot(tf, -ff, lw=1.5, color="C3", ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title, y=1.0)
    if log_panel:
        ax2 = fig.add_subplot(2, 1, 2, sharex=ax)
        if long_record:
            mid, _, peak = _bin_extrema(tt, np.abs(xx), n_bins)
        else:
            mid, peak = tt, np.abs(xx)
        good = np.isfinite(peak) & (peak > 0)
        ax2.semilogy(mid[good], peak[good], lw=0.8, color="0.35", label="peak |signal|")
        _plain_log_axis(ax2.yaxis)
        if fit is not None:
            ff = np.asarray(fit, dtype=float)
            pos = ff > 0
            tf, ffd = (minmax_decimate(tt[pos], ff[pos], n_bins) if pos.sum() >= 2
                       else (tt[:0], ff[:0]))
            ax2.semilogy(tf, ffd, lw=1.5, color="C3", ls="--", label=label_fit)
        ax2.set_xlabel("time [s]")
        ax2.set_ylabel(f"|{ylabel}| (log)" if len(ylabel) < 30 else "amplitude (log)")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(loc="upper right", fontsize=8)
    return fig


def plot_mode_shapes(
    nodes: Any,
    uz: Any,
    fn_hz: Sequence[float],
    *,
    n_cols: int = 2,
):
    """Contour plots of the out-of-plane mode shape component of a plate model.

    Parameters
    ----------
    nodes : array, shape (n_nodes, 3)
        Node coordinates in m (x, y used).
    uz : array, shape (n_nodes, n_modes)
        Out-of-plane displacement of each node in each mode (e.g. ``FEModel.expand``
        of the mode vectors, component ``uz``). Each mode is scaled to a largest
        absolute ``uz`` of 1.
    fn_hz : sequence of float, length n_modes
        Eigenfrequencies in Hz (titles).

    Examples
    --------
    The two lowest modes of a 300 x 200 x 2 mm steel plate clamped at x = 0:

    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> modes = modal_analysis(plate, 2)
    >>> uz = plate.expand(modes.shapes)[:, 2, :]         # (n_nodes, n_modes), component uz
    >>> fig = plot_mode_shapes(plate.nodes, uz, modes.fn_hz)
    >>> len([ax for ax in fig.axes if ax.get_visible()]) >= 2
    True
    """
    xyz = np.asarray(nodes, dtype=float)
    u = np.asarray(uz, dtype=float)
    if xyz.ndim != 2 or xyz.shape[1] < 2:
        raise DimensionError(f"nodes must have shape (n_nodes, 3), got {xyz.shape}")
    if u.ndim == 1:
        u = u[:, None]
    if u.shape[0] != xyz.shape[0]:
        raise DimensionError(f"uz has {u.shape[0]} rows but there are {xyz.shape[0]} nodes")
    fn = np.atleast_1d(np.asarray(fn_hz, dtype=float))
    if fn.size != u.shape[1]:
        raise DimensionError(f"fn_hz has {fn.size} values but uz has {u.shape[1]} modes")
    if n_cols < 1:
        raise ParameterError(f"n_cols must be >= 1, got {n_cols}")
    from matplotlib.tri import Triangulation

    n_modes = u.shape[1]
    n_rows = int(np.ceil(n_modes / n_cols))
    from matplotlib.figure import Figure

    width, height = FIG_WIDTH, FIG_WIDTH / n_cols * 0.75 * n_rows
    fig = Figure(figsize=(width, height))
    # fixed margins (inches): small tick labels and axis labels, panel titles, and the
    # colorbar with its label on the right
    left, right, bottom, top, wgap, hgap = 0.6, 1.2, 0.45, 0.3, 0.6, 0.6
    ax_w = (width - left - right - wgap * (n_cols - 1)) / n_cols
    ax_h = (height - bottom - top - hgap * (n_rows - 1)) / n_rows
    fig.subplots_adjust(left=left / width, right=1 - right / width, bottom=bottom / height,
                        top=1 - top / height, wspace=wgap / ax_w, hspace=hgap / ax_h)
    from ._layout import nice_ticks

    tri = Triangulation(xyz[:, 0] * 1e3, xyz[:, 1] * 1e3)
    # the same ticks in every panel, given (about one per 0.5 in): the automatic
    # locator's ticks of every panel are most of this figure's render time
    xt = nice_ticks(*(tri.x.min(), tri.x.max()), max(2, int(ax_w / 0.5)))
    yt = nice_ticks(*(tri.y.min(), tri.y.max()), max(2, int(ax_h / 0.4)))
    for k in range(n_modes):
        ax = fig.add_subplot(n_rows, n_cols, k + 1)
        shape = u[:, k]
        peak = np.max(np.abs(shape))
        shape = shape / peak if peak > 0 else shape
        cs = ax.tricontourf(tri, shape, levels=np.linspace(-1, 1, 21), cmap="coolwarm")
        ax.tricontour(tri, shape, levels=[0.0], colors="k", linewidths=0.8)
        ax.set_aspect("equal")
        ax.set_title(f"mode {k + 1}: {fn[k]:.2f} Hz", fontsize=9, y=1.0)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.set_ylabel("y [mm]", fontsize=8)
        ax.set_xticks(xt, [f"{t:g}" for t in xt], fontsize=7)
        ax.set_yticks(yt, [f"{t:g}" for t in yt], fontsize=7)
    cax = fig.add_axes(((width - 0.95) / width, 0.1 + 0.8 * bottom / height, 0.2 / width,
                        0.8 * (1 - (top + bottom) / height)))
    fig.colorbar(cs, cax=cax, label="uz (normalised)")
    cax.set_yticks(np.linspace(-1.0, 1.0, 5),
                   [f"{t:.1f}".replace("-", "\u2212") for t in np.linspace(-1, 1, 5)])
    return fig


def plot_time_responses(
    t: Sequence[float],
    responses: Mapping[str, Sequence[float]],
    *,
    zoom: tuple[float, float] | None = None,
    ylabel: str = "tip displacement [m]",
    title: str = "",
):
    """Time histories of several runs (e.g. open loop and each controller) and a zoom.

    Parameters
    ----------
    t : array, shape (n,)
        Time in s.
    responses : mapping of label to array, shape (n,)
    zoom : (t_start, t_end), optional
        Time window of a second panel.

    Examples
    --------
    Open loop and controlled response, with a zoom on the first second:

    >>> t = np.arange(0.0, 5.0, 1e-3)
    >>> y = 1e-3 * np.exp(-0.5 * t) * np.cos(2 * np.pi * 12.0 * t)
    >>> fig = plot_time_responses(t, {"open loop": y, "PPF": y * np.exp(-2 * t)}, zoom=(0.0, 1.0))
    >>> len(fig.axes), [line.get_label() for line in fig.axes[0].get_lines()]
    (2, ['open loop', 'PPF'])
    """
    tt = _vec("t", t)
    if not responses:
        raise ParameterError("responses is empty; give at least one labelled time history")
    for name, y in responses.items():
        if np.asarray(y).shape != tt.shape:
            raise DimensionError(f"response {name!r} has shape {np.shape(y)}, t has {tt.shape}")
    fig = _figure(FIG_WIDTH, 6.0 if zoom else 4.0, n_rows=2 if zoom else 1,
                  title=bool(title))
    axes = [fig.add_subplot(2 if zoom else 1, 1, 1)]
    if zoom:
        axes.append(fig.add_subplot(2, 1, 2))
    for i, (name, y) in enumerate(responses.items()):
        yy = np.asarray(y, dtype=float)
        for j, ax in enumerate(axes):
            tx, yx = _crop(tt, [yy], zoom if j == 1 else None)
            tx, yx = minmax_decimate(tx, yx[0])
            ax.plot(tx, yx, lw=0.8, color=f"C{i}", label=name)
    for ax in axes:
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    if zoom:
        axes[1].set_xlim(*zoom)
        axes[1].set_title(f"zoom {zoom[0]:g}-{zoom[1]:g} s", fontsize=9, y=1.0)
    if title:
        axes[0].set_title(title, y=1.0)
    return fig


def plot_spectra(
    f_hz: Sequence[float],
    spectra: Mapping[str, Sequence[float]],
    *,
    f_range: tuple[float, float] | None = None,
    ylabel: str = "amplitude spectrum [m]",
    title: str = "",
):
    """Amplitude spectra of several runs (e.g. with and without control), log scale.

    Examples
    --------
    >>> f = np.linspace(1.0, 50.0, 500)                                   # Hz
    >>> h = 1 / np.abs(12.0**2 - f**2 + 0.3j * f)
    >>> fig = plot_spectra(f, {"open loop": h, "control": h / 2})
    >>> fig.axes[0].get_yscale()
    'log'
    """
    f = _vec("f_hz", f_hz)
    if not spectra:
        raise ParameterError("spectra is empty; give at least one labelled spectrum")
    fig = _figure(title=bool(title))
    ax = fig.add_subplot()
    for i, (name, s) in enumerate(spectra.items()):
        a = np.abs(np.asarray(s))
        if a.shape != f.shape:
            raise DimensionError(f"spectrum {name!r} has shape {a.shape}, f_hz has {f.shape}")
        fc, (ac,) = _crop(f, [a], f_range)
        fd, ad = minmax_decimate(fc, ac)
        ax.semilogy(fd, np.maximum(ad, np.finfo(float).tiny), lw=0.9, color=f"C{i}",
                    label=name)
    _plain_log_axis(ax.yaxis)
    if f_range is not None:
        ax.set_xlim(*f_range)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title, y=1.0)
    return fig
