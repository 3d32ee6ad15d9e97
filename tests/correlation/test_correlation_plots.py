"""Correlation figures render (PNG) from the objects of mvtk.correlation."""

from __future__ import annotations

import numpy as np
import pytest
from correlation_helpers import plate_setup

from mvtk import correlation as co
from mvtk.errors import DimensionError
from mvtk.plot import figure_to_png, plot_mac, plot_paired_shapes, plot_test_on_mesh


@pytest.mark.slow
def test_correlation_figures(tmp_path):
    model, modal, geo, mp, fe = plate_setup(4)
    # wireframe: the 5 x 4 grid lines
    ids = geo.node.reshape(5, 4)
    geo = co.TestGeometry(geo.node, geo.xyz, sensors=geo.sensors,
                          lines=tuple(ids) + tuple(ids.T))
    test = fe.copy(data=fe.values * (1 + 0.02 * np.random.default_rng(0).normal(size=fe.shape)))
    pr = co.pair_modes(test, fe)
    for fig in (plot_mac(pr.mac), plot_paired_shapes(geo, test, fe, pr),
                plot_test_on_mesh(model, geo, mapping=mp)):
        png = figure_to_png(fig, dpi=50)
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 2000
    (tmp_path / "mac.png").write_bytes(figure_to_png(plot_mac(pr.mac)))
    with pytest.raises(DimensionError, match="expected a 2-D DataArray"):
        plot_mac(co.comac(test, fe))
