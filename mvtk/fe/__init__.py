"""Finite element modelling: sections, elements, meshes, assembly, solvers, piezo."""

from ._assembly import (
    SparsityPattern,
    assemble_element_matrices,
    assemble_shell_model,
    sparsity_pattern,
)
from ._beam import BeamPatch, BeamSection, beam_section, cantilever_beam
from ._laminate import Laminate
from ._materials import IsotropicMaterial, OrthotropicMaterial, PiezoMaterial, Ply
from ._mesh import (
    SUPPORT_TYPES,
    Patch,
    PlateMesh,
    edge_dofs,
    edge_tributary_lengths,
    rectangular_plate_mesh,
    support_components,
)
from ._modal import ModalResult, modal_analysis, mode_type, static_solve
from ._model import DOF_NAMES, FEModel
from ._piezo import (
    PiezoPatch,
    edge_moment_load,
    neutral_axis,
    paper_eq7_moment_per_volt,
    piezo_moment_per_volt,
)
from ._plate import SpringSupport, plate_model
from ._shell import DRILL_FACTOR, mitc4_matrices
from ._solvers import (
    EigenSolution,
    Factorization,
    MemoryEstimate,
    eigsh_lowest,
    estimate_eigen_memory,
    factorize,
    fill_reducing_ordering,
)
from ._structure import build_model, get_by_path, load_structure, set_by_path

__all__ = [
    "DOF_NAMES",
    "FEModel",
    "EigenSolution",
    "eigsh_lowest",
    "factorize",
    "Factorization",
    "fill_reducing_ordering",
    "estimate_eigen_memory",
    "MemoryEstimate",
    "SparsityPattern",
    "sparsity_pattern",
    "IsotropicMaterial",
    "OrthotropicMaterial",
    "PiezoMaterial",
    "Ply",
    "Laminate",
    "DRILL_FACTOR",
    "mitc4_matrices",
    "Patch",
    "PlateMesh",
    "rectangular_plate_mesh",
    "SUPPORT_TYPES",
    "support_components",
    "edge_dofs",
    "edge_tributary_lengths",
    "assemble_shell_model",
    "assemble_element_matrices",
    "SpringSupport",
    "plate_model",
    "ModalResult",
    "modal_analysis",
    "mode_type",
    "static_solve",
    "build_model",
    "load_structure",
    "get_by_path",
    "set_by_path",
    "BeamPatch",
    "BeamSection",
    "beam_section",
    "cantilever_beam",
    "PiezoPatch",
    "edge_moment_load",
    "neutral_axis",
    "paper_eq7_moment_per_volt",
    "piezo_moment_per_volt",
]
