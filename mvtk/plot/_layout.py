"""Fixed figure layouts in inches (no constrained layout, no automatic tick placement).

A figure laid out by matplotlib's constrained layout is drawn twice when saved (once to
measure every text, once to render) and each measuring pass lays out every tick label;
for a grid of a dozen panels that is most of the save time. The helpers here place each
axes at a position computed from the figure size and give the axes their ticks, so a
save is one draw. ``tests/plot`` checks that every text stays inside its figure and no
two panels overlap.
"""

from __future__ import annotations

import numpy as np

#: Height in inches of one line of text at ``fontsize`` points (with leading).
LINE = 1.25 / 72.0


def text_height(fontsize: float, lines: int = 1) -> float:
    """Height in inches of ``lines`` lines of text of ``fontsize`` points."""
    return LINE * fontsize * lines


def figure(width: float, height: float):
    """An Agg-backed figure of ``width`` x ``height`` inches without a layout engine."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def axes_at(fig, left: float, bottom: float, width: float, height: float, **kwargs):
    """Add an axes whose box is ``left, bottom, width, height`` inches in ``fig``."""
    w, h = fig.get_size_inches()
    return fig.add_axes((left / w, bottom / h, width / w, height / h), **kwargs)


def nice_ticks(lo: float, hi: float, n: int = 5) -> np.ndarray:
    """Round tick values inside ``[lo, hi]`` (matplotlib's MaxNLocator, at most ``n`` + 1).

    Given to an axis explicitly, they spare the locator a computation at every draw of
    every shared panel.
    """
    from matplotlib.ticker import MaxNLocator

    t = MaxNLocator(nbins=n, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi)
    span = hi - lo
    return t[(t >= lo - 1e-9 * span) & (t <= hi + 1e-9 * span)]


def equal_limits(x: np.ndarray, y: np.ndarray, *, pad: float = 0.08,
                 aspect_range: tuple[float, float] = (0.35, 1.2)):
    """Axis limits around points for an equal-scale x-y view, and the box aspect h/w.

    The limits are the points' extent padded by ``pad`` of the larger span on each side;
    when the height/width ratio of that extent falls outside ``aspect_range``, the
    shorter direction is widened (centred) so the box keeps a usable shape. Drawing the
    limits in a box of the returned aspect gives equal scales without matplotlib's
    aspect adjustment.

    Returns
    -------
    (x0, x1), (y0, y1), aspect
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    x0, x1 = float(np.nanmin(x)), float(np.nanmax(x))
    y0, y1 = float(np.nanmin(y)), float(np.nanmax(y))
    span = max(x1 - x0, y1 - y0) or 1.0
    x0, x1, y0, y1 = x0 - pad * span, x1 + pad * span, y0 - pad * span, y1 + pad * span
    dx, dy = x1 - x0, y1 - y0
    aspect = dy / dx
    lo, hi = aspect_range
    if aspect < lo:
        grow = (lo * dx - dy) / 2
        y0, y1, aspect = y0 - grow, y1 + grow, lo
    elif aspect > hi:
        grow = (dy / hi - dx) / 2
        x0, x1, aspect = x0 - grow, x1 + grow, hi
    return (x0, x1), (y0, y1), aspect
