"""The lattice: kinematics of triangles, reference geometry, sparse assembly, the
bond operator, bond weights, calibration and the DV/RV models (layer 2: imports the
foundation and the mesh layer only)."""

from . import calibration
from .geometry import Geometry
from .models import BONDS, DV, RV, VoronoiModel, check_model, voronoi_weights
from .operator import LatticeOperator, scatter_bond_forces, virial_sum

__all__ = [
    "calibration",
    "Geometry",
    "BONDS",
    "DV",
    "RV",
    "VoronoiModel",
    "check_model",
    "voronoi_weights",
    "LatticeOperator",
    "scatter_bond_forces",
    "virial_sum",
]
