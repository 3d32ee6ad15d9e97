"""Modal effective mass tables and the choice of the number of modes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DimensionError, ParameterError
from ..fe import FEModel, eigsh_lowest
from ._craig_bampton import SuperElement, _translation, craig_bampton

__all__ = ["EffectiveMassTable", "effective_mass"]


@dataclass(frozen=True)
class EffectiveMassTable:
    """Effective modal masses for a base translation.

    Attributes
    ----------
    fn_hz : ndarray, shape (n,)
        Natural frequencies in Hz.
    participation : ndarray, shape (n,)
        ``L_i = phi_i' M r`` in sqrt(kg) (mass-normalised modes).
    effective_mass_kg : ndarray, shape (n,)
        ``L_i^2`` in kg.
    total_mass_kg : float
        ``r' M r``: the mass moving with the base translation (kg).
    direction : str
        Translation direction ("ux", "uy" or "uz").
    kind : str
        ``"fixed_base"`` (modes of the model with its supports) or
        ``"fixed_interface"`` (Craig-Bampton interior modes).

    Examples
    --------
    Returned by :func:`effective_mass`; the effective masses add up to at most the moving
    mass:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> t = effective_mass(beam, "uz", n_modes=6)
    >>> t.direction, bool(t.effective_mass_kg.sum() <= t.total_mass_kg)
    ('uz', True)
    """

    fn_hz: np.ndarray
    participation: np.ndarray
    effective_mass_kg: np.ndarray
    total_mass_kg: float
    direction: str
    kind: str

    @property
    def fraction(self) -> np.ndarray:
        """Effective mass fraction of each mode."""
        return self.effective_mass_kg / self.total_mass_kg

    @property
    def cumulative(self) -> np.ndarray:
        """Cumulative effective mass fraction."""
        return np.cumsum(self.fraction)

    def n_for_fraction(self, target: float = 0.95) -> int:
        """Fewest leading modes whose cumulative fraction reaches ``target``.

        Raises
        ------
        ParameterError
            If the table does not reach ``target`` (compute more modes).
        """
        if not 0 < target <= 1:
            raise ParameterError(f"target fraction must be in (0, 1], got {target}")
        hit = np.nonzero(self.cumulative >= target)[0]
        if not hit.size:
            reached = self.cumulative[-1] if self.cumulative.size else 0.0
            raise ParameterError(
                f"cumulative effective mass {reached:.4f} of the {self.fn_hz.size} modes "
                f"in the table does not reach {target}; compute more modes"
            )
        return int(hit[0]) + 1

    def n_below(self, f_cut_hz: float) -> int:
        """Number of modes with ``fn_hz <= f_cut_hz``."""
        return int(np.count_nonzero(self.fn_hz <= f_cut_hz))

    def _repr_html_(self) -> str:
        return self.to_dataframe()._repr_html_()

    def to_dataframe(self):
        """Columns mode, fn_hz, participation, effective_mass_kg, fraction, cumulative."""
        import pandas as pd

        return pd.DataFrame(
            {
                "mode": np.arange(1, self.fn_hz.size + 1),
                "fn_hz": self.fn_hz,
                "participation": self.participation,
                "effective_mass_kg": self.effective_mass_kg,
                "fraction": self.fraction,
                "cumulative": self.cumulative,
            }
        )


def effective_mass(
    model_or_se: FEModel | SuperElement,
    direction: str = "uz",
    n_modes: int = 20,
    *,
    base=None,
    modes=None,
) -> EffectiveMassTable:
    """Effective mass table for a unit base translation in ``direction``.

    Parameters
    ----------
    model_or_se : FEModel or SuperElement
        With an :class:`FEModel` the modes are those of the model with its supports
        (the base is the set of constrained DOFs). With a :class:`SuperElement` the
        modes are its fixed-interface modes (the base is the clamp plus the boundary).
    direction : {"ux", "uy", "uz"}
    n_modes : int
        Number of modes for an FEModel (ignored for a SuperElement, which uses its own).
    base : optional
        FEModel only: nodes, node set names or points (as ``retained`` of
        :func:`craig_bampton`) forming a base that is not among the model's supports
        (e.g. the clamp of a free-free model). The modes are then the fixed-interface
        modes with this base held, i.e. ``effective_mass(craig_bampton(model, base,
        n_modes))``.
    modes : ModalResult or EigenSolution, optional
        FEModel only: the model's lowest modes already computed
        (:func:`mvtk.fe.modal_analysis` or :func:`mvtk.fe.eigsh_lowest` of this model,
        mass-normalised), used instead of solving again; their number is ``n_modes``.

    Returns
    -------
    EffectiveMassTable

    Notes
    -----
    ``L = Phi' M r`` with ``r`` the rigid unit translation of every free DOF in
    ``direction`` (rotations zero): the quasi-static motion of the structure when its
    base moves rigidly. For Craig-Bampton interior modes this is
    ``L = Phi' [M_fl  M_ff] r``; when the boundary is the only support, the interior part
    of the boundary-translation constraint mode ``Psi r_l`` equals ``r_f`` and this is the
    usual ``M_r[eta, l] r_l`` coupling of the super element. The total mass is
    ``r' M r`` (mass on constrained DOFs is not counted). Over all modes of a supported
    model the fractions sum to 1; for fixed-interface modes they sum to less than 1 (the
    rest is the boundary's residual mass).

    Examples
    --------
    The first bending mode of a uniform cantilever carries 61.3 % of its mass
    (Euler-Bernoulli closed form); here ``rho A L`` = 0.0942 kg:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> table = effective_mass(beam, "uz", n_modes=6)
    >>> round(float(table.effective_mass_kg[0]) / (7850.0 * 0.02 * 0.002 * 0.3), 3)
    0.613
    """
    if modes is not None and (base is not None or not isinstance(model_or_se, FEModel)):
        raise ParameterError("modes= applies to an FEModel without base=")
    if base is not None:
        if not isinstance(model_or_se, FEModel):
            raise ParameterError("base= applies to an FEModel, not to a SuperElement")
        model_or_se = craig_bampton(model_or_se, base, n_modes)
    if isinstance(model_or_se, SuperElement):
        se = model_or_se
        model = se.model
        r = _translation(model, direction)
        mr = model.M @ r
        total = float(r @ mr)
        fset = np.setdiff1d(np.arange(model.n_dof), se.boundary_dofs)
        phi = se.T[fset, se.n_boundary:]
        L = phi.T @ mr[fset]
        fn = se.interior_fn_hz
        kind = "fixed_interface"
    elif isinstance(model_or_se, FEModel):
        model = model_or_se
        r = _translation(model, direction)
        mr = model.M @ r
        total = float(r @ mr)
        if modes is not None:
            w2 = np.asarray(modes.omega2, dtype=float)
            vectors = np.asarray(modes.shapes if hasattr(modes, "shapes") else modes.vectors)
            if vectors.ndim != 2 or vectors.shape != (model.n_dof, w2.size):
                raise DimensionError(f"modes: expected {model.n_dof} x {w2.size} shapes of "
                                     f"this model, got {vectors.shape}")
        else:
            n_modes = int(n_modes)
            if not 1 <= n_modes <= model.n_dof:
                raise ParameterError(f"n_modes must be in 1..{model.n_dof}, got {n_modes}")
            sol = eigsh_lowest(model.K, model.M, n_modes)
            w2, vectors = sol.omega2, sol.vectors
        L = vectors.T @ mr
        fn = np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)
        kind = "fixed_base"
    else:
        raise ParameterError(
            f"expected an FEModel or a SuperElement, got {type(model_or_se).__name__}"
        )
    if total <= 0:
        raise ParameterError(f"no mass moves with a translation in {direction}")
    return EffectiveMassTable(
        fn_hz=np.asarray(fn, dtype=float),
        participation=L,
        effective_mass_kg=L**2,
        total_mass_kg=total,
        direction=direction,
        kind=kind,
    )

