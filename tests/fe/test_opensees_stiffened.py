"""Stiffened plate (MITC4 shells + offset Timoshenko beams) against OpenSeesPy, same mesh.

External truth: OpenSees (McKenna, Fenves & Scott, openseespy 3.7) on the identical mesh.

Model: a 0.6 m x 0.4 m steel plate, 3 mm thick, 12 x 8 MITC4 quads, clamped along x = 0,
with two tube stiffeners (8 mm / 6 mm radii) along x at y = b/4 and 3b/4 whose axes
hang ``h/2 + r_o`` below the plate mid-surface.

Modelling choice in OpenSees, made to reproduce mvtk's offset-beam kinematics exactly:

- shells: ``ShellMITC4`` with ``ElasticMembranePlateSection`` (shear factor 5/6, as
  mvtk's laminate);
- stiffeners: ``ElasticTimoshenkoBeam`` with ``-cMass`` (exact two-node Timoshenko
  stiffness and the consistent Przemieniecki mass with rotary inertia, the matrices mvtk's
  interdependent-interpolation element gives) on **separate nodes at the offset axis**,
  each tied to its shell node by ``rigidLink("beam", ...)`` and eliminated with the
  ``Transformation`` constraint handler: ``u_beam = u_shell + theta x e``,
  ``theta_beam = theta_shell``, which is the map mvtk applies inside
  :class:`mvtk.fe.BeamSet` (joint offsets of ``geomTransf`` are ignored by
  ElasticTimoshenkoBeam3d, so they cannot be used);
- a circular tube, because OpenSees' torsional inertia is ``rho J`` and mvtk's is the
  polar ``rho (Iy + Iz)``: for a circular tube ``J = Iy + Iz``, so the section is the
  same in both codes.

The assembled OpenSees matrices are read with the ``GimmeMCK`` integrator and
``printA`` and mapped to mvtk's DOFs with ``nodeDOFs``.

Findings (asserted below):

- with mvtk's drilling penalty set to OpenSees' (``gamma_d = A66``, ``drill_factor=1``),
  the stiffness matrices are identical to round-off (1e-15), offsets included;
- the mass matrices differ only in the shell rotary inertia ``rho h^3 / 12`` that
  ShellMITC4 omits (mvtk keeps it); mvtk's stiffness with OpenSees' mass reproduces
  OpenSees' own eigenvalues to 1e-10, and the two codes' own frequencies agree to 3e-4;
- with mvtk's default penalty (``drill_factor=1e-3``) the frequencies of modes with
  in-plane participation are lower by up to 5 % (mode 2, torsion of the stiffened plate)
  on this coarse mesh: the stiffener offset couples bending to the membrane field, and
  the membrane stiffness of a coarse Q4 grows with the drilling penalty. Refining the mesh
  shows that the default is the better choice: mode 2 reads 48.16, 47.99, 47.94, 47.91 Hz
  on 12x8, 24x16, 48x32, 96x64 meshes with the default, and 50.50, 50.89, 50.13, 49.26 Hz
  with OpenSees' penalty (not even monotonic).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

from mvtk.fe import (
    DRILL_FACTOR,
    BeamSet,
    IsotropicMaterial,
    Laminate,
    Ply,
    ShellSet,
    assemble_model,
    tube_section,
)

E, NU, RHO, H = 210e9, 0.3, 7850.0, 0.003
A, B, NX, NY = 0.6, 0.4, 12, 8
RO, RI = 0.008, 0.006
OFFSET = np.array([0.0, 0.0, -(H / 2 + RO)])
N_MODES = 8


def _mesh():
    xs, ys = np.linspace(0.0, A, NX + 1), np.linspace(0.0, B, NY + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(NX), np.arange(NY), indexing="ij")
    base = (i * (NY + 1) + j).ravel()
    quads = np.column_stack([base, base + NY + 1, base + NY + 2, base + 1])
    beams = np.array([[k * (NY + 1) + j, (k + 1) * (NY + 1) + j]
                      for j in (NY // 4, 3 * NY // 4) for k in range(NX)])
    clamp = np.arange(NY + 1)  # nodes on x = 0
    return nodes, quads, beams, clamp


def _mvtk_model(drill_factor):
    nodes, quads, beams, clamp = _mesh()
    steel = IsotropicMaterial("steel", E, NU, RHO)
    members = [ShellSet(quads, Laminate([Ply(steel, H)]), name="plate"),
               BeamSet(beams, tube_section(steel, RO, RI), orientation=(0.0, 1.0, 0.0),
                       offset=OFFSET, name="stiffeners")]
    return assemble_model(nodes, members, supports={"clamp": "clamped"},
                          node_sets={"clamp": clamp}, drill_factor=drill_factor)


def _fn_lowest(K, M, n=N_MODES):
    """Lowest n frequencies (Hz) of K x = w^2 M x by shift-invert Lanczos about 0 (K is
    positive definite, M may be singular: ShellMITC4 has no rotary inertia)."""
    w2 = eigsh(sp.csc_matrix(K), n, sp.csc_matrix(M), sigma=0.0, which="LM",
               return_eigenvectors=False)
    return np.sqrt(np.sort(w2)) / (2 * np.pi)


@pytest.fixture(scope="module")
def opensees():
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError) as err:  # RuntimeError: Debian libblas3/liblapack3
        pytest.skip(f"OpenSeesPy is not usable here: {err}")
    nodes, quads, beams, clamp = _mesh()
    steel = IsotropicMaterial("steel", E, NU, RHO)
    sec = tube_section(steel, RO, RI)
    G = E / (2 * (1 + NU))
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for k, p in enumerate(nodes):
        ops.node(k + 1, *map(float, p))
    for k in clamp:
        ops.fix(int(k) + 1, 1, 1, 1, 1, 1, 1)
    ops.section("ElasticMembranePlateSection", 1, E, NU, H, RHO)
    for e, q in enumerate(quads):
        ops.element("ShellMITC4", e + 1, *(int(n) + 1 for n in q), 1)
    ops.geomTransf("Linear", 1, 0.0, 0.0, 1.0)  # local z = global z: local y = global y
    axis_node = {}
    for k in np.unique(beams):
        axis_node[k] = len(nodes) + 1 + len(axis_node)
        ops.node(axis_node[k], *map(float, nodes[k] + OFFSET))
        ops.rigidLink("beam", int(k) + 1, axis_node[k])
    for e, (a, b) in enumerate(beams):
        ops.element("ElasticTimoshenkoBeam", 10_000 + e, axis_node[a], axis_node[b], E, G,
                    sec.EA / E, sec.GJ / G, sec.EIy / E, sec.EIz / E, sec.kGAy / G,
                    sec.kGAz / G, 1, "-mass", sec.rhoA, "-cMass")
    ops.constraints("Transformation")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.algorithm("Linear")
    ops.analysis("Transient")
    mats = {}
    for name, factors in (("K", (0.0, 0.0, 1.0)), ("M", (1.0, 0.0, 0.0))):
        ops.integrator("GimmeMCK", *factors)
        ops.analyze(1, 0.0)  # forms the matrix; its solve may fail (singular M): unused
        n = ops.systemSize()
        mats[name] = np.array(ops.printA("-ret")).reshape(n, n)
    ref = _mvtk_model(1.0)
    eq = np.array([ops.nodeDOFs(int(n) + 1)[c]
                   for n, c in zip(ref.dof_node, ref.dof_component)])
    ops.wipeAnalysis()
    ops.constraints("Transformation")
    ops.numberer("Plain")
    ops.system("BandGen")
    fn = np.sqrt(np.array(ops.eigen(N_MODES))) / (2 * np.pi)
    ops.wipe()
    assert sorted(eq) == list(range(len(eq))), "OpenSees and mvtk free DOFs differ"
    return {"K": mats["K"][np.ix_(eq, eq)], "M": mats["M"][np.ix_(eq, eq)], "fn": fn}


def test_stiffness_identical_with_opensees_drilling_penalty(opensees):
    model = _mvtk_model(1.0)
    K = model.K.toarray()
    assert np.abs(opensees["K"] - K).max() <= 1e-12 * np.abs(K).max()


def test_mass_differs_only_by_shell_rotary_inertia(opensees):
    model = _mvtk_model(1.0)
    M = model.M.toarray()
    D = opensees["M"] - M
    c = model.dof_component
    rot = np.isin(c, (3, 4))  # rx, ry: ShellMITC4 carries no rotary inertia rho h^3/12
    scale = np.abs(M).max()
    assert np.abs(D[np.ix_(~rot, ~rot)]).max() <= 1e-12 * scale
    assert np.abs(D[np.ix_(rot, ~rot)]).max() <= 1e-12 * scale
    # what is missing is mvtk's consistent rotary inertia I2 = rho h^3 / 12: for a unit
    # rotation of every free node, 2T = I2 * integral (sum of free shape functions)^2 dA
    # = I2 * B * (A - 2 dx / 3) (a linear ramp over the column of elements at the clamp)
    dx = A / NX
    for comp in (3, 4):
        sel = c == comp
        ones = np.ones(sel.sum())
        missing = ones @ (-D[np.ix_(sel, sel)]) @ ones
        assert missing == pytest.approx(RHO * H**3 / 12 * B * (A - 2 * dx / 3), rel=1e-9)


def test_frequencies_against_opensees(opensees):
    model = _mvtk_model(1.0)
    K, M = model.K.toarray(), model.M.toarray()
    # mvtk's stiffness with OpenSees' mass reproduces OpenSees' own eigen solution
    np.testing.assert_allclose(_fn_lowest(K, opensees["M"]), opensees["fn"], rtol=1e-9)
    # each code with its own mass: only the shell rotary inertia separates them
    np.testing.assert_allclose(_fn_lowest(K, M), opensees["fn"], rtol=3e-4)


def test_default_drilling_penalty_is_softer_on_coarse_mesh(opensees):
    """mvtk's default gamma_d = 1e-3 A66 against OpenSees' A66 (see the module docstring)."""
    model = _mvtk_model(DRILL_FACTOR)
    fn = _fn_lowest(model.K.toarray(), model.M.toarray())
    rel = fn / opensees["fn"] - 1
    assert np.all(rel < 0)              # a smaller penalty can only soften
    assert abs(rel[0]) < 1e-3           # first bending mode: little membrane action
    assert -0.06 < rel.min() < -0.03    # the torsion mode (2): 4.6 %, as explained
