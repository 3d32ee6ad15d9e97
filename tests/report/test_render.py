"""Fast report figures: decimation, fixed layouts, rendering in forked processes."""

import multiprocessing as mp
import os
import signal
import subprocess
import sys
import textwrap
import time
from functools import partial

import numpy as np
import pytest

from mvtk.plot import (
    minmax_decimate,
    plot_decay,
    plot_fn_histogram,
    plot_frf,
    plot_mode_shapes,
    plot_spectra,
    plot_time_responses,
)
from mvtk.report import Report
from mvtk.report._render import FigureRenderer, render_figure

needs_fork = pytest.mark.skipif("fork" not in mp.get_all_start_methods(),
                                reason="no fork start method on this platform")


def _reference_decimate(x, y, n_bins):
    """Per-bin loop: first index of the min and of the max of each bin (the definition)."""
    edges = np.searchsorted(x, np.linspace(x[0], x[-1], n_bins + 1)[1:-1])
    keep = []
    for a, b in zip(np.r_[0, edges], np.r_[edges, x.size]):
        if b <= a:
            continue
        seg = np.where(np.isfinite(y[a:b]), y[a:b], np.nan)
        if np.all(np.isnan(seg)):
            keep.append(a)
        else:
            keep += [a + int(np.nanargmin(seg)), a + int(np.nanargmax(seg))]
    idx = np.unique(keep)
    return x[idx], y[idx]


def test_minmax_decimate_equals_the_per_bin_definition():
    rng = np.random.default_rng(7)
    x = np.sort(rng.uniform(0.0, 10.0, 50_000))          # non-uniform abscissa
    y = rng.standard_normal(x.size)
    y[1000:1400] = np.nan                                   # whole bins of NaN
    y[5000] = np.inf
    y[7000] = -np.inf
    y[20_000:20_010] = 3.0                                  # ties: first index kept
    for n_bins in (1, 7, 500, 1000):
        xd, yd = minmax_decimate(x, y, n_bins=n_bins)
        xr, yr = _reference_decimate(x, y, n_bins)
        np.testing.assert_array_equal(xd, xr)
        np.testing.assert_array_equal(yd, yr)
    # the envelope of the full line is kept exactly: the finite extremes survive
    xd, yd = minmax_decimate(x, y, n_bins=500)
    assert np.nanmax(yd[np.isfinite(yd)]) == np.nanmax(y[np.isfinite(y)])
    assert np.nanmin(yd[np.isfinite(yd)]) == np.nanmin(y[np.isfinite(y)])


def _texts_inside(fig):
    """Everything drawn (tick labels, axis labels, titles, legends, colorbar) inside the
    figure, and no two panels overlapping."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = fig.bbox
    drawn = [(ax, ax.get_tightbbox(r)) for ax in fig.axes]
    drawn += [(t, t.get_window_extent(r)) for t in fig.texts if t.get_text().strip()]
    if fig._suptitle is not None and fig._suptitle.get_text():
        drawn.append((fig._suptitle, fig._suptitle.get_window_extent(r)))
    bad = [str(a) for a, e in drawn
           if e.x0 < box.x0 - 1 or e.x1 > box.x1 + 1 or e.y0 < box.y0 - 1
           or e.y1 > box.y1 + 1]
    assert not bad, f"drawn outside the figure: {bad}"
    # titles are placed explicitly at the top of their axes: where matplotlib's own
    # title placement (which avoids top tick labels and y offset texts) puts them too
    placed = [ax.title.get_window_extent(r) for ax in fig.axes]
    for ax in fig.axes:
        ax._autotitlepos = True
    fig.canvas.draw()
    auto = [ax.title.get_window_extent(fig.canvas.get_renderer()) for ax in fig.axes]
    for p, a in zip(placed, auto):
        assert abs(p.y0 - a.y0) < 0.5 and abs(p.x0 - a.x0) < 0.5, (p, a)
    panels = [ax.get_tightbbox(r) for ax in fig.axes]
    for i in range(len(panels)):
        for j in range(i + 1, len(panels)):
            inter = panels[i].intersection(panels[i], panels[j])
            area = 0.0 if inter is None else inter.width * inter.height
            # a colorbar may touch its panel's box; labels must not overlap
            assert area < 0.02 * min(panels[i].width * panels[i].height,
                                     panels[j].width * panels[j].height), (i, j)


def test_fixed_layouts_keep_every_label_inside_the_figure():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    f = np.linspace(0.0, 400.0, 40_001)
    h = 1e4 / np.abs(1 - (f / 13.3) ** 2 + 0.002j * f / 13.3) + 1e-6
    t = np.arange(150 * 128) / 128.0
    x = -2e-3 * np.exp(-0.0487 * t) * np.sin(2 * np.pi * 13.26 * t)
    xs, ys = np.meshgrid(np.linspace(0, 0.18, 13), np.linspace(0, 0.135, 10))
    nodes = np.c_[xs.ravel(), ys.ravel(), 0 * xs.ravel()]
    uz = np.c_[xs.ravel() ** 2, xs.ravel() * (ys.ravel() - 0.0675),
               np.sin(20 * xs.ravel()), np.cos(30 * xs.ravel()) * ys.ravel()]
    fn = np.random.default_rng(3).normal([13.3, 41.0, 78.5, 138.5], 0.3, (40, 4))
    figs = [
        plot_frf(f, h, bands=[(13.2, 13.4, 13.3)], ylabel="|H| [m/s^2/N]",
                 title="Impact FRF (H1) with half-power bands"),
        plot_frf(f, h, f_range=(12.5, 14.0), markers=True, ylabel="|H|"),
        plot_decay(t, x, fit=2e-3 * np.exp(-0.0487 * t), ylabel="tip displacement [m]",
                   title="Free decay"),
        plot_time_responses(t, {"open loop": x, "PPF": 0.1 * x}, zoom=(0.0, 1.0),
                            title="Tip displacement"),
        # micrometre amplitudes: the y axes carry an offset text ("1e-6") at the top
        plot_time_responses(t, {"open loop": 1e-3 * x}, zoom=(0.0, 1.0),
                            title="Tip displacement with and without control"),
        plot_spectra(f, {"open loop": h * 1e-9, "PPF": h * 1e-10}, f_range=(0, 60),
                     title="Amplitude spectra"),
        plot_mode_shapes(nodes, uz, [14.25, 42.18, 83.55, 143.3]),
        plot_fn_histogram(type("MC", (), {"fn_hz": fn})(), bins=12),
    ]
    for fig in figs:
        if fig.canvas is None or not hasattr(fig.canvas, "get_renderer"):
            FigureCanvasAgg(fig)
        _texts_inside(fig)


def _page(workers, tmp_path, figs):
    rep = Report("render test", workers=workers)
    sec = rep.section("Figures")
    for i, fig in enumerate(figs):
        sec.figure(fig, f"figure {i}")
    sec.figure(render_figure(figs[1], "png")[1], "bytes")
    return rep.to_html()


def _figures():
    f = np.linspace(1.0, 400.0, 5000)
    h = 1 / np.abs(1 - (f / 80) ** 2 + 0.01j * f / 80)
    t = np.linspace(0, 6, 6001)
    return [partial(plot_frf, f, h, bands=[(79, 81, 80)], title="FRF"),
            plot_decay(t, np.exp(-t) * np.sin(40 * t), fit=np.exp(-t), title="decay"),
            plot_spectra(f, {"a": h, "b": 2 * h}, title="spectra"),
            plot_time_responses(t, {"a": np.sin(9 * t)}, zoom=(0, 1))]


@needs_fork
def test_parallel_render_gives_the_same_page_as_serial(tmp_path):
    serial = _page(0, tmp_path, _figures())
    parallel = _page(2, tmp_path, _figures())
    three = _page(3, tmp_path, _figures())
    assert serial.count("<img") == 5
    assert parallel == serial and three == serial   # same bytes, same order
    assert not mp.active_children()


class _Broken:
    """Stands in for a figure whose rendering fails (in any process)."""

    axes = ()

    def savefig(self, *a, **k):
        raise ValueError("cannot draw this figure")

    def get_layout_engine(self):
        return None

    images = ()


@needs_fork
def test_a_failing_figure_raises_its_own_error_in_the_main_process():
    rep = Report("x", workers=2)
    sec = rep.section("s")
    sec.figure(_figures()[0], "ok")
    sec.figure(_Broken(), "broken", image_format="png")
    with pytest.raises(ValueError, match="cannot draw this figure"):
        rep.to_html()
    assert not mp.active_children()


class _Slow:
    """A figure that takes ``delay`` s to render in the processes named."""

    images = ()

    def __init__(self, delay_main, delay_child, main_pid):
        self.delay_main, self.delay_child, self.main_pid = delay_main, delay_child, main_pid
        self.axes = ()

    def get_layout_engine(self):
        return None

    def savefig(self, buf, **k):
        time.sleep(self.delay_main if os.getpid() == self.main_pid else self.delay_child)
        buf.write(b"\x89PNG\r\n\x1a\n" + b"0" * 10)


@needs_fork
def test_interrupt_while_waiting_ends_the_render_processes():
    pid = os.getpid()
    r = FigureRenderer(2)
    r.submit(_Slow(1.0, 0.0, pid), "png")
    r.submit(_Slow(0.0, 60.0, pid), "png")

    def _interrupt(*_):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, _interrupt)
    signal.alarm(3)
    t0 = time.perf_counter()
    try:
        with pytest.raises(KeyboardInterrupt):
            r.wait()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    assert time.perf_counter() - t0 < 30
    assert not mp.active_children()


@needs_fork
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux")
def test_render_processes_die_with_a_killed_parent(tmp_path):
    # the parent is SIGKILLed while a child renders: the child must not be left behind
    script = textwrap.dedent("""
        import multiprocessing as mp, os, signal, sys, threading, time
        sys.path.insert(0, %r)
        from test_render import _Slow
        from mvtk.report._render import FigureRenderer

        pid = os.getpid()
        r = FigureRenderer(2)
        r.submit(_Slow(1.0, 0.0, pid), "png")
        r.submit(_Slow(0.0, 120.0, pid), "png")

        def report_and_die():
            time.sleep(2.0)
            print(" ".join(str(p.pid) for p in mp.active_children()), flush=True)
            os.kill(pid, signal.SIGKILL)

        threading.Thread(target=report_and_die, daemon=True).start()
        r.wait()
    """) % os.path.dirname(__file__)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=60)
    pids = [int(p) for p in out.stdout.split()]
    assert pids, out.stderr
    deadline = time.time() + 10
    alive = pids
    while alive and time.time() < deadline:
        alive = [p for p in pids if _alive(p)]
        time.sleep(0.1)
    assert not alive


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.parametrize("ylim", [(1e-6, 1e4), (1.3e3, 1.4e4), (2.1e3, 3.9e3), (0.2, 0.9)])
def test_log_axis_labels_are_matplotlibs_typeset_without_mathtext(ylim):
    # the same ticks carry the same labels as matplotlib's own log formatter (external
    # truth), written as Unicode text instead of mathtext
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from mvtk.plot._figures import _plain_log_axis

    def labels(plain):
        fig = Figure(figsize=(7, 4))
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        ax.semilogy([1, 2], ylim)
        if plain:
            _plain_log_axis(ax.yaxis)
        ax.set_ylim(*ylim)
        fig.canvas.draw()
        return [t.get_text() for t in ax.yaxis.get_ticklabels(which="both")]

    stock, plain = labels(False), labels(True)
    assert any(stock) and len(stock) == len(plain)
    sup = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
    for s, p in zip(stock, plain):
        assert "$" not in p
        want = s.replace(r"$\mathdefault{", "").replace("}$", "").replace(r"\times", "×")
        want = want.replace("^{", "").replace("}", "")
        assert p.translate(sup) == want, (s, p)
