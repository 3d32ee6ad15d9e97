"""Pretest planning: effective independence, kinetic energy, exciters, read-back."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from correlation_helpers import cantilever_plate, grid_points, sdynpy_module

from mvtk import correlation as co
from mvtk.errors import ParameterError


def test_efi_identities_of_kammer_1991():
    """Kammer (1991): E_D = diag(Phi (Phi'Phi)^-1 Phi') is idempotent's diagonal, so
    0 <= E_D <= 1 and sum E_D = number of target modes; when as many sensors as modes
    remain every E_D is 1 (each sensor is needed for full rank)."""
    model, modal = cantilever_plate()
    cand = co.candidate_geometry(model)
    pl = co.effective_independence(model, modal, cand, 5, modes=range(1, 6))
    np.testing.assert_allclose(pl.scores["E_D"], 1.0, atol=1e-10)
    pl12 = co.effective_independence(model, modal, cand, 12, modes=range(1, 6))
    ed = pl12.scores["E_D"].to_numpy()
    assert np.all((ed >= -1e-12) & (ed <= 1 + 1e-12))
    assert ed.sum() == pytest.approx(5.0, abs=1e-10)
    # det(FIM) never increases as candidates are removed
    d = pl12.history["det_fim_after"].to_numpy()
    assert np.all(np.diff(d) <= 1e-12 * d[0])


def test_efi_near_exhaustive_optimum_on_small_problem():
    """Greedy EfI against the exhaustive search of max det(FIM) over all 4-of-14 sets."""
    model, modal = cantilever_plate()
    ids = co.fe_node_ids(model)
    rows = np.flatnonzero((np.isclose(model.nodes[:, 1], 0.2)) & (model.nodes[:, 0] > 0.05))
    cand = co.candidate_geometry(model, nodes=ids[rows][::2].tolist() + ids[rows][1::2][:3]
                                 .tolist())
    pl = co.effective_independence(model, modal, cand, 4, modes=[1, 2, 3])
    A = co.map_sensors(cand, model, method="nearest").observe(modal.shapes[:, :3])
    best = max(np.linalg.det(A[list(c)].T @ A[list(c)])
               for c in itertools.combinations(range(A.shape[0]), 4))
    assert pl.det_fim >= 0.9 * best


def test_efi_beats_uniform_grid_and_reads_back(tmp_path):
    """8 sensors for 6 target modes: EfI against a uniform 4 x 2 grid on the plate.

    (Against a denser, well-placed symmetric grid, e.g. 4 x 3 for 8 modes, the two are
    within a few per cent on the AutoMAC; EfI still has the larger det(FIM).)
    """
    model, modal = cantilever_plate()
    cand = co.candidate_geometry(model)
    pl = co.effective_independence(model, modal, cand, 8, modes=range(1, 7))
    grid = co.TestGeometry(np.arange(1, 9), grid_points(4, 2, 0.075, 0.3, 0.0, 0.2))
    grid = grid.with_sensors([(n, "+z") for n in grid.node])
    g = co.map_sensors(grid, model, method="nearest").project(modal).isel(mode=slice(0, 6))
    am_grid = co.automac(g).values - np.eye(6)
    am_efi = pl.automac.values - np.eye(6)
    assert am_efi.max() < 0.5 < 0.9 < am_grid.max()
    assert np.linalg.cond(pl.automac.values) < 0.2 * np.linalg.cond(co.automac(g).values)
    assert pl.det_fim > np.linalg.det(g.values @ g.values.T)
    assert not pl.quality["identifiable"].all() or am_efi.max() <= 0.25
    # output as a test geometry that the correlation reads back
    path = tmp_path / "efi.toml"
    pl.geometry.to_toml(path)
    back = co.read_test_geometry(path)
    assert back.dof_labels == pl.dof
    shapes = co.map_sensors(back, model).project(modal).isel(mode=slice(0, 6))
    np.testing.assert_allclose(co.automac(shapes).values, pl.automac.values, atol=1e-10)
    assert {"max_automac", "identifiable"} <= set(pl.quality.columns)


def test_kinetic_energy_and_exciter():
    model, modal = cantilever_plate()
    cand = co.candidate_geometry(model)
    ke = co.kinetic_energy_placement(model, modal, cand, 6, modes=range(1, 5))
    assert len(ke.dof) == 6 and (ke.scores["kinetic_energy"] > 0).all()
    ex = co.exciter_placement(model, modal, cand, 1, modes=range(1, 5))
    A = co.map_sensors(cand, model, method="nearest").observe(modal.shapes[:, :4])
    r = A**2 / (A**2).max(axis=0)
    assert ex.dof == [cand.dof_labels[int(np.argmax(r.min(axis=1)))]]
    # the exciter is away from the node lines of every target mode
    assert ex.scores["min_norm_residue"].iloc[0] > 0.1
    with pytest.raises(ParameterError, match="at least as many sensors as target modes"):
        co.effective_independence(model, modal, cand, 3, modes=range(1, 5))
    with pytest.raises(ParameterError, match="cannot place 10000 DOFs"):
        co.kinetic_energy_placement(model, modal, cand, 10000)


def test_efi_closed_form_for_sine_modes():
    """Discrete sine orthogonality: with N equally spaced candidates on a simply
    supported span and the exact modes sin(k pi i / (N + 1)), k = 1..m,
    Phi'Phi = (N + 1)/2 I, so E_D_i = 2/(N + 1) sum_k sin^2(k pi i / (N + 1))."""
    import scipy.sparse as sp

    from mvtk.fe import FEModel

    N, m = 15, 4
    i = np.arange(1, N + 1)
    model = FEModel(nodes=np.column_stack([i / (N + 1), 0 * i, 0 * i]),
                    M=sp.identity(N, format="csr"), K=sp.identity(N, format="csr"),
                    dof_node=np.arange(N), dof_component=np.full(N, 2))

    class Modes:
        vectors = np.sin(np.outer(i, np.arange(1, m + 1)) * np.pi / (N + 1))
        fn_hz = np.arange(1, m + 1) ** 2.0

    cand = co.candidate_geometry(model)
    pl = co.effective_independence(model, Modes, cand, N)  # nothing removed: E_D of all
    expected = 2 / (N + 1) * np.sum(Modes.vectors**2, axis=1)
    np.testing.assert_allclose(pl.scores["E_D"], expected, rtol=1e-12)
    # the first candidates EfI drops are the supports' neighbours (smallest E_D)
    pl8 = co.effective_independence(model, Modes, cand, 8)
    assert pl8.history["removed"].iloc[0] in ("1+z", "15+z")


def test_efi_matches_sdynpy_removal_by_removal():
    """Same candidates and modes in SDynPy's ``by_effective_independence``: the same
    final set and the same det(FIM) after every removal, uniaxial and triaxial (SDynPy
    scores a node by EfI3 = 1 - det(I - P_gg), Kammer & Tinker 2004).

    Candidates on one half of the plate (y < 0.1 m) so that no two candidates are
    mirror images with equal E_D, where the choice would be decided by round-off."""
    sdd = sdynpy_module("fem/sdynpy_dof.py")
    model, modal = cantilever_plate()
    ids = co.fe_node_ids(model)
    rows = np.flatnonzero((model.nodes[:, 1] < 0.099) & (model.nodes[:, 0] > 0.01))
    cand = co.candidate_geometry(model, nodes=ids[rows].tolist())
    A = co.map_sensors(cand, model, method="nearest").observe(modal.shapes[:, :6])
    pl = co.effective_independence(model, modal, cand, 10, modes=range(1, 7))
    keep, dets = sdd.by_effective_independence(10, A, return_efi=True)
    assert sorted(cand.dof_labels[i] for i in keep) == sorted(pl.dof)
    h = pl.history
    assert len(h) == len(dets) == A.shape[0] - 10
    np.testing.assert_allclose(h["det_fim_after"].to_numpy()[:-1], dets[1:], rtol=1e-8)
    # Kammer (1991): removing DOF i multiplies det(FIM) by (1 - E_D,i)
    before = np.concatenate([[np.linalg.det(A.T @ A)], h["det_fim_after"].to_numpy()[:-1]])
    np.testing.assert_allclose(h["det_fim_after"], before * (1 - h["E_D"]), rtol=1e-8)
    # Li, Li & Fritzen (2007): E_D is the kinetic energy (unit mass) of the
    # orthonormalised target modes Psi = Phi (Phi' Phi)^-1/2
    from scipy.linalg import sqrtm

    full = co.effective_independence(model, modal, cand, A.shape[0], modes=range(1, 7))
    Psi = A @ np.linalg.inv(sqrtm(A.T @ A).real)
    np.testing.assert_allclose(full.scores["E_D"], np.sum(Psi**2, axis=1), rtol=1e-10)

    # node groups of 3 DOFs (w and the two slopes: the plate's in-plane DOFs carry none
    # of these bending modes); here EfI3 keeps a different set than the sum of E_D would
    tri = co.candidate_geometry(model, nodes=ids[rows].tolist(),
                                directions=("+z", "+rx", "+ry"))
    A3 = co.map_sensors(tri, model, method="nearest").observe(modal.shapes[:, :6])
    pl3 = co.effective_independence(model, modal, tri, 3 * 7, modes=range(1, 7),
                                    triaxial=True)
    keep3, dets3 = sdd.by_effective_independence(7, A3.reshape(-1, 3, 6), return_efi=True)
    assert sorted(int(tri.node[i]) for i in keep3) == sorted(pl3.geometry.node.tolist())
    np.testing.assert_allclose(pl3.history["det_fim_after"].to_numpy()[:-1], dets3[1:],
                               rtol=1e-8)
    np.testing.assert_allclose(pl3.history["det_fim_after"],
                               np.concatenate([[dets3[0]], dets3[1:]])
                               * (1 - pl3.history["det_loss"]), rtol=1e-8)
    assert pl3.note == ""
    # x y z sensors on a flat plate: the in-plane components of its bending modes are
    # zero, so 5 nodes (5 useful DOFs) cannot separate 6 modes; the result says why it
    # keeps more DOFs than asked
    xyz = co.candidate_geometry(model, nodes=ids[rows][::2].tolist(),
                                directions=("+x", "+y", "+z"))
    pl5 = co.effective_independence(model, modal, xyz, 15, modes=range(1, 7), triaxial=True)
    assert len(pl5.dof) == 18
    assert pl5.note.startswith("stopped at 18 DOFs (asked for 15): removing any further")


def test_efi_node_groups_of_unequal_size_remove_least_information():
    """Nodes with 1 or 2 candidate DOFs: each removal is the node whose removal keeps
    the largest det(FIM), checked against removing every node in turn."""
    model, modal = cantilever_plate()
    ids = co.fe_node_ids(model)
    rows = np.flatnonzero((model.nodes[:, 1] < 0.099) & (model.nodes[:, 0] > 0.01))[::3]
    nodes = ids[rows]
    geo = co.TestGeometry(nodes, model.nodes[rows]).with_sensors(
        [(int(n), d) for k, n in enumerate(nodes)
         for d in (("+z", "+rx") if k % 2 else ("+z",))])
    A = co.map_sensors(geo, model, method="nearest").observe(modal.shapes[:, :5])
    pl = co.effective_independence(model, modal, geo, len(geo.sensors) - 6,
                                   modes=range(1, 6), triaxial=True)
    assert len(pl.history) >= 3
    owner = np.array([s.node for s in geo.sensors])
    alive = np.ones(len(owner), bool)
    for _, step in pl.history.iterrows():
        det0 = np.linalg.det(A[alive].T @ A[alive])
        after = {n: np.linalg.det(A[alive & (owner != n)].T @ A[alive & (owner != n)])
                 for n in np.unique(owner[alive])}
        best = max(after, key=after.get)
        assert {d.split("+")[0] for d in step["removed"].split()} == {str(best)}
        assert step["det_loss"] == pytest.approx(1 - after[best] / det0, rel=1e-8)
        alive &= owner != best
