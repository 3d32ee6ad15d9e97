"""Test-analysis correlation: test geometry, DOF mapping, MAC family, expansion, pretest.

- :func:`correlate` -> :class:`CorrelationResult`: the one call of a study stage;
- :func:`read_test_geometry` / :class:`TestGeometry`: nodes, coordinate systems, trace
  lines and sensor DOFs from UFF (15, 2411, 18, 2420, 82, 2412; Cartesian, cylindrical
  and spherical systems), TOML or CSV;
- :func:`map_sensors` -> :class:`DofMapping`: sensors onto an FE model (nearest node or
  element shape functions), FE shapes projected on the sensor axes;
- :func:`mac`, :func:`comac`, :func:`ecomac`, :func:`msf`, :func:`cross_orthogonality`
  with :func:`guyan_tam` / :func:`serep_tam`, :func:`frac`, :func:`csac`, :func:`csf`,
  :func:`synthesize_frf`; :func:`pair_modes` -> :class:`ModePairing`;
- :func:`expand_serep`, :func:`expand_lsq` -> :class:`ExpansionResult`;
- :func:`effective_independence`, :func:`kinetic_energy_placement`,
  :func:`exciter_placement` -> :class:`PlacementResult`.

Shapes are ``("mode", "dof")`` DataArrays (``docs/conventions.md``).
"""

from ._correlate import CorrelationResult, correlate
from ._expansion import ExpansionResult, expand_lsq, expand_serep
from ._fe_adapter import fe_node_ids, fe_shapes
from ._geometry import (
    CS_KINDS,
    DIRECTIONS,
    CoordinateSystem,
    Sensor,
    TestGeometry,
    direction_label,
    read_test_geometry,
)
from ._mapping import DofMapping, map_sensors, shape_functions
from ._metrics import (
    automac,
    comac,
    cross_orthogonality,
    csac,
    csf,
    ecomac,
    frac,
    guyan_tam,
    mac,
    msf,
    serep_tam,
    synthesize_frf,
)
from ._pairing import ModePairing, pair_modes
from ._pretest import (
    PlacementResult,
    candidate_geometry,
    effective_independence,
    exciter_placement,
    kinetic_energy_placement,
    placement_quality,
)
from ._shapes import read_test_shapes, shapes_at_sensors

__all__ = [
    "CorrelationResult",
    "correlate",
    "DIRECTIONS",
    "CS_KINDS",
    "CoordinateSystem",
    "Sensor",
    "TestGeometry",
    "direction_label",
    "read_test_geometry",
    "read_test_shapes",
    "shapes_at_sensors",
    "fe_node_ids",
    "fe_shapes",
    "DofMapping",
    "map_sensors",
    "shape_functions",
    "mac",
    "automac",
    "comac",
    "ecomac",
    "msf",
    "guyan_tam",
    "serep_tam",
    "cross_orthogonality",
    "frac",
    "csac",
    "csf",
    "synthesize_frf",
    "ModePairing",
    "pair_modes",
    "ExpansionResult",
    "expand_serep",
    "expand_lsq",
    "PlacementResult",
    "candidate_geometry",
    "effective_independence",
    "kinetic_energy_placement",
    "exciter_placement",
    "placement_quality",
]
