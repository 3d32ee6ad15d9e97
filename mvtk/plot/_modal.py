"""Figures of experimental modal analysis: stabilisation diagram, FRF synthesis, AutoMAC."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ._figures import _constrained_figure as _figure

__all__ = ["plot_stabilisation", "plot_frf_synthesis", "plot_automac"]

_STYLE = {"s": ("C3", "o", "stable f, zeta, vector"), "v": ("C2", "^", "stable f, vector"),
          "d": ("C1", "s", "stable f, zeta"), "f": ("C0", "x", "stable f"),
          "o": ("0.6", ".", "new / unstable")}


def plot_stabilisation(diagram, modes=None, *, title: str = ""):
    """Stabilisation diagram: poles per model order over the mode indicator.

    Parameters
    ----------
    diagram : mvtk.modal.StabilisationDiagram
    modes : mvtk.modal.IdentifiedModes, optional
        Selected modes, drawn as vertical lines.

    The indicator (CMIF singular values for pLSCF, singular values of the output PSD
    matrix for SSI-cov, in dB) is drawn on a second axis behind the poles.
    """
    fig = _figure(8.0, 4.5)
    ax = fig.add_subplot()
    ax2 = ax.twinx()
    ind = np.asarray(diagram.indicator)
    with np.errstate(divide="ignore"):
        for k, curve in enumerate(ind[:3]):
            ax2.plot(diagram.indicator_f_hz, 20 * np.log10(np.abs(curve)), lw=0.8,
                     color="0.35" if k == 0 else "0.7", zorder=0)
    ax2.set_ylabel("CMIF [dB]" if diagram.method == "pLSCF" else "PSD singular values [dB]")
    fn = diagram.fn_hz
    for st in ("o", "f", "d", "v", "s"):
        sel = diagram.status == st
        if sel.any():
            c, m, lab = _STYLE[st]
            ax.scatter(fn[sel], diagram.order[sel], s=12 if st == "s" else 8, c=c, marker=m,
                       label=lab, zorder=3)
    if modes is not None:
        for f in modes.fn_hz:
            ax.axvline(f, color="k", lw=0.7, ls="--", zorder=2)
    ax.set_zorder(ax2.get_zorder() + 1)
    ax.patch.set_visible(False)
    ax.set_xlim(*diagram.band_hz)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.legend(loc="upper left", fontsize=7, ncol=3)
    ax.set_title(title or f"{diagram.method} stabilisation diagram")
    return fig


def plot_frf_synthesis(modes, responses=None, reference=0, *, max_curves: int = 4,
                       title: str = ""):
    """Measured vs synthesised FRF magnitude and phase for some responses.

    Parameters
    ----------
    modes : mvtk.modal.IdentifiedModes
        Result of :func:`mvtk.modal.identify` (with ``frf`` and ``synthesised``).
    responses : sequence of str or int, optional
        Response labels or positions (default: the first ``max_curves``).
    reference : str or int
        Reference label or position.
    """
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
    f = h["frequency"].values
    fig = _figure(8.0, 5.0)
    a1 = fig.add_subplot(2, 1, 1)
    a2 = fig.add_subplot(2, 1, 2, sharex=a1)
    for k, i in enumerate(idx):
        c = f"C{k % 10}"
        corr = float(modes.correlation.values[i])
        a1.semilogy(f, np.abs(h.values[i, j]), color=c, lw=1.0,
                    label=f"{names[i]} (corr {corr:.3f})")
        a1.semilogy(f, np.abs(s.values[i, j]), color=c, lw=1.0, ls="--")
        a2.plot(f, np.degrees(np.angle(h.values[i, j])), color=c, lw=0.8)
        a2.plot(f, np.degrees(np.angle(s.values[i, j])), color=c, lw=0.8, ls="--")
    for fn in modes.fn_hz:
        a1.axvline(fn, color="0.6", lw=0.5)
    a1.set_ylabel("|H|  (solid measured, dashed synthesised)")
    a2.set_ylabel("phase [deg]")
    a2.set_xlabel("frequency [Hz]")
    a1.legend(fontsize=7)
    a1.set_title(title or f"measured vs synthesised FRFs, reference {refs[j]} (overall "
                 f"correlation {modes.correlation.attrs['overall']:.3f})")
    return fig


def plot_automac(modes, *, real: bool = False, title: str = ""):
    """AutoMAC matrix of the identified shapes with the values written in the cells."""
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
