"""Relative normal-spring stiffness of every bond (the ``bonds=`` option of the models)."""

from __future__ import annotations

import numpy as np

from .._checks import check_choice
from ..mesh import Mesh
from . import geometry as _geometry
from .geometry import Geometry

__all__ = ["BONDS", "MIN_WEIGHT", "voronoi_weights", "surface_weights", "bond_weights"]

#: bond weighting schemes: half springs on the surface (the default), the paper's
#: uniform springs, or springs weighted by their own Voronoi side
BONDS = ("surface", "uniform", "voronoi")
#: floor of the Voronoi bond weight (a bond whose dual side vanishes keeps a spring)
MIN_WEIGHT = 0.05


def voronoi_weights(geom: Geometry) -> np.ndarray:
    """Bond weights ``sqrt(3) r / l`` (1 on the regular lattice), floored at 0.05."""
    return np.maximum(np.sqrt(3.0) * geom.r / geom.length, MIN_WEIGHT)


def surface_weights(mesh: Mesh) -> np.ndarray:
    """Bond weights 1, and 1/2 on the boundary (bonds with one triangle): a boundary
    bond carries the spring of half a cell, as on the surface of a regular lattice."""
    return 0.5 * mesh.topology.n_tris_per_bond.astype(float)


def bond_weights(scheme: str, mesh: Mesh) -> np.ndarray:
    """Relative spring stiffness of every bond of ``mesh`` for ``scheme`` (one of
    :data:`BONDS`), shape (n_bonds,), read-only."""
    check_choice("bonds", scheme, BONDS)
    if scheme == "uniform":
        w = np.ones(mesh.n_bonds)
    elif scheme == "surface":
        w = surface_weights(mesh)
    else:
        w = voronoi_weights(_geometry.of(mesh))
    w.setflags(write=False)
    return w
