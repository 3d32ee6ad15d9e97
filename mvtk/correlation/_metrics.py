"""Correlation metrics between test and analysis shapes and FRFs.

Shapes are ``("mode", "dof")`` DataArrays (conventions); two shape sets are compared on
identical ``dof`` labels (the second set is reordered to the first; missing labels are an
error). Plain arrays are accepted in the same ``(n_modes, n_dof)`` layout.

References
----------
- MAC: Allemang & Brown, Proc. 1st IMAC, 1982; Allemang, Sound & Vibration 37(8), 2003.
- COMAC: Lieven & Ewins, Proc. 6th IMAC, 1988. Enhanced COMAC: Hunt, Proc. 10th IMAC,
  1992.
- MSF: Allemang (2003), the modal scale factor.
- FRAC: Heylen, Lammens & Sas, *Modal Analysis Theory and Testing*, KU Leuven, 1997;
  CSAC / CSF: Dascotte & Strobbe, Proc. 17th IMAC, 1999; Pascual, Golinval & Razeto,
  Proc. 15th IMAC, 1997.
- TAMs: Guyan, AIAA J 3(2), 1965; SEREP: O'Callahan, Avitabile & Riemer, Proc. 7th
  IMAC, 1989.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import xarray as xr

from .._mac import mac_columns
from ..errors import DimensionError, ParameterError

__all__ = [
    "mac",
    "automac",
    "comac",
    "ecomac",
    "msf",
    "guyan_tam",
    "serep_tam",
    "cross_orthogonality",
    "frac",
    "csac",
    "csf",
    "synthesize_frf",
]


def _as_shapes(x: Any, name: str) -> xr.DataArray:
    if isinstance(x, xr.DataArray):
        if x.dims != ("mode", "dof"):
            if set(x.dims) == {"mode", "dof"}:
                return x.transpose("mode", "dof")
            raise DimensionError(f"{name}: expected dims ('mode', 'dof'), got {x.dims}")
        return x
    a = np.asarray(x)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2:
        raise DimensionError(f"{name}: expected an array (n_modes, n_dof), got shape {a.shape}")
    return xr.DataArray(a, dims=("mode", "dof"),
                        coords={"mode": np.arange(1, a.shape[0] + 1),
                                "dof": [str(i) for i in range(a.shape[1])]})


def _aligned(a: Any, b: Any) -> tuple[xr.DataArray, xr.DataArray]:
    A = _as_shapes(a, "first shape set")
    B = _as_shapes(b, "second shape set")
    la, lb = [str(v) for v in A["dof"].values], [str(v) for v in B["dof"].values]
    if la != lb:
        missing = [x for x in la if x not in set(lb)]
        if missing or len(la) != len(lb):
            extra = [x for x in lb if x not in set(la)]
            raise DimensionError(
                f"shape sets have different DOFs: {len(missing)} of the first set missing "
                f"in the second ({missing[:6]}{' ...' if len(missing) > 6 else ''}), "
                f"{len(extra)} extra ({extra[:6]}{' ...' if len(extra) > 6 else ''}); map "
                "the FE shapes to the test DOFs first (map_sensors(...).project)"
            )
        B = B.sel(dof=la)
    return A, B


def _mode_coords(A: xr.DataArray, suffix: str) -> dict:
    out = {f"mode_{suffix}": A["mode"].values}
    if "fn_hz" in A.coords:
        out[f"fn_hz_{suffix}"] = (f"mode_{suffix}", A["fn_hz"].values)
    return out


def mac(a: Any, b: Any | None = None) -> xr.DataArray:
    """Modal assurance criterion matrix.

    ``MAC_ij = |a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j))`` for real or complex shapes.

    Parameters
    ----------
    a, b : DataArray ("mode", "dof") or array (n_modes, n_dof)
        Shapes on the same DOFs (``b`` default ``a``: the AutoMAC).

    Returns
    -------
    xarray.DataArray
        dims ``("mode_a", "mode_b")``, values in [0, 1] (0 for an all-zero shape), with
        the ``fn_hz`` of each set as coordinates when present.

    Examples
    --------
    >>> a = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]])   # orthogonal shapes
    >>> np.round(mac(a, -2 * a).values, 3)      # scale and sign do not matter
    array([[1., 0.],
           [0., 1.]])
    """
    A, B = _aligned(a, a if b is None else b)
    val = mac_columns(A.values.T, B.values.T)
    return xr.DataArray(val, dims=("mode_a", "mode_b"),
                        coords={**_mode_coords(A, "a"), **_mode_coords(B, "b")},
                        attrs={"metric": "MAC"})


def automac(a: Any) -> xr.DataArray:
    """AutoMAC of one shape set (``mac(a, a)``); off-diagonal terms near 1 mean the
    sensors cannot tell those modes apart (spatial aliasing).

    Examples
    --------
    Two shapes of three DOFs; the off-diagonal term is
    ``(a1 . a2)**2 / (|a1|**2 |a2|**2)`` = 0.2492**2 / (0.7071 x 1.1961):

    >>> a = np.array([[0.114, 0.394, 0.734], [-0.542, -0.593, 0.742]])
    >>> np.round(automac(a).values, 3)
    array([[1.   , 0.073],
           [0.073, 1.   ]])
    """
    return mac(a, a)


def msf(a: Any, b: Any) -> xr.DataArray:
    """Modal scale factor of paired shapes: the factor that scales ``b_i`` onto ``a_i``.

    ``MSF_i = (b_i^H a_i) / (b_i^H b_i)`` (least squares). ``a`` and ``b`` hold the
    same number of modes, paired by position.

    Examples
    --------
    ``b = -2 a`` is scaled back onto ``a`` by -1/2:

    >>> a = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]])
    >>> msf(a, -2 * a).values
    array([-0.5, -0.5])
    """
    A, B = _aligned(a, b)
    if A.sizes["mode"] != B.sizes["mode"]:
        raise DimensionError(f"MSF pairs modes by position: got {A.sizes['mode']} and "
                             f"{B.sizes['mode']} modes")
    x, y = A.values, B.values
    den = np.real(np.einsum("ij,ij->i", np.conj(y), y))
    num = np.einsum("ij,ij->i", np.conj(y), x)
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
    if not np.iscomplexobj(val):
        val = val.real
    return xr.DataArray(val, dims=("pair",), coords={"pair": np.arange(1, len(val) + 1)},
                        attrs={"metric": "MSF"})


def _paired_unit(A: xr.DataArray, B: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """Unit-norm shapes with ``b`` rotated/sign-aligned onto ``a`` (phase of MSF)."""
    x, y = A.values, B.values
    if A.sizes["mode"] != B.sizes["mode"]:
        raise DimensionError(f"pair the modes first: got {A.sizes['mode']} and "
                             f"{B.sizes['mode']} modes")
    nx = np.linalg.norm(x, axis=1, keepdims=True)
    ny = np.linalg.norm(y, axis=1, keepdims=True)
    if np.any(nx == 0) or np.any(ny == 0):
        raise ParameterError("a shape is identically zero; COMAC needs non-zero shapes")
    x, y = x / nx, y / ny
    dot = np.einsum("ij,ij->i", np.conj(y), x)
    phase = np.where(np.abs(dot) > 0, dot / np.where(np.abs(dot) > 0, np.abs(dot), 1.0), 1.0)
    y = y * phase[:, None]
    if not (np.iscomplexobj(x) or np.iscomplexobj(y)):
        y = y.real
    return x, y


def comac(a: Any, b: Any, *, variant: str = "signed") -> xr.DataArray:
    """Coordinate modal assurance criterion per DOF over paired modes.

    Parameters
    ----------
    a, b : DataArray ("mode", "dof")
        Paired shapes: mode ``i`` of ``a`` is paired with mode ``i`` of ``b`` (select
        them with a pairing table first). Each shape is scaled to unit norm and ``b`` is
        phase/sign-aligned onto ``a`` (by its MSF) before the sums.
    variant : {"signed", "lieven_ewins"}
        ``"signed"`` (default): ``|sum_l a_jl b_jl^*|^2 / (sum_l |a_jl|^2 sum_l |b_jl|^2)``,
        which also drops when the agreement at a DOF changes sign between modes.
        ``"lieven_ewins"``: the original 1988 form with ``(sum_l |a_jl b_jl|)^2`` in the
        numerator, blind to signs.

    Notes
    -----
    COMAC is a correlation across modes at each DOF: a constant gain or sign error of
    one sensor (the same factor in every mode) leaves it at 1. A wrongly oriented sensor
    (reading another component) or a misplaced one lowers it; a calibration or polarity
    error is found by :func:`ecomac`.

    Returns
    -------
    xarray.DataArray
        dims ``("dof",)``, values in [0, 1]; 1 = the DOF agrees in every mode.

    Examples
    --------
    Shapes that agree up to scale give COMAC 1 at every DOF:

    >>> a = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]])
    >>> np.round(comac(a, -2 * a).values, 6)
    array([1., 1., 1.])
    """
    if variant not in ("signed", "lieven_ewins"):
        raise ParameterError(f"variant must be 'signed' or 'lieven_ewins', got {variant!r}")
    A, B = _aligned(a, b)
    x, y = _paired_unit(A, B)
    if variant == "signed":
        num = np.abs(np.sum(x * np.conj(y), axis=0)) ** 2
    else:
        num = np.sum(np.abs(x * y), axis=0) ** 2
    den = np.sum(np.abs(x) ** 2, axis=0) * np.sum(np.abs(y) ** 2, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return _dof_result(A, np.clip(val, 0, 1), "COMAC")


def ecomac(a: Any, b: Any) -> xr.DataArray:
    """Enhanced COMAC (Hunt 1992): ``sum_l |a_jl - b_jl| / (2 L)`` per DOF.

    Shapes are unit-normalised and ``b`` is sign/phase-aligned onto ``a``. 0 = perfect
    agreement; a DOF with a large value is in error (unlike COMAC it is not diluted by
    the amplitude of the DOF).

    Examples
    --------
    Shapes that agree up to scale give eCOMAC 0; an error at DOF 3 shows there:

    >>> a = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]])
    >>> np.round(ecomac(a, -2 * a).values, 6)
    array([0., 0., 0.])
    >>> b = a.copy()
    >>> b[:, 2] *= 1.5
    >>> int(np.argmax(ecomac(a, b).values))
    2
    """
    A, B = _aligned(a, b)
    x, y = _paired_unit(A, B)
    val = np.sum(np.abs(x - y), axis=0) / (2 * x.shape[0])
    return _dof_result(A, val, "eCOMAC")


def _dof_result(A: xr.DataArray, val: np.ndarray, metric: str) -> xr.DataArray:
    coords = {"dof": A["dof"].values}
    for c in ("node", "direction"):
        if c in A.coords:
            coords[c] = ("dof", A[c].values)
    return xr.DataArray(val, dims=("dof",), coords=coords, attrs={"metric": metric})


# ---------------------------------------------------------------------- TAMs
def _dense(M) -> np.ndarray:
    return M.toarray() if sp.issparse(M) else np.asarray(M, dtype=float)


def guyan_tam(model, observation) -> np.ndarray:
    """Guyan (static) test-analysis mass matrix on the sensor DOFs.

    The reduction ``u = T y`` is the static response with the sensor readings ``C u = y``
    prescribed and no other load: ``T = K^-1 C' (C K^-1 C')^-1``. When ``C`` selects
    FE DOFs this is Guyan's condensation; it also covers interpolated and skewed sensors.

    Parameters
    ----------
    model : FEModel
        With a non-singular K (a supported structure).
    observation : DofMapping or matrix (n_sensors, n_dof)

    Returns
    -------
    ndarray (n_sensors, n_sensors)
        ``T' M T`` (kg).

    Examples
    --------
    Guyan TAM of a steel cantilever at three +z sensors; the FE shapes at the sensors are
    then nearly orthogonal in it (exact orthogonality needs SEREP):

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> res = correlate(geo, beam, modal_analysis(beam, 2))
    >>> tam = guyan_tam(beam, res.mapping)              # kg
    >>> tam.shape, np.round(cross_orthogonality(res.fe, None, tam).values, 2)
    ((3, 3), array([[ 1.  , -0.01],
           [-0.01,  1.  ]]))
    """
    from ..fe._solvers import factorize

    C = _observation(observation, model.n_dof)
    try:
        lu = factorize(model.K)
    except ParameterError as err:
        raise ParameterError(f"the Guyan TAM needs a non-singular K (a supported "
                             f"structure): {err}") from err
    Z = lu.solve(_dense(C.T))  # K^-1 C'
    if not np.all(np.isfinite(Z)):
        raise ParameterError("the Guyan TAM needs a non-singular K (a supported structure)")
    S = C @ Z
    T = np.linalg.solve(S.T, Z.T).T  # Z S^-1 (S symmetric)
    return T.T @ (model.M @ T)


def serep_tam(modal_shapes: np.ndarray, observation, mass=None) -> np.ndarray:
    """SEREP test-analysis mass matrix.

    ``T = Phi (C Phi)^+`` so that ``T' M T = (C Phi)^+' (C Phi)^+`` for mass-normalised
    ``Phi`` (``mass`` given: computed as ``T' M T``).

    Parameters
    ----------
    modal_shapes : ndarray (n_dof, n_modes)
        FE shapes over all free DOFs (mass-normalised unless ``mass`` is given).
    observation : DofMapping or matrix (n_sensors, n_dof)
    mass : sparse or ndarray, optional
        FE mass matrix.

    Examples
    --------
    SEREP TAM of the two lowest modes of a steel cantilever at three +z sensors: the FE
    shapes are exactly orthogonal in it:

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> fe = modal_analysis(beam, 2)
    >>> res = correlate(geo, beam, fe)
    >>> tam = serep_tam(fe.shapes, res.mapping)
    >>> np.round(cross_orthogonality(res.fe, None, tam).values, 6) + 0.0
    array([[1., 0.],
           [0., 1.]])
    """
    Phi = np.asarray(modal_shapes, dtype=float)
    C = _observation(observation, Phi.shape[0])
    P = np.linalg.pinv(np.asarray(C @ Phi))
    if mass is None:
        return P.T @ P
    T = Phi @ P
    return T.T @ (mass @ T)


def _observation(observation, n_dof: int):
    C = getattr(observation, "matrix", observation)
    C = sp.csr_matrix(C) if sp.issparse(C) else sp.csr_matrix(np.asarray(C, dtype=float))
    if C.shape[1] != n_dof:
        raise DimensionError(f"observation matrix has {C.shape[1]} columns, the model "
                             f"{n_dof} free DOFs")
    return C


def cross_orthogonality(a: Any, b: Any | None, tam: np.ndarray) -> xr.DataArray:
    """Cross-orthogonality ``a' M_TAM b`` with each shape scaled to unit TAM mass.

    Parameters
    ----------
    a : DataArray ("mode", "dof")
        Test shapes on the sensor DOFs (the TAM's rows and columns, same order).
    b : DataArray ("mode", "dof") or None
        FE shapes at the same DOFs; None gives the pseudo-orthogonality of ``a``.
    tam : ndarray (n_sensors, n_sensors)

    Returns
    -------
    xarray.DataArray ("mode_a", "mode_b")
        Near +-1 on paired modes and near 0 elsewhere when test and model agree
        (common acceptance: diagonal terms above 0.9 and off-diagonal terms below 0.1,
        in absolute value).

    Examples
    --------
    With an identity TAM the cross-orthogonality of unit-normalised orthogonal shapes is
    the identity:

    >>> a = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]])
    >>> np.round(np.abs(cross_orthogonality(a, -2 * a, np.eye(3)).values), 6)
    array([[1., 0.],
           [0., 1.]])
    """
    A, B = _aligned(a, a if b is None else b)
    Mt = np.asarray(tam)
    if Mt.shape != (A.sizes["dof"],) * 2:
        raise DimensionError(f"TAM must be {A.sizes['dof']} x {A.sizes['dof']}, got {Mt.shape}")

    def unit(X):
        m = np.real(np.einsum("ij,jk,ik->i", np.conj(X), Mt, X))
        if np.any(m <= 0):
            raise ParameterError("a shape has zero or negative TAM mass; the TAM is not "
                                 "positive definite on these shapes")
        return X / np.sqrt(m)[:, None]

    x, y = unit(A.values), unit(B.values)
    val = np.conj(x) @ Mt @ y.T
    if not np.iscomplexobj(val):
        val = val.real
    return xr.DataArray(val, dims=("mode_a", "mode_b"),
                        coords={**_mode_coords(A, "a"), **_mode_coords(B, "b")},
                        attrs={"metric": "cross-orthogonality"})


# ---------------------------------------------------------------------- FRFs
def _frf_pair(x: xr.DataArray, a: xr.DataArray) -> tuple[xr.DataArray, xr.DataArray]:
    for name, h in (("measured", x), ("analysis", a)):
        if not isinstance(h, xr.DataArray) or h.dims != ("response", "reference", "frequency"):
            raise DimensionError(
                f"{name} FRF: expected a DataArray with dims ('response', 'reference', "
                f"'frequency'), got {getattr(h, 'dims', type(h).__name__)}"
            )
    if x.shape != a.shape:
        raise DimensionError(f"FRF matrices differ in shape: {x.shape} and {a.shape}")
    fx, fa = x["frequency"].values, a["frequency"].values
    if not np.allclose(fx, fa, rtol=1e-9, atol=0):
        raise DimensionError("FRF matrices are on different frequency lines; synthesise the "
                             "analysis FRFs on the measured lines")
    for dim in ("response", "reference"):
        if not np.array_equal(x[dim].values, a[dim].values):
            raise DimensionError(f"FRF matrices have different {dim} labels")
    return x, a


def frac(measured: xr.DataArray, analysis: xr.DataArray) -> xr.DataArray:
    """Frequency response assurance criterion per (response, reference) pair.

    ``FRAC = |sum_f H_x H_a^*|^2 / (sum_f |H_x|^2 sum_f |H_a|^2)`` over the frequency
    lines (Heylen et al. 1997).

    Returns
    -------
    xarray.DataArray ("response", "reference")

    Examples
    --------
    An FRF compared with itself gives FRAC 1:

    >>> import xarray as xr
    >>> shapes = xr.DataArray([[1.0, 0.5]], dims=("mode", "dof"),
    ...                       coords={"dof": ["1+z", "2+z"], "fn_hz": ("mode", [10.0])})
    >>> h = synthesize_frf(shapes, np.arange(1.0, 20.0), references=["1+z"], zeta=0.01)
    >>> np.round(frac(h, h).values, 6)
    array([[1.],
           [1.]])
    """
    x, a = _frf_pair(measured, analysis)
    hx, ha = x.values, a.values
    num = np.abs(np.sum(hx * np.conj(ha), axis=-1)) ** 2
    den = np.sum(np.abs(hx) ** 2, axis=-1) * np.sum(np.abs(ha) ** 2, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return x.isel(frequency=0, drop=True).copy(data=val).assign_attrs(metric="FRAC")


def csac(measured: xr.DataArray, analysis: xr.DataArray) -> xr.DataArray:
    """Cross signature assurance criterion per (reference, frequency).

    ``CSAC(f) = |H_x(f)^H H_a(f)|^2 / ((H_x^H H_x)(H_a^H H_a))`` over the response DOFs:
    the MAC of the operating deflection shapes at each frequency line.

    Examples
    --------
    CSAC is blind to scale: twice the FRF still gives 1 at every line:

    >>> import xarray as xr
    >>> shapes = xr.DataArray([[1.0, 0.5]], dims=("mode", "dof"),
    ...                       coords={"dof": ["1+z", "2+z"], "fn_hz": ("mode", [10.0])})
    >>> h = synthesize_frf(shapes, np.arange(1.0, 20.0), references=["1+z"], zeta=0.01)
    >>> float(np.round(csac(h, 2 * h).values.min(), 6))
    1.0
    """
    x, a = _frf_pair(measured, analysis)
    hx, ha = x.values, a.values
    num = np.abs(np.sum(np.conj(hx) * ha, axis=0)) ** 2
    den = np.sum(np.abs(hx) ** 2, axis=0) * np.sum(np.abs(ha) ** 2, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return x.isel(response=0, drop=True).copy(data=val).assign_attrs(metric="CSAC")


def csf(measured: xr.DataArray, analysis: xr.DataArray) -> xr.DataArray:
    """Cross signature scale factor per (reference, frequency).

    ``CSF(f) = 2 |H_x^H H_a| / (H_x^H H_x + H_a^H H_a)``: 1 only when the deflection
    shapes also agree in amplitude (CSAC is blind to scale).

    Examples
    --------
    CSF sees the scale: twice the FRF gives ``2 * 2 / (1 + 4)`` = 0.8 at every line:

    >>> import xarray as xr
    >>> shapes = xr.DataArray([[1.0, 0.5]], dims=("mode", "dof"),
    ...                       coords={"dof": ["1+z", "2+z"], "fn_hz": ("mode", [10.0])})
    >>> h = synthesize_frf(shapes, np.arange(1.0, 20.0), references=["1+z"], zeta=0.01)
    >>> float(np.round(csf(h, 2 * h).values.max(), 6))
    0.8
    """
    x, a = _frf_pair(measured, analysis)
    hx, ha = x.values, a.values
    num = 2 * np.abs(np.sum(np.conj(hx) * ha, axis=0))
    den = np.sum(np.abs(hx) ** 2, axis=0) + np.sum(np.abs(ha) ** 2, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return x.isel(response=0, drop=True).copy(data=val).assign_attrs(metric="CSF")


def synthesize_frf(
    shapes: xr.DataArray,
    frequency: Any,
    *,
    references: Any,
    zeta: Any = None,
    frf_type: str = "receptance",
) -> xr.DataArray:
    """Modal superposition FRF matrix from mass-normalised shapes.

    ``H_jk(w) = sum_r phi_jr phi_kr / (w_r^2 - w^2 + 2 i zeta_r w_r w)`` (receptance,
    m/N), times ``(i w)`` for mobility or ``-w^2`` for accelerance.

    Parameters
    ----------
    shapes : DataArray ("mode", "dof")
        Mass-normalised shapes at the response DOFs (e.g. mapped FE shapes), with the
        ``fn_hz`` coordinate; the reference DOFs must be among the ``dof`` labels.
    frequency : array of float
        Frequency lines (Hz).
    references : sequence of str
        DOF labels of the excitation points.
    zeta : float or array (n_modes,), optional
        Modal damping ratios (default: the ``zeta`` coordinate, else 0.01 is *not*
        assumed: an error is raised).
    frf_type : {"receptance", "mobility", "accelerance"}

    Returns
    -------
    xarray.DataArray ("response", "reference", "frequency")
        Complex, with the coordinates of the conventions; ``attrs["estimator"] =
        "modal synthesis"``.

    Examples
    --------
    A single mass-normalised mode at 10 Hz, shape 1 at one DOF: at 0 Hz the receptance is
    ``phi**2 / w_n**2`` (m/N):

    >>> import xarray as xr
    >>> shapes = xr.DataArray([[1.0]], dims=("mode", "dof"),
    ...                       coords={"dof": ["1+z"], "fn_hz": ("mode", [10.0])})
    >>> h = synthesize_frf(shapes, [0.0, 10.0], references=["1+z"], zeta=0.01)
    >>> h.dims, round(float(h.real[0, 0, 0]) * (2 * np.pi * 10.0) ** 2, 6)
    (('response', 'reference', 'frequency'), 1.0)
    """
    S = _as_shapes(shapes, "shapes")
    if "fn_hz" not in S.coords:
        raise ParameterError("shapes need an 'fn_hz' coordinate on 'mode' to synthesise FRFs")
    fn = S["fn_hz"].values.astype(float)
    if zeta is None:
        z = S["zeta"].values.astype(float) if "zeta" in S.coords else np.full(fn.size, np.nan)
        if np.any(~np.isfinite(z)):
            raise ParameterError("modal damping unknown (zeta is NaN): pass zeta=...")
    else:
        z = np.broadcast_to(np.asarray(zeta, dtype=float), fn.shape)
    if frf_type not in ("receptance", "mobility", "accelerance"):
        raise ParameterError(f"frf_type must be receptance, mobility or accelerance, got "
                             f"{frf_type!r}")
    labels = [str(v) for v in S["dof"].values]
    refs = [str(r) for r in references]
    missing = [r for r in refs if r not in labels]
    if missing:
        raise ParameterError(f"reference DOFs {missing} are not among the shape DOFs")
    f = np.asarray(frequency, dtype=float).ravel()
    w = 2 * np.pi * f
    wr = 2 * np.pi * fn
    phi = S.values.T  # (n_dof, n_modes)
    phik = S.sel(dof=refs).values.T  # (n_ref, n_modes)
    den = wr[None, :] ** 2 - w[:, None] ** 2 + 2j * z[None, :] * wr[None, :] * w[:, None]
    H = np.einsum("jr,kr,fr->jkf", phi, phik, 1.0 / den)
    units = "m/N"
    if frf_type == "mobility":
        H = H * (1j * w)[None, None, :]
        units = "m/s/N"
    elif frf_type == "accelerance":
        H = H * (-(w**2))[None, None, :]
        units = "m/s^2/N"
    coords = {"response": labels, "reference": refs, "frequency": f}
    if "node" in S.coords:
        coords["node"] = ("response", S["node"].values)
        coords["direction"] = ("response", S["direction"].values)
        ref = S.sel(dof=refs)
        coords["reference_node"] = ("reference", ref["node"].values)
        coords["reference_direction"] = ("reference", ref["direction"].values)
    return xr.DataArray(H, dims=("response", "reference", "frequency"), coords=coords,
                        attrs={"frf_type": frf_type, "estimator": "modal synthesis",
                               "units": units})
