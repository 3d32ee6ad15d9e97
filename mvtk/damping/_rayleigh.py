"""Rayleigh damping C = alpha M + beta K fitted to identified modal damping ratios."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.optimize

from ..errors import AccuracyWarning, DimensionError, IdentifiabilityWarning, ParameterError

__all__ = ["RayleighFit", "rayleigh_fit", "rayleigh_zeta"]


def rayleigh_zeta(f_hz, alpha: float, beta: float) -> np.ndarray:
    """Modal damping ratio of Rayleigh damping: ``alpha / (2 w) + beta w / 2``, w in rad/s.

    Examples
    --------
    ``alpha = 0.5 1/s`` and ``beta = 1e-4 s`` at 10 and 40 Hz:

    >>> np.round(rayleigh_zeta([10.0, 40.0], alpha=0.5, beta=1e-4), 5)
    array([0.00712, 0.01356])
    """
    w = 2 * np.pi * np.asarray(f_hz, dtype=float)
    with np.errstate(divide="ignore"):
        return alpha / (2 * w) + beta * w / 2


@dataclass(frozen=True)
class RayleighFit:
    """Rayleigh coefficients and how well they reproduce the identified damping.

    Attributes
    ----------
    alpha : float
        Mass-proportional coefficient (1/s).
    beta : float
        Stiffness-proportional coefficient (s).
    method : str
        ``"two_mode"``, ``"least_squares"`` or ``"chowdhury"``.
    fn_hz, zeta : numpy.ndarray
        The identified modes used as input (Hz, ratio).
    zeta_fit : numpy.ndarray
        ``alpha / (2 w) + beta w / 2`` at each input mode.
    residual : numpy.ndarray
        ``zeta_fit - zeta``.
    weights : numpy.ndarray
        Least-squares weights (1 for the anchors and 0 elsewhere for the anchored
        methods).
    anchors : tuple of int
        Indices of the anchor modes (anchored methods) or all modes.

    Examples
    --------
    Two modes fitted exactly; the closed form is
    ``alpha = 2 w1 w2 (z1 w2 - z2 w1) / (w2**2 - w1**2)``,
    ``beta = 2 (z2 w2 - z1 w1) / (w2**2 - w1**2)``:

    >>> fit = rayleigh_fit([10.0, 40.0], [0.01, 0.02], "two_mode")
    >>> round(fit.alpha, 4), round(fit.beta * 1e6, 3)   # 1/s, 1e-6 s
    (0.6702, 148.545)
    >>> np.round(fit.zeta_at([10.0, 40.0]), 6)
    array([0.01, 0.02])
    """

    alpha: float
    beta: float
    method: str
    fn_hz: np.ndarray
    zeta: np.ndarray
    zeta_fit: np.ndarray
    residual: np.ndarray
    weights: np.ndarray
    anchors: tuple[int, ...]

    def zeta_at(self, f_hz) -> np.ndarray:
        """Damping ratio of the fitted Rayleigh model at ``f_hz`` (Hz).

        Issues an :class:`~mvtk.errors.AccuracyWarning` when ``f_hz`` lies outside the
        identified modes' range by more than 10 % (extrapolated damping).
        """
        f = np.asarray(f_hz, dtype=float)
        lo, hi = float(np.min(self.fn_hz)), float(np.max(self.fn_hz))
        if np.any(f < 0.9 * lo) or np.any(f > 1.1 * hi):
            warnings.warn(
                f"RayleighFit.zeta_at: frequencies outside the identified range {lo:.4g}.."
                f"{hi:.4g} Hz are extrapolated (Rayleigh damping grows ~ f above it)",
                AccuracyWarning, stacklevel=2,
            )
        return rayleigh_zeta(f, self.alpha, self.beta)

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per input mode with the fit; alpha and beta in ``attrs``."""
        df = pd.DataFrame({
            "fn_hz": self.fn_hz, "zeta": self.zeta, "zeta_fit": self.zeta_fit,
            "residual": self.residual, "weight": self.weights,
            "anchor": [i in self.anchors for i in range(self.fn_hz.size)],
        })
        df.attrs = {"alpha": self.alpha, "beta": self.beta, "method": self.method}
        return df


def _two_mode(wi, wj, zi, zj):
    den = wj**2 - wi**2
    alpha = 2 * wi * wj * (zi * wj - zj * wi) / den
    beta = 2 * (zj * wj - zi * wi) / den
    return alpha, beta


def rayleigh_fit(
    fn_hz,
    zeta,
    method: str = "two_mode",
    *,
    modes: tuple[int, int] | None = None,
    weights="uniform",
    nonnegative: bool = False,
    mass_fraction=None,
    target_mass: float = 0.9,
) -> RayleighFit:
    """Fit Rayleigh damping ``zeta(w) = alpha / (2 w) + beta w / 2`` to identified modes.

    Parameters
    ----------
    fn_hz : array_like
        Natural frequencies in Hz (distinct, > 0).
    zeta : array_like or float
        Damping ratios (0.01 = 1 %), one per mode or a single value for all.
    method : {"two_mode", "least_squares", "chowdhury"}
        ``"two_mode"``: the closed form through two anchor modes ``modes`` (default the
        first two), ``alpha = 2 wi wj (zi wj - zj wi) / (wj^2 - wi^2)``,
        ``beta = 2 (zj wj - zi wi) / (wj^2 - wi^2)``.
        ``"least_squares"``: minimise ``sum w_k (zeta_fit_k - zeta_k)^2`` over all modes;
        with two modes it equals the closed form (Song & Su, Shock Vib. 2017, 2046345).
        ``"chowdhury"``: anchors chosen by mass participation after Chowdhury &
        Dasgupta (2003), see Notes.
    modes : (int, int), optional
        Anchor mode indices for ``"two_mode"``.
    weights : {"uniform", "inverse_omega", "mass_fraction"} or array_like
        Least-squares weights: 1, ``1/omega`` or the effective mass fraction.
    nonnegative : bool
        Constrain ``alpha, beta >= 0`` (least squares; for the anchored methods the
        negative coefficient is set to zero and the other refitted to both anchors).
    mass_fraction : array_like, optional
        Effective modal mass fraction of each mode (needed by ``"chowdhury"`` and by
        ``weights="mass_fraction"``).
    target_mass : float
        Cumulative effective mass fraction that defines the upper anchor in
        ``"chowdhury"`` (default 0.9, as EN 1998-1 4.3.3.3; the paper's super element
        uses 0.95).

    Returns
    -------
    RayleighFit

    Notes
    -----
    The body of Chowdhury & Dasgupta (EJGE 2003, paper 0318) was not available to the
    authors of this module; the rule implemented is our reading of its abstract: instead
    of anchoring at modes 1 and 2, anchor at mode 1 (the lowest identified mode) and at
    mode m, the lowest mode at which the cumulative effective mass fraction (modes
    sorted by frequency) reaches ``target_mass``, so that every mode that contributes
    significantly to the response lies between the anchors, where Rayleigh damping
    under- rather than over-estimates. The measured damping of the two anchors is
    used (``zeta`` may be a single value: equal damping). It does not reproduce the
    paper's "Chowdhury" pair (alpha 0.02577, beta 9.918e-6) because the damping ratios
    behind it are not given in the paper.

    References
    ----------
    I. Chowdhury, S. P. Dasgupta, "Computation of Rayleigh damping coefficients for large
    systems", Electronic Journal of Geotechnical Engineering 8 (2003), paper 0318.
    J. Song, Q. Su, Shock and Vibration (2017) 2046345.

    Examples
    --------
    Two modes, 10 Hz at 1 % and 40 Hz at 2 %: zeta = alpha / (2 w) + beta w / 2 holds
    at both.

    >>> fit = rayleigh_fit([10.0, 40.0], [0.01, 0.02], "two_mode")
    >>> w = 2 * np.pi * np.array([10.0, 40.0])
    >>> np.round(fit.alpha / (2 * w) + fit.beta * w / 2, 6)
    array([0.01, 0.02])
    """
    fn = np.atleast_1d(np.asarray(fn_hz, dtype=float))
    if fn.ndim != 1 or fn.size < 2:
        raise DimensionError(f"fn_hz needs at least 2 modes (1-D), got shape {fn.shape}")
    if np.any(~np.isfinite(fn)) or np.any(fn <= 0):
        raise ParameterError(f"fn_hz must be finite and > 0 Hz, got {fn.tolist()}")
    if np.unique(fn).size != fn.size:
        raise ParameterError(f"fn_hz must be distinct, got {fn.tolist()}")
    z = np.asarray(zeta, dtype=float)
    if z.ndim == 0:
        z = np.full(fn.shape, float(z))
    if z.shape != fn.shape:
        raise DimensionError(f"zeta needs {fn.size} values (one per mode), got shape {z.shape}")
    if np.any(~np.isfinite(z)) or np.any(z < 0) or np.any(z >= 1):
        raise ParameterError(f"zeta must be ratios in [0, 1) (not %), got {z.tolist()}")
    mf = None
    if mass_fraction is not None:
        mf = np.asarray(mass_fraction, dtype=float)
        if mf.shape != fn.shape:
            raise DimensionError(
                f"mass_fraction needs {fn.size} values (one per mode), got shape {mf.shape}"
            )
        if np.any(mf < 0) or np.any(mf > 1 + 1e-9) or np.sum(mf) > 1 + 1e-6:
            raise ParameterError(
                f"mass_fraction must be fractions in [0, 1] summing to <= 1, got {mf.tolist()}"
            )
    w = 2 * np.pi * fn
    if method == "two_mode":
        i, j = (0, 1) if modes is None else (int(modes[0]), int(modes[1]))
        if not (0 <= i < fn.size and 0 <= j < fn.size and i != j):
            raise ParameterError(f"modes must be two distinct indices < {fn.size}, got {modes}")
        anchors = (i, j)
        alpha, beta = _anchored(w, z, anchors, nonnegative)
        wts = np.zeros(fn.size)
        wts[list(anchors)] = 1.0
    elif method == "chowdhury":
        if mf is None:
            raise ParameterError("method 'chowdhury' needs mass_fraction (one per mode)")
        if not 0 < target_mass <= 1:
            raise ParameterError(f"target_mass must be in (0, 1], got {target_mass!r}")
        order = np.argsort(fn)
        cum = np.cumsum(mf[order])
        reach = np.flatnonzero(cum >= target_mass - 1e-12)
        if reach.size == 0:
            raise ParameterError(
                f"the modes' cumulative mass fraction {cum[-1]:.3g} never reaches "
                f"target_mass={target_mass:g}; identify more modes or lower target_mass"
            )
        m = int(reach[0])
        if m == 0:
            m = 1  # mode 1 alone reaches the target: the next mode bounds the band
            warnings.warn(
                f"chowdhury: mode 1 alone holds {cum[0]:.3g} >= {target_mass:g} of the mass; "
                "using modes 1 and 2 as anchors", IdentifiabilityWarning, stacklevel=2,
            )
        anchors = (int(order[0]), int(order[m]))
        alpha, beta = _anchored(w, z, anchors, nonnegative)
        wts = np.zeros(fn.size)
        wts[list(anchors)] = 1.0
    elif method == "least_squares":
        if isinstance(weights, str):
            if weights == "uniform":
                wts = np.ones(fn.size)
            elif weights == "inverse_omega":
                wts = 1.0 / w
            elif weights == "mass_fraction":
                if mf is None:
                    raise ParameterError("weights='mass_fraction' needs mass_fraction")
                wts = mf.copy()
            else:
                raise ParameterError(
                    "weights must be 'uniform', 'inverse_omega', 'mass_fraction' or an "
                    f"array, got {weights!r}"
                )
        else:
            wts = np.asarray(weights, dtype=float)
            if wts.shape != fn.shape:
                raise DimensionError(f"weights needs {fn.size} values, got shape {wts.shape}")
            if np.any(wts < 0) or np.any(~np.isfinite(wts)):
                raise ParameterError("weights must be finite and >= 0")
        if np.count_nonzero(wts) < 2:
            raise ParameterError("least squares needs at least two modes with weight > 0")
        A = np.vstack([1 / (2 * w), w / 2]).T
        # scale columns so both unknowns are O(1) in the solve
        scale = np.array([1 / np.max(np.abs(A[:, 0])), 1 / np.max(np.abs(A[:, 1]))])
        sw = np.sqrt(wts)
        As = A * scale * sw[:, None]
        b = z * sw
        if nonnegative:
            coef, _ = scipy.optimize.nnls(As, b)
        else:
            coef, *_ = np.linalg.lstsq(As, b, rcond=None)
        alpha, beta = (coef * scale).tolist()
        anchors = tuple(int(k) for k in np.flatnonzero(wts > 0))
    else:
        raise ParameterError(
            f"method must be 'two_mode', 'least_squares' or 'chowdhury', got {method!r}"
        )
    fit = rayleigh_zeta(fn, alpha, beta)
    return RayleighFit(float(alpha), float(beta), method, fn, z, fit, fit - z, wts, anchors)


def _anchored(w, z, anchors, nonnegative):
    i, j = anchors
    alpha, beta = _two_mode(w[i], w[j], z[i], z[j])
    if nonnegative and (alpha < 0 or beta < 0):
        # one coefficient at zero, the other by least squares through both anchors
        wa = w[[i, j]]
        za = z[[i, j]]
        if alpha < 0:
            alpha, beta = 0.0, max(float(np.sum(za * wa / 2) / np.sum((wa / 2) ** 2)), 0.0)
        else:
            alpha, beta = max(float(np.sum(za / (2 * wa)) / np.sum((1 / (2 * wa)) ** 2)), 0.0), 0.0
    return float(alpha), float(beta)
