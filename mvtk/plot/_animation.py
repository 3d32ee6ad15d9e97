"""Animated 3-D mode shapes for a self-contained HTML page (canvas + inline script).

The page needs no network and no library: the node coordinates, the wireframe edges and
the shapes are written into the page as JSON, and about a hundred lines of plain
JavaScript draw them on a ``<canvas>`` (orthographic view, drag to rotate, one mode at a
time, the shape oscillating as ``sin(2 pi t)``). A printed page shows the first frame.
"""

from __future__ import annotations

import html
import json
from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError

__all__ = ["mesh_edges", "mode_animation_html"]


def mesh_edges(xyz: np.ndarray, *, max_edge_factor: float = 2.5) -> np.ndarray:
    """Wireframe edges of a point cloud on a surface: a Delaunay triangulation in the
    best-fit plane of the points (principal axes), without the edges longer than
    ``max_edge_factor`` times the median edge (so a concave outline is not bridged).

    Parameters
    ----------
    xyz : array (n, 3)
        Node coordinates (m).
    max_edge_factor : float
        Longest kept edge relative to the median edge length.

    Returns
    -------
    ndarray of int (n_edges, 2)
        Node index pairs, each edge once.

    Examples
    --------
    >>> xy = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    >>> len(mesh_edges(xy))
    5
    """
    from scipy.spatial import Delaunay, QhullError

    p = np.asarray(xyz, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2:
        raise ParameterError(f"mesh_edges needs node coordinates of shape (n, 3) with "
                             f"n >= 2, got {p.shape}")
    if len(p) < 3:
        return np.array([[0, 1]])
    c = p - p.mean(axis=0)
    _, sv, vt = np.linalg.svd(c, full_matrices=False)
    if sv[1] <= 1e-9 * max(sv[0], 1e-300):          # points on a line: a polyline
        order = np.argsort(c @ vt[0])
        return np.column_stack([order[:-1], order[1:]])
    uv = c @ vt[:2].T
    try:
        tri = Delaunay(uv)
    except QhullError:
        order = np.argsort(uv[:, 0])
        return np.column_stack([order[:-1], order[1:]])
    s = tri.simplices
    e = np.vstack([s[:, [0, 1]], s[:, [1, 2]], s[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    length = np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1)
    return e[length <= max_edge_factor * np.median(length)]


def _shape_array(shape, n: int, what: str) -> np.ndarray:
    d = np.real(np.asarray(shape, dtype=complex if np.iscomplexobj(shape) else float))
    if d.shape == (n,):
        d = np.column_stack([np.zeros(n), np.zeros(n), d])   # along z
    if d.shape != (n, 3):
        raise ParameterError(f"{what}: a shape needs {n} values (z) or shape ({n}, 3), got "
                             f"{d.shape}")
    return d


def _round(a: np.ndarray, digits: int = 4) -> list:
    """Values with ``digits`` significant digits relative to the array's largest."""
    a = np.asarray(a, dtype=float)
    scale = float(np.max(np.abs(a))) if a.size else 0.0
    if scale == 0.0:
        return a.tolist()
    q = 10.0 ** (np.floor(np.log10(scale)) - digits + 1)
    return (np.round(a / q) * q).round(12).tolist()


_SCRIPT = r"""
(function () {
  const data = JSON.parse(document.getElementById("%(id)s-data").textContent);
  const canvas = document.getElementById("%(id)s");
  const ctx = canvas.getContext("2d");
  const select = document.getElementById("%(id)s-mode");
  const button = document.getElementById("%(id)s-play");
  let yaw = -0.6, pitch = 0.55, playing = true, mode = 0, t0 = performance.now();
  const layers = data.layers;
  let cx = 0, cy = 0, cz = 0, size = 0, n = 0;
  for (const L of layers) for (const p of L.xyz) { cx += p[0]; cy += p[1]; cz += p[2]; n++; }
  cx /= n; cy /= n; cz /= n;
  for (const L of layers) for (const p of L.xyz)
    size = Math.max(size, Math.hypot(p[0] - cx, p[1] - cy, p[2] - cz));
  size = size || 1;
  const amp = 0.25 * size;
  function project(p) {
    const x = p[0] - cx, y = p[1] - cy, z = p[2] - cz;
    const x1 = Math.cos(yaw) * x - Math.sin(yaw) * y;
    const y1 = Math.sin(yaw) * x + Math.cos(yaw) * y;
    const y2 = Math.cos(pitch) * y1 - Math.sin(pitch) * z;
    const z2 = Math.sin(pitch) * y1 + Math.cos(pitch) * z;
    return [x1, z2, y2];
  }
  function draw(now) {
    const w = canvas.clientWidth || canvas.width, h = Math.round(w * 0.5);
    if (canvas.width !== w) { canvas.width = w; canvas.height = h; }
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    const s = 0.42 * Math.min(canvas.width, canvas.height * 2) / size / 1.15;
    const phase = playing ? Math.cos(2 * Math.PI * 0.7 * (now - t0) / 1000) : 1.0;
    for (const L of layers) {
      const d = L.modes[mode];
      if (!d) continue;
      const m = d.scale * amp * phase;
      ctx.strokeStyle = L.color; ctx.lineWidth = L.width;
      ctx.beginPath();
      const q = L.xyz.map((p, i) => project([p[0] + m * d.u[i][0], p[1] + m * d.u[i][1],
                                            p[2] + m * d.u[i][2]]));
      for (const e of L.edges) {
        const a = q[e[0]], b = q[e[1]];
        ctx.moveTo(canvas.width / 2 + s * a[0], canvas.height / 2 - s * a[1]);
        ctx.lineTo(canvas.width / 2 + s * b[0], canvas.height / 2 - s * b[1]);
      }
      ctx.stroke();
      if (L.points) {
        ctx.fillStyle = L.color;
        for (const a of q) {
          ctx.beginPath();
          ctx.arc(canvas.width / 2 + s * a[0], canvas.height / 2 - s * a[1], 3, 0, 2 * Math.PI);
          ctx.fill();
        }
      }
    }
    if (playing) requestAnimationFrame(draw);
  }
  select.addEventListener("change", () => { mode = +select.value; requestAnimationFrame(draw); });
  button.addEventListener("click", () => {
    playing = !playing; button.textContent = playing ? "pause" : "play";
    t0 = performance.now(); requestAnimationFrame(draw);
  });
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY, yaw, pitch]; });
  window.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    yaw = drag[2] + (e.clientX - drag[0]) * 0.01;
    pitch = Math.max(-1.5, Math.min(1.5, drag[3] + (e.clientY - drag[1]) * 0.01));
    if (!playing) requestAnimationFrame(draw);
  });
  canvas.dataset.frames = "0";
  const count = (now) => { canvas.dataset.frames = String(+canvas.dataset.frames + 1);
                           if (playing) requestAnimationFrame(count); };
  requestAnimationFrame(count);
  requestAnimationFrame(draw);
})();
"""


def mode_animation_html(
    xyz: np.ndarray,
    shapes: np.ndarray,
    labels: Sequence[str],
    *,
    edges: np.ndarray | None = None,
    overlay: dict | None = None,
    element_id: str = "mode-animation",
    name: str = "FE mesh",
) -> str:
    """HTML (canvas, controls, inline data and script) animating mode shapes offline.

    Parameters
    ----------
    xyz : array (n, 3)
        Node coordinates of the model (m).
    shapes : array (n, n_modes) or (n, 3, n_modes)
        Mode shapes: a z displacement per node, or a 3-vector per node.
    labels : list of str
        One label per mode, shown in the mode selector.
    edges : array (n_edges, 2), optional
        Wireframe edges (node indices); default :func:`mesh_edges` of ``xyz``.
    overlay : dict, optional
        A second wireframe drawn over the first in red, e.g. the test geometry with the
        identified shapes: keys ``xyz`` (m, 3), ``shapes`` (m, n_modes) or
        (m, 3, n_modes) with ``nan`` for a mode it lacks, optional ``edges``,
        ``name``. Each overlay shape is drawn at the amplitude of the model's shape
        it is paired with (its own relative scale is kept).
    element_id : str
        ``id`` of the canvas (unique in the page).
    name : str
        Name of the model in the legend.

    Returns
    -------
    str
        An HTML fragment; the page stays self-contained (no network, no library).

    Examples
    --------
    >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    >>> out = mode_animation_html(xyz, np.array([[0, 1, 0, 1.0]]).T, ["mode 1: 10 Hz"])
    >>> "<canvas" in out and "<script>" in out and "http" not in out
    True
    """
    p = np.asarray(xyz, dtype=float)
    n = len(p)
    s = np.asarray(shapes, dtype=float)
    s = s[:, None, :] * np.array([0.0, 0.0, 1.0])[None, :, None] if s.ndim == 2 else s
    if s.shape[:2] != (n, 3):
        raise ParameterError(f"mode_animation_html: shapes must have {n} rows (one per "
                             f"node), got {np.asarray(shapes).shape}")
    k = s.shape[2]
    if len(labels) != k:
        raise ParameterError(f"mode_animation_html: {k} shapes but {len(labels)} labels")
    if not (element_id.replace("-", "").replace("_", "").isalnum()):
        raise ParameterError(f"element_id must be letters, digits, '-' or '_', got "
                             f"{element_id!r}")
    e = mesh_edges(p) if edges is None else np.asarray(edges, dtype=int)

    def modes_of(sh: np.ndarray) -> list:
        out = []
        for j in range(sh.shape[2]):
            u = sh[:, :, j]
            big = float(np.nanmax(np.abs(u))) if np.isfinite(u).any() else 0.0
            if big == 0.0 or not np.isfinite(u).all():
                out.append(None)
                continue
            out.append({"u": _round(u / big), "scale": 1.0})
        return out

    layers = [{"name": name, "xyz": _round(p, 6), "edges": e.tolist(), "color": "#4a5a8a",
               "width": 0.6, "points": False, "modes": modes_of(s)}]
    legend = [f'<span style="color:#4a5a8a">&#9632; {html.escape(name)}</span>']
    if overlay is not None:
        q = np.asarray(overlay["xyz"], dtype=float)
        so = np.asarray(overlay["shapes"], dtype=float)
        so = so[:, None, :] * np.array([0.0, 0.0, 1.0])[None, :, None] if so.ndim == 2 else so
        if so.shape[:2] != (len(q), 3) or so.shape[2] != k:
            raise ParameterError(f"mode_animation_html: overlay shapes must have shape "
                                 f"({len(q)}, {k}) or ({len(q)}, 3, {k}), got "
                                 f"{np.asarray(overlay['shapes']).shape}")
        eo = mesh_edges(q) if overlay.get("edges") is None else np.asarray(overlay["edges"])
        oname = str(overlay.get("name", "test"))
        layers.append({"name": oname, "xyz": _round(q, 6), "edges": np.asarray(eo).tolist(),
                       "color": "#c0392b", "width": 2.0, "points": True,
                       "modes": modes_of(so)})
        legend.append(f'<span style="color:#c0392b">&#9632; {html.escape(oname)}</span>')
    options = "".join(f'<option value="{j}">{html.escape(str(lab))}</option>'
                      for j, lab in enumerate(labels))
    payload = json.dumps({"layers": layers}, separators=(",", ":")).replace("</", "<\\/")
    return (f'<div class="mode-animation"><div class="controls">'
            f'<label>Mode <select id="{element_id}-mode">{options}</select></label> '
            f'<button type="button" id="{element_id}-play">pause</button> '
            f'{" ".join(legend)} <span class="hint">(drag to rotate)</span></div>'
            f'<canvas id="{element_id}" width="900" height="450" '
            'style="width:100%;border:1px solid #ddd;touch-action:none"></canvas>'
            f'<script type="application/json" id="{element_id}-data">{payload}</script>'
            f"<script>{_SCRIPT % {'id': element_id}}</script></div>")
