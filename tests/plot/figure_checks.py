"""Readability checks of a drawn figure: texts inside it, not on each other, panels apart."""

from __future__ import annotations


def drawn_texts(fig):
    """(text, window extent) of every visible, non-empty text of a drawn figure.

    Tick labels of ticks outside their axis' view limits are left out (matplotlib
    keeps them but does not draw them).
    """
    from matplotlib.text import Text

    hidden = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            tol = 1e-9 * (hi - lo)
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not lo - tol <= tick.get_loc() <= hi + tol:
                    hidden |= {id(tick.label1), id(tick.label2)}
    r = fig.canvas.get_renderer()
    out = []
    for t in fig.findobj(Text):
        if not t.get_visible() or not t.get_text().strip() or id(t) in hidden:
            continue
        if t.axes is not None and not t.axes.get_visible():
            continue
        out.append((t, t.get_window_extent(r)))
    return out


def assert_readable(fig, *, overlap_px: float = 1.0):
    """Every text inside the figure, no two texts overlapping, no two panels overlapping.

    Parameters
    ----------
    fig : matplotlib Figure (given an Agg canvas if it has none)
    overlap_px : float
        Overlap tolerated between two text boxes in pixels (antialiasing).
    """
    if not hasattr(fig.canvas, "get_renderer"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = fig.bbox
    texts = drawn_texts(fig)
    outside = [t.get_text() for t, e in texts
               if e.x0 < box.x0 - 1 or e.x1 > box.x1 + 1 or e.y0 < box.y0 - 1
               or e.y1 > box.y1 + 1]
    assert not outside, f"drawn outside the figure: {outside}"
    for i in range(len(texts)):
        for j in range(i + 1, len(texts)):
            a, b = texts[i][1], texts[j][1]
            w = min(a.x1, b.x1) - max(a.x0, b.x0)
            h = min(a.y1, b.y1) - max(a.y0, b.y0)
            assert w <= overlap_px or h <= overlap_px, (
                f"texts overlap: {texts[i][0].get_text()!r} and {texts[j][0].get_text()!r}")
    axes = [ax for ax in fig.axes if ax.get_visible()]
    panels = [ax.get_tightbbox(r) for ax in axes]
    for i in range(len(panels)):
        for j in range(i + 1, len(panels)):
            if axes[i].get_position().bounds == axes[j].get_position().bounds:
                continue  # a twin axis (second y scale) of the same panel
            inter = panels[i].intersection(panels[i], panels[j])
            area = 0.0 if inter is None else inter.width * inter.height
            assert area < 0.02 * min(panels[i].width * panels[i].height,
                                     panels[j].width * panels[j].height), (i, j)
