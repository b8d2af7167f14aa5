"""Node and dof orderings of meshes.

* :func:`spatial_order`: Morton (Z-order) curve, used by the generators so that
  neighbouring particles get nearby indices (narrow assembly chunks, cache locality in
  matrix-vector products and AMG).
* :func:`mesh_dof_order`: the fill-reducing nested-dissection order of direct
  factorisations (:func:`dvstatic.linalg.nested_dissection`), cached per mesh.
"""

from __future__ import annotations

import numpy as np

from .._cache import PerObject
from ..linalg import nested_dissection
from .core import Mesh

__all__ = ["spatial_order", "mesh_dof_order", "nested_dissection"]


def spatial_order(points: np.ndarray) -> np.ndarray:
    """Permutation that sorts points along a Morton (Z-order) curve.

    Neighbouring particles get nearby indices, which narrows the band of the
    stiffness matrix touched by each assembly chunk and improves cache use in
    matrix-vector products and AMG.
    """
    lo = points.min(axis=0)
    span = max(float(np.max(np.ptp(points, axis=0))), np.finfo(float).tiny)
    q = np.minimum(((points - lo) / span * 65535.0).astype(np.uint64), 65535)

    def spread(v: np.ndarray) -> np.ndarray:
        v = (v | (v << np.uint64(8))) & np.uint64(0x00FF00FF)
        v = (v | (v << np.uint64(4))) & np.uint64(0x0F0F0F0F)
        v = (v | (v << np.uint64(2))) & np.uint64(0x33333333)
        return (v | (v << np.uint64(1))) & np.uint64(0x55555555)

    key = spread(q[:, 0]) | (spread(q[:, 1]) << np.uint64(1))
    return np.argsort(key, kind="stable")


def _dof_order(mesh: Mesh) -> np.ndarray:
    nodes = nested_dissection(mesh.points, mesh.topology.bonds)
    o = np.stack([2 * nodes, 2 * nodes + 1], axis=1).reshape(-1)
    o.setflags(write=False)
    return o


_DOF_ORDER = PerObject("dof order", _dof_order)


def mesh_dof_order(mesh: Mesh) -> np.ndarray:
    """Interleaved dof permutation (2N,) from the nested-dissection node order (cached)."""
    if not isinstance(mesh, Mesh):
        raise TypeError(f"expected a dvstatic Mesh, got {type(mesh).__name__}")
    return _DOF_ORDER(mesh)
