"""Figures of the validation workflow (matplotlib, Agg; never pyplot).

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot, so no
GUI backend is touched and nothing is kept in a global figure registry. Convert with
:func:`figure_to_png` or pass the figure to :meth:`mvtk.report.Section.figure`.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import DimensionError, ParameterError

__all__ = [
    "figure_to_png",
    "plot_frf",
    "plot_decay",
    "plot_mode_shapes",
    "plot_time_responses",
    "plot_spectra",
]


def _figure(width: float = 7.0, height: float = 4.0):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def figure_to_png(fig: Any, dpi: int = 100) -> bytes:
    """PNG bytes of a matplotlib figure."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
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
):
    """FRF magnitude (log) with half-power bands marked.

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
    """
    f = _vec("f_hz", f_hz)
    h = np.abs(_vec("H", H))
    if h.shape != f.shape:
        raise DimensionError(f"H has {h.size} values but f_hz has {f.size}")
    fig = _figure()
    ax = fig.add_subplot()
    ax.semilogy(f, h, lw=1.0, color="C0", label="FRF", marker="o" if markers else None,
                ms=3)
    for i, (lo, hi, fn) in enumerate(bands):
        ax.axvspan(lo, hi, color="C3", alpha=0.25, label="half-power band" if i == 0 else None)
        ax.axvline(fn, color="C3", lw=0.8, ls="--")
        ax.annotate(f"{fn:.3f} Hz", (fn, 1.0), xycoords=("data", "axes fraction"),
                    ha="left", va="top", fontsize=8, color="C3")
    if f_range is not None:
        ax.set_xlim(*f_range)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    if title:
        ax.set_title(title)
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
):
    """Free decay with its envelope and the fitted exponential envelope.

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
    """
    tt = _vec("t", t)
    xx = _vec("x", x)
    if xx.shape != tt.shape:
        raise DimensionError(f"x has {xx.size} values but t has {tt.size}")
    fig = _figure()
    ax = fig.add_subplot()
    ax.plot(tt, xx, lw=0.4, color="0.5", label="signal")
    if envelope is not None:
        ax.plot(tt, np.asarray(envelope), lw=1.0, color="C0", label="envelope")
    if fit is not None:
        ff = np.asarray(fit)
        ax.plot(tt, ff, lw=1.5, color="C3", ls="--", label=label_fit)
        ax.plot(tt, -ff, lw=1.5, color="C3", ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title)
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
    fig = _figure(3.6 * n_cols, 2.6 * n_rows)
    tri = Triangulation(xyz[:, 0] * 1e3, xyz[:, 1] * 1e3)
    for k in range(n_modes):
        ax = fig.add_subplot(n_rows, n_cols, k + 1)
        shape = u[:, k]
        peak = np.max(np.abs(shape))
        shape = shape / peak if peak > 0 else shape
        cs = ax.tricontourf(tri, shape, levels=np.linspace(-1, 1, 21), cmap="coolwarm")
        ax.tricontour(tri, shape, levels=[0.0], colors="k", linewidths=0.8)
        ax.set_aspect("equal")
        ax.set_title(f"mode {k + 1}: {fn[k]:.2f} Hz", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.set_ylabel("y [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.colorbar(cs, ax=fig.axes, shrink=0.8, label="uz (normalised)")
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
    """
    tt = _vec("t", t)
    if not responses:
        raise ParameterError("responses is empty; give at least one labelled time history")
    for name, y in responses.items():
        if np.asarray(y).shape != tt.shape:
            raise DimensionError(f"response {name!r} has shape {np.shape(y)}, t has {tt.shape}")
    fig = _figure(7.0, 6.0 if zoom else 3.8)
    axes = [fig.add_subplot(2 if zoom else 1, 1, 1)]
    if zoom:
        axes.append(fig.add_subplot(2, 1, 2))
    for i, (name, y) in enumerate(responses.items()):
        for ax in axes:
            ax.plot(tt, np.asarray(y), lw=0.8, color=f"C{i}", label=name)
    for ax in axes:
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    if zoom:
        axes[1].set_xlim(*zoom)
        axes[1].set_title(f"zoom {zoom[0]:g}-{zoom[1]:g} s", fontsize=9)
    if title:
        axes[0].set_title(title)
    return fig


def plot_spectra(
    f_hz: Sequence[float],
    spectra: Mapping[str, Sequence[float]],
    *,
    f_range: tuple[float, float] | None = None,
    ylabel: str = "amplitude spectrum [m]",
    title: str = "",
):
    """Amplitude spectra of several runs (e.g. with and without control), log scale."""
    f = _vec("f_hz", f_hz)
    if not spectra:
        raise ParameterError("spectra is empty; give at least one labelled spectrum")
    fig = _figure()
    ax = fig.add_subplot()
    for i, (name, s) in enumerate(spectra.items()):
        a = np.abs(np.asarray(s))
        if a.shape != f.shape:
            raise DimensionError(f"spectrum {name!r} has shape {a.shape}, f_hz has {f.shape}")
        ax.semilogy(f, np.maximum(a, np.finfo(float).tiny), lw=0.9, color=f"C{i}", label=name)
    if f_range is not None:
        ax.set_xlim(*f_range)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title)
    return fig
