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

import numpy as np

from .linalg import SolverError
from .models import VoronoiModel

log = logging.getLogger(__name__)

__all__ = ["dynamic_relaxation"]


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
) -> tuple[np.ndarray, dict]:
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
        Called every ``callback_every`` steps (its run time is not counted in
        ``info["seconds"]``).
    time_limit : float, optional
        Wall-clock seconds after which the relaxation stops with an error.

    Returns
    -------
    u : ndarray, shape (2N,)
    info : dict
        ``iterations`` (time steps), ``residuals`` (relative, every 100 steps),
        ``residual``, ``seconds`` (excluding callbacks).

    Raises
    ------
    SolverError
        If the residual target is not reached within ``max_steps`` or ``time_limit``,
        or the iteration blows up (an unstable lattice).
    """
    K = model._stiffness_bsr.tocsr()
    n = K.shape[0]
    free = np.ones(n, dtype=bool)
    free[dofs] = False
    row_abs = np.asarray(abs(K).sum(axis=1)).ravel()
    mass = 0.3 * np.maximum(row_abs, 1e-300)
    u = np.zeros(n)
    u[dofs] = values
    v = np.zeros(n)
    t0 = time.perf_counter()

    def force(x):
        if nonlinear:
            return model.internal_force(x.reshape(-1, 2))
        return K @ x

    with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is caught below
        t_cb = 0.0
        fi = force(u)
        r = f_ext - fi
        f_norm = float(np.linalg.norm(f_ext))
        hist: list[float] = []
        for step in range(1, max_steps + 1):
            r[~free] = 0.0
            scale = max(f_norm, float(np.linalg.norm((fi - f_ext)[~free])), 1e-300)
            res = float(np.linalg.norm(r)) / scale
            if step % 100 == 1:
                hist.append(res)
            if res <= rtol:
                break
            if not np.isfinite(res) or res > 1e12:
                raise SolverError(
                    f"dynamic relaxation blew up at step {step} (relative residual {res:.3e}): "
                    "the lattice is unstable for these micro-parameters",
                    {"solver": "dynamic-relaxation", "iterations": step, "residuals": hist},
                )
            # lowest-frequency estimate (Rayleigh quotient on the free dofs)
            uf = u[free]
            den = float(uf @ (mass[free] * uf))
            num = float(uf @ fi[free]) if not nonlinear else float(uf @ (K @ u)[free])
            c = 2.0 * np.sqrt(max(num, 0.0) / den) if den > 0 else 0.0
            c = min(c, 1.9)
            v = ((2.0 - c) * v + 2.0 * r / mass) / (2.0 + c)
            v[~free] = 0.0
            u += v
            fi = force(u)
            r = f_ext - fi
            if callback is not None and step % callback_every == 0:
                tc = time.perf_counter()
                callback(step, u)
                t_cb += time.perf_counter() - tc
            if time_limit is not None and time.perf_counter() - t0 - t_cb > time_limit:
                raise SolverError(
                    f"dynamic relaxation stopped by the time limit ({time_limit} s) at step {step} "
                    f"with relative residual {res:.3e} (target {rtol:.1e})",
                    {
                        "solver": "dynamic-relaxation",
                        "iterations": step,
                        "residuals": hist,
                        "u": u.copy(),
                        "residual": res,
                    },
                )
        else:
            raise SolverError(
                f"dynamic relaxation did not reach the residual target {rtol:.1e} in {max_steps} "
                f"steps (relative residual {res:.3e}); raise max_steps or use an implicit solver",
                {
                    "solver": "dynamic-relaxation",
                    "iterations": max_steps,
                    "residuals": hist,
                    "u": u.copy(),
                    "residual": res,
                },
            )
        hist.append(res)
        info = {
            "iterations": step,
            "residuals": hist,
            "residual": res,
            "seconds": time.perf_counter() - t0 - t_cb,
            "damping": "adaptive viscous",
        }
        log.info("dynamic relaxation: %d steps, residual %.2e, %.2f s", step, res, info["seconds"])
        return u, info
