"""Newton's method with load stepping, written once for every engine.

Loads and prescribed displacements are scaled together by a load factor that goes
from 0 to 1 in steps. Each step is solved by Newton iterations with the exact
tangent, a backtracking line search with Deuflhard's natural monotonicity test, and
automatic cut-back (halving the step and retrying) when a step fails.

The discretised problem is behind :class:`NewtonProblem`: the serial engine
(:class:`SerialProblem`, with a direct or AMG tangent solver from :mod:`.tangent`) and
the distributed PETSc engine (:mod:`dvstatic.parallel.petsc`) implement it, so both
converge in the same iterations on the same problem.

A step that cannot be completed raises :class:`~dvstatic.errors.ConvergenceError`
naming the step, the test that failed and what was tried. A converged state whose
tangent has negative pivots (loss of stability: buckling or a limit point) raises
:class:`~dvstatic.errors.UnstableError`, unless ``allow_unstable`` is set.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..errors import ConvergenceError, InputError, SolverError, UnstableError
from ..lattice import VoronoiModel
from ..lattice.operator import scatter_bond_forces
from ..linalg import ConstrainedSystem
from ..problem import FollowerPressures
from .info import NewtonStep, SolveInfo
from .options import SolveOptions
from .tangent import TangentSolver

log = logging.getLogger(__name__)

__all__ = [
    "State",
    "NewtonProblem",
    "SerialProblem",
    "NewtonReport",
    "solve_nonlinear",
    "absolute_floor",
    "ATOL_FLOOR",
]


#: Newton's absolute residual floor in units of k_n t l_mean sqrt(n_dof) (force)
ATOL_FLOOR = 1e-10


def absolute_floor(stiffness: float, mean_length: float, n_dof: int) -> float:
    """The absolute floor of Newton's residual tolerance (force): :data:`ATOL_FLOOR`
    ``stiffness * mean_length * sqrt(n_dof)``, ``stiffness`` = ``k_n`` times the
    thickness; the same for the serial and the distributed engines."""
    return ATOL_FLOOR * stiffness * mean_length * float(np.sqrt(n_dof))


@dataclass(frozen=True, eq=False)
class State:
    """Residual of a state: free-dof part, all dofs, and what the tangent needs."""

    r_free: np.ndarray
    r_all: np.ndarray
    aux: Any = None


class NewtonProblem(Protocol):
    """What Newton's method needs from a discretised problem (local pieces of it on
    every rank of a distributed run; norms are global).

    Attributes
    ----------
    constrained : ndarray of bool
        Prescribed dofs.
    targets : ndarray
        Prescribed values at load factor 1 (zero at free dofs).
    f_ext : ndarray
        External forces at load factor 1.
    atol : float
        Absolute floor of the residual tolerance (force).
    """

    constrained: np.ndarray
    targets: np.ndarray
    f_ext: np.ndarray
    atol: float

    def norm(self, v: np.ndarray) -> float: ...

    def max_abs(self, v: np.ndarray) -> float: ...

    def load_norm(self) -> float:
        """Norm of the full load (dead and follower loads in the reference state)."""

    def evaluate(self, u: np.ndarray, lam: float) -> State | None:
        """Residual ``f_int(u) - lam f_ext``; None if the state is invalid (inverted)."""

    def factor(self, u: np.ndarray, state: State) -> None:
        """Build the tangent at ``u`` (whose residual is ``state``)."""

    def solve(self, rhs_free: np.ndarray, du_c: np.ndarray) -> tuple[np.ndarray, int]:
        """Tangent solve with ``du = du_c`` on prescribed dofs; returns du and the
        linear iterations."""

    def negative_pivots(self) -> int | None:
        """Negative pivots of the last tangent (None: not known to this engine)."""

    @property
    def builds(self) -> int: ...


class SerialProblem:
    """A model with its supports and loads, on one process (:class:`NewtonProblem`).

    ``f_ext`` are the dead loads; ``follower`` the follower pressures, whose forces
    follow the deformed boundary (and enter the tangent).
    """

    def __init__(
        self,
        model: VoronoiModel,
        dofs,
        values,
        f_ext,
        tangent: TangentSolver,
        follower: FollowerPressures | None = None,
    ):
        self.op = model.operator
        self.mesh = model.mesh
        n = 2 * self.mesh.n_points
        self.dofs = np.asarray(dofs)
        self.constrained = np.zeros(n, dtype=bool)
        self.constrained[self.dofs] = True
        self.targets = np.zeros(n)
        self.targets[self.dofs] = values
        self.f_ext = np.asarray(f_ext, dtype=float)
        self.follower = follower if follower else None
        self.atol = absolute_floor(model.k_n * model.t, float(np.mean(model.geometry.length)), n)
        self.tangent = tangent
        self.system: ConstrainedSystem | None = None

    def norm(self, v: np.ndarray) -> float:
        return float(np.linalg.norm(v))

    def max_abs(self, v: np.ndarray) -> float:
        return float(np.max(np.abs(v))) if v.size else 0.0

    def load_norm(self) -> float:
        f = self.f_ext
        if self.follower is not None:
            f = f + self.follower.forces(self.mesh.points)
        return self.norm(f)

    def evaluate(self, u: np.ndarray, lam: float) -> State | None:
        uu = u.reshape(-1, 2)
        if self.op.inverted(uu):
            return None
        try:
            t, d, length = self.op.bond_state(uu)
        except InputError:  # a collapsed bond
            return None
        r = scatter_bond_forces(
            self.mesh.topology.bonds, (t / length)[:, None] * d, self.mesh.n_points
        )
        r -= lam * self.f_ext
        if self.follower is not None:
            r -= lam * self.follower.forces(self.mesh.points + uu)
        if not np.all(np.isfinite(r)):
            return None
        r_free = r.copy()
        r_free[self.constrained] = 0.0
        return State(r_free, r, (t, lam))

    def jacobian(self, u: np.ndarray, state: State):
        """The exact derivative of the residual at ``u`` (BSR, not constrained): the
        lattice tangent minus the follower pressures' derivative."""
        import scipy.sparse as sp

        tension, lam = state.aux
        kt = self.op.assemble(u.reshape(-1, 2), None, tension)
        if self.follower is not None and lam != 0.0:
            ft = self.follower.tangent(self.mesh.n_points)
            kt = sp.bsr_matrix(kt.tocsr() - lam * ft, blocksize=(2, 2))
        return kt

    def factor(self, u: np.ndarray, state: State) -> None:
        self.system = ConstrainedSystem(self.jacobian(u, state), self.dofs)
        self.tangent.factor(self.system)

    def solve(self, rhs_free: np.ndarray, du_c: np.ndarray) -> tuple[np.ndarray, int]:
        b = self.system.rhs(rhs_free, du_c[self.dofs])
        return self.tangent.solve(b)

    def negative_pivots(self) -> int | None:
        return self.tangent.negative_pivots

    @property
    def builds(self) -> int:
        return self.tangent.builds


@dataclass(frozen=True)
class NewtonReport:
    """What :func:`solve_nonlinear` did."""

    steps: tuple[NewtonStep, ...]
    cutbacks: int
    tangent_builds: int
    iterations: int
    residual: float


def solve_nonlinear(
    problem: NewtonProblem, opts: SolveOptions, kind: str, description: str | None = None
):
    """Equilibrium ``f_int(u) = f_ext`` with the prescribed values, by load stepping.

    ``kind`` names the engine in the reports (``"direct"``, ``"amg"``, ``"petsc"``),
    ``description`` its linear solver in messages (default ``kind``).

    Returns
    -------
    u : ndarray
        The converged state (the problem's local dofs).
    report : NewtonReport

    Raises
    ------
    ConvergenceError
        A load step failed after every cut-back (``state``, ``load_factor``: the last
        converged state, or the smallest failed step's last iterate when no step
        converged (``equilibrium`` False); for a distributed problem ``state`` holds this
        rank's dofs).
    UnstableError
        A converged state is unstable and ``allow_unstable`` is not set.
    """
    u = np.zeros_like(problem.f_ext)
    lam, dlam = 0.0, 1.0 / opts.steps
    f_scale = problem.load_norm()
    accepted: list[NewtonStep] = []
    cutbacks = step_no = 0
    bar = _progress_bar(opts.progress)
    try:
        while lam < 1.0 - 1e-14:
            target = min(1.0, lam + dlam)
            step_no += 1
            ok, u_new, rec = _newton_step(problem, u, target, f_scale, opts)
            if ok:
                _check_stable(problem, opts, step_no, target, accepted, rec, kind)
                u, lam = u_new, target
                accepted.append(rec)
                _report_step(bar, step_no, rec)
                if rec.iterations <= 4:
                    dlam = min(1.0 / opts.steps, 1.5 * dlam)
                continue
            cutbacks += 1
            if cutbacks > opts.max_cutbacks:
                # the last converged state; with none, the failed step's last iterate
                last = u if accepted or not np.all(np.isfinite(u_new)) else u_new
                raise ConvergenceError(
                    _failure_message(
                        step_no, lam, rec, cutbacks - 1, dlam, opts, description or kind
                    ),
                    _partial(kind, accepted, rec, cutbacks - 1, problem.builds, lam),
                    state=last.copy(),
                    load_factor=lam if last is u else target,
                    equilibrium=last is u,
                )
            dlam *= 0.5
            log.info("step %d failed (%s); cutting the step to %.3g", step_no, rec.reason, dlam)
    finally:
        if bar is not None:
            bar.close()
    residual = accepted[-1].residuals[-1] / max(f_scale, problem.atol) if accepted else 0.0
    report = NewtonReport(
        tuple(accepted),
        cutbacks,
        problem.builds,
        int(sum(s.iterations for s in accepted)),
        float(residual),
    )
    return u, report


def _partial(kind, accepted, failed, cutbacks, builds, lam) -> SolveInfo:
    """What Newton did before it stopped (for the error's ``info``)."""
    return SolveInfo(
        kind,
        nonlinear=True,
        iterations=int(sum(s.iterations for s in accepted)),
        residuals=tuple(r for st in accepted for r in st.residuals),
        steps=tuple(accepted),
        failed_step=failed,
        cutbacks=cutbacks,
        tangent_builds=builds,
        load_factor=lam,
    )


def _check_stable(problem, opts, step_no, target, accepted, rec, kind) -> None:
    neg = problem.negative_pivots()
    if opts.allow_unstable or not neg:
        return
    raise UnstableError(
        f"load step {step_no} (load factor {target:.4g}) converged to an unstable "
        f"equilibrium: the tangent has {neg} negative pivot(s) (buckling or a limit "
        "point); the load cannot be carried in this configuration. Add an imperfection to "
        "follow a post-buckling path, or pass allow_unstable=True to accept the state",
        _partial(kind, accepted, rec, 0, problem.builds, rec.load_factor),
        negative_eigenvalues=neg,
    )


def _report_step(bar, step_no: int, rec: NewtonStep) -> None:
    log.info(
        "step %d: load factor %.4g in %d iterations (residual %.2e)",
        step_no,
        rec.load_factor,
        rec.iterations,
        rec.residuals[-1],
    )
    if bar is not None:
        bar.n = round(100 * rec.load_factor)
        bar.set_postfix_str(f"step {step_no}, {rec.iterations} it")
        bar.refresh()


def _failure_message(step_no, lam, rec, tried, dlam, opts, solver_name) -> str:
    return (
        f"load step {step_no} (from load factor {lam:.4g} to {rec.load_factor:.4g}) did not "
        f"converge: {rec.reason}; tried {tried} cut-back(s) down to a step of {dlam:.3g}, "
        f"with line search={opts.line_search} and the {solver_name} linear solver. The load "
        "may exceed what the structure can carry, or more steps are needed"
    )


def _progress_bar(enabled: bool):
    """A tqdm bar of the load factor (in %), or None."""
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(
        total=100,
        desc="load",
        unit="%",
        leave=False,
        bar_format="{desc}: {percentage:3.0f}%|{bar}| {postfix}",
    )


class _Step:
    """Book-keeping of one load step."""

    def __init__(self, lam: float):
        self.lam = lam
        self.hist: list[float] = []
        self.alphas: list[float] = []
        self.lin_its: list[int] = []
        self.tol = np.nan
        self.inc = np.nan

    def record(self, it: int, reason: str = "") -> NewtonStep:
        return NewtonStep(
            load_factor=self.lam,
            iterations=it,
            residuals=tuple(self.hist) or (np.inf,),
            line_search=tuple(self.alphas),
            linear_iterations=tuple(self.lin_its),
            tolerance=float(self.tol),
            increment=float(self.inc),
            reason=reason,
        )


def _newton_step(problem: NewtonProblem, u0, lam: float, f_scale: float, opts: SolveOptions):
    """Newton iterations for load factor ``lam`` from ``u0``: (ok, u, NewtonStep)."""
    u = u0.copy()
    fixed = problem.constrained
    target_c = lam * problem.targets
    c_scale = max(problem.max_abs(problem.targets), 1e-300)
    rec = _Step(lam)
    state = problem.evaluate(u, lam)
    if state is None:
        return False, u, rec.record(0, "invalid start state")
    rec.tol = max(opts.newton_rtol * f_scale * lam, problem.atol)
    rec.hist.append(problem.norm(state.r_free))
    for it in range(1, opts.newton_maxiter + 1):
        du_c = np.where(fixed, target_c - u, 0.0)
        jump = problem.max_abs(du_c) > 1e-14 * c_scale
        if not jump:
            du_c[:] = 0.0
        try:
            problem.factor(u, state)
            du, lin_its = problem.solve(-state.r_free, du_c)
        except SolverError as exc:
            return False, u, rec.record(it, f"tangent solve failed: {exc}")
        du = np.where(fixed, du_c, du)  # prescribed increments exactly
        rec.lin_its.append(lin_its)
        # the predictor (first iteration of a step) carries the load increment and is
        # only checked for validity; a prescribed increment is taken whole or not at all;
        # the correctors are tested for monotonicity
        if jump:
            trial = problem.evaluate(u + du, lam)
            if trial is None:
                return (
                    False,
                    u,
                    rec.record(it, "the prescribed displacement increment inverts a triangle"),
                )
            best = (problem.norm(trial.r_free), u + du, trial, 1.0)
        else:
            best = _line_search(problem, u, du, lam, opts.line_search and it > 1)
        if best is None:
            return False, u, rec.record(it, "every line-search trial inverted a triangle")
        rn, u, state, alpha = best
        rec.hist.append(rn)
        rec.alphas.append(alpha)
        if not np.isfinite(rn):
            return False, u, rec.record(it, "non-finite residual")
        # reactions set the scale when only displacements are prescribed
        scale = max(f_scale * lam, problem.norm(state.r_all - state.r_free))
        rec.tol = max(opts.newton_rtol * scale, problem.atol)
        rec.inc = problem.norm(alpha * du) / max(problem.norm(u), 1e-300)
        c_err = problem.max_abs(np.where(fixed, u - target_c, 0.0))
        verdict = _converged(rn, rec.tol, rec.inc, c_err, c_scale, opts.newton_rtol)
        if verdict is None:
            return True, u, rec.record(it)
        if it >= 4 and rn > 1e3 * max(rec.hist[:2]) and rn > rec.tol:
            return False, u, rec.record(it, f"residual diverging ({verdict})")
    return False, u, rec.record(opts.newton_maxiter, f"{verdict} after {it} Newton iterations")


def _converged(rn, tol, inc, c_err, c_scale, rtol) -> str | None:
    """None if converged, else which test failed, with its two numbers."""
    if rn > tol:
        return f"residual {rn:.3e} > tolerance {tol:.3e}"
    if c_err > 1e-12 * c_scale:
        return f"prescribed values off by {c_err:.3e} > {1e-12 * c_scale:.3e}"
    if inc > np.sqrt(rtol) and rn > 1e-3 * tol:
        return (
            f"residual {rn:.3e} <= tolerance {tol:.3e}, but the relative increment "
            f"{inc:.3e} > {np.sqrt(rtol):.3e}"
        )
    return None


def _line_search(problem: NewtonProblem, u, du, lam: float, search: bool):
    """Backtracking with Deuflhard's natural monotonicity test.

    A trial ``u + alpha du`` is accepted when the simplified Newton correction there,
    computed with the same tangent (one more back-substitution), is smaller:
    ``|du_bar| <= (1 - alpha / 4) |du|``; otherwise alpha is halved. The test measures
    the residual in the tangent's own norm, so it accepts the right steps on slender
    structures whose first Newton step raises the force residual by orders of
    magnitude (axial stiffness), where a residual-norm test stalls. Trial states that
    invert a triangle are always halved.
    """
    norm_du = problem.norm(du)
    zero_c = np.zeros_like(du)
    alpha, best = 1.0, None
    for _ in range(12):
        trial = u + alpha * du
        state = problem.evaluate(trial, lam)
        if state is None:
            alpha *= 0.5
            continue
        cand = (problem.norm(state.r_free), trial, state, alpha)
        if not search:
            return cand
        try:
            du_bar, _ = problem.solve(-state.r_free, zero_c)
        except SolverError:  # the tangent solve failed: this step is not usable
            return None
        ratio = problem.norm(np.where(problem.constrained, 0.0, du_bar)) / max(norm_du, 1e-300)
        if best is None or ratio < best[0]:
            best = (ratio, cand)
        if ratio <= 1.0 - alpha / 4.0:
            return cand
        alpha *= 0.5
    return None if best is None else best[1]
