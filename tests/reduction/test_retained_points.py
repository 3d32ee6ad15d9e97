"""Retained points: snapped to the nearest node within the local element size, refused
off the structure, and two items on one node refused (issue 16)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError

pytest.importorskip("mvtk.fe._structure")
from mvtk.fe import build_model  # noqa: E402
from mvtk.reduction._config import (  # noqa: E402
    local_element_size,
    resolve_retained_config,
    snap_point,
    super_element_from_config,
)

ROOT = Path(__file__).resolve().parents[2]
SMART_BEAM = ROOT / "data" / "structures" / "smart_beam.toml"


@pytest.fixture(scope="module")
def model():
    d = tomllib.loads(SMART_BEAM.read_text())
    d["mesh"] = {"element_size": 0.015}
    return build_model(d)


def test_local_element_size_is_the_longest_adjacent_edge(model):
    node = model.nearest_node([0.12, 0.0665, 0.0])
    h = local_element_size(model, node)
    # the coarse mesh: 0.015 m elements (the patch edges make some shorter)
    assert 0.005 < h <= 0.015 * np.sqrt(2) + 1e-12


def test_point_on_the_structure_is_snapped_and_its_distance_reported(model):
    node, dist = snap_point(model, [0.121, 0.0665, 0.0], "p")
    assert np.isclose(dist, np.linalg.norm(model.nodes[node] - [0.121, 0.0665, 0.0]))
    pts = resolve_retained_config(model, [{"name": "s", "xyz": [0.121, 0.0665, 0.0]},
                                          {"name": "t", "node_set": "tip"}])
    assert pts[0].snap_distance_m == pytest.approx(dist) and pts[0].snap_distance_m > 0
    assert pts[1].snap_distance_m == 0.0


def test_point_off_the_structure_is_refused(model):
    """Issue 16: a retained point 5 m off a 0.18 m plate was snapped without a word."""
    with pytest.raises(ConfigError, match=r"reduction.retained\[0\]: point \[5.0, 0.0665, "
                                          r"0.0\] m is 4.82 m from the nearest node n\d+ .*"
                                          r"beyond the snap tolerance .* off the structure"):
        resolve_retained_config(model, [{"name": "far", "xyz": [5.0, 0.0665, 0.0]}])
    with pytest.raises(ConfigError, match="off the structure"):  # above the plate
        resolve_retained_config(model, [[0.1, 0.0665, 0.05]])


def test_two_points_on_one_node_are_refused(model):
    """Issue 16: two retained points that fell on one node were merged silently."""
    with pytest.raises(ConfigError, match=r"reduction.retained\[1\] \('b'\) and "
                                          r"reduction.retained\[0\] \('a'\) resolve to the "
                                          r"same node n\d+"):
        resolve_retained_config(model, [{"name": "a", "xyz": [0.12, 0.0665, 0.0]},
                                        {"name": "b", "xyz": [0.1201, 0.0665, 0.0]}])


def test_super_element_keeps_the_configured_order(model):
    se, pts = super_element_from_config(model, {
        "retained": [{"name": "tip", "node_set": "tip"},
                     {"name": "mid", "xyz": [0.09, 0.0665, 0.0]}], "n_modes": 2})
    assert [p.name for p in pts] == ["tip", "mid"]
    assert se.n_boundary == 12 and se.n_modes == 2
