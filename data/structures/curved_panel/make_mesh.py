"""Regenerate curved_panel.msh: a stiffened cylindrical panel (Gmsh 2.2 ASCII, via meshio).

Run from anywhere: ``python data/structures/curved_panel/make_mesh.py``. Deterministic (no
random numbers). Geometry: radius 0.5 m, 60 degree arc, length 0.4 m along x; the arc
lies in the y-z plane, centred on z. Physical groups:

- ``skin`` (2-D): 20 x 16 first-order quads;
- ``stiffener`` (1-D): the line elements along x on the mid-arc line;
- ``ends`` (1-D): the two curved edges x = 0 and x = 0.4 m (supports).
"""

from pathlib import Path

import meshio
import numpy as np

R, ARC_DEG, LENGTH, NX, NA = 0.5, 60.0, 0.4, 20, 16


def build() -> meshio.Mesh:
    x = np.linspace(0.0, LENGTH, NX + 1)
    th = np.radians(np.linspace(-ARC_DEG / 2, ARC_DEG / 2, NA + 1))
    X, T = np.meshgrid(x, th, indexing="ij")  # node (i, j) -> i * (NA + 1) + j
    pts = np.column_stack([X.ravel(), R * np.sin(T.ravel()), R * np.cos(T.ravel())])
    i, j = np.meshgrid(np.arange(NX), np.arange(NA), indexing="ij")
    n00 = (i * (NA + 1) + j).ravel()
    quads = np.column_stack([n00, n00 + NA + 1, n00 + NA + 2, n00 + 1])
    mid = np.arange(NX + 1) * (NA + 1) + NA // 2
    stiff = np.column_stack([mid[:-1], mid[1:]])
    e0 = np.arange(NA + 1)
    e1 = NX * (NA + 1) + np.arange(NA + 1)
    ends = np.vstack([np.column_stack([e0[:-1], e0[1:]]), np.column_stack([e1[:-1], e1[1:]])])
    lines = np.vstack([stiff, ends])
    phys = [np.full(len(quads), 1), np.r_[np.full(len(stiff), 2), np.full(len(ends), 3)]]
    return meshio.Mesh(
        pts, [("quad", quads), ("line", lines)],
        cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
        field_data={"skin": np.array([1, 2]), "stiffener": np.array([2, 1]),
                    "ends": np.array([3, 1])},
    )


if __name__ == "__main__":
    out = Path(__file__).with_name("curved_panel.msh")
    build().write(out, file_format="gmsh22", binary=False)
    print(f"wrote {out}")
