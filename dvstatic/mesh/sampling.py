"""Random point moves and periodic Delaunay triangulation (the pieces generators and
:meth:`Mesh.perturbed <dvstatic.mesh.Mesh.perturbed>` share)."""

from __future__ import annotations

import numpy as np

from .._planar import circumcentres, cross
from ..errors import InputError
from .domain import Domain
from .topology import build_topology

__all__ = ["unit_disc", "move_in_domain", "periodic_delaunay", "cell_centroids"]


def unit_disc(rng: np.random.Generator, n: int) -> np.ndarray:
    """n points uniformly distributed in the unit disc."""
    r = np.sqrt(rng.random(n))
    t = 2 * np.pi * rng.random(n)
    return np.c_[r * np.cos(t), r * np.sin(t)]


def move_in_domain(domain: Domain, p: np.ndarray, amplitude: float, rng, tol: float) -> np.ndarray:
    """Random moves of points generated in ``domain``: interior points by up to
    ``amplitude`` in a random direction (kept inside, off the boundary and the region
    curves), points on a boundary or region curve along it by up to ``amplitude``;
    corners stay. Returns the moved copy."""
    p = p.copy()
    curves = domain.boundary_curves() + domain.region_curves()
    dist = _all_distances(domain, p)
    on = dist <= tol
    n_on = on.sum(axis=1)
    corners = domain.corners()
    is_corner = n_on >= 2
    if len(corners):
        dc = np.min(
            np.hypot(p[:, None, 0] - corners[None, :, 0], p[:, None, 1] - corners[None, :, 1]),
            axis=1,
        )
        is_corner |= dc <= tol
    # nodes on a curve: slide along it
    for c, curve in enumerate(curves):
        sel = np.flatnonzero(on[:, c] & ~is_corner & (n_on == 1))
        if sel.size == 0:
            continue
        s = (rng.random(sel.size) * 2 - 1) * amplitude
        p[sel] = curve.slide(p[sel], s, 0.05 * amplitude)
    idx = np.flatnonzero(n_on == 0)
    for _ in range(8):
        if idx.size == 0:
            break
        trial = p[idx] + unit_disc(rng, idx.size) * amplitude
        d = _all_distances(domain, trial)
        good = domain.contains(trial) & (d.min(axis=1) > 0.05 * amplitude)
        p[idx[good]] = trial[good]
        idx = idx[~good]
    return p


def cell_centroids(
    x: np.ndarray, tri: np.ndarray, n: int, offsets: np.ndarray | None = None, density=None
) -> tuple[np.ndarray, np.ndarray]:
    """Areas (n,) and centroids (n, 2) of the Voronoi cells of ``n`` points, from the
    Delaunay triangles ``tri`` (M, 3) with vertex positions ``x`` (M, 3, 2): each
    triangle adds, for each of its vertices, the two sub-triangles (vertex, edge
    midpoint, circumcentre), signed so that obtuse triangles subtract what lies outside.
    Cells of points on the hull are clipped to it (Lloyd iterations keep those fixed).
    ``offsets`` (M, 3, 2) (periodic meshes: image times period) is subtracted from the
    pieces of each vertex, so that its centroid is near its own position. With
    ``density(points) -> (m,)`` the centroids are weighted by it (evaluated at the
    centre of every piece)."""
    cc = circumcentres(x)
    area = np.zeros(n)
    moment = np.zeros((n, 2))
    for k in range(3):
        o, a = (k + 1) % 3, (k + 2) % 3
        mid = 0.5 * (x[:, o] + x[:, a])
        # the sub-triangle counts negative when the circumcentre lies beyond the edge
        sign = np.sign(np.einsum("mi,mi->m", cc - mid, x[:, k] - mid))
        for v in (o, a):
            xv = x[:, v]
            sa = 0.5 * np.abs(cross(mid - xv, cc - xv)) * sign
            c = (xv + mid + cc) / 3.0
            if density is not None:
                sa = sa * density(c)
            if offsets is not None:
                c = c - offsets[:, v]
            area += np.bincount(tri[:, v], sa, n)
            for d in range(2):
                moment[:, d] += np.bincount(tri[:, v], sa * c[:, d], n)
    safe = np.where(area > 0, area, 1.0)
    return area, moment / safe[:, None]


def _all_distances(domain: Domain, p: np.ndarray) -> np.ndarray:
    """Distances to every boundary curve, then every region curve, (n, c)."""
    d, _ = domain.curve_distances(p)
    return np.hstack([d, domain.region_distances(p)])


def periodic_delaunay(p: np.ndarray, period: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Delaunay triangulation of points in a periodic box.

    Points are copied across the box sides within a margin, triangulated, and the
    triangles whose centroid lies in the box are kept, each once.

    Returns
    -------
    triangles : ndarray of int, shape (M, 3)
    images : ndarray of int, shape (M, 3, 2)
        Periodic image of every triangle vertex.
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
        a2 = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        tri[a2 < 0] = tri[a2 < 0][:, [0, 2, 1]]
        area = 0.5 * np.abs(a2).sum()
        ok = abs(area - period.prod()) <= 1e-9 * period.prod()
        if ok:
            try:
                t, im = ids[tri], img[tri]
                build_topology(t, n, im)
                order = np.argsort(t.min(axis=1), kind="stable")
                return t[order], im[order]
            except InputError:
                ok = False
        if margin >= 1.0:
            raise InputError("could not build a periodic triangulation of these points", "points")
        margin = min(1.0, 2 * margin)
