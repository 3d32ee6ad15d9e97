"""First-order uncertainty of SSI-cov poles and shapes from the data (data blocks).

The covariance of the block Toeplitz matrix of output correlations is estimated from
``n_b`` contiguous data blocks and propagated to first order through the SVD, the
least-squares solution of the shift equation and the eigenvalue problem (Reynders,
Pintelon & De Roeck 2008). As in Döhler & Mevel (2013), the covariance is kept in its
square-root form ``Sigma_H = T T^T`` (``T`` has one column per data block), so every
sensitivity is applied to the ``n_b`` columns of ``T`` (directional derivatives), never
to the ``(i n_l i n_r)^2`` covariance itself.

References
----------
Reynders, Pintelon & De Roeck, "Uncertainty bounds on modal parameters obtained from
stochastic subspace identification", Mechanical Systems and Signal Processing 22(4),
948-969, 2008.
Döhler & Mevel, "Efficient multi-order uncertainty computation for stochastic subspace
identification", Mechanical Systems and Signal Processing 40(2), 464-484, 2013.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.linalg

from ._refine import pole_std

__all__ = ["toeplitz_blocks", "block_perturbations", "BlockPerturbations", "default_blocks",
           "ssi_pole_uncertainty", "truncation_margin", "MIN_BLOCKS", "GAP_MARGIN"]

#: fewest data blocks from which the covariance of the correlations is estimated; with
#: fewer the standard deviations are NaN (a sample covariance of fewer blocks is itself
#: too uncertain to give an error bar)
MIN_BLOCKS = 10
#: smallest singular-value gap at the truncation, in standard deviations of the two
#: singular values, for which the first-order propagation holds at a model order
GAP_MARGIN = 2.0
#: default number of data blocks (Döhler & Mevel 2013 use 50..200)
DEFAULT_BLOCKS = 50


def default_blocks(n_samples: int, n_lags: int) -> int:
    """Data blocks for the covariance: :data:`DEFAULT_BLOCKS`, fewer when a block
    would be shorter than 10 x the ``2 n_lags`` correlation lags it estimates (blocks
    much longer than the lags keep the block estimates nearly independent and their
    edge effects small); 0 when fewer than :data:`MIN_BLOCKS` blocks fit."""
    nb = min(DEFAULT_BLOCKS, (n_samples - 2 * n_lags) // (20 * n_lags))
    return int(nb) if nb >= MIN_BLOCKS else 0


class BlockPerturbations:
    """The square root ``T`` of the Toeplitz covariance, projected on the leading
    singular vectors: ``Q_b = T_b V_K`` (rows x K) and ``W_b = U_K^T T_b`` (K x cols)
    for every data block ``b``, ``K`` = the highest model order + 1.

    Everything the first-order propagation up to order ``K - 1`` needs of ``T_b``
    (``dH v_j``, ``u_j^T dH``) is in them, in ``n_b (rows + cols) K`` numbers instead
    of ``n_b rows cols`` (a 1245-row Toeplitz matrix and 50 blocks: 41 MB instead of
    620 MB).
    """

    def __init__(self, Q, W):
        self.Q, self.W = Q, W
        self._proj = None

    def projections(self, U, Vt):
        """``(U^T Q_b, W_b V, (I - U U^T) Q_b or None)``, computed once for all orders:
        ``u_k^T dH v_j`` for ``j < K`` and every ``k``, ``u_j^T dH v_k`` likewise, and
        the part of ``dH v_j`` outside the range of ``U`` (more rows than columns)."""
        if self._proj is None:
            uq = np.swapaxes(self.Q, 1, 2) @ U                 # (nb, K, r)
            uq = np.swapaxes(uq, 1, 2)                         # (nb, r, K)
            wv = self.W @ Vt.T                                 # (nb, K, r)
            out = self.Q - U @ uq if U.shape[0] > U.shape[1] else None
            self._proj = (uq, wv, out)
        return self._proj

    @classmethod
    def from_blocks(cls, T, U, Vt, k: int):
        """From the full ``T`` of :func:`toeplitz_blocks` (small problems, tests)."""
        return cls(T @ Vt[:k].T, U[:, :k].T @ T)


def _block_correlations(y, yr, i, nbl, nfft, s):
    """Correlations ``R_k``, ``k = 0..2i-1``, of the block of ``nbl`` time steps
    starting at sample ``s`` (lagged samples run into the next block), ``(2i, nl, nr)``."""
    nlag = 2 * i
    Y = scipy.fft.rfft(y[:, s:s + nbl + nlag], nfft)
    Yr = scipy.fft.rfft(yr[:, s:s + nbl], nfft)
    r = scipy.fft.irfft(Y[:, None, :] * np.conj(Yr[None, :, :]), nfft)[..., :nlag]
    return np.moveaxis(r, -1, 0) / nbl


def _blocks(y, yr, i, n_blocks):
    """The correlations of each of ``n_blocks`` contiguous data blocks."""
    nbl = (y.shape[1] - 2 * i) // n_blocks
    nfft = scipy.fft.next_fast_len(nbl + 2 * i)
    for b in range(n_blocks):
        yield _block_correlations(y, yr, i, nbl, nfft, b * nbl)


def _toeplitz(R, i):
    """Block Toeplitz matrix ``[R_{i+a-c}]`` (``a, c = 0..i-1``) of correlations."""
    nl, nr = R.shape[1:]
    a = np.arange(i)
    k = i + a[:, None] - a[None, :]
    return R[k].transpose(0, 2, 1, 3).reshape(i * nl, i * nr)


def toeplitz_blocks(y, yr, i: int, n_blocks: int) -> np.ndarray:
    """Square root ``T`` of the covariance of the block Toeplitz matrix, from data blocks.

    The record is cut into ``n_blocks`` contiguous blocks of ``N_b`` samples; block
    ``b`` gives the correlations ``R_k^b = sum_t y_{t+k} y_ref_t^T / N_b`` over its
    time steps ``t`` (the lagged samples may run into the next block, so the blocks'
    mean is the correlation of the whole span) and the Toeplitz matrix ``H_b =
    [R^b_{i+a-c}]`` of :func:`mvtk.modal.ssi_cov`. Returns ``(H_b - mean_b H_b) /
    sqrt(n_b (n_b - 1))`` with shape ``(n_blocks, i n_l, i n_r)``: ``Sigma_H = sum_b
    vec(T_b) vec(T_b)^T`` estimates the covariance of the Toeplitz matrix of the whole
    record (Döhler & Mevel 2013, sec. 3.2 and 5.1).
    """
    H = np.stack([_toeplitz(R, i) for R in _blocks(y, yr, i, n_blocks)])
    H -= H.mean(axis=0)
    return H / np.sqrt(n_blocks * (n_blocks - 1))


def block_perturbations(y, yr, i: int, n_blocks: int, U, Vt, k: int) -> BlockPerturbations:
    """:class:`BlockPerturbations` of :func:`toeplitz_blocks`, one block at a time
    (the projection is linear, so the blocks' mean is removed after it).

    The Toeplitz matrices are never formed: ``H_b V_K`` is the convolution over lags
    ``sum_c R_{i+a-c} V_c`` and ``U_K^T H_b`` the correlation ``sum_a U_a^T R_{i+a-c}``
    (``V_c``, ``U_a`` the block rows of the singular vectors), both by FFT over the
    ``2i`` lags: ``O(nl nr K i log i)`` per block instead of ``O(nl nr K i^2)``.
    """
    nl, nr = y.shape[0], yr.shape[0]
    k = min(k, U.shape[1])
    g = Vt[:k].T.reshape(i, nr, k)                            # V_c, c = 0..i-1
    u = U[:, :k].reshape(i, nl, k)                            # U_a, a = 0..i-1
    L = scipy.fft.next_fast_len(3 * i)
    gf = scipy.fft.rfft(g, L, axis=0)
    uf = np.conj(scipy.fft.rfft(u, L, axis=0))
    Q, W = [], []
    for R in _blocks(y, yr, i, n_blocks):
        Rf = scipy.fft.rfft(R, L, axis=0)                     # (L/2+1, nl, nr)
        conv = scipy.fft.irfft(np.einsum("flr,frk->flk", Rf, gf), L, axis=0)
        Q.append(conv[i:2 * i].reshape(i * nl, k))            # t = i + a
        xc = scipy.fft.irfft(np.einsum("flk,flr->fkr", uf, Rf), L, axis=0)
        W.append(np.moveaxis(xc[i:0:-1], 0, 1).reshape(k, i * nr))   # t = i - c
    Q, W = np.stack(Q), np.stack(W)
    c = 1 / np.sqrt(n_blocks * (n_blocks - 1))
    return BlockPerturbations((Q - Q.mean(axis=0)) * c, (W - W.mean(axis=0)) * c)


def truncation_margin(U, S, Vt, P: BlockPerturbations, orders) -> np.ndarray:
    """Gap ``(s_n - s_(n+1)) / (std s_n + std s_(n+1))`` of the Toeplitz matrix's
    singular values at each model order ``n``, in their first-order standard deviations
    (``d s_j = u_j^T dH v_j``, over the data blocks).

    The first-order propagation divides by ``s_j^2 - s_k^2`` across the truncation
    (:func:`_shift_derivatives`); it describes the scatter only while the perturbation
    is small against that gap. Above the system's order the truncation cuts through
    the noise singular values (gap below 1 std) and the linearised standard deviations
    exceed the scatter by factors of 2..50 (measured on a 3-DOF chain); at an order
    with a gap of several standard deviations they agree with it. Orders ``n`` with
    ``n + 1`` beyond the projected singular vectors get 0.
    """
    orders = np.atleast_1d(np.asarray(orders, dtype=int))
    top = min(P.Q.shape[2], S.size)
    uq = P.projections(U, Vt)[0]
    d = np.diagonal(uq[:, :top, :top], axis1=1, axis2=2)        # (nb, top): u_j^T dH v_j
    ds = np.sqrt(np.sum(d**2, axis=0))
    out = np.zeros(orders.size)
    for k, n in enumerate(orders):
        if 0 < n < top:
            den = ds[n - 1] + ds[n]
            out[k] = (S[n - 1] - S[n]) / den if den > 0 else np.inf
    return out


def _shift_derivatives(U, S, Vt, P: BlockPerturbations, n, n_out, Oup, res, A):
    """Directional derivatives, along each data block's ``dH``, of the least-squares
    ``A = O_up^+ O_down`` (as ``G dA``, ``G = O_up^T O_up``) and of ``C`` for the
    observability matrix ``O_n = U_n S_n^(1/2)``: ``(G dA (nb, n, n), dC (nb, n_out, n))``.

    Poles and shapes ``C psi`` are invariant to a change of basis ``O_n -> O_n M``
    (``A -> M^-1 A M``), so only the rotation of the subspace out of ``span(U_n)``
    matters: for a singular triple ``(u_j, s_j, v_j)``, ``j <= n``,
    ``du_j = sum_{k > n} (s_j u_k^T dH v_j + s_k u_j^T dH v_k) / (s_j^2 - s_k^2) u_k
    + (I - U U^T) dH v_j / s_j`` (first-order SVD perturbation, distinct singular
    values; Reynders et al. 2008, sec. 4), ``dO_j = s_j^(1/2) du_j``. With
    ``dO = U_o Z + E``, ``G dA = dO_up^T res + O_up^T (dO_down - dO_up A)`` (``res`` the
    least-squares residual) is assembled from ``n x (r - n)`` products of ``U_o``
    formed once per order, never from ``dO`` itself.
    """
    uq, wv, out = P.projections(U, Vt)
    sn, so = S[:n], S[n:]
    Uo = U[:, n:]
    a_kj = uq[:, n:, :n]                                      # u_k^T dH v_j
    a_jk = np.swapaxes(wv[:, :n, n:], 1, 2)                   # u_j^T dH v_k, as [k, j]
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = (sn[None, None, :] * a_kj + so[None, :, None] * a_jk) / (
            sn[None, None, :] ** 2 - so[None, :, None] ** 2) * np.sqrt(sn)[None, None, :]
    P1 = Uo[:-n_out].T @ res                                  # (r-n, n)
    P2 = Oup.T @ Uo[n_out:]                                   # (n, r-n)
    P3 = Oup.T @ Uo[:-n_out]
    rhs = np.swapaxes(Z, 1, 2) @ P1 + P2 @ Z - (P3 @ Z) @ A
    dC = Uo[:n_out] @ Z
    if out is not None:                                       # rows beyond the rank
        E = out[:, :, :n] / np.sqrt(sn)[None, None, :]
        Eup, Edn = E[:, :-n_out], E[:, n_out:]
        rhs += np.swapaxes(Eup, 1, 2) @ res + Oup.T @ (Edn - Eup @ A)
        dC = dC + E[:, :n_out]
    return rhs, dC


def ssi_pole_uncertainty(U, S, Vt, P: BlockPerturbations, n_out: int, order: int, fs: float,
                         poles):
    """Standard deviations of SSI-cov poles of one model order and of their shapes.

    First-order propagation (Reynders, Pintelon & De Roeck 2008) of the Toeplitz
    covariance ``Sigma_H = T T^T`` (:func:`toeplitz_blocks`), data block by data block
    (Döhler & Mevel 2013): ``dO`` from the SVD (:func:`_shift_derivatives`), ``dA``
    of the least-squares ``A = O_up^+ O_down`` including its residual term,
    ``d mu_j = chi_j^H dA phi_j / chi_j^H phi_j`` (left and right eigenvectors),
    ``d lambda = fs d mu / mu``, and the shape ``C phi_j`` normalised to its largest
    component ``r`` (``s = C phi / (C phi)_r``, the unit-maximum shape of
    :func:`mvtk.modal.identify_output_only`), ``ds = (d(C phi) - s d(C phi)_r) / (C phi)_r``
    with ``d phi_j = sum_{k != j} chi_k^H dA phi_j / ((mu_j - mu_k) chi_k^H phi_k) phi_k``.

    Parameters
    ----------
    U, S, Vt : numpy.ndarray
        SVD of the record's block Toeplitz matrix (``full_matrices=False``).
    P : BlockPerturbations
        Square root of its covariance, projected (:func:`block_perturbations`), with
        more than ``order`` singular vectors.
    n_out : int
        Output channels ``n_l`` (rows of a block row).
    order : int
        Model order ``n`` the poles come from.
    fs : float
        Sampling rate in Hz the Toeplitz matrix was built at.
    poles : array_like of complex
        Poles (rad/s) of that order whose uncertainty is wanted; each is matched to the
        nearest eigenvalue of the order's ``A``.

    Returns
    -------
    fn_std_hz, zeta_std : numpy.ndarray
        Standard deviation of the natural frequency (Hz) and of the damping ratio.
    shape_std : numpy.ndarray, shape (n_poles, n_out)
        ``sqrt(E |ds|^2)`` of each component of the unit-maximum complex shape.
    """
    poles = np.atleast_1d(np.asarray(poles, dtype=complex))
    n = int(order)
    O = U[:, :n] * np.sqrt(S[:n])[None, :]
    Oup, Odn = O[:-n_out], O[n_out:]
    G = Oup.T @ Oup
    A = np.linalg.solve(G, Oup.T @ Odn)
    res = Odn - Oup @ A
    C = O[:n_out]
    rhs, dC = _shift_derivatives(U, S, Vt, P, n, n_out, Oup, res, A)
    dA = np.linalg.solve(G[None], rhs)                        # (nb, n, n)
    mu, chi, phi = scipy.linalg.eig(A, left=True, right=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.log(mu.astype(complex)) * fs
    fstd = np.full(poles.size, np.nan)
    zstd = np.full(poles.size, np.nan)
    sstd = np.full((poles.size, n_out), np.nan)
    chiH = chi.conj().T
    norm = np.einsum("ij,ji->i", chiH, phi)                   # chi_k^H phi_k
    for m, p in enumerate(poles):
        j = int(np.nanargmin(np.abs(lam - p)))
        dmu = np.einsum("i,bij,j->b", chiH[j], dA, phi[:, j]) / norm[j]
        dlam = fs * dmu / mu[j]
        parts = np.stack([-dlam.real, dlam.imag], axis=1)     # (sigma, w_d)
        cov = parts.T @ parts
        f_s, z_s = pole_std(lam[j], cov[None])
        fstd[m], zstd[m] = f_s[0], z_s[0]
        # shape C phi_j at unit maximum
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(np.arange(n) == j, 0, 1 / (mu[j] - mu)) / norm
        w[j] = 0.0
        g = np.einsum("ki,bij,j->bk", chiH, dA, phi[:, j])   # chi_k^H dA phi_j
        dphi = (g * w[None, :]) @ phi.T                         # (nb, n)
        v = C @ phi[:, j]
        dv = dC @ phi[:, j] + dphi @ C.T
        r = int(np.argmax(np.abs(v)))
        s = v / v[r]
        ds = (dv - s[None, :] * dv[:, r:r + 1]) / v[r]
        sstd[m] = np.sqrt(np.sum(np.abs(ds) ** 2, axis=0))
    return fstd, zstd, sstd
