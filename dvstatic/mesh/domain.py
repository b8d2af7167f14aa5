"""Planar domains with named boundary curves, and their Delaunay triangulation.

A :class:`Domain` is an outer loop and optional hole loops. Each loop is either a
closed polygon whose edges carry names, or a circle with one name. Generators in
:mod:`dvstatic.mesh` place points in a domain; :meth:`Domain.triangulate` turns the
points into triangles (Delaunay, flat and outside triangles removed) and labels the
boundary edges of the triangulation with the names of the curves they lie on.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .._planar import cross
from ..errors import InputError

log = logging.getLogger(__name__)

__all__ = ["Polygon", "Circle", "Domain", "rectangle_domain"]


@dataclass(frozen=True, eq=False)
class Polygon:
    """Closed polygon loop.

    Parameters
    ----------
    vertices : ndarray, shape (k, 2)
        Corner coordinates, in order (either orientation), k >= 3.
    names : tuple of str, length k
        Name of edge i, which joins vertex i to vertex (i + 1) % k.
    """

    vertices: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise InputError(
                f"polygon vertices must have shape (k, 2) with k >= 3, got {v.shape}", "vertices"
            )
        if not np.all(np.isfinite(v)):
            raise InputError("polygon vertices must be finite", "vertices")
        if len(self.names) != len(v):
            raise InputError(
                f"polygon needs one name per edge: {len(v)} edges, {len(self.names)} names",
                "names",
            )
        edge = np.roll(v, -1, axis=0) - v
        if np.any(np.hypot(edge[:, 0], edge[:, 1]) == 0):
            raise InputError(
                "polygon has repeated consecutive vertices (zero-length edge)", "vertices"
            )
        if _self_intersects(v):
            raise InputError(
                "polygon edges intersect each other (self-intersecting polygon)", "vertices"
            )
        if abs(_signed_area(v)) <= 1e-14 * float(np.max(np.ptp(v, axis=0))) ** 2:
            raise InputError("polygon has zero area", "vertices")
        v.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))

    @property
    def area(self) -> float:
        """Enclosed area (positive)."""
        return abs(_signed_area(self.vertices))

    @property
    def perimeter(self) -> float:
        """Total edge length."""
        e = np.roll(self.vertices, -1, axis=0) - self.vertices
        return float(np.hypot(e[:, 0], e[:, 1]).sum())

    def contains(self, p: np.ndarray) -> np.ndarray:
        """Even-odd point-in-polygon test, (n,) bool (points on edges are ambiguous)."""
        v = self.vertices
        w = np.roll(v, -1, axis=0)
        x, y = p[:, 0:1], p[:, 1:2]
        cond = (v[None, :, 1] > y) != (w[None, :, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = v[None, :, 0] + (y - v[None, :, 1]) * (w[None, :, 0] - v[None, :, 0]) / (
                w[None, :, 1] - v[None, :, 1]
            )
        return (np.count_nonzero(cond & (x < xc), axis=1) % 2) == 1

    def distances(self, p: np.ndarray) -> np.ndarray:
        """Distance of each point to each edge, shape (n, k)."""
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
class Circle:
    """Circular loop of centre ``center`` and radius ``radius``, one boundary ``name``."""

    center: tuple[float, float]
    radius: float
    name: str

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

    @property
    def names(self) -> tuple[str, ...]:
        return (self.name,)

    @property
    def area(self) -> float:
        return float(np.pi * self.radius**2)

    @property
    def perimeter(self) -> float:
        return float(2 * np.pi * self.radius)

    def contains(self, p: np.ndarray) -> np.ndarray:
        c = np.asarray(self.center)
        return np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) < self.radius

    def distances(self, p: np.ndarray) -> np.ndarray:
        c = np.asarray(self.center)
        return np.abs(np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) - self.radius)[:, None]


Loop = Polygon | Circle


@dataclass(frozen=True, eq=False)
class Domain:
    """Region bounded by ``outer`` minus the ``holes``.

    Parameters
    ----------
    outer : Polygon or Circle
        Outer boundary loop.
    holes : tuple of Polygon or Circle
        Hole loops; each must lie strictly inside ``outer`` and not overlap another.
    """

    outer: Loop
    holes: tuple[Loop, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "holes", tuple(self.holes))
        for i, hole in enumerate(self.holes):
            probe = _loop_samples(hole)
            if not np.all(self.outer.contains(probe)) or np.any(
                self.outer.distances(probe).min(axis=1) < 1e-12 * self.scale
            ):
                raise InputError(f"hole {i} is not strictly inside the outer boundary", "holes")
            for j, other in enumerate(self.holes[:i]):
                if np.any(other.contains(probe)) or np.any(hole.contains(_loop_samples(other))):
                    raise InputError(f"holes {j} and {i} overlap", "holes")
        if self.area <= 0:
            raise InputError("domain has no area left after removing the holes", "holes")

    @property
    def loops(self) -> tuple[Loop, ...]:
        return (self.outer, *self.holes)

    @property
    def names(self) -> tuple[str, ...]:
        """All boundary names, outer loop first, without repeats."""
        out: list[str] = []
        for loop in self.loops:
            for n in loop.names:
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
        """Distance of points to every named curve (polygon edge or circle).

        Returns
        -------
        dist : ndarray, shape (n, c)
        names : list of str, length c
        """
        cols, names = [], []
        for loop in self.loops:
            cols.append(loop.distances(p))
            names.extend(loop.names)
        return np.hstack(cols), names

    def corners(self) -> np.ndarray:
        """Polygon vertices of all loops, shape (k, 2)."""
        vs = [lp.vertices for lp in self.loops if isinstance(lp, Polygon)]
        return np.vstack(vs) if vs else np.zeros((0, 2))

    def triangulate(
        self, points: np.ndarray, tol: float, conform: bool = True, max_passes: int = 12
    ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """Delaunay triangulation of ``points`` restricted to the domain.

        Boundary edges that are *encroached* (the opposite angle is obtuse, so the
        circumcentre of the boundary triangle lies outside the body) are split at
        their midpoint and the points re-triangulated, until no boundary edge is
        encroached (conforming Delaunay boundary). Such triangles make the DV
        coupling of the boundary particle indefinite.

        Parameters
        ----------
        points : ndarray, shape (N, 2)
            Boundary points must lie on the curves (within ``tol``).
        tol : float
            Length tolerance for "on a curve" (e.g. 1e-9 times the spacing).
        conform : bool
            Split encroached boundary edges.
        max_passes : int
            Limit on split-and-retriangulate passes.

        Returns
        -------
        points : ndarray, shape (N', 2)
            The input points followed by the inserted boundary midpoints.
        triangles : ndarray, shape (M, 3), int64, counter-clockwise
        parts : dict name -> ndarray (m, 2) of boundary edges (counter-clockwise)

        Raises
        ------
        ValueError
            If a point is not used by any kept triangle, or a boundary edge of the
            triangulation does not lie on a curve of the domain (the mesh does not
            conform to the boundary; use a smaller spacing near that place).
        """
        points = np.asarray(points, dtype=float)
        n_in = len(points)
        for _ in range(max_passes + 1):
            tri = self.delaunay(points)
            edges, third = _boundary_edges(tri, with_third=True)
            curve = self._curve_of_edges(points, edges, tol)
            po, pa, pc = points[edges[:, 0]], points[edges[:, 1]], points[third]
            dot = np.einsum("ij,ij->i", po - pc, pa - pc)
            ll = np.einsum("ij,ij->i", pa - po, pa - po)
            enc = dot < -1e-9 * ll
            if not conform or not enc.any():
                break
            points = np.vstack([points, self._midpoints(points, edges[enc], curve[enc])])
        else:
            log.warning("boundary still encroached after %d passes", max_passes)
        if len(points) > n_in:
            log.debug("inserted %d boundary midpoints (encroached edges)", len(points) - n_in)
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
        parts: dict[str, list[np.ndarray]] = {}
        for c, name in enumerate(self.curve_names()):
            parts.setdefault(name, []).append(edges[curve == c])
        return points, tri, {n: np.concatenate(v) for n, v in parts.items()}

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
        """Name of every curve (polygon edge or circle), in curve order."""
        out: list[str] = []
        for loop in self.loops:
            out.extend(loop.names)
        return out

    def _curve_of_edges(self, points: np.ndarray, edges: np.ndarray, tol: float) -> np.ndarray:
        """Index of the curve every boundary edge lies on (both ends and the middle)."""
        if edges.size == 0:
            return np.zeros(0, np.int64)
        ne = len(edges)
        ends = np.vstack([points[edges[:, 0]], points[edges[:, 1]]])
        dist, _ = self.curve_distances(ends)
        both = (dist[:ne] <= tol) & (dist[ne:] <= tol)
        mid = 0.5 * (points[edges[:, 0]] + points[edges[:, 1]])
        dmid, _ = self.curve_distances(mid)
        seg_len = np.hypot(*(points[edges[:, 1]] - points[edges[:, 0]]).T)
        straight = np.concatenate(
            [np.full(len(loop.names), isinstance(loop, Polygon)) for loop in self.loops]
        )
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
        k = 0
        for loop in self.loops:
            if isinstance(loop, Circle):
                sel = curve == k
                c = np.asarray(loop.center)
                v = mid[sel] - c
                mid[sel] = c + loop.radius * v / np.hypot(v[:, 0], v[:, 1])[:, None]
            k += len(loop.names)
        return mid


def rectangle_domain(width: float, height: float) -> Domain:
    """Axis-aligned rectangle [0, width] x [0, height], edges bottom/right/top/left."""
    v = np.array([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]])
    return Domain(Polygon(v, ("bottom", "right", "top", "left")))


def _signed_area(v: np.ndarray) -> float:
    w = np.roll(v, -1, axis=0)
    return 0.5 * float(np.sum(v[:, 0] * w[:, 1] - w[:, 0] * v[:, 1]))


def _loop_samples(loop: Loop, n: int = 64) -> np.ndarray:
    if isinstance(loop, Circle):
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        c = np.asarray(loop.center)
        return c + loop.radius * np.c_[np.cos(t), np.sin(t)]
    v = loop.vertices
    w = np.roll(v, -1, axis=0)
    s = np.linspace(0, 1, 8, endpoint=False)
    return (v[:, None, :] + s[None, :, None] * (w - v)[:, None, :]).reshape(-1, 2)


def _self_intersects(v: np.ndarray) -> bool:
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


def _boundary_edges(tri: np.ndarray, with_third: bool = False):
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
