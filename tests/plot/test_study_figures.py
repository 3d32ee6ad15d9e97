"""Content of the study's modal and correlation figures (fixed layouts, no layout engine).

Each figure is checked for what it shows (panels, lines, points, labels, legend
entries, values written) against the data it was given, and for readability (every
text inside the figure and on no other text, panels apart): see ``figure_checks``.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
import xarray as xr
from figure_checks import assert_readable, drawn_texts

from mvtk import correlation as co
from mvtk import modal
from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
from mvtk.plot import (
    figure_to_png,
    plot_frf_synthesis,
    plot_mac,
    plot_paired_shapes,
    plot_stabilisation,
    plot_test_on_mesh,
)

STEEL = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)


@pytest.fixture(scope="module")
def plate():
    """Clamped 0.3 x 0.2 m steel plate (12 x 8 MITC4), a 5 x 4 grid of +z sensors and
    'test' shapes: the FE shapes at the sensors with 2 % noise, modes 2 and 4 of the
    test sign-flipped (the figure must match the FE sign to the test)."""
    model = plate_model(0.3, 0.2, [Ply(STEEL, 2e-3)], nx=12, ny=8, clamp="x0")
    fe_modes = modal_analysis(model, 10)
    pts = np.array([[x, y, 0.0] for x in np.linspace(0.05, 0.3, 5)
                    for y in np.linspace(0.01, 0.19, 4)])
    geo = co.TestGeometry(np.arange(1, 21), pts).with_sensors(
        [(n, "+z") for n in range(1, 21)])
    res = co.correlate(geo, model, fe_modes)
    fe = res.fe
    noise = 1 + 0.02 * np.random.default_rng(0).normal(size=(6, fe.sizes["dof"]))
    sign = np.array([1, -1, 1, -1, 1, 1])[:, None]
    test = fe.isel(mode=slice(0, 6)).copy(data=fe.values[:6] * noise * sign)
    pairing = co.pair_modes(test, fe)
    return model, geo, test, fe, pairing, res.mapping


@pytest.fixture(scope="module")
def identified():
    """pLSCF of the exact FRFs of a 4-mass chain (4 modes in 2-115 Hz)."""
    n, k = 4, 1e5
    M = np.eye(n)
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += 2 * k if i < n - 1 else k
        if i > 0:
            K[i, i - 1] = K[i - 1, i] = -k
    f = np.arange(0, 120, 0.2)
    h = modal.exact_frf(M, 0.5 * M + 1e-5 * K, K, f, range(n), [0, 2],
                        frf_type="accelerance")
    return modal.identify(h, 2, 115)


def _titles(fig):
    return [ax.get_title() for ax in fig.axes]


def _panels(fig, n_panels, n_nodes):
    """Per panel of a paired-shapes figure: its node positions (relative to the panel
    frame's lower-left corner, mm), its values and its frame (x0, y0, x1, y1)."""
    ax = fig.axes[0]
    sc = ax.collections[-1]
    pts, vals = sc.get_offsets(), np.asarray(sc.get_array())
    assert len(pts) == n_panels * n_nodes
    frames = [seg for seg in ax.collections[0].get_segments()]
    assert len(frames) == n_panels
    out = []
    for k, fr in enumerate(frames):
        lo, hi = fr.min(axis=0), fr.max(axis=0)
        p = pts[k * n_nodes:(k + 1) * n_nodes]
        assert np.all(p >= lo) and np.all(p <= hi)   # every node inside its frame
        out.append((p - lo, vals[k * n_nodes:(k + 1) * n_nodes], (*lo, *hi)))
    return out


def test_paired_shapes_show_each_pair_normalised_with_matched_sign(plate):
    _, geo, test, fe, pairing, _ = plate
    pairs = pairing.pairs[:6]
    assert len(pairs) == 6
    fig = plot_paired_shapes(geo, test, fe, pairing)
    assert fig.get_layout_engine() is None
    ax, cbar = fig.axes
    assert cbar.get_ylabel() == "z (normalised)"
    panels = _panels(fig, 2 * len(pairs), geo.n_nodes)
    tab = pairing.table.set_index("test_mode")
    titles = [t.get_text() for t in ax.texts]
    xy = geo.xyz[:, :2] * 1e3
    for r, (tm, fm) in enumerate(pairs):
        assert titles[2 * r] == f"test mode {tm}: {tab.loc[tm, 'fn_test_hz']:.1f} Hz"
        assert titles[2 * r + 1] == (f"FE mode {fm}: {tab.loc[tm, 'fn_fe_hz']:.1f} Hz, "
                                     f"MAC {tab.loc[tm, 'mac']:.2f}")
        (pt, vt, _), (pf, vf, _) = panels[2 * r], panels[2 * r + 1]
        # each shape scaled to a largest |z| of 1; the FE sign follows the test
        assert np.nanmax(np.abs(vt)) == pytest.approx(1.0)
        assert np.nanmax(np.abs(vf)) == pytest.approx(1.0)
        assert np.nansum(vt * vf) > 0
        # the values are the sensor readings in node order (sign of +z kept) ...
        want = test.sel(mode=tm).values
        np.testing.assert_allclose(vt, want / np.abs(want).max())
        # ... at the nodes' positions, the same in every panel
        np.testing.assert_allclose(pt - pt[0], xy - xy[0], atol=1e-9)
        np.testing.assert_allclose(pf, pt, atol=1e-9)
    # panels of one size in a 6 x 2 grid, apart, the title above each one
    frames = np.array([f for *_, f in panels])
    sizes = frames[:, 2:] - frames[:, :2]
    np.testing.assert_allclose(sizes, np.broadcast_to(sizes[0], sizes.shape))
    assert len(set(np.round(frames[:, 0], 9))) == 2 and len(set(np.round(frames[:, 1], 9))) == 6
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    for t, f in zip(ax.texts, frames):
        e = t.get_window_extent(r)
        top = ax.transData.transform([(f[0] + f[2]) / 2, f[3]])
        assert e.y0 >= top[1] and abs((e.x0 + e.x1) / 2 - top[0]) < 1.0
    # equal scales; tick labels in mm on the left column and the bottom row
    sx, sy = np.abs(np.diag(ax.transData.get_matrix())[:2])
    assert sx == pytest.approx(sy, rel=2e-3)
    # a label reads the mm of the x (y) coordinate under it in its column (row)
    for which, col in (("x", 0), ("y", 1)):
        ticks = ax.get_xticks() if which == "x" else ax.get_yticks()
        labels = ax.get_xticklabels() if which == "x" else ax.get_yticklabels()
        mm = np.array([float(t.get_text()) for t in labels])
        # panel of the bottom-left: data = frame corner + (mm - lower limit)
        frame = frames[-2]
        lower = xy[0, col] - panels[-2][0][0, col]
        first = ticks < frame[2 + col]
        np.testing.assert_allclose(ticks[first] - frame[col], mm[first] - lower, atol=1e-9)
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel() == "y [mm]"
    assert_readable(fig)


def test_paired_shapes_of_a_long_beam_keep_equal_scales(plate):
    # a 10:1 strip of sensors: the panels stay usable (the short side is widened)
    _, _, test, fe, pairing, _ = plate
    pts = np.array([[x, y, 0.0] for x in np.linspace(0.0, 0.8, 5)
                    for y in np.linspace(0.0, 0.06, 4)])
    geo = co.TestGeometry(np.arange(1, 21), pts)
    fig = plot_paired_shapes(geo, test, fe, pairing, max_pairs=2)
    assert len(fig.axes) == 2
    fig.canvas.draw()
    ax = fig.axes[0]
    sx, sy = np.abs(np.diag(ax.transData.get_matrix())[:2])
    assert sx == pytest.approx(sy, rel=2e-3)
    (*_, f), = _panels(fig, 4, 20)[:1]
    w, h = f[2] - f[0], f[3] - f[1]
    assert 0.3 * w < h < w
    assert_readable(fig)


def test_mac_writes_the_values_it_can_show(plate):
    *_, pairing, _ = plate
    mac = pairing.mac
    v = np.abs(mac.values)
    fig = plot_mac(mac, title="MAC")
    assert fig.get_layout_engine() is None
    ax, cbar = fig.axes
    np.testing.assert_array_equal(ax.images[0].get_array(), v)
    written = sorted(t.get_text() for t in ax.texts)
    assert written == sorted(f"{x:.2f}" for x in v[v >= 0.1])
    assert [t.get_text() for t in ax.get_yticklabels()] == [
        f"{m}\n{f:.1f} Hz" for m, f in zip(mac["mode_a"].values, mac["fn_hz_a"].values)]
    assert ax.get_xlabel() == "mode b" and ax.get_title() == "MAC"
    assert_readable(fig)
    # a 40 x 40 matrix: the figure stays one column wide, the values (no longer
    # readable in 0.15 in cells) are left out and the labels thinned to mode numbers
    m = np.random.default_rng(1).uniform(0, 1, (40, 40))
    big = xr.DataArray(m, dims=("mode_a", "mode_b"),
                       coords={"mode_a": np.arange(1, 41), "mode_b": np.arange(1, 41),
                               "fn_hz_a": ("mode_a", np.linspace(10, 900, 40)),
                               "fn_hz_b": ("mode_b", np.linspace(10, 900, 40))})
    fig = plot_mac(big)
    ax = fig.axes[0]
    assert fig.get_figwidth() <= 7.0 + 1e-9 and fig.get_figheight() <= 7.0 + 1e-9
    assert not ax.texts
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels and all("Hz" not in t for t in labels) and len(labels) < 40
    assert_readable(fig)


def test_mesh_figure_draws_each_edge_once_with_the_sensors(plate):
    model, geo, *_, mapping = plate
    fig = plot_test_on_mesh(model, geo, mapping=mapping)
    ax, = fig.axes
    assert fig.get_layout_engine() is None
    mesh = ax.collections[0]
    # a 12 x 8 grid of quads has 12 x 9 + 8 x 13 distinct edges
    segs = mesh.get_segments()
    assert len(segs) == 12 * 9 + 8 * 13
    keys = {tuple(sorted(map(tuple, np.round(s, 9)))) for s in segs}
    assert len(keys) == len(segs)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "z sensors" in labels
    # the geometry has no trace lines: its 5 x 4 grid of nodes is triangulated, dashed,
    # (5-1) 4 + 5 (4-1) grid edges and (5-1)(4-1) diagonals
    wire = ax.collections[1]
    assert wire.get_label().startswith("test wireframe (triangulated")
    assert len(wire.get_segments()) == 4 * 4 + 5 * 3 + 4 * 3
    sensors = [ln for ln in ax.lines if ln.get_label() == "z sensors"][0]
    np.testing.assert_allclose(np.c_[sensors.get_xdata(), sensors.get_ydata()],
                               geo.xyz[:, :2] * 1e3)
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel() == "y [mm]"
    assert ax.get_title() == "FE mesh and test geometry"
    fig.canvas.draw()
    sx, sy = np.abs(np.diag(ax.transData.get_matrix())[:2])
    assert sx == pytest.approx(sy, rel=2e-3)
    assert_readable(fig)


@pytest.mark.slow
def test_stabilisation_diagram_shows_every_pole(identified):
    res = identified
    d = res.diagram
    fig = plot_stabilisation(d, res)
    assert fig.get_layout_engine() is None
    ax = [a for a in fig.axes if a.collections][0]
    n_drawn = sum(len(c.get_offsets()) for c in ax.collections)
    assert n_drawn == len(d.fn_hz)
    labels = {t.get_text() for t in ax.get_legend().get_texts()}
    from mvtk.plot._modal import _STYLE

    assert labels == {_STYLE[s][2] for s in set(d.status)}
    vlines = [ln for ln in ax.lines if ln.get_linestyle() == "--"]
    np.testing.assert_allclose(sorted(ln.get_xdata()[0] for ln in vlines), sorted(res.fn_hz))
    assert ax.get_xlim() == tuple(d.band_hz)
    assert ax.get_title() == "pLSCF stabilisation diagram"
    assert_readable(fig)


@pytest.mark.slow
def test_frf_synthesis_keeps_every_peak_and_names_each_curve(identified):
    res = identified
    fig = plot_frf_synthesis(res)
    assert fig.get_layout_engine() is None
    a2, a1 = fig.axes   # phase panel first (bottom), then magnitude
    n_resp = min(4, res.frf.sizes["response"])
    curves = [ln for ln in a1.lines if len(ln.get_xdata()) > 2]
    assert len(curves) == 2 * n_resp and len([ln for ln in a2.lines]) == 2 * n_resp
    # decimated to the pixel columns, the largest magnitude of each curve is kept
    for k in range(n_resp):
        for ln, data in ((curves[2 * k], res.frf.values[k, 0]),
                         (curves[2 * k + 1], res.synthesised.values[k, 0])):
            assert np.max(ln.get_ydata()) == np.max(np.abs(data))
            assert len(ln.get_xdata()) <= 2 * a1.bbox.width + 2
    grey = [ln for ln in a1.lines if len(ln.get_xdata()) == 2]
    assert len(grey) == len(res.fn_hz)
    labels = [t.get_text() for t in a1.get_legend().get_texts()]
    names = [str(r) for r in res.frf["response"].values][:n_resp]
    assert labels[:n_resp] == [f"{n} (corr {res.correlation.values[i]:.3f})"
                               for i, n in enumerate(names)]
    assert labels[n_resp:] == ["measured", "synthesised"]
    assert "overall correlation" in a1.get_title()
    assert not any(t.get_text() for t in a1.get_xticklabels())   # shared x, lower panel
    assert a2.get_xlabel() == "frequency [Hz]" and a2.get_ylabel() == "phase [deg]"
    assert_readable(fig)


def test_png_encoding_is_lossless_at_the_fast_level(plate):
    from PIL import Image

    *_, pairing, _ = plate
    fig = plot_mac(pairing.mac)
    fast = figure_to_png(fig, dpi=100)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    a = np.asarray(Image.open(io.BytesIO(fast)))
    b = np.asarray(Image.open(io.BytesIO(buf.getvalue())))
    assert a.shape[:2] == (round(fig.get_figheight() * 100), round(fig.get_figwidth() * 100))
    np.testing.assert_array_equal(a, b)


def test_readability_check_catches_overlapping_texts():
    # the check itself fails on a figure whose texts overlap
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.2, 0.2, 0.7, 0.7))
    ax.text(0.5, 0.5, "first label")
    ax.text(0.52, 0.5, "second label")
    with pytest.raises(AssertionError, match="texts overlap"):
        assert_readable(fig)
    assert len(drawn_texts(fig)) >= 2


def test_decay_is_drawn_per_pixel_column_with_its_peaks():
    from mvtk.plot import plot_decay

    t = np.arange(6400) * (150.0 / 6400)
    env = 2e-3 * np.exp(-0.05 * t)
    x = env * np.cos(2 * np.pi * 13.26 * t)
    fig = plot_decay(t, x, fit=env, ylabel="tip displacement [m]", title="Free decay")
    ax, ax2 = fig.axes
    columns = round(ax.get_position().width * fig.get_figwidth() * 100)
    band = ax.collections[0].get_paths()[0].vertices
    assert len(band) <= 2 * columns + 5
    # the band reaches the signal's extremes; the fit and the log panel one point pair
    # (min, max) per pixel column at most
    assert band[:, 1].max() == x.max() and band[:, 1].min() == x.min()
    assert all(len(ln.get_xdata()) <= 2 * columns for ln in ax.lines + ax2.lines)
    peak = ax2.lines[0].get_ydata()
    assert peak.max() == np.abs(x).max()
    assert_readable(fig)


def test_mode_shape_panels_share_their_given_ticks():
    from mvtk.plot import plot_mode_shapes

    xs, ys = np.meshgrid(np.linspace(0, 0.18, 13), np.linspace(0, 0.135, 10))
    nodes = np.c_[xs.ravel(), ys.ravel(), 0 * xs.ravel()]
    uz = np.c_[xs.ravel() ** 2, xs.ravel() * (ys.ravel() - 0.0675)]
    fig = plot_mode_shapes(nodes, uz, [14.25, 42.18])
    panels, cbar = fig.axes[:-1], fig.axes[-1]
    assert [ax.get_title() for ax in panels] == ["mode 1: 14.25 Hz", "mode 2: 42.18 Hz"]
    ticks = {(tuple(ax.get_xticks()), tuple(ax.get_yticks())) for ax in panels}
    assert len(ticks) == 1
    (xt, yt), = ticks
    assert 3 <= len(xt) <= 8 and 2 <= len(yt) <= 8
    assert min(xt) >= 0 and max(xt) <= 180 and min(yt) >= 0 and max(yt) <= 135
    assert [t.get_text() for t in cbar.get_yticklabels()] == ["\u22121.0", "\u22120.5", "0.0",
                                                              "0.5", "1.0"]
    assert_readable(fig)


def test_frf_with_coherence_and_close_peak_labels_stays_readable():
    """Two modes 1.5 Hz apart (labels would collide) and a coherence panel below."""
    from mvtk.plot import plot_frf

    f = np.linspace(5.0, 60.0, 2000)
    h = 1 / (20.0**2 - f**2 + 0.4j * f) + 1 / (21.5**2 - f**2 + 0.4j * f)
    coh = 1 - 0.5 * np.exp(-((f - 40.0) / 2.0) ** 2)          # a dip at an antiresonance
    fig = plot_frf(f, h, bands=[(19.9, 20.1, 20.0), (21.4, 21.6, 21.5)],
                   ylabel="|H| [m/N]", coherence=coh, title="FRF and coherence")
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == "coherence"
    y = fig.axes[1].lines[0].get_ydata()
    assert min(y) == pytest.approx(0.5, abs=1e-3)              # the dip is drawn
    assert_readable(fig)


def test_modal_uncertainty_bars_are_k_standard_deviations(identified):
    """Each mode at (fn, 100 zeta) with bars of +-2 std (fn_std_hz, zeta_std) drawn from
    the result's own columns; reliable filled, others hollow; labels readable."""
    from matplotlib.container import ErrorbarContainer

    from mvtk.plot import plot_modal_uncertainty

    res = identified
    fig = plot_modal_uncertainty(res)
    ax = fig.axes[0]
    bars = [c for c in ax.containers if isinstance(c, ErrorbarContainer)]
    assert len(bars) == (1 if res.reliable.all() or not res.reliable.any() else 2)
    got_x, got_y, got_dy = [], [], []
    for c in bars:
        x, y = c.lines[0].get_data()
        got_x += list(x)
        got_y += list(y)
        ycol = c.lines[2][-1]                     # the vertical bar segments
        got_dy += [seg[1, 1] - seg[0, 1] for seg in ycol.get_segments()]
    order = np.argsort(got_x)
    np.testing.assert_allclose(np.sort(got_x), np.sort(res.fn_hz))
    np.testing.assert_allclose(np.asarray(got_y)[order], 100 * res.zeta[np.argsort(res.fn_hz)])
    np.testing.assert_allclose(np.asarray(got_dy)[order],
                               2 * 2 * 100 * res.zeta_std[np.argsort(res.fn_hz)], rtol=1e-9)
    assert ax.get_ylabel() == "damping ratio zeta [%]"
    with pytest.raises(Exception, match="k must be a coverage factor"):
        plot_modal_uncertainty(res, k=0)
