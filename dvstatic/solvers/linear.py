"""The linear solve ``K u = f`` on one process: direct (SuperLU) or AMG-CG, with the
factorisation / hierarchy cached per model and the stability check.

The cache keeps the last engine of each model, keyed by solver, constrained dofs and
the stability option: new load cases or prescribed values with the same supports reuse
it (``info.reused``). :func:`dvstatic.clear_caches` empties it.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from .._cache import PerObject
from ..errors import ConvergenceError, SingularError, UnstableError
from ..lattice import VoronoiModel
from ..linalg import AMGSolver, ConstrainedSystem, DirectSolver, rigid_modes
from ..mesh import mesh_dof_order
from .info import SolveInfo, StabilityCheck
from .stability import CHECK_MAX_DOF, stability

log = logging.getLogger(__name__)

__all__ = ["LinearResult", "solve_linear", "unstable_message", "BACKWARD_LIMIT"]

#: the refusal message includes the admissible nu range up to this many dofs
RANGE_IN_MESSAGE_MAX_DOF = 20_000
#: Largest normwise backward error accepted from a direct solve whose residual relative
#: to the load is above 1e-8 (ill-conditioned meshes with slivers): about 500 eps.
BACKWARD_LIMIT = 1e-13

#: the last (system, engine, stability check) of every model, by its key
_ENGINES = PerObject("factorisations", lambda model: {})


@dataclass(frozen=True)
class LinearResult:
    """What :func:`solve_linear` returns besides the solution."""

    iterations: int
    residuals: tuple[float, ...]
    residual: float
    backward_error: float | None
    stability: StabilityCheck
    reused: bool
    setup_seconds: float
    solve_seconds: float


def _engine(model: VoronoiModel, kind: str, dofs, check_stability: bool, supports):
    """Constrained system, factorisation / AMG hierarchy and stability check (cached)."""
    key = (kind, dofs.tobytes(), bool(check_stability))
    cache = _ENGINES(model)
    if key in cache:
        return (*cache[key], True)
    K = model.stiffness("bsr")
    system = ConstrainedSystem(K, dofs)
    try:
        if kind == "direct":
            engine = DirectSolver(system.A, order=mesh_dof_order(model.mesh))
        else:
            engine = AMGSolver(system.A, rigid_modes(model.mesh.points))
    except SingularError as exc:
        raise SingularError(str(exc), SolveInfo(kind, n_dof=K.shape[0])) from None
    stab = StabilityCheck()
    if check_stability:
        stab = _check(model, kind, system, engine, supports)
    cache.clear()
    cache[key] = (system, engine, stab)
    return system, engine, stab, False


def _check(model, kind, system, engine, supports) -> StabilityCheck:
    """Inertia of the factorisation (direct), of one extra factorisation (AMG up to
    CHECK_MAX_DOF dofs), or CG's curvature test above; raises if unstable."""
    t0 = time.perf_counter()
    if kind == "direct":
        neg = engine.negative_pivots
    elif system.A.shape[0] <= CHECK_MAX_DOF:
        neg = DirectSolver(system.A, order=mesh_dof_order(model.mesh)).negative_pivots
    else:
        return StabilityCheck(False, "cg-curvature", None, time.perf_counter() - t0)
    stab = StabilityCheck(neg is not None, "ldl-inertia", neg, time.perf_counter() - t0)
    if neg:
        raise UnstableError(
            unstable_message(model, neg, supports),
            SolveInfo(kind, stability=stab, n_dof=system.A.shape[0]),
            negative_eigenvalues=neg,
        )
    return stab


def solve_linear(model: VoronoiModel, kind: str, dofs, values, f, opts, supports):
    """Solve the constrained linear system with ``kind`` ("direct" or "amg").

    Returns
    -------
    x : ndarray, shape (2N,)
    result : LinearResult

    Raises
    ------
    UnstableError
        The stiffness is not positive definite.
    SingularError
        A direct solve left a large residual (singular or badly conditioned system).
    ConvergenceError
        AMG-CG did not reach its tolerance (``state``: the last iterate).
    """
    t0 = time.perf_counter()
    system, engine, stab, reused = _engine(model, kind, dofs, opts.check_stability, supports)
    b = system.rhs(f, values)
    t1 = time.perf_counter()
    if kind == "direct":
        x, rec = engine.solve(b)
    else:
        x, rec = engine.solve(b, rtol=opts.rtol, maxiter=opts.linear_maxiter())
    t2 = time.perf_counter()
    if rec.indefinite:
        raise UnstableError(
            unstable_message(model, None, supports),
            SolveInfo(kind, stability=stab, iterations=rec.iterations),
        )
    residual = rec.residuals[-1]
    backward = None if np.isnan(rec.backward_error) else rec.backward_error
    result = LinearResult(
        rec.iterations,
        tuple(rec.residuals),
        residual,
        backward,
        stab,
        reused,
        t1 - t0,
        t2 - t1,
    )
    _accept(kind, x, result, opts)
    return x, result


def _accept(kind: str, x: np.ndarray, result: LinearResult, opts) -> None:
    """Raise unless the solve reached its tolerance.

    A direct solve is accepted at the rounding floor too: with slivers the internal
    forces are ~(R/l) times the load and cancel, so |r| / |f| cannot reach 1e-8 while
    the normwise backward error |r| / (|K| |u| + |f|) is still at machine level.
    """
    limit = 1e-8 if kind == "direct" else max(10 * opts.rtol, 1e-14)
    backward = result.backward_error
    at_floor = kind == "direct" and backward is not None and backward <= BACKWARD_LIMIT
    finite = bool(np.all(np.isfinite(x)))
    if finite and (result.residual <= limit or at_floor):
        return
    reason = "a non-finite result" if not finite else f"relative residual {result.residual:.3e}"
    message = (
        f"{kind} solve failed with {reason} (limit {limit:.1e}) after {result.iterations} "
        "iteration(s): the system is singular or badly conditioned (lattice mechanism or "
        "unstable micro-parameters)"
    )
    info = SolveInfo(
        kind,
        iterations=result.iterations,
        residuals=result.residuals,
        residual=result.residual,
        stability=result.stability,
        backward_error=result.backward_error,
    )
    if kind == "amg" and finite:
        raise ConvergenceError(message + "; try solver='direct'", info, state=x.copy())
    raise SingularError(message, info)


def unstable_message(model: VoronoiModel, count: int | None, supports) -> str:
    """Why an unstable stiffness is refused, with the admissible nu range where cheap."""
    what = f"{count} negative eigenvalue(s)" if count else "a negative curvature direction"
    msg = (
        f"the {model.kind} stiffness with these supports is not positive definite ({what}): "
        f"the lattice is unstable for nu = {model.nu} (nu_m = {model.nu_m:.4g}) on this mesh, "
        "so its equilibrium would not be a physical solution"
    )
    if 2 * model.mesh.n_points <= RANGE_IN_MESSAGE_MAX_DOF:
        try:
            rep = stability(model, supports)
            msg += (
                f"; admissible for this mesh and these supports: nu_m in "
                f"({rep.nu_m_range[0]:.4g}, {rep.nu_m_range[1]:.4g}), i.e. nu in "
                f"({rep.nu_range[0]:.4g}, {rep.nu_range[1]:.4g})"
            )
        except (ArithmeticError, ValueError, RuntimeError) as exc:
            log.warning("stability range not computed: %s", exc)  # a courtesy; refusal stands
    else:
        msg += "; call dv.stability(model, supports) for the admissible nu range"
    return msg + (
        ". Irregular meshes (obtuse triangles) shrink the stable range, DV more "
        "than RV: use a more regular mesh (lattice, cvt) or the RV model"
    )
