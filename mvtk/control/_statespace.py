"""A small labelled continuous-time state-space container.

``xdot = A x + B u``, ``y = C x + D u``. Interoperates with scipy.signal
(:meth:`StateSpace.to_scipy`, :meth:`StateSpace.from_scipy`) and python-control
(:meth:`StateSpace.to_control`, :meth:`StateSpace.from_control`, optional).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import DimensionError, MissingDependencyError

__all__ = ["StateSpace"]


def _names(given: Sequence[str] | None, n: int, prefix: str, what: str) -> tuple[str, ...]:
    if given is None or len(given) == 0:
        return tuple(f"{prefix}{i}" for i in range(n))
    names = tuple(str(g) for g in given)
    if len(names) != n:
        raise DimensionError(f"expected {n} {what} names, got {len(names)}")
    if len(set(names)) != n:
        raise DimensionError(f"{what} names must be unique, got {names}")
    return names


@dataclass(frozen=True, eq=False)
class StateSpace:
    """Continuous-time linear state-space model with labelled signals.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, m)
    C : ndarray, shape (p, n)
    D : ndarray, shape (p, m), optional (zeros)
    inputs, outputs, states : sequence of str, optional
        Signal names (defaults ``u0..``, ``y0..``, ``x0..``).
    input_units, output_units : sequence of str, optional
        Unit strings per input/output (e.g. ``"V"``, ``"m"``).

    Examples
    --------
    One mode at 10 Hz, 1 %: poles ``-zeta w +- i w_d`` and static gain ``1 / w**2``:

    >>> w = 2 * np.pi * 10.0
    >>> sys = StateSpace(np.array([[0.0, 1.0], [-w**2, -2 * 0.01 * w]]), np.array([[0.0], [1.0]]),
    ...                  np.array([[1.0, 0.0]]), inputs=["force"], outputs=["x"])
    >>> np.round(sys.poles(), 3)
    array([-0.628+62.829j, -0.628-62.829j])
    >>> round(float(sys.dc_gain()[0, 0]) * w**2, 6)
    1.0
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray | None = None
    inputs: Sequence[str] | None = None
    outputs: Sequence[str] | None = None
    states: Sequence[str] | None = None
    input_units: Sequence[str] | None = None
    output_units: Sequence[str] | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        A = np.asarray(self.A, dtype=float)
        A = A.reshape(0, 0) if A.size == 0 else np.atleast_2d(A)
        n = A.shape[0]
        if A.shape != (n, n):
            raise DimensionError(f"A must be square, got {A.shape}")
        if n == 0:
            # a static gain: the sizes come from D
            if self.D is None:
                raise DimensionError("a system without states needs D to fix its sizes")
            D = np.atleast_2d(np.asarray(self.D, dtype=float))
            p, m = D.shape
            B, C = np.zeros((0, m)), np.zeros((p, 0))
        else:
            B = np.asarray(self.B, dtype=float).reshape(n, -1)
            C = np.asarray(self.C, dtype=float)
            C = C.reshape(-1, n) if C.ndim < 2 else C
            if C.shape[1] != n:
                raise DimensionError(f"C must have {n} columns, got {C.shape}")
            m, p = B.shape[1], C.shape[0]
            D = np.zeros((p, m)) if self.D is None else np.asarray(self.D, dtype=float)
            D = D.reshape(p, m) if D.size == p * m else D
            if D.shape != (p, m):
                raise DimensionError(f"D must have shape ({p}, {m}), got {D.shape}")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "D", D)
        object.__setattr__(self, "inputs", _names(self.inputs, m, "u", "input"))
        object.__setattr__(self, "outputs", _names(self.outputs, p, "y", "output"))
        object.__setattr__(self, "states", _names(self.states, n, "x", "state"))
        iu = tuple(self.input_units) if self.input_units else ("",) * m
        ou = tuple(self.output_units) if self.output_units else ("",) * p
        if len(iu) != m or len(ou) != p:
            raise DimensionError("input_units/output_units must match the number of signals")
        object.__setattr__(self, "input_units", iu)
        object.__setattr__(self, "output_units", ou)

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.B.shape[1]

    @property
    def n_outputs(self) -> int:
        return self.C.shape[0]

    def poles(self) -> np.ndarray:
        """Eigenvalues of A (rad/s), sorted by imaginary part magnitude."""
        p = np.linalg.eigvals(self.A)
        return p[np.argsort(np.abs(p.imag), kind="stable")]

    def frequency_response(self, f_hz: np.ndarray) -> np.ndarray:
        """Complex frequency response, shape (p, m, n_freq), at frequencies ``f_hz`` (Hz)."""
        f_hz = np.atleast_1d(np.asarray(f_hz, dtype=float))
        n = self.n_states
        out = np.empty((self.n_outputs, self.n_inputs, f_hz.size), dtype=complex)
        eye = np.eye(n)
        for k, f in enumerate(f_hz):
            s = 2j * np.pi * f
            out[:, :, k] = self.C @ np.linalg.solve(s * eye - self.A, self.B) + self.D
        return out

    def dc_gain(self) -> np.ndarray:
        """Static gain ``D - C A^-1 B``, shape (p, m)."""
        if self.n_states == 0:
            return self.D.copy()
        return self.D - self.C @ np.linalg.solve(self.A, self.B)

    # ------------------------------------------------------------ conversions
    def to_scipy(self):
        """Return a :class:`scipy.signal.StateSpace`."""
        from scipy import signal

        return signal.StateSpace(self.A, self.B, self.C, self.D)

    @classmethod
    def from_scipy(cls, sys, **names) -> StateSpace:
        """Build from a :class:`scipy.signal.StateSpace` (or lti convertible to it)."""
        ss = sys.to_ss() if hasattr(sys, "to_ss") else sys
        return cls(ss.A, ss.B, ss.C, ss.D, **names)

    def to_control(self):
        """Return a python-control ``StateSpace`` with the signal names (needs ``control``)."""
        try:
            import control
        except ImportError as err:
            raise MissingDependencyError(
                "python-control is not installed: pip install 'mvtk[control]'"
            ) from err
        return control.ss(
            self.A, self.B, self.C, self.D,
            inputs=list(self.inputs), outputs=list(self.outputs), states=list(self.states),
        )

    @classmethod
    def from_control(cls, sys) -> StateSpace:
        """Build from a python-control ``StateSpace`` keeping its signal names."""
        return cls(
            sys.A, sys.B, sys.C, sys.D,
            inputs=list(sys.input_labels), outputs=list(sys.output_labels),
            states=list(sys.state_labels),
        )
