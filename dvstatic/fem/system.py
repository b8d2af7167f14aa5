"""Solving the FE reference's condensed system: SuperLU for small systems, AMG-CG with
the rigid-body modes for large ones."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np

from ..errors import SingularError
from ..linalg import AMGSolver, DirectSolver, SolveRecord

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = ["FE_AMG_ENTRIES", "FE_CG_RTOL", "solve_spd"]

log = logging.getLogger(__name__)

#: FE systems with more stored entries than this (the full symmetric matrix: about 1e5
#: P2 dof) are solved by AMG-CG (rigid-body modes), smaller ones directly. SuperLU's fill
#: grows with the entries per row, higher for P3 and P4 than for P2 at the same dof (P2,
#: plate_with_hole refined once, 2.8e5 dof: AMG-CG 3.9 s and no memory beyond the
#: assembly's, SuperLU 7.5 s and 1.1 GB more; at 5.7e4 dof SuperLU 0.7 s, AMG-CG 0.9 s;
#: P3 on the thick_cylinder example, 7.5e4 dof and 2.5e6 entries: SuperLU 0.9 s and a
#: peak of 452 MB, AMG-CG 2.9 s and 296 MB, the run without FE 198 MB)
FE_AMG_ENTRIES = 2_300_000
#: relative residual of the FE reference's AMG-CG solve
FE_CG_RTOL = 1e-11


def solve_spd(A: sp.spmatrix, b: np.ndarray, locs: np.ndarray, comp: np.ndarray):
    """Solve the condensed FE system ``A`` (the full symmetric matrix), returning
    ``(x, solver, iterations)``: AMG-CG above :data:`FE_AMG_ENTRIES` stored entries (the
    direct solve if it does not converge), else
    SuperLU in symmetric mode with its minimum-degree ordering on ``A^T + A`` (on the
    beam example's P2 systems half the fill and half the time of a nested dissection of
    the dof locations: 8.2e6 against 1.8e7 factor entries at 5.7e4 dof)."""
    import scipy.sparse as sp

    A = sp.csr_matrix(A)
    if A.nnz > FE_AMG_ENTRIES:
        x, its = _solve_amg(A, b, locs, comp)
        if x is not None:
            return x, "amg-cg", its
    lu = DirectSolver(A)
    if lu.negative_pivots:
        raise SingularError("the FE stiffness is not positive definite: check the supports")
    x, info = lu.solve(b)
    # a slender body is ill-conditioned, not singular: judge the solve by its backward
    # error, after one step of iterative refinement (a 10 x 0.5 strip at h = 0.05, P2:
    # relative residual 1.9e-8 before it)
    for _ in range(2):
        if _good(x, info):
            return x, "direct", info.iterations
        dx, _ = lu.solve(b - A @ x)
        x = x + dx
        r = b - A @ x
        nb = float(np.linalg.norm(b)) or 1.0
        nr = float(np.linalg.norm(r))
        info = SolveRecord(0, [nr / nb], nr / (_norm1(A) * float(np.linalg.norm(x)) + nb))
    if not _good(x, info):
        raise SingularError(
            f"FE solve failed (relative residual {info.residuals[-1]:.2e}, backward error "
            f"{info.backward_error:.2e}): the FE system is singular"
        )
    return x, "direct", info.iterations


def _solve_amg(A: sp.spmatrix, b: np.ndarray, locs: np.ndarray, comp: np.ndarray):
    """AMG-CG with the three rigid-body modes of the dofs at ``locs`` (n, 2) with
    components ``comp`` (n,): the solution (None if CG does not reach
    :data:`FE_CG_RTOL`, e.g. for a nearly incompressible material, so that the caller
    solves directly) and the iterations."""
    B = np.zeros((A.shape[0], 3))
    x_, y_ = comp == 0, comp == 1
    B[x_, 0], B[y_, 1] = 1.0, 1.0
    B[x_, 2], B[y_, 2] = -locs[x_, 1], locs[y_, 0]
    amg = AMGSolver(A, B)
    x, info = amg.solve(b, rtol=FE_CG_RTOL, maxiter=1000)
    if info.residuals[-1] <= FE_CG_RTOL and np.all(np.isfinite(x)):
        log.info("FE AMG-CG: %d iterations", info.iterations)
        return x, info.iterations
    log.info("FE AMG-CG stalled at %.1e: solving directly", info.residuals[-1])
    return None, info.iterations


def _good(x: np.ndarray, info: SolveRecord) -> bool:
    """A finite solution with a small residual, or a backward error at rounding level."""
    if not np.all(np.isfinite(x)):
        return False
    backward = np.inf if np.isnan(info.backward_error) else info.backward_error
    return info.residuals[-1] <= 1e-8 or backward <= 1e-13


def _norm1(A) -> float:
    return float(abs(A).sum(axis=0).max())
