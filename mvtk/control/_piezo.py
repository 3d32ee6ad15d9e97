"""Plants whose inputs are piezo electrode voltages and outputs their charge or voltage.

With the electromechanical coupling of :func:`mvtk.fe.piezo_coupling` (``K q = f + B V``,
``Q = B' q + C_p V``), an actuator electrode is an input of load vector ``b`` per volt
and a sensor electrode an output:

- ``sensing="charge"`` (electrodes shorted through a charge amplifier): ``Q = b' q``
  (C), plus the feed-through ``C_p V`` when the sensor is the driven electrode itself
  (self-sensing);
- ``sensing="voltage"`` (open electrodes, a high-impedance voltage amplifier):
  ``V_s = -C_s^-1 b' q`` (V), with the open-circuit stiffness ``b C_s^-1 b'`` of the
  sensor electrodes added to the structure. On a super element the added term is the
  exact projection ``B_r C_s^-1 B_r'`` (``B_r = T' B``).

For a super element keep the electrodes' static shapes in its basis
(:func:`mvtk.reduction.with_electrodes`), otherwise the feed-through that places the
anti-resonances of a collocated pair is truncated.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError
from ..fe import FEModel, PiezoCoupling
from ..reduction import SuperElement
from ._plant import StructuralPlant, structural_plant

__all__ = ["piezo_plant"]


def _names(coupling: PiezoCoupling, names, what: str) -> list[int]:
    if names is None or (not isinstance(names, str) and not len(names)):
        raise ParameterError(f"piezo_plant: name at least one {what} electrode or patch")
    try:
        return [int(i) for i in coupling.index(names)]
    except ParameterError as err:
        raise ParameterError(f"piezo_plant {what}s: {err}") from None


def piezo_plant(se_or_model: SuperElement | FEModel, coupling: PiezoCoupling,
                actuators: str | Sequence[str], sensors: str | Sequence[str] = (), *,
                sensing: str = "charge", points: Sequence = (), **kwargs) -> StructuralPlant:
    """:func:`~mvtk.control.structural_plant` with piezo electrodes as inputs and outputs.

    Parameters
    ----------
    se_or_model : SuperElement or FEModel
        The structure, short-circuited (as assembled).
    coupling : PiezoCoupling
        :func:`mvtk.fe.piezo_coupling` of the full model.
    actuators : str or sequence of str
        Electrode or patch names driven by a voltage (inputs ``"<electrode>"``, V).
    sensors : str or sequence of str
        Electrode or patch names read as outputs ``"Q:<electrode>"`` (C) or
        ``"V:<electrode>"`` (V).
    sensing : {"charge", "voltage"}
    points : sequence of (node, component) or (node, component, quantity)
        Further displacement/velocity outputs, as in ``structural_plant``.
    **kwargs
        Passed to :func:`~mvtk.control.structural_plant` (damping, ``form``,
        ``n_modes``, ``static_correction``).

    Returns
    -------
    StructuralPlant

    Examples
    --------
    Voltage in, charge out on the same electrode (a self-sensing actuator), 3 modes with
    1 % damping; the first is the plate's first bending mode (short circuit):

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Patch, PiezoMaterial, Ply,
    ...                      ShellPiezoPatch, assemble_shell_model, edge_dofs,
    ...                      rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4,
    ...                               patches=[Patch("act", 0.05, 0.15, 0.05, 0.15)])
    >>> base = Laminate((Ply(steel, 1e-3),))
    >>> stack = Laminate((Ply(steel, 1e-3), Ply(pzt, 2e-4)), z_bottom=-0.5e-3)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, mesh.element_region,
    ...                              [base, stack], fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> patch = ShellPiezoPatch("act", mesh.elements[mesh.element_region == 1], stack)
    >>> from mvtk.control import closed_loop_modes
    >>> from mvtk.fe import piezo_coupling
    >>> plant = piezo_plant(model, piezo_coupling(model, [patch]), "act", "act", form="modal",
    ...                     n_modes=3, modal_damping=0.01)
    >>> plant.inputs, plant.outputs, round(float(closed_loop_modes(plant).fn_hz[0]), 2)
    (('act',), ('Q:act',), 9.81)
    """
    if sensing not in ("charge", "voltage"):
        raise ParameterError(f"piezo_plant: sensing must be 'charge' or 'voltage', "
                             f"got {sensing!r}")
    act = _names(coupling, actuators, "actuator")
    sen = _names(coupling, sensors, "sensor") if (isinstance(sensors, str) or len(sensors)) \
        else []
    model = se_or_model.model if isinstance(se_or_model, SuperElement) else se_or_model
    if coupling.B.shape[0] != model.n_dof:
        raise ParameterError(f"piezo_plant: the coupling has {coupling.B.shape[0]} DOFs, "
                             f"the structure {model.n_dof}")
    structure = se_or_model
    if sensing == "voltage" and sen:
        both = sorted(set(act) & set(sen))
        if both:
            raise ParameterError(f"piezo_plant: electrode(s) {[coupling.names[i] for i in both]}"
                                 " cannot be driven and read open-circuit at once")
        c = coupling._capacitance(np.asarray(sen))
        if isinstance(se_or_model, SuperElement):
            Br = se_or_model.T.T @ coupling.B[:, sen]
            Ko = se_or_model.K + Br @ np.diag(1.0 / c) @ Br.T
            structure = dataclasses.replace(se_or_model, K=0.5 * (Ko + Ko.T))
        else:
            structure = coupling.open_circuit_model(se_or_model, [coupling.names[i]
                                                                  for i in sen])
    inputs = {coupling.names[i]: coupling.B[:, i] for i in act}
    outputs: dict = {}
    units = []
    for j in sen:
        if sensing == "charge":
            outputs[f"Q:{coupling.names[j]}"] = coupling.B[:, j]
            units.append("C")
        else:
            c = coupling._capacitance(np.array([j]))[0]
            outputs[f"V:{coupling.names[j]}"] = -coupling.B[:, j] / c
            units.append("V")
    for p in points:
        node, comp = p[0], p[1]
        q = p[2] if len(p) > 2 else "displacement"
        outputs[f"{'u' if q == 'displacement' else 'v'}:n{int(node)}:{comp}"] = tuple(p)
        units.append(("m" if str(comp).startswith("u") else "rad")
                     + ("" if q == "displacement" else "/s"))
    if not outputs:
        raise ParameterError("piezo_plant: no output (give sensors or points)")
    plant = structural_plant(structure, inputs, outputs, input_units=["V"] * len(act),
                             output_units=units, **kwargs)
    if sensing == "charge":
        D = plant.D.copy()
        for r, j in enumerate(sen):
            if j in act:
                D[r, act.index(j)] += coupling.C[j]
        plant = dataclasses.replace(plant, D=D)
    meta = dict(plant.meta, sensing=sensing, electrodes_in=[coupling.names[i] for i in act],
                electrodes_out=[coupling.names[j] for j in sen])
    return dataclasses.replace(plant, meta=meta)
