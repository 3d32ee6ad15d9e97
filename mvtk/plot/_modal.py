"""Figures of experimental modal analysis: stabilisation diagram, FRF synthesis, AutoMAC,
damping against frequency with error bars."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ._figures import FIG_WIDTH, _plain_log_axis, _sparse_log_minor, minmax_decimate
from ._figures import _constrained_figure as _figure
from ._layout import axes_at, figure

__all__ = ["plot_stabilisation", "plot_frf_synthesis", "plot_automac", "plot_modal_uncertainty"]

_STYLE = {"s": ("C3", "o", "stable f, zeta, vector"), "v": ("C2", "^", "stable f, vector"),
          "d": ("C1", "s", "stable f, zeta"), "f": ("C0", "x", "stable f"),
          "o": ("0.6", ".", "new / unstable")}


#: Fixed layout of the stabilisation diagram in inches: left (tick labels and y label),
#: right (the indicator axis' tick labels and label), bottom, top (title).
STAB_LAYOUT = {"left": 0.7, "right": 0.75, "bottom": 0.55, "top": 0.4, "height": 4.5}


def plot_stabilisation(diagram, modes=None, *, title: str = ""):
    """Stabilisation diagram: poles per model order over the mode indicator.

    Parameters
    ----------
    diagram : mvtk.modal.StabilisationDiagram
    modes : mvtk.modal.IdentifiedModes, optional
        Selected modes, drawn as vertical lines.

    The indicator (CMIF singular values for pLSCF, singular values of the output PSD
    matrix for SSI-cov, in dB) is drawn on a second axis behind the poles.

    Examples
    --------
    The stabilisation diagram of the exact FRFs of a 2-mass chain (31.1 and 81.4 Hz):

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> fig = plot_stabilisation(modal.plscf(h, 2.0, 110.0, orders=range(2, 21)))
    >>> fig.axes[0].get_xlabel()
    'frequency [Hz]'
    """
    g = STAB_LAYOUT
    width, height = FIG_WIDTH, g["height"]
    fig = figure(width, height)
    ax = axes_at(fig, g["left"], g["bottom"], width - g["left"] - g["right"],
                 height - g["bottom"] - g["top"])
    ax2 = ax.twinx()
    ind = np.asarray(diagram.indicator)
    f_ind = np.asarray(diagram.indicator_f_hz, dtype=float)
    with np.errstate(divide="ignore"):
        for k, curve in enumerate(ind[:3]):
            fd, cd = minmax_decimate(f_ind, 20 * np.log10(np.abs(curve)))
            ax2.plot(fd, cd, lw=0.8, color="0.35" if k == 0 else "0.7", zorder=0)
    ax2.set_ylabel("CMIF [dB]" if diagram.method == "pLSCF" else "PSD singular values [dB]")
    from matplotlib.lines import Line2D

    fn = diagram.fn_hz
    handles = []
    for st in ("o", "f", "d", "v", "s"):
        sel = diagram.status == st
        if sel.any():
            c, m, lab = _STYLE[st]
            size = 12 if st == "s" else 8
            ax.scatter(fn[sel], diagram.order[sel], s=size, c=c, marker=m, label=lab,
                       zorder=3)
            # a marker-only line as the legend entry: the same symbol, and cheaper to
            # draw than the legend's copy of a scatter collection
            handles.append(Line2D([], [], ls="", marker=m, ms=np.sqrt(size), color=c,
                                  label=lab))
    if modes is not None:
        for f in modes.fn_hz:
            ax.axvline(f, color="k", lw=0.7, ls="--", zorder=2)
    ax.set_zorder(ax2.get_zorder() + 1)
    ax.patch.set_visible(False)
    ax.set_xlim(*diagram.band_hz)
    ax.yaxis.get_major_locator().set_params(integer=True)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.legend(handles=handles, loc="upper left", fontsize=7, ncol=3)
    ax.set_title(title or f"{diagram.method} stabilisation diagram", y=1.0)
    return fig


#: Fixed layout of the FRF synthesis figure in inches: left (log tick labels and y
#: label), right, bottom, the gap between the two panels (the upper panel's x tick
#: labels are hidden: the panels share the frequency axis), the title above and the
#: legend rows between the title and the upper panel.
SYNTH_LAYOUT = {"left": 0.85, "right": 0.2, "bottom": 0.55, "gap": 0.15, "title": 0.35,
                "legend_row": 0.17, "height": 5.0}


def plot_frf_synthesis(modes, responses=None, reference=0, *, max_curves: int = 4,
                       title: str = ""):
    """Measured vs synthesised FRF magnitude and phase for some responses.

    Solid lines are measured, dashed synthesised, one colour per response (legend above
    the plot, with each response's correlation); grey vertical lines mark the
    identified natural frequencies. Lines longer than two points per pixel column are
    drawn as their minimum and maximum per column (:func:`minmax_decimate`), which
    keeps every peak and phase jump.

    Parameters
    ----------
    modes : mvtk.modal.IdentifiedModes
        Result of :func:`mvtk.modal.identify` (with ``frf`` and ``synthesised``).
    responses : sequence of str or int, optional
        Response labels or positions (default: the first ``max_curves``).
    reference : str or int
        Reference label or position.

    Examples
    --------
    Measured (exact) and synthesised FRFs of the 2-mass chain, magnitude and phase:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> fig = plot_frf_synthesis(modal.identify(h, 2.0, 110.0, refine=False))
    >>> len(fig.axes)
    2
    """
    from matplotlib.lines import Line2D

    if modes.frf is None or modes.synthesised is None:
        raise ParameterError("plot_frf_synthesis: these modes have no FRFs (output-only)")
    h, s = modes.frf, modes.synthesised
    names = [str(r) for r in h["response"].values]
    refs = [str(r) for r in h["reference"].values]
    j = reference if isinstance(reference, int) else refs.index(str(reference))
    if responses is None:
        idx = list(range(min(max_curves, len(names))))
    else:
        idx = [r if isinstance(r, int) else names.index(str(r)) for r in responses]
    f = np.asarray(h["frequency"].values, dtype=float)
    g = SYNTH_LAYOUT
    width, height = FIG_WIDTH, g["height"]
    n_entries = len(idx) + 2
    n_cols = 3
    top = g["title"] + g["legend_row"] * -(-n_entries // n_cols) + 0.05
    pw = width - g["left"] - g["right"]
    ph = (height - top - g["bottom"] - g["gap"]) / 2
    fig = figure(width, height)
    a2 = axes_at(fig, g["left"], g["bottom"], pw, ph)
    a1 = axes_at(fig, g["left"], g["bottom"] + ph + g["gap"], pw, ph, sharex=a2)
    n_bins = int(pw * fig.dpi)  # one bin per pixel column at the figure's dpi
    handles = []
    for k, i in enumerate(idx):
        c = f"C{k % 10}"
        corr = float(modes.correlation.values[i])
        handles.append(Line2D([], [], color=c, lw=1.0, label=f"{names[i]} (corr {corr:.3f})"))
        for data, ls in ((h.values[i, j], "-"), (s.values[i, j], "--")):
            a1.semilogy(*minmax_decimate(f, np.abs(data), n_bins), color=c, lw=1.0, ls=ls)
            a2.plot(*minmax_decimate(f, np.degrees(np.angle(data)), n_bins), color=c, lw=0.8,
                    ls=ls)
    handles += [Line2D([], [], color="k", lw=1.0, label="measured"),
                Line2D([], [], color="k", lw=1.0, ls="--", label="synthesised")]
    _plain_log_axis(a1.yaxis)
    _sparse_log_minor(a1)
    for fn in modes.fn_hz:
        a1.axvline(fn, color="0.6", lw=0.5)
    a1.tick_params(labelbottom=False)
    a1.set_xlim(f[0], f[-1])
    a1.set_ylabel("|H|")
    a2.set_ylabel("phase [deg]")
    a2.set_ylim(-200.0, 200.0)
    a2.set_yticks([-180, -90, 0, 90, 180])
    a2.set_xlabel("frequency [Hz]")
    a1.legend(handles=handles, fontsize=7, ncol=n_cols, loc="lower center",
              bbox_to_anchor=(0.5, 1.0), frameon=False)
    a1.set_title(title or f"measured vs synthesised FRFs, reference {refs[j]} (overall "
                 f"correlation {modes.correlation.attrs['overall']:.3f})", fontsize=10,
                 y=1.0 + (top - g["title"]) / ph)
    return fig


def plot_automac(modes, *, real: bool = False, title: str = ""):
    """AutoMAC matrix of the identified shapes with the values written in the cells.

    Examples
    --------
    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> fig = plot_automac(modal.identify(h, 2.0, 110.0, refine=False))
    >>> len(fig.axes)
    2
    """
    m = modes.automac(real=real).values
    fig = _figure(5.0, 4.2)
    ax = fig.add_subplot()
    im = ax.imshow(m, vmin=0, vmax=1, cmap="viridis", origin="lower")
    n = m.shape[0]
    labels = [f"{f:.4g}" for f in modes.fn_hz]
    ax.set_xticks(range(n), labels, rotation=90, fontsize=7)
    ax.set_yticks(range(n), labels, fontsize=7)
    if n <= 15:
        for i in range(n):
            for k in range(n):
                ax.text(k, i, f"{m[i, k]:.2f}", ha="center", va="center", fontsize=6,
                        color="w" if m[i, k] < 0.5 else "k")
    fig.colorbar(im, ax=ax, label="MAC")
    ax.set_xlabel("mode [Hz]")
    ax.set_ylabel("mode [Hz]")
    ax.set_title(title or "AutoMAC")
    return fig


def plot_modal_uncertainty(modes, *, k: float = 2.0, title: str = ""):
    """Damping against frequency of the identified modes with their error bars.

    Each mode is a point at ``(fn_hz, 100 zeta)`` with bars of ``+-k`` standard
    deviations (``fn_std_hz`` horizontally, ``zeta_std`` vertically; default ``k = 2``,
    about a 95 % interval); reliable modes are filled, the others hollow. Modes without
    a standard deviation (NaN) have no bar. Where a bar is smaller than the marker the
    parameter is known better than the figure can show (read the table).

    Parameters
    ----------
    modes : IdentifiedModes
        Result of :func:`mvtk.modal.identify` or :func:`mvtk.modal.identify_output_only`.
    k : float
        Coverage factor of the bars, in standard deviations (> 0).
    title : str
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> fig = plot_modal_uncertainty(modal.identify(h, 2.0, 110.0))
    >>> fig.axes[0].get_ylabel()
    'damping ratio zeta [%]'
    """
    if not (np.isfinite(k) and k > 0):
        raise ParameterError(f"k must be a coverage factor > 0, got {k!r}")
    fn = np.asarray(modes.fn_hz, dtype=float)
    zeta = np.asarray(modes.zeta, dtype=float)
    n = fn.size
    fstd = np.asarray(modes.fn_std_hz if modes.fn_std_hz is not None else np.full(n, np.nan),
                      dtype=float)
    zstd = np.asarray(modes.zeta_std if modes.zeta_std is not None else np.full(n, np.nan),
                      dtype=float)
    reliable = np.asarray(modes.reliable, dtype=bool)
    fig = _figure(FIG_WIDTH, 3.6)
    ax = fig.add_subplot()
    for ok, face, label in ((True, "C0", "reliable"), (False, "none", "not reliable")):
        sel = reliable == ok
        if not sel.any():
            continue
        ax.errorbar(fn[sel], 100 * zeta[sel],
                    xerr=np.nan_to_num(k * fstd[sel]), yerr=np.nan_to_num(k * 100 * zstd[sel]),
                    fmt="o", color="C0", mfc=face, ms=5, capsize=3, lw=1,
                    label=f"{label} (bars +-{k:g} std)")
    for f, z in zip(fn, zeta):
        ax.annotate(f"{f:.4g}", (f, 100 * z), textcoords="offset points", xytext=(4, 4),
                    fontsize=8)
    ax.set_xlabel("frequency fn [Hz]")
    ax.set_ylabel("damping ratio zeta [%]")
    ax.set_ylim(bottom=0)
    if n:
        ax.legend(fontsize=8, loc="best")
    ax.grid(True, alpha=0.3)
    ax.set_title(title or "Identified modes with uncertainty")
    return fig
