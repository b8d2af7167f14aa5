"""Is the body still in one piece? Pieces of the graph of unbroken bonds, nodes that
hang on collinear bonds, and the triangles of every bond."""

from __future__ import annotations

import numpy as np

from ..linalg import rigid_modes

__all__ = ["Pieces", "bond_triangles"]


class Pieces:
    """Detects a body separated into pieces from the graph of unbroken bonds."""

    def __init__(self, model, dofs, values, f, fragment: float):
        self.mesh = model.mesh
        self.bonds = model.mesh.topology.bonds
        self.constrained = np.zeros(2 * self.mesh.n_points, dtype=bool)
        self.constrained[dofs] = True
        loaded = (np.abs(f) > 0).reshape(-1, 2).any(axis=1)
        moved = np.zeros(2 * self.mesh.n_points, dtype=bool)
        moved[dofs[values != 0]] = True
        self.active = loaded | moved.reshape(-1, 2).any(axis=1)
        self.modes = rigid_modes(self.mesh.points)
        self.fragment = fragment

    def hanging(self, stiffness, nodes, spring) -> str | None:
        """A message if a loaded node among ``nodes`` lost its last bond across a direction
        that no support holds (a local mechanism), else None."""
        for node in nodes:
            if not self.active[node]:
                continue
            held = self.constrained.reshape(-1, 2)[node]
            if held.all():
                continue
            at = np.flatnonzero((self.bonds == node).any(axis=1))
            n = self.mesh.points[self.bonds[at, 1]] - self.mesh.points[self.bonds[at, 0]]
            n /= np.hypot(n[:, 0], n[:, 1])[:, None]
            k = np.einsum("e,ei,ej->ij", stiffness[at] * spring[at], n, n)
            scale = float(np.max(spring[at]))
            if held.any():  # one component held: the other must be stiff
                soft = k[1 - int(np.argmax(held)), 1 - int(np.argmax(held))] <= 1e-6 * scale
            else:
                soft = np.linalg.eigvalsh(k)[0] <= 1e-6 * scale
            if soft:
                return (
                    f"node {node} at {np.round(self.mesh.points[node], 4).tolist()}, which "
                    "carries a load or a prescribed displacement, lost its last bond across "
                    "a direction no support holds: the load has separated from the body"
                )
        return None

    def check(self, stiffness: np.ndarray) -> str | None:
        """None, or a message if a loaded or large piece is no longer held."""
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        keep = stiffness > 0
        n = self.mesh.n_points
        b = self.bonds[keep]
        graph = sp.coo_matrix((np.ones(len(b)), (b[:, 0], b[:, 1])), shape=(n, n))
        count, label = connected_components(graph, directed=False)
        if count == 1:
            return None
        for c in range(count):
            nodes = np.flatnonzero(label == c)
            dof_mask = self.constrained.reshape(-1, 2)[nodes]
            cdofs = (2 * nodes[:, None] + np.arange(2))[dof_mask]
            b3 = self.modes[cdofs]
            held = len(cdofs) >= 3 and np.linalg.matrix_rank(b3, tol=1e-8) == 3
            big = len(nodes) > self.fragment * n
            if not held and (big or self.active[nodes].any()):
                what = "carries load" if self.active[nodes].any() else f"has {len(nodes)} nodes"
                return (
                    f"the body separated into {count} pieces: a piece of {len(nodes)} nodes "
                    f"(near {np.round(self.mesh.points[nodes].mean(axis=0), 4).tolist()}) "
                    f"{what} and is no longer held by the supports"
                )
        return None


def bond_triangles(mesh) -> np.ndarray:
    """The triangles of every bond, shape (n_bonds, 2) (a boundary bond's one repeated)."""
    tb = mesh.topology.tri_bonds
    out = np.full((mesh.n_bonds, 2), -1, dtype=np.int64)
    tri = np.repeat(np.arange(mesh.n_triangles), 3)
    bond = tb.ravel()
    order = np.argsort(bond, kind="stable")
    bond, tri = bond[order], tri[order]
    first = np.r_[True, bond[1:] != bond[:-1]]
    out[bond[first], 0] = tri[first]
    out[bond[~first], 1] = tri[~first]
    out[out[:, 1] < 0, 1] = out[out[:, 1] < 0, 0]
    return out
