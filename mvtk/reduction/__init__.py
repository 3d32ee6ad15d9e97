"""Craig-Bampton super elements, effective mass and FE-vs-SE verification tables.

Public API::

    craig_bampton(model, retained, n_modes, *, retained_dofs, mass_fraction, f_cut_hz)
    guyan(model, retained, *, retained_dofs)
    effective_mass(model_or_se, direction="uz", n_modes=20) -> EffectiveMassTable
    compare_modes / static_check / size_table / verify / mac
    reduced_modes(K, M)  (modes of a reduced pencil whose M may be singular)
    super_element_from_config(model, reduction_table) -> (SuperElement, retained points)
    with_electrodes(se, piezo_coupling) -> (SuperElement, B_r)  (piezo electrodes kept)
"""

from ._config import (
    RetainedPoint,
    local_element_size,
    resolve_retained_config,
    snap_point,
    super_element_from_config,
)
from ._craig_bampton import ReducedModes, SuperElement, craig_bampton, guyan, reduced_modes
from ._effective_mass import EffectiveMassTable, effective_mass
from ._electrodes import with_electrodes
from ._verify import (
    ModeComparison,
    SizeTable,
    StaticCheck,
    Verification,
    compare_modes,
    mac,
    size_table,
    static_check,
    verify,
)

__all__ = [
    "SuperElement",
    "craig_bampton",
    "guyan",
    "reduced_modes",
    "ReducedModes",
    "super_element_from_config",
    "resolve_retained_config",
    "snap_point",
    "local_element_size",
    "RetainedPoint",
    "EffectiveMassTable",
    "effective_mass",
    "ModeComparison",
    "SizeTable",
    "StaticCheck",
    "Verification",
    "compare_modes",
    "mac",
    "size_table",
    "static_check",
    "verify",
    "with_electrodes",
]
