"""Super elements that keep piezo electrodes as inputs and outputs.

A Craig-Bampton basis ``T`` (constraint modes and fixed-interface modes) represents a
piezo patch's voltage load only through the modes it keeps: the static (feed-through)
part of the response to the voltage, which sets the anti-resonances of a collocated
pair, is truncated. :func:`with_electrodes` adds, per electrode, the interior static
deformation under that electrode's voltage with the boundary held,
``psi_e = [0; K_ff^-1 b_f]``, to the basis (the residual-attachment idea of MacNeal
1971 and of the modal truncation augmentation, Dickens, Nakagawa & Wittbrodt 1997).
The exact static solution ``u_f = K_ff^-1 (b_f - K_fl u_l)`` then lies in the span of
the basis, so the super element reproduces the full model's voltage-to-response and
voltage-to-charge transfer at 0 Hz exactly and the feed-through above the retained
modes closely.

The added shapes are made M-orthogonal to ``T`` and to each other (the eigenvectors of
the residual pencil), labelled ``"v:<electrode>"``; the reduced input matrix is
``B_r = T' B`` and the charge output ``Q = B_r' q + C_p V``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.linalg as sla

from ..errors import ParameterError
from ..fe import PiezoCoupling, factorize
from ._craig_bampton import SuperElement

__all__ = ["with_electrodes"]


def with_electrodes(se: SuperElement, coupling: PiezoCoupling
                    ) -> tuple[SuperElement, np.ndarray]:
    """Craig-Bampton super element augmented with the electrodes' static shapes.

    Parameters
    ----------
    se : SuperElement
        From :func:`mvtk.reduction.craig_bampton` on the model of ``coupling``.
    coupling : PiezoCoupling
        :func:`mvtk.fe.piezo_coupling` of ``se.model``.
    Returns
    -------
    (SuperElement, ndarray)
        The super element with ``n_electrodes`` more coordinates (labels
        ``"v:<electrode>"``, ``meta["electrodes"]`` their names), and ``B_r``
        (n_r, n_electrodes), N/V in reduced coordinates.

    Raises
    ------
    ParameterError
        If ``coupling.B`` does not match the model, or an electrode's static shape is
        already in the span of the basis (then nothing is added for it: the message
        says which; this only happens for a patch on the boundary DOFs alone).

    Examples
    --------
    The piezo plate of :func:`mvtk.fe.piezo_coupling` reduced to its tip-centre node and
    4 fixed-interface modes; the electrode's static shape adds one coordinate:

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
    >>> from mvtk.fe import piezo_coupling
    >>> from mvtk.reduction import craig_bampton
    >>> se = craig_bampton(model, [model.nearest_node([0.3, 0.1, 0.0])], n_modes=4)
    >>> se_v, B_r = with_electrodes(se, piezo_coupling(model, [patch]))
    >>> se.K.shape, se_v.K.shape, B_r.shape, se_v.labels[-1]
    ((10, 10), (11, 11), (11, 1), 'v:act')
    """
    model = se.model
    B = np.asarray(coupling.B, dtype=float)
    if B.shape[0] != model.n_dof:
        raise ParameterError(f"coupling.B has {B.shape[0]} rows, the model {model.n_dof} "
                             "free DOFs: build it with piezo_coupling(se.model)")
    interior = np.ones(model.n_dof, dtype=bool)
    interior[se.boundary_dofs] = False
    f = np.flatnonzero(interior)
    K_ff = model.K[f][:, f].tocsc()
    psi = np.zeros_like(B)
    psi[f] = factorize(K_ff).solve(B[f])
    T = se.T
    M = model.M
    before = np.sqrt(np.abs(np.einsum("ij,ij->j", psi, M @ psi)))
    # M-orthogonal to the existing basis (two passes for round-off)
    for _ in range(2):
        psi -= T @ np.linalg.solve(se.M, T.T @ (M @ psi))
    m_psi = psi.T @ (M @ psi)
    k_psi = psi.T @ (model.K @ psi)
    weak = np.sqrt(np.abs(np.diag(m_psi))) <= 1e-8 * before
    if np.any(weak):
        n_e = B.shape[1]
        raise ParameterError(
            f"electrode(s) {[coupling.names[i % n_e] for i in np.flatnonzero(weak)]}: "
            "static shape already in the super element's basis")
    w2, vec = sla.eigh(k_psi, m_psi)
    psi = psi @ vec
    Ta = np.hstack([T, psi])
    Mr = Ta.T @ (M @ Ta)
    Kr = Ta.T @ (model.K @ Ta)
    Mr, Kr = 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T)
    labels = se.labels + tuple(f"v:{n}" for n in coupling.names)
    meta = dict(se.meta, electrodes=tuple(coupling.names),
                electrode_shape_fn_hz=np.sqrt(np.abs(w2)) / (2 * np.pi))
    out = replace(se, M=Mr, K=Kr, T=Ta, labels=labels, meta=meta)
    return out, Ta.T @ B
