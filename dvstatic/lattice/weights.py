"""Relative normal-spring stiffness of every bond (the ``bonds=`` option of the models)."""

from __future__ import annotations

import numpy as np

from .._checks import check_choice
from .geometry import Geometry

__all__ = ["BONDS", "MIN_WEIGHT", "voronoi_weights", "bond_weights"]

#: bond weighting schemes: the paper's uniform springs, or springs weighted by their
#: own Voronoi side
BONDS = ("uniform", "voronoi")
#: floor of the Voronoi bond weight (a bond whose dual side vanishes keeps a spring)
MIN_WEIGHT = 0.05


def voronoi_weights(geom: Geometry) -> np.ndarray:
    """Bond weights ``sqrt(3) r / l`` (1 on the regular lattice), floored at 0.05."""
    return np.maximum(np.sqrt(3.0) * geom.r / geom.length, MIN_WEIGHT)


def bond_weights(scheme: str, geom: Geometry) -> np.ndarray:
    """Relative spring stiffness of every bond for ``scheme`` (one of :data:`BONDS`),
    shape (n_bonds,), read-only."""
    check_choice("bonds", scheme, BONDS)
    w = np.ones(len(geom.length)) if scheme == "uniform" else voronoi_weights(geom)
    w.setflags(write=False)
    return w
