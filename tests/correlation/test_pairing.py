"""Automatic pairing by MAC and frequency, swap detection."""

from __future__ import annotations

import numpy as np
import pytest
from correlation_helpers import plate_setup as _setup

from mvtk import correlation as co
from mvtk.errors import ParameterError


def test_pairing_detects_swapped_modes():
    *_, fe = _setup(6)
    # the test sees FE modes 1, 2, 4, 3, 5 in ascending frequency: 3 and 4 swapped
    test = fe.sel(mode=[1, 2, 4, 3, 5]).copy()
    f = fe["fn_hz"].values
    test = test.assign_coords(mode=[1, 2, 3, 4, 5],
                              fn_hz=("mode", [f[0], f[1], 0.9 * f[2], 1.02 * f[2], f[4]]))
    pr = co.pair_modes(test, fe)
    tab = pr.table
    assert tab["fe_mode"].tolist() == [1, 2, 4, 3, 5]
    assert pr.swaps == ((3, 4),)
    assert tab.set_index("test_mode").loc[[3, 4], "swapped"].all()
    assert "order swapped with test mode 4" in tab.set_index("test_mode").loc[3, "reason"]
    assert pr.pairs == [(1, 1), (2, 2), (3, 4), (4, 3), (5, 5)]
    t, a = pr.select(test, fe)
    np.testing.assert_allclose(np.diag(co.mac(t, a)), 1.0)


def test_low_mac_is_reported_not_accepted(rng):
    *_, fe = _setup(4)
    junk = fe.copy(data=rng.normal(size=fe.shape))
    pr = co.pair_modes(junk, fe, mac_min=0.8)
    assert not pr.table["paired"].any()
    assert pr.table["reason"].str.contains("< 0.8").all()
    with pytest.raises(ParameterError, match="no accepted pairs"):
        pr.select(junk, fe)
    with pytest.raises(ParameterError, match="mac_min must be in"):
        co.pair_modes(fe, fe, mac_min=2)
