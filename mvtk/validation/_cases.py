"""The registry of validation cases: mvtk against external truths, one source for tests and docs.

Each :class:`ValidationCase` names a published benchmark, a closed form, a peer library or
a real file of someone else's instrument, states its reference values and tolerance, and
carries the function that computes mvtk's current values. The same registry is

- asserted case by case by ``tests/validation/test_validation_cases.py`` (each case is a
  test that can fail), and
- run by the documentation build (``docs/_ext/mvtk_docs.py``), which writes the validation
  evidence page from :func:`run_validation` (reference, current value, error, tolerance and
  verdict per case), so the page always shows the numbers of the code it documents.

The registry lives in the package (not in ``tests/``) so that an installed mvtk can check
itself (``mvtk.validation.run_validation()``) and the docs build needs no test code on its
path. Only cases that run in well under a second or two each are registered: the whole
registry runs in a few seconds, cheap enough for every docs build. Cases that read the
external measurement corpus (``../shared/data`` next to a checkout, or
``$MVTK_SHARED_DATA``) are reported as skipped, with the reason, when it is absent.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ._checks import Check

__all__ = ["ValidationCase", "validation_cases", "run_validation", "shared_data_dir"]


@dataclass(frozen=True)
class ValidationCase:
    """One benchmark: reference values, tolerance, and how mvtk computes its values.

    Parameters
    ----------
    name : str
        Unique identifier, ``"<area>.<what>"`` (e.g. ``"fe.leissa_cfff_plate"``).
    area : str
        Pipeline stage the case validates (``"io"``, ``"signal"``, ``"damping"``,
        ``"modal"``, ``"fe"``, ``"correlation"``, ``"reduction"``, ``"control"``).
    title : str
        One line: the structure/data and what is compared.
    source : str
        Where the reference values come from (full citation, or the PROVENANCE.md row of
        a real file).
    labels : tuple of str
        Name of each compared quantity, one per reference value.
    reference : tuple of float
        The reference values, in ``unit``.
    tolerance : float
        Allowed deviation, applied as in :class:`mvtk.validation.Check` with ``kind``.
    compute : callable
        ``compute()`` (or ``compute(data_dir)`` when ``data`` is not empty) returns mvtk's
        current values, one per label, in ``unit``.
    unit : str
        Unit of the values (``""`` for dimensionless).
    kind : {"relative", "absolute", "upper", "lower"}
        How ``tolerance`` is applied (see :class:`mvtk.validation.Check`).
    data : tuple of str
        Files of the external measurement corpus the case reads, relative to it.
    """

    name: str
    area: str
    title: str
    source: str
    labels: tuple[str, ...]
    reference: tuple[float, ...]
    tolerance: float
    compute: Callable[..., Sequence[float]] = field(repr=False, compare=False)
    unit: str = ""
    kind: str = "relative"
    data: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if len(self.labels) != len(self.reference):
            raise ParameterError(
                f"validation case {self.name!r}: {len(self.labels)} labels but "
                f"{len(self.reference)} reference values")
        if self.kind not in ("relative", "absolute", "upper", "lower"):
            raise ParameterError(
                f"validation case {self.name!r}: kind must be 'relative', 'absolute', "
                f"'upper' or 'lower', got {self.kind!r}")

    def checks(self, data_dir: str | Path | None = None) -> list[Check]:
        """Run the case: one :class:`~mvtk.validation.Check` per compared quantity.

        Parameters
        ----------
        data_dir : path, optional
            The external measurement corpus (default :func:`shared_data_dir`); only
            used by cases with ``data``.

        Raises
        ------
        FileNotFoundError
            A file of ``data`` is not in ``data_dir``.
        ParameterError
            ``compute`` returned a different number of values than there are labels.
        """
        if self.data:
            root = Path(data_dir) if data_dir is not None else shared_data_dir()
            missing = [f for f in self.data if not (root / f).is_file()]
            if missing:
                raise FileNotFoundError(
                    f"validation case {self.name!r}: {', '.join(missing)} not found in the "
                    f"measurement corpus {str(root)!r} (set $MVTK_SHARED_DATA)")
            values = self.compute(root)
        else:
            values = self.compute()
        values = np.atleast_1d(np.asarray(values, dtype=float))
        if values.size != len(self.labels):
            raise ParameterError(
                f"validation case {self.name!r}: computed {values.size} values for "
                f"{len(self.labels)} labels {list(self.labels)}")
        return [Check(f"{self.name}: {lab}", float(v), ref, self.tolerance, self.unit,
                      self.kind, self.source)
                for lab, v, ref in zip(self.labels, values, self.reference)]


def shared_data_dir() -> Path:
    """The external measurement corpus: ``$MVTK_SHARED_DATA``, else ``../shared/data``
    next to the checkout mvtk is imported from (it may not exist)."""
    env = os.environ.get("MVTK_SHARED_DATA")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "shared" / "data"


# --------------------------------------------------------------------------- io
def _uff_mpstd_sums(root: Path):
    import mvtk.io

    th = mvtk.io.read(root / "uff" / "MPSTD_Set001_2024_10_08_10_27_07.uff")["time_history"]
    return th.sum("time").values


def _lvm_acceleration(root: Path):
    import mvtk.io

    th = mvtk.io.read(root / "lvm" / "acceleration.lvm")["time_history"]
    vals = th.values
    return [vals[0].sum(), vals[1].sum(), vals[1].max(), float(np.argmax(vals[1]))]


def _tdms_sum(root: Path):
    import mvtk.io

    th = mvtk.io.read(root / "tdms" / "good_tdms_1.tdms")["time_history"]
    return [float(th.values.astype(np.float64).sum()), float(th.attrs["fs"])]


def _uff55_complex_mode(root: Path):
    import mvtk.io

    ms = mvtk.io.read(root / "uff" / "uff55_sample_test_record10.uff")["mode_shape"]
    lam = complex(ms.eigenvalue.item())
    return [lam.real, lam.imag]


def _mat_case1_peak(root: Path):
    import scipy.io

    from mvtk.damping import half_power
    from mvtk.errors import ResolutionWarning

    d = scipy.io.loadmat(root / "mat" / "case1.mat")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResolutionWarning)  # 1.1 lines: known, flagged
        r = half_power(d["Hf_chan_2"].ravel(), d["Freq_domain"].ravel(), fn_hz=[212.0])
    return [r.fn_hz[0]]


# --------------------------------------------------------------------------- signal
def _csd_vs_scipy():
    import scipy.signal

    import mvtk.testing as T
    from mvtk.signal import csd

    th = T.random_excitation_test([20.0, 55.0], [0.02, 0.03], 512.0, 60.0,
                                  np.random.default_rng(1))
    c = csd(th, reference="force", nperseg=512, noverlap=128, window="hamming")
    _, ref = scipy.signal.csd(th.values[0], th.values, fs=512.0, nperseg=512, noverlap=128,
                              window="hamming")
    return [float(np.max(np.abs(c.values[:, 0] - ref)) / np.max(np.abs(ref)))]


# --------------------------------------------------------------------------- damping
def _rayleigh_table3():
    from mvtk.damping import rayleigh_fit

    r = rayleigh_fit([13.26, 41.14], [5.84e-4, 1.32e-3])
    return [r.alpha, r.beta]


def _half_power_exact():
    import mvtk.testing as T
    from mvtk.damping import half_power

    fn, zeta = 50.0, 2e-3
    df = 2 * zeta * fn / 5  # 5 lines across the half-power band
    f = np.arange(fn * (1 - 40 * zeta), fn * (1 + 40 * zeta), df)
    r = half_power(T.modal_frf(f, fn, zeta, kind="receptance"), fn_hz=[fn])
    return [r.fn_hz[0], r.zeta[0]]


# --------------------------------------------------------------------------- modal
def _chain_matrices(n=6, m=1.0, k=1e5, alpha=0.5, beta=1e-5):
    M = np.eye(n) * m
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] = 2 * k if i < n - 1 else k
        if i > 0:
            K[i, i - 1] = K[i - 1, i] = -k
    return M, alpha * M + beta * K, K


def _chain_exact_poles():
    import scipy.linalg as sla

    M, C, K = _chain_matrices()
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = sla.eigvals(A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))][:4]
    return np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam)


def _chain_identified():
    from mvtk.modal import exact_frf, identify

    M, C, K = _chain_matrices()
    fn, _ = _chain_exact_poles()
    f = np.arange(0.0, 1.15 * fn[-1], 0.05)
    h = exact_frf(M, C, K, f, range(6), [0, 5], frf_type="accelerance")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = identify(h, 0.5 * fn[0], 1.1 * fn[-1])
    j = [int(np.argmin(np.abs(res.fn_hz - x))) for x in fn]
    return np.concatenate([res.fn_hz[j], res.zeta[j]])


def _chain_reference():
    fn, zeta = _chain_exact_poles()
    return tuple(float(x) for x in np.concatenate([fn, zeta]))


# --------------------------------------------------------------------------- fe
def _steel():
    from mvtk.fe import IsotropicMaterial

    return IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def _kirchhoff_lambda(h: float, a: float = 1.0, E=210e9, nu=0.3, rho=7850.0) -> float:
    """``a^2 sqrt(rho h / D)``: omega times this is Leissa's frequency parameter."""
    return a**2 * np.sqrt(rho * h / (E * h**3 / (12 * (1 - nu**2))))


def _leissa_cfff():
    from mvtk.fe import Ply, modal_analysis, plate_model

    h = 1e-3
    model = plate_model(1.0, 1.0, [Ply(_steel(), h)], nx=24, ny=24, clamp="x0")
    return 2 * np.pi * modal_analysis(model, 5).fn_hz * _kirchhoff_lambda(h)


def _ssss_thin_plate():
    from mvtk.fe import Ply, modal_analysis, plate_model

    h = 1e-3
    ssss = {e: "simply_supported" for e in ("x0", "x1", "y0", "y1")}
    model = plate_model(1.0, 1.0, [Ply(_steel(), h)], nx=24, ny=24, supports=ssss)
    lam = 2 * np.pi * modal_analysis(model, 4).fn_hz * _kirchhoff_lambda(h)
    return [lam[0], lam[1], lam[3]]


def _leissa_ffff():
    from mvtk.fe import Ply, modal_analysis, plate_model

    h = 1e-3
    res = modal_analysis(plate_model(1.0, 1.0, [Ply(_steel(), h)], nx=20, ny=20), 9)
    return 2 * np.pi * res.fn_hz[6:] * _kirchhoff_lambda(h)  # after the six rigid modes


def _smits_bimorph():
    from mvtk.fe import PiezoMaterial, Ply, factorize
    from mvtk.fe._beam import cantilever_beam
    from mvtk.fe._piezo import PiezoPatch

    pic151 = PiezoMaterial("PIC151", 66.667e9, 0.34, 7800.0, d31=-210e-12)
    L, b, t, V = 0.03, 0.005, 0.25e-3, 10.0
    lay = (Ply(pic151, t), Ply(pic151, t))
    model = cantilever_beam(L, b, lay, 8)
    top = PiezoPatch("top", lay, 1, ("clamp", "tip"), b)
    bottom = PiezoPatch("bottom", lay, 0, ("clamp", "tip"), b)
    u = factorize(model.K).solve(top.load_vector(model, V / 2)
                                 + bottom.load_vector(model, -V / 2))
    return [u[model.dof_index(model.node_set("tip")[0], "uz")]]


def _piezo_strip(L, b, nx, ny):
    xs, ys = np.linspace(0, L, nx + 1), np.linspace(0, b, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    q = np.array([[i * (ny + 1) + j, (i + 1) * (ny + 1) + j, (i + 1) * (ny + 1) + j + 1,
                   i * (ny + 1) + j + 1] for i in range(nx) for j in range(ny)])
    return nodes, q


def _smits_parallel_shell():
    from mvtk.fe import (
        Electrode,
        Laminate,
        PiezoMaterial,
        Ply,
        ShellPiezoPatch,
        ShellSet,
        assemble_model,
        piezo_coupling,
        static_solve,
    )

    pz = PiezoMaterial("PZT nu=0", 66.667e9, 0.0, 7800.0, -210e-12)
    L, b, t = 0.04, 0.005, 0.25e-3
    nodes, q = _piezo_strip(L, b, 40, 2)
    lam = Laminate((Ply(pz, t), Ply(pz, t)))
    m = assemble_model(nodes, [ShellSet(q, lam)], supports={"c": "clamped"},
                       node_sets={"c": np.flatnonzero(nodes[:, 0] == 0)})
    cp = piezo_coupling(m, [ShellPiezoPatch("bim", q, lam, electrodes=(
        Electrode("V", (0, 1), (-1, 1)),))])
    tip = np.flatnonzero(np.isclose(nodes[:, 0], L))
    w = m.expand(static_solve(m, cp.B[:, 0]))[tip, 2].mean()
    f = np.zeros(m.n_dof)
    f[[m.dof_index(i, "uz") for i in tip]] = 1.0 / len(tip)
    g = m.expand(static_solve(m, f))[tip, 2].mean()
    return [w, w / g]


def _ieee176_k31():
    from mvtk.fe import (
        Laminate,
        PiezoMaterial,
        Ply,
        ShellPiezoPatch,
        ShellSet,
        assemble_model,
        modal_emcc,
        piezo_coupling,
    )

    s11, s12 = 16.5e-12, -4.78e-12
    pz = PiezoMaterial("PZT-5H", 1 / s11, -s12 / s11, 7500.0, -274e-12,
                       eps33=3400 * 8.8541878128e-12)
    nodes, q = _piezo_strip(0.04, 0.002, 80, 1)
    lam = Laminate((Ply(pz, 0.5e-3),))
    m = assemble_model(nodes, [ShellSet(q, lam)], supports={"all": ["uz", "rx", "ry"]},
                       node_sets={"all": np.arange(len(nodes))})
    rows = modal_emcc(m, piezo_coupling(m, [ShellPiezoPatch("p", q, lam)]), n_modes=8)
    ext = max((r for r in rows if np.isfinite(r["k2"])), key=lambda r: r["k2"])
    return [ext["f_oc_hz"] / ext["f_sc_hz"]]


def _ieee176_k31_reference():
    from scipy.optimize import brentq

    k2 = (274e-12) ** 2 / (16.5e-12 * 3400 * 8.8541878128e-12)
    xa = brentq(lambda x: (1 - k2) * np.cos(x) * x + k2 * np.sin(x), np.pi / 2 + 1e-9,
                np.pi - 1e-9)
    return (xa / (np.pi / 2),)


def _navier_cross_ply_omega(E1, E2, G12, G13, G23, nu12, rho, a, h, ks=5.0 / 6.0):
    """Lowest omega (rad/s) of mode (1, 1) of a simply supported square 0/90/90/0 plate
    (equal plies) in first-order shear deformation theory: the 3 x 3 Navier eigenproblem
    (Reddy 2004, section 6.3.2), with the laminate stiffnesses written out here from the
    ply constants (not from mvtk.fe.Laminate, the code under test)."""
    import scipy.linalg as sla

    nu21 = nu12 * E2 / E1
    q11, q22 = E1 / (1 - nu12 * nu21), E2 / (1 - nu12 * nu21)
    q12, q66 = nu12 * E2 / (1 - nu12 * nu21), G12
    # outer 0-degree plies: int z^2 = 7 h^3 / 96; inner 90-degree plies: h^3 / 96
    d11, d22 = (7 * q11 + q22) * h**3 / 96, (7 * q22 + q11) * h**3 / 96
    d12, d66 = q12 * h**3 / 12, q66 * h**3 / 12
    s = ks * (G13 + G23) / 2 * h  # A44 = A55 for the symmetric equal-ply stack
    al = be = np.pi / a
    Kn = np.array([
        [s * (al**2 + be**2), s * al, s * be],
        [s * al, d11 * al**2 + d66 * be**2 + s, (d12 + d66) * al * be],
        [s * be, (d12 + d66) * al * be, d66 * al**2 + d22 * be**2 + s],
    ])
    Mn = np.diag([rho * h, rho * h**3 / 12, rho * h**3 / 12])
    return float(np.sqrt(sla.eigh(Kn, Mn, eigvals_only=True)[0]))


def _reddy_cross_ply():
    from mvtk.fe import OrthotropicMaterial, Ply, modal_analysis, plate_model

    E2 = 1e10
    mat = OrthotropicMaterial("gr", E1=40 * E2, E2=E2, G12=0.6 * E2, G13=0.6 * E2,
                              G23=0.5 * E2, nu12=0.25, rho=1500.0)
    a, h = 1.0, 0.1
    plies = [Ply(mat, h / 4, ang) for ang in (0, 90, 90, 0)]
    ssss = {e: "simply_supported" for e in ("x0", "x1", "y0", "y1")}
    model = plate_model(a, a, plies, nx=20, ny=20, supports=ssss)
    return [2 * np.pi * modal_analysis(model, 1).fn_hz[0]]


def _reddy_cross_ply_reference():
    E2 = 1e10
    return (_navier_cross_ply_omega(40 * E2, E2, 0.6 * E2, 0.6 * E2, 0.5 * E2, 0.25, 1500.0,
                                    1.0, 0.1),)


def _nafems_fv2():
    from mvtk.fe import (
        BeamSet,
        IsotropicMaterial,
        assemble_model,
        modal_analysis,
        rectangle_section,
    )

    mat = IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    sec = rectangle_section(mat, 0.125, 0.125)
    L, per_arm = 5.0, 4
    nodes, els, ends = [np.zeros(3)], [], []
    for k in range(8):
        d = np.array([np.cos(k * np.pi / 4), np.sin(k * np.pi / 4), 0.0])
        start = 0
        for s in range(1, per_arm + 1):
            nodes.append(d * L * s / per_arm)
            els.append([start, len(nodes) - 1])
            start = len(nodes) - 1
        ends.append(start)
    nodes = np.array(nodes)
    model = assemble_model(
        nodes, [BeamSet(np.array(els), sec, orientation=(0, 0, 1))],
        supports={"ends": "pinned", "all": "symmetry_z"},  # in-plane vibration only
        node_sets={"ends": np.array(ends), "all": np.arange(len(nodes))})
    f = modal_analysis(model, 9).fn_hz
    return [f[0], f[1], f[7], f[8]]


def _cantilever_strip():
    from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model

    L, b, h = 1.0, 0.05, 0.005
    mat = IsotropicMaterial("nu0", 210e9, 0.0, 7850.0)  # nu = 0: the strip is a beam
    res = modal_analysis(plate_model(L, b, [Ply(mat, h)], nx=40, ny=2, clamp="x0"), 6)
    return res.fn_hz[np.array(res.mode_type) == "bending"][:3]


def _cantilever_strip_reference():
    L, b, h, E, rho = 1.0, 0.05, 0.005, 210e9, 7850.0
    beta = np.array([1.875104069, 4.694091133, 7.854757438])
    return tuple(beta**2 / (2 * np.pi * L**2) * np.sqrt(E * b * h**3 / 12 / (rho * b * h)))


# --------------------------------------------------------------------------- updating
def _twin_modulus():
    from mvtk.updating import FrequencyTarget, Parameter, update

    L, b, h, E, rho = 0.3, 0.02, 2e-3, 210e9, 7850.0
    desc = {"name": "steel strip", "materials": {"steel": {"E": 1.3 * E, "nu": 0.3,
                                                           "rho": rho}},
            "structure": {"type": "beam", "length": L, "width": b,
                          "layers": [{"material": "steel", "thickness": h}]},
            "mesh": {"n_elements": 40}, "boundary": {"clamp": "x0"}}
    beta = _BETA_L[:2]
    f = beta**2 / (2 * np.pi * L**2) * np.sqrt(E * b * h**3 / 12 / (rho * b * h))
    r = update(desc, [Parameter("materials.steel.E", lower=1e11, upper=4e11)],
               [FrequencyTarget(x) for x in f])
    return [r.values[0]]


# --------------------------------------------------------------------------- correlation
def _serep_round_off():
    from mvtk import correlation as co
    from mvtk.fe import IsotropicMaterial, Ply, modal_analysis, plate_model

    steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    model = plate_model(0.3, 0.2, [Ply(steel, 2e-3)], nx=12, ny=8, clamp="x0")
    modal = modal_analysis(model, 10)
    pts = np.array([[x, y, 0.0] for x in np.linspace(0.05, 0.3, 5)
                    for y in np.linspace(0.01, 0.19, 4)])
    geo = co.TestGeometry(np.arange(1, 21), pts)
    geo = geo.with_sensors([(n, "+z") for n in geo.node])
    mp = co.map_sensors(geo, model)
    test = mp.project(modal).isel(mode=slice(0, 6))
    ex = co.expand_serep(test, model, modal, mp, modes=range(1, 7))
    full = co.fe_shapes(model, modal).isel(mode=slice(0, 6))
    return [float(np.abs(ex.shapes.values - full.values).max() / np.abs(full.values).max())]


# --------------------------------------------------------------------------- reduction
_BETA_L = np.array([1.875104069, 4.694091133, 7.854757438, 10.99554073])


def _cb_all_interior_modes():
    import scipy.linalg as sla

    from mvtk.reduction import craig_bampton
    from mvtk.reduction._examples import eb_beam_xz

    beam = eb_beam_xz(n_el=40)
    se = craig_bampton(beam, ["tip", "mid"], n_modes=beam.n_dof - 4)
    full = sla.eigh(beam.K.toarray(), beam.M.toarray(), eigvals_only=True)
    red = sla.eigh(se.K, se.M, eigvals_only=True)
    return [float(np.max(np.abs(red - full)) / full.max())]


def _cb_beam_closed_form():
    import scipy.linalg as sla

    from mvtk.reduction import craig_bampton
    from mvtk.reduction._examples import eb_beam_xz

    beam = eb_beam_xz(n_el=40)
    se = craig_bampton(beam, ["tip", "mid"], n_modes=8)
    w2 = sla.eigh(se.K, se.M, eigvals_only=True)[:4]
    return np.sqrt(w2) / (2 * np.pi)


def _cb_beam_reference():
    # eb_beam_xz defaults: L = 0.2 m, E = 210 GPa, rho = 7900, 20 mm x 0.5 mm
    L, E, rho, b, h = 0.2, 210e9, 7900.0, 0.02, 0.5e-3
    return tuple(_BETA_L**2 / (2 * np.pi * L**2) * np.sqrt(E * b * h**3 / 12 / (rho * b * h)))


# --------------------------------------------------------------------------- control
_F1 = 13.26


def _sdof(zeta=5.84e-4):
    from mvtk.control import modal_plant

    return modal_plant([_F1], zeta, [[0.37]], [[2.5]], inputs=["u"], outputs=["y"])


def _ppf_eq15():
    from mvtk.control import PPF, added_damping

    zf = 0.3
    return [added_damping(_sdof(), PPF([(_F1, zf, G)]), 1)["added"]
            for G in (0.001, 0.002, 0.005)]


def _ppf_unit_gain():
    from mvtk.control import PPF, critical_gain

    return [critical_gain(_sdof(), PPF([(r * _F1, zf, 0.1)]), g_max=2.0)
            for r, zf in ((1.0, 0.3), (0.7, 0.1), (1.5, 0.5))]


_SRF_CASES = ((1.2, 0.3), (1.5, 0.5), (2.0, 0.2))


def _srf_bound():
    from mvtk.control import SRF, critical_gain

    out = []
    for r, zf in _SRF_CASES:
        bound = _srf_routh(_F1, r * _F1, zf)
        out.append(critical_gain(_sdof(0.0), SRF([(r * _F1, zf, bound / 10)]),
                                 g_max=3 * bound))
    return out


def _srf_routh(f: float, ff: float, zf: float) -> float:
    """Closed-form SRF gain limit on an undamped mode, ``2 zf (wf^2 - w^2) / (w^2 wf)`` (s).

    Routh-Hurwitz on the loop ``xi'' + w^2 xi = -G w^2 eta``, ``eta'' + 2 zf wf eta' +
    wf^2 eta = wf^2 xi'`` (Newman 1992; PHYSICS.md section 4), written out here so that
    the reference does not come from the code under test.
    """
    w, wf = 2 * np.pi * f, 2 * np.pi * ff
    return 2 * zf * (wf**2 - w**2) / (w**2 * wf)


def _velocity_feedback():
    from mvtk.control import VelocityFeedback, added_damping

    return [added_damping(_sdof(0.0), VelocityFeedback(1e-3), 1)["zeta_closed"]]


# --------------------------------------------------------------------------- the registry
_LEISSA = "A. W. Leissa, Vibration of Plates, NASA SP-160 (1969)"


def validation_cases() -> tuple[ValidationCase, ...]:
    """All registered validation cases, in pipeline order.

    Returns
    -------
    tuple of ValidationCase
    """
    w1 = 2 * np.pi * _F1
    return (
        ValidationCase(
            "io.uff_mpstd_sums", "io",
            "UFF 58b, 4 acceleration channels of a real test: sum of each record",
            "shared/data PROVENANCE.md (pyuff test data, values read with pyuff 2.5.8)",
            ("channel 1", "channel 2", "channel 3", "channel 4"),
            (16068.767305360794, -70573.08901242912, -16626.510861555733, 28644.6128317588),
            1e-12, _uff_mpstd_sums, "m/s^2",
            data=("uff/MPSTD_Set001_2024_10_08_10_27_07.uff",)),
        ValidationCase(
            "io.lvm_impact_record", "io",
            "LabVIEW LVM (comma decimals) of a real hammer test: sums, peak force and its sample",
            "shared/data PROVENANCE.md (ladisk open_source_research_in_structural_dynamics, "
            "acceleration.lvm, values from numpy on the text)",
            ("sum acceleration (g)", "sum force (N)", "peak force (N)", "peak sample"),
            (-544.9039429631198, 14592.541468000001, 195.605522, 36.0),
            1e-9, _lvm_acceleration, "",
            data=("lvm/acceleration.lvm",)),
        ValidationCase(
            "io.tdms_tower_accelerations", "io",
            "NI TDMS, 8 float32 accelerometer channels of an offshore wind turbine tower: "
            "total sum (in float64) and sampling rate",
            "shared/data PROVENANCE.md (values read with npTDMS 1.13)",
            ("sum of all channels (g)", "fs (Hz)"), (-15.5978486, 30.0), 1e-7, _tdms_sum,
            data=("tdms/good_tdms_1.tdms",)),
        ValidationCase(
            "io.uff55_complex_mode", "io",
            "UFF 55 complex mode (pyuff sample record): eigenvalue",
            "shared/data PROVENANCE.md: eigenvalue -0.1111111 + 41.11111j",
            ("real part (1/s)", "imaginary part (rad/s)"), (-0.1111111, 41.11111), 1e-6,
            _uff55_complex_mode, data=("uff/uff55_sample_test_record10.uff",)),
        ValidationCase(
            "signal.csd_vs_scipy", "signal",
            "cross-spectral matrix (mvtk's own segment averaging, Hamming, 512 samples, "
            "128 overlap) of a 60 s random test against the force: max |mvtk - scipy| "
            "relative to the peak",
            "peer: scipy.signal.csd on the same data", ("max relative difference",),
            (0.0,), 1e-10, _csd_vs_scipy, "", "absolute"),
        ValidationCase(
            "damping.half_power_exact", "damping",
            "half-power on an exact single-mode receptance (50 Hz, zeta 0.2 %), 5 lines "
            "across the band",
            "closed form: the exact half-power relations of a single mode (PHYSICS.md "
            "section 2)", ("fn (Hz)", "zeta"), (50.0, 2e-3), 1e-6, _half_power_exact),
        ValidationCase(
            "damping.rayleigh_table3", "damping",
            "Rayleigh alpha, beta from the half-power pair zeta 5.84e-4 at 13.26 Hz, "
            "1.32e-3 at 41.14 Hz",
            "the seed paper, 'Active Vibration Control of a Super Element Model of a "
            "Thin-walled Structure', Table 3 (alpha 0.02955 1/s, beta 9.77e-6 s; printed to "
            "3-4 digits, hence 0.5 %)",
            ("alpha (1/s)", "beta (s)"), (0.02955, 9.77e-6), 5e-3, _rayleigh_table3),
        ValidationCase(
            "damping.mat_case1_212hz", "damping",
            "half-power on the measured FRF of case1.mat (vibration_toolbox), mode near 212 Hz",
            "shared/data PROVENANCE.md: the source project's single-mode curve fit, "
            "212.0925 Hz", ("fn (Hz)",), (212.0925,), 0.02, _mat_case1_peak, "Hz",
            "absolute", data=("mat/case1.mat",)),
        ValidationCase(
            "modal.chain_plscf_lsfd", "modal",
            "pLSCF/LSFD on the exact accelerance matrix of a 6-mass chain with Rayleigh "
            "damping (6 responses, 2 references): first four poles",
            "closed form: eigenvalues of the state matrix of the same M, C, K "
            "(scipy.linalg.eigvals)",
            ("f1 (Hz)", "f2 (Hz)", "f3 (Hz)", "f4 (Hz)",
             "zeta1", "zeta2", "zeta3", "zeta4"),
            _chain_reference(), 1e-4, _chain_identified),
        ValidationCase(
            "fe.kirchhoff_ssss_plate", "fe",
            "MITC4, thin (a/h = 1000) simply supported square steel plate, 24 x 24: "
            "frequency parameters omega a^2 sqrt(rho h / D)",
            f"closed form (Navier, Kirchhoff): 2 pi^2, 5 pi^2, 8 pi^2; {_LEISSA}, eq. 4.21",
            ("mode (1,1)", "mode (1,2)", "mode (2,2)"),
            (2 * np.pi**2, 5 * np.pi**2, 8 * np.pi**2), 1e-2, _ssss_thin_plate),
        ValidationCase(
            "fe.leissa_cfff_plate", "fe",
            "MITC4, cantilevered (CFFF) square steel plate, 24 x 24, nu = 0.3: frequency "
            "parameters of the first five modes",
            f"{_LEISSA}, Table 4.50 (Ritz values)",
            ("mode 1", "mode 2", "mode 3", "mode 4", "mode 5"),
            (3.492, 8.525, 21.43, 27.33, 31.11), 1e-2, _leissa_cfff),
        ValidationCase(
            "fe.leissa_ffff_plate", "fe",
            "MITC4, free square steel plate, 20 x 20, nu = 0.3: frequency parameters of the "
            "first three elastic modes (after six rigid-body modes)",
            f"{_LEISSA}, free square plate, nu = 0.3", ("mode 7", "mode 8", "mode 9"),
            (13.468, 19.596, 24.270), 1e-2, _leissa_ffff),
        ValidationCase(
            "fe.smits_bimorph", "fe",
            "series PIC 151 bimorph 30 x 5 x 0.5 mm, 10 V, 8 beam elements with the piezo "
            "moment pairs: free-tip deflection",
            "closed form: delta = 3/2 d31 V L^2 / h^2 (J. G. Smits, S. I. Dalke, T. K. "
            "Cooney, Sensors and Actuators A 28 (1991) 41-61)", ("tip deflection (m)",),
            (1.5 * 210e-12 * 10.0 * 0.03**2 / (0.5e-3) ** 2,), 1e-9, _smits_bimorph, "m"),
        ValidationCase(
            "fe.smits_bimorph_shell", "fe",
            "parallel PZT bimorph 40 x 5 x 0.5 mm (nu = 0), 40 x 2 MITC4 shells with the "
            "electromechanical coupling: tip deflection and blocked force per volt",
            "closed form: delta = 3 d31 L^2 / h^2, F = 3/4 E d31 b h / L (J. G. Smits, "
            "S. I. Dalke, T. K. Cooney, Sensors and Actuators A 28 (1991) 41-61)",
            ("tip deflection per volt (m/V)", "blocked force per volt (N/V)"),
            (3 * 210e-12 * 0.04**2 / (0.5e-3) ** 2,
             0.75 * 66.667e9 * 210e-12 * 0.005 * 0.5e-3 / 0.04), 1e-2,
            _smits_parallel_shell, ""),
        ValidationCase(
            "fe.ieee176_k31_bar", "fe",
            "free PZT-5H bar 40 x 2 x 0.5 mm with full electrodes, 80 MITC4 shells: "
            "open-circuit / short-circuit frequency of the length-extensional mode",
            "IEEE Standard on Piezoelectricity, ANSI/IEEE Std 176-1987: the anti-resonance of "
            "the k31 bar solves (1 - k31^2) + k31^2 tan(x)/x = 0, x = omega L / (2 c); PZT-5H "
            "s11E = 16.5e-12 m^2/N, d31 = -274 pm/V, eps33T = 3400 eps0",
            ("f_oc / f_sc",), _ieee176_k31_reference(), 1e-3, _ieee176_k31, ""),
        ValidationCase(
            "fe.reddy_cross_ply", "fe",
            "MITC4, simply supported 0/90/90/0 plate, a/h = 10, E1/E2 = 40, 20 x 20: "
            "fundamental omega",
            "closed form: Navier solution of first-order shear deformation theory, J. N. "
            "Reddy, Mechanics of Laminated Composite Plates and Shells, 2nd ed. (2004), "
            "section 6.3 (shear correction 5/6), laminate stiffnesses from the ply constants; "
            "omega a^2 / h sqrt(rho / E2) = 15.1426",
            ("omega_11 (rad/s)",), _reddy_cross_ply_reference(), 1e-2,
            _reddy_cross_ply, "rad/s"),
        ValidationCase(
            "fe.cantilever_strip", "fe",
            "MITC4 strip (nu = 0) 1 m x 50 mm x 5 mm clamped at one end: first three "
            "bending frequencies",
            "closed form: Euler-Bernoulli cantilever, beta_n L = 1.8751, 4.6941, 7.8548 "
            "(R. D. Blevins, Formulas for Natural Frequency and Mode Shape, 1979, table 8-1)",
            ("f1 (Hz)", "f2 (Hz)", "f3 (Hz)"), _cantilever_strip_reference(), 5e-3,
            _cantilever_strip, "Hz"),
        ValidationCase(
            "fe.nafems_fv2", "fe",
            "Timoshenko beams, pin-ended double cross (8 arms of 4 elements), in-plane "
            "vibration",
            "NAFEMS, The Standard NAFEMS Benchmarks, TNSB rev. 3 (1990), test FV2: "
            "f1 = 11.336 Hz, f2..f8 = 17.709 Hz, f9 = 45.345 Hz",
            ("f1", "f2", "f8", "f9"), (11.336, 17.709, 17.709, 45.345), 5e-3, _nafems_fv2,
            "Hz"),
        ValidationCase(
            "updating.twin_modulus", "updating",
            "updating E of a 300 x 20 x 2 mm steel cantilever (40 beam elements) from a start "
            "30 % too stiff to the first two Euler-Bernoulli frequencies of E = 210 GPa",
            "closed form: Euler-Bernoulli cantilever roots (R. D. Blevins, Formulas for "
            "Natural Frequency and Mode Shape, 1979, table 8-1) with the known modulus",
            ("E (Pa)",), (210e9,), 5e-3, _twin_modulus, "Pa"),
        ValidationCase(
            "correlation.serep_round_off", "correlation",
            "SEREP expansion of 6 FE mode shapes sampled at 20 sensors of a cantilever plate "
            "back to all DOFs: max deviation relative to the largest entry",
            "exact: SEREP reproduces shapes that lie in its mode basis (J. C. O'Callahan, "
            "P. Avitabile, R. Riemer, IMAC VII, 1989)", ("max relative deviation",), (0.0,),
            1e-12, _serep_round_off, "", "absolute"),
        ValidationCase(
            "reduction.cb_beam_closed_form", "reduction",
            "Craig-Bampton (tip and mid-span retained, 8 fixed-interface modes) of a 40-element "
            "Euler-Bernoulli steel cantilever 200 x 20 x 0.5 mm: first four frequencies",
            "closed form: Euler-Bernoulli cantilever roots (R. D. Blevins, Formulas for "
            "Natural Frequency and Mode Shape, 1979, table 8-1)",
            ("f1 (Hz)", "f2 (Hz)", "f3 (Hz)", "f4 (Hz)"), _cb_beam_reference(), 1e-3,
            _cb_beam_closed_form, "Hz"),
        ValidationCase(
            "reduction.cb_all_interior_modes", "reduction",
            "Craig-Bampton keeping every interior mode reproduces every eigenvalue of the FE "
            "model: max |lambda_SE - lambda_FE| / max lambda_FE",
            "exact: a complete basis (R. R. Craig, M. C. C. Bampton, AIAA J. 6 (1968) "
            "1313-1319); tolerance: round-off of a dense eigensolve", ("max relative eigenvalue "
            "error",), (0.0,), 1e-10,
            _cb_all_interior_modes, "", "absolute"),
        ValidationCase(
            "control.ppf_eq15", "control",
            "PPF tuned to a 13.26 Hz mode (filter damping 0.3): added damping ratio for "
            "G = 0.001, 0.002, 0.005",
            "closed form: the seed paper's eq. 15, added zeta = G / (4 zeta_f) "
            "(first order in G)", ("G = 0.001", "G = 0.002", "G = 0.005"),
            tuple(G / (4 * 0.3) for G in (0.001, 0.002, 0.005)), 0.02, _ppf_eq15),
        ValidationCase(
            "control.ppf_stability_limit", "control",
            "PPF on a single collocated mode: critical normalised gain for filter/mode "
            "frequency ratios 1.0, 0.7, 1.5",
            "closed form: PPF is stable for G < 1 (static stiffness K - G > 0; J. L. Fanson, "
            "T. K. Caughey, AIAA J. 28 (1990) 717-724)",
            ("wf/w = 1.0", "wf/w = 0.7", "wf/w = 1.5"), (1.0, 1.0, 1.0), 1e-4,
            _ppf_unit_gain),
        ValidationCase(
            "control.srf_routh_bound", "control",
            "SRF on an undamped single mode: critical gain found from the closed-loop poles "
            "for filter/mode ratios 1.2, 1.5, 2.0",
            "closed form: Routh-Hurwitz bound 2 zeta_f (wf^2 - w^2) / (w^2 wf) of the SRF loop "
            "(PHYSICS.md section 4; standard SRF form of Newman 1992)",
            tuple(f"wf/w = {r:g}" for r, _ in _SRF_CASES),
            tuple(_srf_routh(_F1, r * _F1, zf) for r, zf in _SRF_CASES), 1e-2, _srf_bound),
        ValidationCase(
            "control.velocity_feedback", "control",
            "direct velocity feedback, normalised gain 1e-3 s, on an undamped 13.26 Hz mode: "
            "closed-loop damping ratio",
            "closed form: xi'' + G w^2 xi' + w^2 xi = 0 gives zeta = G w / 2",
            ("zeta",), (1e-3 * w1 / 2,), 1e-9, _velocity_feedback),
    )


def run_validation(cases: Iterable[ValidationCase] | None = None, *,
                   data_dir: str | Path | None = None) -> pd.DataFrame:
    """Run validation cases and tabulate every compared quantity.

    A case that cannot run (its measurement file is absent, an optional dependency is
    missing) is kept in the table with ``status`` ``"skipped: <why>"``; a case that
    raises is ``"error: <message>"`` and never passes.

    Parameters
    ----------
    cases : iterable of ValidationCase, optional
        Default: :func:`validation_cases`.
    data_dir : path, optional
        The external measurement corpus (default :func:`shared_data_dir`).

    Returns
    -------
    pandas.DataFrame
        One row per compared quantity, columns ``case, area, title, quantity, value,
        reference, unit, error, error_pct, tolerance, source, passed, status, seconds``.
        ``passed`` is True/False, or ``pd.NA`` for a case that did not run; ``status``
        is ``"pass"``, ``"FAIL"``, ``"skipped: ..."`` or ``"error: ..."``; ``seconds`` is
        the run time of the whole case.
    """
    from ..errors import MissingDependencyError

    rows = []
    for case in validation_cases() if cases is None else cases:
        t0 = time.perf_counter()
        try:
            checks = case.checks(data_dir)
            failure = None
        except (FileNotFoundError, MissingDependencyError) as err:
            checks, failure = None, f"skipped: {err}"
        except Exception as err:  # noqa: BLE001 - a broken case is a result of the table
            checks, failure = None, f"error: {type(err).__name__}: {err}"
        seconds = time.perf_counter() - t0
        base = {"case": case.name, "area": case.area, "title": case.title,
                "source": case.source, "seconds": seconds}
        if checks is None:
            for lab, ref in zip(case.labels, case.reference):
                rows.append(base | {"quantity": lab, "value": np.nan, "reference": ref,
                                    "unit": case.unit, "error": np.nan, "error_pct": np.nan,
                                    "tolerance": _tolerance_text(case), "passed": pd.NA,
                                    "status": failure})
            continue
        for lab, c in zip(case.labels, checks):
            rows.append(base | {"quantity": lab, "value": c.value, "reference": c.reference,
                                "unit": c.unit, "error": c.error,
                                "error_pct": 100.0 * c.relative_error,
                                "tolerance": c.describe_tolerance(), "passed": c.passed,
                                "status": "pass" if c.passed else "FAIL"})
    columns = ["case", "area", "title", "quantity", "value", "reference", "unit", "error",
               "error_pct", "tolerance", "source", "passed", "status", "seconds"]
    return pd.DataFrame(rows, columns=columns)


def _tolerance_text(case: ValidationCase) -> str:
    ref = case.reference[0] if case.kind != "relative" or case.reference[0] else 1.0
    return Check("tolerance", ref, ref, case.tolerance, case.unit, case.kind).describe_tolerance()
