"""FE-vs-SE verification tables (paper Tables 4 and 5), MAC and static check."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtk.errors import DimensionError, ParameterError
from mvtk.reduction import (
    ModeComparison,
    compare_modes,
    craig_bampton,
    mac,
    size_table,
    static_check,
    verify,
)
from mvtk.reduction._craig_bampton import reduced_modes
from mvtk.reduction._examples import eb_beam_xz


@pytest.fixture(scope="module")
def beam():
    return eb_beam_xz(n_el=40)


def test_paper_table5_error_convention():
    """The paper's % errors (Table 5) are relative to the SE frequency."""
    fe = np.array([13.811, 42.673, 145.49, 150.16])
    se = np.array([14.249, 43.414, 152.54, 154.38])
    cmp = ModeComparison(fe_hz=fe, se_hz=se, mac_matrix=np.eye(4)[:, [1, 0, 2, 3]])
    np.testing.assert_array_equal(cmp.se_match, [2, 1, 3, 4])  # a swapped pair is flagged
    np.testing.assert_array_equal(cmp.mac_diagonal, [0, 0, 1, 1])
    np.testing.assert_allclose(np.round(cmp.error_pct_of_se, 2), [3.07, 1.71, 4.62, 2.73])
    np.testing.assert_allclose(cmp.error_pct, 100 * (se - fe) / fe)


def test_compare_modes_truncated(beam):
    se = craig_bampton(beam, ["mid", "tip"], 2)
    cmp = compare_modes(beam, se, 4)
    df = cmp.to_dataframe()
    assert list(df.columns) == ["mode", "fe_hz", "se_hz", "error_pct", "error_pct_of_se", "mac",
                                "se_match", "mac_match"]
    np.testing.assert_array_equal(cmp.se_match, [1, 2, 3, 4])
    assert np.all(cmp.error_pct >= -1e-8)
    assert cmp.error_pct[0] < 0.01 and cmp.error_pct[3] > 0.1
    assert np.all(cmp.mac_diagonal > 0.98)
    off = cmp.mac_matrix[:, :4] - np.diag(cmp.mac_diagonal)
    assert off.max() < 0.02 and cmp.mac_matrix.shape == (4, 6)  # all 6 SE modes


def test_compare_modes_all_kept_is_exact(beam):
    se = craig_bampton(beam, ["tip"], beam.n_dof - 2)
    cmp = compare_modes(None, se, 6)
    np.testing.assert_allclose(cmp.se_hz, cmp.fe_hz, rtol=1e-7)
    np.testing.assert_allclose(cmp.mac_diagonal, 1.0, atol=1e-8)


def test_mac_properties(rng):
    a = rng.standard_normal((20, 3))
    np.testing.assert_allclose(np.diag(mac(a, -3.0 * a)), 1.0)
    e = np.eye(4)
    np.testing.assert_allclose(mac(e, e), np.eye(4))
    assert mac(a[:, 0], a[:, 0]).shape == (1, 1)
    z = a + 1j * rng.standard_normal((20, 3))
    np.testing.assert_allclose(np.diag(mac(z, (2 - 1j) * z)), 1.0)
    with pytest.raises(DimensionError, match="same number of rows"):
        mac(a, a[:10])


def test_static_check_boundary_loads_exact(beam):
    se = craig_bampton(beam, ["mid", "tip"], 3)
    chk = static_check(beam, se)
    assert chk.labels == ("n20:uz", "n20:ry", "n40:uz", "n40:ry")
    assert chk.max_rel_error < 1e-8
    # an interior load is not reproduced exactly: the check can fail
    f = np.zeros(beam.n_dof)
    f[beam.dof_index(30, "uz")] = 1.0
    inner = static_check(beam, se, f)
    assert inner.rel_error_full[0] > 1e-4
    assert list(inner.to_dataframe().columns) == ["load", "rel_error_boundary",
                                                  "rel_error_full"]
    with pytest.raises(DimensionError, match=r"loads must have shape \(80, k\)"):
        static_check(beam, se, np.zeros(5))


def test_size_table_paper_shape(beam):
    se = craig_bampton(beam, ["clamp", "mid", "tip"], 3)
    st = size_table(beam, se)
    df = st.to_dataframe()
    assert list(df.index) == ["Number of nodes", "Number of elements", "DOF (free)",
                              "DOF (6 per node)"]
    assert df["FE model"].tolist() == [41, 40, 80, 246]
    # the clamp node counts as a retained node although all its DOFs are constrained
    assert df["SE model"].tolist() == [3, 1, 7, 21]


def test_verify_bundle_and_json(beam):
    se = craig_bampton(beam, ["mid", "tip"], 4)
    v = verify(beam, se, 3)
    assert len(v.to_dataframe()) == 3
    d = json.loads(json.dumps(v.to_dict()))
    assert set(d) == {"sizes", "modes", "static", "static_max_rel_error"}
    assert d["sizes"][2] == {"quantity": "DOF (free)", "fe": 80, "se": 8}
    assert d["static_max_rel_error"] < 1e-8


def test_bad_inputs(beam):
    se = craig_bampton(beam, ["tip"], 2)
    with pytest.raises(ParameterError, match=r"must be in 1..4 \(SE size\), got 5"):
        compare_modes(beam, se, 5)
    other = eb_beam_xz(n_el=10)
    with pytest.raises(DimensionError, match="model has 20 free DOFs"):
        compare_modes(other, se, 2)
    modal_only = craig_bampton(beam, "clamp", 3)
    with pytest.raises(ParameterError, match="no boundary DOF to load"):
        static_check(beam, modal_only)


def test_reduced_modes_with_massless_coordinate():
    K = np.array([[2.0, -1.0], [-1.0, 1.0]])
    M = np.diag([1.0, 0.0])  # second coordinate without inertia: condensed K = 1
    modes = reduced_modes(K, M)
    assert modes.n_massless == 1
    np.testing.assert_allclose(modes.omega2, [1.0])
    np.testing.assert_allclose(modes.vectors[:, 0], [1.0, 1.0])
    free = reduced_modes(np.array([[1.0, -1.0], [-1.0, 1.0]]), np.eye(2))  # rigid mode
    np.testing.assert_allclose(free.omega2, [0.0, 2.0], atol=1e-10)
    np.testing.assert_allclose(free.fn_hz, np.sqrt([0.0, 2.0]) / (2 * np.pi), atol=1e-6)


def test_shell_super_element_respects_upper_bound():
    """MITC4 plate SE: boundary drilling rotations have ~no inertia, M_r is singular to
    working precision; a naive eigh(K_r, M_r) put mode 2 below the FE value."""
    import tomllib
    from pathlib import Path

    from mvtk.fe import build_model

    text = (Path(__file__).resolve().parents[2] / "data" / "structures" /
            "smart_beam.toml").read_text().replace("element_size = 0.005",
                                                   "element_size = 0.01")
    model = build_model(tomllib.loads(text))
    pts = [[0.005, 0.0665, 0], [0.055, 0.0665, 0], [0.12, 0.0665, 0], [0.18, 0.0665, 0]]
    se = craig_bampton(model, pts, 10)
    assert reduced_modes(se.K, se.M).n_massless >= 1
    cmp = compare_modes(model, se, 5)
    assert np.all(cmp.error_pct >= -1e-9)
    assert np.all(cmp.error_pct < 0.2) and np.all(cmp.mac_diagonal > 0.999)
