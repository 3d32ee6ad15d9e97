"""Second-order structural systems ``M q'' + C q' + K q = B u``.

The common plant form between reduction (which builds it from a super element or a
full FE model) and the controllers (which need M, K and the input matrix B for the
Lyapunov laws and the collocated checks).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import DimensionError
from ._statespace import StateSpace

__all__ = ["SecondOrderSystem"]


@dataclass(frozen=True, eq=False)
class SecondOrderSystem:
    """Linear structure ``M q'' + C q' + K q = B u``, ``y = Cq q + Cv q'``.

    Parameters
    ----------
    M, C, K : ndarray, shape (n, n)
        Mass, damping and stiffness (dense; super elements and modal models are small).
    B : ndarray, shape (n, m)
        Input matrix: generalised force per unit input (e.g. N m per V).
    Cq, Cv : ndarray, shape (p, n)
        Output matrices on displacement and velocity.
    inputs, outputs, coords : sequence of str, optional
        Names of inputs, outputs and generalised coordinates.
    input_units, output_units : sequence of str, optional

    Examples
    --------
    One degree of freedom, 1 kg, 10 Hz, 1 %:

    >>> from mvtk.control import closed_loop_modes
    >>> w = 2 * np.pi * 10.0
    >>> sys = SecondOrderSystem(np.eye(1), np.array([[2 * 0.01 * w]]), np.array([[w**2]]),
    ...                         B=np.array([[1.0]]), Cq=np.array([[1.0]]), Cv=np.zeros((1, 1)),
    ...                         inputs=["force"], outputs=["x"])
    >>> m = closed_loop_modes(sys)
    >>> m.fn_hz, np.round(m.zeta, 6)
    (array([10.]), array([0.01]))
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    B: np.ndarray
    Cq: np.ndarray
    Cv: np.ndarray
    inputs: Sequence[str] | None = None
    outputs: Sequence[str] | None = None
    coords: Sequence[str] | None = None
    input_units: Sequence[str] | None = None
    output_units: Sequence[str] | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        M = np.atleast_2d(np.asarray(self.M, dtype=float))
        n = M.shape[0]
        arrays = {"M": M}
        for key in ("C", "K"):
            a = np.atleast_2d(np.asarray(getattr(self, key), dtype=float))
            if a.shape != (n, n):
                raise DimensionError(f"{key} must have shape ({n}, {n}), got {a.shape}")
            arrays[key] = a
        B = np.asarray(self.B, dtype=float).reshape(n, -1)
        Cq = np.atleast_2d(np.asarray(self.Cq, dtype=float))
        Cv = np.atleast_2d(np.asarray(self.Cv, dtype=float))
        if Cq.shape[1] != n or Cv.shape != Cq.shape:
            raise DimensionError(
                f"Cq and Cv must both have shape (p, {n}), got {Cq.shape} and {Cv.shape}"
            )
        arrays.update(B=B, Cq=Cq, Cv=Cv)
        for key, a in arrays.items():
            object.__setattr__(self, key, a)
        m, p = B.shape[1], Cq.shape[0]
        object.__setattr__(self, "inputs", tuple(self.inputs or (f"u{i}" for i in range(m))))
        object.__setattr__(self, "outputs", tuple(self.outputs or (f"y{i}" for i in range(p))))
        object.__setattr__(self, "coords", tuple(self.coords or (f"q{i}" for i in range(n))))
        if len(self.inputs) != m or len(self.outputs) != p or len(self.coords) != n:
            raise DimensionError("names must match the numbers of inputs, outputs and coordinates")

    @property
    def n_coords(self) -> int:
        return self.M.shape[0]

    def to_state_space(self) -> StateSpace:
        """State space with ``x = [q; q']``."""
        n = self.n_coords
        Minv_K = np.linalg.solve(self.M, self.K)
        Minv_C = np.linalg.solve(self.M, self.C)
        Minv_B = np.linalg.solve(self.M, self.B)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv_K, -Minv_C]])
        B = np.vstack([np.zeros_like(Minv_B), Minv_B])
        C = np.hstack([self.Cq, self.Cv])
        states = [*self.coords, *(f"d({c})/dt" for c in self.coords)]
        return StateSpace(
            A, B, C, None, inputs=self.inputs, outputs=self.outputs, states=states,
            input_units=self.input_units, output_units=self.output_units, meta=dict(self.meta),
        )
