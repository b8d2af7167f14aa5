"""The :class:`Mesh` container: validated triangles, bonds, named boundary parts.

A mesh is a set of particles (``points``) and counter-clockwise ``triangles``; its
edges are the bonds of the lattice. Bounded meshes carry named boundary ``parts``
(boundary edges); periodic meshes (for homogenisation) carry a ``period`` and, for
every triangle vertex, the periodic ``image`` it refers to.
"""

from __future__ import annotations

import logging
import types
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._checks import check_positive, check_seed
from .._planar import cross
from ..errors import InputError
from .domain import Domain
from .recipe import Sampling
from .sampling import move_in_domain, periodic_delaunay, unit_disc
from .topology import Topology, build_topology

log = logging.getLogger(__name__)

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """Validated triangle mesh.

    Parameters
    ----------
    points : array_like, shape (N, 2)
        Particle coordinates (length units).
    triangles : array_like of int, shape (M, 3)
        Vertex indices; re-ordered counter-clockwise on construction.
    parts : mapping str -> array_like of int, shape (m, 2), optional
        Named boundary parts as lists of boundary edges.
    period : array_like, shape (2,), optional
        Period lengths of a periodic mesh (points must lie in ``[0, period)``).
    images : array_like of int, shape (M, 3, 2), optional
        For periodic meshes, the periodic image of each triangle vertex: vertex
        ``v`` of triangle ``t`` sits at ``points[triangles[t, v]] + images[t, v] * period``.
    domain : Domain, optional
        The domain the points were generated in (used to re-triangulate after
        :meth:`perturbed`, and by the FE reference to keep curved boundaries curved).
    regions : mapping str -> array_like of int, optional
        Named regions: the triangles of each (disjoint sets; the other triangles
        belong to no region). Each region can carry its own material.
    sampling : Sampling, optional
        How the points were placed (set by the generators and kept by
        :meth:`perturbed`): the relaxed calibration makes its periodic sample by the
        same recipe. None for meshes built from points and triangles.

    Raises
    ------
    InputError (a ValueError)
        Non-finite coordinates, duplicate points, indices out of range, zero-area
        triangles, unused points, edges shared by more than two triangles or
        overlapping triangles, unknown or non-boundary part edges.
    TypeError
        Triangles given with a non-integer dtype.
    """

    points: np.ndarray
    triangles: np.ndarray
    parts: Mapping[str, np.ndarray] = field(default_factory=dict)
    period: np.ndarray | None = None
    images: np.ndarray | None = None
    domain: Domain | None = None
    regions: Mapping[str, np.ndarray] = field(default_factory=dict)
    sampling: Sampling | None = None

    def __post_init__(self) -> None:
        if self.sampling is not None and not isinstance(self.sampling, Sampling):
            raise TypeError(
                f"sampling must be a Sampling or None, got {type(self.sampling).__name__}"
            )
        p = _as_points(self.points)
        _check_duplicates(p)
        t = _as_triangles(self.triangles, len(p))
        period, images = None, None
        if (self.period is None) != (self.images is None):
            raise InputError("a periodic mesh needs both `period` and `images`", "period")
        if self.period is not None:
            period = np.asarray(self.period, dtype=float).reshape(-1)
            if period.shape != (2,) or not np.all(np.isfinite(period)) or np.any(period <= 0):
                raise InputError(
                    f"period must be two positive finite lengths, got {self.period!r}", "period"
                )
            images = np.asarray(self.images)
            if images.shape != t.shape + (2,):
                raise InputError(
                    f"images must have shape {t.shape + (2,)}, got {images.shape}", "images"
                )
            if not np.issubdtype(images.dtype, np.integer):
                raise TypeError(f"images must be integers, got dtype {images.dtype}")
            images = images.astype(np.int64)
            if np.any(np.abs(images) > 1):
                raise InputError("periodic images must be -1, 0 or 1", "images")
            if np.any(p < 0) or np.any(p >= period):
                raise InputError("points of a periodic mesh must lie in [0, period)", "points")
        x = p[t]
        if images is not None:
            x = x + images * period
        a2 = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        flip = a2 < 0
        if flip.any():
            t[flip] = t[flip][:, [0, 2, 1]]
            if images is not None:
                images[flip] = images[flip][:, [0, 2, 1]]
            x[flip] = x[flip][:, [0, 2, 1]]
            a2 = np.abs(a2)
        e = np.stack([x[:, 2] - x[:, 1], x[:, 0] - x[:, 2], x[:, 1] - x[:, 0]], axis=1)
        lmax2 = np.max(np.einsum("mki,mki->mk", e, e), axis=1)
        degenerate = a2 <= 64 * np.finfo(float).eps * lmax2
        if degenerate.any():
            i = int(np.flatnonzero(degenerate)[0])
            raise InputError(
                f"{int(degenerate.sum())} triangle(s) have zero area (first: triangle {i} with "
                f"vertices {t[i].tolist()}); every triangle needs three non-collinear points",
                "triangles",
            )
        if images is None and np.any(
            (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])
        ):
            raise InputError("a triangle repeats a vertex index", "triangles")
        used = np.bincount(t.ravel(), minlength=len(p))
        if np.any(used == 0):
            bad = np.flatnonzero(used == 0)
            raise InputError(
                f"{bad.size} point(s) are not used by any triangle (first: point {bad[0]}); "
                "remove them or add triangles",
                "points",
            )
        for arr in (p, t) + ((period, images) if images is not None else ()):
            arr.setflags(write=False)
        areas = 0.5 * a2
        areas.setflags(write=False)
        object.__setattr__(self, "triangle_areas", areas)  # the cached_property, computed here
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "triangles", t)
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "images", images)
        topo = self.topology  # validates edges (manifold, orientation)
        object.__setattr__(self, "parts", types.MappingProxyType(self._checked_parts(topo)))
        object.__setattr__(self, "regions", types.MappingProxyType(self._checked_regions()))

    # ------------------------------------------------------------------ basics
    @property
    def n_points(self) -> int:
        """Number of particles N."""
        return len(self.points)

    @property
    def n_triangles(self) -> int:
        """Number of triangles M."""
        return len(self.triangles)

    @property
    def n_bonds(self) -> int:
        """Number of bonds (mesh edges)."""
        return len(self.topology.bonds)

    @property
    def is_periodic(self) -> bool:
        """True for periodic meshes."""
        return self.period is not None

    @cached_property
    def topology(self) -> Topology:
        """Bonds and their triangles (:class:`Topology`), computed once."""
        return build_topology(self.triangles, self.n_points, self.images)

    def triangle_coordinates(self) -> np.ndarray:
        """Vertex coordinates of every triangle, unwrapped for periodic meshes, (M, 3, 2)."""
        x = self.points[self.triangles]
        if self.images is not None:
            x = x + self.images * self.period
        return x

    @cached_property
    def triangle_areas(self) -> np.ndarray:
        """Triangle areas, shape (M,)."""
        x = self.triangle_coordinates()
        a = 0.5 * cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        a.setflags(write=False)
        return a

    @property
    def area(self) -> float:
        """Total area of the mesh."""
        return float(self.triangle_areas.sum())

    @property
    def boundary_edges(self) -> np.ndarray:
        """Boundary edges, counter-clockwise, shape (m, 2) (empty for periodic meshes)."""
        return self.topology.boundary_edges

    @property
    def boundary_nodes(self) -> np.ndarray:
        """Sorted indices of boundary nodes."""
        return np.unique(self.boundary_edges)

    def bond_vectors(self) -> np.ndarray:
        """Reference bond vectors A - O, shape (n_bonds, 2)."""
        b = self.topology.bonds
        d = self.points[b[:, 1]] - self.points[b[:, 0]]
        if self.period is not None:
            d = d + self.topology.bond_image * self.period
        return d

    def bond_lengths(self) -> np.ndarray:
        """Reference bond lengths, shape (n_bonds,)."""
        d = self.bond_vectors()
        return np.hypot(d[:, 0], d[:, 1])

    def edge_length_spread(self) -> float:
        """sigma_L = std(l) / mean(l) over all bonds (the paper's mesh irregularity)."""
        lengths = self.bond_lengths()
        return float(np.std(lengths) / np.mean(lengths))

    @property
    def h(self) -> float:
        """Mean bond length."""
        return float(np.mean(self.bond_lengths()))

    # ------------------------------------------------------------------ parts
    def part_edges(self, name: str) -> np.ndarray:
        """Boundary edges of the named part, shape (m, 2).

        Raises
        ------
        InputError
            If the mesh has no part of that name (the message lists the names).
        """
        if not isinstance(name, str):
            raise TypeError(f"part name must be a string, got {type(name).__name__}")
        if name not in self.parts:
            known = ", ".join(repr(k) for k in self.parts) or "none (this mesh has no named parts)"
            raise InputError(f"unknown boundary part {name!r}; known parts: {known}", "where")
        return self.parts[name]

    def part_nodes(self, name: str) -> np.ndarray:
        """Sorted node indices of the named boundary part."""
        return np.unique(self.part_edges(name))

    def _checked_parts(self, topo: Topology) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        if not self.parts:
            return out
        if self.is_periodic:
            raise InputError("periodic meshes have no boundary, so they cannot have parts", "parts")
        be = topo.boundary_edges
        n = self.n_points
        fwd = be[:, 0] * n + be[:, 1]
        order = np.argsort(fwd)
        fwd_sorted = fwd[order]
        for name, edges in self.parts.items():
            e = np.asarray(edges)
            if e.size == 0:
                e = np.zeros((0, 2), np.int64)
            if e.ndim != 2 or e.shape[1] != 2 or not np.issubdtype(e.dtype, np.integer):
                raise InputError(f"part {name!r} must be an (m, 2) integer array of edges", "parts")
            e = e.astype(np.int64)
            if np.any(e < 0) or np.any(e >= n):
                raise InputError(f"part {name!r} has node indices outside [0, {n})", "parts")
            k1 = e[:, 0] * n + e[:, 1]
            k2 = e[:, 1] * n + e[:, 0]
            i1 = np.minimum(np.searchsorted(fwd_sorted, k1), len(fwd_sorted) - 1)
            i2 = np.minimum(np.searchsorted(fwd_sorted, k2), len(fwd_sorted) - 1)
            ok1 = fwd_sorted[i1] == k1 if len(fwd_sorted) else np.zeros(len(e), bool)
            ok2 = fwd_sorted[i2] == k2 if len(fwd_sorted) else np.zeros(len(e), bool)
            if not np.all(ok1 | ok2):
                bad = e[~(ok1 | ok2)][0]
                raise InputError(
                    f"part {name!r} contains {bad.tolist()}, which is not a boundary edge", "parts"
                )
            ccw = np.where(ok1[:, None], e, e[:, ::-1])
            ccw.setflags(write=False)
            out[str(name)] = ccw
        return out

    def _checked_regions(self) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        taken = np.zeros(self.n_triangles, dtype=bool)
        for name, tris in self.regions.items():
            t = np.asarray(tris)
            if t.size == 0:
                t = np.zeros(0, np.int64)
            if t.ndim != 1 or not np.issubdtype(t.dtype, np.integer):
                raise InputError(
                    f"region {name!r} must be a 1-D integer array of triangles", "regions"
                )
            if t.size and (t.min() < 0 or t.max() >= self.n_triangles):
                raise InputError(
                    f"region {name!r} has triangle indices outside [0, {self.n_triangles})",
                    "regions",
                )
            t = np.unique(t.astype(np.int64))
            if np.any(taken[t]):
                raise InputError(f"region {name!r} overlaps another region", "regions")
            taken[t] = True
            t.setflags(write=False)
            out[str(name)] = t
        return out

    # ------------------------------------------------------------------ transforms
    def perturbed(self, amplitude: float, seed: int | None = 0) -> Mesh:
        """Randomly moved copy of the mesh (the paper's way to raise sigma_L).

        Interior nodes move by a vector drawn uniformly from the disc of radius
        ``amplitude``; boundary nodes slide along their straight side (or circle)
        by up to ``amplitude``; polygon corners stay. Meshes generated in a domain
        (and periodic meshes) are re-triangulated (Delaunay); other meshes keep
        their triangles, and a move that would invert a triangle is an error.

        Parameters
        ----------
        amplitude : float
            Largest displacement of a node (length units), >= 0.
        seed : int or None
            Random seed.

        Returns
        -------
        Mesh
        """
        amplitude = check_positive("amplitude", amplitude, allow_zero=True)
        rng = np.random.default_rng(check_seed(seed))
        p = np.array(self.points)
        if amplitude == 0:
            return self
        sampling = None if self.sampling is None else self.sampling.perturbed(amplitude)
        if self.is_periodic:
            p = np.mod(p + unit_disc(rng, len(p)) * amplitude, self.period)
            p[p >= self.period] = 0.0
            tri, images = periodic_delaunay(p, self.period)
            return Mesh(p, tri, period=self.period, images=images, sampling=sampling)
        if self.domain is None:
            bnd = self.boundary_nodes
            inner = np.setdiff1d(np.arange(self.n_points), bnd)
            p[inner] += unit_disc(rng, inner.size) * amplitude
            try:
                return Mesh(p, self.triangles, parts=dict(self.parts), sampling=sampling)
            except InputError as exc:
                raise InputError(
                    f"perturbation of amplitude {amplitude} inverts triangles of this mesh "
                    f"({exc}); use a smaller amplitude",
                    "amplitude",
                ) from None
        tol = 1e-9 * self.h
        p = move_in_domain(self.domain, p, amplitude, rng, tol)
        p, tri, parts, regions = self.domain.triangulate(p, tol, segments=self._segments(p))
        return Mesh(p, tri, parts=parts, regions=regions, domain=self.domain, sampling=sampling)

    def _segments(self, p: np.ndarray) -> np.ndarray | None:
        """Region segments at points ``p``: consecutive nodes along every region curve,
        (s, 3) with the index of the curve both ends lie on."""
        if self.domain is None or not self.domain.regions:
            return None
        tol = 1e-9 * self.h
        out, k0 = [], 0
        for loop in self.domain.regions:
            curves = loop.pieces()
            d = np.stack([c.distance(p) for c in curves], axis=1) <= tol
            nodes = np.flatnonzero(d.any(axis=1))
            k = np.argmax(d[nodes], axis=1)
            t = np.array(
                [curves[ki].param(p[n : n + 1])[0] for ki, n in zip(k, nodes, strict=True)]
            )
            nodes = nodes[np.lexsort((t, k))]
            a, b = nodes, np.roll(nodes, -1)
            both = d[a] & d[b]
            # the segments that run inside the body (not along the boundary)
            dist, _ = self.domain.curve_distances(0.5 * (p[a] + p[b]))
            inside = both.any(axis=1) & (dist.min(axis=1) > tol)
            out.append(np.c_[a, b, k0 + np.argmax(both, axis=1)][inside])
            k0 += len(curves)
        return np.vstack(out).astype(np.int64)

    def __repr__(self) -> str:
        kind = "periodic " if self.is_periodic else ""
        parts = f", parts={list(self.parts)}" if self.parts else ""
        regions = f", regions={list(self.regions)}" if self.regions else ""
        return f"Mesh({kind}N={self.n_points}, triangles={self.n_triangles}{parts}{regions})"


# ---------------------------------------------------------------------- internals
def _as_points(points) -> np.ndarray:
    try:
        p = np.array(points, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("points must be a numeric array of shape (N, 2)") from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputError(f"points must have shape (N, 2), got {p.shape}", "points")
    if len(p) < 3:
        raise InputError(f"a mesh needs at least 3 points, got {len(p)}", "points")
    if not np.all(np.isfinite(p)):
        bad = np.flatnonzero(~np.all(np.isfinite(p), axis=1))
        raise InputError(
            f"{bad.size} point(s) have non-finite coordinates (first: point {bad[0]})", "points"
        )
    return p


def _as_triangles(triangles, n: int) -> np.ndarray:
    t = np.array(triangles)
    if t.ndim != 2 or t.shape[1] != 3:
        raise InputError(f"triangles must have shape (M, 3), got {t.shape}", "triangles")
    if len(t) == 0:
        raise InputError("a mesh needs at least one triangle", "triangles")
    if not np.issubdtype(t.dtype, np.integer):
        raise TypeError(f"triangles must be integer indices, got dtype {t.dtype}")
    t = t.astype(np.int64)
    if t.min() < 0 or t.max() >= n:
        raise InputError(
            f"triangle indices must be in [0, {n}), got range [{t.min()}, {t.max()}]", "triangles"
        )
    return t


def _check_duplicates(p: np.ndarray) -> None:
    order = np.lexsort((p[:, 1], p[:, 0]))
    q = p[order]
    same = np.all(q[1:] == q[:-1], axis=1)
    if same.any():
        k = int(np.flatnonzero(same)[0])
        i, j = sorted((int(order[k]), int(order[k + 1])))
        raise InputError(
            f"{int(same.sum())} duplicate point(s) (first: points {i} and {j} at {p[i].tolist()})",
            "points",
        )
