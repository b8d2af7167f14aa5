"""Newton-Raphson with load stepping for the geometrically exact DV/RV models.

Loads and prescribed displacements are scaled together by a load factor that goes
from 0 to 1 in steps. Each step is solved by Newton iterations with the exact
tangent, a backtracking line search on the residual norm, and automatic cut-back
(halving the step and retrying) when a step fails. Linear systems are solved by
sparse LU, or by GMRES preconditioned with a smoothed-aggregation AMG hierarchy built
on the symmetric part of a tangent and reused while it keeps working.

A step that cannot be completed raises :class:`~dvstatic.linalg.SolverError` naming
the step, the residual reached and what was tried. A converged state whose tangent
has negative pivots (loss of stability: buckling or a limit point) also raises,
unless ``allow_unstable`` is set.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import linalg
from .models import VoronoiModel
from .ordering import mesh_dof_order

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    pass


log = logging.getLogger(__name__)

__all__ = ["NewtonOptions", "solve_nonlinear"]


@dataclass(frozen=True)
class NewtonOptions:
    """Controls of :func:`solve_nonlinear` (see :func:`dvstatic.solve` for meanings)."""

    steps: int = 10
    rtol: float = 1e-8
    atol: float | None = None
    max_iter: int = 25
    max_cutbacks: int = 8
    line_search: bool = True
    solver: str = "direct"
    allow_unstable: bool = False
    linear_rtol: float = 1e-10
    progress: bool = False


@dataclass
class _Tangent:
    """Linear solver for tangent systems: factor once per Newton iteration, apply
    as often as needed (Newton step and the line-search monotonicity test)."""

    kind: str
    model: VoronoiModel
    dofs: np.ndarray
    builds: int = 0
    amg: linalg.AMGSolver | None = None
    amg_baseline: int | None = None
    last_negative_pivots: int | None = None
    system: linalg.ConstrainedSystem | None = None
    lu: linalg.DirectSolver | None = None
    linear_rtol: float = 1e-10

    def factor(self, u: np.ndarray, tension: np.ndarray) -> None:
        kt = self.model._assemble(u.reshape(-1, 2), None, tension)
        self.system = linalg.ConstrainedSystem(kt, self.dofs)
        if self.kind == "direct":
            self._factor_direct()

    def _factor_direct(self) -> None:
        self.lu = linalg.DirectSolver(self.system.A, order=mesh_dof_order(self.model.mesh))
        self.builds += 1
        self.last_negative_pivots = self.lu.negative_pivots

    def apply(self, rhs_free: np.ndarray, du_c: np.ndarray) -> tuple[np.ndarray, dict]:
        """Solve K_t du = rhs on free dofs with du = du_c on the constrained ones."""
        system = self.system
        b = rhs_free.copy()
        if np.any(du_c):
            uc = np.zeros_like(b)
            uc[self.dofs] = du_c
            b -= system.K @ uc
        b[self.dofs] = system.diag_value * du_c
        if self.lu is not None:
            x, info = self.lu.solve(b)
            return x, {"solver": "direct", "iterations": 0, "residual": info["residuals"][-1]}
        return self._amg(system, b)

    def _amg(self, system, b):
        rebuilt = False
        if self.amg is None:
            self._build(system)
            rebuilt = True
        x, its, ok = self._gmres(system.A, b)
        if not ok or (self.amg_baseline is not None and its > 3 * self.amg_baseline + 5):
            # the hierarchy no longer fits the tangent: rebuild on the current one
            self._build(system)
            rebuilt = True
            x, its, ok = self._gmres(system.A, b)
        if not ok:
            log.info("GMRES+AMG failed on the tangent; falling back to a direct solve")
            self._factor_direct()
            x, info = self.lu.solve(b)
            return x, {
                "solver": "direct",
                "iterations": 0,
                "residual": info["residuals"][-1],
                "fallback": "direct",
            }
        if self.amg_baseline is None:
            self.amg_baseline = its
        res = float(np.linalg.norm(system.A @ x - b) / (np.linalg.norm(b) or 1.0))
        return x, {"solver": "amg-gmres", "iterations": its, "residual": res, "rebuilt": rebuilt}

    def _build(self, system) -> None:
        import scipy.sparse as sp

        sym = (system.A + system.A.T) * 0.5
        self.amg = linalg.AMGSolver(
            sp.bsr_matrix(sym, blocksize=(2, 2)), linalg.rigid_modes(self.model.mesh.points)
        )
        self.builds += 1

    def _gmres(self, A, b):
        import scipy.sparse.linalg as spla

        count = [0]

        def cb(_):
            count[0] += 1

        if not np.any(b):
            return np.zeros_like(b), 0, True
        M = self.amg.ml.aspreconditioner()
        x, status = spla.gmres(
            A,
            b,
            rtol=self.linear_rtol,
            atol=0.0,
            M=M,
            restart=60,
            maxiter=5,
            callback=cb,
            callback_type="pr_norm",
        )
        ok = status == 0 and np.all(np.isfinite(x))
        if ok:
            true = np.linalg.norm(A @ x - b) / (np.linalg.norm(b) or 1.0)
            ok = true <= max(100 * self.linear_rtol, 1e-12)
        return x, count[0], ok


def _residual(model: VoronoiModel, u: np.ndarray, f: np.ndarray, dofs: np.ndarray):
    """Free-dof residual f_int(u) - f, the tension, or None if the state is invalid."""
    y = model._triangles_now(u.reshape(-1, 2), None)
    a2 = (y[:, 1, 0] - y[:, 0, 0]) * (y[:, 2, 1] - y[:, 0, 1]) - (y[:, 1, 1] - y[:, 0, 1]) * (
        y[:, 2, 0] - y[:, 0, 0]
    )
    if not np.all(a2 > 0):
        return None, None
    try:
        t, d, length = model._tension(u.reshape(-1, 2), None)
    except ValueError:
        return None, None
    fb = (t / length)[:, None] * d
    b = model.mesh.topology.bonds
    n = model.mesh.n_points
    fi = np.zeros((n, 2))
    for c in range(2):
        fi[:, c] = np.bincount(b[:, 1], fb[:, c], n) - np.bincount(b[:, 0], fb[:, c], n)
    r = fi.reshape(-1) - f
    r_free = r.copy()
    r_free[dofs] = 0.0
    if not np.all(np.isfinite(r)):
        return None, None
    return (r_free, r), t


def solve_nonlinear(
    model: VoronoiModel,
    dofs: np.ndarray,
    values: np.ndarray,
    f_ext: np.ndarray,
    opts: NewtonOptions,
) -> tuple[np.ndarray, dict]:
    """Equilibrium ``f_int(u) = f_ext`` with ``u[dofs] = values``, by load stepping.

    Returns
    -------
    u : ndarray, shape (2N,)
    info : dict
        ``steps`` (one dict per accepted step: load factor, iterations, residual
        history, line-search factors, linear-solver iterations), ``cutbacks``,
        ``tangent_builds`` (factorisations or AMG hierarchies built), ``seconds``.
    """
    t_start = time.perf_counter()
    n = 2 * model.mesh.n_points
    u = np.zeros(n)
    lam = 0.0
    dlam = 1.0 / opts.steps
    f_scale = float(np.linalg.norm(f_ext))
    force_unit = model.k_n * float(np.mean(model.geometry.length))
    atol = opts.atol if opts.atol is not None else 1e-10 * force_unit * np.sqrt(n)
    tangent = _Tangent(opts.solver, model, dofs, linear_rtol=opts.linear_rtol)
    steps_info: list[dict] = []
    cutbacks = 0
    step_no = 0
    bar = _progress_bar(opts.progress)
    try:
        while lam < 1.0 - 1e-14:
            target = min(1.0, lam + dlam)
            step_no += 1
            ok, u_new, sinfo = _newton_step(
                model, u, lam, target, dofs, values, f_ext, f_scale, atol, opts, tangent
            )
            if ok:
                if (
                    not opts.allow_unstable
                    and opts.solver == "direct"
                    and tangent.last_negative_pivots
                ):
                    raise linalg.SolverError(
                        f"load step {step_no} (load factor {target:.4g}) converged to an unstable "
                        f"equilibrium: the tangent has {tangent.last_negative_pivots} negative "
                        "pivot(s) (buckling or a limit point); the load cannot be carried in this "
                        "configuration. Add an imperfection to follow a post-buckling path, or "
                        "pass allow_unstable=True to accept the state",
                        {"steps": steps_info, "failed_step": sinfo},
                    )
                u = u_new
                lam = target
                sinfo["load_factor"] = lam
                steps_info.append(sinfo)
                log.info(
                    "step %d: load factor %.4g in %d iterations (residual %.2e)",
                    step_no,
                    lam,
                    sinfo["iterations"],
                    sinfo["residuals"][-1],
                )
                if bar is not None:
                    bar.n = round(100 * lam)
                    bar.set_postfix_str(f"step {step_no}, {sinfo['iterations']} it")
                    bar.refresh()
                if sinfo["iterations"] <= 4:
                    dlam = min(1.0 / opts.steps, 1.5 * dlam)
                continue
            cutbacks += 1
            if cutbacks > opts.max_cutbacks:
                raise linalg.SolverError(
                    f"load step {step_no} (from load factor {lam:.4g} to {target:.4g}) did not "
                    f"converge: residual {sinfo['residuals'][-1]:.3e} against a tolerance of "
                    f"{sinfo['tolerance']:.3e} after {sinfo['iterations']} Newton iterations "
                    f"({sinfo['reason']}); tried {cutbacks - 1} cut-back(s) down to a step of "
                    f"{dlam:.3g}, with line search={opts.line_search} and the "
                    f"{opts.solver} linear solver. The load may exceed what the structure can "
                    "carry, or more steps are needed",
                    {
                        "steps": steps_info,
                        "failed_step": sinfo,
                        "cutbacks": cutbacks - 1,
                        "u": u.copy(),
                        "load_factor": lam,
                    },
                )
            dlam *= 0.5
            log.info(
                "step %d failed (%s); cutting the step to %.3g", step_no, sinfo["reason"], dlam
            )
    finally:
        if bar is not None:
            bar.close()
    info = {
        "steps": steps_info,
        "cutbacks": cutbacks,
        "tangent_builds": tangent.builds,
        "iterations": int(sum(s["iterations"] for s in steps_info)),
        "residual": steps_info[-1]["residuals"][-1] / max(f_scale, atol) if steps_info else 0.0,
        "newton_seconds": time.perf_counter() - t_start,
    }
    return u, info


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


def _newton_step(model, u0, lam0, lam, dofs, values, f_ext, f_scale, atol, opts, tangent):
    u = u0.copy()
    f = lam * f_ext
    target_c = lam * values
    c_scale = max(float(np.max(np.abs(values))) if values.size else 0.0, 1e-300)
    hist: list[float] = []
    alphas: list[float] = []
    lin_its: list[int] = []
    state, tension = _residual(model, u, f, dofs)
    if state is None:
        return False, u, _fail(hist, 0, np.inf, "invalid start state")
    r_free, r_all = state
    tol = max(opts.rtol * f_scale * lam, atol)
    hist.append(float(np.linalg.norm(r_free)))
    for it in range(1, opts.max_iter + 1):
        du_c = target_c - u[dofs]
        jump = bool(np.any(np.abs(du_c) > 1e-14 * c_scale))
        if not jump:
            du_c = np.zeros_like(du_c)
        try:
            tangent.factor(u, tension)
            du, linfo = tangent.apply(-r_free, du_c)
        except linalg.SolverError as exc:
            return False, u, _fail(hist, it, tol, f"tangent solve failed: {exc}")
        lin_its.append(linfo["iterations"])
        # the predictor (first iteration of a step) is only checked for validity: it
        # carries the load increment and is the right step even when it raises the
        # residual; the correctors are tested for monotonicity
        if jump:
            # a prescribed displacement increment is taken whole or not at all
            state, t_trial = _residual(model, u + du, f, dofs)
            if state is None:
                return (
                    False,
                    u,
                    _fail(
                        hist, it, tol, "the prescribed displacement increment inverts a triangle"
                    ),
                )
            best = (float(np.linalg.norm(state[0])), u + du, state, t_trial, 1.0)
        else:
            best = _line_search(model, tangent, u, du, f, dofs, opts.line_search and it > 1)
        if best is None:
            return False, u, _fail(hist, it, tol, "every line-search trial inverted a triangle")
        rn, u, (r_free, r_all), tension, alpha = best
        hist.append(rn)
        alphas.append(alpha)
        if not np.isfinite(rn):
            return False, u, _fail(hist, it, tol, "non-finite residual")
        # reactions set the scale when only displacements are prescribed
        scale = max(f_scale * lam, float(np.linalg.norm(r_all - r_free)))
        tol = max(opts.rtol * scale, atol)
        inc = float(np.linalg.norm(alpha * du)) / max(float(np.linalg.norm(u)), 1e-300)
        c_err = float(np.max(np.abs(u[dofs] - target_c))) if dofs.size else 0.0
        if (
            rn <= tol
            and c_err <= 1e-12 * c_scale
            and (inc <= np.sqrt(opts.rtol) or rn <= 1e-3 * tol)
        ):
            return (
                True,
                u,
                {
                    "iterations": it,
                    "residuals": hist,
                    "line_search": alphas,
                    "linear_iterations": lin_its,
                    "tolerance": tol,
                    "increment": inc,
                },
            )
        if it >= 4 and rn > 1e3 * max(hist[:2]) and rn > tol:
            return False, u, _fail(hist, it, tol, "residual diverging")
    return (
        False,
        u,
        _fail(hist, opts.max_iter, tol, f"no convergence in {opts.max_iter} iterations"),
    )


def _line_search(model, tangent, u, du, f, dofs, search: bool):
    """Backtracking with Deuflhard's natural monotonicity test.

    A trial ``u + alpha du`` is accepted when the simplified Newton correction there,
    computed with the same tangent (one more back-substitution), is smaller:
    ``|du_bar| <= (1 - alpha / 4) |du|``; otherwise alpha is halved. The test measures
    the residual in the tangent's own norm, so it accepts the right steps on slender
    structures whose first Newton step raises the force residual by orders of
    magnitude (axial stiffness), where a residual-norm test stalls. Trial states that
    invert a triangle are always halved.
    """
    norm_du = float(np.linalg.norm(du))
    zero_c = np.zeros(len(dofs))
    alpha, best = 1.0, None
    for _ in range(12):
        trial = u + alpha * du
        state, t_trial = _residual(model, trial, f, dofs)
        if state is None:
            alpha *= 0.5
            continue
        rn = float(np.linalg.norm(state[0]))
        cand = (rn, trial, state, t_trial, alpha)
        if not search:
            return cand
        du_bar, _ = tangent.apply(-state[0], zero_c)
        ratio = float(np.linalg.norm(du_bar)) / max(norm_du, 1e-300)
        if best is None or ratio < best[0]:
            best = (ratio, cand)
        if ratio <= 1.0 - alpha / 4.0:
            return cand
        alpha *= 0.5
    return None if best is None else best[1]


def _fail(hist, it, tol, reason):
    return {"iterations": it, "residuals": hist or [np.inf], "tolerance": tol, "reason": reason}
