"""Dynamic relaxation: the explicit pseudo-dynamic solver of the kind the paper uses.

The static problem ``f_int(u) = f`` is solved as the steady state of a damped
fictitious dynamics ``M u'' + c M u' + f_int(u) = f`` by central differences
(refs. [4], [5] of the paper; Underwood 1983):

* lumped fictitious masses per dof from the Gershgorin bound of the stiffness,
  ``m_i = 0.3 sum_j |K_ij|`` (> 1/4 of the row sum), so the time step ``dt = 1`` is
  stable;
* adaptive viscous damping ``c = 2 sqrt(u.K.u / u.M.u)`` (the Rayleigh estimate of
  the lowest frequency, updated every step: critical damping of the slowest mode);
* stop when the free-dof residual falls below ``rtol`` times the load (or, with only
  prescribed displacements, the reactions).

It is here as the baseline the implicit solvers are measured against, and because
users coming from explicit scripts may want the like-for-like number. It is slow by
nature: the number of steps grows with the square root of the stiffness condition
number (about the number of particles across the body).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ConvergenceError, UnstableError
from ..lattice import VoronoiModel
from .info import SolveInfo

log = logging.getLogger(__name__)

__all__ = ["RelaxationReport", "dynamic_relaxation"]


@dataclass(frozen=True)
class RelaxationReport:
    """What :func:`dynamic_relaxation` did."""

    iterations: int
    residuals: tuple[float, ...]
    residual: float
    seconds: float
    damping: str = "adaptive viscous"


class _Relaxation:
    """State of the damped fictitious dynamics."""

    def __init__(self, model: VoronoiModel, dofs, values, f_ext, nonlinear: bool):
        self.model = model
        self.K = model.stiffness("csr")
        n = self.K.shape[0]
        self.free = np.ones(n, dtype=bool)
        self.free[dofs] = False
        row_abs = np.asarray(abs(self.K).sum(axis=1)).ravel()
        self.mass = 0.3 * np.maximum(row_abs, 1e-300)
        self.u = np.zeros(n)
        self.u[dofs] = values
        self.v = np.zeros(n)
        self.f_ext = f_ext
        self.f_norm = float(np.linalg.norm(f_ext))
        self.nonlinear = nonlinear
        self.fi = self.force(self.u)

    def force(self, x: np.ndarray) -> np.ndarray:
        if self.nonlinear:
            return self.model.internal_force(x.reshape(-1, 2))
        return self.K @ x

    def residual(self) -> tuple[np.ndarray, float]:
        """Free-dof residual and its norm relative to the load (or the reactions)."""
        r = self.f_ext - self.fi
        r[~self.free] = 0.0
        scale = max(self.f_norm, float(np.linalg.norm((self.fi - self.f_ext)[~self.free])), 1e-300)
        return r, float(np.linalg.norm(r)) / scale

    def run(self, rtol, max_steps, callback, callback_every, time_limit):
        """Step until the residual target; returns the steps, the residual history
        (every 100 steps and the last), the last residual and the callbacks' time."""
        t0 = time.perf_counter()
        t_cb = 0.0
        hist: list[float] = []
        with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is caught below
            for step in range(1, max_steps + 1):
                r, res = self.residual()
                if step % 100 == 1:
                    hist.append(res)
                if res <= rtol:
                    break
                if not np.isfinite(res) or res > 1e12:
                    raise UnstableError(
                        f"dynamic relaxation blew up at step {step} (relative residual "
                        f"{res:.3e}): the lattice is unstable for these micro-parameters",
                        _partial(step, hist, res),
                    )
                self.step(r)
                if callback is not None and step % callback_every == 0:
                    tc = time.perf_counter()
                    callback(step, self.u)
                    t_cb += time.perf_counter() - tc
                if time_limit is not None and time.perf_counter() - t0 - t_cb > time_limit:
                    raise ConvergenceError(
                        f"dynamic relaxation stopped by the time limit ({time_limit} s) at "
                        f"step {step} with relative residual {res:.3e} (target {rtol:.1e})",
                        _partial(step, hist, res),
                        state=self.u.copy(),
                    )
            else:
                raise ConvergenceError(
                    f"dynamic relaxation did not reach the residual target {rtol:.1e} in "
                    f"{max_steps} steps (relative residual {res:.3e}); raise maxiter or use "
                    "an implicit solver",
                    _partial(max_steps, hist, res),
                    state=self.u.copy(),
                )
        hist.append(res)
        return step, hist, res, t_cb

    def step(self, r: np.ndarray) -> None:
        """One central-difference step with damping from the Rayleigh quotient."""
        free, u = self.free, self.u
        uf = u[free]
        den = float(uf @ (self.mass[free] * uf))
        num = float(uf @ self.fi[free]) if not self.nonlinear else float(uf @ (self.K @ u)[free])
        c = 2.0 * np.sqrt(max(num, 0.0) / den) if den > 0 else 0.0
        c = min(c, 1.9)
        self.v = ((2.0 - c) * self.v + 2.0 * r / self.mass) / (2.0 + c)
        self.v[~free] = 0.0
        self.u += self.v
        self.fi = self.force(self.u)


def _partial(step: int, hist: list[float], res: float) -> SolveInfo:
    """What a failed relaxation did (for the error's ``info``)."""
    return SolveInfo(
        "dynamic-relaxation",
        iterations=step,
        residuals=tuple(hist) + (res,),
        residual=res,
        damping="adaptive viscous",
    )


def dynamic_relaxation(
    model: VoronoiModel,
    dofs: np.ndarray,
    values: np.ndarray,
    f_ext: np.ndarray,
    rtol: float = 1e-8,
    max_steps: int = 1_000_000,
    nonlinear: bool = False,
    callback=None,
    callback_every: int = 100,
    time_limit: float | None = None,
) -> tuple[np.ndarray, RelaxationReport]:
    """Explicit dynamic relaxation to equilibrium.

    Parameters
    ----------
    model : DV or RV
    dofs, values : ndarray
        Constrained dofs and their prescribed values.
    f_ext : ndarray, shape (2N,)
        External nodal forces.
    rtol : float
        Stop when ``|r_free| <= rtol * max(|f_ext|, |reactions|)``.
    max_steps : int
    nonlinear : bool
        Use the exact internal forces every step (large strain) instead of ``K u``.
    callback : callable(step, u), optional
        Called every ``callback_every`` steps (its run time is not counted).
    time_limit : float, optional
        Wall-clock seconds after which the relaxation stops with an error.

    Returns
    -------
    u : ndarray, shape (2N,)
    report : RelaxationReport
        Steps, relative residuals (every 100 steps), final residual, seconds
        (excluding callbacks).

    Raises
    ------
    ConvergenceError
        The residual target is not reached within ``max_steps`` or ``time_limit``
        (``state`` is the last iterate).
    UnstableError
        The iteration blows up (an unstable lattice).
    """
    dr = _Relaxation(model, dofs, values, f_ext, nonlinear)
    t0 = time.perf_counter()
    step, hist, res, t_cb = dr.run(rtol, max_steps, callback, callback_every, time_limit)
    report = RelaxationReport(step, tuple(hist), res, time.perf_counter() - t0 - t_cb)
    log.info("dynamic relaxation: %d steps, residual %.2e, %.2f s", step, res, report.seconds)
    return dr.u, report
