"""Boundary curves: straight lines, circular arcs and elliptic arcs, each with a name.

A loop of a :class:`~dvstatic.mesh.domain.Domain` is a closed chain of curves
(:class:`~dvstatic.mesh.domain.Polygon`: lines; :class:`~dvstatic.mesh.domain.Circle`:
one full arc; :class:`~dvstatic.mesh.domain.Path`: any chain). A curve gives points
along itself (the generators place boundary nodes with it), distances and projections
(meshes keep their true geometry when the FE reference refines them), and sliding
along itself (perturbed meshes keep their boundary nodes on it). Angles are in
degrees.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .._checks import check_positive, check_real, check_vector2
from ..errors import InputError

__all__ = ["Curve", "Line", "Arc", "EllipseArc"]


@dataclass(frozen=True, eq=False)
class Curve(ABC):
    """A named parametric curve ``C(t)``, ``t`` in [0, 1] (base of the concrete kinds,
    each a frozen dataclass with a ``name`` field)."""

    straight: ClassVar[bool] = False

    @abstractmethod
    def point(self, t: np.ndarray) -> np.ndarray:
        """Points ``C(t)``, shape (m, 2)."""

    @abstractmethod
    def derivative(self, t: np.ndarray) -> np.ndarray:
        """``C'(t)``, shape (m, 2)."""

    @property
    def start(self) -> np.ndarray:
        return self.point(np.zeros(1))[0]

    @property
    def end(self) -> np.ndarray:
        return self.point(np.ones(1))[0]

    @property
    def closed(self) -> bool:
        """True for a curve that ends where it starts (a full circle or ellipse)."""
        return bool(np.allclose(self.start, self.end, atol=1e-12 * (1 + self.length)))

    @property
    def length(self) -> float:
        t = np.linspace(0.0, 1.0, 2049)
        x = self.point(t)
        return float(np.hypot(*np.diff(x, axis=0).T).sum())

    def spaced(self, h: float) -> np.ndarray:
        """Points at spacing about ``h`` from the start, the end excluded, (n, 2)."""
        n = self.count(self.length / h)
        return self.point(self._arclength_params(np.arange(n) / n))

    def count(self, steps: float) -> int:
        """Nodes of a curve ``steps`` spacings long: a closed curve gets a multiple of
        four (at least 4), so that the ends of its axes (of a full circle: the points
        at 0, 90, 180 and 270 degrees) are nodes, where symmetry supports go."""
        if getattr(self, "closed", False):
            return 4 * max(1, int(round(steps / 4)))
        return max(1, int(round(steps)))

    def _arclength_params(self, frac: np.ndarray) -> np.ndarray:
        """Curve parameters at fractions ``frac`` of the arc length."""
        t = np.linspace(0.0, 1.0, 2049)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(self.point(t), axis=0).T))])
        return np.interp(frac * s[-1], s, t)

    def samples(self, n: int = 256) -> np.ndarray:
        """A fine polyline of the curve, the end excluded, (n, 2)."""
        return self.point(np.arange(n) / n) if not self.straight else self.point(np.zeros(1))

    def param(self, p: np.ndarray) -> np.ndarray:
        """Parameter of the nearest point of the curve, shape (m,)."""
        p = np.asarray(p, dtype=float).reshape(-1, 2)
        t0 = np.linspace(0.0, 1.0, 513)
        x0 = self.point(t0)
        d2 = ((p[:, None, :] - x0[None]) ** 2).sum(axis=2)
        t = t0[np.argmin(d2, axis=1)]
        for _ in range(8):  # Newton on C'(t).(C(t) - p) = 0
            c, dc = self.point(t), self.derivative(t)
            h = 1e-6
            ddc = self.derivative(np.minimum(t + h, 1.0)) - self.derivative(np.maximum(t - h, 0))
            ddc /= (np.minimum(t + h, 1.0) - np.maximum(t - h, 0.0))[:, None]
            f = np.einsum("ij,ij->i", dc, c - p)
            fp = np.einsum("ij,ij->i", ddc, c - p) + np.einsum("ij,ij->i", dc, dc)
            t = np.clip(t - f / np.where(fp > 0, fp, 1.0), 0.0, 1.0)
        return t

    def project(self, p: np.ndarray) -> np.ndarray:
        """Nearest points on the curve, shape (m, 2)."""
        return self.point(self.param(p))

    def distance(self, p: np.ndarray) -> np.ndarray:
        """Distance of points to the curve, shape (m,)."""
        q = self.project(p)
        return np.hypot(*(np.asarray(p) - q).T)

    def slide(self, p: np.ndarray, shift: np.ndarray, margin: float) -> np.ndarray:
        """Points on the curve moved along it by arc lengths ``shift`` (kept ``margin``
        away from its ends unless the curve is closed), shape (m, 2)."""
        t = self.param(p) + shift / self.length
        t = (
            np.mod(t, 1.0)
            if self.closed
            else np.clip(t, margin / self.length, 1 - margin / self.length)
        )
        return self.point(t)


@dataclass(frozen=True, eq=False)
class Line(Curve):
    """The straight segment from ``a`` to ``b``."""

    a: object
    b: object
    name: str = "line"
    straight: ClassVar[bool] = True

    def __post_init__(self) -> None:
        a, b = check_vector2("line start", self.a), check_vector2("line end", self.b)
        if np.hypot(*(b - a)) == 0:
            raise InputError("a line needs two different end points", "a")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "name", str(self.name))

    def point(self, t):
        return self.a + np.asarray(t, dtype=float)[:, None] * (self.b - self.a)

    def derivative(self, t):
        return np.broadcast_to(self.b - self.a, (len(t), 2)).copy()

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.b - self.a)))

    def spaced(self, h: float) -> np.ndarray:
        n = max(1, int(round(self.length / h)))
        t = np.arange(n)[:, None] / n
        return self.a + t * (self.b - self.a)

    def param(self, p):
        d = self.b - self.a
        return np.clip((np.asarray(p, dtype=float).reshape(-1, 2) - self.a) @ d / (d @ d), 0, 1)

    def slide(self, p, shift, margin):
        d = self.b - self.a
        length = self.length
        u = (np.asarray(p) - self.a) @ (d / length) + shift
        u = np.clip(u, margin, length - margin)
        return self.a + u[:, None] * (d / length)


@dataclass(frozen=True, eq=False)
class Arc(Curve):
    """Circular arc of ``center`` and ``radius`` from angle ``start`` to ``end``
    (degrees, counter-clockwise when ``end > start``); ``end = start + 360`` is a full
    circle."""

    center: object
    radius: float
    start_angle: float = 0.0
    end_angle: float = 360.0
    name: str = "arc"

    def __post_init__(self) -> None:
        c = check_vector2("arc center", self.center)
        r = check_positive("arc radius", self.radius)
        a0, a1 = check_real("arc start", self.start_angle), check_real("arc end", self.end_angle)
        if a0 == a1 or abs(a1 - a0) > 360.0:
            raise InputError(
                f"an arc sweeps between 0 and 360 degrees, got {a0} to {a1}", "end_angle"
            )
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "start_angle", a0)
        object.__setattr__(self, "end_angle", a1)
        object.__setattr__(self, "name", str(self.name))

    @property
    def _sweep(self) -> float:
        return np.radians(self.end_angle - self.start_angle)

    def point(self, t):
        ang = np.radians(self.start_angle) + np.asarray(t, dtype=float) * self._sweep
        return self.center + self.radius * np.c_[np.cos(ang), np.sin(ang)]

    def derivative(self, t):
        ang = np.radians(self.start_angle) + np.asarray(t, dtype=float) * self._sweep
        return self.radius * self._sweep * np.c_[-np.sin(ang), np.cos(ang)]

    @property
    def closed(self) -> bool:
        return abs(self.end_angle - self.start_angle) == 360.0

    @property
    def length(self) -> float:
        return float(self.radius * abs(self._sweep))

    def spaced(self, h: float) -> np.ndarray:
        if not self.closed:
            n = max(1, int(round(self.length / h)))
            return self.point(np.arange(n) / n)
        # a multiple of 4: nodes on the axes through the centre (symmetric loads)
        n = 4 * max(2, int(round(self.length / (4 * h))))
        ang = np.radians(self.start_angle) + np.sign(self._sweep) * 2 * np.pi * np.arange(n) / n
        return self.center + self.radius * np.c_[np.cos(ang), np.sin(ang)]

    def param(self, p):
        v = np.asarray(p, dtype=float).reshape(-1, 2) - self.center
        ang = np.degrees(np.arctan2(v[:, 1], v[:, 0]))
        rel = (ang - self.start_angle) / (self.end_angle - self.start_angle)
        sweep = abs(self.end_angle - self.start_angle) / 360.0
        rel = np.mod(rel, 1.0 / sweep)  # the same direction round, in [0, 360/sweep)
        if self.closed:
            return rel
        # outside the arc: the nearer end
        over = rel > 1.0
        past_end = (rel - 1.0) * sweep
        before_start = (1.0 / sweep - rel) * sweep
        return np.where(over, np.where(past_end < before_start, 1.0, 0.0), rel)

    def project(self, p):
        p = np.asarray(p, dtype=float).reshape(-1, 2)
        if self.closed:
            v = p - self.center
            return self.center + self.radius * v / np.hypot(v[:, 0], v[:, 1])[:, None]
        return self.point(self.param(p))

    def distance(self, p):
        p = np.asarray(p, dtype=float).reshape(-1, 2)
        if self.closed:
            return np.abs(np.hypot(*(p - self.center).T) - self.radius)
        return np.hypot(*(p - self.project(p)).T)

    def slide(self, p, shift, margin):
        if not self.closed:
            return super().slide(p, shift, margin)
        v = np.asarray(p) - self.center
        ang = np.arctan2(v[:, 1], v[:, 0]) + shift / self.radius
        return self.center + self.radius * np.c_[np.cos(ang), np.sin(ang)]


@dataclass(frozen=True, eq=False)
class EllipseArc(Curve):
    """Elliptic arc: semi-axes ``a`` (along the rotated x axis) and ``b``, axes turned by
    ``rotation``; from parametric angle ``start`` to ``end`` (degrees), the point at
    angle ``phi`` being ``center + R(rotation) (a cos phi, b sin phi)``."""

    center: object
    a: float
    b: float
    rotation: float = 0.0
    start_angle: float = 0.0
    end_angle: float = 360.0
    name: str = "ellipse"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check_vector2("ellipse center", self.center))
        object.__setattr__(self, "a", check_positive("ellipse a", self.a))
        object.__setattr__(self, "b", check_positive("ellipse b", self.b))
        object.__setattr__(self, "rotation", check_real("ellipse rotation", self.rotation))
        a0, a1 = (
            check_real("ellipse start", self.start_angle),
            check_real("ellipse end", self.end_angle),
        )
        if a0 == a1 or abs(a1 - a0) > 360.0:
            raise InputError(
                f"an elliptic arc sweeps between 0 and 360 degrees, got {a0} to {a1}", "end_angle"
            )
        object.__setattr__(self, "start_angle", a0)
        object.__setattr__(self, "end_angle", a1)
        object.__setattr__(self, "name", str(self.name))

    def _rot(self) -> np.ndarray:
        c, s = np.cos(np.radians(self.rotation)), np.sin(np.radians(self.rotation))
        return np.array([[c, -s], [s, c]])

    def _phi(self, t):
        return np.radians(
            self.start_angle + np.asarray(t, dtype=float) * (self.end_angle - self.start_angle)
        )

    def point(self, t):
        phi = self._phi(t)
        return self.center + np.c_[self.a * np.cos(phi), self.b * np.sin(phi)] @ self._rot().T

    def derivative(self, t):
        phi = self._phi(t)
        k = np.radians(self.end_angle - self.start_angle)
        return k * np.c_[-self.a * np.sin(phi), self.b * np.cos(phi)] @ self._rot().T

    @property
    def closed(self) -> bool:
        return abs(self.end_angle - self.start_angle) == 360.0
