"""Finite element modelling: sections, elements, meshes, assembly, solvers, piezo."""

from ._assembly import assemble_element_matrices, assemble_shell_model
from ._beam import BeamPatch, BeamSection, beam_section, cantilever_beam
from ._general import (
    GENERAL_SUPPORTS,
    BeamSet,
    PointMass,
    RigidLink,
    ShellSet,
    Spring,
    assemble_model,
    support_dofs,
)
from ._laminate import Laminate
from ._materials import IsotropicMaterial, OrthotropicMaterial, PiezoMaterial, Ply
from ._matrices import read_matrices
from ._mesh import (
    SUPPORT_TYPES,
    ModelSize,
    Patch,
    PlateMesh,
    edge_dofs,
    edge_tributary_lengths,
    estimate_plate_size,
    memory_limit_bytes,
    rectangular_plate_mesh,
    support_components,
)
from ._meshio import (
    BeamProperty,
    ImportedMesh,
    ShellSection,
    from_meshio,
    mesh_model,
    read_mesh,
    write_uff,
    write_vtu,
)
from ._modal import (
    ENERGY_PARTS,
    ModalResult,
    energy_split,
    modal_analysis,
    mode_type,
    static_solve,
)
from ._model import DOF_NAMES, FEModel
from ._nastran import read_nastran
from ._piezo import (
    PiezoPatch,
    edge_moment_load,
    neutral_axis,
    paper_eq7_moment_per_volt,
    piezo_moment_per_volt,
)
from ._plate import SpringSupport, plate_model
from ._sections import (
    box_section,
    generic_section,
    i_section,
    rectangle_section,
    tube_section,
)
from ._shell import DRILL_FACTOR, mitc4_matrices
from ._shell3d import TRI_SHEAR_ALPHA, mitc3_matrices, shell_element_matrices, shell_frames
from ._solvers import EigenSolution, eigsh_lowest, factorize
from ._structure import build_model, constrain_model, get_by_path, load_structure, set_by_path

__all__ = [
    "DOF_NAMES",
    "FEModel",
    "EigenSolution",
    "eigsh_lowest",
    "factorize",
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
    "energy_split",
    "ENERGY_PARTS",
    "GENERAL_SUPPORTS",
    "ShellSet",
    "BeamSet",
    "PointMass",
    "Spring",
    "RigidLink",
    "assemble_model",
    "support_dofs",
    "rectangle_section",
    "tube_section",
    "i_section",
    "box_section",
    "generic_section",
    "TRI_SHEAR_ALPHA",
    "ImportedMesh",
    "ShellSection",
    "BeamProperty",
    "read_mesh",
    "from_meshio",
    "mesh_model",
    "write_vtu",
    "write_uff",
    "read_matrices",
    "read_nastran",
    "constrain_model",
    "ModelSize",
    "estimate_plate_size",
    "memory_limit_bytes",
    "mitc3_matrices",
    "shell_element_matrices",
    "shell_frames",
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
