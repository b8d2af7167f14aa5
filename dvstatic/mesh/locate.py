"""Locating points in a mesh and interpolating nodal fields there (P1)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .core import Mesh

__all__ = ["interpolate", "snap_point", "local_spacing"]


def interpolate(mesh: Mesh, field, points) -> np.ndarray:
    """Linear (P1) interpolation of a nodal field at arbitrary points inside the mesh.

    Parameters
    ----------
    mesh : Mesh
    field : array_like, shape (N,) or (N, k)
        Nodal values (e.g. ``sol.u``).
    points : array_like, shape (n, 2)

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    InputError
        If a point lies outside the mesh.
    """
    from scipy.spatial import cKDTree

    f = np.asarray(field, dtype=float)
    p = np.atleast_2d(np.asarray(points, dtype=float))
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputError(f"points must have shape (n, 2), got {p.shape}", "points")
    if not np.all(np.isfinite(p)):
        bad = p[~np.all(np.isfinite(p), axis=1)][0]
        raise InputError(f"point {bad.tolist()} is not finite", "points")
    if f.shape[0] != mesh.n_points:
        raise InputError(f"field must have {mesh.n_points} rows, got {f.shape[0]}", "field")
    x = mesh.triangle_coordinates()
    tree = cKDTree(x.mean(axis=1))
    tri_idx = np.full(len(p), -1)
    bary = np.zeros((len(p), 3))
    todo = np.arange(len(p))
    k = min(8, mesh.n_triangles)
    while todo.size:
        _, cand = tree.query(p[todo], k=k)
        cand = cand.reshape(len(todo), -1)
        a = x[cand, 1] - x[cand, 0]
        b = x[cand, 2] - x[cand, 0]
        q = p[todo, None, :] - x[cand, 0]
        det = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        l1 = (q[..., 0] * b[..., 1] - q[..., 1] * b[..., 0]) / det
        l2 = (a[..., 0] * q[..., 1] - a[..., 1] * q[..., 0]) / det
        lam = np.stack([1 - l1 - l2, l1, l2], axis=-1)
        inside = np.all(lam >= -1e-10, axis=-1)
        found = inside.any(axis=1)
        j = np.argmax(inside, axis=1)
        rows = np.flatnonzero(found)
        tri_idx[todo[rows]] = cand[rows, j[rows]]
        bary[todo[rows]] = lam[rows, j[rows]]
        todo = todo[~found]
        if k >= mesh.n_triangles:
            break
        k = min(4 * k, mesh.n_triangles)
    if np.any(tri_idx < 0):
        bad = p[tri_idx < 0][0]
        raise InputError(f"point {bad.tolist()} lies outside the mesh", "points")
    vals = f[mesh.triangles[tri_idx]]  # (n, 3, ...)
    return np.einsum("nv,nv...->n...", bary, vals)


def snap_point(mesh: Mesh, point) -> np.ndarray:
    """``point`` (shape (1, 2)) if it lies in the mesh, else its foot on the nearest
    boundary edge when that is within half the edge's length (a point on a curved
    boundary, which the mesh's straight edges cut inside).

    Raises
    ------
    InputError
        If the point is not finite, or farther than that from the mesh.
    """
    point = np.asarray(point, dtype=float).reshape(1, 2)
    if not np.all(np.isfinite(point)):
        raise InputError(f"point {point[0].tolist()} is not finite", "points")
    if _inside(mesh, point):
        return point
    e = mesh.boundary_edges
    a, b = mesh.points[e[:, 0]], mesh.points[e[:, 1]]
    ab = b - a
    length2 = np.einsum("ij,ij->i", ab, ab)
    t = np.clip(np.einsum("ij,ij->i", point - a, ab) / length2, 0.0, 1.0)
    foot = a + t[:, None] * ab
    d = np.hypot(*(foot - point).T)
    k = int(np.argmin(d))
    if d[k] > 0.5 * np.sqrt(length2[k]):
        raise InputError(
            f"point {point[0].tolist()} lies outside the mesh ({d[k]:.3g} from its "
            "boundary, more than half the local spacing)",
            "points",
        )
    near = e[k, 0] if t[k] < 0.5 else e[k, 1]
    # the foot lies on the edge; round-off may put it a hair outside: then the node
    return foot[k : k + 1] if _inside(mesh, foot[k : k + 1]) else mesh.points[near : near + 1]


def _inside(mesh: Mesh, point: np.ndarray) -> bool:
    try:
        interpolate(mesh, np.zeros(mesh.n_points), point)
    except InputError:
        return False
    return True


def local_spacing(mesh: Mesh, node: int) -> float:
    """Mean length of the bonds at ``node`` (length): the spacing of a graded mesh
    there (``mesh.h`` is the mean over the whole mesh)."""
    b = mesh.topology.bonds
    at = b[np.any(b == node, axis=1)]
    if at.size == 0:
        return float(mesh.h)
    d = mesh.points[at[:, 1]] - mesh.points[at[:, 0]]
    return float(np.mean(np.hypot(d[:, 0], d[:, 1])))
