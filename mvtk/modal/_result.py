"""The identified-modes result: table with quality, shapes, synthesis, AutoMAC."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import xarray as xr

from ._quality import mac
from ._stabilisation import StabilisationDiagram

__all__ = ["IdentifiedModes"]


@dataclass(frozen=True)
class IdentifiedModes:
    """Modes identified from test data, with the evidence and quality of each.

    Attributes
    ----------
    method : str
        ``"pLSCF+LSFD"`` or ``"SSI-cov"``.
    fn_hz, zeta : numpy.ndarray
        Undamped natural frequency (Hz) and damping ratio of each mode.
    pole : numpy.ndarray of complex
        ``-zeta w_n + i w_d`` in rad/s.
    shapes : xarray.DataArray
        Complex shapes ``("mode", "dof")``; ``attrs["normalisation"]`` is ``"mass"``
        (unit modal A, residue ``A_oi = phi_o phi_i / (2 i w_d)`` scaled from a driving
        point) or ``"unit_max"`` (largest component 1).
    real_shapes : xarray.DataArray
        Real normal shapes ``("mode", "dof")``: each complex shape rotated onto its
        best-fit line in the complex plane and its real part kept; mass-normalised when
        a driving point scaled them, else unit maximum.
    participation : numpy.ndarray, shape (n_modes, n_reference) or None
        Modal participation of the references (pLSCF).
    mpc, mpd : numpy.ndarray
        Modal phase collinearity (0..1) and mean phase deviation (deg) of the shapes.
    stability_count : numpy.ndarray of int
        Model orders in which the mode was fully stable.
    reliable : numpy.ndarray of bool
    reason : tuple of str
        Why a mode is not reliable (``"ok"`` otherwise).
    frf, synthesised : xarray.DataArray or None
        Measured FRFs in the band and the FRFs of the identified model (pLSCF+LSFD).
    correlation : xarray.DataArray or None
        Per-response correlation of measured and synthesised FRFs over references and
        lines, ``|sum H_m conj(H_s)|^2 / (sum |H_m|^2 sum |H_s|^2)``; ``attrs["overall"]``
        is the same over all FRFs.
    residue : numpy.ndarray or None
        ``(n_modes, n_response, n_reference)`` receptance residues.
    lower_residual, upper_residual : numpy.ndarray or None
        Real residual terms ``(n_response, n_reference)`` of the LSFD fit.
    diagram : StabilisationDiagram
        The stabilisation diagram the poles were selected from.
    support : numpy.ndarray or None
        Evidence that the data need each mode (pLSCF+LSFD): the LSFD misfit
        ``sum |H - H_fit|^2`` within ``fn +- max(5 lines, 2 zeta fn)`` of a fit without
        the mode divided by that of the full fit (``inf`` for an exact fit). Below 2
        the mode is marked not reliable. ``None`` (SSI-cov: no FRFs).
    excitation_db : numpy.ndarray or None
        Level of the excitation (reference autospectrum, best reference) at each mode's
        frequency in dB re its maximum in the band; NaN when the FRFs carry no
        excitation level (UFF 58 and other FRF files). Below the threshold of the
        excitation type (``mvtk.modal._identify.WEAK_EXCITATION_DB``: impact -35 dB,
        sweep and random -50 dB) the mode is marked not reliable ("weakly excited").
    band_hz : tuple of float or None
        The analysis band (Hz) the modes were identified in.
    band_reason : str
        Why that band: ``"given"``, or how it was chosen from the data (excited band,
        resonance peaks, peaks the band leaves out or cuts; :func:`mvtk.modal.identify`).
    kurtosis : numpy.ndarray or None
        SSI-cov: kurtosis of the response band-passed around each mode on its strongest
        channel (:func:`mvtk.modal._harmonics.band_kurtosis`; 3 for a mode's response to
        random excitation, 1.5 for a sinusoid). Below
        :data:`~mvtk.modal._harmonics.HARMONIC_KURTOSIS` (2.0) the mode is marked not
        reliable ("harmonic"). A mode that explains one of the record's strongest
        spectral lines (within 1 % or 2 lines) gets that line's band kurtosis when it
        is lower. ``None`` (pLSCF+LSFD).
    fn_std_hz, zeta_std : numpy.ndarray or None
        First-order standard deviations of ``fn_hz`` (Hz) and ``zeta``: pLSCF+LSFD from
        the FRF fit residual, SSI-cov from the scatter of data blocks (Reynders,
        Pintelon & De Roeck 2008; Döhler & Mevel 2013); NaN where not computed.
    shape_std : xarray.DataArray or None
        Standard deviation of each shape component, dims of :attr:`shapes`.

    Examples
    --------
    Returned by :func:`mvtk.modal.identify`; ``to_dataframe`` is the quality table:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> modes = modal.identify(h, 2.0, 110.0)
    >>> modes.to_dataframe()[["fn_hz", "zeta"]].round({"fn_hz": 3, "zeta": 5}).values.tolist()
    [[31.105, 0.00128], [81.434, 0.00049]]
    """

    method: str
    fn_hz: np.ndarray
    zeta: np.ndarray
    pole: np.ndarray
    shapes: xr.DataArray
    real_shapes: xr.DataArray
    participation: np.ndarray | None
    mpc: np.ndarray
    mpd: np.ndarray
    stability_count: np.ndarray
    reliable: np.ndarray
    reason: tuple
    frf: xr.DataArray | None
    synthesised: xr.DataArray | None
    correlation: xr.DataArray | None
    residue: np.ndarray | None
    lower_residual: np.ndarray | None
    upper_residual: np.ndarray | None
    diagram: StabilisationDiagram
    support: np.ndarray | None = None
    excitation_db: np.ndarray | None = None
    kurtosis: np.ndarray | None = None
    fn_std_hz: np.ndarray | None = None
    zeta_std: np.ndarray | None = None
    shape_std: xr.DataArray | None = None
    refined: np.ndarray | None = None
    zeta_window: np.ndarray | None = None
    window_tau_s: float | None = None
    band_hz: tuple | None = None
    band_reason: str = ""

    @property
    def n_modes(self) -> int:
        """Number of identified modes."""
        return int(self.fn_hz.size)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per mode: ``mode fn_hz fn_std_hz zeta zeta_std zeta_window mpc mpd
        stability_count support excitation_db kurtosis refined reliable reason``
        (``fn_std_hz``, ``zeta_std``, ``zeta_window``, ``support``, ``excitation_db``,
        ``kurtosis`` NaN where they do not apply: no uncertainty computed, no
        exponential window, SSI-cov has no FRFs, FRFs without the force no excitation
        level, pLSCF no time histories)."""
        def column(v):
            return (np.full(self.n_modes, np.nan) if v is None
                    else np.asarray(v, dtype=float))

        return pd.DataFrame({
            "mode": np.arange(1, self.n_modes + 1),
            "fn_hz": self.fn_hz, "fn_std_hz": column(self.fn_std_hz), "zeta": self.zeta,
            "zeta_std": column(self.zeta_std), "zeta_window": column(self.zeta_window),
            "mpc": self.mpc, "mpd": self.mpd,
            "stability_count": self.stability_count, "support": column(self.support),
            "excitation_db": column(self.excitation_db), "kurtosis": column(self.kurtosis),
            "refined": (np.zeros(self.n_modes, bool) if self.refined is None
                        else np.asarray(self.refined, bool)),
            "reliable": self.reliable, "reason": list(self.reason),
        })

    def shape_table(self, real: bool = False) -> pd.DataFrame:
        """The shapes as one row per mode and DOF: ``mode dof node direction real imag``.

        ``real`` picks :attr:`real_shapes` instead of the complex :attr:`shapes` (then
        ``imag`` is 0). The long form suits CSV and JSON
        (``to_json(orient="records", double_precision=15)``).
        """
        s = self.real_shapes if real else self.shapes
        v = np.asarray(s.values, dtype=complex)
        nm, nd = v.shape
        return pd.DataFrame({
            "mode": np.repeat(s["mode"].values, nd),
            "dof": np.tile(np.asarray(s["dof"].values, dtype=str), nm),
            "node": np.tile(s["node"].values, nm),
            "direction": np.tile(np.asarray(s["direction"].values, dtype=str), nm),
            "real": v.real.ravel(), "imag": v.imag.ravel(),
        })

    def automac(self, real: bool = False) -> xr.DataArray:
        """AutoMAC of the (complex, or real) shapes, dims ``("mode", "mode_2")``."""
        s = self.real_shapes if real else self.shapes
        m = mac(s.values)
        modes = s["mode"].values
        return xr.DataArray(m, dims=("mode", "mode_2"),
                            coords={"mode": modes, "mode_2": modes}, name="automac")

    def _repr_html_(self) -> str:
        head = (f"<b>IdentifiedModes</b> ({self.method}, {self.n_modes} modes, band "
                f"{self.diagram.band_hz[0]:g}..{self.diagram.band_hz[1]:g} Hz")
        if self.correlation is not None:
            head += f", FRF correlation {self.correlation.attrs['overall']:.3f}"
        head += ")"
        return head + self.to_dataframe().to_html(index=False, float_format=lambda v: f"{v:.4g}")

    def __repr__(self) -> str:
        return f"IdentifiedModes({self.method}, {self.n_modes} modes)\n" + \
            self.to_dataframe().to_string(index=False)
