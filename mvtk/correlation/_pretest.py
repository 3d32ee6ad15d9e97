"""Pretest planning: sensor placement (effective independence, kinetic energy) and
exciter placement (driving-point residues).

Candidates are the sensor DOFs of a :class:`TestGeometry` mapped onto the FE model
(:func:`candidate_geometry` builds one from FE nodes). The chosen set comes back as a
:class:`TestGeometry` the correlation reads (``to_toml`` / :func:`read_test_geometry`).

References
----------
- Kammer, D. C., "Sensor placement for on-orbit modal identification and correlation of
  large space structures", J. Guidance, Control, and Dynamics 14(2), 251-259, 1991.
- Li, D. S., Li, H. N. & Fritzen, C. P., "The connection between effective independence
  and modal kinetic energy methods for sensor placement", J. Sound Vib. 305, 945-955,
  2007 (EfI = iterated kinetic energy of the orthonormalised candidate modes).
- Imamovic, N., *Validation of large structural dynamics models using modal test data*,
  PhD thesis, Imperial College London, 1998 (driving-point residues for exciters).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from ..errors import ParameterError
from ..fe._model import FEModel
from ._fe_adapter import FE_DIRECTIONS, fe_node_ids, modal_arrays
from ._geometry import Sensor, TestGeometry
from ._mapping import map_sensors
from ._metrics import mac

__all__ = [
    "PlacementResult",
    "candidate_geometry",
    "effective_independence",
    "kinetic_energy_placement",
    "exciter_placement",
    "placement_quality",
]


def candidate_geometry(model: FEModel, *, nodes: Sequence[int] | None = None,
                       directions: Sequence[str] = ("+z",), node_set: str | None = None
                       ) -> TestGeometry:
    """Candidate sensor DOFs at FE nodes (labels = FE node labels).

    Parameters
    ----------
    model : FEModel
    nodes : sequence of int, optional
        FE node *labels* (default: every node carrying a free DOF of each direction).
    directions : sequence of str
        Directions of the candidate sensors (global axes), e.g. ``("+z",)`` or
        ``("+x", "+y", "+z")``.
    node_set : str, optional
        Restrict to a named node set of the model.

    Examples
    --------
    Every free node of a 12-element cantilever is a +z candidate:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> cand = candidate_geometry(cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12))
    >>> len(cand.sensors), cand.sensors[0].direction
    (12, '+z')
    """
    ids = fe_node_ids(model)
    comp = [FE_DIRECTIONS.index(d) for d in directions]
    if nodes is None:
        rows = np.unique(model.dof_node[np.isin(model.dof_component, comp)])
        if node_set is not None:
            rows = np.intersect1d(rows, model.node_set(node_set))
    else:
        pos = {int(v): i for i, v in enumerate(ids)}
        bad = [n for n in nodes if int(n) not in pos]
        if bad:
            raise ParameterError(f"candidate nodes {bad[:8]} are not FE node labels")
        rows = np.array([pos[int(n)] for n in nodes], dtype=np.int64)
    sens = [Sensor(int(ids[r]), d, None, d[1] == "r") for r in rows for d in directions]
    return TestGeometry(ids[rows], model.nodes[rows], None, {}, (), tuple(sens), "candidates")


@dataclass(frozen=True, eq=False)
class PlacementResult:
    """A chosen set of sensor (or exciter) DOFs.

    Attributes
    ----------
    geometry : TestGeometry
        Chosen nodes and sensors (read back by :func:`map_sensors`).
    dof : list of str
        Chosen DOF labels.
    scores : pandas.DataFrame
        Per chosen DOF: the method's score (EfI ``E_D``, kinetic energy, DPR ...).
    history : pandas.DataFrame
        Per elimination step (EfI): removed DOF, its ``E_D`` and ``det(FIM)`` left.
    quality : pandas.DataFrame
        Per target mode (:func:`placement_quality`).
    automac : xarray.DataArray
        AutoMAC of the target modes on the chosen DOFs.
    condition_number : float
        Condition number of the target modes at the chosen DOFs (``C Phi``).
    det_fim : float
        ``det(Phi_s' Phi_s)`` of the chosen set (Fisher information, unit noise).
    method : str
    note : str
        Why the set has more DOFs than asked for (empty otherwise): effective
        independence stops where removing any further candidate (node) would leave the
        target modes linearly dependent at the sensors.

    Examples
    --------
    Returned by the placement functions; ``geometry`` is the chosen sensor set:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> res = kinetic_energy_placement(beam, modal_analysis(beam, 2), candidate_geometry(beam), 2)
    >>> res.method, res.geometry.dof_labels
    ('kinetic energy', ['12+z', '13+z'])
    """

    geometry: TestGeometry
    dof: list[str]
    scores: Any
    history: Any
    quality: Any
    automac: xr.DataArray
    condition_number: float
    det_fim: float
    method: str
    note: str = ""

    def to_dataframe(self):
        """The per-DOF score table."""
        return self.scores


def _setup(model, modal, candidates, modes, n):
    if not isinstance(candidates, TestGeometry):
        raise ParameterError(f"candidates must be a TestGeometry, got "
                             f"{type(candidates).__name__}")
    mp = map_sensors(candidates, model, method="nearest")
    Phi, fn = modal_arrays(modal)
    if modes is not None:
        idx = [int(k) - 1 for k in modes]
        Phi, fn = Phi[:, idx], fn[idx]
    A = np.asarray(mp.observe(Phi))
    if n is not None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ParameterError(f"number of DOFs to place must be a positive integer, got {n!r}")
        if n > A.shape[0]:
            raise ParameterError(f"cannot place {n} DOFs among {A.shape[0]} candidates")
    return mp, np.asarray(Phi), fn, A


def _shapes_da(A, labels, fn):
    return xr.DataArray(A.T, dims=("mode", "dof"),
                        coords={"mode": np.arange(1, A.shape[1] + 1), "fn_hz": ("mode", fn),
                                "dof": list(labels)})


def placement_quality(shapes: xr.DataArray, *, automac_max: float = 0.25):
    """Expected identifiability of each target mode on a sensor set.

    Columns: ``mode``, ``fn_hz``, ``max_automac`` (largest off-diagonal AutoMAC),
    ``closest_mode`` (the mode it is most confused with), ``identifiable``
    (``max_automac <= automac_max``) and ``reason``.

    Examples
    --------
    Two shapes with an AutoMAC of 0.073 (below ``automac_max`` = 0.25) are both
    identifiable:

    >>> import xarray as xr
    >>> shapes = xr.DataArray([[0.114, 0.394, 0.734], [-0.542, -0.593, 0.742]],
    ...                       dims=("mode", "dof"), coords={"mode": [1, 2],
    ...                       "dof": ["1+z", "2+z", "3+z"], "fn_hz": ("mode", [18.6, 116.3])})
    >>> placement_quality(shapes)[["mode", "identifiable"]].values.tolist()
    [[1, True], [2, True]]
    """
    import pandas as pd

    am = mac(shapes, shapes).values.copy()
    np.fill_diagonal(am, 0.0)
    j = np.argmax(am, axis=1) if am.shape[1] > 1 else np.zeros(am.shape[0], int)
    mx = am[np.arange(am.shape[0]), j] if am.shape[1] > 1 else np.zeros(am.shape[0])
    modes = shapes["mode"].values
    ok = mx <= automac_max
    return pd.DataFrame({
        "mode": modes,
        "fn_hz": shapes["fn_hz"].values if "fn_hz" in shapes.coords else np.nan,
        "max_automac": mx,
        "closest_mode": modes[j],
        "identifiable": ok,
        "reason": ["" if o else f"AutoMAC {v:.2f} with mode {modes[k]} > {automac_max:g}"
                   for o, v, k in zip(ok, mx, j)],
    })


def _result(candidates, mp, keep, A, fn, scores, history, method, automac_max, note=""):
    import pandas as pd

    labels = [mp.dof[i] for i in keep]
    sens = [candidates.sensors[i] for i in keep]
    nodes = sorted({s.node for s in sens})
    rows = [candidates.row(n) for n in nodes]
    geo = TestGeometry(np.array(nodes), candidates.xyz[rows], candidates.cs[rows],
                       candidates.coordinate_systems, (), tuple(sens), f"{method} placement")
    sub = A[keep]
    da = _shapes_da(sub, labels, fn)
    s = np.linalg.svd(sub, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else np.inf
    return PlacementResult(
        geometry=geo, dof=labels, scores=pd.DataFrame({"dof": labels, **scores}),
        history=history, quality=placement_quality(da, automac_max=automac_max),
        automac=mac(da, da), condition_number=cond,
        det_fim=float(np.linalg.det(sub.T @ sub)), method=method, note=note,
    )


def _rank(A: np.ndarray) -> int:
    """Numerical rank with a relative tolerance of 1e-8 (a mode 1e-8 times smaller than
    the others at every candidate cannot be measured)."""
    s = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0])) if s.size and s[0] > 0 else 0


def effective_independence(
    model: FEModel,
    modal: Any,
    candidates: TestGeometry,
    n_sensors: int,
    *,
    modes: Sequence[int] | None = None,
    triaxial: bool = False,
    automac_max: float = 0.25,
) -> PlacementResult:
    """Sensor placement by effective independence (Kammer 1991).

    Candidates are removed one at a time (or one node at a time with ``triaxial``),
    always the one whose removal costs the smallest fraction of the Fisher information
    ``det(Phi' Phi)`` (unit sensor noise), until ``n_sensors`` remain. For a single DOF
    ``i`` that fraction is its effective independence ``E_D,i``, the diagonal of the
    projector ``Phi (Phi' Phi)^-1 Phi'`` (its contribution to the rank of the target
    modes; ``sum E_D = n_modes``), since ``det(FIM_without_i) = det(FIM) (1 - E_D,i)``.
    For a node ``g`` carrying several candidate DOFs (``triaxial=True``) it is
    ``1 - det(I - P_gg)`` with ``P_gg`` the node's block of the projector (EfI3 of
    Kammer & Tinker 2004), not the sum of the node's ``E_D``.

    Parameters
    ----------
    model : FEModel
    modal : ModalResult or EigenSolution
    candidates : TestGeometry
        Candidate sensor DOFs (:func:`candidate_geometry`), mapped to the model's nearest
        nodes.
    n_sensors : int
        Number of DOFs to keep (>= number of target modes); with ``triaxial`` the number
        of DOFs kept is the nearest multiple of the DOFs per node at or above it.
    modes : sequence of int, optional
        1-based target modes (default all modes of ``modal``).
    triaxial : bool
        Remove whole nodes (all candidate DOFs of a node).
    automac_max : float
        Threshold of :func:`placement_quality`.

    Returns
    -------
    PlacementResult
        ``scores`` holds ``E_D`` of each kept DOF in the final set; ``history`` one row
        per removal: ``removed`` DOF label(s), ``E_D`` (their sum), ``det_loss`` (the
        fraction of ``det(FIM)`` the removal cost, the quantity minimised) and
        ``det_fim_after``.

    References
    ----------
    Kammer, D. C., J. Guidance, Control, and Dynamics 14(2), 251-259, 1991.
    Kammer, D. C. & Tinker, M. L., "Optimal placement of triaxial accelerometers for
    modal vibration tests", Mech. Syst. Signal Process. 18(1), 29-41, 2004.

    Examples
    --------
    Three sensors for the two lowest modes of a steel cantilever:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> fe = modal_analysis(beam, 2)
    >>> res = effective_independence(beam, fe, candidate_geometry(beam), 3)
    >>> res.dof, res.quality["identifiable"].tolist()
    (['7+z', '8+z', '13+z'], [True, True])
    """
    import pandas as pd

    mp, Phi, fn, A = _setup(model, modal, candidates, modes, n_sensors)
    m = A.shape[1]
    if n_sensors < m:
        raise ParameterError(f"effective independence needs at least as many sensors as target "
                             f"modes ({m}), got n_sensors={n_sensors}")
    if _rank(A) < m:
        raise ParameterError("the target modes are linearly dependent on the candidate DOFs "
                             "(add candidates or drop modes)")
    keep = np.arange(A.shape[0])
    groups = np.array([s.node for s in candidates.sensors]) if triaxial else keep.copy()
    hist = []
    note = ""
    while True:
        Q, _ = np.linalg.qr(A[keep])
        ed = np.sum(Q**2, axis=1)  # diag of the projector
        ug, inv = np.unique(groups[keep], return_inverse=True)
        gsize = np.bincount(inv)
        loss = np.empty(ug.size)
        if gsize.max() == 1:
            loss[inv] = ed
        elif gsize.min() == gsize.max():  # equal groups (triaxial): all blocks at once
            Qg = Q[np.argsort(inv, kind="stable")].reshape(ug.size, gsize[0], -1)
            loss[:] = 1.0 - np.linalg.det(np.eye(gsize[0]) - Qg @ Qg.transpose(0, 2, 1))
        else:
            for g in range(ug.size):
                Qg = Q[inv == g]
                loss[g] = 1.0 - np.linalg.det(np.eye(Qg.shape[0]) - Qg @ Qg.T)
        k = int(np.argmin(loss))
        if keep.size - gsize[k] < n_sensors or keep.size - gsize[k] < m:
            break
        drop = keep[inv == k]
        rest = keep[inv != k]
        if _rank(A[rest]) < m:
            note = (f"stopped at {keep.size} DOFs (asked for {n_sensors}): removing any "
                    "further candidate would leave the target modes linearly dependent "
                    "at the sensors")
            break
        hist.append({"step": len(hist) + 1, "removed": " ".join(mp.dof[i] for i in drop),
                     "E_D": float(ed[inv == k].sum()), "det_loss": float(loss[k]),
                     "det_fim_after": float(np.linalg.det(A[rest].T @ A[rest]))})
        keep = rest
    Q, _ = np.linalg.qr(A[keep])
    ed = np.sum(Q**2, axis=1)
    return _result(candidates, mp, keep, A, fn, {"E_D": ed}, pd.DataFrame(hist),
                   "effective independence", automac_max, note)


def kinetic_energy_placement(
    model: FEModel, modal: Any, candidates: TestGeometry, n_sensors: int, *,
    modes: Sequence[int] | None = None, automac_max: float = 0.25,
) -> PlacementResult:
    """Sensor placement by modal kinetic energy.

    Score of candidate ``i``: ``KE_i = sum_r (C phi_r)_i (C M phi_r)_i`` with
    mass-normalised ``phi_r`` (the share of each target mode's kinetic energy at the
    candidate DOF, summed over the modes); the ``n_sensors`` largest are kept. It
    favours large signals, not independence (compare the AutoMAC with EfI).

    Examples
    --------
    Kinetic energy favours the tip of a cantilever:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> res = kinetic_energy_placement(beam, modal_analysis(beam, 2), candidate_geometry(beam), 3)
    >>> res.dof
    ['11+z', '12+z', '13+z']
    """
    mp, Phi, fn, A = _setup(model, modal, candidates, modes, n_sensors)
    MA = np.asarray(mp.observe(model.M @ Phi))
    ke = np.sum(A * MA, axis=1)
    keep = np.sort(np.argsort(ke)[::-1][:n_sensors])
    import pandas as pd

    return _result(candidates, mp, keep, A, fn, {"kinetic_energy": ke[keep]}, pd.DataFrame(),
                   "kinetic energy", automac_max)


def exciter_placement(
    model: FEModel, modal: Any, candidates: TestGeometry, n_exciters: int = 1, *,
    modes: Sequence[int] | None = None,
) -> PlacementResult:
    """Exciter locations by driving-point residues.

    For each candidate DOF ``j`` and target mode ``r`` the driving-point residue is
    ``phi_jr^2`` (mass-normalised shapes; the residue of the receptance
    ``H_jj``). The score is the smallest residue over the target modes, each mode's
    residues divided by their maximum over the candidates (so that every target mode is
    excited: a point near a node line of one mode scores low); the average
    driving-point residue ``ADPR_j = sum_r phi_jr^2 / omega_r`` is reported too.

    Examples
    --------
    The tip of a cantilever drives both lowest bending modes best:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> exciter_placement(beam, modal_analysis(beam, 2), candidate_geometry(beam), 1).dof
    ['13+z']
    """
    import pandas as pd

    mp, Phi, fn, A = _setup(model, modal, candidates, modes, n_exciters)
    res = A**2
    mx = res.max(axis=0)
    if np.any(mx == 0):
        raise ParameterError("a target mode has zero amplitude at every candidate DOF")
    score = np.min(res / mx[None, :], axis=1)
    w = 2 * np.pi * np.where(fn > 0, fn, np.nan)
    adpr = np.nansum(res / w[None, :], axis=1)
    keep = np.sort(np.argsort(score)[::-1][:n_exciters])
    return _result(candidates, mp, keep, A, fn,
                   {"min_norm_residue": score[keep], "adpr": adpr[keep]}, pd.DataFrame(),
                   "driving-point residue", 1.0)
