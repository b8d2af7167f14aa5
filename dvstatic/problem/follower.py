"""Follower pressures: normal to the deformed boundary, for nonlinear solves.

On a straight boundary edge ``a -> b`` (counter-clockwise, the body on its left) the
pressure force is ``-p n L = -p R d`` with ``d = x_b - x_a`` the *current* edge vector
and ``R d = (d_y, -d_x)``. Lumped with the edge's linear shape functions, the ends get
``f_a = -c_a R d`` and ``f_b = -c_b R d`` with ``c_a = int (1 - s) p ds`` and
``c_b = int s p ds`` (two Gauss points; ``p`` evaluated on the reference edge), times
the thickness. The forces are linear in ``d``, so their derivative is exact and
constant: ``df_a/dx_a = c_a R``, ``df_a/dx_b = -c_a R`` (likewise for ``b``); it is
not symmetric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh
from .fields import evaluate
from .loads import _GAUSS_S, _GAUSS_W, Pressure
from .select import as_list, label, select_edges

__all__ = ["FollowerPressures", "split_followers"]

_R = np.array([[0.0, 1.0], [-1.0, 0.0]])


def split_followers(loads) -> tuple[list, list]:
    """Dead loads and follower pressures of a load list."""
    loads = as_list(loads, "Traction, Pressure, BodyForce or PointLoad")
    follow = [ld for ld in loads if isinstance(ld, Pressure) and ld.follower]
    return [ld for ld in loads if ld not in follow], follow


@dataclass(frozen=True, eq=False)
class FollowerPressures:
    """The loaded edges of follower pressures and the weights of their ends.

    Attributes
    ----------
    edges : ndarray of int, shape (k, 2)
        Counter-clockwise boundary edges (node indices).
    ca, cb : ndarray, shape (k,)
        Pressure integrals against the end shape functions (force per length).
    """

    edges: np.ndarray
    ca: np.ndarray
    cb: np.ndarray

    @classmethod
    def from_loads(cls, mesh: Mesh, loads, thickness: float = 1.0) -> FollowerPressures:
        """The follower pressures among ``loads`` (empty if there are none)."""
        _, follow = split_followers(loads)
        edges, ca, cb = [np.zeros((0, 2), np.int64)], [np.zeros(0)], [np.zeros(0)]
        for load in follow:
            e = select_edges(mesh, load.where, "Pressure")
            xa, xb = mesh.points[e[:, 0]], mesh.points[e[:, 1]]
            if callable(load.p):
                xq = (xa[None] + _GAUSS_S[:, None, None] * (xb - xa)[None]).reshape(-1, 2)
                pq = evaluate(load.p, xq, (), f"Pressure on {label(load.where)}").reshape(2, -1)
            else:
                pq = np.full((2, len(e)), load.p)
            edges.append(e)
            ca.append(thickness * np.einsum("q,q,qm->m", _GAUSS_W, 1.0 - _GAUSS_S, pq))
            cb.append(thickness * np.einsum("q,q,qm->m", _GAUSS_W, _GAUSS_S, pq))
        return cls(np.concatenate(edges), np.concatenate(ca), np.concatenate(cb))

    def __bool__(self) -> bool:
        return len(self.edges) > 0

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces at current positions ``x`` (n, 2), interleaved (2n,)."""
        n = len(x)
        rd = (x[self.edges[:, 1]] - x[self.edges[:, 0]]) @ _R.T
        f = np.zeros((n, 2))
        for c in range(2):
            f[:, c] -= np.bincount(self.edges[:, 0], self.ca * rd[:, c], n)
            f[:, c] -= np.bincount(self.edges[:, 1], self.cb * rd[:, c], n)
        return f.reshape(-1)

    def tangent(self, n: int):
        """``d forces / d x``, CSR (2n, 2n) (constant: the forces are linear in x)."""
        import scipy.sparse as sp

        a, b = self.edges[:, 0], self.edges[:, 1]
        rows, cols, vals = [], [], []
        for node, coef in ((a, self.ca), (b, self.cb)):
            for other, sign in ((a, 1.0), (b, -1.0)):
                for i in range(2):
                    for j in range(2):
                        if _R[i, j] == 0.0:
                            continue
                        rows.append(2 * node + i)
                        cols.append(2 * other + j)
                        vals.append(sign * coef * _R[i, j])
        return sp.coo_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(2 * n, 2 * n),
        ).tocsr()

    def restricted(self, local_of: np.ndarray) -> FollowerPressures:
        """The edges whose both ends have a local number (``local_of >= 0``), renumbered."""
        la, lb = local_of[self.edges[:, 0]], local_of[self.edges[:, 1]]
        keep = (la >= 0) & (lb >= 0)
        return FollowerPressures(np.c_[la[keep], lb[keep]], self.ca[keep], self.cb[keep])
