"""Reference geometry of the bond lattice, computed once per mesh and cached.

For every bond: length ``l``, unit direction ``n`` (from O to A), the one or two
signed half sides of its dual Voronoi side and their sum ``r``. For every
triangle: circumcentre, its barycentric coordinates, the half sides of its three
local edges. For every node: the Voronoi cell area.

Signed half sides follow the design card: for bond e and neighbouring triangle T,
``r_T = (H_T - M_e) . t_T`` (``H_T`` circumcentre, ``M_e`` bond midpoint, ``t_T`` the
unit normal to the bond pointing to T's third vertex), which equals
``(l / 2) cot(theta_T)``. ``sum over bonds of l r / 2`` is the mesh area exactly.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from .._cache import PerObject
from ..mesh import Mesh
from .kinematics import edge_frames

log = logging.getLogger(__name__)

__all__ = ["Geometry", "of", "is_cached", "smallest_sine"]

#: a half side larger than this many times its bond flags a near-degenerate triangle
SLIVER_WARNING = 1e3


@dataclass(frozen=True, eq=False)
class Geometry:
    """Reference geometry of a mesh (read-only arrays).

    Attributes
    ----------
    x_tri : (M, 3, 2) unwrapped reference vertex coordinates of each triangle
    tri_area : (M,) triangle areas
    circumcentre : (M, 2) circumcentres (unwrapped frame of the triangle)
    bary : (M, 3) barycentric coordinates of the circumcentres
    tri_r : (M, 3) signed half side of local edge k in its triangle
    tri_l : (M, 3) length of local edge k
    tri_weight : (M, 3) 1 / (number of triangles of the bond of local edge k)
    length : (n_bonds,) bond lengths l
    direction : (n_bonds, 2) unit bond directions n (from O to A)
    half_sides : (n_bonds, 2) signed half sides r_T1, r_T2 (0 where a bond has one triangle)
    r : (n_bonds,) dual Voronoi side length r = r_T1 + r_T2
    cell_area : (N,) Voronoi cell area of each node (sum of l r / 4 over its bonds);
        sums to the mesh area
    dual_area : (N,) one third of the area of the node's triangles (always positive)
    seconds : float, time it took to compute
    """

    x_tri: np.ndarray
    tri_area: np.ndarray
    circumcentre: np.ndarray
    bary: np.ndarray
    tri_r: np.ndarray
    tri_l: np.ndarray
    tri_weight: np.ndarray
    length: np.ndarray
    direction: np.ndarray
    half_sides: np.ndarray
    r: np.ndarray
    cell_area: np.ndarray
    dual_area: np.ndarray
    seconds: float


def is_cached(mesh: Mesh) -> bool:
    """True if the geometry of ``mesh`` has already been computed."""
    return mesh in _GEOMETRY


def of(mesh: Mesh) -> Geometry:
    """Geometry of ``mesh`` (computed on first use, then cached for the mesh's lifetime)."""
    if not isinstance(mesh, Mesh):
        raise TypeError(f"expected a dvstatic Mesh, got {type(mesh).__name__}")
    return _GEOMETRY(mesh)


def smallest_sine(g: Geometry, sl=slice(None)) -> np.ndarray:
    """The sine of every triangle's smallest angle (of triangles ``sl``), ``2 A / (l_i
    l_j)`` over its corners, shape (m,)."""
    length = g.tri_l[sl]
    return (2.0 * g.tri_area[sl, None] / (length * np.roll(length, 1, axis=1))).min(axis=1)


def _compute(mesh: Mesh) -> Geometry:
    t0 = time.perf_counter()
    topo = mesh.topology
    n_nodes = mesh.n_points
    x = mesh.triangle_coordinates()
    tri_area = np.asarray(mesh.triangle_areas)
    d, tri_l, _ = edge_frames(x)  # local edge k from vertex k+1 to k+2
    # angle at vertex k between the edges to k+1 (= d[k+2]) and k+2 (= -d[k+1])
    cos_num = -np.einsum("mki,mki->mk", d[:, [2, 0, 1]], d[:, [1, 2, 0]])
    tri_r = 0.5 * tri_l * cos_num / (2.0 * tri_area)[:, None]  # (l/2) cot(theta)
    # barycentric coordinates of the circumcentre: l_k^2 (l_k+1^2 + l_k+2^2 - l_k^2)
    l2 = tri_l**2
    wts = l2 * (l2.sum(axis=1, keepdims=True) - 2.0 * l2)
    bary = wts / wts.sum(axis=1, keepdims=True)
    cc = np.einsum("mv,mvi->mi", bary, x)
    ntri = topo.n_tris_per_bond
    tri_weight = 1.0 / ntri[topo.tri_bonds]

    bvec = mesh.bond_vectors()
    length = np.hypot(bvec[:, 0], bvec[:, 1])
    direction = bvec / length[:, None]
    bt, bl = topo.bond_tris, topo.bond_local
    hs = np.zeros((len(length), 2))
    hs[:, 0] = tri_r[bt[:, 0], bl[:, 0]]
    two = bt[:, 1] >= 0
    hs[two, 1] = tri_r[bt[two, 1], bl[two, 1]]
    r = hs.sum(axis=1)

    b = topo.bonds
    lr4 = 0.25 * length * r
    cell = np.bincount(b[:, 0], lr4, n_nodes) + np.bincount(b[:, 1], lr4, n_nodes)
    dual = np.zeros(n_nodes)
    for v in range(3):
        dual += np.bincount(mesh.triangles[:, v], tri_area, n_nodes)
    dual /= 3.0
    g = Geometry(
        x_tri=x,
        tri_area=tri_area,
        circumcentre=cc,
        bary=bary,
        tri_r=tri_r,
        tri_l=tri_l,
        tri_weight=tri_weight,
        length=length,
        direction=direction,
        half_sides=hs,
        r=r,
        cell_area=cell,
        dual_area=dual,
        seconds=time.perf_counter() - t0,
    )
    for arr in vars(g).values():
        if isinstance(arr, np.ndarray):
            arr.setflags(write=False)
    log.debug("geometry of %r in %.3f s", mesh, g.seconds)
    worst = float(np.max(np.abs(tri_r) / tri_l))
    if worst > SLIVER_WARNING:
        i = int(np.argmax(np.max(np.abs(tri_r) / tri_l, axis=1)))
        log.warning(
            "near-degenerate triangle %d (a half side %.3g times its bond): its circumcentre is "
            "far away; expect ill-conditioning, and DV to be unstable there",
            i,
            worst,
        )
    return g


_GEOMETRY = PerObject("geometry", _compute)
