"""Sensitivity-based FE model updating against measured natural frequencies."""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import (
    AccuracyWarning,
    ConfigError,
    IdentifiabilityWarning,
    MvtkError,
    ParameterError,
)
from ..fe._model import FEModel
from ..fe._solvers import EigenSolution, eigsh_lowest
from ._pairing import Pairing, classify_modes, pair_modes, target_mac, target_rows
from ._parameters import Parameter, get_path, with_values
from ._reduced import reduced_fit
from ._roundoff import without_roundoff
from ._sensitivity import (
    check_difference,
    check_model,
    d_omega2,
    matrix_derivative,
    same_dofs,
)
from ._targets import FrequencyTarget

__all__ = ["update", "UpdateResult", "HistoryEntry", "DEFAULT_MODEL_FORM_STD"]

TWO_PI = 2.0 * math.pi

#: Relative standard deviation of the model-form term (0.5 % of each target frequency)
#: used when targets carry identification standard deviations and no ``model_form_std``
#: is given. It stands for what a mesh-converged model cannot represent with any value
#: of the updated parameters (idealised boundaries and joints, sensor masses, thickness
#: and density variation): on the example smart beam, whose specimen differs from the
#: model in exactly these ways (``data/smart_beam/README.md``), updating the modulus and
#: the clamp stiffness leaves residuals of 0.13-0.51 % (RMS 0.35 %); identification
#: standard deviations (1e-5 .. 1e-3 of fn) are far smaller, so without this term the
#: weights would follow the noise of the test instead of what the model can reproduce.
DEFAULT_MODEL_FORM_STD = 0.005

#: Residual verdicts of :attr:`UpdateResult.verdicts` (see :func:`update`, Notes).
VERDICTS = ("noise", "model-form term", "model form", "no redundancy", "no std")


def _default_builder() -> Callable[[Mapping[str, Any]], FEModel]:
    try:
        from ..fe import build_model
    except ImportError as err:
        raise ConfigError(
            "no model builder given and mvtk.fe.build_model is not available; pass "
            "builder=callable(description) -> FEModel"
        ) from err
    return build_model


@dataclass(frozen=True)
class HistoryEntry:
    """One model evaluation during the update.

    Attributes
    ----------
    evaluation : int
        1-based evaluation counter.
    values : dict
        Parameter path -> value (free and fixed).
    cost : float
        ``0.5 * sum(residual^2)`` including MAC and regularisation terms.
    fn_hz : ndarray
        Model frequencies paired with the targets (Hz).
    modes : ndarray of int
        1-based model modes paired with the targets.
    model : {"full", "reduced"}
        ``"reduced"``: Ritz values of the reduced-basis inner loop (see ``update``'s
        ``reduced_basis``), not eigenvalues of the full model.

    Examples
    --------
    One entry per model evaluation in ``UpdateResult.history``:

    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> res = update(beam, ["materials.steel.E"], [19.0], n_modes=2)
    >>> first = res.history[0]
    >>> first.evaluation, first.model, round(float(first.fn_hz[0]), 2)
    (1, 'full', 18.57)
    """

    evaluation: int
    values: dict
    cost: float
    fn_hz: np.ndarray
    modes: np.ndarray
    model: str = "full"


@dataclass
class _State:
    x: np.ndarray
    model: FEModel
    omega2: np.ndarray
    vectors: np.ndarray
    fn_all: np.ndarray
    kinds: list[str] | None
    mac_matrix: np.ndarray | None
    pairing: Pairing
    residual: np.ndarray
    jac: np.ndarray | None = None
    d_omega2: np.ndarray | None = None  # (n_targets, n_free) per physical unit
    ritz: np.ndarray | None = None  # reduced-basis coordinates of the modes (None: full)


class _Matched(Exception):
    """Raised inside least_squares when every frequency error is below freq_tol."""


class _Problem:
    """Residuals and Jacobian in scaled variables x = p / scale (or log(p / scale))."""

    def __init__(self, description, params, targets, builder, n_modes, weights, mac_weight,
                 regularization, mode_classifier, rel_step, difference, affine=False,
                 eigvec_weight=0.0, shape_derivative="nelson"):
        self.description = description
        self.params = params
        self.targets = targets
        self.builder = builder
        self.n_modes = n_modes
        self.w = weights
        self.mac_weight = mac_weight
        self.reg = regularization
        self.classifier = mode_classifier
        self.rel_step = rel_step
        self.difference = difference
        self.freq_tol = 0.0
        self.affine = affine
        self._aff = None
        resolved = [p.resolve(description) for p in params]
        self.initial = np.array([v for v, _ in resolved])
        self.scale = np.array([s for _, s in resolved])
        self.free = np.array([not p.fixed for p in params], dtype=bool)
        self.log = np.array([p.log for p in params], dtype=bool)[self.free]
        self.x0 = self.to_x(self.initial[self.free])
        self.ft = np.array([t.fn_hz for t in targets])
        self.mac_rows = (
            [i for i, t in enumerate(targets) if t.has_shape] if mac_weight > 0 else []
        )
        self.eigvec_weight = eigvec_weight
        self.shape_derivative = shape_derivative
        self.eig_rows = (
            [i for i, t in enumerate(targets) if t.has_shape] if eigvec_weight > 0 else []
        )
        self.n_eig = int(sum(targets[i].shape_values.size for i in self.eig_rows))
        self.need_kinds = mode_classifier is not None or any(
            t.kind is not None for t in targets
        )
        self.history: list[HistoryEntry] = []
        self.swaps: list[dict] = []
        self.timing = {"build_s": 0.0, "eigen_s": 0.0, "sensitivity_s": 0.0,
                       "n_builds": 0, "n_eigen": 0, "n_jacobians": 0}
        self.fd_params: set[str] = set()
        self.one_sided: set[str] = set()
        self._cache: _State | None = None
        self._lowest: float | None = None
        self.n_rigid = 0   # rigid-body modes of the model (free-free): solved, then dropped
        self._vectors = None  # last eigenvectors: warm start of the next eigen solve
        self.rb = None  # RitzBasis: evaluations on the reduced model while set
        self._last_full: _State | None = None

    # -------------------------------------------------------------- helpers
    def to_x(self, p_free: np.ndarray) -> np.ndarray:
        """Scaled variables of free parameter values (or bounds; log of <= 0 is -inf)."""
        r = np.asarray(p_free, dtype=float) / self.scale[self.free]
        with np.errstate(divide="ignore", invalid="ignore"):
            lg = np.where(r > 0, np.log(np.where(r > 0, r, 1.0)), -np.inf)
        return np.where(self.log, lg, r)

    def dp_dx(self, x: np.ndarray) -> np.ndarray:
        """Derivative of the free physical values with respect to x."""
        return np.where(self.log, self.values(x)[self.free], self.scale[self.free])

    def values(self, x: np.ndarray) -> np.ndarray:
        v = self.initial.copy()
        x = np.asarray(x, dtype=float)
        sc = self.scale[self.free]
        v[self.free] = np.where(self.log, sc * np.exp(np.where(self.log, x, 0.0)), sc * x)
        return v

    def describe(self, x: np.ndarray) -> dict:
        return with_values(
            self.description, {p.path: float(v) for p, v in zip(self.params, self.values(x))}
        )

    def build(self, desc) -> FEModel:
        t0 = time.perf_counter()
        try:
            built = self.builder(desc)
        except MvtkError as err:
            now = ", ".join(f"{p.path}={get_path(desc, p.path):.6g}" for p in self.params)
            raise ConfigError(
                f"the model builder failed at {now}: {err} (if other fields depend on an "
                "updated one, e.g. points on a length, keep them consistent or fix bounds)"
            ) from err
        model = check_model(built, "model builder")
        self.timing["build_s"] += time.perf_counter() - t0
        self.timing["n_builds"] += 1
        return model

    def eigen(self, model: FEModel):
        n = min(self.n_modes, model.n_dof)
        if n < len(self.targets):
            raise ParameterError(
                f"the model has {model.n_dof} DOFs, fewer than the {len(self.targets)} targets"
            )
        t0 = time.perf_counter()
        # shift: eigsh_lowest's default (-1e-6 x median K_ii/M_ii) sits far below the
        # wanted modes when rotational DOFs carry little inertia, and shift-invert then
        # needs many more iterations. Shift to -0.1 x the lowest eigenvalue (of the
        # previous solve; the lowest target before the first): negative, so K - sigma M
        # stays positive definite, and close to the wanted modes
        lowest = self._lowest
        if lowest is None:
            lowest = (TWO_PI * float(self.ft.min())) ** 2
        sigma = -0.1 * lowest if lowest > 0 else None
        v0 = self._vectors
        if v0 is not None and v0.shape[0] != model.n_dof:
            v0 = None
        # after a first solve without rigid-body modes, K without its round-off entries
        # (faster factorisation, one ordering for every evaluation); a free-free model
        # keeps them: its rigid-body null space rests on their exact cancellation
        K = (without_roundoff(model.K) if self._lowest is not None and self.n_rigid == 0
             else model.K)
        while True:   # more than once only while the rigid-body modes are being counted
            k = min(n + self.n_rigid, model.n_dof)
            eig = self._elastic(eigsh_lowest(K, model.M, k, sigma=sigma, v0=v0))
            if eig.omega2.size >= n or k == model.n_dof or k == n + self.n_rigid:
                break
        if eig.omega2.size < len(self.targets):
            raise ParameterError(
                f"the model has {self.n_rigid} rigid-body modes and only {eig.omega2.size} "
                f"elastic modes among the {n} computed, fewer than the "
                f"{len(self.targets)} targets: support it or raise n_modes")
        self._vectors = eig.vectors
        if eig.omega2[0] > 0:
            self._lowest = float(eig.omega2[0])
        self.timing["eigen_s"] += time.perf_counter() - t0
        self.timing["n_eigen"] += 1
        return eig

    def _elastic(self, eig):
        """``eig`` without its rigid-body modes: eigenvalues below 1e-4 x that of the
        lowest target (f below 1 % of it), which no target can pair with and whose zero
        frequency has no finite sensitivity. Their count is kept so that later solves ask
        for ``n_modes`` elastic modes."""
        rigid = eig.omega2 < 1e-4 * (TWO_PI * float(self.ft.min())) ** 2
        if not rigid.any():
            return eig
        self.n_rigid = max(self.n_rigid, int(rigid.sum()))
        keep = ~rigid
        return replace(eig, omega2=eig.omega2[keep], vectors=eig.vectors[:, keep])

    # ------------------------------------------------------------ affine path
    def _affine_setup(self) -> None:
        """Base model and constant dK/dp, dM/dp (forward differences, exact if affine)."""
        v0 = self.values(self.x0)
        desc0 = self.describe(self.x0)
        base = self.build(desc0)
        dK, dM = [], []
        # a builder that knows its exact matrix derivatives (mvtk.fe.AffineModel) gives them
        exact = getattr(self.builder, "matrix_derivatives", None)
        for j in np.flatnonzero(self.free):
            p = self.params[j]
            if exact is not None:
                dKj, dMj = exact(p.path)
                dK.append(dKj)
                dM.append(dMj)
                continue
            h = 0.5 * self.scale[j]
            if v0[j] + h > p.upper:
                h = -h
            pert = self.build(with_values(desc0, {p.path: float(v0[j] + h)}))
            if not same_dofs(base, pert):
                raise ParameterError(
                    f"affine=True needs a fixed mesh, but perturbing {p.path!r} changed the "
                    f"free DOFs ({base.n_dof} -> {pert.n_dof})"
                )
            dK.append((pert.K - base.K) / h)
            dM.append((pert.M - base.M) / h)
        self._aff = (base, v0[self.free].copy(), dK, dM)

    def model_at(self, x: np.ndarray) -> FEModel:
        """Model at scaled variables x: a build, or the affine update of the base model."""
        if not self.affine:
            return self.build(self.describe(x))
        if self._aff is None:
            self._affine_setup()
        base, v0, dK, dM = self._aff
        dv = self.values(x)[self.free] - v0
        K, M = base.K, base.M
        for d, kk, mm in zip(dv, dK, dM):
            if d != 0.0:
                K = K + d * kk
                M = M + d * mm
        return replace(base, K=K, M=M)

    def kinds_of(self, model, vectors):
        if self.classifier is not None:
            kinds = list(self.classifier(model, vectors))
            if len(kinds) != vectors.shape[1]:
                raise ParameterError(
                    f"mode_classifier returned {len(kinds)} labels for {vectors.shape[1]} modes"
                )
            return kinds
        return classify_modes(model, vectors)

    # ------------------------------------------------------------- evaluate
    def use_basis(self, basis) -> None:
        """Evaluate on the reduced model of ``basis`` (a RitzBasis) from now on, or on the
        full model (None)."""
        self.rb = basis
        self._cache = None if basis is not None else self._last_full

    def _ritz(self, x: np.ndarray):
        """Model (for DOF maps, kinds) and Ritz pairs of the reduced model at x."""
        base, v0, _, _ = self._aff
        dv = self.values(x)[self.free] - v0
        n = min(self.n_modes, base.n_dof)
        w2, Y = self.rb.eig(dv, n)
        model = self.model_at(x) if self.need_kinds else base
        return model, EigenSolution(w2, self.rb.V @ Y, method="ritz"), Y

    def state(self, x: np.ndarray) -> _State:
        x = np.asarray(x, dtype=float)
        if self._cache is not None and np.array_equal(self._cache.x, x):
            return self._cache
        ritz = None
        if self.rb is not None:
            model, eig, ritz = self._ritz(x)
        else:
            model = self.model_at(x)
            eig = self.eigen(model)
        fn_all = np.sqrt(np.maximum(eig.omega2, 0.0)) / TWO_PI
        kinds = self.kinds_of(model, eig.vectors) if self.need_kinds else None
        has_shapes = any(t.has_shape for t in self.targets)
        macm = target_mac(model, eig.vectors, self.targets) if has_shapes else None
        pairing = pair_modes(self.targets, fn_all, macm, kinds)
        fp = fn_all[pairing.modes]
        r = [self.w * (fp - self.ft) / self.ft]
        if self.mac_rows:
            r.append(self.mac_weight * self.w[self.mac_rows] * (1.0 - pairing.mac[self.mac_rows]))
        for i in self.eig_rows:
            y = target_rows(model, eig.vectors[:, [pairing.modes[i]]], self.targets[i], i)[:, 0]
            r.append(self.eigvec_weight * self.w[i] * _unit_difference(
                y, self.targets[i].shape_values))
        if self.reg > 0:
            r.append(math.sqrt(self.reg) * (x - self.x0))
        res = np.concatenate(r)
        st = _State(x.copy(), model, eig.omega2, eig.vectors, fn_all, kinds, macm, pairing, res,
                    ritz=ritz)
        self._record(st)
        self._cache = st
        if ritz is None:
            self._last_full = st
        return st

    def _record(self, st: _State) -> None:
        modes = st.pairing.modes + 1
        if self.history:
            prev = self.history[-1].modes
            for i, (a, b) in enumerate(zip(prev, modes)):
                if a != b:
                    self.swaps.append({
                        "evaluation": len(self.history) + 1,
                        "target": self.targets[i].label or f"f{i + 1}",
                        "from_mode": int(a), "to_mode": int(b),
                    })
        self.history.append(HistoryEntry(
            evaluation=len(self.history) + 1,
            values={p.path: float(v) for p, v in zip(self.params, self.values(st.x))},
            cost=float(0.5 * st.residual @ st.residual),
            fn_hz=st.fn_all[st.pairing.modes].copy(),
            modes=modes,
            model="full" if st.ritz is None else "reduced",
        ))

    def _mac_derivative(self, st, phi, pert, pert_eig, k, h, dmac) -> None:
        """Forward difference of the paired MACs into column k of ``dmac``."""
        pm = target_mac(pert, pert_eig.vectors, self.targets)
        for r, i in enumerate(self.mac_rows):
            # follow the paired mode: the perturbed mode most M-parallel to it
            if same_dofs(st.model, pert):
                ov = np.abs(phi[:, i] @ (pert.M @ pert_eig.vectors))
                m = int(np.argmax(ov))
            else:
                m = int(st.pairing.modes[i])
            dmac[r, k] = (pm[i, m] - st.pairing.mac[i]) / h

    def _vector_derivative(self, st, phi, pert, pert_eig, k, h, out, n_free) -> None:
        """Forward difference of the paired mode shapes (mode followed by M-overlap)."""
        if not same_dofs(st.model, pert):
            raise ParameterError(
                "mode-shape residuals need a fixed mesh: perturbing a parameter changed the "
                "model's free DOFs"
            )
        for i in sorted(set(self.mac_rows) | set(self.eig_rows)):
            m = int(st.pairing.modes[i])
            ov = st.vectors[:, m] @ (pert.M @ pert_eig.vectors)
            mp = int(np.argmax(np.abs(ov)))
            v = pert_eig.vectors[:, mp] * np.sign(ov[mp])
            out.setdefault(i, np.zeros((st.model.n_dof, n_free)))[:, k] = (
                v - st.vectors[:, m]) / h

    def residual(self, x):
        st = self.state(x)
        if self.freq_tol > 0:
            err = np.abs(st.residual[: len(self.targets)] / np.where(self.w > 0, self.w, 1.0))
            if err.max() <= self.freq_tol:
                raise _Matched
        return st.residual

    # ------------------------------------------------------------- jacobian
    def jacobian(self, x) -> np.ndarray:
        st = self.state(x)
        if st.jac is not None:
            return st.jac
        t_start = time.perf_counter()
        b0, e0 = self.timing["build_s"], self.timing["eigen_s"]
        nt = len(self.targets)
        free_idx = np.flatnonzero(self.free)
        modes = st.pairing.modes
        phi = st.vectors[:, modes]
        w2 = st.omega2[modes]
        fp = st.fn_all[modes]
        dw2 = np.zeros((nt, free_idx.size))
        dmac = np.zeros((len(self.mac_rows), free_idx.size))
        shape_idx = sorted(set(self.mac_rows) | set(self.eig_rows))
        nelson = bool(shape_idx) and self.shape_derivative == "nelson"
        fd_mac = bool(self.mac_rows) and not nelson
        need_vec = bool(self.eig_rows) and not nelson
        mats: list = [None] * free_idx.size
        dphi_fd: dict[int, np.ndarray] = {}
        base_vals = self.values(x)
        base_desc = self.describe(x)
        for k, j in enumerate(free_idx):
            p = self.params[j]
            h = self.rel_step * (abs(base_vals[j]) if p.log else self.scale[j])
            if base_vals[j] + h > p.upper:
                h = -h
            pert_eig = None
            if st.ritz is not None:
                # reduced model: derivative of the Ritz values (projected matrices)
                dw2[:, k] = d_omega2(w2, st.ritz[:, modes], self.rb.dKr[k], self.rb.dMr[k])
                continue
            if self.affine:
                dw2[:, k] = d_omega2(w2, phi, self._aff[2][k], self._aff[3][k])
                mats[k] = (self._aff[2][k], self._aff[3][k])
                if need_vec:
                    xp = np.array(x, dtype=float)
                    xp[k] += h / self.dp_dx(x)[k]
                    pert = self.model_at(xp)
                    hp = self.values(xp)[j] - base_vals[j]
                    self._vector_derivative(st, phi, pert, self.eigen(pert), k, hp, dphi_fd,
                                            free_idx.size)
                if fd_mac:
                    xp = np.array(x, dtype=float)
                    xp[k] += h / self.dp_dx(x)[k]
                    pert = self.model_at(xp)
                    pert_eig = self.eigen(pert)
                    hp = self.values(xp)[j] - base_vals[j]
                    self._mac_derivative(st, phi, pert, pert_eig, k, hp, dmac)
                continue
            steps = (h, -h) if self.difference == "central" else (h,)
            built = [self.build(with_values(base_desc, {p.path: float(base_vals[j] + s)}))
                     for s in steps]
            pert = built[0]
            same = [same_dofs(st.model, b) for b in built]
            if all(same):
                dK, dM = matrix_derivative(st.model, built, h)
                dw2[:, k] = d_omega2(w2, phi, dK, dM)
                mats[k] = (dK, dM)
            elif any(same):
                # a mesh that conforms to the moved field (e.g. a patch edge) changed on
                # one side only: one-sided difference on the side that kept the mesh
                self.one_sided.add(p.path)
                i_same = same.index(True)
                pert, hs = built[i_same], steps[i_same]
                dK, dM = matrix_derivative(st.model, [pert], hs)
                dw2[:, k] = d_omega2(w2, phi, dK, dM)
                mats[k] = (dK, dM)
                h = hs
            else:
                # the mesh changed: finite differences of the eigenvalues, modes tracked
                # by index (documented limitation)
                self.fd_params.add(p.path)
                pert_eig = self.eigen(pert)
                dw2[:, k] = (pert_eig.omega2[modes] - w2) / h
            if fd_mac or need_vec or (nelson and mats[k] is None):
                if pert_eig is None:
                    pert_eig = self.eigen(pert)
                if fd_mac:
                    self._mac_derivative(st, phi, pert, pert_eig, k, h, dmac)
                if need_vec or (nelson and mats[k] is None):
                    self._vector_derivative(st, phi, pert, pert_eig, k, h, dphi_fd,
                                            free_idx.size)
        dfp = dw2 / (8 * math.pi**2 * fp[:, None])
        scale = self.dp_dx(x)[None, :]
        deig = np.zeros((self.n_eig, free_idx.size))
        if shape_idx:
            dphi = dict(dphi_fd)
            if nelson:
                for i in shape_idx:
                    m = int(modes[i])
                    d = _nelson(st.model.K, st.model.M, float(st.omega2[m]), st.vectors[:, m],
                                [mk for mk in mats if mk is not None])
                    full = dphi.get(i, np.zeros((st.model.n_dof, free_idx.size)))
                    cols = [c for c in range(free_idx.size) if mats[c] is not None]
                    full[:, cols] = d
                    dphi[i] = full
            row = 0
            for i in shape_idx:
                t = self.targets[i]
                y = target_rows(st.model, st.vectors[:, [modes[i]]], t, i)[:, 0]
                dy = target_rows(st.model, dphi[i], t, i)
                if nelson and i in self.mac_rows:
                    dmac[self.mac_rows.index(i)] = _mac_gradient(t.shape_values, y, dy)
                if i in self.eig_rows:
                    n_s = y.size
                    deig[row:row + n_s] = (self.eigvec_weight * self.w[i]
                                           * _unit_difference_gradient(y, t.shape_values, dy))
                    row += n_s
        rows = [(self.w / self.ft)[:, None] * dfp * scale]
        if self.mac_rows:
            rows.append(-self.mac_weight * self.w[self.mac_rows][:, None] * dmac * scale)
        if self.eig_rows:
            rows.append(deig * scale)
        if self.reg > 0:
            rows.append(math.sqrt(self.reg) * np.eye(free_idx.size))
        st.jac = np.vstack(rows)
        st.d_omega2 = dw2
        self.timing["n_jacobians"] += 1
        spent = time.perf_counter() - t_start
        self.timing["sensitivity_s"] += spent - (self.timing["build_s"] - b0) - (
            self.timing["eigen_s"] - e0
        )
        return st.jac


def _statistical_weights(tg, w, frequency_std, model_form_std):
    """Row weights and the standard deviations of the targets (see :func:`update`).

    Returns ``(w, sigma)``: ``w`` the weights of the relative residuals (the given ones
    unless statistical weighting applies) and ``sigma`` a dict: ``weighted`` (bool),
    ``model_form`` (relative std or None), ``id_hz`` and ``total_hz`` (per target, Hz;
    NaN where unknown).
    """
    if model_form_std is not None and not (
            isinstance(model_form_std, int | float) and not isinstance(model_form_std, bool)
            and math.isfinite(model_form_std) and 0 <= model_form_std < 1):
        raise ParameterError(
            f"model_form_std must be a relative standard deviation in [0, 1), got "
            f"{model_form_std!r}")
    ft = np.array([t.fn_hz for t in tg])
    given = np.array([np.nan if t.std_hz is None else t.std_hz for t in tg])
    weighted = model_form_std is not None or bool(np.isfinite(given).any())
    fill = np.nan if frequency_std is None else frequency_std * ft
    sid = np.where(np.isfinite(given), given, fill)
    if not weighted:
        return w, {"weighted": False, "model_form": None, "id_hz": sid,
                   "total_hz": sid.copy()}
    mf = DEFAULT_MODEL_FORM_STD if model_form_std is None else float(model_form_std)
    total = np.sqrt(np.nan_to_num(sid) ** 2 + (mf * ft) ** 2)
    bad = [t.label or f"f{i + 1}" for i, t in enumerate(tg) if total[i] == 0 and w[i] > 0]
    if bad:
        raise ParameterError(
            f"targets {bad} have a zero standard deviation (std_hz 0 or none, and "
            "model_form_std 0): their weight 1/sigma^2 would be infinite; give std_hz > 0 "
            "or model_form_std > 0")
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(w > 0, w * ft / total, 0.0)
    return w, {"weighted": True, "model_form": mf, "id_hz": sid, "total_hz": total}


def _residual_verdicts(rel, Jr, A, w, sigma, ft) -> dict:
    """Noise / model-form verdict of every relative residual ``rel`` (see :func:`update`).

    ``Jr`` (n_targets, n_free): d(relative frequency)/dx at the solution; ``A`` the
    Gauss-Newton matrix J'J of all rows; ``w`` the row weights.

    Returns
    -------
    dict
        ``verdict`` (list of str) and ``limits_hz`` (n_targets, 2): twice the residual
        standard deviation in Hz under the identification variances alone and with the
        model-form term (NaN where unknown).
    """
    n = rel.size
    limits = np.full((n, 2), np.nan)
    sid, stot = sigma["id_hz"] / ft, sigma["total_hz"] / ft
    if not np.isfinite(stot).any() or not np.isfinite(Jr).all():
        return {"verdict": ["no std"] * n, "limits_hz": limits}
    P = np.eye(n) - Jr @ np.linalg.pinv(A) @ Jr.T * (w**2)[None, :]
    s_id = np.sqrt(np.einsum("ij,j,ij->i", P, np.nan_to_num(sid) ** 2, P))
    s_tot = np.sqrt(np.einsum("ij,j,ij->i", P, np.nan_to_num(stot) ** 2, P))
    limits[:, 0] = np.where(np.isfinite(sid), 2 * s_id * ft, np.nan)
    limits[:, 1] = 2 * s_tot * ft
    out = []
    for i in range(n):
        r = abs(float(rel[i]))
        if not np.isfinite(stot[i]):
            out.append("no std")
        elif s_tot[i] < 1e-3 * stot[i]:
            out.append("no redundancy")
        elif np.isfinite(sid[i]) and r <= 2 * s_id[i]:
            out.append("noise")
        elif r <= 2 * s_tot[i]:
            out.append("model-form term")
        else:
            out.append("model form")
    return {"verdict": out, "limits_hz": limits}


def _rayleigh(model: FEModel, phi: np.ndarray) -> np.ndarray:
    """Rayleigh quotients ``phi' K phi / phi' M phi`` of each column, (rad/s)^2."""
    return (np.einsum("ij,ij->j", phi, model.K @ phi)
            / np.einsum("ij,ij->j", phi, model.M @ phi))


def _rank_report(J: np.ndarray, tol: float, names: Sequence[str]) -> dict:
    """Singular values, identifiability and null directions of a (scaled) Jacobian."""
    n = J.shape[1]
    _, s, vt = np.linalg.svd(J)
    sv = np.zeros(n)
    sv[: s.size] = s
    smax = float(sv.max()) if n else 0.0
    weak = np.flatnonzero(sv < tol * smax) if smax > 0 else np.arange(n)
    return {
        "singular_values": sv,
        "identifiable": not weak.size,
        "null_directions": [{p: round(float(c), 4) for p, c in zip(names, vt[k])}
                            for k in weak],
    }


def _unit_difference(y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``s y/|y| - t/|t|`` with ``s = sign(t'y)``: scale- and sign-free shape difference."""
    s = 1.0 if float(t @ y) >= 0 else -1.0
    return s * y / np.linalg.norm(y) - t / np.linalg.norm(t)


def _unit_difference_gradient(y: np.ndarray, t: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Derivative of :func:`_unit_difference` for ``dy`` (n_sensors, n_params)."""
    s = 1.0 if float(t @ y) >= 0 else -1.0
    ny = np.linalg.norm(y)
    u = y / ny
    return s * (dy - np.outer(u, u @ dy)) / ny


def _mac_gradient(t: np.ndarray, y: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """d MAC(t, y) for ``dy`` (n_sensors, n_params)."""
    ty, tt, yy = float(t @ y), float(t @ t), float(y @ y)
    return 2 * ty * (t @ dy) / (tt * yy) - 2 * ty**2 * (y @ dy) / (tt * yy**2)


def _nelson(K, M, lam: float, phi: np.ndarray, mats) -> np.ndarray:
    """Derivatives of a mass-normalised eigenvector by Nelson's method.

    For each ``(dK, dM)``: ``(K - lam M) v = -(dK - lam dM - dlam M) phi`` solved with
    the component of largest ``|phi|`` held at zero, then
    ``dphi = v + c phi`` with ``c = -phi' M v - phi' dM phi / 2`` (keeps
    ``phi' M phi = 1``). Nelson, AIAA J 14(9), 1976. Exact for a distinct eigenvalue.

    Returns
    -------
    ndarray (n_dof, len(mats))
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    n = phi.size
    if not mats:
        return np.zeros((n, 0))
    kmax = int(np.argmax(np.abs(phi)))
    keep = np.setdiff1d(np.arange(n), [kmax])
    A = (sp.csr_matrix(K) - lam * sp.csr_matrix(M))[keep][:, keep].tocsc()
    lu = splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})
    Mphi = M @ phi
    F = np.empty((n, len(mats)))
    dMphi = np.empty(len(mats))
    for c, (dK, dM) in enumerate(mats):
        dKp, dMp = dK @ phi, dM @ phi
        dlam = float(phi @ dKp - lam * (phi @ dMp))
        F[:, c] = -(dKp - lam * dMp - dlam * Mphi)
        dMphi[c] = float(phi @ dMp)
    V = np.zeros((n, len(mats)))
    V[keep] = lu.solve(F[keep])
    cst = -(Mphi @ V) - 0.5 * dMphi
    return V + phi[:, None] * cst[None, :]


@dataclass(frozen=True, eq=False)
class UpdateResult:
    """Outcome of :func:`update`.

    Attributes
    ----------
    description : dict
        Updated structure description (deep copy with the new parameter values).
    initial_description : dict
        Description at the initial parameter values.
    model : FEModel
        Model built from ``description``.
    parameters, targets : tuple
        As given.
    initial_values, values : ndarray, shape (n_params,)
        Parameter values before/after (SI units of each field).
    std : ndarray, shape (n_params,)
        Standard deviation of each updated value from the Jacobian covariance
        (NaN for fixed parameters or when it cannot be estimated; inf along a
        non-identifiable direction).
    covariance : ndarray, shape (n_free, n_free)
        Covariance of the free parameters in their physical units.
    at_bound : ndarray of bool, shape (n_params,)
    fn_hz_initial, fn_hz : ndarray, shape (n_targets,)
        Paired model frequencies (Hz) before/after.
    modes_initial, modes : ndarray of int, shape (n_targets,)
        1-based paired model modes before/after.
    mac_initial, mac : ndarray, shape (n_targets,)
        MAC of the pairs (NaN without measured shapes).
    pairing_method : tuple of str
    model_fn_hz : ndarray
        All computed model frequencies after updating (Hz).
    model_kinds : tuple of str
        Mode type of each computed mode (see :func:`classify_modes`).
    sensitivity : ndarray, shape (n_targets, n_free)
        Normalised sensitivities (p/f) df/dp at the solution.
    singular_values : ndarray
        Singular values of the weighted frequency Jacobian in scaled variables.
    condition_number : float
    identifiable : bool
        From the frequency rows alone.
    null_directions : tuple of dict
        For each non-identifiable direction, the parameter weights of the (scaled)
        right singular vector.
    history : tuple of HistoryEntry
    swaps : tuple of dict
        Pairing changes between consecutive evaluations.
    success : bool
    message : str
    n_evaluations, n_jacobians : int
    cost : float
    timing : dict
        Seconds spent in builds, eigen solves and sensitivity products.
    meta : dict
    identifiable_with_shapes : bool or None
        From all data rows (frequencies and mode-shape terms); None without shape
        terms. ``identifiable=False`` with ``identifiable_with_shapes=True`` says the
        frequencies alone cannot locate the change but the shapes can.
    data_singular_values : ndarray or None
        Singular values of the weighted data Jacobian (frequency + shape rows).
    initial_identifiable, initial_identifiable_with_shapes : bool or None
        The same diagnostics at the initial parameter values. On a symmetric structure
        mirror-image parameters have equal frequency sensitivities there: the
        frequencies fit two (mirror) solutions equally well and the end point can be the
        wrong one although its local Jacobian looks regular.
    initial_null_directions : tuple of dict
        Null directions of the frequency Jacobian at the initial values.
    identification_std_hz, target_std_hz : ndarray or None, shape (n_targets,)
        Standard deviation of each target from its identification (``std_hz``, or
        ``frequency_std``) and with the model-form term, Hz (NaN where unknown).
    verdicts : tuple of str
        Per target: ``"noise"``, ``"model-form term"``, ``"model form"``,
        ``"no redundancy"`` or ``"no std"`` (see :func:`update`, Notes).
    residual_limits_hz : ndarray or None, shape (n_targets, 2)
        The verdicts' thresholds: twice the residual standard deviation from the
        identification alone and with the model-form term, Hz.

    Examples
    --------
    Returned by :func:`update`; ``to_dataframe`` lists the targets before and after:

    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> res = update(beam, ["materials.steel.E"], [19.0], n_modes=2)
    >>> res.success, res.to_dataframe()[["target_hz", "updated_hz"]].round(3).values.tolist()
    (True, [[19.0, 19.0]])
    """

    description: dict
    initial_description: dict
    model: FEModel
    parameters: tuple[Parameter, ...]
    targets: tuple[FrequencyTarget, ...]
    initial_values: np.ndarray
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    at_bound: np.ndarray
    fn_hz_initial: np.ndarray
    fn_hz: np.ndarray
    modes_initial: np.ndarray
    modes: np.ndarray
    mac_initial: np.ndarray
    mac: np.ndarray
    pairing_method: tuple[str, ...]
    model_fn_hz: np.ndarray
    model_kinds: tuple[str, ...]
    sensitivity: np.ndarray
    singular_values: np.ndarray
    condition_number: float
    identifiable: bool
    null_directions: tuple[dict, ...]
    history: tuple[HistoryEntry, ...]
    swaps: tuple[dict, ...]
    success: bool
    message: str
    n_evaluations: int
    n_jacobians: int
    cost: float
    timing: dict
    meta: dict = field(default_factory=dict)
    identifiable_with_shapes: bool | None = None
    data_singular_values: np.ndarray | None = None
    initial_identifiable: bool | None = None
    initial_identifiable_with_shapes: bool | None = None
    initial_null_directions: tuple[dict, ...] = ()
    identification_std_hz: np.ndarray | None = None
    target_std_hz: np.ndarray | None = None
    verdicts: tuple[str, ...] = ()
    residual_limits_hz: np.ndarray | None = None

    # ----------------------------------------------------------------- tables
    def _target_labels(self) -> list[str]:
        return [t.label or f"f{i + 1}" for i, t in enumerate(self.targets)]

    def residual_table(self):
        """Targets vs initial and updated model frequencies (``pandas.DataFrame``).

        With the residual ``residual_hz`` (updated - target), the standard deviations
        ``id_std_hz`` (identification) and ``std_hz`` (with the model-form term), the
        verdict thresholds ``noise_limit_hz`` and ``limit_hz`` (twice the residual's
        standard deviation without and with the model-form term) and ``verdict``.
        """
        import pandas as pd

        ft = np.array([t.fn_hz for t in self.targets])
        n = ft.size
        nan = np.full(n, np.nan)
        lim = self.residual_limits_hz if self.residual_limits_hz is not None else (
            np.full((n, 2), np.nan))
        return pd.DataFrame(
            {
                "target_hz": ft,
                "initial_hz": self.fn_hz_initial,
                "updated_hz": self.fn_hz,
                "initial_error_pct": 100 * (self.fn_hz_initial - ft) / ft,
                "error_pct": 100 * (self.fn_hz - ft) / ft,
                "mode": self.modes,
                "mac": self.mac,
                "pairing": list(self.pairing_method),
                "kind": [self.model_kinds[m - 1] if self.model_kinds else None
                         for m in self.modes],
                "weight": [t.weight for t in self.targets],
                "residual_hz": self.fn_hz - ft,
                "id_std_hz": (nan if self.identification_std_hz is None
                              else self.identification_std_hz),
                "std_hz": nan if self.target_std_hz is None else self.target_std_hz,
                "noise_limit_hz": lim[:, 0],
                "limit_hz": lim[:, 1],
                "verdict": list(self.verdicts) if self.verdicts else ["no std"] * n,
            },
            index=pd.Index(self._target_labels(), name="target"),
        )

    def parameter_table(self):
        """Initial and updated parameters, change %, bounds and std (``pandas.DataFrame``)."""
        import pandas as pd

        with np.errstate(divide="ignore", invalid="ignore"):
            change = 100 * (self.values - self.initial_values) / np.abs(self.initial_values)
            std_pct = 100 * self.std / np.abs(self.values)
        return pd.DataFrame(
            {
                "initial": self.initial_values,
                "updated": self.values,
                "change_pct": change,
                "std": self.std,
                "std_pct": std_pct,
                "lower": [p.lower for p in self.parameters],
                "upper": [p.upper for p in self.parameters],
                "at_bound": self.at_bound,
                "fixed": [p.fixed for p in self.parameters],
            },
            index=pd.Index([p.name for p in self.parameters], name="parameter"),
        )

    def history_table(self):
        """One row per model evaluation: cost, parameter values and paired frequencies."""
        import pandas as pd

        rows = []
        labels = self._target_labels()
        for h in self.history:
            row = {"evaluation": h.evaluation, "model": h.model, "cost": h.cost}
            row.update(h.values)
            row.update({f"{lab}_hz": f for lab, f in zip(labels, h.fn_hz)})
            row.update({f"{lab}_mode": int(m) for lab, m in zip(labels, h.modes)})
            rows.append(row)
        return pd.DataFrame(rows).set_index("evaluation")

    def sensitivity_table(self):
        """Normalised sensitivities (p/f) df/dp, targets x free parameters."""
        import pandas as pd

        cols = [p.name for p in self.parameters if not p.fixed]
        return pd.DataFrame(
            self.sensitivity, index=pd.Index(self._target_labels(), name="target"),
            columns=cols,
        )

    def unpaired_table(self):
        """Updated model modes not paired with any target (the modes the test missed)."""
        import pandas as pd

        paired = set(int(m) for m in self.modes)
        idx = [m for m in range(1, len(self.model_fn_hz) + 1) if m not in paired]
        return pd.DataFrame(
            {
                "fn_hz": self.model_fn_hz[[m - 1 for m in idx]],
                "kind": [self.model_kinds[m - 1] if self.model_kinds else None for m in idx],
            },
            index=pd.Index(idx, name="mode"),
        )

    @property
    def unpaired_fn_hz(self) -> np.ndarray:
        """Frequencies (Hz) of the computed model modes not paired with a target."""
        return self.unpaired_table()["fn_hz"].to_numpy()

    def to_dataframe(self, table: str = "residuals"):
        """A result table: ``"residuals"``, ``"parameters"``, ``"history"``,
        ``"sensitivity"`` or ``"unpaired"``."""
        tables = {
            "residuals": self.residual_table,
            "parameters": self.parameter_table,
            "history": self.history_table,
            "sensitivity": self.sensitivity_table,
            "unpaired": self.unpaired_table,
        }
        if table not in tables:
            raise ParameterError(f"unknown table {table!r}; expected one of {sorted(tables)}")
        return tables[table]()

    def _repr_html_(self) -> str:
        from .._table import html_table

        return (html_table(self.residual_table(), caption="Residuals", passed_column=None)
                + html_table(self.parameter_table(), caption="Parameters",
                             passed_column=None))

    # ----------------------------------------------------------------- output
    def to_toml(self) -> str:
        """The updated structure description as TOML text (``tomli_w``)."""
        import tomli_w

        return tomli_w.dumps(self.description)

    def write_toml(self, path: str | Path) -> Path:
        """Write the updated structure description to ``path`` as TOML."""
        from .._atomic import write_text

        return write_text(Path(path), self.to_toml())

    def to_dict(self) -> dict:
        """JSON-serialisable summary (tables as lists of records, no model)."""

        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
            if isinstance(v, np.generic):
                return clean(v.item())
            return v

        def deep(v):
            if isinstance(v, dict):
                return {k: deep(x) for k, x in v.items()}
            if isinstance(v, list | tuple):
                return [deep(x) for x in v]
            return clean(v)

        def records(df):
            df = df.reset_index()
            return [{k: clean(v) for k, v in row.items()} for row in df.to_dict("records")]

        return {
            "success": bool(self.success),
            "message": self.message,
            "n_evaluations": int(self.n_evaluations),
            "n_jacobians": int(self.n_jacobians),
            "cost": clean(float(self.cost)),
            "identifiable": bool(self.identifiable),
            "identifiable_with_shapes": self.identifiable_with_shapes,
            "initial_identifiable": self.initial_identifiable,
            "initial_identifiable_with_shapes": self.initial_identifiable_with_shapes,
            "condition_number": clean(float(self.condition_number)),
            "singular_values": [clean(float(s)) for s in self.singular_values],
            "null_directions": list(self.null_directions),
            "residuals": records(self.residual_table()),
            "parameters": records(self.parameter_table()),
            "sensitivity": records(self.sensitivity_table()),
            "unpaired_modes": records(self.unpaired_table()),
            "swaps": list(self.swaps),
            "timing": {k: clean(v) for k, v in self.timing.items()},
            "updated_values": {p.path: float(v) for p, v in zip(self.parameters, self.values)},
            "reduced_basis": deep(self.meta.get("reduced_basis", {"used": False})),
            "covariance": {
                "parameters": [p.path for p in self.parameters if not p.fixed],
                "matrix": [[clean(float(v)) for v in row]
                           for row in np.asarray(self.covariance, dtype=float)]},
            "weighting": self.meta.get("weighting", "weights"),
            "model_form_std": clean(self.meta.get("model_form_std")),
            "variance_factor": clean(self.meta.get("variance_factor", math.nan)),
            "covariance_scaling": self.meta.get("covariance_scaling"),
        }


def _check_inputs(parameters, targets, weights, regularization, mac_weight, max_iter, n_modes):
    params = [p if isinstance(p, Parameter) else Parameter(p) for p in parameters]
    if not params:
        raise ParameterError("update needs at least one parameter")
    paths = [p.path for p in params]
    dup = sorted({p for p in paths if paths.count(p) > 1})
    if dup:
        raise ParameterError(f"parameters listed twice: {dup}")
    if all(p.fixed for p in params):
        raise ParameterError("all parameters are fixed; nothing to update")
    tg = []
    for i, t in enumerate(targets):
        if isinstance(t, FrequencyTarget):
            tg.append(t)
        elif isinstance(t, int | float) and not isinstance(t, bool):
            tg.append(FrequencyTarget(float(t)))
        else:
            raise ParameterError(
                f"target {i + 1}: expected a FrequencyTarget or a frequency in Hz, "
                f"got {type(t).__name__}"
            )
    if not tg:
        raise ParameterError("update needs at least one target frequency")
    if weights is None:
        w = np.array([t.weight for t in tg])
    else:
        w = np.asarray(weights, dtype=float).ravel()
        if w.shape != (len(tg),):
            raise ParameterError(f"expected {len(tg)} weights (one per target), got {w.size}")
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ParameterError(f"weights must be finite and >= 0, got {w.tolist()}")
    if not np.any(w > 0):
        raise ParameterError("all target weights are zero")
    for name, v in (("regularization", regularization), ("mac_weight", mac_weight)):
        if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
            raise ParameterError(f"{name} must be a finite number >= 0, got {v!r}")
    if not (isinstance(max_iter, int) and max_iter >= 1):
        raise ParameterError(f"max_iter must be a positive integer, got {max_iter!r}")
    fixed_modes = [t.mode for t in tg if t.mode is not None]
    need = max([len(tg), *fixed_modes])
    if n_modes is None:
        n_modes = max(need, len(tg) + 4, 2 * len(tg))
    elif not (isinstance(n_modes, int) and n_modes >= need):
        raise ParameterError(
            f"n_modes must be an integer >= {need} (number of targets / highest fixed "
            f"mode), got {n_modes!r}"
        )
    return params, tg, w, n_modes


def update(
    description: Mapping[str, Any] | str | Path,
    parameters: Sequence[Parameter | str],
    targets: Sequence[FrequencyTarget | float],
    *,
    builder: Callable[[Mapping[str, Any]], FEModel] | None = None,
    n_modes: int | None = None,
    weights: Sequence[float] | None = None,
    regularization: float = 0.0,
    mac_weight: float = 0.0,
    eigvec_weight: float = 0.0,
    shape_derivative: str = "nelson",
    max_iter: int = 50,
    mode_classifier: Callable[[FEModel, np.ndarray], Sequence[str]] | None = None,
    frequency_std: float | None = None,
    model_form_std: float | None = None,
    identifiability_tol: float = 1e-3,
    rel_step: float | None = None,
    difference: str = "central",
    freq_tol: float = 1e-7,
    affine: bool = False,
    reduced_basis: bool | None = None,
    xtol: float = 1e-10,
    ftol: float = 1e-12,
) -> UpdateResult:
    """Update parameters of a structure description so the model matches target frequencies.

    Minimises, with bounds (:func:`scipy.optimize.least_squares`, trust-region
    reflective), the residual vector

    - ``w_i (f_i(p) - f_i^test) / f_i^test`` for every target (weighted relative
      frequency errors, f_i the paired model mode),
    - ``mac_weight * w_i * (1 - MAC_i)`` for targets with a measured shape (if
      ``mac_weight > 0``),
    - ``eigvec_weight * w_i * (s y/|y| - t/|t|)`` per sensor of each target with a
      measured shape (if ``eigvec_weight > 0``; ``y`` model, ``t`` test shape at the
      sensors, ``s = sign(t'y)``),
    - ``sqrt(regularization) * (x - x0)`` (Tikhonov towards the initial values),

    in scaled variables ``x = p / scale``. Modes are re-paired at every evaluation (MAC +
    Hungarian when shapes exist, else by order and mode type; see :func:`pair_modes`).
    The Jacobian is analytic: ``d(omega^2)/dp = phi'(dK/dp - omega^2 dM/dp) phi`` with
    ``dK/dp``, ``dM/dp`` finite differences of the assembled matrices (two extra builds
    per free parameter per iteration, one with ``difference="forward"``). MAC
    derivatives (only with ``mac_weight > 0``) use one extra eigen solve per parameter.
    If a perturbed build changes the DOF map (a mesh that conforms to a moved patch
    edge), the matrix difference is taken one-sided on the side that kept the mesh
    (``meta["one_sided_parameters"]``); if both sides changed it, that parameter falls
    back to finite differences of the eigenvalues, modes tracked by index
    (``meta["fd_eigen_parameters"]``).

    Parameters
    ----------
    description : mapping or path
        Structure description (nested dicts/lists, e.g. a parsed structure TOML), or
        the path of a structure TOML file.
    parameters : sequence of Parameter or str
        Fields to update (a str is ``Parameter(path)`` without bounds).
    targets : sequence of FrequencyTarget or float
        Measured natural frequencies (Hz).
    builder : callable, optional
        ``builder(description) -> FEModel``; default :func:`mvtk.fe.build_model`.
    n_modes : int, optional
        Model modes computed per evaluation (default ``max(2 n_t, n_t + 4)``).
    weights : sequence of float, optional
        Per-target weights overriding ``FrequencyTarget.weight``.
    regularization : float
        Tikhonov weight on ``x - x0`` (dimensionless, scaled variables).
    mac_weight : float
        Weight of the ``1 - MAC`` residuals (0: MAC only for pairing).
    eigvec_weight : float
        Weight of the eigenvector-difference residuals ``s y/|y| - t/|t|`` per sensor
        (``y`` the model shape at the target's sensors, ``t`` the measured shape,
        ``s = sign(t'y)``): they carry where the shapes differ, not only how much.
    shape_derivative : {"nelson", "fd"}
        Derivatives of the shape terms: ``"nelson"`` (analytic, Nelson's method from the
        same dK/dp, dM/dp as the eigenvalue derivatives: no extra eigen solve) or
        ``"fd"`` (one extra eigen solve per parameter, mode followed by M-overlap).
    max_iter : int
        Maximum number of residual evaluations (``max_nfev`` of least_squares; with
        ``reduced_basis``: of each reduced fit, whose evaluations cost no eigen solve).
    mode_classifier : callable, optional
        ``f(model, vectors) -> labels`` used for kind checks; default
        :func:`classify_modes`.
    frequency_std : float, optional
        Known relative standard deviation of the measured frequencies (e.g. 0.002),
        for the targets without ``std_hz``. Without any standard deviation (no target
        ``std_hz``, no ``model_form_std``) it only sets the parameter covariance; if
        None there, the residual variance ``|r|^2 / (m - n)`` is used (needs more
        targets than free parameters, else std is NaN).
    model_form_std : float, optional
        Relative standard deviation of the model-form term (what no parameter value of
        the model can reproduce), e.g. 0.005. When it is given or any target has
        ``std_hz``, every target is weighted statistically: its relative residual is
        divided by ``sigma_i / f_i`` with ``sigma_i^2 = std_hz_i^2 + (model_form_std
        f_i)^2`` (``std_hz_i = frequency_std f_i`` or 0 when the target has none), so
        the cost is half the chi-square and ``W = 1 / sigma^2``; the target ``weight``
        still multiplies it (1 keeps the chi-square meaning). None with some ``std_hz``:
        :data:`DEFAULT_MODEL_FORM_STD` (0.005). ``regularization`` is then the inverse
        prior variance of the scaled variables.
    identifiability_tol : float
        Smallest accepted ratio ``s_min / s_max`` of the singular values of the
        weighted frequency Jacobian (scaled variables); below it an
        :class:`~mvtk.errors.IdentifiabilityWarning` is issued.
    rel_step : float, optional
        Finite-difference step relative to each parameter's scale (default 1e-4 for
        central, 1e-6 for forward differences; with ``affine=True`` a step of half the
        scale is used, exact for affine matrices and free of cancellation where a
        small spring sits on a large stiffness entry).
    difference : {"central", "forward"}
        Scheme for dK/dp, dM/dp: central (two builds per free parameter per
        iteration, accurate for geometry) or forward (one build; exact for parameters
        entering the matrices linearly such as moduli, densities, springs).
    freq_tol : float
        Stop as soon as every relative frequency error is below this (only without
        MAC and regularisation terms, whose optimum is not an exact match; 0 disables).
    affine : bool
        Assume K and M are affine in every free parameter on a fixed mesh (moduli,
        densities, spring stiffnesses; not geometry): build the model once plus once
        per parameter, then evaluate ``K(p) = K0 + sum_j (p_j - p0_j) dK/dp_j`` (same
        for M) without further builds. A real build at the solution checks the
        assumption (``meta["affine_check_rel"]``; AccuracyWarning above 1e-6) and
        provides ``model``. A builder with a ``matrix_derivatives(path) -> (dK, dM)``
        method (:class:`mvtk.fe.AffineModel`) gives the exact derivatives instead.
    reduced_basis : bool, optional
        Iterate on a reduced (Rayleigh-Ritz) model instead of solving the full
        eigenproblem at every evaluation. Applies when ``affine=True`` and there are no
        mode-shape residuals (``mac_weight = eigvec_weight = 0``; MAC pairing is fine):
        the basis holds the full modes at the initial values, the fit runs on the
        projected ``V'K(p)V``, ``V'M(p)V``, then ONE full eigen solve at the reduced
        optimum checks it and its modes join the basis; the rounds repeat until the
        full model's own Gauss-Newton step at the last full solution is below 1e-8
        (scaled variables; see :mod:`mvtk.updating._reduced`), so the result is a
        stationary point of the full problem and every reported quantity
        (frequencies, shapes, Jacobian, diagnostics) comes from the full model at the
        final values. ``meta["reduced_basis"]`` gives the rounds, the full eigen
        solves (``n_full_eigen``; ``timing["n_eigen"]`` counts all), the reduced-vs-full
        frequency mismatch at the final values (``mismatch``) and that Gauss-Newton
        step; history entries of the reduced model have ``model="reduced"``. The
        affine check then uses Rayleigh quotients of the final modes on the real build
        (no further eigen solve; ``meta["reduced_basis"]["affine_check"]``). None
        (default): on whenever it applies; False: every evaluation on the full model,
        as before; True: required (a ParameterError if it does not apply).
    xtol, ftol : float
        Stopping tolerances of least_squares.

    Returns
    -------
    UpdateResult

    Warns
    -----
    IdentifiabilityWarning
        Fewer target rows than free parameters or a near-singular sensitivity matrix
        (e.g. a modulus and a density together from frequencies alone).
    AccuracyWarning
        The solver stopped at ``max_iter`` evaluations.

    Notes
    -----
    Eigenvalue derivative: Fox & Kapoor, AIAA J 6(12), 1968. The standard deviation of
    the parameters uses the Gauss-Newton covariance
    ``A^-1 J_d' Sigma J_d A^-1`` with ``A = J'J`` (data and regularisation rows) and
    ``Sigma`` the residual covariance (Friswell & Mottershead, Finite Element Model
    Updating in Structural Dynamics, 1995, ch. 7). With statistical weights
    (``model_form_std`` or target ``std_hz``) the weighted rows have unit variance and
    without regularisation this is ``(J_f' W J_f)^-1``: the a-priori covariance, not
    scaled by the a-posteriori variance factor ``chi^2 / (m - n)``, which is reported
    (``meta["variance_factor"]``) as the test of the stated standard deviations.

    Residual verdicts: linearised at the solution, a relative error ``e`` of the
    targets moves the relative residuals by ``-P e`` with
    ``P = I - J_r A^-1 J_r' W^2`` (``J_r`` the relative frequency Jacobian, ``W`` the
    row weights), so the residual of target i has the standard deviation
    ``s_i = sqrt((P D P')_ii)`` for target variances ``D``. With ``s_id`` from the
    identification variances and ``s_tot`` from those plus the model-form term:
    ``|r_i| <= 2 s_id``: ``"noise"``; ``<= 2 s_tot``: ``"model-form term"`` (explained
    by the stated model-form allowance); beyond: ``"model form"`` (the model lacks
    something no updated value can supply); ``s_tot`` below 1e-3 of the target's own
    standard deviation (as many free parameters as the targets they fit):
    ``"no redundancy"``; no standard deviation at all: ``"no std"``.

    Examples
    --------
    Young's modulus of a steel cantilever (300 x 20 x 2 mm) updated to a measured first
    frequency 10 % stiffer than the model's (f ~ sqrt(E), so E must grow by 10 %):

    >>> from mvtk.fe import build_model, modal_analysis
    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> f1 = modal_analysis(build_model(beam), 1).fn_hz[0]            # 18.566 Hz
    >>> res = update(beam, ["materials.steel.E"], [f1 * np.sqrt(1.1)], n_modes=2)
    >>> round(float(res.values[0]) / 2.1e11, 4)
    1.1
    >>> round(res.description["materials"]["steel"]["E"] / 1e9, 3)     # GPa
    231.0
    """
    from scipy.optimize import least_squares

    if isinstance(description, str | Path):
        import tomllib

        try:
            description = tomllib.loads(Path(description).read_text(encoding="utf-8"))
        except (OSError, tomllib.TOMLDecodeError) as err:
            raise ConfigError(f"cannot read structure TOML {description}: {err}") from err
    if not isinstance(description, Mapping):
        raise ParameterError(
            f"description must be a mapping (parsed structure TOML), got "
            f"{type(description).__name__}"
        )
    params, tg, w, n_modes = _check_inputs(
        parameters, targets, weights, regularization, mac_weight, max_iter, n_modes
    )
    if frequency_std is not None and not (
        isinstance(frequency_std, int | float) and frequency_std > 0
    ):
        raise ParameterError(f"frequency_std must be a positive number, got {frequency_std!r}")
    w, sigma = _statistical_weights(tg, w, frequency_std, model_form_std)
    check_difference(difference)
    if rel_step is None:
        rel_step = 1e-4 if difference == "central" else 1e-6
    if not (isinstance(rel_step, int | float) and 0 < rel_step < 1):
        raise ParameterError(f"rel_step must be in (0, 1), got {rel_step!r}")
    if builder is None:
        builder = _default_builder()
    if not (isinstance(eigvec_weight, int | float) and math.isfinite(eigvec_weight)
            and eigvec_weight >= 0):
        raise ParameterError(f"eigvec_weight must be a finite number >= 0, got {eigvec_weight!r}")
    if shape_derivative not in ("nelson", "fd"):
        raise ParameterError(
            f"shape_derivative must be 'nelson' or 'fd', got {shape_derivative!r}")
    if eigvec_weight > 0 and not any(t.has_shape for t in tg):
        raise ParameterError("eigvec_weight > 0 needs targets with measured shapes")
    if reduced_basis not in (None, True, False):
        raise ParameterError(f"reduced_basis must be None, True or False, got {reduced_basis!r}")
    rb_applies = bool(affine) and mac_weight == 0 and eigvec_weight == 0
    if reduced_basis and not rb_applies:
        raise ParameterError(
            "reduced_basis=True needs affine=True and no mode-shape residuals "
            f"(mac_weight = eigvec_weight = 0), got affine={affine!r}, "
            f"mac_weight={mac_weight!r}, eigvec_weight={eigvec_weight!r}")
    use_rb = rb_applies if reduced_basis is None else bool(reduced_basis)
    prob = _Problem(description, params, tg, builder, n_modes, w, float(mac_weight),
                    float(regularization), mode_classifier, rel_step, difference,
                    affine=bool(affine), eigvec_weight=float(eigvec_weight),
                    shape_derivative=shape_derivative)
    free = prob.free
    lb = prob.to_x(np.array([p.lower for p in params])[free])
    ub = prob.to_x(np.array([p.upper for p in params])[free])
    st0 = prob.state(prob.x0)
    fn0, modes0, mac0 = st0.fn_all[st0.pairing.modes], st0.pairing.modes + 1, st0.pairing.mac
    # identifiability at the start: a symmetric structure has equal sensitivity columns
    # for mirror-image parameters there, and the frequencies then cannot tell which of
    # several (mirror) solutions is the right one, even if the end point looks regular
    n_shape0 = len(prob.mac_rows) + prob.n_eig
    J0 = prob.jacobian(prob.x0)
    free_names = [p.path for p in params if not p.fixed]
    init_f = _rank_report(J0[: len(tg)], identifiability_tol, free_names)
    init_d = (_rank_report(J0[: len(tg) + n_shape0], identifiability_tol, free_names)
              if n_shape0 else None)
    if not (isinstance(freq_tol, int | float) and freq_tol >= 0):
        raise ParameterError(f"freq_tol must be a number >= 0, got {freq_tol!r}")
    if mac_weight == 0 and regularization == 0 and eigvec_weight == 0:
        prob.freq_tol = float(freq_tol)
    rb_meta = {"used": False}
    if use_rb:
        x, status, message, nfev, rb_meta = reduced_fit(
            prob, st0, lb, ub, max_iter=max_iter, xtol=xtol, ftol=ftol, matched=_Matched,
            freq_tol=prob.freq_tol)
    else:
        try:
            sol = least_squares(
                prob.residual, prob.x0, jac=prob.jacobian, bounds=(lb, ub), method="trf",
                x_scale=1.0, max_nfev=max_iter, xtol=xtol, ftol=ftol, gtol=1e-12,
            )
            x, status, message, nfev = sol.x, int(sol.status), str(sol.message), int(sol.nfev)
        except _Matched:
            x = prob._cache.x
            status, nfev = 5, len(prob.history)
            message = f"every relative frequency error is below freq_tol = {freq_tol:g}"
    prob.freq_tol = 0.0
    st = prob.state(x)
    J = prob.jacobian(x)
    n_t, n_free = len(tg), int(free.sum())
    n_shape = len(prob.mac_rows) + prob.n_eig
    n_data = n_t + n_shape
    Jd = J[:n_data]
    Jf = J[:n_t]
    # identifiability from the frequency rows (regularisation would mask it)
    _, s, vt = np.linalg.svd(Jf)  # vt: (n_free, n_free)
    s_full = np.zeros(n_free)
    s_full[: s.size] = s
    smax = float(s_full.max()) if s_full.size else 0.0
    ratio = s_full / smax if smax > 0 else np.zeros_like(s_full)
    weak = np.flatnonzero(ratio < identifiability_tol)
    cond = float(smax / s_full.min()) if s_full.min() > 0 else math.inf
    free_params = [p for p in params if not p.fixed]
    shape_ok, s_data = None, None
    if n_shape:
        sd = np.linalg.svd(Jd, compute_uv=False)
        s_data = np.zeros(n_free)
        s_data[: sd.size] = sd
        rd = s_data / s_data.max() if s_data.max() > 0 else np.zeros_like(s_data)
        shape_ok = bool(np.all(rd >= identifiability_tol))
    null_dirs = []
    if weak.size:
        for k in weak:
            v = vt[k]
            null_dirs.append({p.path: round(float(c), 4) for p, c in zip(free_params, v)})
        pretty = "; ".join(
            " + ".join(f"{c:+.2f}*{pth}" for pth, c in d.items() if abs(c) > 1e-3)
            for d in null_dirs
        )
        why = (
            f"{n_t} target frequencies for {n_free} free parameters"
            if n_t < n_free else f"condition number {cond:.3g}"
        )
        if shape_ok is not True:
            shapes_too = " (nor the mode-shape terms)" if n_shape else ""
            warnings.warn(
                f"parameters cannot be separated by the targets ({why}); the frequencies"
                f"{shapes_too} do not change along the direction(s) (in p/scale) {pretty}. "
                "Fix one of them, add targets (other modes, mode shapes) or use "
                "regularization",
                IdentifiabilityWarning, stacklevel=2,
            )
    if (not weak.size and not init_f["identifiable"]
            and (init_d is None or not init_d["identifiable"])):
        pretty0 = "; ".join(
            " + ".join(f"{c:+.2f}*{pth}" for pth, c in d.items() if abs(c) > 1e-3)
            for d in init_f["null_directions"]
        )
        warnings.warn(
            "at the initial values the targets cannot separate the parameters along "
            f"{pretty0}: several parameter sets (e.g. mirror images on a symmetric "
            "structure) may fit them equally well and the result may be the wrong one; "
            "add mode-shape targets (eigvec_weight) or fix parameters",
            IdentifiabilityWarning, stacklevel=2,
        )
    # covariance (scaled variables) -> physical units
    std_note = None
    A = J.T @ J
    ft = np.array([t.fn_hz for t in tg])
    if sigma["weighted"]:
        # weighted rows w_i r_i with w_i = weight_i f_i / sigma_i: variance weight_i^2
        sig = np.concatenate([(w * sigma["total_hz"] / ft) ** 2, np.zeros(n_shape)])
    elif frequency_std is not None:
        sig = np.concatenate([(w * frequency_std) ** 2, np.zeros(n_shape)])
    elif n_data > n_free:
        r = st.residual[:n_data]
        sig = np.full(n_data, float(r @ r) / (n_data - n_free))
    else:
        sig = np.full(n_data, np.nan)
        std_note = (
            f"std not estimated: {n_data} residuals for {n_free} free parameters leave no "
            "degree of freedom for the residual variance; give frequency_std"
        )
    Ainv = np.linalg.pinv(A)
    cov_x = Ainv @ (Jd.T * sig) @ Jd @ Ainv
    sc = prob.dp_dx(x)
    cov = cov_x * np.outer(sc, sc)
    std_free = np.sqrt(np.abs(np.diag(cov)))
    if weak.size and regularization == 0 and shape_ok is not True:
        involved = np.zeros(n_free, dtype=bool)
        for d in null_dirs:
            involved |= np.abs(np.array(list(d.values()))) > 1e-3
        std_free[involved] = math.inf
    std = np.full(len(params), np.nan)
    std[free] = std_free
    values = prob.values(x)
    at_bound = np.zeros(len(params), dtype=bool)
    span = np.where(np.isfinite(ub - lb), ub - lb, np.abs(x) + 1.0)
    at_bound[free] = (np.abs(x - lb) <= 1e-6 * span) | (np.abs(ub - x) <= 1e-6 * span)
    if at_bound.any():
        hit = [p.path for p, b in zip(params, at_bound) if b]
        warnings.warn(
            f"parameters {hit} ended on a bound; the match may rely on the bound, not the "
            "data", AccuracyWarning, stacklevel=2,
        )
    if status == 0:
        warnings.warn(
            f"model updating stopped after {nfev} evaluations (max_iter={max_iter}) "
            f"without meeting the tolerances; cost {0.5 * st.residual @ st.residual:.3g}",
            AccuracyWarning, stacklevel=2,
        )
    fp = st.fn_all[st.pairing.modes]
    with np.errstate(divide="ignore", invalid="ignore"):
        dfp = st.d_omega2 / (8 * math.pi**2 * fp[:, None])
        sens = dfp * values[free][None, :] / fp[:, None]
    rel = (fp - ft) / ft
    verdict = _residual_verdicts(rel, dfp / ft[:, None] * prob.dp_dx(x)[None, :], A, w,
                                 sigma, ft)
    n_w = int(np.count_nonzero(w > 0))
    chi2 = float(np.sum((w * rel) ** 2)) if sigma["weighted"] else math.nan
    var_factor = chi2 / (n_w - n_free) if sigma["weighted"] and n_w > n_free else math.nan
    kinds = st.kinds if st.kinds is not None else prob.kinds_of(st.model, st.vectors)
    final_model = st.model
    affine_dev = None
    if affine:
        final_model = prob.build(prob.describe(x))
        if use_rb and same_dofs(final_model, st.model):
            # Rayleigh quotients of the final modes on the real build: the frequency
            # change its matrices cause, exact to first order in their difference from
            # the affine ones (to its square), without an eigen solve
            phi = st.vectors[:, st.pairing.modes]
            affine_dev = float(np.max(np.abs(np.sqrt(
                _rayleigh(final_model, phi) / _rayleigh(st.model, phi)) - 1.0)))
            rb_meta["affine_check"] = "rayleigh"
        else:
            true_eig = prob.eigen(final_model)
            true_f = np.sqrt(np.maximum(true_eig.omega2[st.pairing.modes], 0.0)) / TWO_PI
            affine_dev = float(np.max(np.abs(true_f / fp - 1.0)))
        if affine_dev > 1e-6:
            warnings.warn(
                f"affine=True: a real build at the solution gives frequencies up to "
                f"{100 * affine_dev:.3g} % away from the affine model; the matrices are not "
                "affine in the parameters (geometry?), rerun with affine=False",
                AccuracyWarning, stacklevel=2,
            )
    return UpdateResult(
        description=prob.describe(x),
        initial_description=prob.describe(prob.x0),
        model=final_model,
        parameters=tuple(params),
        targets=tuple(tg),
        initial_values=prob.initial.copy(),
        values=values,
        std=std,
        covariance=cov,
        at_bound=at_bound,
        fn_hz_initial=fn0,
        fn_hz=fp,
        modes_initial=modes0,
        modes=st.pairing.modes + 1,
        mac_initial=mac0,
        mac=st.pairing.mac,
        pairing_method=st.pairing.method,
        model_fn_hz=st.fn_all,
        model_kinds=tuple(kinds),
        sensitivity=sens,
        singular_values=s_full,
        condition_number=cond,
        identifiable=not weak.size,
        null_directions=tuple(null_dirs),
        history=tuple(prob.history),
        swaps=tuple(prob.swaps),
        success=bool(status > 0),
        message=message,
        n_evaluations=nfev,
        n_jacobians=int(prob.timing["n_jacobians"]),
        cost=float(0.5 * st.residual @ st.residual),
        timing=dict(prob.timing),
        meta={"n_modes": n_modes, "fd_eigen_parameters": sorted(prob.fd_params),
              "one_sided_parameters": sorted(prob.one_sided),
              "least_squares_status": status, "affine_check_rel": affine_dev,
              "reduced_basis": rb_meta,
              "std_note": std_note,
              "weighting": "statistical" if sigma["weighted"] else "weights",
              "model_form_std": sigma["model_form"],
              "chi_square": chi2, "variance_factor": var_factor,
              "covariance_scaling": (
                  "a priori (stated standard deviations, not scaled by the variance "
                  "factor)" if sigma["weighted"] or frequency_std is not None else
                  ("a posteriori (residual variance)" if std_note is None else "none")),
              "initial_frequency_singular_values": init_f["singular_values"],
              "initial_data_singular_values": (None if init_d is None
                                               else init_d["singular_values"])},
        identifiable_with_shapes=shape_ok,
        initial_identifiable=init_f["identifiable"],
        initial_identifiable_with_shapes=None if init_d is None else init_d["identifiable"],
        initial_null_directions=tuple(init_f["null_directions"]),
        data_singular_values=s_data,
        identification_std_hz=sigma["id_hz"],
        target_std_hz=sigma["total_hz"],
        verdicts=tuple(verdict["verdict"]),
        residual_limits_hz=verdict["limits_hz"],
    )
