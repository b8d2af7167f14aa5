"""Meshes that mix micro-structures, calibrated class by class.

A mesh without a generator recipe is calibrated on a periodic sample with its local
bond-length spread (:func:`.descriptors.local_spread`). Where its regions differ in
micro-structure (a structured region beside an unstructured one: the spread around
each node, :func:`.descriptors.spread_field`, varies by more than
:data:`.descriptors.MIXED_SPREAD` from its 10th to its 90th percentile), one spread serves
none of them: a regular lattice beside random points (3,845 nodes, uniaxial tension)
came out 8 % stiff on the lattice side and 2 % soft on the random side, 5.2 % (L2) from
P2 on the same triangles. Such a mesh's triangles are sorted into classes of their local
spread, and each class is calibrated on its own sample (the curves are cached, so
classes of equal spread in several meshes cost one sample): 1.4 % from P2 on that
mesh, each side's modulus within 0.6 %. A mesh whose percentiles do not differ that
much but that holds a *patch* of another micro-structure (:func:`.quality.patches`: a
connected region of at least 100 triangles whose local spread differs from the mesh's
by more than 0.1) is calibrated by class too: a disc of random points 30 spacings
across in a regular lattice (23,686 nodes) came out 8 % (DV) and 5 % (RV) soft
calibrated as the whole mesh, within 0.4 % by class.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...mesh import Mesh
from .descriptors import (
    DEFECT_RINGS,
    MIXED_SPREAD,
    deep_nodes,
    local_spread,
    node_degrees,
    relative_lengths,
    spread_field,
)
from .quality import patches

__all__ = [
    "CLASS_WIDTH",
    "MAX_CLASSES",
    "MicroField",
    "SpreadClasses",
    "calibrate_classes",
    "spread_classes",
]

#: width of a class in local spread (the relaxed moduli move by about 1 % per 0.05 of
#: spread on perturbed lattices)
CLASS_WIDTH = 0.1
#: at most this many classes (wider ones beyond)
MAX_CLASSES = 4


@dataclass(frozen=True)
class SpreadClasses:
    """The classes of a mesh that mixes micro-structures.

    Attributes
    ----------
    of_triangle : ndarray of int, shape (M,)
        Every triangle's class.
    spread : ndarray, shape (C,)
        Every class's local spread: the standard deviation of the relative bond
        lengths (:func:`.descriptors.relative_lengths`) of the bonds inside it.
    field : ndarray, shape (M,)
        The local spread around every triangle (the mean of its nodes'
        :func:`.descriptors.spread_field`) the classes were cut from.
    defects : ndarray, shape (C,)
        Every class's defect fraction (:func:`.descriptors.defect_fraction`): the share of
        its interior nodes (a node belongs to the class of most of its triangles) with
        other than six bonds.
    """

    of_triangle: np.ndarray
    spread: np.ndarray
    field: np.ndarray
    defects: np.ndarray

    @property
    def n_classes(self) -> int:
        return len(self.spread)


def spread_classes(mesh: Mesh) -> SpreadClasses | None:
    """The local-spread classes of a mesh without a reproducible recipe that mixes
    micro-structures (regions whose spread differs: :data:`.descriptors.MIXED_SPREAD`
    between the node field's 10th and 90th percentiles, or a patch,
    :func:`.quality.patches`); None for a mesh of one micro-structure (or with a
    recipe, or periodic), which one sample serves."""
    s = mesh.sampling
    if (s is not None and s.reproducible) or mesh.is_periodic:
        return None
    node = spread_field(mesh)
    lo, hi = np.percentile(node, [10, 90])
    if hi - lo <= MIXED_SPREAD and not patches(mesh, local_spread(mesh)):
        return None
    field = node[mesh.triangles].mean(axis=1)
    width = max(CLASS_WIDTH, float(np.ptp(field)) / MAX_CLASSES * (1 + 1e-9))
    _, cls = np.unique(np.floor((field - field.min()) / width), return_inverse=True)
    cls = cls.ravel()
    # a bond belongs to the class of its first triangle; bonds with a node on the
    # boundary are left out (as in local_spread), unless a class has too few others
    topo = mesh.topology
    bond_cls = cls[topo.bond_tris[:, 0]]
    on_boundary = np.zeros(mesh.n_points, dtype=bool)
    on_boundary[mesh.boundary_nodes] = True
    inner = ~(on_boundary[topo.bonds[:, 0]] | on_boundary[topo.bonds[:, 1]])
    ratio = relative_lengths(mesh)
    spread = np.empty(cls.max() + 1)
    for c in range(len(spread)):  # a handful of classes
        sel = bond_cls == c
        if np.count_nonzero(sel & inner) >= 30:
            sel = sel & inner
        spread[c] = float(np.std(ratio[sel]))
    cls.setflags(write=False)
    return SpreadClasses(cls, spread, field, _class_defects(mesh, cls, len(spread)))


def _class_defects(mesh: Mesh, cls: np.ndarray, n_classes: int) -> np.ndarray:
    """Every class's defect fraction, shape (C,), counted as
    :func:`.descriptors.defect_fraction` counts the mesh's."""
    degree = node_degrees(mesh)
    votes = np.zeros((mesh.n_points, n_classes))
    np.add.at(votes, (mesh.triangles.ravel(), np.repeat(cls, 3)), 1.0)
    node_cls = np.argmax(votes, axis=1)
    deep, off = deep_nodes(mesh, DEFECT_RINGS), deep_nodes(mesh, 0)
    out = np.zeros(n_classes)
    for c in range(n_classes):  # a handful of classes
        mine = node_cls == c
        sel = mine & deep if np.count_nonzero(mine & deep) >= 30 else mine & off
        out[c] = float(np.mean(degree[sel] != 6)) if sel.any() else 0.0
    return out


@dataclass(frozen=True)
class MicroField:
    """Micro-parameters triangle by triangle (a mesh calibrated class by class).

    Attributes
    ----------
    classes : SpreadClasses
    k_n, nu_m : ndarray, shape (M,)
        Every triangle's bond stiffness (units of E) and coupling coefficient.
    micros : dict
        ``(material, class) -> MicroParameters`` for every pair that occurs.
    """

    classes: SpreadClasses
    k_n: np.ndarray
    nu_m: np.ndarray
    micros: dict

    def restricted(self, triangles: np.ndarray) -> MicroField:
        """The field on the triangles ``triangles`` (global indices, shape (m,)), in
        their order: a patch of the mesh (the distributed engine's)."""
        c = self.classes
        sub = SpreadClasses(c.of_triangle[triangles], c.spread, c.field[triangles], c.defects)
        return MicroField(sub, self.k_n[triangles], self.nu_m[triangles], self.micros)

    def describe(self) -> str:
        """One line for the run summary."""
        s = self.classes.spread
        return (
            f"calibrated in {len(s)} classes of local spread "
            f"({float(s.min()):.3f} to {float(s.max()):.3f}): the mesh mixes micro-structures"
        )


def calibrate_classes(classes: SpreadClasses, material_of_triangle: np.ndarray, calibrate):
    """The :class:`MicroField` of ``classes``: ``calibrate(material, spread, defects)``
    gives the MicroParameters of every (material, class) pair that occurs."""
    n = len(material_of_triangle)
    k_n, nu_m = np.empty(n), np.empty(n)
    micros = {}
    pair = material_of_triangle * classes.n_classes + classes.of_triangle
    for key in np.unique(pair):  # materials x classes: a handful
        mat, c = divmod(int(key), classes.n_classes)
        micro = calibrate(mat, float(classes.spread[c]), float(classes.defects[c]))
        sel = pair == key
        k_n[sel], nu_m[sel] = micro.k_n, micro.nu_m
        micros[(mat, c)] = micro
    for a in (k_n, nu_m):
        a.setflags(write=False)
    return MicroField(classes, k_n, nu_m, micros)
