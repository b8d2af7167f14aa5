"""Descriptors of a mesh's micro-structure, read by the relaxed calibration
(:mod:`.relaxed`), its classes (:mod:`.classes`) and its quality flags
(:mod:`.quality`).

* the **local spread** (:func:`local_spread`): the spread of the bond lengths relative
  to the local spacing (scale-free: a graded mesh of regular cells scores as its cells),
  and its field around every node (:func:`spread_field`);
* the **defect fraction** (:func:`defect_fraction`): the share of interior nodes with
  other than six bonds (0 on perturbed lattices, 0.14-0.21 on CVT-like cells, 0.70 on
  random points);
* the **fabric anisotropy** (:func:`fabric_anisotropy`): the deviator of the bonds'
  fabric tensor around every node (0 on a regular lattice, at most 0.07 on CVT, 0.16 on
  random points, 0.25 on a square grid split by parallel diagonals).

The per-mesh values are kept (weakly) for the mesh's life: meshes are immutable.
"""

from __future__ import annotations

import weakref

import numpy as np

from ...mesh import Mesh
from ..weights import FABRIC_RINGS, node_fabric

__all__ = [
    "DEFECT_RINGS",
    "MIXED_SPREAD",
    "deep_nodes",
    "defect_fraction",
    "fabric_anisotropy",
    "interior_spread",
    "local_spread",
    "node_degrees",
    "relative_lengths",
    "ring_mean",
    "spread_field",
]


def interior_spread(mesh: Mesh) -> float:
    """sigma_L over the bonds whose end nodes are both off the boundary."""
    lengths = mesh.bond_lengths()
    if not mesh.is_periodic:
        bnd = np.zeros(mesh.n_points, dtype=bool)
        bnd[mesh.boundary_nodes] = True
        b = mesh.topology.bonds
        inner = ~(bnd[b[:, 0]] | bnd[b[:, 1]])
        if inner.sum() >= 30:
            lengths = lengths[inner]
    return float(np.std(lengths) / np.mean(lengths))


def relative_lengths(mesh: Mesh) -> np.ndarray:
    """Every bond's length over the mean of the mean bond lengths at its two nodes,
    shape (n_bonds,) (kept per mesh, read-only)."""
    cache = _FIELDS.setdefault(mesh, {})
    if "ratio" not in cache:
        b = mesh.topology.bonds
        lengths = mesh.bond_lengths()
        n = mesh.n_points
        total = np.bincount(b[:, 0], lengths, n) + np.bincount(b[:, 1], lengths, n)
        count = np.bincount(b[:, 0], None, n) + np.bincount(b[:, 1], None, n)
        h = total / np.maximum(count, 1)
        ratio = lengths / (0.5 * (h[b[:, 0]] + h[b[:, 1]]))
        ratio.setflags(write=False)
        cache["ratio"] = ratio
    return cache["ratio"]


#: per mesh (weakly): the relative bond lengths, the defect fraction, the deep nodes
#: and the squared-deviation field smoothed over 0 and more rings
_FIELDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def local_spread(mesh: Mesh) -> float:
    """The spread of the bond lengths relative to the local spacing: the standard
    deviation, over the interior bonds (both end nodes off the boundary; all bonds if
    fewer than 30), of every bond's length divided by the mean of the mean bond lengths
    at its two nodes. Scale-free, so a graded mesh of regular cells scores as its
    cells do, not as its grading."""
    b = mesh.topology.bonds
    n = mesh.n_points
    ratio = relative_lengths(mesh)
    if not mesh.is_periodic:
        bnd = np.zeros(n, dtype=bool)
        bnd[mesh.boundary_nodes] = True
        inner = ~(bnd[b[:, 0]] | bnd[b[:, 1]])
        if inner.sum() >= 30:
            ratio = ratio[inner]
    return float(np.std(ratio))


#: nodes more than this many rings from the boundary count in :func:`defect_fraction`
#: (the boundary's rows have other numbers of neighbours by construction)
DEFECT_RINGS = 3


def defect_fraction(mesh: Mesh) -> float:
    """The share of interior nodes with other than six bonds: 0 on a perturbed
    lattice of small moves, 0.13-0.21 on CVT-like meshes (gmsh's graded meshes,
    Lloyd-relaxed points), 0.70 on random points. Interior: more than
    :data:`DEFECT_RINGS` rings from the boundary (every node of a periodic mesh; all
    nodes off the boundary where fewer than 30 are that deep). Kept per mesh."""
    cache = _FIELDS.setdefault(mesh, {})
    if "defects" not in cache:
        degree = node_degrees(mesh)
        if mesh.is_periodic:
            cache["defects"] = float(np.mean(degree != 6))
        else:
            inner = deep_nodes(mesh, DEFECT_RINGS)
            if np.count_nonzero(inner) < 30:
                inner = deep_nodes(mesh, 0)
            cache["defects"] = float(np.mean(degree[inner] != 6)) if inner.any() else 0.0
    return cache["defects"]


def node_degrees(mesh: Mesh) -> np.ndarray:
    """Every node's number of bonds, shape (N,)."""
    b = mesh.topology.bonds
    n = mesh.n_points
    return np.bincount(b[:, 0], None, n) + np.bincount(b[:, 1], None, n)


def deep_nodes(mesh: Mesh, rings: int) -> np.ndarray:
    """The nodes more than ``rings`` rings from the boundary (0: off the boundary),
    bool, shape (N,), read-only; all nodes of a periodic mesh. Kept per mesh."""
    cache = _FIELDS.setdefault(mesh, {})
    key = ("deep", int(rings))
    if key not in cache:
        n = mesh.n_points
        if mesh.is_periodic:
            deep = np.ones(n, dtype=bool)
        else:
            near = np.zeros(n)
            near[mesh.boundary_nodes] = 1.0
            if rings:
                step = mesh.topology.ring_step(n)
                for _ in range(rings):
                    near = step @ near
            deep = near == 0
        deep.setflags(write=False)
        cache[key] = deep
    return cache[key]


def ring_mean(mesh: Mesh, node_values: np.ndarray, rings: int) -> np.ndarray:
    """``node_values`` (N,) or (N, k) averaged ``rings`` times over every node and its
    neighbours, same shape."""
    node = np.asarray(node_values, dtype=float)
    if rings:
        step = mesh.topology.ring_step(mesh.n_points)
        deg = np.asarray(step.sum(axis=1)).ravel()
        deg = deg if node.ndim == 1 else deg[:, None]
        for _ in range(rings):
            node = (step @ node) / deg
    return node


#: a mesh whose local spread varies by more than this between its regions (10th to
#: 90th percentile of the node field) mixes micro-structures: the models calibrate it
#: class by class (:mod:`.classes`; measured: 0.07 on a gmsh plate graded 0.04 -> 0.24,
#: 0.40 on a lattice beside random points)
MIXED_SPREAD = 0.15


def spread_field(mesh: Mesh, rings: int = 2) -> np.ndarray:
    """The local spread around every node, shape (N,): the rms deviation from 1 of the
    relative lengths (as in :func:`local_spread`) of the bonds within ``rings`` rings.

    Kept per mesh (the classes, their trigger and the calibration flags read 2 and 4
    rings of the same field: each ring is smoothed once)."""
    return np.sqrt(_smoothed_dev2(mesh, rings))


def _smoothed_dev2(mesh: Mesh, rings: int) -> np.ndarray:
    cache = _FIELDS.setdefault(mesh, {})
    if 0 not in cache:
        b = mesh.topology.bonds
        n = mesh.n_points
        dev2 = (relative_lengths(mesh) - 1.0) ** 2
        node = (np.bincount(b[:, 0], dev2, n) + np.bincount(b[:, 1], dev2, n)) / np.maximum(
            node_degrees(mesh), 1
        )
        node.setflags(write=False)
        cache[0] = node
    done = max(k for k in cache if isinstance(k, int) and k <= rings)
    if done < rings:  # the ring step is not kept (it is most of the memory)
        node = ring_mean(mesh, cache[done], rings - done)
        node.setflags(write=False)
        cache[rings] = node
    return cache[rings]


def fabric_anisotropy(mesh: Mesh, rings: int = FABRIC_RINGS) -> np.ndarray:
    """The magnitude of the deviator of the bonds' fabric tensor
    (:func:`..weights.node_fabric`, uniform springs, over ``rings`` rings) around every
    node, shape (N,): 0 for an isotropic fabric, 0.5 for bonds all along one direction.
    Measured (largest node value more than 8 rings from the boundary): regular lattice
    0, jittered 0.016, CVT 0.070, random points 0.159, gmsh meshes 0.012-0.067, a square
    grid split by parallel diagonals 0.25 (alternating diagonals: 0)."""
    a = node_fabric(mesh, np.ones(mesh.n_bonds), rings)
    return np.hypot(0.5 * (a[:, 0] - a[:, 2]), a[:, 1])
