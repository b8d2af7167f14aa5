"""Periodic meshes of the unit square (representative volume elements)."""

from __future__ import annotations

import numpy as np

from .._checks import check_int
from .core import Mesh
from .generators import SQRT3_2, check_sampling
from .ordering import spatial_order
from .sampling import periodic_delaunay, unit_disc

__all__ = ["periodic_square", "periodic_delaunay", "PERIODIC_KINDS"]

#: point sets of periodic samples
PERIODIC_KINDS = ("random", "jittered", "lattice")


def periodic_square(
    n_points: int, kind: str = "random", seed: int | None = 0, jitter: float = 0.3
) -> Mesh:
    """Periodic triangulation of the unit square (a representative volume element).

    Parameters
    ----------
    n_points : int
        Approximate number of particles, >= 16 (exact for ``random``).
    kind : {"random", "jittered", "lattice"}
        ``lattice`` is a triangular lattice with ``nx`` columns and an even number of
        rows (so it closes periodically; nearly equilateral), ``jittered`` the same
        with shifts up to ``jitter`` times the spacing, ``random`` uniform points.
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
    if kind == "random":
        p = rng.random((n_points, 2))
    else:
        nx = max(4, int(round(np.sqrt(n_points * SQRT3_2))))
        ny = max(4, 2 * int(round(nx / np.sqrt(3.0))))
        j, i = np.divmod(np.arange(nx * ny), nx)
        p = np.c_[(i + 0.5 * (j % 2) + 0.25) / nx, (j + 0.25) / ny]
        if kind == "jittered" and jitter > 0:
            p += unit_disc(rng, len(p)) * jitter / nx
            p = np.mod(p, 1.0)
    p[p >= 1.0] = 0.0
    p = p[spatial_order(p)]
    period = np.array([1.0, 1.0])
    tri, images = periodic_delaunay(p, period)
    return Mesh(p, tri, period=period, images=images)
