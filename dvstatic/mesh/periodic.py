"""Periodic meshes (representative volume elements): the unit square, and samples made
by the recipe of a generated mesh."""

from __future__ import annotations

import numpy as np

from .._checks import check_int
from ..errors import InputError
from .core import Mesh
from .generators import CVT_ITERATIONS, SQRT3_2, check_sampling
from .ordering import spatial_order
from .recipe import Sampling
from .sampling import cell_centroids, periodic_delaunay, unit_disc

__all__ = ["periodic_square", "periodic_sample", "periodic_delaunay", "PERIODIC_KINDS"]

#: point sets of periodic samples
PERIODIC_KINDS = ("random", "jittered", "lattice", "cvt")


def periodic_square(
    n_points: int, kind: str = "random", seed: int | None = 0, jitter: float = 0.3
) -> Mesh:
    """Periodic triangulation of the unit square (a representative volume element).

    Parameters
    ----------
    n_points : int
        Approximate number of particles, >= 16 (exact for ``random`` and ``cvt``).
    kind : {"random", "jittered", "lattice", "cvt"}
        ``lattice`` is a triangular lattice with ``nx`` columns and an even number of
        rows (so it closes periodically; nearly equilateral), ``jittered`` the same
        with shifts up to ``jitter`` times the spacing, ``random`` uniform points,
        ``cvt`` random points after 30 periodic Lloyd iterations.
    seed : int or None
        Random seed.
    jitter : float
        Relative jitter for ``kind="jittered"``, in [0, 0.5).

    Returns
    -------
    Mesh
        Periodic mesh (``period = (1, 1)``); bonds across the period carry the image
        shift in :attr:`Topology.bond_image`.
    """
    n_points = check_int("n_points", n_points, minimum=16)
    kind, jitter, rng = check_sampling(kind, jitter, seed, PERIODIC_KINDS)
    period = np.array([1.0, 1.0])
    if kind in ("random", "cvt"):
        p = rng.random((n_points, 2))
        h = np.sqrt(1.0 / (SQRT3_2 * n_points))
    else:
        nx = max(4, int(round(np.sqrt(n_points * SQRT3_2))))
        ny = max(4, 2 * int(round(nx / np.sqrt(3.0))))
        j, i = np.divmod(np.arange(nx * ny), nx)
        p = np.c_[(i + 0.5 * (j % 2) + 0.25) / nx, (j + 0.25) / ny]
        h = 1.0 / nx
        if kind == "jittered" and jitter > 0:
            p = p + unit_disc(rng, len(p)) * jitter / nx
    sampling = Sampling(kind, jitter, CVT_ITERATIONS, h=h)
    if kind == "cvt":
        p = periodic_lloyd(p, period, CVT_ITERATIONS)
    return _periodic_mesh(p, period, sampling)


def periodic_sample(sampling: Sampling, n_points: int, seed: int | None = 0) -> Mesh:
    """A periodic sample made by the recipe of a generated mesh.

    Lattice-based recipes (``lattice``, ``jittered``) use an exactly equilateral
    lattice with an even number of rows, so the period is ``(1, ny sqrt(3)/2 / nx)``;
    ``random`` and ``cvt`` use the unit square. The recipe's perturbations follow, each
    a random move of every node by up to its amplitude times the spacing.

    Parameters
    ----------
    sampling : Sampling
        The recipe (:attr:`Mesh.sampling`), reproducible (no unknown amplitudes).
    n_points : int
        Approximate number of particles, >= 64.
    seed : int or None

    Returns
    -------
    Mesh
        Periodic, with ``sampling`` recorded.
    """
    if not isinstance(sampling, Sampling):
        raise TypeError(f"sampling must be a Sampling, got {type(sampling).__name__}")
    if not sampling.reproducible:
        raise InputError(f"the recipe {sampling} cannot be reproduced", "sampling")
    n_points = check_int("n_points", n_points, minimum=64)
    _, _, rng = check_sampling("random", 0.0, seed)
    if sampling.kind in ("random", "cvt"):
        period = np.array([1.0, 1.0])
        h = np.sqrt(1.0 / (SQRT3_2 * n_points))
        p = rng.random((n_points, 2))
        if sampling.kind == "cvt":
            p = periodic_lloyd(p, period, sampling.iterations)
    else:
        nx = max(4, int(round(np.sqrt(n_points * SQRT3_2))))
        ny = 2 * max(2, int(round(n_points / nx / 2)))
        h = 1.0 / nx
        period = np.array([1.0, ny * SQRT3_2 * h])
        j, i = np.divmod(np.arange(nx * ny), nx)
        p = np.c_[(i + 0.5 * (j % 2) + 0.25) * h, (j + 0.25) * SQRT3_2 * h]
        if sampling.jitter > 0:
            p = p + unit_disc(rng, len(p)) * sampling.jitter * h
    for amp in sampling.perturbations:
        p = p + unit_disc(rng, len(p)) * amp * h
    return _periodic_mesh(p, period, Sampling(**{**sampling.__dict__, "h": h, "graded": False}))


def periodic_lloyd(p: np.ndarray, period: np.ndarray, iterations: int) -> np.ndarray:
    """Lloyd iterations in a periodic box: every point moves to the centroid of its
    Voronoi cell (periodically wrapped), ``iterations`` times. Returns the moved copy."""
    p = np.mod(np.array(p, dtype=float), period)
    for _ in range(iterations):
        p[p >= period] = 0.0
        tri, images = periodic_delaunay(p, period)
        offsets = images * period
        area, centroid = cell_centroids(p[tri] + offsets, tri, len(p), offsets)
        # a centroid near a side may lie just outside the box: wrap it back
        ok = area > 0
        p[ok] = np.mod(centroid[ok], period)
    return p


def _periodic_mesh(p: np.ndarray, period: np.ndarray, sampling: Sampling) -> Mesh:
    p = np.mod(p, period)
    p[p >= period] = 0.0
    p = p[spatial_order(p)]
    tri, images = periodic_delaunay(p, period)
    return Mesh(p, tri, period=period, images=images, sampling=sampling)
