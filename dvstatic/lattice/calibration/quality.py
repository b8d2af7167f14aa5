"""Where a mesh's micro-structure lies outside what its calibration was measured on.

A mesh without a generator recipe is calibrated on periodic samples of its *local
spread* (:func:`.descriptors.local_spread`: the spread of the bond lengths relative to the
local spacing), one sample for the whole mesh or one per class of a mesh that mixes
micro-structures (:mod:`.classes`). Two things put a part of such a mesh outside what
its sample measured:

* **a patch of another micro-structure**: a region whose local spread differs from
  its calibration's by more than :data:`TOLERANCE` (a patch of random points in a
  regular mesh, too small to make the mesh count as mixed; slivers where a mesher
  struggled). The relaxed moduli move by about 3 % per 0.1 of spread (a regular
  lattice calibrated as spread 0.27 came out 8 % stiff, random points as 0.27 2 %
  soft; validation/mixed_mesh.py);
* **a spread beyond the samples' reach**: the most irregular sample is a set of random
  points (local spread 0.365); a mesh (or class) more irregular still (clustered
  points) is calibrated as random points.

:func:`calibration_flags` finds both; the models log one warning per flag, naming the
region (or the place) and the descriptor, and keep them in
``model.calibration_flags`` (the run's JSON: ``model.calibration_flags``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...mesh import Mesh
from ...mesh.graded import MAX_GRADING
from .. import geometry as _geometry
from .descriptors import deep_nodes, ring_mean, spread_field

__all__ = [
    "ANISOTROPY",
    "BOUNDARY_RINGS",
    "DEFECT_MARGIN",
    "MIN_TRIANGLES",
    "QUALITY_RINGS",
    "TOLERANCE",
    "QualityFlag",
    "calibration_flags",
    "anisotropy_flags",
    "defect_flags",
    "grading_flags",
    "slope_field",
    "patches",
    "triangle_spread",
]

#: a region is flagged where its local spread differs from its calibration's by more
#: than this (about 3 % in the relaxed moduli)
TOLERANCE = 0.1
#: the local spread is averaged over this many rings (on random points the node
#: values then scatter from 0.30 to 0.45 around 0.36, 1st to 99th percentile)
QUALITY_RINGS = 4
#: a flagged region has at least this many connected triangles (the noise of the
#: ring average on random points makes clusters of up to about 50)
MIN_TRIANGLES = 100
#: a calibration's spread may exceed its sample's by this much, plus twice the
#: standard error of a spread measured on that many bonds, before it counts as beyond
#: the samples' reach (the samples match spreads to 1 %, quantised to 0.005; random
#: points of 150 to 500 nodes measure 0.37 to 0.39)
REACH_MARGIN = 0.02
#: patches are looked for more than this many rings away from the boundary: its cut cells,
#: surface springs and (on a Delaunay triangulation of raw points) the hull's slivers,
#: up to 7 rings deep, are not the interior micro-structure, and the ring average
#: carries them inwards (2 x QUALITY_RINGS)
BOUNDARY_RINGS = 2 * QUALITY_RINGS
#: a region holding more than this share of the mesh does not name a place
WHOLE_SHARE = 0.9
#: a region whose bonds' fabric deviator (:func:`.descriptors.fabric_anisotropy`)
#: exceeds this is anisotropic beyond what an isotropic calibration describes (random
#: points reach 0.16 at single nodes, a square grid split by parallel diagonals is 0.25
#: everywhere and 9 % soft along its axes)
ANISOTROPY = 0.2
#: a region whose mesh spacing grows faster than this (per unit length, measured as
#: :func:`slope_field` does) is graded too steeply for the lattice to relax evenly
#: (mesh.graded.MAX_GRADING, 0.1, with a margin for the estimate: on uniform random
#: points it reads up to 0.099, on gmsh meshes graded at 0.1 up to 0.105)
GRADING = 1.25 * MAX_GRADING
#: rings over which the node spacing, then its gradient, are averaged
GRADING_RINGS = 6
#: a calibration whose defect fraction exceeds the CVT family's at its local spread by
#: more than this is of cells no sample family has (CVT-like meshes lie within 0.05
#: of the family, random points on it)
DEFECT_MARGIN = 0.15


@dataclass(frozen=True)
class QualityFlag:
    """A part of a mesh outside what its calibration was measured on.

    Attributes
    ----------
    kind : {"patch", "reach", "defects", "anisotropy", "grading"}
        A region of another local spread, a spread beyond the samples', a defect
        fraction beyond the samples' (cells of no sample family), an anisotropic
        fabric, or a spacing that grows too fast.
    where : str
        ``"region 'name'"``, ``"the whole mesh"``, ``"class k"`` or
        ``"triangles around (x, y)"``.
    triangles : int
        How many triangles it holds.
    spread : float
        Its local spread (``"patch"``: the mean over its triangles of the spread
        around them; ``"reach"``: the spread its calibration asked for); ``"defects"``:
        its defect fraction.
    calibrated : float
        The local spread its calibration was measured at: its sample's (``"patch"``
        in a mesh calibrated as one: the mesh's, which its sample matches to 1 %
        unless the whole mesh is beyond reach); ``"defects"``: the CVT family's defect
        fraction at its local spread. ``"grading"``: ``spread`` is the largest slope
        of the spacing in the region, ``calibrated`` the limit (:data:`GRADING`).
    box : tuple of float
        Its bounding box ``(x_min, y_min, x_max, y_max)`` (mesh units).
    """

    kind: str
    where: str
    triangles: int
    spread: float
    calibrated: float
    box: tuple[float, float, float, float]

    def message(self) -> str:
        """The warning's text."""
        x0, y0, x1, y1 = self.box
        box = f"[{x0:.3g}, {x1:.3g}] x [{y0:.3g}, {y1:.3g}]"
        if self.kind == "grading":
            return (
                f"{self.where} ({self.triangles} triangles, {box}): the mesh spacing grows "
                f"by up to {self.spread:.2f} per unit length, more than {MAX_GRADING:g} "
                f"(measured over {GRADING_RINGS} rings): the lattice relaxes unevenly across "
                "so steep a grading and the stresses near its fine side can be biased by "
                "several % (a tunnel wall graded at 0.16: +5 % hoop stress); remesh with "
                "the spacing growing more slowly"
            )
        if self.kind == "anisotropy":
            return (
                f"{self.where} ({self.triangles} triangles, {box}): the fabric of its bonds "
                f"is anisotropic (deviator {self.spread:.3f}, above {self.calibrated:.2f}; "
                "e.g. a square grid split by parallel diagonals, 0.25): the lattice there "
                "is stiffer along some directions than others, which an isotropic "
                "calibration cannot match (that grid: 9 % soft along its axes); remesh "
                "with unstructured cells"
            )
        if self.kind == "defects":
            return (
                f"{self.where} ({self.triangles} triangles, {box}): {self.spread:.2f} of its "
                "interior nodes have other than six bonds, beyond the calibration samples of "
                f"its local spread (at most {self.calibrated:.2f}, CVT-like cells): cells no "
                "sample has (e.g. a square grid split by alternating diagonals); its moduli "
                "may be off by several % (17 % on that grid)"
            )
        if self.kind == "reach":
            return (
                f"{self.where} ({self.triangles} triangles, {box}): local spread "
                f"{self.spread:.3f} (bond length over the local spacing) is beyond the most "
                f"irregular calibration sample's ({self.calibrated:.3f}, random points); "
                "it is calibrated as random points"
            )
        return (
            f"{self.where} ({self.triangles} triangles, {box}): local spread "
            f"{self.spread:.3f} (bond length over the local spacing, {QUALITY_RINGS} rings) "
            f"against {self.calibrated:.3f} that its calibration was measured at; "
            "its moduli may be off by about 3 % per 0.1 of difference"
        )

    def as_dict(self) -> dict:
        """The flag as JSON-ready values."""
        return {
            "kind": self.kind,
            "where": self.where,
            "triangles": self.triangles,
            **_values(self),
            "box": list(self.box),
        }


def calibration_flags(
    mesh: Mesh, calibrated: np.ndarray, sample: np.ndarray | None = None
) -> tuple[QualityFlag, ...]:
    """The parts of ``mesh`` outside what their calibration was measured on.

    Parameters
    ----------
    mesh : Mesh
        Not periodic.
    calibrated : ndarray, shape (M,)
        The local spread every triangle's calibration was measured at (the mesh's,
        or its class's sample's); a region whose own spread differs from it (averaged
        over the same rings) by more than :data:`TOLERANCE` is a patch. A class of a
        mesh calibrated by class has no "reach" flag (its spread is a selection of
        the mesh's bonds, so a class of the highest spreads scores above random
        points while it is random points): a region beyond reach there is a patch
        against the random points' sample.
    sample : ndarray, shape (M,), optional
        The local spread of the sample every triangle's calibration was measured on;
        where ``calibrated`` exceeds it by more than :data:`REACH_MARGIN`, the
        calibration is beyond its samples' reach.

    Returns
    -------
    tuple of QualityFlag
        Beyond-reach flags first (one per distinct calibrated spread), then the
        patches, largest first.
    """
    calibrated = np.asarray(calibrated, dtype=float)
    flags = list(_reach_flags(mesh, calibrated, sample))
    field = triangle_spread(mesh)
    for tris in patches(mesh, calibrated, field):
        flags.append(
            QualityFlag(
                "patch",
                _where(mesh, tris),
                len(tris),
                float(field[tris].mean()),
                float(np.median(calibrated[tris])),
                _box(mesh, tris),
            )
        )
    return tuple(flags)


def triangle_spread(mesh: Mesh) -> np.ndarray:
    """The local spread around every triangle, shape (M,): the mean over its nodes of
    :func:`.descriptors.spread_field` over :data:`QUALITY_RINGS` rings."""
    return spread_field(mesh, rings=QUALITY_RINGS)[mesh.triangles].mean(axis=1)


def patches(mesh: Mesh, calibrated, field: np.ndarray | None = None) -> list[np.ndarray]:
    """The regions of ``mesh`` (arrays of triangle indices, largest first) whose local
    spread differs from ``calibrated`` by more than :data:`TOLERANCE`: edge-connected,
    at least :data:`MIN_TRIANGLES` triangles, more than :data:`BOUNDARY_RINGS` rings
    from the boundary.

    ``calibrated`` is a value, or one per triangle (shape (M,): a mesh calibrated by
    class), then averaged over the same rings as the local spread (as rms), so that
    the two blur an interface between classes alike. ``field`` (shape (M,)) is
    :func:`triangle_spread`, computed when not given."""
    field = triangle_spread(mesh) if field is None else field
    calibrated = np.asarray(calibrated, dtype=float)
    if calibrated.ndim and np.ptp(calibrated) > 0:
        calibrated = _ring_rms(mesh, calibrated)
    off = (np.abs(field - calibrated) > TOLERANCE) & ~_near_boundary(mesh)
    return _clusters(mesh, off)


def _ring_rms(mesh: Mesh, per_triangle: np.ndarray) -> np.ndarray:
    """``per_triangle`` (M,) averaged as rms over :data:`QUALITY_RINGS` rings, as
    :func:`triangle_spread` averages the bonds' deviations, shape (M,)."""
    n = mesh.n_points
    tri = mesh.triangles.ravel()
    sq = np.repeat(per_triangle**2, 3)
    node = np.bincount(tri, sq, n) / np.maximum(np.bincount(tri, None, n), 1)
    return np.sqrt(ring_mean(mesh, node, QUALITY_RINGS))[mesh.triangles].mean(axis=1)


def _reach_flags(mesh: Mesh, calibrated: np.ndarray, sample):
    if sample is None:
        return
    sample = np.asarray(sample, dtype=float)
    beyond = calibrated > sample + REACH_MARGIN
    whole = bool(beyond.all())
    for value in np.unique(calibrated[beyond]):  # one per class: a handful
        tris = np.flatnonzero(beyond & (calibrated == value))
        # a spread measured on about 1.5 bonds per triangle: its standard error
        if value <= np.median(sample[tris]) + REACH_MARGIN + 2 * value / np.sqrt(3 * len(tris)):
            continue
        where = "the whole mesh" if whole else _where(mesh, tris)
        yield QualityFlag(
            "reach",
            where,
            len(tris),
            float(value),
            float(np.median(sample[tris])),
            _box(mesh, tris),
        )


def anisotropy_flags(mesh: Mesh) -> list[QualityFlag]:
    """The regions of ``mesh`` whose fabric deviator exceeds :data:`ANISOTROPY`
    (edge-connected, at least :data:`MIN_TRIANGLES` triangles, more than
    :data:`BOUNDARY_RINGS` rings from the boundary), largest first."""
    from .descriptors import fabric_anisotropy

    tri = fabric_anisotropy(mesh)[mesh.triangles].mean(axis=1)
    inner = ~_near_boundary(mesh)
    found = _clusters(mesh, (tri > ANISOTROPY) & inner)
    whole = len(found) == 1 and len(found[0]) > WHOLE_SHARE * np.count_nonzero(inner)
    return [
        QualityFlag(
            "anisotropy",
            "the whole mesh" if whole else _where(mesh, tris),
            len(tris),
            float(tri[tris].mean()),
            ANISOTROPY,
            _box(mesh, tris),
        )
        for tris in found
    ]


def defect_flags(mesh: Mesh, spread: np.ndarray, defects: np.ndarray) -> list[QualityFlag]:
    """The calibrations of ``mesh`` whose defect fraction lies more than
    :data:`DEFECT_MARGIN` above the CVT family's at their local spread.

    Parameters
    ----------
    mesh : Mesh
    spread, defects : ndarray, shape (M,)
        The local spread and the defect fraction every triangle's calibration was
        asked for (one value for the whole mesh, or one per class).
    """
    from .table import family_defects

    spread, defects = np.asarray(spread, dtype=float), np.asarray(defects, dtype=float)
    flags = []
    pairs = np.unique(np.c_[spread, defects], axis=0)
    for s, d in pairs:  # one per class: a handful
        limit = family_defects(float(s))
        if not d > limit + DEFECT_MARGIN:  # NaN (no family in the table): no flag
            continue
        tris = np.flatnonzero((spread == s) & (defects == d))
        where = "the whole mesh" if len(pairs) == 1 else _where(mesh, tris)
        flags.append(
            QualityFlag("defects", where, len(tris), float(d), float(limit), _box(mesh, tris))
        )
    return flags


def slope_field(mesh: Mesh) -> np.ndarray:
    """How fast the mesh spacing grows around every triangle, shape (M,) (length per
    length): the node spacing (the median length of a node's bonds) averaged over
    :data:`GRADING_RINGS` rings, its gradient on every triangle, area-weighted at the
    nodes and averaged over as many rings again, and the gradient's length. It reads
    0.152 / 0.094 on CVT meshes of the package graded at 0.15 / 0.075, 0.105 / 0.082 /
    0.188 on gmsh meshes graded at 0.1 / 0.075 / 0.2; at single nodes off the boundary
    up to 0.068 on uniform CVT meshes and 0.134 on uniform random points (in regions
    too small to flag)."""
    n, p, t = mesh.n_points, mesh.points, mesh.triangles
    h = ring_mean(mesh, _median_bond(mesh), GRADING_RINGS)
    x = p[t]
    edges = [x[:, 2] - x[:, 1], x[:, 0] - x[:, 2], x[:, 1] - x[:, 0]]  # opposite each node
    twice = edges[2][:, 0] * edges[1][:, 1] - edges[2][:, 1] * edges[1][:, 0]  # -2 A
    grad = sum(h[t[:, k], None] * np.c_[-e[:, 1], e[:, 0]] for k, e in enumerate(edges))
    grad = grad / -twice[:, None]
    area = np.repeat(np.abs(twice), 3)
    weight = np.maximum(np.bincount(t.ravel(), area, n), 1e-300)
    node = [
        ring_mean(
            mesh, np.bincount(t.ravel(), area * np.repeat(grad[:, c], 3), n) / weight, GRADING_RINGS
        )
        for c in range(2)
    ]
    return np.hypot(*node)[t].mean(axis=1)


#: a boundary is taken for the convex hull of raw points (a Delaunay triangulation
#: without a mesher's boundary) where more than this share of its triangles has an
#: angle below :data:`SLIVER_ANGLE` degrees (a mesher's graded boundaries: none)
HULL_SLIVERS = 0.1
SLIVER_ANGLE = 10.0


def _raw_hull(mesh: Mesh) -> bool:
    """Whether ``mesh``'s boundary looks like the hull of raw points (slivers)."""
    bt = mesh.topology.bond_tris
    tris = bt[bt[:, 1] < 0, 0]  # a triangle at every boundary bond
    sine = _geometry.smallest_sine(_geometry.of(mesh), tris)
    return bool(np.mean(sine < np.sin(np.radians(SLIVER_ANGLE))) > HULL_SLIVERS)


def _median_bond(mesh: Mesh) -> np.ndarray:
    """The median length of every node's bonds, shape (N,) (a hull's long slivers
    leave it alone)."""
    b, p = mesh.topology.bonds, mesh.points
    length = np.hypot(*(p[b[:, 1]] - p[b[:, 0]]).T)
    node, value = b.ravel(), np.repeat(length, 2)
    # sorted by node, then by length: one sort of node + length / (a bit more than the
    # longest) (a third of the time of a lexsort on the two keys)
    order = np.argsort(node + value / (2.0 * value.max()))
    node, value = node[order], value[order]
    count = np.bincount(node, None, mesh.n_points).astype(np.int64)
    start = np.r_[0, np.cumsum(count)[:-1]]
    lo, hi = start + (count - 1) // 2, start + count // 2
    out = np.zeros(mesh.n_points)
    has = count > 0
    out[has] = 0.5 * (value[lo[has]] + value[hi[has]])
    return out


def grading_flags(mesh: Mesh) -> list[QualityFlag]:
    """The regions of ``mesh`` whose spacing grows faster than :data:`GRADING`
    (:func:`slope_field`; edge-connected, at least :data:`MIN_TRIANGLES` triangles, more
    than two rings from the boundary, or :data:`BOUNDARY_RINGS` rings where the boundary
    is the hull of raw points, whose slivers read as steep grading), largest first."""
    slope = slope_field(mesh)
    rings = BOUNDARY_RINGS if _raw_hull(mesh) else 2
    inner = deep_nodes(mesh, rings)[mesh.triangles].all(axis=1)
    return [
        QualityFlag(
            "grading",
            _steepest(mesh, tris, slope),
            len(tris),
            float(slope[tris].max()),
            GRADING,
            _box(mesh, tris),
        )
        for tris in _clusters(mesh, (slope > GRADING) & inner)
    ]


def _steepest(mesh: Mesh, tris: np.ndarray, slope: np.ndarray) -> str:
    """A graded region's name, or its steepest place (a ring of graded cells around a
    hole has its centroid in the hole)."""
    where = _where(mesh, tris)
    if where.startswith("region"):
        return where
    x, y = mesh.points[mesh.triangles[tris[np.argmax(slope[tris])]]].mean(axis=0)
    return f"the cells around ({x:.3g}, {y:.3g})"


def _values(flag: QualityFlag) -> dict:
    """The flag's two numbers under their names for the JSON."""
    if flag.kind == "defects":
        return {"defect_fraction": flag.spread, "family_defect_fraction": flag.calibrated}
    if flag.kind == "grading":
        return {"slope": flag.spread, "limit": flag.calibrated}
    return {"local_spread": flag.spread, "calibrated_spread": flag.calibrated}


def _near_boundary(mesh: Mesh) -> np.ndarray:
    """Triangles with a node within :data:`BOUNDARY_RINGS` rings of the boundary,
    shape (M,)."""
    return (~deep_nodes(mesh, BOUNDARY_RINGS))[mesh.triangles].any(axis=1)


def _clusters(mesh: Mesh, flagged: np.ndarray) -> list[np.ndarray]:
    """Edge-connected sets of flagged triangles with at least :data:`MIN_TRIANGLES`,
    largest first."""
    if np.count_nonzero(flagged) < MIN_TRIANGLES:
        return []
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    bt = mesh.topology.bond_tris
    a, b = bt[:, 0], bt[:, 1]
    keep = (b >= 0) & flagged[a] & flagged[np.maximum(b, 0)]
    m = mesh.n_triangles
    graph = sp.coo_matrix((np.ones(np.count_nonzero(keep)), (a[keep], b[keep])), shape=(m, m))
    _, label = connected_components(graph, directed=False)
    label = np.where(flagged, label, -1)
    sizes = np.bincount(label[flagged])
    big = np.flatnonzero(sizes >= MIN_TRIANGLES)
    big = big[np.argsort(-sizes[big], kind="stable")]
    return [np.flatnonzero(label == c) for c in big]  # a handful of regions


def _where(mesh: Mesh, tris: np.ndarray) -> str:
    """The named region holding most of ``tris`` (if it holds most of them and is not
    nearly the whole mesh), else the place (their centroid)."""
    best, share = None, 0.5
    for name, members in mesh.regions.items():
        if len(members) > WHOLE_SHARE * mesh.n_triangles:
            continue  # "region 'body'" of a one-surface import says nothing
        s = np.count_nonzero(np.isin(tris, members)) / len(tris)
        if s > share:
            best, share = name, s
    if best is not None:
        return f"region {best!r}"
    x, y = mesh.points[mesh.triangles[tris]].reshape(-1, 2).mean(axis=0)
    return f"triangles around ({x:.3g}, {y:.3g})"


def _box(mesh: Mesh, tris: np.ndarray) -> tuple[float, float, float, float]:
    p = mesh.points[mesh.triangles[tris]].reshape(-1, 2)
    lo, hi = p.min(axis=0), p.max(axis=0)
    return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
