"""Figures of test-analysis correlation: MAC matrix, paired shapes, mesh with test wireframe.

Built without pyplot (see :mod:`mvtk.plot._figures`). Inputs are the plain objects of
:mod:`mvtk.correlation` (DataArrays, TestGeometry, FEModel); nothing is computed here
beyond scaling for display.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DimensionError, ParameterError
from ._figures import FIG_WIDTH
from ._layout import axes_at, equal_limits, figure, nice_ticks

__all__ = ["plot_mac", "plot_paired_shapes", "plot_test_on_mesh"]


#: Fixed layout of :func:`plot_mac` in inches: margins for the two-line tick labels and
#: axis labels (left, bottom), the title (top), the colorbar strip (gap, bar, tick
#: labels), the preferred cell size and the largest figure size.
MAC_LAYOUT = {"left": 0.85, "bottom": 0.65, "top": 0.35, "cbar": (0.2, 0.15, 0.45),
              "cell": (0.52, 0.47), "max_size": (FIG_WIDTH, 7.0)}
#: Smallest cell (width, height in inches) in which a value is written (``0.98`` at 7 pt
#: is about 0.22 x 0.1 in), and in which a two-line tick label (mode and frequency) fits.
MAC_TEXT_CELL, MAC_LABEL_CELL = (0.3, 0.18), (0.45, 0.3)


def plot_mac(mac: Any, *, title: str = "MAC", annotate: bool = True):
    """Heat map of a MAC (or AutoMAC, cross-orthogonality) matrix.

    The cells are about half an inch square; a large matrix is shrunk to fit a figure
    of at most :data:`MAC_LAYOUT` ``max_size``, and then only what stays readable is
    written: the values when a cell can hold them, the frequencies in the tick labels
    when a cell is wide (tall) enough for them, otherwise the mode numbers, thinned
    to one label per 0.2 in.

    Parameters
    ----------
    mac : xarray.DataArray ("mode_a", "mode_b")
        From :func:`mvtk.correlation.mac`; ``fn_hz_a`` / ``fn_hz_b`` label the axes when
        present.
    title : str
    annotate : bool
        Write the values >= 0.1 in the cells (where they are readable).

    Examples
    --------
    >>> import xarray as xr
    >>> mac = xr.DataArray([[1.0, 0.07], [0.07, 1.0]], dims=("mode_a", "mode_b"))
    >>> fig = plot_mac(mac, title="AutoMAC")
    >>> len(fig.axes)            # the matrix and its colour bar
    2
    """
    dims = getattr(mac, "dims", None)
    if dims is None or len(dims) != 2:
        raise DimensionError(f"expected a 2-D DataArray (mode_a, mode_b), got {dims}")
    v = np.abs(np.asarray(mac.values, dtype=complex)).real
    na, nb = v.shape
    g = MAC_LAYOUT
    gap, bar, ticks = g["cbar"]
    max_w, max_h = g["max_size"]
    right = gap + bar + ticks
    cw = min(g["cell"][0], (max_w - g["left"] - right) / nb)
    ch = min(g["cell"][1], (max_h - g["bottom"] - g["top"]) / na)
    width = g["left"] + nb * cw + right
    height = g["bottom"] + na * ch + g["top"]
    fig = figure(width, height)
    ax = axes_at(fig, g["left"], g["bottom"], nb * cw, na * ch)
    im = ax.imshow(v, vmin=0, vmax=1, cmap="viridis", origin="upper", aspect="auto",
                   interpolation="nearest")

    def ticks_of(dim, fcoord, cell, label_cell):
        modes = mac[dim].values
        pos = np.arange(len(modes))
        if fcoord in mac.coords and cell >= label_cell:
            return pos, [f"{m}\n{f:.1f} Hz" for m, f in zip(modes, mac[fcoord].values)]
        step = max(1, int(np.ceil(0.2 / cell)))
        return pos[::step], [str(m) for m in modes[::step]]

    ax.set_yticks(*ticks_of(dims[0], "fn_hz_a", ch, MAC_LABEL_CELL[1]), fontsize=7)
    ax.set_xticks(*ticks_of(dims[1], "fn_hz_b", cw, MAC_LABEL_CELL[0]), fontsize=7)
    ax.set_ylabel(dims[0].replace("_", " "))
    ax.set_xlabel(dims[1].replace("_", " "))
    if annotate and cw >= MAC_TEXT_CELL[0] and ch >= MAC_TEXT_CELL[1]:
        for i, j in zip(*np.nonzero(v >= 0.1)):
            ax.text(j, i, f"{v[i, j]:.2f}", ha="center", va="center", fontsize=7,
                    color="k" if v[i, j] > 0.6 else "w")
    ax.set_title(title, fontsize=10, y=1.0)
    cax = axes_at(fig, g["left"] + nb * cw + gap, g["bottom"] + 0.1 * na * ch, bar,
                  0.8 * na * ch)
    fig.colorbar(im, cax=cax)
    cax.set_yticks(np.linspace(0.0, 1.0, 6), [f"{t:.1f}" for t in np.linspace(0, 1, 6)])
    return fig


def _wire(ax, geometry, values=None, scale=0.0, color="k", lw=1.0, label=None,
          triangulate=False):
    """Wireframe of a test geometry in the x-y view with optional z displacement colour.

    With ``triangulate`` a geometry without trace lines is drawn as the triangulation of
    its nodes (:func:`mvtk.plot.mesh_edges`, dashed) so the test grid shows over a mesh.
    """
    from matplotlib.collections import LineCollection

    xyz = geometry.xyz * 1e3
    segs = geometry.edges()
    style = "solid"
    if not len(segs) and triangulate and len(xyz) >= 3:
        from ._animation import mesh_edges

        segs, style = mesh_edges(geometry.xyz), "dashed"
        label = f"{label} (triangulated: no trace lines)" if label else label
    if len(segs):
        ax.add_collection(LineCollection(xyz[segs][:, :, :2], colors=color, linewidths=lw,
                                         linestyles=style, label=label))
    if values is not None:
        sc = ax.scatter(xyz[:, 0], xyz[:, 1], c=values, cmap="coolwarm", vmin=-1, vmax=1,
                        s=40, edgecolors="k", linewidths=0.5, zorder=3)
        return sc
    ax.plot(xyz[:, 0], xyz[:, 1], "o", ms=4, color=color, zorder=3)
    return None


def _node_values(geometry, shape) -> np.ndarray:
    """Per test node: the reading of its +z / -z sensor (NaN where there is none)."""
    out = np.full(geometry.n_nodes, np.nan)
    values = np.real(np.asarray(shape.values))
    for v, node, direction in zip(values, shape["node"].values, shape["direction"].values):
        if direction in ("+z", "-z"):
            out[geometry.row(int(node))] = float(v) * (1 if direction == "+z" else -1)
    return out


#: Fixed layout of :func:`plot_paired_shapes` in inches: left margin (tick labels and
#: y label), gap between the two columns, colorbar strip right of the panels (gap, bar,
#: tick labels and label), bottom margin (tick labels and x label), top margin, title
#: band above each panel, largest panel width and height.
PAIRED = {"left": 0.5, "wgap": 0.25, "cbar": (0.25, 0.18, 0.75), "bottom": 0.45,
          "top": 0.05, "title": 0.3, "max_panel_w": 2.6, "max_panel_h": 2.0}


def plot_paired_shapes(geometry: Any, test: Any, fe: Any, pairing: Any, *, max_pairs: int = 6):
    """Paired test and FE shapes side by side on the test geometry (z components).

    One row per accepted pair (test left, FE right, the FE shape's sign matched to the
    test), each shape scaled to a largest absolute value of 1 and coloured by it on
    the same colour scale. All panels show the same x-y extent at equal scales.

    The panels are drawn as a grid of framed regions of one axes (the tick labels in
    mm on the left column and the bottom row): a figure of a dozen small matplotlib
    axes spends most of its time creating and laying out their ticks.

    Parameters
    ----------
    geometry : TestGeometry
    test, fe : DataArray ("mode", "dof")
        Test shapes and FE shapes mapped on the same test DOFs (``node``/``direction``
        coordinates on ``dof``).
    pairing : ModePairing
        From :func:`mvtk.correlation.pair_modes`; the accepted pairs are drawn.
    max_pairs : int

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the grid of ``2 n_pairs`` panels (one scatter of all panels' nodes,
        values in row order test, FE; panel titles as annotations) and the colorbar.

    Examples
    --------
    Test shapes (here the FE shapes scaled by -2) next to the paired FE shapes:

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> pts = [(3 * j + i + 1, 0.1 * (i + 1), 0.1 * j) for j in range(3) for i in range(3)]
    >>> geo = read_test_geometry({"nodes": [{"node": n, "x": x, "y": y, "z": 0.0}
    ...                                     for n, x, y in pts],
    ...                           "sensors": [{"node": n, "direction": "+z"} for n, _, _ in pts]})
    >>> fe = modal_analysis(plate, 2)
    >>> pre = correlate(geo, plate, fe)
    >>> res = correlate(geo, plate, fe, test=-2.0 * pre.fe)
    >>> fig = plot_paired_shapes(geo, res.test, res.fe, res.pairing)
    >>> len(fig.axes) >= 1
    True
    """
    from matplotlib.collections import LineCollection

    pairs = pairing.pairs[:max_pairs]
    if not pairs:
        raise ParameterError("no accepted pairs to draw")
    tab = pairing.table.set_index("test_mode")
    xy = geometry.xyz[:, :2] * 1e3
    (x0, x1), (y0, y1), aspect = equal_limits(xy[:, 0], xy[:, 1])
    g = PAIRED
    gap, bar, label = g["cbar"]
    width = FIG_WIDTH
    pw = min(g["max_panel_w"], (width - g["left"] - g["wgap"] - gap - bar - label) / 2)
    ph = min(pw * aspect, g["max_panel_h"])
    pw = ph / aspect
    n = len(pairs)
    height = g["bottom"] + n * (ph + g["title"]) + g["top"]
    fig = figure(width, height)
    # the panels and the colorbar centred across the figure width
    left = (width - (g["left"] + 2 * pw + g["wgap"] + gap + bar + label)) / 2 + g["left"]
    grid_w, grid_h = 2 * pw + g["wgap"], n * ph + (n - 1) * g["title"]
    ax = axes_at(fig, left, g["bottom"], grid_w, grid_h)
    # data units of the grid: mm of the panels, the gaps converted at the same scale
    dx, dy = x1 - x0, y1 - y0
    mm_per_in = dx / pw
    step_x, step_y = dx + g["wgap"] * mm_per_in, dy + g["title"] * mm_per_in
    ax.set_xlim(0.0, 2 * dx + g["wgap"] * mm_per_in)
    ax.set_ylim(0.0, n * dy + (n - 1) * g["title"] * mm_per_in)
    ax.set_frame_on(False)
    origins = [(c * step_x - x0, (n - 1 - r) * step_y - y0) for r in range(n) for c in (0, 1)]
    pts, vals, titles = [], [], []
    for r, (tm, fm) in enumerate(pairs):
        vt = _node_values(geometry, test.sel(mode=tm))
        vf = _node_values(geometry, fe.sel(mode=fm))
        s = 1.0 if np.nansum(vt * vf) >= 0 else -1.0
        row = tab.loc[tm]
        for c, (v, name, m) in enumerate(((vt, "test", tm), (s * vf, "FE", fm))):
            ox, oy = origins[2 * r + c]
            peak = np.nanmax(np.abs(v)) if np.any(np.isfinite(v)) else 1.0
            pts.append(xy + (ox, oy))
            vals.append(v / (peak or 1.0))
            f = row["fn_test_hz"] if c == 0 else row["fn_fe_hz"]
            extra = f", MAC {row['mac']:.2f}" if c == 1 else ""
            titles.append((ox + (x0 + x1) / 2, oy + y1, f"{name} mode {m}: {f:.1f} Hz{extra}"))
    frame = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    boxes = [np.r_[frame + o, frame[:1] + o] for o in origins]
    ax.add_collection(LineCollection(boxes, colors="k", linewidths=0.8, clip_on=False),
                      autolim=False)
    edges = geometry.edges()
    if len(edges):
        ax.add_collection(LineCollection([seg + o for o in origins for seg in xy[edges]],
                                         colors="k", linewidths=1.0), autolim=False)
    p = np.concatenate(pts)
    sc = ax.scatter(p[:, 0], p[:, 1], c=np.concatenate(vals), cmap="coolwarm", vmin=-1,
                    vmax=1, s=40, edgecolors="k", linewidths=0.5, zorder=3)
    for tx, ty, text in titles:
        ax.annotate(text, (tx, ty), xytext=(0, 3), textcoords="offset points", ha="center",
                    va="bottom", fontsize=8)
    # tick labels in mm on the left column and the bottom row, about one per 0.3 in
    xt = nice_ticks(x0, x1, max(3, int(pw / 0.3)))
    yt = nice_ticks(y0, y1, max(3, int(ph / 0.3)))
    ax.set_xticks(np.r_[xt - x0, xt - x0 + step_x], [f"{t:g}" for t in xt] * 2, fontsize=6)
    ax.set_yticks(np.concatenate([yt - y0 + k * step_y for k in range(n)]),
                  [f"{t:g}" for t in yt] * n, fontsize=6)
    ax.set_xlabel("x [mm]", fontsize=7)
    ax.set_ylabel("y [mm]", fontsize=7)
    area = height - g["bottom"] - g["top"] - g["title"]
    ch = min(0.6 * area, 6.0)
    cax = axes_at(fig, left + grid_w + gap, g["bottom"] + (area - ch) / 2, bar, ch)
    fig.colorbar(sc, cax=cax)
    cax.set_yticks(np.linspace(-1.0, 1.0, 5),
                   [f"{t:.1f}".replace("-", "\u2212") for t in np.linspace(-1, 1, 5)])
    cax.tick_params(labelsize=7)
    cax.set_ylabel("z (normalised)", fontsize=8)
    return fig


def _mesh_segments(model: Any, xy: np.ndarray) -> np.ndarray:
    """Edges of the model's elements in the x-y view, each drawn once, shape (n, 2, 2).

    An edge shared by two surface elements is kept once (drawn twice it would be darker
    where antialiased and cost twice the drawing).
    """
    pairs = []
    for conn in model.elements.values():
        conn = np.asarray(conn)
        if conn.shape[1] < 3:
            pairs.append(conn[:, :2])
        else:
            pairs.append(np.stack([conn.ravel(), np.roll(conn, -1, axis=1).ravel()], axis=1))
    if not pairs:
        return np.zeros((0, 2, 2))
    e = np.sort(np.concatenate(pairs), axis=1)
    e = np.unique(e[e[:, 0] != e[:, 1]], axis=0)
    return xy[e]


#: Fixed layout of :func:`plot_test_on_mesh` in inches: left (tick labels and y label),
#: right, bottom (tick labels, x label and the legend row below), top (title), largest
#: plot height.
MESH_LAYOUT = {"left": 0.75, "right": 0.2, "bottom": 0.95, "top": 0.35, "max_h": 3.6}


def plot_test_on_mesh(model: Any, geometry: Any, *, mapping: Any = None):
    """FE mesh (x-y view) with the test wireframe, sensor positions and directions.

    The view has equal scales and the figure's height follows the mesh's aspect; the
    legend is a row below the plot, where it hides no sensor.

    Parameters
    ----------
    model : FEModel
        Its elements (surface elements by their edges, 2-node elements as segments)
        are drawn.
    geometry : TestGeometry
    mapping : DofMapping, optional
        Sensors off their nearest FE node by more than a tenth of ``tol`` are ringed.

    Examples
    --------
    A plate mesh with three sensors along its centre line:

    >>> from mvtk.correlation import read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=6, ny=4, clamp="x0")
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.1, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)],
    ...                           "lines": [{"nodes": [1, 2, 3]}]})
    >>> fig = plot_test_on_mesh(plate, geo)
    >>> fig.axes[0].get_aspect()
    1.0
    """
    from matplotlib.collections import LineCollection

    xy = model.nodes[:, :2] * 1e3
    pts = np.r_[xy, geometry.xyz[:, :2] * 1e3]
    (x0, x1), (y0, y1), aspect = equal_limits(pts[:, 0], pts[:, 1], pad=0.06,
                                              aspect_range=(0.2, 1.5))
    g = MESH_LAYOUT
    width = FIG_WIDTH
    pw = width - g["left"] - g["right"]
    ph = min(pw * aspect, g["max_h"])
    pw = ph / aspect
    fig = figure(width, g["bottom"] + ph + g["top"])
    ax = axes_at(fig, g["left"] + (width - g["left"] - g["right"] - pw) / 2, g["bottom"],
                 pw, ph)
    ax.add_collection(LineCollection(_mesh_segments(model, xy), colors="0.8", linewidths=0.5),
                      autolim=False)
    _wire(ax, geometry, color="tab:red", lw=1.4, label="test wireframe", triangulate=True)
    if geometry.sensors:
        v = geometry.sensor_vectors()
        p = np.array([geometry.xyz[geometry.row(s.node)] for s in geometry.sensors]) * 1e3
        span = float(np.ptp(xy, axis=0).max()) or 1.0
        inplane = np.linalg.norm(v[:, :2], axis=1) > 1e-9
        if inplane.any():
            ax.quiver(p[inplane, 0], p[inplane, 1], v[inplane, 0], v[inplane, 1],
                      color="tab:blue", angles="xy", scale_units="xy", scale=20 / span,
                      width=0.004, label="in-plane sensors")
        out = ~inplane
        ax.plot(p[out, 0], p[out, 1], "^", color="tab:blue", ms=6, label="z sensors")
    if mapping is not None:
        far = mapping.report["node_distance_m"].to_numpy() > 0.1 * mapping.tol
        if far.any():
            rows = [geometry.row(n) for n in mapping.report["node"].to_numpy()[far]]
            q = geometry.xyz[rows] * 1e3
            ax.plot(q[:, 0], q[:, 1], "o", mfc="none", mec="tab:orange", ms=11,
                    label="between FE nodes")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xticks(nice_ticks(x0, x1, max(3, int(pw / 0.6))))
    ax.set_yticks(nice_ticks(y0, y1, max(3, int(ph / 0.45))))
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(handles, labels, fontsize=7, loc="upper center", ncol=len(handles),
                  bbox_to_anchor=(0.5, -0.55 / ph), frameon=False)
    ax.set_title("FE mesh and test geometry", fontsize=10, y=1.0)
    return fig
