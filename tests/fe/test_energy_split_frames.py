"""energy_split on flat elements rotates node vectors by the element frame directly
(identity frame skipped, a common frame applied once); the parts must not depend on the
frame: a plate in its own plane, a rotated and shifted copy (frames differ by
round-off), the same plate built by the general assembly, and the strain energy."""

import numpy as np
from scipy.spatial.transform import Rotation

import mvtk.fe as fe
from mvtk.fe import _modal as modal

STEEL = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
ROT = Rotation.from_euler("zyx", [31.0, -47.0, 68.0], degrees=True).as_matrix()


def test_energy_split_is_frame_independent():
    mesh = fe.rectangular_plate_mesh(0.3, 0.2, nx=9, ny=6)
    lam = fe.Laminate([fe.Ply(STEEL, 2e-3)])

    def build(nodes, axis=(1.0, 0.0, 0.0)):
        return fe.assemble_model(nodes, [fe.ShellSet(mesh.elements, lam, axis)],
                                 supports={"x0": "clamped"}, node_sets=mesh.node_sets)

    m0 = build(mesh.nodes)
    m1 = build(mesh.nodes @ ROT.T + 1.0, ROT[:, 0])
    r0 = fe.modal_analysis(m0, 6)
    r1 = fe.modal_analysis(m1, 6)
    e0 = modal.energy_split(m0, r0.shapes)
    e1 = modal.energy_split(m1, r1.shapes)
    scale = e0.sum(axis=1, keepdims=True)
    np.testing.assert_allclose(e1 / scale, e0 / scale, atol=1e-8)
    # isotropic plate: the parts add up to the modal strain energy omega^2 (phi' M phi = 1)
    np.testing.assert_allclose(e0.sum(axis=1), r0.omega2, rtol=1e-6)
    np.testing.assert_allclose(e1.sum(axis=1), r1.omega2, rtol=1e-6)


def test_energy_split_on_a_faceted_cylinder_panel():
    """Flat quads whose frames all differ (a 60-degree cylindrical panel): the parts of
    an isotropic shell add up to the modal strain energy, and the elementwise-frame
    path equals the general transformation (forced through the warped-element branch)."""
    R, n_t, n_z = 0.5, 8, 6
    th = np.linspace(0.0, np.pi / 3, n_t + 1)
    z = np.linspace(0.0, 0.4, n_z + 1)
    T, Z = np.meshgrid(th, z, indexing="ij")
    nodes = np.column_stack([R * np.cos(T).ravel(), R * np.sin(T).ravel(), Z.ravel()])
    i, j = np.meshgrid(np.arange(n_t), np.arange(n_z), indexing="ij")
    base = (i * (n_z + 1) + j).ravel()
    quads = np.column_stack([base, base + n_z + 1, base + n_z + 2, base + 1])
    lam = fe.Laminate([fe.Ply(STEEL, 2e-3)])
    model = fe.assemble_model(nodes, [fe.ShellSet(quads, lam, (0.0, 0.0, 1.0))],
                              supports={"edge": "clamped"},
                              node_sets={"edge": np.arange(n_z + 1)})
    res = fe.modal_analysis(model, 6)
    e = modal.energy_split(model, res.shapes)
    np.testing.assert_allclose(e.sum(axis=1), res.omega2, rtol=1e-6)


def test_energy_split_frame_paths_agree(monkeypatch):
    """The direct rotation of node vectors equals the block transformation T that the
    warped-element branch applies (forced by a non-zero warping test). The plate lies in
    the x-z plane (a rotation by 90 degrees about x, exact in floating point, so the
    elements are exactly flat and share one frame, which is not the identity; a general
    rotation leaves round-off out of plane and takes the T branch anyway)."""
    mesh = fe.rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    lam = fe.Laminate([fe.Ply(STEEL, 2e-3)])
    P = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    model = fe.assemble_model(mesh.nodes @ P.T, [fe.ShellSet(mesh.elements, lam,
                                                              (1.0, 0.0, 0.0))],
                              supports={"x0": "clamped"}, node_sets=mesh.node_sets)
    V = np.random.default_rng(5).standard_normal((model.n_dof, 4))
    direct = modal.energy_split(model, V)
    import mvtk.fe._shell3d as s3

    real = s3._local_frames

    def warped(xyz, axis):
        local, Rf = real(xyz, axis)
        local = local.copy()
        local[:, 0, 2] += 1e-300                          # takes the T branch
        return local, Rf

    monkeypatch.setattr(s3, "_local_frames", warped)
    general = modal.energy_split(model, V)
    np.testing.assert_allclose(direct, general, rtol=1e-10, atol=1e-12 * np.abs(general).max())
