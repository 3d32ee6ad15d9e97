"""Mode labels from strain energy and, for shells, from the motion normal to the surface.

A mode is labelled by the largest part of its strain energy (:func:`energy_split`):
``bending``, ``torsion``, ``in-plane`` (membrane) or ``axial``. On a flat plate that is
unambiguous. On a curved shell a flexural mode (the surface moving along its normal, what
a test engineer calls a bending or shell mode) stores much of its strain energy in
membrane stretching: 35-47 % for the first ten modes of the example curved panel, where
it was the largest part in 7 of them. Such a mode is not "in-plane" in any sense a reader
would expect. So when the membrane part is the largest, the label is decided by where
the mode's kinetic energy is: if the translations normal to the shell surface carry at
least half of the shells' translational kinetic energy, the mode is flexural and gets
the larger of its bending and torsion parts; otherwise it is ``in-plane``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["label_modes", "shell_node_normals", "normal_kinetic_fraction"]

#: Normal-motion share of the shells' translational kinetic energy from which a
#: membrane-dominated mode is labelled flexural (bending/torsion) rather than in-plane.
FLEXURAL_SHARE = 0.5


def shell_node_normals(model) -> np.ndarray | None:
    """Unit surface normal at every node of the model's shells (zero at other nodes).

    Element normals (cross product of the diagonals of a quad, of two edges of a
    triangle; their length is twice the element area) are summed at the element's nodes,
    so a node's normal is the area-weighted mean of its elements'. Where the elements
    of a node face opposite ways (inconsistent orientation), their normals are aligned
    with the node's first element before summing. Returns None for a model without
    shell elements.
    """
    normals = np.zeros((model.n_nodes, 3))
    found = False
    for kind in ("mitc4", "mitc3"):
        conn = model.elements.get(kind)
        if conn is None or len(conn) == 0:
            continue
        found = True
        xyz = model.nodes[conn]
        if conn.shape[1] == 4:
            n_el = np.cross(xyz[:, 2] - xyz[:, 0], xyz[:, 3] - xyz[:, 1])
        else:
            n_el = np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0])
        # orientation: an element's normal is only defined up to sign; align each with
        # the running sum at its first node so that opposite windings do not cancel
        ref = np.zeros((model.n_nodes, 3))
        np.add.at(ref, conn[:, 0], n_el)
        sign = np.sign(np.einsum("ij,ij->i", n_el, ref[conn[:, 0]]))
        sign[sign == 0] = 1.0
        n_el = n_el * sign[:, None]
        for j in range(conn.shape[1]):
            np.add.at(normals, conn[:, j], n_el)
    if not found:
        return None
    length = np.linalg.norm(normals, axis=1)
    on = length > 0
    normals[on] /= length[on, None]
    return normals


def normal_kinetic_fraction(model, shapes: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Share of the shells' translational kinetic energy in motion normal to the surface.

    Each mode's translations at the shell nodes are split into the part along the node
    normal and the tangential rest; the kinetic energies ``phi' M phi`` of the two parts
    (rotations and non-shell nodes left out) give the share ``T_n / (T_n + T_t)``.

    Parameters
    ----------
    model : FEModel
    shapes : ndarray, shape (n_dof, n_modes)
    normals : ndarray, shape (n_nodes, 3)
        From :func:`shell_node_normals`.

    Returns
    -------
    ndarray, shape (n_modes,)
        In [0, 1]; NaN for a mode without translation at the shell nodes.
    """
    phi = np.atleast_2d(np.asarray(shapes, dtype=float).T).T
    k = phi.shape[1]
    full = model.expand(phi).reshape(model.n_nodes, 6, k)
    u = full[:, :3, :]
    un = np.einsum("nc,nck->nk", normals, u)
    u_n = normals[:, :, None] * un[:, None, :]
    u_t = (u - u_n) * (np.linalg.norm(normals, axis=1) > 0)[:, None, None]
    share = np.full(k, np.nan)
    parts = []
    for part in (u_n, u_t):
        g = np.zeros((model.n_nodes, 6, k))
        g[:, :3, :] = part
        v = _restrict(model, g.reshape(model.n_nodes * 6, k))
        parts.append(np.einsum("ik,ik->k", v, model.M @ v))
    total = parts[0] + parts[1]
    ok = total > 0
    share[ok] = parts[0][ok] / total[ok]
    return share


def _restrict(model, full: np.ndarray) -> np.ndarray:
    """Full (n_nodes*6, k) DOF vectors -> the model's free DOFs (model.expand's inverse)."""
    idx = np.asarray(model.dof_node) * 6 + np.asarray(model.dof_component)
    return full[idx]


def label_modes(model, shapes: np.ndarray, split: np.ndarray, parts) -> list[str | None]:
    """Labels of elastic modes from their strain-energy split (None where it is undefined).

    Parameters
    ----------
    model : FEModel
    shapes : ndarray, shape (n_dof, n_modes)
    split : ndarray, shape (n_modes, 4)
        :func:`mvtk.fe.energy_split` of ``shapes``.
    parts : sequence of str
        The names of the split's columns (:data:`mvtk.fe.ENERGY_PARTS`).

    Returns
    -------
    list
        A label per mode; None where the split is not finite or zero (the caller falls
        back to a label from the kinetic energy per DOF component).
    """
    parts = list(parts)
    labels: list[str | None] = []
    membrane = parts.index("in-plane")
    normals = None
    for i, e in enumerate(split):
        if not (np.all(np.isfinite(e)) and e.sum() > 0):
            labels.append(None)
            continue
        best = int(np.argmax(e))
        if best == membrane:
            if normals is None:
                normals = shell_node_normals(model)
            if normals is not None:
                share = normal_kinetic_fraction(model, shapes[:, i], normals)[0]
                if np.isfinite(share) and share >= FLEXURAL_SHARE:
                    best = parts.index("bending") if e[parts.index("bending")] >= e[
                        parts.index("torsion")] else parts.index("torsion")
        labels.append(parts[best])
    return labels
