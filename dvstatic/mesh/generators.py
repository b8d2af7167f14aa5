"""Mesh generators: rectangles, polygons with holes, discs (periodic squares are in
:mod:`dvstatic.mesh.periodic`).

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

from .._checks import check_choice, check_positive, check_seed
from ..errors import InputError
from .core import Mesh
from .distance import distance_to_boundary
from .domain import Circle, Domain, Polygon, rectangle_domain
from .graded import SizeField, check_h, density_points, local_h, min_h, spaced
from .grid import (
    SQRT3_2,
    Grid,
    jitter_rectangle,
    lattice_counts,
    lattice_points,
    random_rectangle_points,
)
from .ordering import spatial_order
from .recipe import ROW_KINDS, Sampling
from .sampling import cell_centroids, unit_disc

__all__ = [
    "KINDS",
    "rectangle",
    "generate",
    "polygon",
    "disc",
    "lloyd",
    "with_spread",
    "check_sampling",
    "SQRT3_2",
    "DEFAULT_JITTER",
]

log = logging.getLogger(__name__)

#: Mesh kinds understood by the generators.
KINDS = ("lattice", "jittered", "random", "cvt")
#: the kind of a mesh with a uniform spacing when none is given (graded meshes: "cvt")
DEFAULT_KIND = "jittered"


#: relative jitter of kind "jittered": irregular (sigma_L about 0.1) yet well-shaped
#: cells, no obtuse interior triangle (0.3 gives about 10 % of them, which soften DV)
DEFAULT_JITTER = 0.15

#: a generated mesh with fewer nodes is warned about
COARSE_NODES = 50

#: Lloyd iterations of kind "cvt"
CVT_ITERATIONS = 30


def rectangle(
    width: float = 1.0,
    height: float = 1.0,
    h: float = 0.1,
    kind: str | None = None,
    jitter: float = DEFAULT_JITTER,
    seed: int | None = 0,
    regions=(),
    holes=(),
) -> Mesh:
    """Triangulated rectangle ``[0, width] x [0, height]``.

    Parameters
    ----------
    width, height : float
        Rectangle size (length units), > 0.
    h : float or callable
        Target node spacing, 0 < h <= min(width, height); or a size field ``h(x) ->
        (m,)`` for points ``x`` (m, 2): a graded mesh whose spacing follows it
        (:mod:`dvstatic.mesh.graded`).
    kind : {"lattice", "jittered", "random", "cvt"}, optional
        Default ``"jittered"``, and ``"cvt"`` for a graded mesh (a size field), which
        can be ``"cvt"`` or ``"random"`` only (the rows of a lattice cannot grade).
        ``lattice``: regular triangular lattice (rows ``h sqrt(3)/2`` apart, exact
        equilateral triangles when the size fits); ``jittered``: lattice nodes shifted
        by up to ``jitter * h``, the shift tapering off within about one spacing of the
        sides, where nodes slide along their side by up to ``jitter * h / 2``; ``random``:
        uniformly distributed interior points (same density), boundary nodes at
        spacing about ``h``; ``cvt``: random points moved by Lloyd iterations towards a
        centroidal Voronoi tessellation.
    jitter : float
        Relative jitter for ``kind="jittered"``, in [0, 0.5) (default 0.15: sigma_L about
        0.1, no obtuse interior triangle).
    seed : int or None
        Random seed.
    regions : sequence of Polygon, Circle or Path
        Named regions inside the rectangle (``dv.domain.Circle(c, r, name="inclusion")``,
        ``dv.domain.Polygon(v, name="layer")``): the triangles conform to their
        boundaries and ``mesh.regions`` lists their triangles.
    holes : sequence of Polygon, Circle or Path
        Holes (each gives its name to its boundary part), as for :func:`polygon`.

    Returns
    -------
    Mesh
        With parts ``"bottom"``, ``"right"``, ``"top"``, ``"left"``; boundary nodes lie
        exactly on the sides.
    """
    width = check_positive("width", width)
    height = check_positive("height", height)
    if callable(h) or holes:
        domain = rectangle_domain(width, height)
        return generate(Domain(domain.outer, tuple(holes), tuple(regions)), h, kind, jitter, seed)
    h = check_positive("h", h)
    kind = DEFAULT_KIND if kind is None else kind
    if h > min(width, height):
        raise InputError(
            f"h = {h} is larger than the domain (min(width, height) = {min(width, height)}); "
            "use h <= min(width, height)",
            "h",
        )
    kind, jitter, rng = check_sampling(kind, jitter, seed)
    if kind in ("random", "cvt"):
        pts = random_rectangle_points(width, height, h, rng)
    else:
        pts, boundary, side_dir, side_step = lattice_points(width, height, h)
        # the lattice's own spacing (within 15 % of h): the jitter is relative to it,
        # so that the interior has the statistics of the recipe (and its calibration)
        h = width / lattice_counts(width, height, h)[0]
        if kind == "jittered" and jitter > 0:
            jitter_rectangle(pts, boundary, side_dir, side_step, width, height, h, jitter, rng)
    domain = rectangle_domain(width, height)
    if regions:
        domain = Domain(domain.outer, (), tuple(regions))
    return _triangulated(domain, pts, h, Sampling(kind, jitter, CVT_ITERATIONS, h=h))


def generate(
    domain: Domain,
    h: float,
    kind: str | None = None,
    jitter: float = DEFAULT_JITTER,
    seed: int | None = 0,
) -> Mesh:
    """Mesh any :class:`~dvstatic.domain.Domain` (polygon or circle, with holes).

    Parameters
    ----------
    domain : Domain
    h : float or callable
        Target node spacing, 0 < h <= the smallest extent of the domain; or a size
        field ``h(x) -> (m,)`` (see :func:`rectangle`).
    kind : {"lattice", "jittered", "random", "cvt"}, optional
        As for :func:`rectangle` (default ``"jittered"``, ``"cvt"`` for a size field).
    jitter : float
        Relative jitter for ``kind="jittered"``, in [0, 0.5) (default 0.15: sigma_L about
        0.1, no obtuse interior triangle).
    seed : int or None

    Returns
    -------
    Mesh
        With a part per boundary curve name and a region per region of the domain.
    """
    if not isinstance(domain, Domain):
        raise TypeError(f"domain must be a dvstatic Domain, got {type(domain).__name__}")
    h = check_h(h, domain)
    if isinstance(h, SizeField):
        return _graded(domain, h, "cvt" if kind is None else kind, seed)
    kind = DEFAULT_KIND if kind is None else kind
    lo, hi = domain.bbox
    if h > float(np.min(hi - lo)):
        raise InputError(
            f"h = {h} is larger than the domain (smallest extent {float(np.min(hi - lo)):.4g}); "
            "use a smaller h",
            "h",
        )
    kind, jitter, rng = check_sampling(kind, jitter, seed)
    grid = Grid.fitted(*domain.bbox, h) if kind in ROW_KINDS else None
    bnd, seg_a, seg_b = _loop_points(domain.loops, h, grid)
    inner = _interior_points(domain, h, "random" if kind == "cvt" else kind, jitter, rng, grid)
    inner = _gabriel(inner, seg_a, seg_b)
    sampling = Sampling(kind, jitter, CVT_ITERATIONS, h=grid.hx if grid is not None else h)
    return _triangulated(domain, np.vstack([bnd, inner]), h, sampling)


def _graded(domain: Domain, h: SizeField, kind: str, seed) -> Mesh:
    """A mesh whose spacing follows the size field ``h``: CVT of density 1 / h^2
    (``kind="random"``: the random points only)."""
    kind, _, rng = check_sampling(kind, 0.0, seed)
    if kind in ROW_KINDS:
        raise InputError(
            f"a graded mesh (h as a size field) cannot be of kind {kind!r}: the rows of a "
            "lattice do not grade; use kind='cvt' (the default for graded meshes) or 'random'",
            "kind",
        )
    bnd, seg_a, seg_b = _loop_points(domain.loops, h)
    inner = density_points(domain, h, rng, lambda p: distance_to_boundary(domain, p))
    inner = _gabriel(inner, seg_a, seg_b)
    graded = h.max > h.min * (1.0 + 1e-9)  # a constant field grades nothing
    sampling = Sampling(kind, 0.0, CVT_ITERATIONS, h=h.min, graded=graded)
    return _triangulated(domain, np.vstack([bnd, inner]), h, sampling)


def _gabriel(inner: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray) -> np.ndarray:
    """Points outside the diametral circle of every segment (Gabriel condition), so
    that every segment is an edge of the Delaunay triangulation."""
    from scipy.spatial import cKDTree

    if not len(inner) or not len(seg_a):
        return inner
    mid = 0.5 * (seg_a + seg_b)
    half = 0.5 * np.hypot(*(seg_b - seg_a).T)
    k = min(6, len(mid))
    dist, idx = cKDTree(mid).query(inner, k=k)
    dist, idx = dist.reshape(len(inner), k), idx.reshape(len(inner), k)
    return inner[~np.any(dist < half[idx] * (1 + 1e-9), axis=1)]


def _triangulated(domain: Domain, pts: np.ndarray, h, sampling: Sampling) -> Mesh:
    """The mesh of ``pts`` in ``domain``: region curves added (points near them
    removed), Morton order, Lloyd iterations for ``cvt``, conforming Delaunay
    triangulation."""
    segments = None
    n_fixed = 0
    if domain.regions:
        rp, segments = _region_points(domain, h)
        pts = _clear_around(domain, pts, rp, h)
        pts = np.vstack([rp, _gabriel(pts, rp[segments[:, 0]], rp[segments[:, 1]])])
        n_fixed = len(rp)
    order = np.concatenate([np.arange(n_fixed), n_fixed + spatial_order(pts[n_fixed:])])
    pts = pts[order]
    if sampling.kind == "cvt":
        pts = lloyd(domain, pts, h, sampling.iterations)
    pts, tri, parts, regions = domain.triangulate(pts, 1e-9 * min_h(h), segments=segments)
    mesh = Mesh(pts, tri, parts=parts, regions=regions, domain=domain, sampling=sampling)
    log.debug("generated %s mesh: %r", sampling, mesh)
    if mesh.n_points < COARSE_NODES:
        log.warning(
            "the mesh has only %d nodes (h = %.3g): a lattice this coarse has errors of "
            "tens of percent (its stresses average over 4 spacings); use a smaller h",
            mesh.n_points,
            min_h(h),
        )
    return mesh


def _region_points(domain: Domain, h) -> tuple[np.ndarray, np.ndarray]:
    """Points along the region curves inside the body (spacing about h, none within
    0.45 h of the boundary), plus the region corners that lie on the boundary; and the
    segments between consecutive points that run inside the body, (s, 3): two point
    indices and the index of their region curve."""
    tol = 1e-9 * min_h(h)
    pts, segs, k0 = [], [], 0
    n = 0
    for loop in domain.regions:
        curves = loop.pieces()
        keep_pts, keep_curve = [], []
        for k, c in enumerate(curves):
            p = spaced(c, h)
            d = _distance_to_domain_boundary(domain, p)
            corner = np.zeros(len(p), dtype=bool)
            corner[0] = not c.closed  # the curve's start is a corner of the loop
            ok = (d >= 0.45 * local_h(h, p)) | (corner & (d <= tol))
            keep_pts.append(p[ok])
            keep_curve.append(np.full(int(ok.sum()), k0 + k))
        p = np.vstack(keep_pts)
        curve = np.concatenate(keep_curve)
        ids = n + np.arange(len(p))
        nxt = np.roll(np.arange(len(p)), -1)
        # a segment runs along the curve of its first point (a corner ends that curve):
        # kept where its end lies on that curve too and it runs inside the body
        on_curve = np.array(
            [
                curves[c - k0].distance(p[j : j + 1])[0] <= tol
                for c, j in zip(curve, nxt, strict=True)
            ]
        )
        mid = 0.5 * (p + p[nxt])
        inside = on_curve & (_distance_to_domain_boundary(domain, mid) > tol)
        pts.append(p)
        segs.append(np.c_[ids, ids[nxt], curve][inside])
        n += len(p)
        k0 += len(curves)
    return np.vstack(pts), np.vstack(segs).astype(np.int64)


def _clear_around(domain: Domain, pts: np.ndarray, rp: np.ndarray, h) -> np.ndarray:
    """``pts`` without the points within 0.45 h of a region curve: interior points, and
    boundary points (other than the domain's corners) near a region point on the
    boundary or near a region curve that runs inside the body."""
    tol = 1e-9 * min_h(h)
    hp = np.broadcast_to(local_h(h, pts), (len(pts),))
    on_bnd = _distance_to_domain_boundary(domain, pts) <= tol
    far = domain.region_distances(pts).min(axis=1) >= 0.45 * hp
    bnd_rp = rp[_distance_to_domain_boundary(domain, rp) <= tol]
    if on_bnd.any():
        idx = np.flatnonzero(on_bnd)
        # near a region curve that runs along the boundary is fine; near one that
        # leaves it (or near a region point on the boundary) is not
        inner = _inner_region_distance(domain, pts[idx], min_h(h))
        near_rp = _near(pts[idx], bnd_rp, 0.45 * min_h(h))
        corner = _near(pts[idx], domain.boundary_corners(), tol)
        far[idx] = ((inner >= 0.45 * hp[idx]) & ~near_rp) | corner
        far[idx] &= ~_near(pts[idx], bnd_rp, tol)  # the region's own point replaces it
    return pts[far]


def _inner_region_distance(domain: Domain, p: np.ndarray, h: float) -> np.ndarray:
    """Distance of points to the parts of the region curves inside the body (sampled
    at spacing h / 8), (n,)."""
    samples = np.vstack([c.spaced(h / 8) for c in domain.region_curves()])
    samples = samples[_distance_to_domain_boundary(domain, samples) > 1e-9 * h]
    if not len(samples):
        return np.full(len(p), np.inf)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(samples).query(p)
    return d


def _near(p: np.ndarray, q: np.ndarray, tol: float) -> np.ndarray:
    """Which points ``p`` lie within ``tol`` of one of ``q``, (n,) bool."""
    if not len(q) or not len(p):
        return np.zeros(len(p), dtype=bool)
    return np.min(np.hypot(*(p[:, None, :] - q[None]).transpose(2, 0, 1)), axis=1) <= tol


def _distance_to_domain_boundary(domain: Domain, p: np.ndarray) -> np.ndarray:
    d, _ = domain.curve_distances(p)
    return d.min(axis=1)


def polygon(
    vertices,
    h: float,
    kind: str | None = None,
    jitter: float = DEFAULT_JITTER,
    seed: int | None = 0,
    names=None,
    holes=(),
    regions=(),
) -> Mesh:
    """Mesh a polygon, optionally with holes and regions.

    Parameters
    ----------
    vertices : array_like, shape (k, 2)
        Corners in order (either orientation).
    h, kind, jitter, seed
        As for :func:`generate`.
    names : sequence of str, optional
        Name of every edge (edge i joins vertex i to vertex i+1); default
        ``"edge0"``, ``"edge1"``, ...
    holes : sequence of Polygon, Circle or Path
        Hole loops (:class:`dvstatic.domain.Polygon`, :class:`dvstatic.domain.Circle`);
        each gives its part name to its whole boundary.
    regions : sequence of Polygon, Circle or Path
        Named regions inside the body (see :func:`rectangle`).

    Returns
    -------
    Mesh
    """
    v = np.asarray(vertices, dtype=float)
    if names is None:
        names = [f"edge{i}" for i in range(len(v))]
    domain = Domain(Polygon(v, tuple(names)), tuple(holes), tuple(regions))
    return generate(domain, h, kind, jitter, seed)


def disc(
    radius: float = 1.0,
    h: float = 0.1,
    center=(0.0, 0.0),
    kind: str | None = None,
    jitter: float = DEFAULT_JITTER,
    seed: int | None = 0,
    name: str = "boundary",
    holes=(),
    regions=(),
) -> Mesh:
    """Mesh a disc (boundary part ``name``), optionally with holes and regions."""
    radius = check_positive("radius", radius)
    domain = Domain(Circle(center, radius, name), tuple(holes), tuple(regions))
    return generate(domain, h, kind, jitter, seed)


def _loop_points(loops, h, grid: Grid | None = None):
    """Points on every curve of ``loops`` at spacing about h (from the lattice ``grid``
    where a line runs along it), and the segments between consecutive points of each
    loop (start and end points)."""
    pts, a_list, b_list = [], [], []
    for loop in loops:
        pieces = []
        for c in loop.pieces():
            lp = grid.line_points(c, 1e-9 * min_h(h)) if grid is not None else None
            pieces.append(spaced(c, h) if lp is None else lp)
        lp = np.vstack(pieces)
        pts.append(lp)
        a_list.append(lp)
        b_list.append(np.roll(lp, -1, axis=0))
    if not pts:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2))
    return np.vstack(pts), np.vstack(a_list), np.vstack(b_list)


def _interior_points(
    domain: Domain, h: float, kind: str, jitter: float, rng, grid: Grid | None = None
) -> np.ndarray:
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
            cand = cand[distance_to_boundary(domain, cand, 0.3 * h) >= 0.3 * h]
            out = np.vstack([out, cand])
        return out[:n_target]
    grid = grid or Grid.fitted(lo, hi, h)
    p = grid.points()
    p = p[domain.contains(p)]
    d = distance_to_boundary(domain, p, 1.2 * grid.hx)  # (the taper's reach)
    keep = d >= 0.45 * grid.hx
    p, d = p[keep], d[keep]
    if kind == "jittered" and jitter > 0 and len(p):
        hx = grid.hx
        taper = np.clip((d - 0.4 * hx) / (0.8 * hx), 0.0, 1.0)
        trial = p + unit_disc(rng, len(p)) * (jitter * hx * taper)[:, None]
        ok = domain.contains(trial) & (distance_to_boundary(domain, trial, 0.3 * hx) >= 0.3 * hx)
        p[ok] = trial[ok]
    return p


def lloyd(domain: Domain, points: np.ndarray, h, iterations: int = CVT_ITERATIONS) -> np.ndarray:
    """Lloyd relaxation: interior points move to the centroids of their Voronoi cells.

    Boundary points (on a domain curve) stay. Cells are clipped to the triangulated
    domain; their centroids are assembled from the sub-triangles (vertex, edge
    midpoint, circumcentre) of every triangle, vectorised.

    Parameters
    ----------
    domain : Domain
    points : ndarray, shape (N, 2)
    h : float or SizeField
        Spacing (sets the tolerance for "on the boundary"); a size field weights the
        centroids by ``h^-4`` (cells of a 2-D CVT scale as the density^(-1/4)).
    iterations : int

    Returns
    -------
    ndarray, shape (N, 2)
    """
    p = np.array(points, dtype=float)
    hmin = min_h(h)
    density = (lambda x: (hmin / h(x)) ** 4) if isinstance(h, SizeField) else None
    on_bnd = distance_to_boundary(domain, p, 1e-9 * hmin) <= 1e-9 * hmin
    movable = np.flatnonzero(~on_bnd)
    for _ in range(iterations):
        tri = domain.delaunay(p)
        area, centroid = cell_centroids(p[tri], tri, len(p), density=density)
        ok = area[movable] > 1e-12 * hmin * hmin
        idx = movable[ok]
        target = centroid[idx]
        reach = 0.2 * local_h(h, target)
        far = distance_to_boundary(domain, target, reach) > reach
        inside = domain.contains(target) & far
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
    InputError
        If the target is below the spread of ``mesh`` or cannot be reached.
    """
    sigma_l = check_positive("sigma_l", sigma_l)
    s0 = mesh.edge_length_spread()
    if sigma_l < s0 * (1 - rtol):
        raise InputError(
            f"target sigma_L = {sigma_l} is below the spread of the starting mesh "
            f"({s0:.4f}); start from a more regular mesh",
            "sigma_l",
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
        raise InputError(f"could not reach sigma_L = {sigma_l} (best {reached:.4f})", "sigma_l")
    return m


def check_sampling(
    kind: str, jitter: float, seed, kinds=KINDS
) -> tuple[str, float, np.random.Generator]:
    """Checked ``kind`` (one of ``kinds``) and ``jitter`` (in [0, 0.5)) and the random
    generator for ``seed``."""
    kind = check_choice("mesh kind", kind, kinds, "kind")
    jitter = float(check_positive("jitter", jitter, allow_zero=True))
    if jitter >= 0.5:
        raise InputError(f"jitter must be in [0, 0.5), got {jitter}", "jitter")
    return kind, jitter, np.random.default_rng(check_seed(seed))
