"""Converged first ten frequencies of the stiffened curved panel (curved_panel.toml).

Builds the panel of curved_panel.toml with mvtk's elements on structured meshes of the
same cylinder (numpy, no Gmsh): MITC9 on 20 x 16 (the shipped grid), 40 x 32 and
60 x 48 elements, and MITC4 on 80 x 64, and prints their frequencies (Hz). Output
(mvtk at the commit that added this file)::

    MITC9 20x16 : 122.146 122.669 232.261 232.318 307.209 329.578 366.639 367.358 450.058 450.559
    MITC9 40x32 : 121.811 122.331 231.062 231.119 306.729 329.022 364.008 364.720 448.037 448.570
    MITC9 60x48 : 121.778 122.298 230.949 231.005 306.695 328.980 363.755 364.466 447.893 448.470
    MITC4 80x64 : 122.034 122.559 231.591 231.647 308.424 330.845 365.065 365.808 451.707 453.154

The 60 x 48 MITC9 values changed by less than 0.07 % from 40 x 32 and are the converged
reference of tests/fe/test_mitc9.py; the much finer MITC4 mesh is within 0.9 % of them
(it converges from above). Run: ``python data/structures/curved_panel/reference_modes.py``
(about four minutes).
"""

import numpy as np

from mvtk.fe import (
    BeamSet,
    IsotropicMaterial,
    Laminate,
    Ply,
    PointMass,
    ShellSet,
    assemble_model,
    modal_analysis,
    rectangle_section,
)
from mvtk.fe._mitc9 import NODE_RS


def panel(nx: int, na: int, order: int):
    """The panel with nx x na elements, nine-node (order 2) or four-node (order 1)."""
    al = IsotropicMaterial("al", 70e9, 0.33, 2700.0)
    R, L = 0.5, 0.4
    m, k = order * nx + 1, order * na + 1
    X, P = np.meshgrid(np.linspace(0, L, m), np.radians(np.linspace(-30, 30, k)),
                       indexing="ij")
    nodes = np.column_stack([X.ravel(), R * np.sin(P).ravel(), R * np.cos(P).ravel()])
    idx = np.arange(m * k).reshape(m, k)
    if order == 2:
        els = np.array([[idx[2 * i + 1 + int(r), 2 * j + 1 + int(s)] for r, s in NODE_RS]
                        for i in range(nx) for j in range(na)])
    else:
        els = np.array([[idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]]
                        for i in range(nx) for j in range(na)])
    crown = idx[:, (k - 1) // 2]
    centre = int(np.argmin(np.linalg.norm(nodes - [0.2, 0.0, 0.5], axis=1)))
    return assemble_model(
        nodes, [ShellSet(els, Laminate((Ply(al, 1e-3),)), material_axis=(1, 0, 0)),
                BeamSet(np.column_stack([crown[:-1], crown[1:]]),
                        rectangle_section(al, 6e-3, 15e-3), orientation=(0, 1, 0),
                        offset=(0, 0, 8e-3)),
                PointMass(centre, 0.05)],
        supports={"ends": "clamped"}, node_sets={"ends": np.concatenate([idx[0], idx[-1]])})


if __name__ == "__main__":
    for nx, na, order in [(20, 16, 2), (40, 32, 2), (60, 48, 2), (80, 64, 1)]:
        f = modal_analysis(panel(nx, na, order), 10).fn_hz
        print(f"MITC{9 if order == 2 else 4} {nx}x{na} :", " ".join(f"{v:.3f}" for v in f))
