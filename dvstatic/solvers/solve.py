"""Static solves: :func:`solve` (linear, Newton, dynamic relaxation, or an engine)."""

from __future__ import annotations

import dataclasses
import inspect
import logging
import time

import numpy as np

from ..errors import ConvergenceError, InputError
from ..lattice import VoronoiModel, check_model
from ..lattice import geometry as _geometry
from ..problem import FollowerPressures, Problem, as_list, load_vector
from ..problem.follower import split_followers
from . import backends
from .linear import solve_linear
from .newton import SerialProblem, solve_nonlinear
from .options import SolveOptions, options_docstring
from .relaxation import dynamic_relaxation
from .result import Solution, SolveInfo, Timings
from .tangent import tangent_solver

log = logging.getLogger(__name__)

__all__ = ["solve"]


def solve(model: VoronoiModel, supports=None, loads=None, *, options=None, **kwargs) -> Solution:
    check_model(model)
    opts = SolveOptions.from_kwargs(options, **kwargs)
    if model.mesh.is_periodic:
        raise InputError(
            "solve() needs a bounded mesh; use homogenize() on periodic meshes", "mesh"
        )
    supports_l = as_list(supports, "Fix")
    loads_l = as_list(loads, "Traction, Pressure, BodyForce or PointLoad")
    if opts.solver == "petsc":
        return backends.engine("petsc").solve(model, supports_l, loads_l, opts)
    t0 = time.perf_counter()
    problem = Problem.build(model, supports_l, loads_l)  # resolved once, carried on
    try:
        return _solve_serial(model, problem, opts)
    except ConvergenceError as exc:
        if not opts.best_effort or exc.state is None:
            raise
        return _unconverged(model, problem, exc, opts, t0)


class _Problem:
    """Supports and loads turned into dofs, values and forces, with stage timings."""

    def __init__(self, model: VoronoiModel, problem: Problem):
        self.t_start = time.perf_counter()
        mesh = model.mesh
        # the model calibrated itself at construction: its cost is reported, not re-run
        self.t_calibration = sum(float((m.details or {}).get("seconds", 0.0)) for m in model.micros)
        self.problem = problem
        self.dofs, self.values, self.f = problem.dofs, problem.values, problem.f
        self.reused: list[str] = []
        t0 = time.perf_counter()
        if _geometry.is_cached(mesh):
            self.reused.append("geometry")
        _ = model.geometry
        self.t_geometry = time.perf_counter() - t0
        t0 = time.perf_counter()
        if model.is_assembled:
            self.reused.append("assembly")
        self.K = model.stiffness("bsr")
        self.t_assembly = time.perf_counter() - t0

    def reactions(self, r_full: np.ndarray) -> np.ndarray:
        """Support reactions (N, 2) from the full residual ``f_int - f``."""
        out = np.zeros_like(r_full)
        out[self.dofs] = r_full[self.dofs]
        return out.reshape(-1, 2)

    def timings(self, **stages) -> Timings:
        return Timings(
            geometry=self.t_geometry,
            calibration=self.t_calibration,
            assembly=self.t_assembly,
            total=time.perf_counter() - self.t_start,
            **stages,
        )


def _solve_serial(model: VoronoiModel, problem: Problem, opts) -> Solution:
    supports, loads = list(problem.supports), list(problem.loads)
    p = _Problem(model, problem)
    n = p.K.shape[0]
    kind = opts.resolved_solver(n)
    common = dict(
        n_dof=n,
        n_constrained=int(p.dofs.size),
        converged=True,
        coupling_assembled=model.operator.has_coupling,
        nonlinear=opts.nonlinear,
    )
    if kind == "dynamic-relaxation":
        if opts.nonlinear and split_followers(loads)[1]:
            raise InputError(
                "follower pressures need an implicit solver (direct, amg or petsc), not "
                "dynamic relaxation",
                "solver",
            )
        x, r_full, info = _relax(model, p, opts, common)
    elif opts.nonlinear:
        x, r_full, info = _newton(model, p, opts, kind, common, loads)
    else:
        x, r_full, info = _linear(model, p, opts, kind, common, supports)
    log.info(
        "%s %s solve: %d dof, %d iterations, residual %.2e, %.3f s",
        model.kind,
        info.solver,
        n,
        info.iterations,
        info.residual,
        info.seconds.total,
    )
    if not opts.nonlinear:
        _warn_large(model.mesh, x.reshape(-1, 2))
    return Solution(
        model, x.reshape(-1, 2), p.reactions(r_full), info, supports, loads, problem=problem
    )


#: a linear solution whose largest displacement exceeds this fraction of the body's
#: size is warned about (small-strain theory no longer describes it)
LARGE_DISPLACEMENT = 0.1


def _warn_large(mesh, u: np.ndarray) -> None:
    size = float(np.max(np.ptp(mesh.points, axis=0)))
    umax = float(np.max(np.hypot(u[:, 0], u[:, 1])))
    if umax > LARGE_DISPLACEMENT * size:
        log.warning(
            "the largest displacement, %.3g, is %.0f %% of the body's size (%.3g): a linear "
            "(small-strain) solution does not describe this; solve with nonlinear=True "
            "(scene: [solver] nonlinear = true)",
            umax,
            100 * umax / size,
            size,
        )


def _relax(model: VoronoiModel, p: _Problem, opts, common: dict):
    t0 = time.perf_counter()
    x, rep = dynamic_relaxation(
        model, p.dofs, p.values, p.f, opts.rtol, opts.linear_maxiter(), opts.nonlinear
    )
    r_full = _internal(model, x, p.K, opts.nonlinear) - p.f
    info = SolveInfo(
        "dynamic-relaxation",
        iterations=rep.iterations,
        residuals=rep.residuals,
        residual=rep.residual,
        seconds=p.timings(solve=time.perf_counter() - t0),
        reused=tuple(p.reused),
        damping=rep.damping,
        **common,
    )
    return x, r_full, info


def _newton(model: VoronoiModel, p: _Problem, opts, kind: str, common: dict, loads: list):
    t0 = time.perf_counter()
    dead, follow = split_followers(loads)
    f_dead = load_vector(model.mesh, dead, thickness=model.t) if follow else p.f
    follower = FollowerPressures.from_loads(model.mesh, follow, model.t)
    # GMRES+AMG: the options' rtol, and its iteration limit (default 300: 5 restarts of 60)
    maxiter = opts.maxiter if opts.maxiter is not None else 300
    tangent = tangent_solver(kind, model.mesh, opts.rtol, maxiter)
    problem = SerialProblem(model, p.dofs, p.values, f_dead, tangent, follower)
    x, rep = solve_nonlinear(problem, opts, kind)
    r_full = _internal(model, x, p.K, True) - f_dead
    if follower:
        r_full -= follower.forces(model.mesh.points + x.reshape(-1, 2))
    info = SolveInfo(
        kind,
        iterations=rep.iterations,
        residuals=tuple(r for st in rep.steps for r in st.residuals),
        residual=rep.residual,
        seconds=p.timings(solve=time.perf_counter() - t0),
        reused=tuple(p.reused),
        steps=rep.steps,
        cutbacks=rep.cutbacks,
        tangent_builds=rep.tangent_builds,
        **common,
    )
    return x, r_full, info


def _linear(model: VoronoiModel, p: _Problem, opts, kind: str, common: dict, supports):
    x, rep = solve_linear(model, kind, p.dofs, p.values, p.f, opts, supports)
    reused = list(p.reused)
    if rep.reused:
        reused.append("factorisation" if kind == "direct" else "amg hierarchy")
    info = SolveInfo(
        kind,
        iterations=rep.iterations,
        residuals=rep.residuals,
        residual=rep.residual,
        seconds=p.timings(setup=rep.setup_seconds, solve=rep.solve_seconds),
        reused=tuple(reused),
        stability=rep.stability,
        backward_error=rep.backward_error,
        **common,
    )
    return x, p.K @ x - p.f, info


def _internal(model: VoronoiModel, x: np.ndarray, K, nonlinear: bool) -> np.ndarray:
    return model.internal_force(x.reshape(-1, 2)) if nonlinear else K @ x


def _unconverged(model, problem: Problem, exc: ConvergenceError, opts, t0: float) -> Solution:
    """The last state of a failed iteration, marked unconverged (best effort)."""
    dofs, f_full = problem.dofs, problem.f
    supports, loads = list(problem.supports), list(problem.loads)
    x = np.asarray(exc.state, dtype=float).reshape(-1)
    r_full = _internal(model, x, model.stiffness("bsr"), opts.nonlinear) - exc.load_factor * f_full
    reactions = np.zeros_like(x)
    reactions[dofs] = r_full[dofs]
    free = np.ones(x.size, dtype=bool)
    free[dofs] = False
    # relative to the load the state belongs to (or the reactions, with only prescribed
    # displacements)
    scale = max(
        float(np.linalg.norm(exc.load_factor * f_full)), float(np.linalg.norm(r_full[dofs]))
    )
    r_free = float(np.linalg.norm(r_full[free]))
    residual = r_free / scale if scale > 0 else (0.0 if r_free == 0 else float("inf"))
    prior = exc.info if isinstance(exc.info, SolveInfo) else SolveInfo(opts.resolved_solver(x.size))
    info = dataclasses.replace(
        prior,
        nonlinear=opts.nonlinear,
        converged=False,
        n_dof=x.size,
        n_constrained=int(dofs.size),
        residual=residual,
        load_factor=exc.load_factor,
        failure=str(exc),
        equilibrium=exc.equilibrium,
        seconds=dataclasses.replace(prior.seconds, total=time.perf_counter() - t0),
        coupling_assembled=model.operator.has_coupling,
    )
    what = (
        "the last converged load step"
        if exc.equilibrium
        else "the last iterate of a step that did not converge"
    )
    log.warning(
        "best effort: returning %s, load factor %.4g (%s)",
        what,
        exc.load_factor,
        exc,
        extra={"best_effort": True},
    )
    return Solution(
        model, x.reshape(-1, 2), reactions.reshape(-1, 2), info, supports, loads, problem=problem
    )


def _signature() -> inspect.Signature:
    params = [
        inspect.Parameter("model", inspect.Parameter.POSITIONAL_OR_KEYWORD),
        inspect.Parameter("supports", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None),
        inspect.Parameter("loads", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None),
        inspect.Parameter("options", inspect.Parameter.KEYWORD_ONLY, default=None),
    ]
    defaults = SolveOptions()
    for name in SolveOptions.__dataclass_fields__:
        params.append(
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=getattr(defaults, name))
        )
    return inspect.Signature(params, return_annotation=Solution)


solve.__signature__ = _signature()
solve.__doc__ = f"""Solve the static problem: linear ``K u = f`` or geometrically exact equilibrium.

    Parameters
    ----------
    model : DV or RV
    supports : Fix or list of Fix
        Must prevent all rigid-body motion.
    loads : Traction, BodyForce, PointLoad or a list of them
    options : SolveOptions, optional
        All options at once; keywords given as well override it.
{options_docstring()}

    Returns
    -------
    Solution
        ``u``, ``reactions`` and the typed report ``info`` (:class:`SolveInfo`).

    Raises
    ------
    InputError (a ValueError)
        Bad input, or supports that leave a rigid-body motion free.
    UnstableError (a SolverError)
        The stiffness (or a converged Newton state) is not positive definite.
    SingularError (a SolverError)
        The system is singular or badly conditioned.
    ConvergenceError (a SolverError)
        An iteration did not converge (AMG limit, a load step failing after every
        cut-back); with ``best_effort`` the last state is returned instead.
    MissingDependencyError (an ImportError)
        ``solver="petsc"`` without petsc4py.
    """
