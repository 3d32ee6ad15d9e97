"""Figures of test-analysis correlation: MAC matrix, paired shapes, mesh with test wireframe.

Built without pyplot (see :mod:`mvtk.plot._figures`). Inputs are the plain objects of
:mod:`mvtk.correlation` (DataArrays, TestGeometry, FEModel); nothing is computed here
beyond scaling for display.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DimensionError, ParameterError
from ._figures import _constrained_figure as _figure

__all__ = ["plot_mac", "plot_paired_shapes", "plot_test_on_mesh"]


def plot_mac(mac: Any, *, title: str = "MAC", annotate: bool = True):
    """Heat map of a MAC (or AutoMAC, cross-orthogonality) matrix.

    Parameters
    ----------
    mac : xarray.DataArray ("mode_a", "mode_b")
        From :func:`mvtk.correlation.mac`; ``fn_hz_a`` / ``fn_hz_b`` label the axes when
        present.
    title : str
    annotate : bool
        Write the values >= 0.1 in the cells.
    """
    dims = getattr(mac, "dims", None)
    if dims is None or len(dims) != 2:
        raise DimensionError(f"expected a 2-D DataArray (mode_a, mode_b), got {dims}")
    v = np.abs(np.asarray(mac.values, dtype=complex)).real
    fig = _figure(1.2 + 0.55 * v.shape[1], 1.0 + 0.5 * v.shape[0])
    ax = fig.add_subplot(1, 1, 1)
    im = ax.imshow(v, vmin=0, vmax=1, cmap="viridis", origin="upper", aspect="auto")

    def labels(dim, fcoord):
        modes = mac[dim].values
        if fcoord in mac.coords:
            return [f"{m}\n{f:.1f} Hz" for m, f in zip(modes, mac[fcoord].values)]
        return [str(m) for m in modes]

    ax.set_yticks(range(v.shape[0]), labels(dims[0], "fn_hz_a"), fontsize=7)
    ax.set_xticks(range(v.shape[1]), labels(dims[1], "fn_hz_b"), fontsize=7)
    ax.set_ylabel(dims[0].replace("_", " "))
    ax.set_xlabel(dims[1].replace("_", " "))
    if annotate:
        for i in range(v.shape[0]):
            for j in range(v.shape[1]):
                if v[i, j] >= 0.1:
                    ax.text(j, i, f"{v[i, j]:.2f}", ha="center", va="center", fontsize=7,
                            color="k" if v[i, j] > 0.6 else "w")
    ax.set_title(title, fontsize=10)
    fig.colorbar(im, ax=ax, shrink=0.8)
    return fig


def _wire(ax, geometry, values=None, scale=0.0, color="k", lw=1.0, label=None):
    """Wireframe of a test geometry in the x-y view with optional z displacement colour."""
    from matplotlib.collections import LineCollection

    xyz = geometry.xyz * 1e3
    segs = geometry.edges()
    if len(segs):
        ax.add_collection(LineCollection(xyz[segs][:, :, :2], colors=color, linewidths=lw,
                                         label=label))
    if values is not None:
        sc = ax.scatter(xyz[:, 0], xyz[:, 1], c=values, cmap="coolwarm", vmin=-1, vmax=1,
                        s=40, edgecolors="k", linewidths=0.5, zorder=3)
        return sc
    ax.plot(xyz[:, 0], xyz[:, 1], "o", ms=4, color=color, zorder=3)
    return None


def _node_values(geometry, shape) -> np.ndarray:
    """Per test node: the reading of its +z / -z sensor (NaN where there is none)."""
    out = np.full(geometry.n_nodes, np.nan)
    for d, node, direction in zip(shape["dof"].values, shape["node"].values,
                                  shape["direction"].values):
        if direction in ("+z", "-z"):
            out[geometry.row(int(node))] = float(np.real(shape.sel(dof=d))) * (
                1 if direction == "+z" else -1)
    return out


def plot_paired_shapes(geometry: Any, test: Any, fe: Any, pairing: Any, *, max_pairs: int = 6):
    """Paired test and FE shapes side by side on the test geometry (z components).

    Parameters
    ----------
    geometry : TestGeometry
    test, fe : DataArray ("mode", "dof")
        Test shapes and FE shapes mapped on the same test DOFs (``node``/``direction``
        coordinates on ``dof``).
    pairing : ModePairing
        From :func:`mvtk.correlation.pair_modes`; the accepted pairs are drawn.
    max_pairs : int
    """
    pairs = pairing.pairs[:max_pairs]
    if not pairs:
        raise ParameterError("no accepted pairs to draw")
    tab = pairing.table.set_index("test_mode")
    fig = _figure(7.0, 2.3 * len(pairs))
    sc = None
    for r, (tm, fm) in enumerate(pairs):
        vt = _node_values(geometry, test.sel(mode=tm))
        vf = _node_values(geometry, fe.sel(mode=fm))
        s = 1.0 if np.nansum(vt * vf) >= 0 else -1.0
        for c, (v, name, m) in enumerate(((vt, "test", tm), (s * vf, "FE", fm))):
            ax = fig.add_subplot(len(pairs), 2, 2 * r + c + 1)
            peak = np.nanmax(np.abs(v)) if np.any(np.isfinite(v)) else 1.0
            sc = _wire(ax, geometry, v / (peak or 1.0))
            ax.set_aspect("equal")
            row = tab.loc[tm]
            f = row["fn_test_hz"] if c == 0 else row["fn_fe_hz"]
            extra = f", MAC {row['mac']:.2f}" if c == 1 else ""
            ax.set_title(f"{name} mode {m}: {f:.1f} Hz{extra}", fontsize=8)
            ax.tick_params(labelsize=6)
    if sc is not None:
        fig.colorbar(sc, ax=fig.axes, shrink=0.6, label="z (normalised)")
    return fig


def plot_test_on_mesh(model: Any, geometry: Any, *, mapping: Any = None):
    """FE mesh (x-y view) with the test wireframe, sensor positions and directions.

    Parameters
    ----------
    model : FEModel
        Its surface elements (4- and 3-node) are drawn.
    geometry : TestGeometry
    mapping : DofMapping, optional
        Sensors off their nearest FE node by more than a tenth of ``tol`` are ringed.
    """
    fig = _figure(6.5, 4.5)
    ax = fig.add_subplot(1, 1, 1)
    from matplotlib.collections import LineCollection

    xy = model.nodes[:, :2] * 1e3
    for conn in model.elements.values():
        if conn.shape[1] < 3:
            segs = xy[conn]
        else:
            nxt = np.roll(conn, -1, axis=1)
            segs = np.stack([xy[conn.ravel()], xy[nxt.ravel()]], axis=1)
        ax.add_collection(LineCollection(segs, colors="0.8", linewidths=0.5))
    _wire(ax, geometry, color="tab:red", lw=1.4, label="test wireframe")
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
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.legend(fontsize=7, loc="best")
    ax.set_title("FE mesh and test geometry", fontsize=10)
    return fig
