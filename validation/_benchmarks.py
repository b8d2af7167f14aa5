"""Classic plane benchmarks with closed-form or published reference values (used by
``convergence.py``).

Each :class:`Benchmark` makes its mesh for a target number of nodes, its supports and
loads, and gives the reference: an exact displacement field (``exact``) or a
fine-mesh P2 FE solution (``fe_reference``), and key values (a displacement or a
stress at a boundary point) with their reference values and sources.

* ``uniaxial``  paper exp. 3: unit square, rollers left and bottom, traction on the
  right (exact: homogeneous stress).
* ``beam``  paper exp. 2: 4 x 1 beam clamped at both ends under its own weight
  (reference: P2 FE, two uniform refinements of the lattice triangulation).
* ``cantilever``  Timoshenko & Goodier's end-loaded cantilever 4 x 1: parabolic shear
  on the free end, the exact displacement prescribed on the other (exact field;
  key value: tip deflection).
* ``lame``  thick-walled cylinder a = 1, b = 2 under internal pressure, quarter with
  symmetry rollers, plane strain (exact field; hoop stress at the bore).
* ``kirsch``  quarter of a 4a x 4a plate with a hole of radius a in uniaxial tension,
  the exact Kirsch tractions on the outer sides (exact field; sxx = 3 S at the hole's
  top).
* ``cook``  Cook's membrane (48 / 44 / 16, E = 70, nu = 1/3, plane strain, shear
  resultant 100 on the right side): tip deflection 32.30 (P4 on meshes refined at the
  clamped and the loaded edges; the published 32.20-32.28 are coarser), field
  reference by fine P2 FE.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

import dvstatic as dv

SQRT3_2 = np.sqrt(3.0) / 2.0


@dataclass
class KeyValue:
    """A scalar checked against a reference: ``where`` a point (a node of every mesh),
    ``what`` one of "uy" (displacement), "sxx", "syy" (stress), "hoop"."""

    name: str
    where: tuple[float, float]
    what: str
    reference: float
    source: str


@dataclass
class Benchmark:
    name: str
    E: float
    nu: float
    area: float
    make_mesh: Callable[..., dv.Mesh]  # (h, **mesh keywords) -> Mesh
    problem: Callable[[dv.Mesh], tuple[list, list]]
    exact: Callable[[np.ndarray], np.ndarray] | None = None
    keys: list[KeyValue] = field(default_factory=list)
    plane: str = "stress"
    fe_reference: Callable[[], object] | None = None
    #: a boundary part whose tangential stress is compared with ``stress_exact``
    stress_part: str | None = None
    stress_exact: Callable[[np.ndarray], np.ndarray] | None = None  # (m, 2) -> (m, 2, 2)

    def h_for(self, nodes: int) -> float:
        """Spacing for about ``nodes`` nodes."""
        return float(np.sqrt(self.area / (SQRT3_2 * nodes)))


# ------------------------------------------------------------------ uniaxial (exp. 3)
def uniaxial(nu: float = 0.2, E: float = 1e5) -> Benchmark:
    def problem(mesh):
        return [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)], [dv.Traction("right", (-1.0, 0.0))]

    return Benchmark(
        f"uniaxial (nu={nu:g})",
        E,
        nu,
        1.0,
        lambda h, **kw: dv.mesh.rectangle(1.0, 1.0, h, **kw),
        problem,
        exact=lambda p: np.c_[-p[:, 0] / E, nu * p[:, 1] / E],
    )


# ------------------------------------------------------------------ beam (exp. 2)
def beam() -> Benchmark:
    E, nu = 1e5, 0.2

    def problem(mesh):
        return [dv.Fix("left"), dv.Fix("right")], [dv.BodyForce((0.0, -1.0))]

    def reference():
        mesh = dv.mesh.rectangle(4.0, 1.0, 0.05, kind="lattice")
        return dv.fem.solve(mesh, E, nu, *problem(mesh), order=2, refine=2)

    return Benchmark(
        "beam (exp. 2)",
        E,
        nu,
        4.0,
        lambda h, **kw: dv.mesh.rectangle(4.0, 1.0, h, **kw),
        problem,
        fe_reference=reference,
    )


# ------------------------------------------------------------------ cantilever
def cantilever_exact(p, E, nu, L=4.0, D=1.0, P=1.0):
    """Timoshenko & Goodier: free end x = 0 under a parabolic shear of resultant P
    (upwards), clamped end x = L; the mesh spans 0 <= y <= D."""
    x, y = p[:, 0], p[:, 1] - D / 2
    inertia = D**3 / 12
    G = E / (2 * (1 + nu))
    u = (
        -P * x**2 * y / (2 * E * inertia)
        - nu * P * y**3 / (6 * E * inertia)
        + P * y**3 / (6 * inertia * G)
        + (P * L**2 / (2 * E * inertia) - P * D**2 / (8 * inertia * G)) * y
    )
    v = (
        nu * P * x * y**2 / (2 * E * inertia)
        + P * x**3 / (6 * E * inertia)
        - P * L**2 * x / (2 * E * inertia)
        + P * L**3 / (3 * E * inertia)
    )
    return np.c_[u, v]


def cantilever(nu: float = 0.3, E: float = 1e3) -> Benchmark:
    L, D = 4.0, 1.0
    inertia = D**3 / 12

    def exact(p):
        return cantilever_exact(p, E, nu, L, D)

    def problem(mesh):
        def shear(x):
            y = x[:, 1] - D / 2
            return np.c_[np.zeros(len(y)), (D**2 / 4 - y**2) / (2 * inertia)]

        return [dv.Fix("right", x=lambda x: exact(x)[:, 0], y=lambda x: exact(x)[:, 1])], [
            dv.Traction("left", shear)
        ]

    return Benchmark(
        f"cantilever (nu={nu:g})",
        E,
        nu,
        L * D,
        lambda h, **kw: dv.mesh.rectangle(L, D, h, **kw),
        problem,
        exact=exact,
        keys=[
            KeyValue(
                "tip deflection",
                (0.0, 0.0),
                "uy",
                float(exact(np.zeros((1, 2)))[0, 1]),
                "Timoshenko & Goodier (exact)",
            )
        ],
    )


# ------------------------------------------------------------------ Lame cylinder
def lame(nu: float = 0.3, E: float = 1e3, a: float = 1.0, b: float = 2.0, p: float = 1.0):
    Es, nus = E / (1 - nu**2), nu / (1 - nu)  # plane strain = plane stress with these

    def exact(x):
        r = np.hypot(x[:, 0], x[:, 1])
        A = p * a**2 / (b**2 - a**2)
        B = p * a**2 * b**2 / (b**2 - a**2)
        ur = ((1 - nus) * A * r + (1 + nus) * B / r) / Es
        return x * (ur / r)[:, None]

    def make(h, **kw):
        path = dv.domain.Path(
            (
                dv.domain.Line((a, 0.0), (b, 0.0), "bottom"),
                dv.domain.Arc((0.0, 0.0), b, 0.0, 90.0, "outer"),
                dv.domain.Line((0.0, b), (0.0, a), "left"),
                dv.domain.Arc((0.0, 0.0), a, 90.0, 0.0, "bore"),
            )
        )
        return dv.mesh.generate(dv.domain.Domain(path), h, **kw)

    def problem(mesh):
        return [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)], [dv.Pressure("bore", p)]

    hoop = p * (b**2 + a**2) / (b**2 - a**2)

    def stress(x):
        r2 = np.sum(x**2, axis=1)
        A, B = p * a**2 / (b**2 - a**2), p * a**2 * b**2 / (b**2 - a**2)
        srr, stt = A - B / r2, A + B / r2
        n = x / np.sqrt(r2)[:, None]
        t = np.c_[-n[:, 1], n[:, 0]]
        return srr[:, None, None] * np.einsum("mi,mj->mij", n, n) + stt[:, None, None] * (
            np.einsum("mi,mj->mij", t, t)
        )

    return Benchmark(
        f"Lame cylinder, plane strain (nu={nu:g})",
        E,
        nu,
        np.pi * (b**2 - a**2) / 4,
        make,
        problem,
        exact=exact,
        keys=[KeyValue("hoop stress at the bore", (0.0, a), "sxx", hoop, "Lame (exact)")],
        plane="strain",
        stress_part="bore",
        stress_exact=stress,
    )


# ------------------------------------------------------------------ Kirsch plate
def kirsch(nu: float = 0.3, E: float = 1e3, a: float = 1.0, L: float = 4.0, S: float = 1.0):
    mu = E / (2 * (1 + nu))
    kap = (3 - nu) / (1 + nu)  # plane stress

    def polar(x):
        r = np.hypot(x[:, 0], x[:, 1])
        return r, np.arctan2(x[:, 1], x[:, 0])

    def exact(x):
        r, th = polar(x)
        c2, s2 = np.cos(2 * th), np.sin(2 * th)
        ur = (
            S
            / (8 * mu)
            * (
                r * (kap - 1)
                + 2 * a**2 / r
                + (2 * r + 2 * (kap + 1) * a**2 / r - 2 * a**4 / r**3) * c2
            )
        )
        ut = -S / (8 * mu) * (2 * r + 2 * (kap - 1) * a**2 / r + 2 * a**4 / r**3) * s2
        c, s = np.cos(th), np.sin(th)
        return np.c_[ur * c - ut * s, ur * s + ut * c]

    def stress(x):
        r, th = polar(x)
        c2, s2 = np.cos(2 * th), np.sin(2 * th)
        q = a**2 / r**2
        srr = S / 2 * (1 - q) + S / 2 * (1 - 4 * q + 3 * q**2) * c2
        stt = S / 2 * (1 + q) - S / 2 * (1 + 3 * q**2) * c2
        srt = -S / 2 * (1 + 2 * q - 3 * q**2) * s2
        c, s = np.cos(th), np.sin(th)
        sxx = srr * c * c + stt * s * s - 2 * srt * s * c
        syy = srr * s * s + stt * c * c + 2 * srt * s * c
        sxy = (srr - stt) * s * c + srt * (c * c - s * s)
        return sxx, syy, sxy

    def make(h, **kw):
        path = dv.domain.Path(
            (
                dv.domain.Line((a, 0.0), (L, 0.0), "bottom"),
                dv.domain.Line((L, 0.0), (L, L), "right"),
                dv.domain.Line((L, L), (0.0, L), "top"),
                dv.domain.Line((0.0, L), (0.0, a), "left"),
                dv.domain.Arc((0.0, 0.0), a, 90.0, 0.0, "hole"),
            )
        )
        return dv.mesh.generate(dv.domain.Domain(path), h, **kw)

    def right(x):  # outward normal +x
        sxx, _, sxy = stress(x)
        return np.c_[sxx, sxy]

    def top(x):  # outward normal +y
        _, syy, sxy = stress(x)
        return np.c_[sxy, syy]

    def problem(mesh):
        return [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)], [
            dv.Traction("right", right),
            dv.Traction("top", top),
        ]

    return Benchmark(
        f"Kirsch plate with a hole (nu={nu:g})",
        E,
        nu,
        L * L - np.pi * a * a / 4,
        make,
        problem,
        exact=exact,
        keys=[KeyValue("sxx at the hole's top", (0.0, a), "sxx", 3.0 * S, "Kirsch (exact)")],
        stress_part="hole",
        stress_exact=lambda x: np.stack(
            [
                np.stack([stress(x)[0], stress(x)[2]], -1),
                np.stack([stress(x)[2], stress(x)[1]], -1),
            ],
            -2,
        ),
    )


# ------------------------------------------------------------------ Cook's membrane
#: tip deflection of Cook's membrane in plane strain (E = 70, nu = 1/3, shear
#: resultant 100 on the right side), computed here with P4 (``dv.fem.solve(order=4)``):
#: 32.2723 / 32.2859 / 32.2938 / 32.2965 on uniform meshes h = 2 / 1 / 0.5 / 0.25, and
#: 32.2989 / 32.2998 on meshes refined to h = 0.1 / 0.05 along the clamped and the
#: loaded edges (8,741 / 33,576 nodes), whose corners (the tip is one) converge slowly.
#: The values usually quoted, CalculiX 32.27, Elmer 32.28, Code_Aster 32.20 (CoFEA,
#: "very fine quadratic", tabulated by the solids4foam tutorial), are 0.1-0.3 % low.
COOK_TIP = 32.30


def cook() -> Benchmark:
    """Cook's membrane in plane strain. (The often-quoted 23.96 for E = 1, nu = 1/3 is
    not the plane-stress value of this set-up: P2 FE converges to 25.17 there, as does a
    direct scikit-fem computation. In plane strain: :data:`COOK_TIP`.)"""
    E, nu = 70.0, 1.0 / 3.0
    corners = [(0.0, 0.0), (48.0, 44.0), (48.0, 60.0), (0.0, 44.0)]

    def make(h, **kw):
        return dv.mesh.polygon(corners, h, names=["bottom", "right", "top", "left"], **kw)

    def problem(mesh):
        return [dv.Fix("left")], [dv.Traction("right", (0.0, 100.0 / 16.0))]

    def reference():
        mesh = make(1.0, kind="lattice")
        return dv.fem.solve(mesh, E, nu, *problem(mesh), order=2, refine=2, plane="strain")

    return Benchmark(
        "Cook's membrane, plane strain",
        E,
        nu,
        0.5 * (44.0 + 16.0) * 48.0,
        make,
        problem,
        keys=[
            KeyValue(
                "tip deflection",
                (48.0, 60.0),
                "uy",
                COOK_TIP,
                "P4 on meshes refined at the clamped and loaded edges (CalculiX 32.27 / "
                "Elmer 32.28 / Code_Aster 32.20 in the CoFEA comparison are coarser)",
            )
        ],
        plane="strain",
        fe_reference=reference,
    )


# ------------------------------------------------------------------ NAFEMS LE1
#: NAFEMS LE1 (elliptic membrane): syy at point D (2, 0), the published target
LE1_SYY_D = 92.7


def le1() -> Benchmark:
    """NAFEMS LE1: a quarter of an elliptic membrane between the ellipses
    (x/2)^2 + y^2 = 1 and (x/3.25)^2 + (y/2.75)^2 = 1, outward pressure 10 (MPa) on the
    outer edge, symmetry rollers on the axes, E = 210e3, nu = 0.3, plane stress;
    target syy = 92.7 at D = (2, 0) (NAFEMS, "The standard NAFEMS benchmarks", 1990).
    The field reference is fine P2 FE."""
    E, nu = 210e3, 0.3

    def make(h, **kw):
        path = dv.domain.Path(
            (
                dv.domain.Line((2.0, 0.0), (3.25, 0.0), "bottom"),
                dv.domain.EllipseArc((0.0, 0.0), 3.25, 2.75, 0.0, 0.0, 90.0, "outer"),
                dv.domain.Line((0.0, 2.75), (0.0, 1.0), "left"),
                dv.domain.EllipseArc((0.0, 0.0), 2.0, 1.0, 0.0, 90.0, 0.0, "inner"),
            )
        )
        return dv.mesh.generate(dv.domain.Domain(path), h, **kw)

    def problem(mesh):
        return [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)], [dv.Pressure("outer", -10.0)]

    def reference():
        mesh = make(0.05, kind="lattice")
        return dv.fem.solve(mesh, E, nu, *problem(mesh), order=2, refine=1)

    area = np.pi * (3.25 * 2.75 - 2.0 * 1.0) / 4
    return Benchmark(
        "NAFEMS LE1 (elliptic membrane)",
        E,
        nu,
        area,
        make,
        problem,
        keys=[KeyValue("syy at D", (2.0, 0.0), "syy", LE1_SYY_D, "NAFEMS LE1 target")],
        fe_reference=reference,
    )
