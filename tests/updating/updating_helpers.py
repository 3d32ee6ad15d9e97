"""A small, fast test builder: layered-free Euler-Bernoulli + St-Venant torsion cantilever.

``strip_model(description) -> FEModel`` builds a thin strip of length L (x), width b (y)
and thickness t (z), clamped at x = 0 through a rotational spring ``clamp_stiffness``
(N m/rad) on ry (omit the key for a rigid clamp), with an optional tip mass (kg). DOFs per
node: uz, rx, ry. Bending: Hermite beam elements (EI = E b t^3 / 12, consistent mass);
torsion: linear elements (GJ with J = b t^3 / 3, G = E / (2 (1 + nu)), polar mass
rho (b t^3 + t b^3) / 12 per length).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from mvtk.fe import FEModel

NOMINAL = {
    "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    "structure": {"length": 0.18, "width": 0.05, "thickness": 5e-4, "n_elements": 12},
    "boundary": {"clamp_stiffness": 6.0},
    "tip_mass": 0.002,
    "patches": [{"x0": 0.01, "length": 0.05}],
}


def strip_model(d) -> FEModel:
    mat = d["materials"]["steel"]
    s = d["structure"]
    E, nu, rho = mat["E"], mat["nu"], mat["rho"]
    L, b, t, ne = s["length"], s["width"], s["thickness"], int(s["n_elements"])
    le = L / ne
    EI = E * b * t**3 / 12
    GJ = E / (2 * (1 + nu)) * b * t**3 / 3
    rA = rho * b * t
    rIp = rho * (b * t**3 + t * b**3) / 12
    kb = EI / le**3 * np.array([
        [12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
        [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    mb = rA * le / 420 * np.array([
        [156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
        [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    kt = GJ / le * np.array([[1, -1], [-1, 1]])
    mt = rIp * le / 6 * np.array([[2, 1], [1, 2]])
    nn = ne + 1
    # global numbering over all nodes: per node (uz, rx, ry); vectorised assembly
    ndof = 3 * nn
    e = np.arange(ne)[:, None]
    bi = np.hstack([3 * e, 3 * e + 2, 3 * e + 3, 3 * e + 5])  # (ne, 4)
    ti = np.hstack([3 * e + 1, 3 * e + 4])  # (ne, 2)

    def assemble(kb_, kt_):
        rows = np.concatenate([np.repeat(bi, 4, axis=1).ravel(), np.repeat(ti, 2, axis=1).ravel()])
        cols = np.concatenate([np.tile(bi, 4).ravel(), np.tile(ti, 2).ravel()])
        vals = np.concatenate([np.tile(kb_.ravel(), ne), np.tile(kt_.ravel(), ne)])
        return sp.coo_matrix((vals, (rows, cols)), shape=(ndof, ndof)).toarray()

    K = assemble(kb, kt)
    M = assemble(mb, mt)
    M[3 * ne, 3 * ne] += d.get("tip_mass", 0.0)
    kr = d.get("boundary", {}).get("clamp_stiffness")
    fixed = [0, 1]  # uz and rx of the root
    if kr is None:
        fixed.append(2)
    else:
        K[2, 2] += kr
    free = np.setdiff1d(np.arange(ndof), fixed)
    comp_of = np.array([2, 3, 4] * nn)
    node_of = np.repeat(np.arange(nn), 3)
    nodes = np.column_stack([np.linspace(0, L, nn), np.zeros(nn), np.zeros(nn)])
    return FEModel(
        nodes=nodes,
        M=sp.csr_matrix(M[np.ix_(free, free)]),
        K=sp.csr_matrix(K[np.ix_(free, free)]),
        dof_node=node_of[free],
        dof_component=comp_of[free],
        node_sets={"tip": np.array([nn - 1])},
        elements={"beam2": np.column_stack([np.arange(ne), np.arange(1, nn)])},
        name="strip",
    )


def model_fn(d, n=8):
    from mvtk.fe import eigsh_lowest

    m = strip_model(d)
    eig = eigsh_lowest(m.K, m.M, n)
    return np.sqrt(eig.omega2) / (2 * np.pi), eig, m
