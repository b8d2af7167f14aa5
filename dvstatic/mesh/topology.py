"""Edge structure of a (periodic) triangulation: bonds, triangle-bond incidence and
boundary, from the triangle array alone (validated: manifold, consistently oriented)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Topology", "build_topology"]


@dataclass(frozen=True, eq=False)
class Topology:
    """Edge structure of a triangulation (computed once per mesh).

    Attributes
    ----------
    bonds : ndarray, shape (n_bonds, 2), int64
        End nodes (O, A) of every bond (mesh edge), O < A for bounded meshes.
    bond_image : ndarray, shape (n_bonds, 2), int64
        Periodic image of A relative to O (zeros for bounded meshes); the bond
        vector is ``points[A] + bond_image * period - points[O]``.
    tri_bonds : ndarray, shape (M, 3), int64
        Bond index of local edge k of each triangle; local edge k joins local
        vertices k+1 and k+2 (mod 3) and is opposite vertex k.
    bond_tris : ndarray, shape (n_bonds, 2), int64
        The one or two triangles of each bond; -1 where a bond has one triangle.
    bond_local : ndarray, shape (n_bonds, 2), int64
        Local edge index of the bond in each of ``bond_tris`` (-1 where absent).
    boundary_edges : ndarray, shape (m, 2), int64
        Boundary edges oriented counter-clockwise around the domain.
    """

    bonds: np.ndarray
    bond_image: np.ndarray
    tri_bonds: np.ndarray
    bond_tris: np.ndarray
    bond_local: np.ndarray
    boundary_edges: np.ndarray

    @property
    def n_tris_per_bond(self) -> np.ndarray:
        """Number of triangles (1 or 2) of every bond, shape (n_bonds,)."""
        return 1 + (self.bond_tris[:, 1] >= 0)

    def ring_step(self, n_points: int):
        """Node adjacency with the diagonal, CSR (n_points, n_points) of ones: one
        product sums every node's values over itself and its neighbours (one ring)."""
        import scipy.sparse as sp

        b = self.bonds
        a = sp.coo_matrix((np.ones(len(b)), (b[:, 0], b[:, 1])), shape=(n_points, n_points))
        return (a + a.T + sp.identity(n_points)).tocsr()


def build_topology(tri: np.ndarray, n: int, images: np.ndarray | None) -> Topology:
    """Bonds, triangle-bond incidence and boundary of a (periodic) triangulation.

    Parameters
    ----------
    tri : ndarray of int, shape (M, 3)
        Counter-clockwise triangles.
    n : int
        Number of points.
    images : ndarray of int, shape (M, 3, 2), or None
        Periodic image of every triangle vertex (periodic meshes).

    Raises
    ------
    InputError
        Edges shared by more than two triangles, overlapping triangles, a periodic
        triangle spanning more than one period.
    """
    m = len(tri)
    o = tri[:, [1, 2, 0]]
    a = tri[:, [2, 0, 1]]
    lo, hi = np.minimum(o, a), np.maximum(o, a)
    key = lo * n + hi
    if images is not None:
        s = images[:, [2, 0, 1]] - images[:, [1, 2, 0]]  # image of a relative to o
        s = np.where((o > a)[..., None], -s, s)
        if np.any(np.abs(s) > 1):
            raise InputError("periodic triangle spans more than one period")
        if np.any(o == a):
            raise InputError(
                "a periodic triangle joins a point to its own image: too few points for a "
                "periodic mesh"
            )
        key = key * 9 + (s[..., 0] + 1) * 3 + (s[..., 1] + 1)
    uniq, inv, cnt = np.unique(key.ravel(), return_inverse=True, return_counts=True)
    if cnt.max() > 2:
        e = int(np.argmax(cnt))
        raise InputError(
            f"{int(np.sum(cnt > 2))} edge(s) are shared by more than two triangles "
            f"(first shared by {int(cnt[e])}); the triangles overlap"
        )
    sign = np.where(o < a, 1, -1).ravel()
    balance = np.bincount(inv, weights=sign, minlength=len(uniq))
    if np.any((cnt == 2) & (balance != 0)):
        raise InputError("two triangles share an edge with the same orientation: they overlap")
    if images is not None and np.any(cnt != 2):
        raise InputError("a periodic triangulation must have every edge in exactly two triangles")
    order = np.argsort(inv, kind="stable")
    start = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    first = order[start]
    second = np.where(cnt == 2, order[np.minimum(start + 1, len(order) - 1)], -1)
    bond_tris = np.stack([first // 3, np.where(second >= 0, second // 3, -1)], axis=1)
    bond_local = np.stack([first % 3, np.where(second >= 0, second % 3, -1)], axis=1)
    tri_bonds = inv.reshape(m, 3).astype(np.int64)
    if images is None:
        bonds = np.stack([uniq // n, uniq % n], axis=1)
        bond_image = np.zeros_like(bonds)
    else:
        pair = uniq // 9
        code = uniq % 9
        bonds = np.stack([pair // n, pair % n], axis=1)
        bond_image = np.stack([code // 3 - 1, code % 3 - 1], axis=1)
    ob, ab = o.ravel(), a.ravel()
    bmask = np.flatnonzero(cnt[inv] == 1)
    boundary = np.stack([ob[bmask], ab[bmask]], axis=1)
    out = Topology(
        bonds=bonds.astype(np.int64),
        bond_image=bond_image.astype(np.int64),
        tri_bonds=tri_bonds,
        bond_tris=bond_tris.astype(np.int64),
        bond_local=bond_local.astype(np.int64),
        boundary_edges=boundary.astype(np.int64),
    )
    for arr in vars(out).values():
        arr.setflags(write=False)
    return out
