"""What an intact bond compares with its strength (the breaking criterion), and the
bond strengths derived from the material's tensile strength (docs/fracture.md)."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping

import numpy as np

from ..errors import InputError, UnknownRegionError
from ..lattice import VoronoiModel
from ..linalg import ConstrainedSystem, DirectSolver
from ..mesh import mesh_dof_order
from .strength import bond_strength, principal_response, uniform_stress_loads, weibull_factors

__all__ = ["CRITERIA", "Measure", "strengths", "per_bond", "positive"]

#: breaking criteria of intact bonds
CRITERIA = ("stress", "tension")


def positive(value, name: str) -> None:
    """Refuse ``value`` unless it is a finite number > 0 (numpy scalars accepted)."""
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)) or float(value) <= 0:
        raise InputError(f"{name} must be a finite number > 0, got {value!r}", name)


def per_bond(model: VoronoiModel, value, name: str) -> np.ndarray:
    """A material property per bond: a number, or {region: number} over a default
    (``None`` key or ``"default"``); a bond between regions takes the smaller value."""
    mesh = model.mesh
    if isinstance(value, Mapping):
        values = dict(value)
        default = values.pop(None, values.pop("default", None))
        if default is None:
            raise InputError(f"{name} as a mapping needs a 'default' value", name)
        positive(default, name)
        tri = np.full(mesh.n_triangles, float(default))
        for region, v in values.items():
            if region not in mesh.regions:
                raise UnknownRegionError(
                    f"{name}: unknown region {region!r}; the mesh has {sorted(mesh.regions)}",
                    name,
                    region,
                )
            positive(v, f"{name}[{region!r}]")
            tri[mesh.regions[region]] = float(v)
    else:
        positive(value, name)
        tri = np.full(mesh.n_triangles, float(value))
    out = np.full(mesh.n_bonds, np.inf)
    np.minimum.at(out, mesh.topology.tri_bonds.ravel(), np.repeat(tri, 3))
    return out


def _voigt(s: np.ndarray) -> np.ndarray:
    """(xx, yy, xy) of stresses (n, 2, 2)."""
    return np.stack([s[:, 0, 0], s[:, 1, 1], s[:, 0, 1]], axis=1)


class Measure:
    """The breaking criterion: per unit load factor, what every intact bond compares
    with its strength.

    ``"tension"``: the bond's tension ``T_e``.

    ``"stress"`` (a Rankine criterion on the bond's face): away from damage,
    ``H_nn sigma_nn``, the normal stress across the face times the bond's tension per
    unit normal stress ``H_nn``. ``sigma`` is the mean stress of the triangles at the
    bond's two end nodes, corrected by the inverse of that patch's response to uniform
    stress (so that it is exact under any uniform stress). Next to damage (in a damaged
    triangle), the bond's own tension without the part that stress along its face
    causes, ``T_e - (H_e : sigma - H_nn sigma_nn)``: the tension resolves
    the stress concentration at a crack tip that a patch mean would smear, and damaged
    triangles are left out of ``sigma`` so that the crack does not shield the bonds
    ahead of it. Under uniform stress both are ``H_nn sigma_nn``. Slivers whose tension
    hardly follows the normal stress (``H_nn < lambda_max(H_e) / 4``) use their tension.
    """

    def __init__(self, model, sp_, criterion: str):
        self.sp, self.criterion = sp_, criterion
        geo = model.geometry
        self.length = geo.tri_l
        self.area = geo.tri_area * model.t
        self.n = geo.direction
        self.bonds = model.mesh.topology.bonds
        self.h = None  # (n_bonds, 3): tension per unit xx, yy and xy stress

    def set_response(self, h: np.ndarray, patches) -> None:
        """Tensions (n_bonds, 3) and patch stresses (3 x (stress, covered)) under the unit
        uniform stresses xx, yy, xy."""
        self.h = h
        lam = principal_response([h[:, 0], h[:, 1], h[:, 2]])
        p = np.stack([_voigt(s) for s, _ in patches], axis=2)  # (xx, yy, xy) -> patch
        ok = np.linalg.cond(p) < 1e3
        self.unbias = np.broadcast_to(np.eye(3), p.shape).copy()
        self.unbias[ok] = np.linalg.inv(p[ok])
        #: slivers, and bonds whose patch is degenerate, use their tension
        self.use_tension = (self.h_nn < 0.25 * lam) | ~ok | ~patches[0][1]

    @property
    def h_nn(self) -> np.ndarray:
        n, h = self.n, self.h
        return h[:, 0] * n[:, 0] ** 2 + h[:, 1] * n[:, 1] ** 2 + h[:, 2] * n[:, 0] * n[:, 1]

    def __call__(self, x, w, g, intact=None) -> np.ndarray:
        f = self.sp.forces(x, w, g)
        t = self.sp.tension(x, w, g, f)
        if self.criterion == "tension":
            return t
        s, covered = self.sp.patch_stress(x, w, g, self.length, self.area, intact, f)
        v = np.einsum("eij,ej->ei", self.unbias, _voigt(s))
        n = self.n
        normal = self.h_nn * (
            v[:, 0] * n[:, 0] ** 2 + v[:, 1] * n[:, 1] ** 2 + 2 * v[:, 2] * n[:, 0] * n[:, 1]
        )
        if intact is None or intact.all():
            return np.where(covered & ~self.use_tension, normal, t)
        h = self.h
        along = h[:, 0] * v[:, 0] + h[:, 1] * v[:, 1] + h[:, 2] * v[:, 2] - normal
        m = np.where(self._near_damage(intact), t - along, normal)
        return np.where(covered & ~self.use_tension, m, t)

    def _near_damage(self, intact: np.ndarray) -> np.ndarray:
        """Bonds of a damaged triangle (the damaged bond's neighbours), (n_bonds,) bool."""
        hit = np.zeros(len(self.bonds), dtype=bool)
        hit[self.sp.tri_bonds[intact < 1].ravel()] = True
        return hit

    def elongation(self, x) -> np.ndarray:
        u = x.reshape(-1, 2)
        return np.einsum("ei,ei->e", self.n, u[self.bonds[:, 1]] - u[self.bonds[:, 0]])


def _uniform_response(model, length, area, dofs=None):
    """Tensions (3 x (n_bonds,)) and patch stresses (3 x (stress, covered)) of ``model``
    under the unit uniform stresses xx, yy, xy: boundary tractions, and at the problem's
    prescribed ``dofs`` the uniform state's displacement (so that a bond at a support
    or a grip answers as it does in the problem: the stress at a support is the
    stress); without ``dofs``, three pinned dofs."""
    from ..lattice.damage import split

    mesh = model.mesh
    sp_ = split(model)
    w, g = sp_.factors(np.ones(mesh.n_bonds))
    x = mesh.points
    if dofs is None:
        p1 = int(np.argmax(np.hypot(*(x - x[0]).T)))
        dd = x[p1] - x[0]
        dofs = np.array(sorted([0, 1, 2 * p1 + (1 if abs(dd[0]) >= abs(dd[1]) else 0)]))
        affine = [np.zeros(3)] * 3
    else:
        E, nu = model.material.in_plane
        affine = [(x @ strain.T).reshape(-1)[dofs] for strain in _unit_strains(E, nu)]
    system = ConstrainedSystem(sp_.stiffness(mesh, w, g), dofs)
    engine = DirectSolver(system.A, order=mesh_dof_order(mesh))
    loads = uniform_stress_loads(mesh, model.t)
    us = [engine.apply(system.rhs(f, v)) for f, v in zip(loads, affine, strict=True)]
    forces = [sp_.forces(u, w, g) for u in us]
    tens = [sp_.tension(u, w, g, f) for u, f in zip(us, forces, strict=True)]
    patches = [
        sp_.patch_stress(u, w, g, length, area, None, f) for u, f in zip(us, forces, strict=True)
    ]
    return tens, patches


def _unit_strains(E: float, nu: float) -> list[np.ndarray]:
    """The strains (2, 2) of the unit stresses xx, yy, xy under the in-plane law."""
    return [
        np.array([[1.0, 0.0], [0.0, -nu]]) / E,
        np.array([[-nu, 0.0], [0.0, 1.0]]) / E,
        np.array([[0.0, 1.0 + nu], [1.0 + nu, 0.0]]) / E,
    ]


def _responses(model, measure, dofs=None):
    """The uniform-stress response of every bond. With several materials a uniform
    traction does not give a uniform stress, so each material's bonds take the response
    of the mesh made entirely of that material (a bond between materials takes the one
    of its first triangle)."""
    import dataclasses

    if len(model.all_materials) == 1:
        return _uniform_response(model, measure.length, measure.area, dofs)
    from .pieces import bond_triangles

    mat = model.material_of_triangle[bond_triangles(model.mesh)[:, 0]]
    tens = [np.zeros(model.mesh.n_bonds) for _ in range(3)]
    patches = [
        (np.zeros((model.mesh.n_bonds, 2, 2)), np.zeros(model.mesh.n_bonds, bool)) for _ in range(3)
    ]
    for k, material in enumerate(model.all_materials):
        sel = mat == k
        if not sel.any():
            continue
        alone = dataclasses.replace(model, E=material.E, nu=material.nu, materials=None)
        t_k, p_k = _uniform_response(alone, measure.length, measure.area, dofs)
        for c in range(3):
            tens[c][sel] = t_k[c][sel]
            patches[c][0][sel] = p_k[c][0][sel]
            patches[c][1][sel] = p_k[c][1][sel]
    return tens, patches


def strengths(model, measure, ft, weibull, timings, dofs=None):
    """First-crack strength of every bond in the units of the criterion, and its
    tension-based strength (see :mod:`dvstatic.crack.strength`); ``dofs``: the
    problem's prescribed dofs (the responses hold them at the uniform state)."""
    t0 = time.perf_counter()
    mesh = model.mesh
    tens, patches = _responses(model, measure, dofs)
    measure.set_response(np.stack(tens, axis=1), patches)
    factors = None
    if weibull is not None:
        factors = weibull_factors(mesh.points[mesh.topology.bonds].mean(axis=1), weibull)
    ftb = per_bond(model, ft, "ft")
    s_t = bond_strength(principal_response(tens), ftb, factors)
    s = s_t
    if measure.criterion == "stress":
        scale = ftb * measure.h_nn * (1.0 if factors is None else factors)
        s = np.where(measure.use_tension, s_t, scale)
    timings["strength"] = time.perf_counter() - t0
    return s, s_t
