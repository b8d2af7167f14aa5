"""Distances of points to a domain's boundary and region curves, for the mesh generators.

The mesher asks, for every point of every Lloyd iteration, whether it is farther from
the curves than a length; :func:`distance_to_boundary` answers with the exact distance
where it may be below that length and ``inf`` where a lower bound from samples of the
curves (a k-d tree) says it is not, so only a thin band of points is projected onto the
curves (an ellipse projects by comparing every point with 513 of its own first).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .domain import Domain

__all__ = ["distance_to_boundary", "BOUND_SAMPLES"]


def distance_to_boundary(domain: Domain, p: np.ndarray, beyond=None) -> np.ndarray:
    """Distance to the nearest boundary or region curve, shape (n,).

    With ``beyond`` (a length, or one per point) the points that are certainly farther
    than it get ``inf``: a lower bound of their distance (:func:`_boundary_bound`)
    exceeds it. Only the others are projected onto the curves (a curve without a
    closed-form projection, an ellipse, compares every point with 513 of its points),
    so tests ``d > beyond``, ``d >= beyond`` come out as with every distance."""
    p = np.asarray(p, dtype=float).reshape(-1, 2)
    if beyond is None:
        return _curve_distance(domain, p)
    d = np.full(len(p), np.inf)
    near = np.flatnonzero(_boundary_bound(domain, p, np.max(beyond)) <= beyond)
    if near.size:
        d[near] = _curve_distance(domain, p[near])
    return d


def _curve_distance(domain: Domain, p: np.ndarray) -> np.ndarray:
    d, _ = domain.curve_distances(p)
    d = d.min(axis=1)
    if domain.regions:
        d = np.minimum(d, domain.region_distances(p).min(axis=1))
    return d


#: points per curve of the boundary samples that bound the distance from below
BOUND_SAMPLES = 4096


@lru_cache(maxsize=8)
def _boundary_samples(domain: Domain):
    """A k-d tree of :data:`BOUND_SAMPLES` points on every boundary and region curve and
    the longest chord between neighbours: every curve point is within half an arc (at
    most a chord, for these fine samples) of a sample."""
    from scipy.spatial import cKDTree

    curves = [c for loop in domain.loops + tuple(domain.regions) for c in loop.pieces()]
    pts = [c.point(np.linspace(0.0, 1.0, BOUND_SAMPLES + 1)) for c in curves]
    chord = max(float(np.hypot(*np.diff(x, axis=0).T).max()) for x in pts)
    return cKDTree(np.vstack(pts)), chord


def _boundary_bound(domain: Domain, p: np.ndarray, reach: float) -> np.ndarray:
    """A lower bound of every point's distance to the boundary and region curves, where
    it is at most ``reach`` (``inf`` beyond: the search stops there, as it must for
    speed, the samples lying on lines)."""
    tree, chord = _boundary_samples(domain)
    return tree.query(p, distance_upper_bound=float(reach) + chord)[0] - chord
