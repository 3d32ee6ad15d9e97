"""Finite element modelling: sections, elements, meshes, assembly, solvers, piezo."""

from ._materials import IsotropicMaterial, OrthotropicMaterial, PiezoMaterial, Ply
from ._model import DOF_NAMES, FEModel
from ._solvers import EigenSolution, eigsh_lowest, factorize

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
]
