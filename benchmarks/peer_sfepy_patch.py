"""3-D coupled-field peer of a partial-width piezo patch on a cantilever plate (SfePy).

The same geometry as ``tests/fe/test_electro.py::test_partial_width_patch_matches_3d_peer``:
a steel cantilever plate 100 x 40 x 1 mm clamped at x = 0, a PZT patch 0.25 mm thick
from x = 10 to 60 mm and y = 10 to 30 mm (half the width) bonded on top, electrodes on
the patch faces. SfePy (https://sfepy.org, BSD) solves 3-D linear piezoelasticity
(displacement + electric potential) on triquadratic hexahedra; the printed number is
the mean tip deflection per volt of the plate's mid-surface edge at x = 40 mm, with the
voltage applied along the patch's poling (+z). Run with SfePy installed
(``pip install sfepy``)::

    python benchmarks/peer_sfepy_patch.py [element size, m]

Results (SfePy 2026.3): 7.1225e-07 m/V with 2.5 mm elements (44 277 DOFs), 7.0817e-07
m/V with 1.25 mm (173 013 DOFs), against mvtk's MITC4 shells 7.184e-07 m/V (+0.9 %,
+1.4 %).

The 3-D material is the plane-stress shell's: isotropic elastic (E, nu at constant
field), d31 = d32, d33 = d15 = 0 (neither enters the shell's bending), eps33^T; its
e-form constants follow from ``e = d c``, ``eps^S = eps^T - d c d'``.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

E_ST, NU_ST = 210e9, 0.30
E_P, NU_P, D31, EPS33 = 66.667e9, 0.34, -210e-12, 2400 * 8.8541878128e-12
L, B, T_ST, T_P = 0.1, 0.04, 1e-3, 0.25e-3
PX, PY = (0.01, 0.06), (0.01, 0.03)


def _lines(a, b, breaks, h):
    pts = sorted({a, b, *breaks})
    out = [pts[0]]
    for p, q in zip(pts[:-1], pts[1:]):
        n = max(1, int(np.ceil((q - p) / h - 1e-9)))
        out += list(np.linspace(p, q, n + 1)[1:])
    return np.array(out)


def mesh_arrays(h=2.5e-3, nz_steel=2, nz_pzt=1):
    xs = _lines(0.0, L, PX, h)
    ys = _lines(0.0, B, PY, h)
    zs = np.concatenate([np.linspace(0, T_ST, nz_steel + 1),
                         np.linspace(T_ST, T_ST + T_P, nz_pzt + 1)[1:]])
    nx, ny, nz = len(xs), len(ys), len(zs)
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    coors = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])

    def nid(i, j, k):
        return (i * ny + j) * nz + k

    conn, mat = [], []
    for i in range(nx - 1):
        for j in range(ny - 1):
            for k in range(nz - 1):
                xc, yc = 0.5 * (xs[i] + xs[i + 1]), 0.5 * (ys[j] + ys[j + 1])
                piezo = k >= nz_steel
                if piezo and not (PX[0] < xc < PX[1] and PY[0] < yc < PY[1]):
                    continue
                conn.append([nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k),
                             nid(i, j + 1, k), nid(i, j, k + 1), nid(i + 1, j, k + 1),
                             nid(i + 1, j + 1, k + 1), nid(i, j + 1, k + 1)])
                mat.append(2 if piezo else 1)
    conn = np.array(conn)
    used = np.unique(conn)
    renum = np.full(len(coors), -1)
    renum[used] = np.arange(len(used))
    return coors[used], renum[conn], np.array(mat)


def solve(order=2, h=2.5e-3):
    from sfepy.base.base import output
    from sfepy.discrete import Equation, Equations, FieldVariable, Integral, Material, Problem
    from sfepy.discrete.conditions import Conditions, EssentialBC
    from sfepy.discrete.fem import FEDomain, Field, Mesh
    from sfepy.mechanics.matcoefs import stiffness_from_youngpoisson
    from sfepy.solvers.ls import ScipyDirect
    from sfepy.solvers.nls import Newton
    from sfepy.terms import Term

    output.set_output(quiet=True)
    coors, conn, mat = mesh_arrays(h)
    mesh = Mesh.from_data("plate", coors, None, [conn], [mat], ["3_8"])
    domain = FEDomain("d", mesh)
    omega = domain.create_region("Omega", "all")
    pzt = domain.create_region("Pzt", "cells of group 2")
    eps = 1e-9
    clamp = domain.create_region("Clamp", f"vertices in (x < {eps})", "facet")
    top = domain.create_region("Top", f"vertices in (z > {T_ST + T_P - eps})", "facet",
                               parent="Pzt")
    bot = domain.create_region("Bot", f"vertices in (z < {T_ST + eps}) & (z > {T_ST - eps})",
                               "facet", parent="Pzt")
    fu = Field.from_args("u", np.float64, 3, omega, approx_order=order)
    fp = Field.from_args("phi", np.float64, 1, pzt, approx_order=order)
    u = FieldVariable("u", "unknown", fu)
    v = FieldVariable("v", "test", fu, primary_var_name="u")
    phi = FieldVariable("phi", "unknown", fp)
    psi = FieldVariable("psi", "test", fp, primary_var_name="phi")

    # sfepy's 3-D Voigt order: 11, 22, 33, 12, 13, 23
    c_st = stiffness_from_youngpoisson(3, E_ST, NU_ST)
    c_p = stiffness_from_youngpoisson(3, E_P, NU_P)
    d = np.zeros((3, 6))
    d[2, 0] = d[2, 1] = D31
    e = d @ c_p
    # PEER_EPS_SCALE (diagnostic, default 1) multiplies the permittivity: a large value
    # forces the through-thickness uniform field the shell theory assumes
    eps_s = (np.diag([EPS33, EPS33, EPS33]) - d @ c_p @ d.T) * float(
        os.environ.get("PEER_EPS_SCALE", "1"))
    m_st = Material("st", D=c_st)
    m_p = Material("p", D=c_p, coupling=e, dielectric=eps_s)
    integral = Integral("i", order=2 * order)
    steel = domain.create_region("Steel", "cells of group 1")
    t1 = Term.new("dw_lin_elastic(st.D, v, u)", integral, steel, st=m_st, v=v, u=u)
    t2 = Term.new("dw_lin_elastic(p.D, v, u)", integral, pzt, p=m_p, v=v, u=u)
    t3 = Term.new("dw_piezo_coupling(p.coupling, v, phi)", integral, pzt, p=m_p, v=v,
                  phi=phi)
    t4 = Term.new("dw_piezo_coupling(p.coupling, u, psi)", integral, pzt, p=m_p, u=u,
                  psi=psi)
    t5 = Term.new("dw_diffusion(p.dielectric, psi, phi)", integral, pzt, p=m_p, psi=psi,
                  phi=phi)
    eqs = Equations([Equation("mech", t1 + t2 - t3), Equation("elec", t4 + t5)])
    # +1 V along the poling (+z): the field -grad(phi) points along +z
    bcs = Conditions([EssentialBC("fix", clamp, {"u.all": 0.0}),
                      EssentialBC("bot", bot, {"phi.0": 1.0}),
                      EssentialBC("top", top, {"phi.0": 0.0})])
    pb = Problem("piezo", equations=eqs)
    pb.set_bcs(ebcs=bcs)
    pb.set_solver(Newton({"i_max": 1, "eps_a": 1e-30, "eps_r": 1.0},
                         lin_solver=ScipyDirect({})))
    state = pb.solve(save_results=False)
    uu = state.get_state_parts()["u"].reshape(-1, 3)
    xyz = fu.get_coor()
    tip = (np.abs(xyz[:, 0] - L) < 1e-7) & (np.abs(xyz[:, 2] - T_ST / 2) < 1e-7)
    return float(uu[tip, 2].mean()), int(tip.sum()), int(len(uu) * 3)


if __name__ == "__main__":
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 2.5e-3
    w, n_tip, n_dof = solve(2, h)
    print(json.dumps({"tip_uz_per_volt_m": w, "tip_points": n_tip, "n_dof": n_dof,
                      "element_size_m": h, "order": 2}))
