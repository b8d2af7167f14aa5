"""The FE mesh of a lattice mesh: uniform refinement that keeps track of the boundary.

Every boundary facet of the refined mesh remembers the coarse boundary edge it lies on
(``parent``, an index into ``mesh.boundary_edges``) and the parameters ``s`` of its two
ends along that edge (0 at its first node, 1 at its second). Supports and loads on
named parts then select facets by parent, per-node prescribed values are interpolated
along the coarse edge, and new boundary nodes are moved onto the true boundary curve
of the mesh's domain (circles stay circles under refinement). With ``order >= 2`` the
mid-edge nodes of boundary facets are moved onto the curve too (quadratic geometry:
isoparametric for P2, subparametric for P3 and P4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh

__all__ = ["FEMesh", "build"]


@dataclass(frozen=True, eq=False)
class FEMesh:
    """A refined triangulation with its boundary bookkeeping.

    Attributes
    ----------
    points : ndarray, shape (n, 2)
        The lattice nodes first (same indices), then the nodes added by refinement.
    triangles : ndarray of int, shape (m, 3)
    parent_triangle : ndarray of int, shape (m,)
        Coarse triangle each triangle lies in.
    facets : ndarray of int, shape (k, 2)
        Boundary facets, counter-clockwise.
    parent : ndarray of int, shape (k,)
        Coarse boundary edge (index into ``mesh.boundary_edges``) of every facet.
    s : ndarray, shape (k, 2)
        Parameters of the facet's ends along its coarse edge.
    curve : ndarray of int, shape (n_coarse_boundary_edges,) or None
        Domain curve of every coarse boundary edge (None without a domain).
    skfem : skfem.Mesh
        ``MeshTri1``, or ``MeshTri2`` (quadratic geometry on curves) for ``order >= 2``.
    linear : skfem.MeshTri1
        The straight-sided mesh (where points are located).
    """

    points: np.ndarray
    triangles: np.ndarray
    parent_triangle: np.ndarray
    facets: np.ndarray
    parent: np.ndarray
    s: np.ndarray
    curve: np.ndarray | None
    skfem: object
    linear: object

    def facet_index(self, skfem_facets: np.ndarray) -> np.ndarray:
        """Row in :attr:`facets` of skfem boundary facets (given by their index)."""
        fm = self.skfem
        n = len(self.points)
        ends = np.sort(fm.facets[:, skfem_facets].T, axis=1).astype(np.int64)  # skfem: int32
        mine = np.sort(self.facets, axis=1)
        key_mine = mine[:, 0] * n + mine[:, 1]
        order = np.argsort(key_mine)
        pos = np.searchsorted(key_mine[order], ends[:, 0] * n + ends[:, 1])
        return order[pos]


def build(mesh: Mesh, refine: int, order: int) -> FEMesh:
    """Refine ``mesh`` ``refine`` times (each splits a triangle into four) into an FE mesh.

    New nodes on the boundary lie on the domain's curves when the mesh was generated
    in a :class:`~dvstatic.domain.Domain`; with ``order >= 2`` so do the mid-edge nodes
    of the boundary facets.
    """
    import skfem

    p = np.array(mesh.points, dtype=float)
    t = np.array(mesh.triangles)
    be = mesh.boundary_edges
    curve = _curves(mesh)
    state = (
        p,
        t,
        np.arange(len(t)),
        be.copy(),
        np.arange(len(be)),
        np.tile([0.0, 1.0], (len(be), 1)),
    )
    for _ in range(refine):
        state = _refine_once(*state)
        if curve is not None:
            state = _on_curves(mesh, curve, *state)
    p, t, parent_t, facets, parent, s = state
    fm = skfem.MeshTri(np.ascontiguousarray(p.T), np.ascontiguousarray(t.T))
    fe = FEMesh(p, t, parent_t, facets, parent, s, curve, fm, fm)
    if order >= 2 and curve is not None and not _all_straight(mesh, curve):
        fe = _quadratic(mesh, fe)
    return fe


def _all_straight(mesh: Mesh, curve: np.ndarray) -> bool:
    """True if every boundary edge lies on a straight curve (no quadratic geometry
    needed)."""
    curves = mesh.domain.boundary_curves()
    return all(curves[int(c)].straight for c in np.unique(curve) if c >= 0)


def _curves(mesh: Mesh) -> np.ndarray | None:
    if mesh.domain is None:
        return None
    return mesh.domain.curve_of_edges(mesh.points, mesh.boundary_edges, 1e-9 * mesh.h)


def _refine_once(p, t, parent_t, facets, parent, s):
    """Red refinement: edge midpoints become nodes, every triangle four triangles."""
    n = len(p)
    e = np.stack([t[:, [1, 2]], t[:, [2, 0]], t[:, [0, 1]]], axis=1).reshape(-1, 2)
    lo, hi = np.minimum(e[:, 0], e[:, 1]), np.maximum(e[:, 0], e[:, 1])
    keys, inv = np.unique(lo * n + hi, return_inverse=True)
    a, b = keys // n, keys % n
    p_new = np.vstack([p, 0.5 * (p[a] + p[b])])
    m = (n + inv).reshape(-1, 3)  # m[:, k]: midpoint of the edge opposite vertex k
    v0, v1, v2 = t[:, 0], t[:, 1], t[:, 2]
    m0, m1, m2 = m[:, 0], m[:, 1], m[:, 2]
    t_new = np.concatenate(
        [
            np.stack([v0, m2, m1], axis=1),
            np.stack([v1, m0, m2], axis=1),
            np.stack([v2, m1, m0], axis=1),
            np.stack([m0, m1, m2], axis=1),
        ]
    )
    parent_new = np.tile(parent_t, 4)
    fl, fh = np.minimum(facets[:, 0], facets[:, 1]), np.maximum(facets[:, 0], facets[:, 1])
    mid = n + np.searchsorted(keys, fl * n + fh)
    sm = s.mean(axis=1)
    f_new = np.concatenate([np.stack([facets[:, 0], mid], 1), np.stack([mid, facets[:, 1]], 1)])
    s_new = np.concatenate([np.stack([s[:, 0], sm], 1), np.stack([sm, s[:, 1]], 1)])
    return p_new, t_new, parent_new, f_new, np.tile(parent, 2), s_new


def _on_curves(mesh: Mesh, curve, p, t, parent_t, facets, parent, s):
    """Move the boundary nodes that refinement added onto their curve."""
    new = facets[:, 1] >= mesh.n_points  # the first child of a split facet ends at the midpoint
    nodes = facets[new, 1]
    p = p.copy()
    p[nodes] = mesh.domain.project(p[nodes], curve[parent[new]])
    return p, t, parent_t, facets, parent, s


def _quadratic(mesh: Mesh, fe: FEMesh) -> FEMesh:
    """MeshTri2 whose boundary-facet mid-nodes lie on the curves."""
    import dataclasses

    import skfem

    m2 = skfem.MeshTri2.from_mesh(fe.skfem)
    bf = m2.boundary_facets()
    rows = fe.facet_index(bf)
    dofs = m2.dofs.facet_dofs[0, bf]
    doflocs = m2.doflocs.copy()
    doflocs[:, dofs] = mesh.domain.project(doflocs[:, dofs].T, fe.curve[fe.parent[rows]]).T
    return dataclasses.replace(fe, skfem=dataclasses.replace(m2, doflocs=doflocs))
