"""Structural plants ``M q'' + C q' + K q = B u`` from a super element or an FE model.

:func:`structural_plant` turns a :class:`~mvtk.reduction.SuperElement` (or, for
reference, the full :class:`~mvtk.fe.FEModel`) into a labelled
:class:`~mvtk.control.SecondOrderSystem`. Inputs are load vectors on the free DOFs of
the full model (e.g. the piezo patch load per volt) or unit forces/moments at
``(node, component)``; they are projected with ``T'``. Outputs are displacements or
velocities at ``(node, component)`` or any free-DOF row vector (e.g. the patch strain as
a difference of rotations), projected with ``T``.

In modal form the coordinates are the mass-normalised eigenmodes of the plant, so
Rayleigh damping ``alpha M + beta K`` becomes exactly ``diag(alpha + beta omega^2)``.
Truncating modes loses static flexibility; the static correction adds the residual
flexibility of the dropped modes as a feedthrough ``D`` so the DC gain stays exact
(PHYSICS.md section 3).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import AccuracyWarning, DimensionError, ParameterError
from ..fe import DOF_NAMES, FEModel, eigsh_lowest, factorize
from ..reduction import SuperElement
from ..reduction._craig_bampton import damping_matrix, reduced_modes, solve_columns
from ._second_order import SecondOrderSystem
from ._statespace import StateSpace

__all__ = ["StructuralPlant", "structural_plant", "dof_load", "dof_output"]

#: Largest full FE model accepted in physical form (dense matrices).
MAX_DENSE_DOF = 3000

_QUANTITIES = ("displacement", "velocity")


@dataclass(frozen=True, eq=False)
class StructuralPlant(SecondOrderSystem):
    """A :class:`SecondOrderSystem` with a direct feedthrough ``D`` (static correction).

    ``y = Cq q + Cv q' + D u``. ``D`` is zero unless modes were truncated with static
    correction. :meth:`to_state_space` carries ``D`` into the :class:`StateSpace`.
    Controllers that only use ``M, C, K, B`` see the truncated modal model.

    Examples
    --------
    Returned by :func:`structural_plant`; ``to_state_space`` carries the feedthrough ``D``:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)], n_elements=10)
    >>> plant = structural_plant(beam, {"force": (10, "uz")}, {"tip": (10, "uz")},
    ...                          form="modal", n_modes=3, modal_damping=0.01)
    >>> plant.M.shape, plant.D.shape
    ((3, 3), (1, 1))
    """

    D: np.ndarray | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        p, m = self.Cq.shape[0], self.B.shape[1]
        D = np.zeros((p, m)) if self.D is None else np.asarray(self.D, dtype=float)
        if D.shape != (p, m):
            raise DimensionError(f"D must have shape ({p}, {m}), got {D.shape}")
        object.__setattr__(self, "D", D)

    def to_state_space(self) -> StateSpace:
        """State space with ``x = [q; q']`` and the feedthrough ``D``."""
        ss = super().to_state_space()
        return dataclasses.replace(ss, D=self.D)


def dof_load(model: FEModel, node: int, component: int | str, value: float = 1.0) -> np.ndarray:
    """Free-DOF load vector with ``value`` (N or N m) at one DOF.

    Examples
    --------
    A unit force on the tip uz DOF of a cantilever:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)])
    >>> f = dof_load(beam, 20, "uz")
    >>> float(f.sum()), int(f.argmax()) == beam.dof_index(20, "uz")
    (1.0, True)
    """
    f = np.zeros(model.n_dof)
    f[model.dof_index(node, component)] = value
    return f


def dof_output(model: FEModel, node: int, component: int | str) -> np.ndarray:
    """Free-DOF row vector picking one DOF (displacement in m or rotation in rad).

    Examples
    --------
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)])
    >>> c = dof_output(beam, 20, "uz")
    >>> c.shape, int(c.argmax()) == beam.dof_index(20, "uz")
    ((120,), True)
    """
    return dof_load(model, node, component, 1.0)


def _is_dof_spec(spec) -> bool:
    return (
        isinstance(spec, tuple | list)
        and len(spec) in (2, 3)
        and isinstance(spec[0], int | np.integer)
        and isinstance(spec[1], str | int | np.integer)
    )


def _named(specs, what: str) -> list[tuple[str | None, object]]:
    if isinstance(specs, Mapping):
        return [(str(k), v) for k, v in specs.items()]
    single = (isinstance(specs, np.ndarray) and specs.ndim == 1) or _is_dof_spec(specs)
    if single or hasattr(specs, "load_vector"):
        specs = [specs]
    try:
        items = list(specs)
    except TypeError:
        raise ParameterError(
            f"{what} must be a mapping name -> spec or a sequence of specs, got "
            f"{type(specs).__name__}"
        ) from None
    if not items:
        raise ParameterError(f"at least one {what[:-1]} is needed, got none")
    return [(None, s) for s in items]


def _component_name(component) -> str:
    return component if isinstance(component, str) else DOF_NAMES[int(component)]


def _vector(model: FEModel, v, what: str, key) -> np.ndarray:
    vec = np.asarray(v, dtype=float)
    if vec.shape != (model.n_dof,):
        raise DimensionError(
            f"{what} {key!r}: a vector spec must have shape ({model.n_dof},) (free DOFs of "
            f"the full model), got {vec.shape}"
        )
    return vec


def _parse_inputs(model: FEModel, inputs, units):
    vectors, names, unit_list = [], [], []
    for i, (name, spec) in enumerate(_named(inputs, "inputs")):
        if hasattr(spec, "load_vector"):
            # an actuator such as mvtk.fe._piezo.PiezoPatch: load per volt
            vectors.append(_vector(model, spec.load_vector(model), "input", name or i))
            names.append(name or str(getattr(spec, "name", f"u{i}")))
            unit_list.append("V")
        elif _is_dof_spec(spec):
            if len(spec) != 2:
                raise ParameterError(
                    f"input {spec!r}: a DOF input is (node, component), got {len(spec)} items"
                )
            node, comp = spec
            vectors.append(dof_load(model, node, comp))
            cname = _component_name(comp)
            names.append(name or f"f:n{int(node)}:{cname}")
            unit_list.append("N" if cname.startswith("u") else "N m")
        else:
            vectors.append(_vector(model, spec, "input", name or i))
            names.append(name or f"u{i}")
            unit_list.append("")
    if units is not None:
        unit_list = list(units)
        if len(unit_list) != len(vectors):
            raise DimensionError(
                f"expected {len(vectors)} input units, got {len(unit_list)}"
            )
    return np.column_stack(vectors), tuple(names), tuple(unit_list)


def _parse_outputs(model: FEModel, outputs, units):
    rows, quantities, names, unit_list = [], [], [], []
    for i, (name, spec) in enumerate(_named(outputs, "outputs")):
        quantity = "displacement"
        if _is_dof_spec(spec):
            node, comp = spec[0], spec[1]
            if len(spec) == 3:
                quantity = spec[2]
            row = dof_output(model, node, comp)
            cname = _component_name(comp)
            base = "m" if cname.startswith("u") else "rad"
            label = f"n{int(node)}:{cname}"
        else:
            if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[1], str):
                spec, quantity = spec
            row = _vector(model, spec, "output", name or i)
            base, label = "", f"y{i}"
        if quantity not in _QUANTITIES:
            raise ParameterError(
                f"output {name or i}: quantity must be one of {_QUANTITIES}, got {quantity!r}"
            )
        rows.append(row)
        quantities.append(quantity)
        prefix = "u" if quantity == "displacement" else "v"
        names.append(name or (f"{prefix}:{label}" if base else label))
        unit_list.append(base if quantity == "displacement" or not base else f"{base}/s")
    if units is not None:
        unit_list = list(units)
        if len(unit_list) != len(rows):
            raise DimensionError(f"expected {len(rows)} output units, got {len(unit_list)}")
    return np.vstack(rows), np.array(quantities), tuple(names), tuple(unit_list)


def _modal_damping_diag(zeta, n_kept, n_total, omega):
    z = np.asarray(zeta, dtype=float)
    if z.ndim == 0:
        z = np.full(n_kept, float(z))
    elif z.shape in ((n_kept,), (n_total,)):
        z = z[:n_kept]
    else:
        raise DimensionError(
            f"modal_damping must be one ratio or one per mode ({n_kept} kept"
            f"{'' if n_total == n_kept else f' or {n_total} total'}), got shape {z.shape}"
        )
    if np.any(z < 0):
        raise ParameterError(f"damping ratios must be >= 0, got min {z.min()}")
    return 2.0 * z * omega


def _check_restrained(K, M, w2: np.ndarray, correct: bool) -> None:
    """Static correction needs K^-1: refuse a structure with rigid-body modes.

    The lowest eigenvalue must exceed ``1e-8`` times the seventh one (a free structure
    has up to six rigid-body modes, whose computed eigenvalues are round-off) and 1 mHz. Diagonal
    ratios ``K_ii / M_ii`` are no scale here: the nearly massless drilling coordinates of
    shell models make them huge.
    """
    if not correct:
        return
    rigid_floor = (2.0 * np.pi * 1e-3) ** 2  # a mode below 1 mHz counts as rigid-body
    if w2.size and w2[0] > rigid_floor and w2[0] > 1e-8 * w2[min(6, w2.size - 1)]:
        return
    lowest = w2[0] if w2.size else 0.0
    raise ParameterError(
        "static correction needs a restrained structure, but K is singular (rigid-body "
        f"mode, lowest omega^2 = {lowest:.3g} (rad/s)^2); use static_correction=False"
    )


def structural_plant(
    se_or_model,
    inputs,
    outputs,
    *,
    alpha: float = 0.0,
    beta: float = 0.0,
    modal_damping: float | Iterable[float] | None = None,
    form: str = "physical",
    n_modes: int | None = None,
    static_correction: bool = True,
    input_units: Iterable[str] | None = None,
    output_units: Iterable[str] | None = None,
) -> StructuralPlant:
    """Second-order plant of a super element (or full FE model) with labelled signals.

    Parameters
    ----------
    se_or_model : SuperElement or FEModel
        The structure. A full FE model is accepted for reference comparisons (physical
        form up to :data:`MAX_DENSE_DOF` DOFs; modal form needs ``n_modes``).
    inputs : mapping name -> spec, or sequence of specs
        Each spec is ``(node, component)`` (unit force in N or moment in N m at that DOF),
        a load vector of shape ``(n_dof,)`` over the free DOFs of the full model, or an
        actuator object with ``load_vector(model)`` giving the load per volt, such as
        :class:`mvtk.fe._piezo.PiezoPatch` (input in V, named after the patch).
    outputs : mapping name -> spec, or sequence of specs
        Each spec is ``(node, component)`` or ``(node, component, quantity)`` with
        quantity ``"displacement"`` (default; m or rad) or ``"velocity"`` (m/s, rad/s),
        or a free-DOF row vector ``c`` (output ``c u``, e.g. a rotation difference
        proportional to the patch strain), or ``(c, quantity)``.
    alpha, beta : float
        Rayleigh damping ``C = alpha M + beta K`` (alpha in 1/s, beta in s).
    modal_damping : float or sequence, optional
        Damping ratio(s) of the plant's eigenmodes instead of Rayleigh damping.
    form : {"physical", "modal"}
        Coordinates: the SE's (boundary DOFs + fixed-interface modal coordinates) or
        the plant's mass-normalised eigenmodes (diagonal M = I, K = diag(omega^2), and
        diagonal C for Rayleigh or modal damping).
    n_modes : int, optional
        Modal form only: number of eigenmodes kept (default: all SE modes of finite
        frequency; required for an FE model). Shell super elements have boundary
        drilling rotations without inertia: their M is singular (the physical form warns)
        and the highest finite modes can reach 1e7 Hz; keep ``n_modes`` to the band of
        interest with ``static_correction=True`` for a non-stiff plant.
    static_correction : bool
        Modal form with truncation (or massless coordinates): add the residual static
        flexibility of the dropped modes as a feedthrough ``D`` on displacement outputs,
        so the DC gain is exact.
    input_units, output_units : sequence of str, optional
        Override the unit strings (defaults: N / N m for DOF inputs, V for actuators,
        m / rad / m/s / rad/s for DOF outputs, empty for vectors).

    Returns
    -------
    StructuralPlant
        A :class:`SecondOrderSystem` (with ``D``); ``.to_state_space()`` gives the
        :class:`StateSpace` (``x = [q; q']``). ``meta`` holds ``form``, ``source``,
        ``fn_hz`` (modal form), ``alpha``, ``beta``.

    Examples
    --------
    A force at the tip of a steel cantilever (300 x 20 x 2 mm) reduced to its tip node
    and 4 fixed-interface modes, tip displacement out, 1 % modal damping. The static gain
    is the tip flexibility ``L**3 / (3 E I)`` = 3.214 mm/N:

    >>> from mvtk.control import closed_loop_modes
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> from mvtk.reduction import craig_bampton
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> tip = int(beam.node_sets["tip"][0])
    >>> se = craig_bampton(beam, [tip], n_modes=4)
    >>> plant = structural_plant(se, {"force": (tip, "uz")}, {"tip": (tip, "uz")},
    ...                          modal_damping=0.01)
    >>> np.round(closed_loop_modes(plant).fn_hz[:2], 2)
    array([ 18.57, 116.37])
    >>> round(float(plant.to_state_space().dc_gain()[0, 0]) * 1e3, 3)     # mm/N
    3.214
    """
    if isinstance(se_or_model, SuperElement):
        se, model = se_or_model, se_or_model.model
    elif isinstance(se_or_model, FEModel):
        se, model = None, se_or_model
    else:
        raise ParameterError(
            f"expected a SuperElement or an FEModel, got {type(se_or_model).__name__}"
        )
    if form not in ("physical", "modal"):
        raise ParameterError(f"form must be 'physical' or 'modal', got {form!r}")
    if alpha < 0 or beta < 0:
        raise ParameterError(f"Rayleigh coefficients must be >= 0, got alpha={alpha}, beta={beta}")
    if modal_damping is not None and (alpha or beta):
        raise ParameterError("give either Rayleigh alpha/beta or modal_damping, not both")
    F, in_names, in_units = _parse_inputs(model, inputs, input_units)
    Cphys, quantities, out_names, out_units = _parse_outputs(model, outputs, output_units)
    disp = quantities == "displacement"
    meta = {"form": form, "source": "super_element" if se is not None else "fe_model",
            "alpha": float(alpha), "beta": float(beta), "modal_damping": modal_damping}

    if form == "physical":
        if n_modes is not None:
            raise ParameterError("n_modes applies to form='modal' only")
        if se is not None:
            M, K, coords = se.M, se.K, list(se.labels)
            n_massless = reduced_modes(K, M).n_massless
            if n_massless:
                warnings.warn(
                    f"{n_massless} coordinate(s) of the super element have no inertia (e.g. "
                    "shell drilling rotations): M is singular and the physical-form state "
                    "space is ill-conditioned; use form='modal'",
                    AccuracyWarning,
                    stacklevel=2,
                )
            B, Cr = se.T.T @ F, Cphys @ se.T
        else:
            if model.n_dof > MAX_DENSE_DOF:
                raise ParameterError(
                    f"the FE model has {model.n_dof} DOFs; physical form is limited to "
                    f"{MAX_DENSE_DOF} (dense matrices): use form='modal' with n_modes"
                )
            M, K, coords = model.M.toarray(), model.K.toarray(), model.dof_labels
            B, Cr = F, Cphys
        C = damping_matrix(M, K, alpha, beta, modal_damping)
        return StructuralPlant(
            M=M, C=C, K=K, B=B, Cq=np.where(disp[:, None], Cr, 0.0),
            Cv=np.where(disp[:, None], 0.0, Cr), inputs=in_names, outputs=out_names,
            coords=coords, input_units=in_units, output_units=out_units, meta=meta,
        )

    # ---------------------------------------------------------------- modal form
    if se is not None:
        modes = reduced_modes(se.K, se.M)
        n_total = se.n_dof
        n_finite = modes.omega2.size
        n_kept = n_finite if n_modes is None else int(n_modes)
        if not 1 <= n_kept <= n_finite:
            raise ParameterError(
                f"n_modes must be in 1..{n_finite} (SE modes of finite frequency; SE size "
                f"{n_total}), got {n_modes}"
            )
        w2, phi = modes.omega2, modes.vectors
        B_r, C_r = se.T.T @ F, Cphys @ se.T
        correct = n_kept < n_total and static_correction
        _check_restrained(se.K, se.M, w2, correct)
        if correct:
            flex = np.linalg.solve(se.K, B_r)
        w2, phi = w2[:n_kept], phi[:, :n_kept]
    else:
        if n_modes is None:
            raise ParameterError("modal form of a full FE model needs n_modes")
        n_total = model.n_dof
        n_kept = int(n_modes)
        if not 1 <= n_kept <= n_total:
            raise ParameterError(f"n_modes must be in 1..{n_total}, got {n_modes}")
        sol = eigsh_lowest(model.K, model.M, n_kept)
        w2, phi = sol.omega2, sol.vectors
        B_r, C_r = F, Cphys
        correct = n_kept < n_total and static_correction
        _check_restrained(model.K, model.M, w2, correct)
        if correct:
            flex = solve_columns(factorize(model.K), F)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    Bm, Cm = phi.T @ B_r, C_r @ phi
    if modal_damping is not None:
        cdiag = _modal_damping_diag(modal_damping, n_kept, n_total if se is None else n_finite,
                                    omega)
    else:
        cdiag = alpha + beta * w2
    D = np.zeros((Cm.shape[0], Bm.shape[1]))
    if correct:
        residual = flex - phi @ (Bm / w2[:, None])
        D[disp] = C_r[disp] @ residual
    meta.update(fn_hz=omega / (2 * np.pi), n_modes=n_kept, static_correction=correct)
    return StructuralPlant(
        M=np.eye(n_kept), C=np.diag(cdiag), K=np.diag(w2), B=Bm,
        Cq=np.where(disp[:, None], Cm, 0.0), Cv=np.where(disp[:, None], 0.0, Cm),
        inputs=in_names, outputs=out_names, coords=[f"mode{i + 1}" for i in range(n_kept)],
        input_units=in_units, output_units=out_units, meta=meta, D=D,
    )
