"""Experimental and operational modal analysis.

FRF matrices (:func:`frf_matrix`, :func:`as_frf_matrix`, :func:`convert_frf`), poles by
pLSCF (:func:`plscf`) or SSI-cov (:func:`ssi_cov`) in a :class:`StabilisationDiagram`,
automatic or frequency-guided pole selection (:func:`select_poles`, :func:`poles_near`),
residues and shapes by LSFD (:func:`lsfd`), and the one-call :func:`identify` /
:func:`identify_output_only` returning :class:`IdentifiedModes` (table with quality,
shapes ``("mode", "dof")``, synthesised FRFs, AutoMAC). Export to UFF 55/58 with
:func:`write_uff`. Conventions: ``docs/conventions.md``; guide: ``docs/modal.md``.
"""

from ._export import write_frf_uff, write_modes_uff
from ._frf import (
    FRF_TYPES,
    as_frf_matrix,
    convert_frf,
    frf_matrix,
    frf_of_sets,
    merge_frf,
    reciprocal,
)
from ._identify import default_band, identify, own_lines
from ._lsfd import LsfdFit, lsfd, synthesise
from ._plscf import plscf
from ._quality import cmif, mac, mpc, mpd
from ._result import IdentifiedModes
from ._ssi import identify_output_only, ssi_cov
from ._stabilisation import (
    ClusterCriteria,
    SelectedPoles,
    StabilisationDiagram,
    StabilityCriteria,
    poles_near,
    select_poles,
)
from ._synthetic import exact_frf, exact_modes

__all__ = [
    "FRF_TYPES",
    "ClusterCriteria",
    "IdentifiedModes",
    "LsfdFit",
    "SelectedPoles",
    "StabilisationDiagram",
    "StabilityCriteria",
    "as_frf_matrix",
    "cmif",
    "convert_frf",
    "exact_frf",
    "exact_modes",
    "frf_matrix",
    "frf_of_sets",
    "identify",
    "own_lines",
    "default_band",
    "identify_output_only",
    "lsfd",
    "mac",
    "merge_frf",
    "mpc",
    "mpd",
    "plscf",
    "poles_near",
    "reciprocal",
    "select_poles",
    "ssi_cov",
    "synthesise",
    "write_frf_uff",
    "write_modes_uff",
]
