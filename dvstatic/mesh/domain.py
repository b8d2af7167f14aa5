"""Planar domains with named boundary curves and regions, and their Delaunay
triangulation.

A :class:`Domain` is an outer loop, optional hole loops and optional *regions* (loops
inside the body that name a part of it, e.g. an inclusion or a layer with its own
material). A loop is a closed chain of named curves (:mod:`.curves`): a
:class:`Polygon` (straight edges), a :class:`Circle`, or a :class:`Path` of lines,
circular arcs and elliptic arcs. Generators in :mod:`dvstatic.mesh` place points in a
domain; :meth:`Domain.triangulate` turns them into triangles (Delaunay, flat and
outside triangles removed, conforming to the boundary and to the region curves),
labels the boundary edges with the names of the curves they lie on and the triangles
with the region they lie in.
"""

from __future__ import annotations

import logging
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from .._planar import cross
from ..errors import InputError
from .curves import Arc, Curve, EllipseArc, Line
from .polygons import are_edges, boundary_edges, in_polygon, self_intersects, signed_area

log = logging.getLogger(__name__)

__all__ = [
    "Polygon",
    "Circle",
    "Path",
    "Domain",
    "Line",
    "Arc",
    "EllipseArc",
    "rectangle_domain",
]


class _LoopBase(ABC):
    """What every loop offers (its curves give the rest)."""

    @abstractmethod
    def pieces(self) -> tuple[Curve, ...]:
        """The loop's curves, in order."""

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.pieces())

    @property
    def region_name(self) -> str:
        """The name of the loop as a region (its first curve's name)."""
        return self.names[0]

    def samples(self) -> np.ndarray:
        """A closed polyline of the loop (the last point not repeated), (n, 2)."""
        return np.vstack([c.samples() for c in self.pieces()])

    @property
    def area(self) -> float:
        return abs(signed_area(self.samples()))

    def contains(self, p: np.ndarray) -> np.ndarray:
        """Even-odd point-in-polygon test on the polyline, (n,) bool."""
        return in_polygon(self.samples(), p)

    def distances(self, p: np.ndarray) -> np.ndarray:
        """Distance of each point to each curve, shape (n, k)."""
        return np.stack([c.distance(p) for c in self.pieces()], axis=1)


@dataclass(frozen=True, eq=False)
class Polygon(_LoopBase):
    """Closed polygon loop.

    Parameters
    ----------
    vertices : ndarray, shape (k, 2)
        Corner coordinates, in order (either orientation), k >= 3.
    names : tuple of str, length k, optional
        Name of edge i, which joins vertex i to vertex (i + 1) % k; default: every
        edge ``name``, or ``"edge0"``, ``"edge1"``, ...
    name : str, optional
        One name for every edge (and the region name of the polygon).
    """

    vertices: np.ndarray
    names: tuple[str, ...] | None = None
    name: str | None = None

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise InputError(
                f"polygon vertices must have shape (k, 2) with k >= 3, got {v.shape}", "vertices"
            )
        if not np.all(np.isfinite(v)):
            raise InputError("polygon vertices must be finite", "vertices")
        names = self.names
        if names is None:
            names = [self.name] * len(v) if self.name else [f"edge{i}" for i in range(len(v))]
        if len(names) != len(v):
            raise InputError(
                f"polygon needs one name per edge: {len(v)} edges, {len(names)} names", "names"
            )
        edge = np.roll(v, -1, axis=0) - v
        if np.any(np.hypot(edge[:, 0], edge[:, 1]) == 0):
            raise InputError(
                "polygon has repeated consecutive vertices (zero-length edge)", "vertices"
            )
        if self_intersects(v):
            raise InputError(
                "polygon edges intersect each other (self-intersecting polygon)", "vertices"
            )
        if abs(signed_area(v)) <= 1e-14 * float(np.max(np.ptp(v, axis=0))) ** 2:
            raise InputError("polygon has zero area", "vertices")
        v.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "names", tuple(str(n) for n in names))

    def pieces(self) -> tuple[Curve, ...]:
        v = self.vertices
        k = len(v)
        return tuple(Line(v[i], v[(i + 1) % k], self.names[i]) for i in range(k))

    @property
    def region_name(self) -> str:
        return self.name or self.names[0]

    def samples(self) -> np.ndarray:
        return self.vertices

    @property
    def area(self) -> float:
        return abs(signed_area(self.vertices))

    def distances(self, p: np.ndarray) -> np.ndarray:
        v = self.vertices
        w = np.roll(v, -1, axis=0)
        e = w - v
        ee = np.einsum("ij,ij->i", e, e)
        d = p[:, None, :] - v[None, :, :]
        s = np.clip(np.einsum("nkj,kj->nk", d, e) / ee, 0.0, 1.0)
        q = d - s[..., None] * e[None]
        return np.hypot(q[..., 0], q[..., 1])

    def curves(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """Edges as (name, start, end)."""
        v = self.vertices
        return [(n, v[i], v[(i + 1) % len(v)]) for i, n in enumerate(self.names)]


@dataclass(frozen=True, eq=False)
class Circle(_LoopBase):
    """Circular loop of centre ``center`` and radius ``radius``, one boundary ``name``."""

    center: tuple[float, float]
    radius: float
    name: str = "circle"

    def __post_init__(self) -> None:
        c = np.asarray(self.center, dtype=float)
        if c.shape != (2,) or not np.all(np.isfinite(c)):
            raise InputError(
                f"circle center must be two finite numbers, got {self.center!r}", "center"
            )
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise InputError(f"circle radius must be finite and > 0, got {self.radius!r}", "radius")
        object.__setattr__(self, "center", (float(c[0]), float(c[1])))
        object.__setattr__(self, "radius", float(self.radius))
        object.__setattr__(self, "name", str(self.name))

    def pieces(self) -> tuple[Curve, ...]:
        return (Arc(self.center, self.radius, 0.0, 360.0, self.name),)

    @property
    def area(self) -> float:
        return float(np.pi * self.radius**2)

    def contains(self, p: np.ndarray) -> np.ndarray:
        c = np.asarray(self.center)
        return np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) < self.radius

    def distances(self, p: np.ndarray) -> np.ndarray:
        c = np.asarray(self.center)
        return np.abs(np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) - self.radius)[:, None]


@dataclass(frozen=True, eq=False)
class Path(_LoopBase):
    """A closed loop of curves (:class:`Line`, :class:`Arc`, :class:`EllipseArc`), each
    starting where the previous one ends; the curves keep their names.

    Parameters
    ----------
    curves : sequence of Curve
    name : str, optional
        The loop's name as a region (default: its first curve's name).
    """

    curves: tuple[Curve, ...]
    name: str | None = None

    def __post_init__(self) -> None:
        curves = tuple(self.curves)
        if not curves or not all(isinstance(c, Curve) for c in curves):
            raise InputError("a path needs a sequence of Line, Arc or EllipseArc curves", "curves")
        scale = max(c.length for c in curves)
        for i, c in enumerate(curves):
            nxt = curves[(i + 1) % len(curves)]
            if np.hypot(*(c.end - nxt.start)) > 1e-9 * scale:
                raise InputError(
                    f"path curve {i} ({c.name!r}) ends at {c.end.tolist()} but curve "
                    f"{(i + 1) % len(curves)} starts at {nxt.start.tolist()}: the path must be "
                    "closed and connected",
                    "curves",
                )
        if self_intersects(self._polyline(curves)):
            raise InputError("path curves intersect each other", "curves")
        object.__setattr__(self, "curves", curves)

    @staticmethod
    def _polyline(curves) -> np.ndarray:
        return np.vstack([c.samples(64) if not c.straight else c.start[None] for c in curves])

    def pieces(self) -> tuple[Curve, ...]:
        return self.curves

    @property
    def region_name(self) -> str:
        return self.name or self.names[0]


Loop = Polygon | Circle | Path


@dataclass(frozen=True, eq=False)
class Domain:
    """Region bounded by ``outer`` minus the ``holes``, with optional named ``regions``.

    Parameters
    ----------
    outer : Polygon, Circle or Path
        Outer boundary loop.
    holes : tuple of loops
        Hole loops; each must lie strictly inside ``outer`` and not overlap another.
    regions : tuple of loops
        Loops inside the body whose area is a named region (the loop's
        ``region_name``); the triangulation conforms to them. Regions may not overlap
        each other, cross a hole or touch the boundary.
    """

    outer: Loop
    holes: tuple[Loop, ...] = ()
    regions: tuple[Loop, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "holes", tuple(self.holes))
        object.__setattr__(self, "regions", tuple(self.regions))
        for i, hole in enumerate(self.holes):
            probe = hole.samples()
            if not np.all(self.outer.contains(probe)) or np.any(
                self.outer.distances(probe).min(axis=1) < 1e-12 * self.scale
            ):
                raise InputError(f"hole {i} is not strictly inside the outer boundary", "holes")
            for j, other in enumerate(self.holes[:i]):
                if np.any(other.contains(probe)) or np.any(hole.contains(other.samples())):
                    raise InputError(f"holes {j} and {i} overlap", "holes")
        if self.area <= 0:
            raise InputError("domain has no area left after removing the holes", "holes")
        self._check_regions()

    def _check_regions(self) -> None:
        names = [r.region_name for r in self.regions]
        if len(set(names)) != len(names):
            raise InputError(f"region names must be different, got {names}", "regions")
        tol = 1e-9 * self.scale
        for i, region in enumerate(self.regions):
            probe = region.samples()
            name = region.region_name
            d, _ = self.curve_distances(probe)
            if not np.all(self.contains(probe) | (d.min(axis=1) <= tol)):
                raise InputError(
                    f"region {name!r} leaves the body (its boundary must lie inside the "
                    "domain or on its boundary, outside the holes)",
                    "regions",
                )
            for hole in self.holes:
                inside = region.contains(hole.samples())
                if inside.any() and not inside.all():
                    raise InputError(f"region {name!r} crosses a hole", "regions")
            mine = _interior_samples(region)
            for other in self.regions[:i]:
                theirs = _interior_samples(other)
                if np.any(other.contains(mine)) or np.any(region.contains(theirs)):
                    raise InputError(
                        f"regions {other.region_name!r} and {name!r} overlap", "regions"
                    )

    @property
    def loops(self) -> tuple[Loop, ...]:
        """The boundary loops: outer first, then the holes."""
        return (self.outer, *self.holes)

    def boundary_curves(self) -> list[Curve]:
        """Every boundary curve, in :meth:`curve_names` order."""
        return [c for loop in self.loops for c in loop.pieces()]

    def region_curves(self) -> list[Curve]:
        """Every curve of every region loop."""
        return [c for loop in self.regions for c in loop.pieces()]

    @property
    def names(self) -> tuple[str, ...]:
        """All boundary names, outer loop first, without repeats."""
        out: list[str] = []
        for n in self.curve_names():
            if n not in out:
                out.append(n)
        return tuple(out)

    @property
    def area(self) -> float:
        return self.outer.area - sum(h.area for h in self.holes)

    @property
    def bbox(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower-left and upper-right corners of the outer loop."""
        s = _loop_samples(self.outer)
        return s.min(axis=0), s.max(axis=0)

    @property
    def scale(self) -> float:
        lo, hi = self.bbox
        return float(np.max(hi - lo))

    def contains(self, p: np.ndarray) -> np.ndarray:
        """Strictly inside the domain (n,) bool; points on the boundary are ambiguous."""
        inside = self.outer.contains(p)
        for h in self.holes:
            inside &= ~h.contains(p)
        return inside

    def curve_distances(self, p: np.ndarray) -> tuple[np.ndarray, list[str]]:
        """Distance of points to every boundary curve.

        Returns
        -------
        dist : ndarray, shape (n, c)
        names : list of str, length c
        """
        return np.hstack([loop.distances(p) for loop in self.loops]), self.curve_names()

    def region_distances(self, p: np.ndarray) -> np.ndarray:
        """Distance of points to every region curve, shape (n, r) (r may be 0)."""
        if not self.regions:
            return np.zeros((len(p), 0))
        return np.hstack([loop.distances(p) for loop in self.regions])

    def boundary_corners(self) -> np.ndarray:
        """Points where two boundary curves meet, shape (k, 2)."""
        pts = [c.start for loop in self.loops for c in loop.pieces() if not c.closed]
        return np.array(pts) if pts else np.zeros((0, 2))

    def corners(self) -> np.ndarray:
        """Points where two curves meet (polygon vertices, path joints), shape (k, 2)."""
        curves = [c for loop in (*self.loops, *self.regions) for c in loop.pieces()]
        pts = [c.start for c in curves if not c.closed]
        return np.array(pts) if pts else np.zeros((0, 2))

    def triangulate(
        self,
        points: np.ndarray,
        tol: float,
        conform: bool = True,
        max_passes: int = 12,
        segments: np.ndarray | None = None,
    ):
        """Delaunay triangulation of ``points`` restricted to the domain.

        Boundary edges that are *encroached* (the opposite angle is obtuse, so the
        circumcentre of the boundary triangle lies outside the body) are split at
        their midpoint (on the curve) and the points re-triangulated, until no boundary
        edge is encroached (conforming Delaunay boundary). Such triangles make the DV
        coupling of the boundary particle indefinite. Region ``segments`` that are not
        edges of the triangulation are split likewise, so that the triangles conform to
        the regions.

        Parameters
        ----------
        points : ndarray, shape (N, 2)
            Boundary and region points must lie on their curves (within ``tol``).
        tol : float
            Length tolerance for "on a curve" (e.g. 1e-9 times the spacing).
        conform : bool
            Split encroached boundary edges.
        max_passes : int
            Limit on split-and-retriangulate passes.
        segments : ndarray of int, shape (s, 3), optional
            Region segments: two point indices and the index of their region curve
            (in :meth:`region_curves` order).

        Returns
        -------
        points : ndarray, shape (N', 2)
            The input points followed by the inserted midpoints.
        triangles : ndarray, shape (M, 3), int64, counter-clockwise
        parts : dict name -> ndarray (m, 2) of boundary edges (counter-clockwise)
        regions : dict name -> ndarray of triangle indices

        Raises
        ------
        InputError
            If a point is not used by any kept triangle, or a boundary edge of the
            triangulation does not lie on a curve of the domain (the mesh does not
            conform to the boundary; use a smaller spacing near that place).
        """
        points = np.asarray(points, dtype=float)
        segs = np.zeros((0, 3), np.int64) if segments is None else np.asarray(segments)
        n_in = len(points)
        for _ in range(max_passes + 1):
            tri = self.delaunay(points)
            edges, third = boundary_edges(tri, with_third=True)
            curve = self.curve_of_edges(points, edges, tol)
            po, pa, pc = points[edges[:, 0]], points[edges[:, 1]], points[third]
            dot = np.einsum("ij,ij->i", po - pc, pa - pc)
            ll = np.einsum("ij,ij->i", pa - po, pa - po)
            enc = dot < -1e-9 * ll if conform else np.zeros(len(edges), dtype=bool)
            missing = ~are_edges(tri, segs[:, :2], len(points))
            if not enc.any() and not missing.any():
                break
            points, segs = self._split(points, edges[enc], curve[enc], segs, missing)
        else:
            log.warning("boundary still encroached after %d passes", max_passes)
        if len(points) > n_in:
            log.debug("inserted %d midpoints (encroached or missing edges)", len(points) - n_in)
        _check_used(points, tri)
        parts: dict[str, list[np.ndarray]] = {}
        for c, name in enumerate(self.curve_names()):
            parts.setdefault(name, []).append(edges[curve == c])
        parts_arr = {n: np.concatenate(v) for n, v in parts.items()}
        return points, tri, parts_arr, self.tag_regions(points, tri)

    def _split(self, points, edges, curve, segs, missing):
        """Insert the midpoints of encroached boundary edges and of missing region
        segments (each on its curve); the split segments replace the old ones."""
        new = [points, self._midpoints(points, edges, curve)]
        if missing.any():
            gone = segs[missing]
            mid = 0.5 * (points[gone[:, 0]] + points[gone[:, 1]])
            rc = self.region_curves()
            for k in np.unique(gone[:, 2]):
                sel = gone[:, 2] == k
                mid[sel] = rc[k].project(mid[sel])
            first = sum(len(a) for a in new)
            ids = first + np.arange(len(gone))
            new.append(mid)
            halves = np.concatenate(
                [np.c_[gone[:, 0], ids, gone[:, 2]], np.c_[ids, gone[:, 1], gone[:, 2]]]
            )
            segs = np.concatenate([segs[~missing], halves])
        return np.vstack(new), segs

    def tag_regions(self, points: np.ndarray, tri: np.ndarray) -> dict[str, np.ndarray]:
        """Triangles of every region (by their centroid), name -> indices."""
        if not self.regions:
            return {}
        centroid = points[tri].mean(axis=1)
        return {
            r.region_name: np.flatnonzero(r.contains(centroid)).astype(np.int64)
            for r in self.regions
        }

    def delaunay(self, points: np.ndarray) -> np.ndarray:
        """Counter-clockwise Delaunay triangles of ``points`` inside the domain (flat
        ones removed), ordered by their first particle, shape (M, 3)."""
        from scipy.spatial import Delaunay

        tri = Delaunay(points).simplices.astype(np.int64)
        x = points[tri]
        a2 = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        tri[a2 < 0] = tri[a2 < 0][:, [0, 2, 1]]
        a2 = np.abs(a2)
        e = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 1], x[:, 0] - x[:, 2]], axis=1)
        lmax2 = np.max(np.einsum("mki,mki->mk", e, e), axis=1)
        flat = a2 <= 1e-10 * lmax2
        keep = ~flat & self.contains(x.mean(axis=1))
        tri = tri[keep]
        # triangles in order of their first particle (spatial locality for assembly)
        return tri[np.argsort(tri.min(axis=1), kind="stable")]

    def curve_names(self) -> list[str]:
        """Name of every boundary curve, in curve order."""
        return [c.name for c in self.boundary_curves()]

    def curve_of_edges(self, points: np.ndarray, edges: np.ndarray, tol: float) -> np.ndarray:
        """Index of the curve (in :meth:`curve_names` order) every boundary edge lies on
        (both ends and the middle), shape (m,).

        Raises
        ------
        InputError
            An edge does not lie on any curve of the domain.
        """
        if edges.size == 0:
            return np.zeros(0, np.int64)
        ne = len(edges)
        ends = np.vstack([points[edges[:, 0]], points[edges[:, 1]]])
        dist, _ = self.curve_distances(ends)
        both = (dist[:ne] <= tol) & (dist[ne:] <= tol)
        mid = 0.5 * (points[edges[:, 0]] + points[edges[:, 1]])
        dmid, _ = self.curve_distances(mid)
        seg_len = np.hypot(*(points[edges[:, 1]] - points[edges[:, 0]]).T)
        straight = np.array([c.straight for c in self.boundary_curves()])
        both &= np.where(straight[None, :], dmid <= tol, dmid <= 0.5 * seg_len[:, None])
        n_on = both.sum(axis=1)
        if np.any(n_on == 0):
            i = int(np.flatnonzero(n_on == 0)[0])
            p0, p1 = points[edges[i]]
            raise InputError(
                f"{int(np.sum(n_on == 0))} boundary edge(s) of the triangulation do not lie on "
                f"the domain boundary (first from {p0.tolist()} to {p1.tolist()}): the mesh does "
                "not conform to the domain; use a smaller h or a less concave domain",
                "h",
            )
        return np.argmax(both, axis=1)

    def _midpoints(self, points: np.ndarray, edges: np.ndarray, curve: np.ndarray) -> np.ndarray:
        mid = 0.5 * (points[edges[:, 0]] + points[edges[:, 1]])
        return self.project(mid, curve)

    def project(self, points: np.ndarray, curve: np.ndarray) -> np.ndarray:
        """Points moved onto boundary curve ``curve[i]`` (index in :meth:`curve_names`
        order): orthogonally onto straight edges, to the nearest point of curved ones;
        shape (m, 2)."""
        out = np.array(points, dtype=float).reshape(-1, 2)
        for k, c in enumerate(self.boundary_curves()):
            sel = curve == k
            if sel.any():
                if c.straight:
                    d = (c.b - c.a) / np.hypot(*(c.b - c.a))
                    out[sel] = c.a + np.outer((out[sel] - c.a) @ d, d)
                else:
                    out[sel] = c.project(out[sel])
        return out


def rectangle_domain(width: float, height: float) -> Domain:
    """Axis-aligned rectangle [0, width] x [0, height], edges bottom/right/top/left."""
    v = np.array([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]])
    return Domain(Polygon(v, ("bottom", "right", "top", "left")))


def _interior_samples(loop, n: int = 48) -> np.ndarray:
    """Grid points strictly inside a loop (away from its curves)."""
    v = loop.samples()
    lo, hi = v.min(axis=0), v.max(axis=0)
    g = np.stack(np.meshgrid(*(np.linspace(lo[k], hi[k], n + 2)[1:-1] for k in range(2))), -1)
    g = g.reshape(-1, 2)
    g = g[loop.contains(g)]
    away = loop.distances(g).min(axis=1) > 1e-6 * float(np.max(hi - lo))
    return g[away]


def _check_used(points: np.ndarray, tri: np.ndarray) -> None:
    used = np.zeros(len(points), dtype=bool)
    used[tri.ravel()] = True
    if not used.all():
        bad = np.flatnonzero(~used)
        raise InputError(
            f"{bad.size} point(s) are not part of any triangle inside the domain "
            f"(first: {bad[0]} at {points[bad[0]].tolist()}); points must lie inside "
            "the domain or on its boundary",
            "points",
        )


def _loop_samples(loop: Loop, n: int = 64) -> np.ndarray:
    if isinstance(loop, Circle):
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        c = np.asarray(loop.center)
        return c + loop.radius * np.c_[np.cos(t), np.sin(t)]
    if isinstance(loop, Polygon):
        v = loop.vertices
        w = np.roll(v, -1, axis=0)
        s = np.linspace(0, 1, 8, endpoint=False)
        return (v[:, None, :] + s[None, :, None] * (w - v)[:, None, :]).reshape(-1, 2)
    return loop.samples()
