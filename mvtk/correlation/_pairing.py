"""Automatic pairing of test and FE modes by MAC and frequency, with swap detection."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from ..errors import ParameterError
from ._metrics import _aligned, mac

__all__ = ["ModePairing", "pair_modes"]


@dataclass(frozen=True, eq=False)
class ModePairing:
    """Test-FE mode pairs.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per test mode: ``test_mode``, ``fe_mode`` (-1 when unpaired),
        ``fn_test_hz``, ``fn_fe_hz``, ``df_pct`` (100 (f_fe - f_test)/f_test), ``mac``,
        ``second_mac`` (next best MAC of that test mode: a small gap = ambiguous pair),
        ``swapped`` (the pair breaks the frequency order of the pairs, i.e. the FE model
        has two modes in the opposite order to the test), ``paired`` (MAC >= ``mac_min``)
        and ``reason`` (why a row is not paired or is doubtful).
    mac : xarray.DataArray
        The full MAC matrix (test modes x FE modes).
    swaps : tuple of (int, int)
        Test-mode pairs whose FE partners are in swapped order.

    Examples
    --------
    Returned by :func:`pair_modes` (and in :class:`CorrelationResult`): the pair table:

    >>> import xarray as xr
    >>> fe = xr.DataArray([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]], dims=("mode", "dof"),
    ...                   coords={"mode": [1, 2], "dof": ["1+z", "2+z", "3+z"],
    ...                           "fn_hz": ("mode", [10.0, 30.0])})
    >>> pairing = pair_modes(-fe, fe)
    >>> pairing.table[["test_mode", "fe_mode"]].values.tolist(), pairing.swaps
    ([[1, 1], [2, 2]], ())
    """

    table: Any
    mac: xr.DataArray
    swaps: tuple[tuple[int, int], ...]

    def to_dataframe(self):
        """The pairing table."""
        return self.table

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.table, caption=type(self).__name__, passed_column=None)

    @property
    def pairs(self) -> list[tuple[int, int]]:
        """``(test_mode, fe_mode)`` of the accepted pairs (1-based labels)."""
        t = self.table[self.table["paired"]]
        return list(zip(t["test_mode"].astype(int), t["fe_mode"].astype(int)))

    def select(self, test: Any, fe: Any) -> tuple[xr.DataArray, xr.DataArray]:
        """The paired modes of ``test`` and ``fe`` in pair order (for COMAC, MSF ...)."""
        p = self.pairs
        if not p:
            raise ParameterError("no accepted pairs (all MAC below mac_min)")
        return (test.sel(mode=[a for a, _ in p]), fe.sel(mode=[b for _, b in p]))


def pair_modes(
    test: Any,
    fe: Any,
    *,
    mac_min: float = 0.6,
    freq_weight: float = 0.0,
    max_df: float | None = None,
) -> ModePairing:
    """Pair test modes with FE modes (one-to-one) by MAC and frequency.

    Assignment: Hungarian algorithm (:func:`scipy.optimize.linear_sum_assignment`) on the
    cost ``(1 - MAC) + freq_weight * |f_fe - f_test| / f_test``; pairs with MAC below
    ``mac_min`` (or a relative frequency gap above ``max_df``) are reported but not
    accepted. A *swap* is a pair of accepted pairs whose FE modes are in the opposite
    frequency order of their test modes (a mode that the model places above its
    neighbour while the test places it below: typical of a wrong stiffness ratio, e.g.
    bending against torsion).

    Parameters
    ----------
    test, fe : DataArray ("mode", "dof")
        Shapes on identical DOFs; ``fn_hz`` coordinates are used when present.
    mac_min : float
        Smallest MAC of an accepted pair.
    freq_weight : float
        Weight of the relative frequency gap in the cost (0: MAC only).
    max_df : float, optional
        Largest accepted relative frequency gap (e.g. 0.3).

    Returns
    -------
    ModePairing

    Examples
    --------
    Two "test" modes that are the FE modes in reverse order (and scaled): each is paired
    with its FE mode at MAC 1:

    >>> import xarray as xr
    >>> fe = xr.DataArray([[1.0, 2.0, 3.0], [1.0, 1.0, -1.0]], dims=("mode", "dof"),
    ...                   coords={"mode": [1, 2], "dof": ["1+z", "2+z", "3+z"],
    ...                           "fn_hz": ("mode", [10.0, 30.0])})
    >>> test = -2.0 * fe.isel(mode=[1, 0]).assign_coords(mode=[1, 2], fn_hz=("mode", [31.0, 9.8]))
    >>> pairing = pair_modes(test, fe)
    >>> pairing.table[["test_mode", "fe_mode", "mac"]].round(6).values.tolist()
    [[1.0, 2.0, 1.0], [2.0, 1.0, 1.0]]
    """
    import pandas as pd
    from scipy.optimize import linear_sum_assignment

    if not 0 <= mac_min <= 1:
        raise ParameterError(f"mac_min must be in [0, 1], got {mac_min!r}")
    if freq_weight < 0:
        raise ParameterError(f"freq_weight must be >= 0, got {freq_weight!r}")
    T, F = _aligned(test, fe)
    M = mac(T, F)
    m = M.values
    ft = T["fn_hz"].values.astype(float) if "fn_hz" in T.coords else np.full(m.shape[0], np.nan)
    ff = F["fn_hz"].values.astype(float) if "fn_hz" in F.coords else np.full(m.shape[1], np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(ff[None, :] - ft[:, None]) / ft[:, None]
    cost = 1.0 - m
    if freq_weight > 0:
        cost = cost + freq_weight * np.nan_to_num(rel, nan=0.0)
    rows, cols = linear_sum_assignment(cost)
    fe_of = np.full(m.shape[0], -1)
    fe_of[rows] = cols
    tm, fm = T["mode"].values, F["mode"].values
    recs = []
    for i in range(m.shape[0]):
        j = fe_of[i]
        rowm = np.sort(m[i])[::-1]
        second = float(rowm[1]) if rowm.size > 1 else np.nan
        if j < 0:
            recs.append({"test_mode": int(tm[i]), "fe_mode": -1, "fn_test_hz": ft[i],
                         "fn_fe_hz": np.nan, "df_pct": np.nan, "mac": np.nan,
                         "second_mac": second, "paired": False,
                         "reason": "more test modes than FE modes"})
            continue
        reason = []
        ok = m[i, j] >= mac_min
        if not ok:
            reason.append(f"MAC {m[i, j]:.2f} < {mac_min:g}")
        if max_df is not None and np.isfinite(rel[i, j]) and rel[i, j] > max_df:
            ok = False
            reason.append(f"|df| {100 * rel[i, j]:.1f} % > {100 * max_df:g} %")
        if ok and np.isfinite(second) and m[i, j] - second < 0.2:
            reason.append(f"ambiguous: next MAC {second:.2f}")
        recs.append({"test_mode": int(tm[i]), "fe_mode": int(fm[j]), "fn_test_hz": ft[i],
                     "fn_fe_hz": ff[j], "df_pct": 100 * (ff[j] - ft[i]) / ft[i],
                     "mac": float(m[i, j]), "second_mac": second, "paired": bool(ok),
                     "reason": "; ".join(reason)})
    tab = pd.DataFrame(recs)
    swaps = []
    acc = tab[tab["paired"]]
    order_t = np.argsort(acc["fn_test_hz"].to_numpy()) if np.all(
        np.isfinite(acc["fn_test_hz"])) else np.arange(len(acc))
    acc = acc.iloc[order_t]
    pos = {int(b): k for k, b in enumerate(fm)}
    swapped = set()
    tml, fml = acc["test_mode"].tolist(), acc["fe_mode"].tolist()
    for a in range(len(acc)):
        for b in range(a + 1, len(acc)):
            if pos[fml[a]] > pos[fml[b]]:
                swaps.append((int(tml[a]), int(tml[b])))
                swapped.update((tml[a], tml[b]))
    tab["swapped"] = tab["test_mode"].isin(swapped)
    for a, b in swaps:
        for t in (a, b):
            k = tab.index[tab["test_mode"] == t][0]
            other = b if t == a else a
            note = f"order swapped with test mode {other}"
            tab.loc[k, "reason"] = (tab.loc[k, "reason"] + "; " if tab.loc[k, "reason"]
                                    else "") + note
    cols_order = ["test_mode", "fe_mode", "fn_test_hz", "fn_fe_hz", "df_pct", "mac",
                  "second_mac", "swapped", "paired", "reason"]
    return ModePairing(table=tab[cols_order], mac=M, swaps=tuple(swaps))
