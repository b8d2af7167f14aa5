"""Exact boundary cells: the triangles at the boundary carry the continuum's tensor.

Each linear DV/RV triangle is a P1 element with its own tensor ``C_T = E_T^T Q_T E_T /
A_T`` (:func:`dvstatic.lattice.stabilise.triangle_tensors`): ``E_T`` (3 bonds, 3 Mandel
strains) holds the elongations of its bonds per unit strain, ``E_T[k] = l_k (nx^2, ny^2,
sqrt(2) nx ny)``, and ``Q_T`` (3, 3) its bond matrix (springs and coupling). Inside a
regular or relaxed lattice ``C_T`` is right on average; the triangles cut to fit a
boundary are not (at a curved boundary their mean is up to 20 % too stiff:
``validation/boundary_layer.py``), and that layer carries most of the lattice's
displacement error and the stress error at a hole's wall.

An *exact cell* adds to its triangle the bond matrix ``dQ_T = A_T E_T^-T C E_T^-1 - Q_T``,
so that its tensor is the isotropic ``C`` of its material: the triangle is exactly P1.
The term acts on the triangle's three bond elongations ``e`` (the exact ones, ``l' -
l``, in the nonlinear model): an energy ``e.dQ e / 2`` whose tensions ``dQ e`` add to
the bonds' own, so forces, tangent, stresses and fracture criteria read it as any other
part of the tension. A damaged cell keeps ``min(d)`` of it, as of its Voronoi coupling
(:mod:`dvstatic.lattice.damage`): a cracked cell falls back to its springs.

The cells reach :data:`CELL_RINGS` = 3 rings of bonds into the body (four layers of
triangles). The relaxed calibration holds where a triangle's neighbours relax with it
on every side; near a boundary they do not, and a mesher's boundary rows meet its
interior in a disordered zone about three rings deep (gmsh: ring spread 0.067 / 0.061
/ 0.038 against 0.004 inside). One layer of cells left a uniform gmsh ring's Lame
displacement 1.18 % off at 7,174 nodes and Cook's membrane 1.1 % stiff; four layers
give 0.22 % and 0.37 % (docs/theory.md 8.2b).

Slivers (smallest angle below about 3 degrees, :data:`CELL_SINE`) stay lattice
triangles: their ``E_T`` is near singular.
"""

from __future__ import annotations

import logging

import numpy as np

from ..mesh import Mesh
from . import geometry as _geometry
from .kinematics import edge_frames
from .stabilise import reference_matrices

__all__ = [
    "BOUNDARY_CELLS",
    "CELL_RINGS",
    "boundary_triangles",
    "exact_cells",
    "isotropic_tensor",
    "unit_elongations",
    "cell_corrections",
    "cell_tensors",
]

#: choices of ``boundary_cells`` of :class:`dvstatic.DV` / :class:`dvstatic.RV`
BOUNDARY_CELLS = ("exact", "lattice")
#: triangles whose smallest angle has a sine below this (about 3 degrees) stay lattice
#: triangles: ``E_T^-1`` grows as 1 / sine and would make the cell needlessly stiff
CELL_SINE = 0.05
#: the cells reach this many rings of bonds into the body (:func:`boundary_triangles`):
#: four layers of triangles, the boundary's own and three more
CELL_RINGS = 3

log = logging.getLogger(__name__)


def boundary_triangles(mesh: Mesh, rings: int = CELL_RINGS) -> np.ndarray:
    """Indices of the triangles with a vertex at most ``rings`` rings of bonds from the
    mesh's boundary (holes, inner boundaries and straight edges alike; 0: a vertex on
    it), slivers (:data:`CELL_SINE`) left out, shape (k,) int; empty for periodic
    meshes."""
    if mesh.is_periodic:
        return np.zeros(0, dtype=np.int64)
    near = np.zeros(mesh.n_points, dtype=bool)
    near[mesh.boundary_nodes] = True
    b = mesh.topology.bonds
    for _ in range(rings):
        step = near[b[:, 0]] | near[b[:, 1]]
        near[b[step].ravel()] = True
    sine = _geometry.smallest_sine(_geometry.of(mesh))
    return np.flatnonzero(near[mesh.triangles].any(axis=1) & (sine >= CELL_SINE))


def exact_cells(mesh: Mesh) -> np.ndarray:
    """The models' exact cells: :func:`boundary_triangles` :data:`CELL_RINGS` deep, shape
    (k,) int; logged when they are more than 90 % of the triangles (a body less than
    about eight spacings across is then P1 but for its middle)."""
    cells = boundary_triangles(mesh)
    if len(cells) > 0.9 * mesh.n_triangles:
        log.info(
            "%d of the %d triangles are exact cells (within %d rings of the boundary): the "
            "body is P1 but for %d; boundary_cells='lattice' keeps the lattice",
            len(cells),
            mesh.n_triangles,
            CELL_RINGS,
            mesh.n_triangles - len(cells),
        )
    return cells


def isotropic_tensor(E: float, nu: float) -> np.ndarray:
    """The in-plane isotropic tensor (Mandel, (3, 3), units of E) of the in-plane
    constants ``E``, ``nu`` (plane stress; plane strain passes ``E*``, ``nu*``)."""
    c = E / (1.0 - nu * nu)
    return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 1.0 - nu]])


def unit_elongations(mesh: Mesh, idx: np.ndarray) -> np.ndarray:
    """``E_T`` (k, 3 bonds, 3 Mandel strains) of triangles ``idx``: the elongation of
    every local bond per unit strain (length units)."""
    _, length, n = edge_frames(_geometry.of(mesh).x_tri[idx])
    nm = np.stack([n[..., 0] ** 2, n[..., 1] ** 2, np.sqrt(2.0) * n[..., 0] * n[..., 1]], -1)
    return length[..., None] * nm


def cell_corrections(
    mesh: Mesh,
    idx: np.ndarray,
    spring: np.ndarray,
    coupling: np.ndarray,
    barycentric: bool,
    tensors: np.ndarray,
) -> np.ndarray:
    """``dQ_T = A_T E_T^-T C_T E_T^-1 - Q_T`` of triangles ``idx``, shape (k, 3, 3).

    Parameters
    ----------
    mesh : Mesh
    idx : ndarray of int, shape (k,)
        The cells (:func:`boundary_triangles`).
    spring : ndarray, shape (n_bonds,)
        Spring stiffness of every bond (force / length).
    coupling : ndarray, shape (M,)
        Coupling stiffness of every triangle (force / length).
    barycentric : bool
        DV (True) or RV (False).
    tensors : ndarray, shape (k, 3, 3) or (3, 3)
        The tensor each cell is to have (Mandel, units of E times the thickness).
    """
    g = _geometry.of(mesh)
    e_inv = np.linalg.inv(unit_elongations(mesh, idx))
    c = np.broadcast_to(tensors, (len(idx), 3, 3))
    target = g.tri_area[idx, None, None] * np.einsum("mki,mkl,mlj->mij", e_inv, c, e_inv)
    w = g.tri_weight[idx] * np.asarray(spring)[mesh.topology.tri_bonds[idx]]
    q = np.asarray(coupling)[idx, None, None] * reference_matrices(g, barycentric, idx)
    q[:, [0, 1, 2], [0, 1, 2]] += w
    dq = target - q
    return 0.5 * (dq + dq.transpose(0, 2, 1))


def cell_tensors(mesh: Mesh, idx: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """The tensors (k, 3, 3, Mandel) that bond matrices ``dq`` (k, 3, 3) add to
    triangles ``idx``: ``E_T^T dQ_T E_T / A_T``."""
    e = unit_elongations(mesh, idx)
    area = _geometry.of(mesh).tri_area[idx, None, None]
    return np.einsum("mki,mkl,mlj->mij", e, dq, e) / area
