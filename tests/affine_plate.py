"""The substructured plate of the affine-model tests (tests/fe, tests/updating).

An 8 x 4 MITC4 aluminium plate, 0.4 x 0.2 x 0.002 m, clamped on its x = 0 edge, whose
elements form two substructures: the ``left`` and ``right`` halves.
"""

from __future__ import annotations

import numpy as np

from mvtk.fe import IsotropicMaterial, Laminate, Ply, ShellSet, assemble_model

NX, NY, A, B, H = 8, 4, 0.4, 0.2, 0.002
LAMINATE = Laminate([Ply(IsotropicMaterial("al", 70e9, 0.33, 2700.0), H)])
NODE_SETS = {"clamp": np.arange(NY + 1)}


def plate_mesh() -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Node coordinates (m) and the quads of each half, ``{"left": ..., "right": ...}``."""
    X, Y = np.meshgrid(np.linspace(0, A, NX + 1), np.linspace(0, B, NY + 1), indexing="ij")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(NX), np.arange(NY), indexing="ij")
    base = (i * (NY + 1) + j).ravel()
    quads = np.column_stack([base, base + NY + 1, base + NY + 2, base + 1])
    return nodes, {"left": quads[i.ravel() < NX // 2], "right": quads[i.ravel() >= NX // 2]}


def assemble(nodes, halves: dict[str, np.ndarray], clamped: bool = True):
    """The model of the given halves (one shell set each), clamped at x = 0 or free."""
    return assemble_model(nodes, [ShellSet(q, LAMINATE, name=k) for k, q in halves.items()],
                          supports={"clamp": "clamped"} if clamped else None,
                          node_sets=NODE_SETS)


def dof_table(model) -> np.ndarray:
    """``(node id, DOF 1..6)`` per free DOF of ``model``, as read_matrices expects."""
    return np.column_stack([model.node_ids[model.dof_node], model.dof_component + 1])
