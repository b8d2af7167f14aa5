"""The recovered stress of a linear solution (:mod:`dvstatic.stress.recovery`), with the
lattice's responses to uniform stress solved here: with the solution's own engine and
factorisation where it has one (three more back-substitutions after a direct solve),
AMG-CG otherwise."""

from __future__ import annotations

import logging
import time

import numpy as np

from ..lattice import VoronoiModel
from ..linalg import AUTO_DIRECT_MAX_DOF
from ..problem import constraints
from ..stress import recovery_of
from .linear import solve_linear
from .options import SolveOptions

log = logging.getLogger(__name__)

__all__ = ["recovered_stress", "RESPONSE_RTOL"]

#: relative tolerance of the AMG solves of the responses
RESPONSE_RTOL = 1e-10


def recovered_stress(
    model: VoronoiModel, u: np.ndarray, supports, loads, solver: str, problem=None
) -> np.ndarray:
    """The default stress (N, 2, 2) of a linear solution ``u`` (N, 2) of ``model``
    under ``supports`` and ``loads``, solved with ``solver`` (its engine is reused for
    the responses); ``problem``: the solve's resolved :class:`~dvstatic.problem.Problem`
    (its constrained dofs, not worked out again)."""
    mesh = model.mesh
    dofs = problem.dofs if problem is not None else constraints(mesh, supports)[0]
    fixed = np.zeros(2 * mesh.n_points, dtype=bool)
    fixed[dofs] = True
    rec = recovery_of(model, fixed)
    if rec.needs_responses:
        _solve_responses(rec, dofs, solver, supports)
    return rec.stress(u, loads)


def _solve_responses(rec, dofs: np.ndarray, solver: str, supports) -> None:
    t0 = time.perf_counter()
    kind = solver if solver in ("direct", "amg") else _auto(rec.model)
    opts = SolveOptions(rtol=RESPONSE_RTOL)  # the solve's own engine (same cache key)
    for material in rec.pending:
        model, states = rec.uniform_states(material)
        out = []
        for f, values in states:
            x, _ = solve_linear(model, kind, dofs, values[dofs], f, opts, supports)
            out.append(x.reshape(-1, 2))
        rec.set_responses(material, np.stack(out))
    log.info(
        "stress recovery: responses to uniform stress (%s) in %.2f s",
        kind,
        time.perf_counter() - t0,
    )


def _auto(model: VoronoiModel) -> str:
    return "direct" if model.n_dof <= AUTO_DIRECT_MAX_DOF else "amg"
