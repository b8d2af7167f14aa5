"""Relative normal-spring stiffness of every bond (the ``bonds=`` option of the models)."""

from __future__ import annotations

import logging

import numpy as np

from .._cache import PerObject
from .._checks import check_choice
from ..errors import InputError
from ..mesh import Mesh
from . import geometry as _geometry
from .geometry import Geometry

log = logging.getLogger(__name__)

__all__ = [
    "BONDS",
    "MIN_WEIGHT",
    "FABRIC_MIN",
    "FABRIC_CLIP_SHARE",
    "FABRIC_CLIP_FEW",
    "FABRIC_RINGS",
    "FABRIC_KINDS",
    "voronoi_weights",
    "surface_weights",
    "fabric_factors",
    "node_fabric",
    "bond_weights",
    "mixed_springs",
    "default_bonds",
    "resolve_bonds",
]

#: bond weighting schemes: half springs on the surface (the default on lattices,
#: jittered and imported meshes: :func:`default_bonds`), the same corrected for the
#: local fabric, the paper's uniform springs, or springs weighted by their own Voronoi
#: side
BONDS = ("surface", "fabric", "uniform", "voronoi")
#: floor of the Voronoi bond weight (a bond whose dual side vanishes keeps a spring)
MIN_WEIGHT = 0.05
#: the fabric is averaged over this many rings of neighbours (about this many spacings)
FABRIC_RINGS = 6
#: the fabric correction refuses a mesh whose springs it would scale below this (a
#: fabric deviator of about 0.22; CVT and random points reach 0.07 and 0.16)
FABRIC_MIN = 0.1
#: up to this share of the bonds, or FABRIC_CLIP_FEW of them (a few bonds at a random
#: mesh's corner), the factors are clipped at FABRIC_MIN instead of refused
FABRIC_CLIP_SHARE = 1e-3
FABRIC_CLIP_FEW = 3
#: point-set kinds whose uniform meshes take the fabric springs by default
FABRIC_KINDS = ("cvt", "random")


def voronoi_weights(geom: Geometry) -> np.ndarray:
    """Bond weights ``sqrt(3) r / l`` (1 on the regular lattice), floored at 0.05."""
    return np.maximum(np.sqrt(3.0) * geom.r / geom.length, MIN_WEIGHT)


def surface_weights(mesh: Mesh) -> np.ndarray:
    """Bond weights 1, and 1/2 on the boundary (bonds with one triangle): a boundary
    bond carries the spring of half a cell, as on the surface of a regular lattice."""
    return 0.5 * mesh.topology.n_tris_per_bond.astype(float)


def fabric_factors(mesh: Mesh, weights: np.ndarray, rings: int = FABRIC_RINGS) -> np.ndarray:
    """Factors ``1 - 4 n.D.n`` (shape (n_bonds,)) that take the local anisotropy out
    of the springs' fabric.

    ``D`` is the deviator of the fabric tensor ``a = sum w l^2 n n / sum w l^2`` (the
    springs' share of the affine stiffness, by direction; summed over the three edges
    of every triangle with the triangle's share of each spring, so that a graded mesh
    of equilateral cells has an isotropic fabric) of the triangles within ``rings``
    rings of the bond's two ends; triangles with a boundary edge (cut to fit the
    boundary) take no part. For a fabric density ``1 + e cos 2(t - t0)``
    the factor is ``1 - e cos 2(t - t0)``: isotropic to first order in ``e``. A regular
    lattice has an isotropic fabric (factors 1); a graded mesh's cells are stretched
    along its grading, a CVT or random point set has patches of either orientation.

    Parameters
    ----------
    mesh : Mesh
    weights : ndarray, shape (n_bonds,)
        Spring weights to correct (:func:`surface_weights`).
    rings : int
        Averaging scale, in rings of neighbours.

    Raises
    ------
    InputError
        Where more than :data:`FABRIC_CLIP_SHARE` of the factors (and more than
        :data:`FABRIC_CLIP_FEW`) would fall below :data:`FABRIC_MIN` (a fabric too
        anisotropic to correct: the message says where); fewer are clipped at
        :data:`FABRIC_MIN` (logged).
    """
    b = mesh.topology.bonds
    d = _geometry.of(mesh).direction
    a = node_fabric(mesh, weights, rings)
    a = 0.5 * (a[b[:, 0]] + a[b[:, 1]])
    half = 0.5 * (a[:, 0] - a[:, 2])  # the deviator is [[half, a01], [a01, -half]]
    q = (d[:, 0] ** 2 - d[:, 1] ** 2) * half + 2.0 * d[:, 0] * d[:, 1] * a[:, 1]
    factors = 1.0 - 4.0 * q
    low = factors < FABRIC_MIN
    if not low.any():
        return factors
    worst = int(np.argmin(factors))
    x, y = mesh.points[b[worst]].mean(axis=0)
    where = f"near ({x:.4g}, {y:.4g}) (deviator {np.hypot(half[worst], a[worst, 1]):.3f})"
    if low.sum() <= max(FABRIC_CLIP_FEW, FABRIC_CLIP_SHARE * len(factors)):
        log.info(
            "bonds='fabric': %d of %d bonds clipped at %g of their springs (the worst "
            "would fall to %.3g, %s)",
            low.sum(),
            len(factors),
            FABRIC_MIN,
            factors[worst],
            where,
        )
        return np.maximum(factors, FABRIC_MIN)
    raise InputError(
        f"bonds='fabric' cannot correct this mesh's fabric: it is too anisotropic at "
        f"{low.sum()} of {len(factors)} bonds, the worst {where}; the correction needs "
        f"a deviator below about {(1 - FABRIC_MIN) / 4:.3f}; the springs there would "
        f"fall to {factors[worst]:.3g} of theirs (a square grid split by parallel "
        "diagonals: 0.25); use bonds='surface' (and expect anisotropic moduli) or remesh",
        "bonds",
    )


def node_fabric(mesh: Mesh, weights: np.ndarray, rings: int = FABRIC_RINGS) -> np.ndarray:
    """The springs' fabric tensor ``a = sum w l^2 n n / sum w l^2`` around every node,
    ``(a_xx, a_xy, a_yy)``, shape (N, 3): every triangle's share of the springs (all
    three edges; triangles with a boundary edge take no part), summed over the
    triangles within ``rings`` rings (see :func:`fabric_factors`). Isotropic: a_xx =
    a_yy = 1/2, a_xy = 0."""
    g = _geometry.of(mesh)
    n = mesh.n_points
    tb = mesh.topology.tri_bonds
    w = g.tri_weight * np.asarray(weights, dtype=float)[tb] * g.tri_l**2
    w[(mesh.topology.n_tris_per_bond[tb] == 1).any(axis=1)] = 0.0
    dt = g.direction[tb]
    parts = np.stack([w * dt[..., 0] ** 2, w * dt[..., 0] * dt[..., 1], w * dt[..., 1] ** 2, w])
    tri = parts.sum(axis=2).T  # (m, 4)
    node = np.zeros((n, 4))
    for c in range(4):
        node[:, c] = np.bincount(mesh.triangles.ravel(), np.repeat(tri[:, c], 3), n)
    step = mesh.topology.ring_step(n)
    for _ in range(rings):
        node = step @ node
    return node[:, :3] / np.maximum(node[:, 3:], np.finfo(float).tiny)


def default_bonds(mesh: Mesh) -> str:
    """The spring scheme a model takes on ``mesh`` by default (``bonds="auto"``):
    ``"fabric"`` on the generators' graded meshes (a size field: their cells are
    stretched along the grading, and over seeds the fabric correction keeps a tunnel
    wall's mean displacement within 0.6 % where the plain springs scatter by -5 to
    +3 %) and on their CVT and random point sets (patches of either orientation: over
    seeds it halves Cook's tip error at 4e3-1.6e4 nodes and lowers Kirsch's peak error
    on CVT; mixed on the cantilever and on LE1 with random points; docs/validation.md);
    ``"surface"`` on lattices, jittered lattices (an isotropic fabric), imported meshes
    (on a strongly graded gmsh plate the fabric triples the L2 error), and wherever the
    fabric is too anisotropic to correct (logged as a warning). Kept per mesh."""
    return _AUTO(mesh)


def resolve_bonds(bonds: str, mesh: Mesh) -> str:
    """``bonds`` checked (one of :data:`BONDS` or ``"auto"``), ``"auto"`` resolved for
    ``mesh`` (:func:`default_bonds`)."""
    check_choice("bonds", bonds, ("auto",) + BONDS)
    return default_bonds(mesh) if bonds == "auto" else bonds


def _auto_scheme(mesh: Mesh) -> str:
    s = mesh.sampling
    if s is None or not (s.graded or s.kind in FABRIC_KINDS):
        return "surface"
    try:
        _FABRIC(mesh)
    except InputError as exc:
        log.warning("bonds='auto' keeps the surface springs on this mesh: %s", exc)
        return "surface"
    return "fabric"


def _fabric_weights(mesh: Mesh) -> np.ndarray:
    w = surface_weights(mesh)
    w = w * fabric_factors(mesh, w)
    w.setflags(write=False)
    return w


_AUTO = PerObject("default bonds", _auto_scheme)
_FABRIC = PerObject("fabric weights", _fabric_weights)


def bond_weights(scheme: str, mesh: Mesh) -> np.ndarray:
    """Relative spring stiffness of every bond of ``mesh`` for ``scheme`` (one of
    :data:`BONDS`), shape (n_bonds,), read-only."""
    check_choice("bonds", scheme, BONDS)
    if scheme == "uniform":
        w = np.ones(mesh.n_bonds)
    elif scheme == "surface":
        w = surface_weights(mesh)
    elif scheme == "fabric":
        return _FABRIC(mesh)  # kept per mesh: read again by bonds="auto" and the ranks
    else:
        w = voronoi_weights(_geometry.of(mesh))
    w.setflags(write=False)
    return w


def mixed_springs(geom: Geometry, mesh: Mesh, k_tri: np.ndarray) -> np.ndarray:
    """Spring stiffness of every bond from its triangles' ``k_tri`` (M,), each in
    proportion to its (non-negative) share of the bond's Voronoi side; equal shares
    where the side vanishes. Shape (n_bonds,)."""
    topo = mesh.topology
    bt, bl = topo.bond_tris, topo.bond_local
    two = bt[:, 1] >= 0
    r1 = np.maximum(geom.tri_r[bt[:, 0], bl[:, 0]], 0.0)
    t2, l2 = np.maximum(bt[:, 1], 0), np.maximum(bl[:, 1], 0)
    r2 = np.where(two, np.maximum(geom.tri_r[t2, l2], 0.0), 0.0)
    total = r1 + r2
    s1 = np.where(total > 0, r1 / np.where(total > 0, total, 1.0), np.where(two, 0.5, 1.0))
    k2 = np.where(two, k_tri[t2], 0.0)
    return s1 * k_tri[bt[:, 0]] + (1.0 - s1) * k2
