"""Geometry of polygons and triangle lists on plain arrays: point in polygon, signed
area, self-intersection, boundary edges of a triangulation, which pairs are edges.
"""

from __future__ import annotations

import numpy as np

from .._planar import cross

__all__ = ["in_polygon", "signed_area", "self_intersects", "boundary_edges", "are_edges"]


def are_edges(tri: np.ndarray, pairs: np.ndarray, n: int) -> np.ndarray:
    """Which node pairs (s, 2) are edges of the triangulation, (s,) bool."""
    if len(pairs) == 0:
        return np.zeros(0, dtype=bool)
    e = np.stack([tri[:, [1, 2]], tri[:, [2, 0]], tri[:, [0, 1]]], axis=1).reshape(-1, 2)
    keys = np.unique(np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1]))
    want = np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1])
    return np.isin(want, keys)


def in_polygon(v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Even-odd point-in-polygon test, (n,) bool (points on edges are ambiguous).

    An edge can only be crossed by the rays of the points whose ``y`` lies in its
    ``[min y, max y)``: with the points sorted by ``y`` those are a contiguous run, so
    only (edge, point) pairs of those runs are tested (about two per point for a loop,
    instead of every edge against every point); the crossing is the same arithmetic."""
    p = np.asarray(p, dtype=float).reshape(-1, 2)
    w = np.roll(v, -1, axis=0)
    order = np.argsort(p[:, 1], kind="stable")
    ys = p[order, 1]
    start = np.searchsorted(ys, np.minimum(v[:, 1], w[:, 1]), side="left")
    counts = np.searchsorted(ys, np.maximum(v[:, 1], w[:, 1]), side="left") - start
    e = np.repeat(np.arange(len(v)), counts)
    run = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    k = order[np.repeat(start, counts) + run]
    y = p[k, 1]
    xc = v[e, 0] + (y - v[e, 1]) * (w[e, 0] - v[e, 0]) / (w[e, 1] - v[e, 1])
    hits = np.bincount(k[p[k, 0] < xc], minlength=len(p))
    return (hits % 2) == 1


def signed_area(v: np.ndarray) -> float:
    w = np.roll(v, -1, axis=0)
    return 0.5 * float(np.sum(v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]))


def self_intersects(v: np.ndarray) -> bool:
    k = len(v)
    p, q = v, np.roll(v, -1, axis=0)
    i, j = np.triu_indices(k, 1)
    adjacent = (j == i + 1) | ((i == 0) & (j == k - 1))
    i, j = i[~adjacent], j[~adjacent]
    if i.size == 0:
        return False

    def orient(a, b, c):
        return np.sign(cross(b - a, c - a))

    o1 = orient(p[i], q[i], p[j])
    o2 = orient(p[i], q[i], q[j])
    o3 = orient(p[j], q[j], p[i])
    o4 = orient(p[j], q[j], q[i])
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)
    touching = ((o1 == 0) | (o2 == 0) | (o3 == 0) | (o4 == 0)) & (
        np.maximum(np.minimum(p[i], q[i]), np.minimum(p[j], q[j]))
        <= np.minimum(np.maximum(p[i], q[i]), np.maximum(p[j], q[j]))
    ).all(axis=1)
    return bool(np.any(proper | touching))


def boundary_edges(tri: np.ndarray, with_third: bool = False):
    """Directed boundary edges (counter-clockwise) of a triangle list.

    With ``with_third`` also return the vertex opposite each edge.
    """
    e = np.stack([tri[:, [1, 2]], tri[:, [2, 0]], tri[:, [0, 1]]], axis=1).reshape(-1, 2)
    n = int(tri.max()) + 1
    key = np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1])
    _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
    sel = cnt[inv] == 1
    if with_third:
        return e[sel], tri.reshape(-1)[sel]
    return e[sel]
