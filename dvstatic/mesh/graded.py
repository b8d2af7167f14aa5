"""Graded meshes: a node spacing that varies over the domain (a size field).

``h`` may be a function of position, ``h(x) -> (m,)`` for points ``x`` of shape (m, 2):
the generators then place boundary nodes at equal steps of ``int ds / h`` along every
curve, draw interior points with density ``1 / h^2`` (about one node per
``sqrt(3)/2 h^2`` of area), and move them by density-weighted Lloyd iterations towards
a centroidal Voronoi tessellation of that density: well-shaped cells whose size follows
``h`` (weighted by ``h^-4``: a CVT's cells scale as the density to the power -1/4 in
2-D, so ``h^-2`` would flatten the grading). A graded mesh is therefore of kind
``"cvt"`` (or ``"random"`` without the Lloyd iterations); its relaxed calibration uses
the CVT micro-structure, which does not depend on the scale.
"""

from __future__ import annotations

import logging

import numpy as np

from .._checks import check_positive
from ..errors import InputError
from .domain import Domain

log = logging.getLogger(__name__)

__all__ = ["SizeField", "size_near", "local_h", "min_h", "spaced"]

#: points per direction of the grid on which a size field is checked
_PROBE = 64
#: steepest growth of the spacing per unit length accepted without a warning (by
#: size_near, and on the probe grid of every size field given as h). Measured on the
#: tunnel example (CVT, h_near 0.0125 growing to 0.5, seeds 0-3): at 0.16 the wall's
#: recovered hoop stress is off by -0.9 to +5.4 % in the mean (rms over the wall nodes
#: 2.3-6.6 %) although the wall displacement is right to 0.2 %: cells that grow fast
#: relax unevenly, the lattice is stiffer in some patches of the grading than in
#: others, and the recovery's correction (measured under uniform stress) reads that as
#: a bias of the micro-structure; at 0.08 the mean is within 0.9 % (rms 1.6-1.9 %), at
#: 0.04 within 1.1 % (rms 1.4 %)
MAX_GRADING = 0.1


class SizeField:
    """A checked node spacing ``h(x)`` over a domain.

    Parameters
    ----------
    fn : callable
        ``fn(x) -> (m,)`` positive finite spacings (length units) at points (m, 2).
    domain : Domain

    Raises
    ------
    InputError
        If ``fn`` returns another shape, a non-finite or non-positive value, or a
        spacing larger than the domain.
    """

    def __init__(self, fn, domain: Domain):
        self.fn = fn
        lo, hi = domain.bbox
        g = np.linspace(0.0, 1.0, _PROBE)
        xx, yy = np.meshgrid(lo[0] + g * (hi[0] - lo[0]), lo[1] + g * (hi[1] - lo[1]))
        inside = domain.contains(np.c_[xx.ravel(), yy.ravel()]).reshape(xx.shape)
        grid = np.full(xx.shape, np.nan)
        grid[inside] = self(np.c_[xx[inside], yy[inside]])
        curves = self(np.vstack([c.samples(64) for c in domain.boundary_curves()]))
        self.min = float(min(np.nanmin(grid, initial=np.inf), curves.min()))
        self.max = float(max(np.nanmax(grid, initial=-np.inf), curves.max()))
        if not getattr(fn, "slope_checked", False):  # size_near checks its own
            _warn_steep(xx, yy, grid)
        if self.max > float(np.min(hi - lo)):
            raise InputError(
                f"the size field reaches h = {self.max:.4g}, larger than the domain "
                f"(smallest extent {float(np.min(hi - lo)):.4g})",
                "h",
            )

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float).reshape(-1, 2)
        try:
            h = np.asarray(self.fn(x.copy()), dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"the size field h(x) failed: {exc}", "h") from None
        if h.shape != (len(x),):
            raise InputError(
                f"the size field h(x) must return shape ({len(x)},) for {len(x)} points, "
                f"got {h.shape}",
                "h",
            )
        if not np.all(np.isfinite(h)) or np.any(h <= 0):
            raise InputError("the size field h(x) must be finite and > 0 everywhere", "h")
        return h


def _warn_steep(xx: np.ndarray, yy: np.ndarray, hv: np.ndarray) -> None:
    """Log a warning where the size field ``hv`` (its values on the probe grid ``xx,
    yy``, NaN outside the domain) grows faster than :data:`MAX_GRADING` between
    neighbouring grid points."""
    dx, dy = xx[0, 1] - xx[0, 0], yy[1, 0] - yy[0, 0]
    gx = np.pad(np.diff(hv, axis=1) / dx, ((0, 0), (0, 1)), constant_values=np.nan)
    gy = np.pad(np.diff(hv, axis=0) / dy, ((0, 1), (0, 0)), constant_values=np.nan)
    slope = np.hypot(np.nan_to_num(gx), np.nan_to_num(gy))  # the gradient's length
    slope[np.isnan(gx) & np.isnan(gy)] = np.nan
    if not np.any(slope > MAX_GRADING):
        return
    i = np.unravel_index(np.nanargmax(slope), slope.shape)
    log.warning(
        "the size field grows by up to %.3g per unit length (near (%.4g, %.4g)), more "
        "than %g: the lattice relaxes unevenly across so steep a grading and stresses "
        "near the fine region can be biased by several percent",
        slope[i],
        xx[i],
        yy[i],
        MAX_GRADING,
    )


def local_h(h, p: np.ndarray) -> np.ndarray | float:
    """The spacing at points ``p``: ``h`` itself, or the size field's values."""
    return h(p) if isinstance(h, SizeField) else h


def min_h(h) -> float:
    """The smallest spacing (sets tolerances)."""
    return h.min if isinstance(h, SizeField) else float(h)


def spaced(curve, h) -> np.ndarray:
    """Points on ``curve`` at spacing ``h`` (a number or a size field), the end
    excluded, (n, 2): equal steps of ``int ds / h``."""
    if not isinstance(h, SizeField):
        return curve.spaced(h)
    t = np.linspace(0.0, 1.0, 2049)
    x = curve.point(t)
    mid = 0.5 * (x[1:] + x[:-1])
    steps = np.hypot(*np.diff(x, axis=0).T) / h(mid)
    cum = np.concatenate([[0.0], np.cumsum(steps)])
    n = curve.count(cum[-1])
    return curve.point(np.interp(np.arange(n) / n * cum[-1], cum, t))


def check_h(h, domain: Domain):
    """``h`` checked: a positive number, or a :class:`SizeField` for a callable."""
    if callable(h):
        return SizeField(h, domain)
    return check_positive("h", h)


def density_points(domain: Domain, h: SizeField, rng, distance) -> np.ndarray:
    """Interior points with density ``1 / (sqrt(3)/2 h^2)`` by rejection sampling,
    none closer than ``0.3 h`` to the boundary (``distance(p)`` gives that distance).

    The proposals of every round are sized by the acceptance rate measured on a probe
    (``(h_min / h)^2`` over the domain), so a strong grading (``h_near << h``) still
    gets all its points: the count grows as ``h_near`` shrinks."""
    lo, hi = domain.bbox
    probe = lo + (hi - lo) * rng.random((20000, 2))
    inside = domain.contains(probe)
    if not inside.any():
        return np.zeros((0, 2))
    hp = h(probe[inside])
    box = float(np.prod(hi - lo))
    frac = inside.mean()
    n_target = int(round(frac * box * np.mean(1.0 / (np.sqrt(3) / 2 * hp**2))))
    accept = max(frac * float(np.mean((h.min / hp) ** 2)), 1e-9)
    out = [np.zeros((0, 2))]
    have = 0
    for _ in range(1000):
        if have >= n_target:
            break
        want = min(int(1.3 * (n_target - have) / accept) + 64, 4_000_000)
        cand = lo + (hi - lo) * rng.random((want, 2))
        cand = cand[domain.contains(cand)]
        hc = h(cand)
        cand = cand[rng.random(len(cand)) < (h.min / hc) ** 2]
        cand = cand[distance(cand) >= 0.3 * h(cand)]
        out.append(cand)
        have += len(cand)
    return np.vstack(out)[:n_target]


def size_near(domain: Domain, parts, h_near: float, h: float, distance: float):
    """A size field finer near named boundary curves: ``h_near`` on them, growing
    linearly to ``h`` at ``distance`` from them (and ``h`` beyond).

    Parameters
    ----------
    domain : Domain
    parts : str or sequence of str
        Names of boundary curves (a hole, a loaded side) or of region loops.
    h_near, h : float
        Spacing on the curves and far from them (length), 0 < h_near <= h.
    distance : float
        Length over which the spacing grows, > 0.

    Returns
    -------
    callable
        ``h(x) -> (m,)``, to pass as ``h`` to a generator.
    """
    names = [parts] if isinstance(parts, str) else list(parts)
    h_near = check_positive("h_near", h_near)
    h = check_positive("h", h)
    distance = check_positive("distance", distance)
    if h_near > h:
        raise InputError(f"h_near = {h_near} must not exceed h = {h}", "h_near")
    known = domain.curve_names() + [loop.region_name for loop in domain.regions]
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise InputError(
            f"size_near: unknown part(s) {bad or names}; the domain's: {', '.join(known)}",
            "parts",
        )
    slope = (h - h_near) / distance
    if slope > MAX_GRADING:
        log.warning(
            "size_near: the spacing grows by %.3g per unit length (from %g to %g over %g), "
            "more than %g: the lattice relaxes unevenly across so steep a grading and "
            "stresses near the fine region can be biased by several percent; use a larger "
            "distance (grading) of at least %.3g",
            slope,
            h_near,
            h,
            distance,
            MAX_GRADING,
            (h - h_near) / MAX_GRADING,
        )
    # one column per curve of every region loop, named by its loop
    region_cols = [loop.region_name for loop in domain.regions for _ in loop.pieces()]

    def field(x: np.ndarray) -> np.ndarray:
        d, curve_names = domain.curve_distances(x)
        sel = [i for i, n in enumerate(curve_names) if n in names]
        dist = d[:, sel].min(axis=1) if sel else np.full(len(x), np.inf)
        rsel = [i for i, n in enumerate(region_cols) if n in names]
        if rsel:
            dist = np.minimum(dist, domain.region_distances(x)[:, rsel].min(axis=1))
        return h_near + (h - h_near) * np.clip(dist / distance, 0.0, 1.0)

    field.slope_checked = True  # warned above, with the distance to use
    return field
