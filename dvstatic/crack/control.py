"""What a fracture analysis grows and what it holds: the reference problem (scaled by the
load factor), its control (force or displacement) and load measure, the held loads (at
full value in every state), and the strength keywords a criterion takes."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..problem import Problem
from ..problem.loads import nodal_forces
from .criteria import REGISTRY

__all__ = ["BALANCED", "reference", "held_problem", "criterion_parameters"]

#: loads whose resultants sum to less than this fraction of the sum of their sizes
#: balance each other (the load is then the force on one side)
BALANCED = 1e-2


def reference(model, problem: Problem):
    """Constrained dofs, prescribed values, forces and the control of the problem."""
    mesh = model.mesh
    dofs, values, f = problem.dofs, problem.values, problem.f
    loads = list(problem.loads)
    if np.any(values):
        return dofs, values, f, "displacement", _displacement_measure(dofs, values)
    if not np.any(f):
        raise InputError(
            "nothing loads the body: give loads or a non-zero prescribed displacement "
            "(Fix(..., y=-1e-3)); they are scaled by the load factor",
            "loads",
        )
    return dofs, values, f, "force", _load_measure(mesh, loads, model.t)


def _displacement_measure(dofs, values) -> float:
    """The control displacement per unit load factor: the largest spread of the
    prescribed values of one component (a fixed side and a moved side: the moved value;
    two sides moved apart by +-d/2, or to d and 2 d: d).

    Raises
    ------
    InputError
        If the prescribed values only translate the body (no spread).
    """
    spread = 0.0
    for c in (0, 1):
        v = values[dofs % 2 == c]
        if len(v):
            spread = max(spread, float(v.max() - v.min()))
    if not spread > 0:
        raise InputError(
            "the prescribed displacements only translate the body (every prescribed value "
            "of a component is the same): nothing deforms it; fix one side (0) and move "
            "the other",
            "supports",
        )
    return spread


def _load_measure(mesh, loads, thickness) -> float:
    """The load per unit load factor: the resultant of one side.

    A load object whose own resultant vanishes (a pressure in a hole) counts half its
    total nodal force; loads whose resultants balance each other to :data:`BALANCED`
    of their sum (two opposite point loads or strips on a disc, also on a mesh that is
    not quite symmetric) count half the sum of their resultants, the force on one side;
    otherwise the resultants add up (the supports react).
    """
    own, resultants = 0.0, []
    for load in loads:
        fk = nodal_forces(mesh, [load], thickness=thickness).reshape(-1, 2)
        r = fk.sum(axis=0)
        total = float(np.hypot(fk[:, 0], fk[:, 1]).sum())
        if np.hypot(*r) > 1e-6 * total:
            resultants.append(r)
        else:
            own += 0.5 * total
    if not resultants:
        return own
    r = np.array(resultants)
    size = float(np.hypot(r[:, 0], r[:, 1]).sum())
    balanced = np.hypot(*r.sum(axis=0)) <= BALANCED * size
    return own + (0.5 * size if balanced else size)


def criterion_parameters(criterion: str, **given) -> dict:
    """The given strength keywords of ``criterion``; a keyword another criterion takes
    is refused rather than ignored."""
    params = {k: v for k, v in given.items() if v is not None}
    wrong = sorted(set(params) - set(REGISTRY[criterion].parameters))
    if wrong:
        users = [n for n, c in REGISTRY.items() if wrong[0] in c.parameters]
        raise InputError(
            f"{wrong[0]} is a strength of criterion {users[0]!r}, not of {criterion!r}: "
            f"give criterion={users[0]!r} or leave {wrong[0]} out",
            wrong[0],
        )
    return params


def held_problem(model, held) -> Problem | None:
    """The held loads as a problem without supports (None: no held load).

    Raises
    ------
    TypeError
        A held item that is not a load (a support has no place among them).
    """
    if held is None or (isinstance(held, (list, tuple)) and not held):
        return None
    items = held if isinstance(held, (list, tuple)) else [held]
    for item in items:
        if type(item).__name__ == "Fix":
            raise TypeError(
                "held takes loads (Traction, Pressure, BodyForce, PointLoad), not a Fix: "
                "the supports go in `supports` (their prescribed values grow with the load "
                "factor)"
            )
    try:
        return Problem.build(model, None, list(items), restrained=False)
    except InputError as exc:
        raise InputError(f"held: {exc}", "held") from exc
    except TypeError as exc:
        raise TypeError(f"held: {exc}") from exc
