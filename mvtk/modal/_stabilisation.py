"""Stabilisation diagrams and pole selection shared by pLSCF and SSI-cov."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.spatial.distance import squareform

from ..errors import ParameterError

__all__ = ["StabilisationDiagram", "StabilityCriteria", "ClusterCriteria", "select_poles",
           "poles_near"]


@dataclass(frozen=True)
class StabilityCriteria:
    """When a pole counts as stable against the nearest pole of the previous order.

    Attributes
    ----------
    df : float
        Relative frequency change ``|f - f'| / f`` (default 0.01).
    dzeta : float
        Relative damping change ``|zeta - zeta'| / zeta`` (default 0.05).
    dmac : float
        ``1 - MAC`` of the pole vectors (participation vectors for pLSCF, shapes for
        SSI-cov) (default 0.02). Ignored for one-element vectors.
    zeta_max : float
        Poles with ``zeta <= 0`` or ``zeta > zeta_max`` are not physical (default 0.2).

    Examples
    --------
    Tighter frequency stability (0.5 %) for the diagram of the exact 2-mass-chain FRFs:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> d = modal.plscf(h, 2.0, 110.0, orders=range(2, 21), criteria=StabilityCriteria(df=0.005))
    >>> d.criteria.df, sorted(set(d.status.tolist()))
    (0.005, ['o', 's', 'v'])
    """

    df: float = 0.01
    dzeta: float = 0.05
    dmac: float = 0.02
    zeta_max: float = 0.2


@dataclass(frozen=True)
class ClusterCriteria:
    """Automatic selection: hierarchical clustering of the fully stable poles.

    Two stable poles are "near" when ``|f_i - f_j| / f <= cluster_df`` and
    ``|zeta_i - zeta_j| / max(zeta, zeta_floor) <= cluster_dzeta``; clusters are cut
    from an average-linkage tree at that distance. A cluster is a physical mode when
    it holds poles from at least ``max(min_count, min_fraction * largest)`` different
    model orders, ``largest`` being the order count of the largest cluster. Clusters
    closer than ``df`` of :class:`StabilityCriteria` whose orders mostly differ (less
    than ``merge_overlap`` shared) are one mode split by scatter and are merged; two
    clusters that share most orders are two close modes and are kept apart.

    Examples
    --------
    Ask for at least 5 model orders per physical mode:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> sel = select_poles(modal.plscf(h, 2.0, 110.0, orders=range(2, 21)),
    ...                    ClusterCriteria(min_count=5))
    >>> np.round(np.abs(sel.pole) / (2 * np.pi), 3), bool((sel.count >= 5).all())
    (array([31.105, 81.434]), True)
    """

    cluster_df: float = 0.003
    cluster_dzeta: float = 0.5
    zeta_floor: float = 0.005
    min_count: int = 3
    min_fraction: float = 0.3
    merge_overlap: float = 0.2


@dataclass(frozen=True)
class StabilisationDiagram:
    """Poles of every model order with their stability status.

    Attributes
    ----------
    method : str
        ``"pLSCF"`` or ``"SSI-cov"``.
    order : numpy.ndarray of int
        Model order of each pole (one entry per pole with positive imaginary part).
    pole : numpy.ndarray of complex
        Continuous-time pole ``lambda = -zeta w_n + i w_d`` in rad/s.
    vector : numpy.ndarray of complex, shape (n_poles, n)
        Participation vector (pLSCF) or mode shape (SSI-cov) of each pole.
    status : numpy.ndarray of str
        ``"o"`` new/unstable, ``"f"`` stable frequency, ``"d"`` frequency and damping,
        ``"v"`` frequency and vector, ``"s"`` all three; ``"x"`` not physical
        (damping outside ``(0, zeta_max]`` or frequency outside the band).
    orders : numpy.ndarray of int
        The model orders computed.
    band_hz : tuple of float
        Frequency band analysed.
    indicator_f_hz, indicator : numpy.ndarray
        Frequencies and curves drawn behind the diagram: CMIF singular values
        (pLSCF) or singular values of the output spectra (SSI-cov), shape
        ``(n_curves, n_frequency)``.
    criteria : StabilityCriteria

    Examples
    --------
    Returned by :func:`mvtk.modal.plscf` and :func:`mvtk.modal.ssi_cov`: every pole of
    every order with its status (``s``: stable in frequency, damping and vector):

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> d = modal.plscf(h, 2.0, 110.0, orders=range(2, 21))
    >>> d.method, int(d.orders.min()), int(d.orders.max()), d.pole.shape == d.status.shape
    ('pLSCF', 2, 20, True)
    """

    method: str
    order: np.ndarray
    pole: np.ndarray
    vector: np.ndarray
    status: np.ndarray
    orders: np.ndarray
    band_hz: tuple
    indicator_f_hz: np.ndarray
    indicator: np.ndarray
    criteria: StabilityCriteria = field(default_factory=StabilityCriteria)

    @property
    def fn_hz(self) -> np.ndarray:
        """Undamped natural frequency ``|lambda| / 2 pi`` of each pole in Hz."""
        return np.abs(self.pole) / (2 * np.pi)

    @property
    def zeta(self) -> np.ndarray:
        """Damping ratio ``-Re(lambda) / |lambda|`` of each pole."""
        return -self.pole.real / np.abs(self.pole)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per pole: order, fn_hz, zeta, status."""
        return pd.DataFrame({"order": self.order, "fn_hz": self.fn_hz, "zeta": self.zeta,
                             "status": self.status})

    def _repr_html_(self) -> str:
        counts = pd.Series(self.status).value_counts().to_dict()
        return (f"<b>StabilisationDiagram</b> ({self.method}, orders {self.orders.min()}.."
                f"{self.orders.max()}, band {self.band_hz[0]:g}..{self.band_hz[1]:g} Hz): "
                f"{len(self.pole)} poles, status counts {counts}")


def poles_to_diagram(method, per_order, band, ind_f, ind, criteria) -> StabilisationDiagram:
    """Assemble the diagram from ``[(order, poles, vectors), ...]`` and classify stability."""
    c = criteria
    orders, poles, vecs, status = [], [], [], []
    nvec = max((v.shape[1] for _, _, v in per_order if v.size), default=1)
    prev = None
    for p, lam, vec in per_order:
        keep = lam.imag > 0
        lam, vec = lam[keep], vec[keep]
        idx = np.argsort(lam.imag)
        lam, vec = lam[idx], vec[idx]
        fn = np.abs(lam) / (2 * np.pi)
        z = -lam.real / np.abs(lam)
        st = np.full(lam.size, "o", dtype="<U1")
        phys = (z > 0) & (z <= c.zeta_max) & (fn >= band[0]) & (fn <= band[1])
        st[~phys] = "x"
        if prev is not None and prev[0].size and lam.size:
            pf, pz, pv = prev
            j = np.argmin(np.abs(fn[:, None] - pf[None, :]), axis=1)
            okf = np.abs(fn - pf[j]) <= c.df * fn
            okz = np.abs(z - pz[j]) <= c.dzeta * np.abs(z)
            if vec.shape[1] > 1:
                b = pv[j]
                num = np.abs(np.sum(np.conj(vec) * b, axis=1)) ** 2
                den = np.sum(np.abs(vec) ** 2, axis=1) * np.sum(np.abs(b) ** 2, axis=1)
                m = np.where(den > 0, num / np.where(den > 0, den, 1), 0.0)
                okv = m >= 1 - c.dmac
            else:
                okv = np.ones(lam.size, bool)
            s = np.where(okf & okz & okv, "s", np.where(okf & okz, "d",
                         np.where(okf & okv, "v", np.where(okf, "f", "o"))))
            st = np.where(phys, s, "x")
        prev = (fn[st != "x"], z[st != "x"], vec[st != "x"])
        orders.append(np.full(lam.size, p))
        poles.append(lam)
        v = np.zeros((lam.size, nvec), complex)
        v[:, :vec.shape[1]] = vec
        vecs.append(v)
        status.append(st)
    return StabilisationDiagram(
        method=method, order=np.concatenate(orders).astype(int),
        pole=np.concatenate(poles), vector=np.concatenate(vecs, axis=0),
        status=np.concatenate(status), orders=np.array([p for p, _, _ in per_order]),
        band_hz=(float(band[0]), float(band[1])), indicator_f_hz=ind_f, indicator=ind,
        criteria=c,
    )


@dataclass(frozen=True)
class SelectedPoles:
    """Poles chosen as physical modes (one per mode), with their stability evidence.

    Examples
    --------
    Returned by :func:`select_poles` and :func:`poles_near`: one pole per mode with the
    model order it came from and how many orders support it:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> sel = select_poles(modal.plscf(h, 2.0, 110.0, orders=range(2, 21)))
    >>> sel.pole.shape, sel.vector.shape[0]
    ((2,), 2)
    """

    pole: np.ndarray
    vector: np.ndarray
    order: np.ndarray
    count: np.ndarray
    members: tuple


def _cluster(f, z, crit: ClusterCriteria):
    """Average-linkage cluster labels of the poles ``(f, z)`` cut at distance 1.

    Sorted by frequency, neighbours further apart than ``cluster_df`` (relative) split
    the poles into groups whose every cross distance exceeds 1, so no cluster spans two
    groups: each group is clustered on its own (the same clusters as one tree over all
    poles, at a fraction of the O(n^2) cost).
    """
    n = f.size
    labels = np.zeros(n, dtype=int)
    idx = np.argsort(f, kind="stable")
    fs = f[idx]
    gap = np.diff(fs) > crit.cluster_df * 0.5 * (fs[1:] + fs[:-1])
    bounds = np.concatenate([[0], np.flatnonzero(gap) + 1, [n]])
    top = 0
    for a, b in zip(bounds[:-1], bounds[1:]):
        g = idx[a:b]
        if g.size == 1:
            lab = np.array([1])
        elif g.size == 2:
            # one merge at the pair's distance: together when it is within the cut
            fa, fb, za, zb = f[g[0]], f[g[1]], z[g[0]], z[g[1]]
            d = max(abs(fa - fb) / (0.5 * (fa + fb)) / crit.cluster_df,
                    abs(za - zb) / max(0.5 * (za + zb), crit.zeta_floor) / crit.cluster_dzeta)
            lab = np.array([1, 1]) if d <= 1.0 else np.array([1, 2])
        else:
            fg, zg = f[g], z[g]
            fm = 0.5 * (fg[:, None] + fg[None, :])
            zm = np.maximum(0.5 * (zg[:, None] + zg[None, :]), crit.zeta_floor)
            d = np.maximum(np.abs(fg[:, None] - fg[None, :]) / fm / crit.cluster_df,
                           np.abs(zg[:, None] - zg[None, :]) / zm / crit.cluster_dzeta)
            np.fill_diagonal(d, 0.0)
            tree = linkage(squareform(d, checks=False), method="average")
            lab = fcluster(tree, t=1.0, criterion="distance")
        labels[g] = lab + top
        top += int(lab.max())
    return labels


def select_poles(diagram: StabilisationDiagram, criteria: ClusterCriteria | None = None
                 ) -> SelectedPoles:
    """Physical poles picked automatically by clustering the fully stable poles.

    Criteria (see :class:`ClusterCriteria`): only poles with status ``"s"`` enter; a
    cluster must span enough model orders; its representative is the member closest to
    the cluster median in frequency and damping. Returns the poles sorted by frequency.

    Examples
    --------
    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> sel = select_poles(modal.plscf(h, 2.0, 110.0, orders=range(2, 21)))
    >>> np.round(np.abs(sel.pole) / (2 * np.pi), 3)      # Hz
    array([31.105, 81.434])
    """
    crit = criteria or ClusterCriteria()
    stable = np.flatnonzero(diagram.status == "s")
    empty = SelectedPoles(np.zeros(0, complex), np.zeros((0, diagram.vector.shape[1]), complex),
                          np.zeros(0, int), np.zeros(0, int), ())
    if stable.size == 0:
        return empty
    fn_all, z_all, ord_all = diagram.fn_hz, diagram.zeta, diagram.order
    f, z = fn_all[stable], z_all[stable]
    labels = _cluster(f, z, crit)
    groups = [stable[labels == lab] for lab in np.unique(labels)]
    meds = [float(np.median(fn_all[g])) for g in groups]
    idx = np.argsort(meds)
    groups, meds = [groups[i] for i in idx], [meds[i] for i in idx]
    # merge neighbouring clusters of one mode split by scatter (near in f, disjoint orders)
    i = 0
    while i < len(groups) - 1:
        fa, fb = meds[i], meds[i + 1]
        oa, ob = set(ord_all[groups[i]]), set(ord_all[groups[i + 1]])
        if (abs(fa - fb) <= diagram.criteria.df * 0.5 * (fa + fb)
                and len(oa & ob) <= crit.merge_overlap * min(len(oa), len(ob))):
            groups[i] = np.concatenate([groups[i], groups[i + 1]])
            meds[i] = float(np.median(fn_all[groups[i]]))
            del groups[i + 1], meds[i + 1]
            i = max(i - 1, 0)
        else:
            i += 1
    counts = np.array([len(set(ord_all[g])) for g in groups])
    need = max(crit.min_count, crit.min_fraction * counts.max())
    reps, members = [], []
    for g, n in zip(groups, counts):
        if n < need:
            continue
        fg, zg = fn_all[g], z_all[g]
        dist = np.abs(fg - np.median(fg)) / np.median(fg) / crit.cluster_df + \
            np.abs(zg - np.median(zg)) / max(np.median(zg), crit.zeta_floor) / crit.cluster_dzeta
        reps.append(g[np.argmin(dist)])
        members.append(g)
    if not reps:
        return empty
    reps = np.array(reps)
    order = np.argsort(diagram.fn_hz[reps])
    reps = reps[order]
    members = tuple(members[i] for i in order)
    return SelectedPoles(diagram.pole[reps], diagram.vector[reps], diagram.order[reps],
                         np.array([len(set(diagram.order[g])) for g in members]), members)


def poles_near(diagram: StabilisationDiagram, fn_hz, *, tol: float = 0.05) -> SelectedPoles:
    """The pole nearest each requested frequency, preferring the most stable ones.

    For each frequency the candidates within ``tol`` (relative) are ranked by status
    (``s`` > ``v``/``d`` > ``f`` > ``o``) and then by model order (highest first), and
    the nearest of the best rank is taken.

    Raises
    ------
    ParameterError
        No physical pole lies within ``tol`` of a requested frequency.

    Examples
    --------
    Pick the poles nearest 31 and 81.5 Hz instead of clustering:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> sel = poles_near(modal.plscf(h, 2.0, 110.0, orders=range(2, 21)), [31.0, 81.5])
    >>> np.round(np.abs(sel.pole) / (2 * np.pi), 3)
    array([31.105, 81.434])
    """
    rank = {"s": 0, "d": 1, "v": 1, "f": 2, "o": 3}
    fn = diagram.fn_hz
    ok = diagram.status != "x"
    picks, counts, members = [], [], []
    for f0 in np.atleast_1d(np.asarray(fn_hz, dtype=float)):
        cand = np.flatnonzero(ok & (np.abs(fn - f0) <= tol * f0))
        if cand.size == 0:
            raise ParameterError(
                f"poles_near: no physical pole within {tol:.0%} of {f0:g} Hz in the "
                f"{diagram.method} stabilisation diagram (band {diagram.band_hz[0]:g}.."
                f"{diagram.band_hz[1]:g} Hz)"
            )
        r = np.array([rank[s] for s in diagram.status[cand]])
        best = cand[r == r.min()]
        top = best[diagram.order[best] == diagram.order[best].max()]
        k = top[np.argmin(np.abs(fn[top] - f0))]
        near = cand[(np.abs(fn[cand] - fn[k]) <= diagram.criteria.df * fn[k])
                    & (diagram.status[cand] == "s")]
        picks.append(k)
        members.append(near)
        counts.append(len(set(diagram.order[near])))
    picks = np.array(picks, dtype=int)
    return SelectedPoles(diagram.pole[picks], diagram.vector[picks], diagram.order[picks],
                         np.array(counts, dtype=int), tuple(members))
