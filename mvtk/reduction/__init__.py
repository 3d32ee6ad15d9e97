"""Craig-Bampton super elements, effective mass and FE-vs-SE verification tables.

Public API::

    craig_bampton(model, retained, n_modes, *, retained_dofs, mass_fraction, f_cut_hz)
    guyan(model, retained, *, retained_dofs)
    effective_mass(model_or_se, direction="uz", n_modes=20) -> EffectiveMassTable
    compare_modes / static_check / size_table / verify / mac
"""

from ._craig_bampton import SuperElement, craig_bampton, guyan
from ._effective_mass import EffectiveMassTable, effective_mass
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
]
