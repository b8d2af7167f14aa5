"""The triangular lattice of rectangles and bounding boxes: row and column counts
that keep the rows nearly equilateral, lattice points, jitter that tapers off at the
boundary, and random points of the same density.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sampling import unit_disc

__all__ = [
    "SQRT3_2",
    "SPACING_FREEDOM",
    "Grid",
    "lattice_counts",
    "lattice_points",
    "jitter_rectangle",
    "random_rectangle_points",
]


#: relative freedom of the lattice spacing of a rectangle (see :func:`lattice_counts`)
SPACING_FREEDOM = 0.15


SQRT3_2 = np.sqrt(3.0) / 2.0


@dataclass(frozen=True)
class Grid:
    """The triangular lattice of a domain's bounding box: rows ``hy`` apart from its
    bottom to its top, ``nx`` columns ``hx`` apart from its left to its right side, odd
    rows shifted by ``hx / 2`` (:func:`lattice_counts` makes the rows nearly
    equilateral). Boundary lines along a row or a side of the box get their nodes
    from it, so that the cells there are the lattice's own."""

    lo: np.ndarray
    hx: float
    hy: float
    nx: int
    ny: int

    @classmethod
    def fitted(cls, lo: np.ndarray, hi: np.ndarray, h: float) -> Grid:
        nx, ny = lattice_counts(float(hi[0] - lo[0]), float(hi[1] - lo[1]), h)
        return cls(np.asarray(lo, dtype=float), (hi[0] - lo[0]) / nx, (hi[1] - lo[1]) / ny, nx, ny)

    def points(self) -> np.ndarray:
        """Every lattice point of the box, (n, 2)."""
        rows = []
        for j in range(self.ny + 1):
            i = np.arange(self.nx + 1) if j % 2 == 0 else np.arange(self.nx) + 0.5
            rows.append(np.c_[self.lo[0] + i * self.hx, np.full(len(i), self.lo[1] + j * self.hy)])
        return np.vstack(rows)

    def line_points(self, curve, tol: float) -> np.ndarray | None:
        """Nodes of a straight boundary line from the lattice (its start included, its
        end excluded): the row's points along a row, every row along a vertical line at
        a column of the box; None for other lines."""
        if not curve.straight:
            return None
        a, b = curve.a, curve.b
        if abs(a[1] - b[1]) <= tol:
            j = (a[1] - self.lo[1]) / self.hy
            if abs(j - round(j)) * self.hy > tol:
                return None
            off = 0.5 * (round(j) % 2)
            i = np.arange(-1, self.nx + 2) + off
            x = self.lo[0] + i * self.hx
            along = (x - a[0]) / (b[0] - a[0])
        elif abs(a[0] - b[0]) <= tol:
            i = (a[0] - self.lo[0]) / self.hx
            if abs(i - round(2 * i) / 2) * self.hx > tol:
                return None
            y = self.lo[1] + np.arange(-1, self.ny + 2) * self.hy
            along = (y - a[1]) / (b[1] - a[1])
        else:
            return None
        eps = tol / curve.length
        t = np.sort(along[(along > eps) & (along < 1 - eps)])
        t = np.concatenate([[0.0], t])
        # a first or last step shorter than 0.45 of the spacing is merged away
        step = (self.hx if abs(a[1] - b[1]) <= tol else self.hy) / curve.length
        if len(t) > 1 and t[1] < 0.45 * step:
            t = np.delete(t, 1)
        if len(t) > 1 and 1 - t[-1] < 0.45 * step:
            t = t[:-1]
        return a + t[:, None] * (b - a)


def lattice_counts(width: float, height: float, h: float) -> tuple[int, int]:
    """Columns and rows of the triangular lattice of a rectangle: the node spacing
    ``width / nx`` within :data:`SPACING_FREEDOM` of ``h``, chosen so that the rows
    (``height / ny`` apart) are as close as possible to the equilateral
    ``sqrt(3)/2 width / nx`` (a lattice stretched by a few percent is anisotropic, and
    the stretch would change sign from one refinement to the next)."""
    ny0 = height / (h * SQRT3_2)
    lo = max(1, int(np.floor(ny0 * (1 - SPACING_FREEDOM))))
    ny = np.arange(lo, max(lo, int(np.ceil(ny0 * (1 + SPACING_FREEDOM)))) + 1)
    hy = height / ny
    nx = np.maximum(1, np.round(width * SQRT3_2 / hy)).astype(int)
    hx = width / nx
    stretch = np.abs(hy / (hx * SQRT3_2) - 1.0)
    off = np.abs(hx / h - 1.0)
    cost = stretch + 0.05 * off + np.where(off > SPACING_FREEDOM, 1.0, 0.0)
    best = int(np.argmin(cost))
    return int(nx[best]), int(ny[best])


def lattice_points(width: float, height: float, h: float):
    """Triangular lattice filling the rectangle, boundary nodes on the sides.

    Returns points, boundary mask, along-side direction (0 = x, 1 = y, -1 corner)
    and the node spacing along that side.
    """
    nx, ny = lattice_counts(width, height, h)
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


def jitter_rectangle(p, boundary, side_dir, side_step, width, height, h, jitter, rng) -> None:
    """Shift lattice nodes: interior nodes in a disc of radius ``jitter * h``, tapered
    to zero near the sides (ramp from 0.4 h to 1.2 h), boundary nodes along their side by
    up to half that. The taper keeps the boundary cells well shaped: a boundary node
    with two triangles and an obtuse angle makes the DV coupling there indefinite.
    """
    interior = ~boundary
    d_wall = np.minimum.reduce([p[:, 0], width - p[:, 0], p[:, 1], height - p[:, 1]])
    taper = np.clip((d_wall - 0.4 * h) / (0.8 * h), 0.0, 1.0)
    shift = unit_disc(rng, len(p)) * (jitter * h * taper)[:, None]
    p[interior] += shift[interior]
    slide = (rng.random(len(p)) * 2 - 1) * 0.5 * jitter * side_step
    for axis in (0, 1):
        sel = boundary & (side_dir == axis)
        p[sel, axis] += slide[sel]


def random_rectangle_points(width: float, height: float, h: float, rng) -> np.ndarray:
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
