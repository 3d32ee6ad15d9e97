"""A weak mode beside a strong one that makes no peak of its own: the default orders
are raised until it is found, instead of biasing its neighbours with confident stds.

Truth: the FE modes of the stiffened curved panel (``data/structures/curved_panel``)
as the specimen: a 3 x 4 roving-hammer grid on the curved skin, the accelerometer at
one grid node, zeta 0.6 % on every mode, 1.5 s records, 0.1 % noise
(``tests/roving_hammer.write_fe_test``). At the grid the 364.97 Hz mode has 4.7 % of the
strongest modal constant and sits 3.6 Hz (0.8 half-power bandwidths) below 368.60 Hz.
The 232 Hz pair is nodal at the sensor (no data); 123.32 Hz is 0.6 Hz from 123.91 Hz
at 0.2 % of the strongest constant (not separable here).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from mvtk import fe, io, modal
from mvtk.modal._frf import frf_of_sets
from mvtk.modal._identify import MAX_LACK_OF_FIT, lack_of_fit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import roving_hammer as RH  # noqa: E402

PANEL = Path(__file__).resolve().parents[2] / "data" / "structures" / "curved_panel"
ZETA = 0.006


@pytest.fixture(scope="module")
def panel_test(tmp_path_factory):
    model = fe.build_model(fe.load_structure(PANEL / "curved_panel.toml"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        modes = fe.modal_analysis(model, 8)
    radius, pts = 0.5, []
    for x in (0.1, 0.2, 0.3):
        for y in (-0.12, -0.04, 0.04, 0.12):
            at = [x, y, np.sqrt(radius**2 - y**2)]
            pts.append(int(np.argmin(np.linalg.norm(model.nodes - at, axis=1))))
    folder = tmp_path_factory.mktemp("panel")
    files = RH.write_fe_test(folder, model, modes, pts, pts[5], zeta=ZETA, fs=2048.0,
                             record_s=1.5, f_max_hz=420.0, seed=101)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = frf_of_sets([io.read(p) for p in files], None)
    return np.asarray(modes.fn_hz), h, files


def test_the_weak_neighbour_is_found_and_the_neighbours_are_right(panel_test):
    truth, h, _ = panel_test
    res = modal.identify(h)
    assert "model orders raised from 2..64 to 2..128" in res.band_reason
    assert "add 364.97 Hz" in res.band_reason
    for f0 in (335.719, 356.929, 364.972, 368.599):
        k = int(np.argmin(np.abs(res.fn_hz - f0)))
        exact = truth[int(np.argmin(np.abs(truth - f0)))]
        assert abs(res.fn_hz[k] / exact - 1) < 1e-4
        assert res.reliable[k]
        err = abs(res.zeta[k] - ZETA)
        assert err < 0.005 * ZETA and err < 3 * res.zeta_std[k] + 1e-7
        assert lack_of_fit(res)[k] < MAX_LACK_OF_FIT


def test_without_the_raise_the_neighbours_are_biased(panel_test):
    """The premise: at the peak count's orders (2..64) 364.97 Hz is missing and both
    neighbours carry zeta +7 %, several standard deviations off, with a residual around
    them far above the rest of the band."""
    _, h, _ = panel_test
    res = modal.identify(h, orders=range(2, 65))
    assert not np.any(np.abs(res.fn_hz - 364.97) < 1.0)
    lack = lack_of_fit(res)
    for f0 in (356.9, 368.6):
        k = int(np.argmin(np.abs(res.fn_hz - f0)))
        assert res.zeta[k] > 1.05 * ZETA and res.zeta[k] - ZETA > 3 * res.zeta_std[k]
        assert lack[k] > MAX_LACK_OF_FIT


def test_mvtk_modal_with_defaults_says_why_the_orders_rose(panel_test, capsys):
    from mvtk.cli import main

    _, _, files = panel_test
    assert main(["modal", *map(str, files)]) == 0
    out = capsys.readouterr().out
    assert "model orders raised" in out and "364.97" in out


@pytest.mark.shared_data
def test_real_hammer_test_takes_no_far_poles_from_higher_orders(modal_data):
    """acceleration.lvm: 8747.6 Hz leaves 2800 x the band's median residual (a real
    peak no modal model holds exactly), and orders 2..128 find "modes" at 4080, 8545 and
    9650 Hz where the response spectrum has no peak. The raise looks only beside the
    modes that lack fit, finds no neighbour there, and keeps the default result."""
    ds = io.read(modal_data / "lvm" / "acceleration.lvm")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = modal.frf_matrix([ds], {"quantity": "force"})
        res = modal.identify(h)
        high = modal.identify(h, orders=range(2, 129))
    assert "model orders raised" not in res.band_reason
    assert int(res.diagram.orders.max()) == 64
    far = [f for f in high.fn_hz[high.reliable]
           if np.all(np.abs(res.fn_hz - f) > 0.01 * f)]
    assert any(abs(f - 8545) < 10 for f in far)     # what the raise must not take
    for f0 in (695.8, 1898.1, 2779.7, 3670.8, 5975.0, 8747.5):   # PROVENANCE.md peaks
        k = int(np.argmin(np.abs(res.fn_hz - f0)))
        assert abs(res.fn_hz[k] / f0 - 1) < 2e-3 and res.reliable[k]


@pytest.fixture(scope="module")
def nastran_panel(tmp_path_factory):
    """A newcomer's own Nastran deck and roving-hammer test
    (:func:`roving_hammer.write_nastran_panel_test`)."""
    return RH.write_nastran_panel_test(tmp_path_factory.mktemp("nastran_panel"))


def test_mvtk_modes_takes_a_nastran_deck_as_it_is(nastran_panel, capsys):
    from mvtk.cli import main

    deck, truth, model, _ = nastran_panel
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["modes", str(deck), "-n", "6", "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert np.allclose(out["fn_hz"], truth[:6], rtol=1e-9)
    assert out["n_dof"] == model.n_dof
    # the free pair 269.97 / 270.72 Hz and 445.60 / 447.75 Hz (a curved panel's pairs)
    assert abs(truth[1] / truth[0] - 1) < 0.005 and abs(truth[6] / truth[5] - 1) < 0.006


def test_roving_test_of_the_deck_close_pair_is_marked_and_the_rest_right(nastran_panel):
    """Every mode marked reliable is right (frequency within 1e-4 of the deck's, zeta
    within 1 % and 3 std), and the pair 445.60 / 447.75 Hz, 2.15 Hz apart in 2.2 Hz
    lines, is one pole marked "unresolved". Known limit, excluded: the pair 269.97 /
    270.72 Hz (a third of a line apart) comes out as one pole at 270.07 Hz with a real
    shape (MPC 0.99) and a residual ratio of 6-11, zeta +3 %, marked reliable."""
    _, truth, _, files = nastran_panel
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = frf_of_sets([io.read(p) for p in files], None)
        res = modal.identify(h)
    sets = h.attrs["set_quality"]
    assert "hit_11.csv" in sets and "double hit" in sets           # named, refused
    k = int(np.argmin(np.abs(res.fn_hz - 446.7)))
    assert not res.reliable[k] and res.reason[k].startswith("unresolved")
    assert "model orders raised" in res.band_reason
    right = 0
    for k in np.flatnonzero(res.reliable):
        if abs(res.fn_hz[k] - 270.3) < 1.0:
            continue                                   # the known limit above
        exact = truth[int(np.argmin(np.abs(truth - res.fn_hz[k])))]
        assert abs(res.fn_hz[k] / exact - 1) < 1e-4, res.fn_hz[k]
        assert abs(res.zeta[k] / 0.005 - 1) < 0.01
        assert abs(res.zeta[k] - 0.005) < 3 * res.zeta_std[k]
        right += 1
    assert right >= 3
