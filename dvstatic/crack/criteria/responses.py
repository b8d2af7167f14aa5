"""What the criteria share: material properties per bond, and every bond's response to
the three unit uniform stresses (its tension and its patch stress), from which the
criteria make their strengths (docs/fracture.md)."""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from ...errors import InputError, UnknownRegionError
from ...lattice import VoronoiModel
from ...linalg import ConstrainedSystem, DirectSolver
from ...mesh import mesh_dof_order
from ..strength import uniform_stress_loads

log = logging.getLogger(__name__)

__all__ = ["positive", "per_bond", "voigt", "responses", "Factorised"]


def positive(value, name: str) -> None:
    """Refuse ``value`` unless it is a finite number > 0 (numpy scalars accepted)."""
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)) or float(value) <= 0:
        raise InputError(f"{name} must be a finite number > 0, got {value!r}", name)


def per_bond(model: VoronoiModel, value, name: str, check=None) -> np.ndarray:
    """A material property per bond: a number, or {region: number} over a default
    (``None`` key or ``"default"``); a bond between regions takes the smaller value.
    ``check(value, name)`` refuses a bad number (default: :func:`positive`)."""
    check = check or positive
    mesh = model.mesh
    if isinstance(value, Mapping):
        values = dict(value)
        default = values.pop(None, values.pop("default", None))
        if default is None:
            raise InputError(f"{name} as a mapping needs a 'default' value", name)
        check(default, name)
        tri = np.full(mesh.n_triangles, float(default))
        for region, v in values.items():
            if region not in mesh.regions:
                raise UnknownRegionError(
                    f"{name}: unknown region {region!r}; the mesh has {sorted(mesh.regions)}",
                    name,
                    region,
                )
            check(v, f"{name}[{region!r}]")
            tri[mesh.regions[region]] = float(v)
    else:
        check(value, name)
        tri = np.full(mesh.n_triangles, float(value))
    out = np.full(mesh.n_bonds, np.inf)
    np.minimum.at(out, mesh.topology.tri_bonds.ravel(), np.repeat(tri, 3))
    return out


def voigt(s: np.ndarray) -> np.ndarray:
    """(xx, yy, xy) of stresses (n, 2, 2)."""
    return np.stack([s[:, 0, 0], s[:, 1, 1], s[:, 0, 1]], axis=1)


class Factorised(NamedTuple):
    """The undamaged constrained stiffness the responses solved with, factorised (the
    event loop starts from it when its prescribed dofs are the same)."""

    dofs: np.ndarray
    K: object  #: (2N, 2N) BSR
    system: ConstrainedSystem
    engine: DirectSolver


def _uniform_response(model, length, area, dofs=None, sp_=None):
    """Tensions (3 x (n_bonds,)) and patch stresses (3 x (stress, covered)) of ``model``
    under the unit uniform stresses xx, yy, xy: boundary tractions, and at the problem's
    prescribed ``dofs`` the uniform state's displacement (so that a bond at a support
    or a grip answers as it does in the problem: the stress at a support is the
    stress); without ``dofs``, three pinned dofs. ``sp_``: the model's split stiffness,
    if made already. Also returns the :class:`Factorised` system."""
    from ...lattice.damage import split

    mesh = model.mesh
    sp_ = split(model) if sp_ is None else sp_
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
    K = sp_.stiffness(mesh, w, g)
    system = ConstrainedSystem(K, dofs)
    engine = DirectSolver(system.A, order=mesh_dof_order(mesh))
    loads = uniform_stress_loads(mesh, model.t)
    us = [engine.apply(system.rhs(f, v)) for f, v in zip(loads, affine, strict=True)]
    if np.any([np.any(v) for v in affine]):
        us = _unit_mean_stress(mesh, K, us, model.t)
    forces = [sp_.forces(u, w, g) for u in us]
    tens = [sp_.tension(u, w, g, f) for u, f in zip(us, forces, strict=True)]
    patches = [
        sp_.patch_stress(u, w, g, length, area, None, f) for u, f in zip(us, forces, strict=True)
    ]
    return tens, patches, Factorised(np.asarray(dofs), K, system, engine)


def _unit_mean_stress(mesh, K, us, thickness):
    """The three states recombined so that their mean stresses are exactly the unit
    stresses xx, yy, xy. A state with prescribed displacements has the stress the
    lattice's stiffness gives the prescribed strain, which differs from E times it by
    the lattice's modulus error on this mesh (between platens every bond sees it, and
    so do the reactions, which measure the load); the mean stress over the body is
    what equilibrium says, ``sum_i x_i (x) F_i / (A t)`` with ``F = K u`` (loads and
    reactions), so the states are scaled to it and a bond fails at the load the
    reactions measure."""
    x = mesh.points
    area = float(mesh.triangle_areas.sum()) * thickness
    cols = []
    for u in us:
        f = (K @ u).reshape(-1, 2)
        s = np.einsum("ni,nj->ij", x - x.mean(axis=0), f) / area
        s = 0.5 * (s + s.T)
        cols.append([s[0, 0], s[1, 1], s[0, 1]])
    m = np.linalg.inv(np.array(cols).T)  # state'_k = sum_j state_j m[j, k]
    log.debug("uniform-stress responses: mean stresses %s", np.array(cols).round(6).tolist())
    return [sum(m[j, k] * us[j] for j in range(3)) for k in range(3)]


def _unit_strains(E: float, nu: float) -> list[np.ndarray]:
    """The strains (2, 2) of the unit stresses xx, yy, xy under the in-plane law."""
    return [
        np.array([[1.0, 0.0], [0.0, -nu]]) / E,
        np.array([[-nu, 0.0], [0.0, 1.0]]) / E,
        np.array([[0.0, 1.0 + nu], [1.0 + nu, 0.0]]) / E,
    ]


def responses(model, length, area, dofs=None, sp_=None):
    """The uniform-stress response of every bond: tensions (3 x (n_bonds,)), patch
    stresses (3 x (stress, covered)) and the :class:`Factorised` system (None with
    several materials). With several materials a uniform traction does not give a
    uniform stress, so each material's bonds take the response of the mesh made entirely
    of that material (a bond between materials takes the one of its first triangle).
    ``sp_``: the model's split stiffness, if made already."""
    import dataclasses

    if len(model.all_materials) == 1:
        return _uniform_response(model, length, area, dofs, sp_)
    from ..pieces import bond_triangles

    mat = model.material_of_triangle[bond_triangles(model.mesh)[:, 0]]
    tens = [np.zeros(model.mesh.n_bonds) for _ in range(3)]
    patches = [
        (np.zeros((model.mesh.n_bonds, 2, 2)), np.zeros(model.mesh.n_bonds, bool)) for _ in range(3)
    ]
    for k, material in enumerate(model.all_materials):
        sel = mat == k
        if not sel.any():
            continue
        # that material's own micro-parameters (as the stress recovery's companions
        # take them; a mesh calibrated class by class calibrates them afresh)
        cal = "relaxed" if model.micro_field is not None else model.micros[k]
        alone = dataclasses.replace(
            model, E=material.E, nu=material.nu, materials=None, calibration=cal
        )
        alone.share_calibration_flags(model)
        t_k, p_k, _ = _uniform_response(alone, length, area, dofs)
        for c in range(3):
            tens[c][sel] = t_k[c][sel]
            patches[c][0][sel] = p_k[c][0][sel]
            patches[c][1][sel] = p_k[c][1][sel]
    return tens, patches, None
