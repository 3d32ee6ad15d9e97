"""Super element keeping piezo electrodes (mvtk.reduction.with_electrodes) against the
full electromechanical model of the curved panel with a collocated pair of patches."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ParameterError
from mvtk.fe import build_model, factorize, modal_analysis, piezo_coupling
from mvtk.reduction import craig_bampton, with_electrodes

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fe"))
from test_electro import _panel  # noqa: E402

ETA = 0.01  # structural damping (loss factor) of the FRF comparison


def _full_frf(m, cp, f_hz):
    """Voltage-to-charge FRFs of the full model, one sparse (complex) solve per
    frequency."""
    out = []
    for f in f_hz:
        w = 2 * np.pi * f
        A = (m.K * (1 + 1j * ETA) - w**2 * m.M).tocsc()
        out.append(cp.B.T @ factorize(A, backend="superlu").solve(cp.B)
                   + np.diag(cp.C))
    return np.array(out)


def _se_frf(se, Br, C, f_hz):
    return np.array([Br.T @ np.linalg.solve(se.K * (1 + 1j * ETA) - (2 * np.pi * f) ** 2
                                            * se.M, Br) + np.diag(C) for f in f_hz])


@pytest.fixture(scope="module")
def panel():
    m = build_model(_panel())
    cp = piezo_coupling(m)
    se = craig_bampton(m, ["centre"], f_cut_hz=1000.0)
    return m, cp, se


@pytest.mark.slow
def test_se_voltage_to_charge_frf_matches_the_full_model_to_two_thirds_of_the_kept_modes(
        panel):
    """The SE keeps fixed-interface modes to 973 Hz; in the band to 973 / 1.5 = 649 Hz
    (16 modes of the full model) every voltage-to-charge FRF (each electrode on itself
    with its feed-through C_p, and actuator -> collocated sensor) is within 1 % in
    magnitude of the full model's, computed by a sparse solve per frequency. The
    frequencies checked: a uniform grid, every resonance of the full model
    (short-circuit modes) and every anti-resonance of each electrode's own transfer
    (its open-circuit modes: C + b'(K - w^2 M)^-1 b = 0 <=> det(K + b b'/C - w^2 M) = 0),
    each with its two half-power flanks f (1 -+ eta/2), where a shift of the SE's
    frequency shows most; and the local minima of the cross transfer."""
    m, cp, se = panel
    f_top = float(se.interior_fn_hz.max())
    assert 950.0 < f_top < 1000.0
    band = f_top / 1.5
    se1, Br1 = with_electrodes(se, cp)              # static shapes + 1 inertia block
    se0, Br0 = with_electrodes(se, cp, inertia_order=0)
    assert se1.labels[se.n_dof:se.n_dof + 2] == ("v:act", "v:sen")
    assert se1.meta["inertia_vectors"] == se1.n_dof - se.n_dof - 2 > 0
    # static transfer exact (the static shapes are in both bases)
    G = cp.B.T @ factorize(m.K.tocsc()).solve(cp.B)
    for s, Br in ((se0, Br0), (se1, Br1)):
        assert np.max(np.abs(Br.T @ np.linalg.solve(s.K, Br) - G)) <= 1e-8 * np.abs(G).max()
    f_sc = modal_analysis(m, 20).fn_hz
    f_oc = np.concatenate([modal_analysis(cp.open_circuit_model(m, [n]), 20).fn_hz
                           for n in cp.names])
    loci = np.concatenate([f_sc, f_oc])
    loci = loci[loci < band]
    assert np.sum(f_sc < band) >= 15
    # cross transfer minima, located on a fine SE grid, refined on the full model below
    fine = np.linspace(5.0, band, 4000)
    h = np.abs(_se_frf(se1, Br1, cp.C, fine)[:, 0, 1])
    mins = fine[1:-1][(h[1:-1] < h[:-2]) & (h[1:-1] < h[2:])]
    assert len(mins) >= 3
    pts = np.concatenate([np.linspace(5.0, band, 40),
                          *[loci * (1 + s * ETA / 2) for s in (-1, 0, 1)], mins])
    pts = np.sort(pts[(pts > 0) & (pts <= band)])
    H = _full_frf(m, cp, pts)
    err1 = np.abs(np.abs(_se_frf(se1, Br1, cp.C, pts)) - np.abs(H)) / np.abs(H)
    err0 = np.abs(np.abs(_se_frf(se0, Br0, cp.C, pts)) - np.abs(H)) / np.abs(H)
    # measured 0.10 % (act on itself), 0.02 % (sen on itself), 0.30 % (act -> sen)
    assert err1.max() < 0.01, err1.max(axis=0)
    # the full model's cross minima are where the SE puts them: no deeper full-model
    # minimum next to an SE minimum
    Hm = np.abs(H[np.isin(pts, mins), 0, 1])
    Hl = np.abs(_full_frf(m, cp, mins * (1 - 2e-3))[:, 0, 1])
    Hr = np.abs(_full_frf(m, cp, mins * (1 + 2e-3))[:, 0, 1])
    assert np.all(Hm <= np.minimum(Hl, Hr) * 1.001)
    # with the static shapes alone the fixed-interface modes' truncation shows: tens of
    # per cent near the modes above 1/3 of the kept ones (measured 79 %)
    assert err0.max() > 0.2


def test_inertia_order_is_checked(panel):
    _, cp, se = panel
    with pytest.raises(ParameterError, match="inertia_order"):
        with_electrodes(se, cp, inertia_order=-1)
