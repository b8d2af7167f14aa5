"""Mesh generators: rectangles, polygons with holes, discs (periodic squares are in
:mod:`dvstatic.periodic`).

Every generator places boundary nodes exactly on the boundary at spacing about ``h``
(polygon corners included), fills the interior according to ``kind``:

* ``lattice``: regular triangular lattice (rows ``h sqrt(3)/2`` apart);
* ``jittered``: lattice nodes moved by up to ``jitter * h``, the move tapering off
  within about one spacing of the boundary (well-shaped boundary cells);
* ``random``: uniformly distributed points of the same density;
* ``cvt``: random points moved by Lloyd iterations towards a centroidal Voronoi
  tessellation (boundary nodes fixed): near-regular cells without lattice directions,

and triangulates with :meth:`dvstatic.domain.Domain.triangulate` (Delaunay, conforming
to the boundary, triangles outside the domain removed).
"""

from __future__ import annotations

import logging

import numpy as np

from ._checks import check_positive, check_seed
from .domain import Circle, Domain, Polygon, rectangle_domain
from .mesh import Mesh

log = logging.getLogger(__name__)

#: Mesh kinds understood by the generators.
KINDS = ("lattice", "jittered", "random", "cvt")

#: Lloyd iterations of kind "cvt"
CVT_ITERATIONS = 30

SQRT3_2 = np.sqrt(3.0) / 2.0


def rectangle(
    width: float = 1.0,
    height: float = 1.0,
    h: float = 0.1,
    kind: str = "jittered",
    jitter: float = 0.3,
    seed: int | None = 0,
) -> Mesh:
    """Triangulated rectangle ``[0, width] x [0, height]``.

    Parameters
    ----------
    width, height : float
        Rectangle size (length units), > 0.
    h : float
        Target node spacing, 0 < h <= min(width, height).
    kind : {"lattice", "jittered", "random"}
        ``lattice``: regular triangular lattice (rows ``h sqrt(3)/2`` apart, exact
        equilateral triangles when the size fits); ``jittered``: lattice nodes shifted
        by up to ``jitter * h``, the shift tapering off within about one spacing of the
        sides, where nodes slide along their side by up to ``jitter * h / 2``; ``random``:
        uniformly distributed interior points (same density), boundary nodes at
        spacing about ``h``.
    jitter : float
        Relative jitter for ``kind="jittered"``, in [0, 0.5).
    seed : int or None
        Random seed.

    Returns
    -------
    Mesh
        With parts ``"bottom"``, ``"right"``, ``"top"``, ``"left"``; boundary nodes lie
        exactly on the sides.
    """
    width = check_positive("width", width)
    height = check_positive("height", height)
    h = check_positive("h", h)
    if h > min(width, height):
        raise ValueError(
            f"h = {h} is larger than the domain (min(width, height) = {min(width, height)}); "
            "use h <= min(width, height)"
        )
    kind, jitter, rng = _sampling(kind, jitter, seed)
    if kind in ("random", "cvt"):
        pts = _random_rectangle_points(width, height, h, rng)
    else:
        pts, boundary, side_dir, side_step = _lattice_points(width, height, h)
        if kind == "jittered" and jitter > 0:
            _jitter_rectangle(pts, boundary, side_dir, side_step, width, height, h, jitter, rng)
    pts = pts[spatial_order(pts)]
    domain = rectangle_domain(width, height)
    if kind == "cvt":
        pts = lloyd(domain, pts, h)
    pts, tri, parts = domain.triangulate(pts, 1e-9 * h)
    mesh = Mesh(pts, tri, parts=parts, domain=domain)
    log.debug("rectangle %s: %r", kind, mesh)
    return mesh


def generate(
    domain: Domain,
    h: float,
    kind: str = "jittered",
    jitter: float = 0.3,
    seed: int | None = 0,
) -> Mesh:
    """Mesh any :class:`~dvstatic.domain.Domain` (polygon or circle, with holes).

    Parameters
    ----------
    domain : Domain
    h : float
        Target node spacing, 0 < h <= the smallest extent of the domain.
    kind : {"lattice", "jittered", "random"}
    jitter : float
        Relative jitter for ``kind="jittered"``, in [0, 0.5).
    seed : int or None

    Returns
    -------
    Mesh
        With a part per polygon edge name and per hole name.
    """
    from scipy.spatial import cKDTree

    if not isinstance(domain, Domain):
        raise TypeError(f"domain must be a dvstatic Domain, got {type(domain).__name__}")
    h = check_positive("h", h)
    lo, hi = domain.bbox
    if h > float(np.min(hi - lo)):
        raise ValueError(
            f"h = {h} is larger than the domain (smallest extent {float(np.min(hi - lo)):.4g}); "
            "use a smaller h"
        )
    kind, jitter, rng = _sampling(kind, jitter, seed)
    bnd, seg_a, seg_b = _boundary_points(domain, h)
    inner = _interior_points(domain, h, "random" if kind == "cvt" else kind, jitter, rng)
    # Gabriel condition: no interior point inside the diametral circle of a boundary
    # segment, so that every segment is an edge of the Delaunay triangulation
    if len(inner):
        mid = 0.5 * (seg_a + seg_b)
        half = 0.5 * np.hypot(*(seg_b - seg_a).T)
        tree = cKDTree(mid)
        k = min(6, len(mid))
        dist, idx = tree.query(inner, k=k)
        dist, idx = dist.reshape(len(inner), k), idx.reshape(len(inner), k)
        inner = inner[~np.any(dist < half[idx] * (1 + 1e-9), axis=1)]
    pts = np.vstack([bnd, inner])
    pts = pts[spatial_order(pts)]
    if kind == "cvt":
        pts = lloyd(domain, pts, h)
    pts, tri, parts = domain.triangulate(pts, 1e-9 * h)
    mesh = Mesh(pts, tri, parts=parts, domain=domain)
    log.debug("generated %s mesh: %r", kind, mesh)
    return mesh


def polygon(
    vertices,
    h: float,
    kind: str = "jittered",
    jitter: float = 0.3,
    seed: int | None = 0,
    names=None,
    holes=(),
) -> Mesh:
    """Mesh a polygon, optionally with holes.

    Parameters
    ----------
    vertices : array_like, shape (k, 2)
        Corners in order (either orientation).
    h, kind, jitter, seed
        As for :func:`generate`.
    names : sequence of str, optional
        Name of every edge (edge i joins vertex i to vertex i+1); default
        ``"edge0"``, ``"edge1"``, ...
    holes : sequence of Polygon or Circle
        Hole loops (:class:`dvstatic.domain.Polygon`, :class:`dvstatic.domain.Circle`);
        each gives its part name to its whole boundary.

    Returns
    -------
    Mesh
    """
    v = np.asarray(vertices, dtype=float)
    if names is None:
        names = [f"edge{i}" for i in range(len(v))]
    return generate(Domain(Polygon(v, tuple(names)), tuple(holes)), h, kind, jitter, seed)


def disc(
    radius: float = 1.0,
    h: float = 0.1,
    center=(0.0, 0.0),
    kind: str = "jittered",
    jitter: float = 0.3,
    seed: int | None = 0,
    name: str = "boundary",
    holes=(),
) -> Mesh:
    """Mesh a disc (boundary part ``name``), optionally with holes."""
    radius = check_positive("radius", radius)
    return generate(Domain(Circle(center, radius, name), tuple(holes)), h, kind, jitter, seed)


def _boundary_points(domain: Domain, h: float):
    """Points on every curve at spacing about h, and the boundary segments."""
    pts, a_list, b_list = [], [], []
    for loop in domain.loops:
        if isinstance(loop, Polygon):
            v = loop.vertices
            w = np.roll(v, -1, axis=0)
            loop_pts = []
            for a, b in zip(v, w, strict=True):
                n = max(1, int(round(np.hypot(*(b - a)) / h)))
                t = np.arange(n)[:, None] / n
                loop_pts.append(a + t * (b - a))
            lp = np.vstack(loop_pts)
        else:
            # a multiple of 4: nodes on the axes through the centre (symmetric loads)
            n = 4 * max(2, int(round(2 * np.pi * loop.radius / (4 * h))))
            ang = 2 * np.pi * np.arange(n) / n
            lp = np.asarray(loop.center) + loop.radius * np.c_[np.cos(ang), np.sin(ang)]
        pts.append(lp)
        a_list.append(lp)
        b_list.append(np.roll(lp, -1, axis=0))
    return np.vstack(pts), np.vstack(a_list), np.vstack(b_list)


def _distance_to_boundary(domain: Domain, p: np.ndarray) -> np.ndarray:
    d, _ = domain.curve_distances(p)
    return d.min(axis=1)


def _interior_points(domain: Domain, h: float, kind: str, jitter: float, rng) -> np.ndarray:
    lo, hi = domain.bbox
    if kind == "random":
        n_target = int(round(domain.area / (SQRT3_2 * h * h)))
        out = np.zeros((0, 2))
        for _ in range(50):
            if len(out) >= n_target:
                break
            cand = lo + (hi - lo) * rng.random((2 * (n_target - len(out)) + 16, 2))
            ok = domain.contains(cand)
            cand = cand[ok]
            cand = cand[_distance_to_boundary(domain, cand) >= 0.3 * h]
            out = np.vstack([out, cand])
        return out[:n_target]
    hy = h * SQRT3_2
    ny = int(np.ceil((hi[1] - lo[1]) / hy)) + 1
    nx = int(np.ceil((hi[0] - lo[0]) / h)) + 2
    j, i = np.divmod(np.arange(nx * ny), nx)
    p = np.c_[lo[0] + (i + 0.5 * (j % 2) - 0.5) * h, lo[1] + j * hy]
    p = p[domain.contains(p)]
    d = _distance_to_boundary(domain, p)
    keep = d >= 0.45 * h
    p, d = p[keep], d[keep]
    if kind == "jittered" and jitter > 0 and len(p):
        taper = np.clip((d - 0.4 * h) / (0.8 * h), 0.0, 1.0)
        trial = p + _disc(rng, len(p)) * (jitter * h * taper)[:, None]
        ok = domain.contains(trial) & (_distance_to_boundary(domain, trial) >= 0.3 * h)
        p[ok] = trial[ok]
    return p


def lloyd(
    domain: Domain, points: np.ndarray, h: float, iterations: int = CVT_ITERATIONS
) -> np.ndarray:
    """Lloyd relaxation: interior points move to the centroids of their Voronoi cells.

    Boundary points (on a domain curve) stay. Cells are clipped to the triangulated
    domain; their centroids are assembled from the sub-triangles (vertex, edge
    midpoint, circumcentre) of every triangle, vectorised.

    Parameters
    ----------
    domain : Domain
    points : ndarray, shape (N, 2)
    h : float
        Spacing (sets the tolerance for "on the boundary").
    iterations : int

    Returns
    -------
    ndarray, shape (N, 2)
    """
    from .kinematics import circumcentres

    p = np.array(points, dtype=float)
    on_bnd = _distance_to_boundary(domain, p) <= 1e-9 * h
    movable = np.flatnonzero(~on_bnd)
    for _ in range(iterations):
        tri = domain._delaunay(p)
        x = p[tri]
        cc = circumcentres(x)
        n = len(p)
        area = np.zeros(n)
        moment = np.zeros((n, 2))
        for k in range(3):
            o, a = (k + 1) % 3, (k + 2) % 3
            mid = 0.5 * (x[:, o] + x[:, a])
            for v in (o, a):
                xv = x[:, v]
                sa = 0.5 * (
                    (mid[:, 0] - xv[:, 0]) * (cc[:, 1] - xv[:, 1])
                    - (mid[:, 1] - xv[:, 1]) * (cc[:, 0] - xv[:, 0])
                )
                sa = np.abs(sa) * np.sign(
                    (cc[:, 0] - mid[:, 0]) * (x[:, k, 0] - mid[:, 0])
                    + (cc[:, 1] - mid[:, 1]) * (x[:, k, 1] - mid[:, 1])
                )
                c = (xv + mid + cc) / 3.0
                area += np.bincount(tri[:, v], sa, n)
                for d in range(2):
                    moment[:, d] += np.bincount(tri[:, v], sa * c[:, d], n)
        ok = area[movable] > 1e-12 * h * h
        idx = movable[ok]
        target = moment[idx] / area[idx, None]
        inside = domain.contains(target) & (_distance_to_boundary(domain, target) > 0.2 * h)
        p[idx[inside]] = target[inside]
    return p


def with_spread(
    mesh: Mesh, sigma_l: float, seed: int | None = 0, rtol: float = 0.02, max_evaluations: int = 24
) -> Mesh:
    """Randomly moved copy of ``mesh`` whose sigma_L is about ``sigma_l`` (paper exp. 3).

    The perturbation amplitude of :meth:`Mesh.perturbed` is found by bisection.

    Parameters
    ----------
    mesh : Mesh
        A more regular mesh (lower sigma_L), generated in a domain.
    sigma_l : float
        Target std(l) / mean(l).
    seed : int or None
    rtol : float
        Accepted relative deviation from the target.

    Returns
    -------
    Mesh
        Its reached value is ``mesh.edge_length_spread()`` (logged).

    Raises
    ------
    ValueError
        If the target is below the spread of ``mesh`` or cannot be reached.
    """
    sigma_l = check_positive("sigma_l", sigma_l)
    s0 = mesh.edge_length_spread()
    if sigma_l < s0 * (1 - rtol):
        raise ValueError(
            f"target sigma_L = {sigma_l} is below the spread of the starting mesh "
            f"({s0:.4f}); start from a more regular mesh"
        )
    if sigma_l <= s0 * (1 + rtol):
        return mesh
    h = mesh.h
    lo, hi = 0.0, 0.5 * h
    best = (np.inf, mesh)
    for _ in range(max_evaluations):
        amp = 0.5 * (lo + hi)
        m = mesh.perturbed(amp, seed=seed)
        s = m.edge_length_spread()
        if abs(s - sigma_l) < best[0]:
            best = (abs(s - sigma_l), m)
        if abs(s / sigma_l - 1) <= rtol:
            break
        if s < sigma_l:
            lo = amp
            if hi - amp < 1e-3 * h:
                hi *= 2.0
        else:
            hi = amp
    m = best[1]
    reached = m.edge_length_spread()
    log.info("with_spread: target sigma_L %.4f, reached %.4f", sigma_l, reached)
    if abs(reached / sigma_l - 1) > 5 * rtol:
        raise ValueError(f"could not reach sigma_L = {sigma_l} (best {reached:.4f})")
    return m


def spatial_order(points: np.ndarray) -> np.ndarray:
    """Permutation that sorts points along a Morton (Z-order) curve.

    Neighbouring particles get nearby indices, which narrows the band of the
    stiffness matrix touched by each assembly chunk and improves cache use in
    matrix-vector products and AMG.
    """
    lo = points.min(axis=0)
    span = max(float(np.max(np.ptp(points, axis=0))), np.finfo(float).tiny)
    q = np.minimum(((points - lo) / span * 65535.0).astype(np.uint64), 65535)

    def spread(v: np.ndarray) -> np.ndarray:
        v = (v | (v << np.uint64(8))) & np.uint64(0x00FF00FF)
        v = (v | (v << np.uint64(4))) & np.uint64(0x0F0F0F0F)
        v = (v | (v << np.uint64(2))) & np.uint64(0x33333333)
        return (v | (v << np.uint64(1))) & np.uint64(0x55555555)

    key = spread(q[:, 0]) | (spread(q[:, 1]) << np.uint64(1))
    return np.argsort(key, kind="stable")


def _sampling(kind: str, jitter: float, seed) -> tuple[str, float, np.random.Generator]:
    """Checked ``kind`` and ``jitter`` (in [0, 0.5)) and the generator for ``seed``."""
    kind = _check_kind(kind)
    jitter = float(check_positive("jitter", jitter, allow_zero=True))
    if jitter >= 0.5:
        raise ValueError(f"jitter must be in [0, 0.5), got {jitter}")
    return kind, jitter, np.random.default_rng(check_seed(seed))


def _check_kind(kind: str) -> str:
    if not isinstance(kind, str):
        raise TypeError(f"kind must be a string, one of {KINDS}, got {type(kind).__name__}")
    if kind not in KINDS:
        raise ValueError(f"unknown mesh kind {kind!r}; accepted: {', '.join(KINDS)}")
    return kind


def _disc(rng: np.random.Generator, n: int) -> np.ndarray:
    """n points uniformly distributed in the unit disc."""
    r = np.sqrt(rng.random(n))
    t = 2 * np.pi * rng.random(n)
    return np.c_[r * np.cos(t), r * np.sin(t)]


def _lattice_points(width: float, height: float, h: float):
    """Triangular lattice filling the rectangle, boundary nodes on the sides.

    Returns points, boundary mask, along-side direction (0 = x, 1 = y, -1 corner)
    and the node spacing along that side.
    """
    nx = max(1, int(round(width / h)))
    ny = max(1, int(round(height / (h * SQRT3_2))))
    hx, hy = width / nx, height / ny
    rows = []
    for j in range(ny + 1):
        y = height if j == ny else j * hy
        if j % 2 == 0:
            x = np.arange(nx + 1) * hx
        else:
            x = np.concatenate([[0.0], (np.arange(nx) + 0.5) * hx, [width]])
        x[-1] = width
        rows.append(np.c_[x, np.full(len(x), y)])
    p = np.vstack(rows)
    on_x = (p[:, 0] == 0) | (p[:, 0] == width)
    on_y = (p[:, 1] == 0) | (p[:, 1] == height)
    boundary = on_x | on_y
    side_dir = np.full(len(p), -1)
    side_dir[on_y & ~on_x] = 0
    side_dir[on_x & ~on_y] = 1
    side_step = np.where(side_dir == 0, hx, hy)
    # on odd rows the x-sides get an extra node: spacing along them is hy
    return p, boundary, side_dir, side_step


def _jitter_rectangle(p, boundary, side_dir, side_step, width, height, h, jitter, rng) -> None:
    """Shift lattice nodes: interior nodes in a disc of radius ``jitter * h``, tapered
    to zero near the sides (ramp from 0.4 h to 1.2 h), boundary nodes along their side by
    up to half that. The taper keeps the boundary cells well shaped: a boundary node
    with two triangles and an obtuse angle makes the DV coupling there indefinite.
    """
    interior = ~boundary
    d_wall = np.minimum.reduce([p[:, 0], width - p[:, 0], p[:, 1], height - p[:, 1]])
    taper = np.clip((d_wall - 0.4 * h) / (0.8 * h), 0.0, 1.0)
    shift = _disc(rng, len(p)) * (jitter * h * taper)[:, None]
    p[interior] += shift[interior]
    slide = (rng.random(len(p)) * 2 - 1) * 0.5 * jitter * side_step
    for axis in (0, 1):
        sel = boundary & (side_dir == axis)
        p[sel, axis] += slide[sel]


def _random_rectangle_points(width: float, height: float, h: float, rng) -> np.ndarray:
    nbx = max(1, int(round(width / h)))
    nby = max(1, int(round(height / h)))
    xs = np.linspace(0.0, width, nbx + 1)
    ys = np.linspace(0.0, height, nby + 1)
    xs[-1], ys[-1] = width, height
    bnd = np.vstack(
        [
            np.c_[xs, np.zeros_like(xs)],
            np.c_[xs, np.full_like(xs, height)],
            np.c_[np.zeros(nby - 1), ys[1:-1]],
            np.c_[np.full(nby - 1, width), ys[1:-1]],
        ]
    )
    n_int = max(0, int(round(width * height / (SQRT3_2 * h * h) - 0.5 * len(bnd))))
    margin = 0.1 * h
    inner = np.c_[
        margin + (width - 2 * margin) * rng.random(n_int),
        margin + (height - 2 * margin) * rng.random(n_int),
    ]
    return np.vstack([bnd, inner])


def _move_in_domain(domain: Domain, p: np.ndarray, amplitude: float, rng, tol: float) -> np.ndarray:
    """Random moves keeping boundary nodes on their curve and corners fixed."""
    p = p.copy()
    dist, names = domain.curve_distances(p)
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
    curves = []
    for loop in domain.loops:
        if isinstance(loop, Polygon):
            curves.extend(("seg", a, b) for _, a, b in loop.curves())
        else:
            curves.append(("circle", loop, None))
    interior = n_on == 0
    # boundary nodes: slide along their curve
    for c, (kind, a, b) in enumerate(curves):
        sel = np.flatnonzero(on[:, c] & ~is_corner & (n_on == 1))
        if sel.size == 0:
            continue
        s = (rng.random(sel.size) * 2 - 1) * amplitude
        if kind == "seg":
            t = (b - a) / np.hypot(*(b - a))
            length = np.hypot(*(b - a))
            u = np.einsum("ij,j->i", p[sel] - a, t) + s
            u = np.clip(u, 0.05 * amplitude, length - 0.05 * amplitude)
            p[sel] = a + u[:, None] * t
        else:
            circ: Circle = a
            cc = np.asarray(circ.center)
            ang = np.arctan2(p[sel, 1] - cc[1], p[sel, 0] - cc[0]) + s / circ.radius
            p[sel] = cc + circ.radius * np.c_[np.cos(ang), np.sin(ang)]
    idx = np.flatnonzero(interior)
    for _ in range(8):
        if idx.size == 0:
            break
        trial = p[idx] + _disc(rng, idx.size) * amplitude
        d, _ = domain.curve_distances(trial)
        good = domain.contains(trial) & (d.min(axis=1) > 0.05 * amplitude)
        p[idx[good]] = trial[good]
        idx = idx[~good]
    return p
