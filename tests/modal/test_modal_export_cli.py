"""UFF 55/58 export read back by mvtk.io, the ``mvtk modal`` command, the figures."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtk import io, modal
from mvtk.cli import main
from mvtk.errors import FormatError, ParameterError


def _modes(msys):
    M, C, K = msys.chain(4)
    f = np.arange(0, 120, 0.2)
    h = modal.exact_frf(M, C, K, f, range(4), [0, 2], frf_type="accelerance")
    return modal.identify(h, 2, 115), M, C, K


def test_uff_round_trip(msys, tmp_path):
    res, *_ = _modes(msys)
    p55 = modal.write_modes_uff(res, tmp_path / "modes.uff")
    back = io.read(p55)
    assert back["mode_shape"].shape == (4, 4, 3)
    np.testing.assert_allclose(back["fn_hz"].values, res.fn_hz, rtol=1e-5)
    np.testing.assert_allclose(back["eigenvalue"].values, res.pole, rtol=1e-5)
    np.testing.assert_allclose(back["mode_shape"].values[:, :, 2], res.shapes.values,
                               rtol=1e-4, atol=1e-9)
    real = io.read(modal.write_modes_uff(res, tmp_path / "real.uff", shapes="real"))
    np.testing.assert_allclose(real["mode_shape"].values[:, :, 2], res.real_shapes.values,
                               rtol=1e-4, atol=1e-9)
    np.testing.assert_allclose(real["damping_ratio"].values, res.zeta, rtol=1e-4)
    p58 = modal.write_frf_uff(res.synthesised, tmp_path / "frf.uff")
    h = modal.as_frf_matrix(io.read(p58))
    assert h.shape == res.synthesised.shape and h.attrs["frf_type"] == "accelerance"
    assert h["node"].values.tolist() == [1, 2, 3, 4]
    np.testing.assert_allclose(h.values, res.synthesised.values, rtol=1e-6,
                               atol=1e-9 * np.abs(h.values).max())
    with pytest.raises(ParameterError, match="shapes must be 'complex' or 'real'"):
        modal.write_modes_uff(res, tmp_path / "x.uff", shapes="imag")
    with pytest.raises(FormatError, match="uniformly spaced"):
        modal.write_frf_uff(res.synthesised.isel(frequency=[0, 1, 3]), tmp_path / "y.uff")


def test_cli_json_and_exports(msys, tmp_path, capsys):
    res, *_ = _modes(msys)
    p = modal.write_frf_uff(res.frf, tmp_path / "meas.uff")
    rc = main(["modal", str(p), "--fmin", "2", "--fmax", "115", "--json",
               "--uff-modes", str(tmp_path / "m.uff"), "--uff-frf", str(tmp_path / "s.uff")])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "pLSCF+LSFD" and len(out["modes"]) == 4
    assert len(out["shapes"]) == 16 and out["shape_normalisation"] == "mass"
    np.testing.assert_allclose([m["fn_hz"] for m in out["modes"]], res.fn_hz, rtol=1e-6)
    assert set(out["modes"][0]) >= {"fn_hz", "zeta", "mpc", "mpd", "stability_count",
                                    "support", "reliable", "reason"}
    # support is a number (JSON null only for an exact fit or where it does not apply)
    assert all(m["support"] is None or m["support"] > 2 for m in out["modes"])
    assert (tmp_path / "m.uff").exists() and (tmp_path / "s.uff").exists()
    rc = main(["modal", str(p), "--fmin", "2", "--fmax", "115", "--fn", "500"])
    assert rc == 2
    assert "no physical pole within 5% of 500 Hz" in capsys.readouterr().err


@pytest.mark.slow
def test_figures(msys):
    pytest.importorskip("matplotlib")
    from mvtk import plot

    res, *_ = _modes(msys)
    for fig in (plot.plot_stabilisation(res.diagram, res), plot.plot_frf_synthesis(res),
                plot.plot_automac(res)):
        assert plot.figure_to_png(fig)[:4] == b"\x89PNG"
    assert len(plot.plot_stabilisation(res.diagram).axes) == 2


def test_band_from_zero_hz_keeps_a_meaningful_synthesis_correlation(msys):
    """A band starting at 0 Hz made the residual terms infinite at DC and reported a
    measured-vs-synthesised correlation of 0 for an exact fit."""
    M, C, K = msys.chain(4)
    f = np.arange(0, 120, 0.2)
    h = modal.exact_frf(M, C, K, f, range(4), [0, 2], frf_type="mobility")
    res = modal.identify(h, 0.0)
    assert res.diagram.band_hz[0] == 0.0
    assert res.correlation.attrs["overall"] > 0.99
    assert (res.correlation.values > 0.99).all()
