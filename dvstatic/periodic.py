"""Periodic meshes of the unit square (representative volume elements)."""

from __future__ import annotations

import numpy as np

from ._checks import check_int
from .mesh import Mesh, _cross, _topology
from .meshgen import SQRT3_2, _disc, _sampling, spatial_order

__all__ = ["periodic_square", "periodic_delaunay"]


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
    kind, jitter, rng = _sampling(kind, jitter, seed)
    if kind == "random":
        p = rng.random((n_points, 2))
    else:
        nx = max(4, int(round(np.sqrt(n_points * SQRT3_2))))
        ny = max(4, 2 * int(round(nx / np.sqrt(3.0))))
        j, i = np.divmod(np.arange(nx * ny), nx)
        p = np.c_[(i + 0.5 * (j % 2) + 0.25) / nx, (j + 0.25) / ny]
        if kind == "jittered" and jitter > 0:
            p += _disc(rng, len(p)) * jitter / nx
            p = np.mod(p, 1.0)
    p[p >= 1.0] = 0.0
    p = p[spatial_order(p)]
    period = np.array([1.0, 1.0])
    tri, images = periodic_delaunay(p, period)
    return Mesh(p, tri, period=period, images=images)


def periodic_delaunay(p: np.ndarray, period: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Delaunay triangulation of points in a periodic box.

    Points are copied across the box sides within a margin, triangulated, and the
    triangles whose centroid lies in the box are kept, each once.
    """
    from scipy.spatial import Delaunay

    n = len(p)
    margin = min(1.0, 4.0 * np.sqrt(np.log(n + 2.0) / n))
    while True:
        offs = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)])
        allp, ids, img = [], [], []
        for o in offs:
            q = p + o * period
            keep = np.all((q >= -margin * period) & (q < (1 + margin) * period), axis=1)
            allp.append(q[keep])
            ids.append(np.flatnonzero(keep))
            img.append(np.broadcast_to(o, (int(keep.sum()), 2)))
        allp = np.vstack(allp)
        ids = np.concatenate(ids)
        img = np.vstack(img)
        tri = Delaunay(allp).simplices
        c = allp[tri].mean(axis=1)
        keep = np.all((c >= 0) & (c < period), axis=1)
        tri = tri[keep]
        x = allp[tri]
        a2 = _cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        tri[a2 < 0] = tri[a2 < 0][:, [0, 2, 1]]
        area = 0.5 * np.abs(a2).sum()
        ok = abs(area - period.prod()) <= 1e-9 * period.prod()
        if ok:
            try:
                t, im = ids[tri], img[tri]
                _topology(t, n, im)
                order = np.argsort(t.min(axis=1), kind="stable")
                return t[order], im[order]
            except ValueError:
                ok = False
        if margin >= 1.0:
            raise ValueError("could not build a periodic triangulation of these points")
        margin = min(1.0, 2 * margin)
