"""Linear solvers for Newton tangents on one process: factor once per Newton
iteration, apply as often as needed (the Newton step and the line-search test).

* :class:`DirectTangent`: sparse LU (nested dissection); its inertia tells stability.
* :class:`AMGTangent`: GMRES preconditioned with a smoothed-aggregation hierarchy built
  on the symmetric part of a tangent and reused while it keeps working; a direct
  solve when GMRES fails.
"""

from __future__ import annotations

import logging
from typing import Protocol

import numpy as np

from ..linalg import AMGSolver, ConstrainedSystem, DirectSolver, rigid_modes
from ..mesh import Mesh, mesh_dof_order

log = logging.getLogger(__name__)

__all__ = ["TangentSolver", "DirectTangent", "AMGTangent", "tangent_solver"]


class TangentSolver(Protocol):
    """Factor a constrained tangent, then solve with it."""

    builds: int
    negative_pivots: int | None

    def factor(self, system: ConstrainedSystem) -> None: ...

    def solve(self, b: np.ndarray) -> tuple[np.ndarray, int]: ...


class DirectTangent:
    """Sparse LU of every tangent."""

    def __init__(self, mesh: Mesh):
        self.mesh = mesh
        self.builds = 0
        self.negative_pivots: int | None = None
        self.lu: DirectSolver | None = None

    def factor(self, system: ConstrainedSystem) -> None:
        self.lu = DirectSolver(system.A, order=mesh_dof_order(self.mesh))
        self.builds += 1
        self.negative_pivots = self.lu.negative_pivots

    def solve(self, b: np.ndarray) -> tuple[np.ndarray, int]:
        x, _ = self.lu.solve(b)
        return x, 0


class AMGTangent:
    """GMRES + AMG on the symmetric part, rebuilt when it stops working."""

    def __init__(self, mesh: Mesh, linear_rtol: float = 1e-10, maxiter: int = 300):
        self.mesh = mesh
        self.linear_rtol = linear_rtol
        self.restart = min(60, maxiter)
        self.cycles = max(1, -(-maxiter // self.restart))  # restart cycles: >= maxiter its
        self.builds = 0
        self.negative_pivots: int | None = None
        self.amg: AMGSolver | None = None
        self.baseline: int | None = None
        self.system: ConstrainedSystem | None = None
        self.direct: DirectTangent | None = None

    def factor(self, system: ConstrainedSystem) -> None:
        self.system = system
        self.direct = None
        self.negative_pivots = None

    def solve(self, b: np.ndarray) -> tuple[np.ndarray, int]:
        if self.direct is not None:
            return self.direct.solve(b)
        A = self.system.A
        if self.amg is None:
            self._build()
        x, its, ok = self._gmres(A, b)
        if not ok or (self.baseline is not None and its > 3 * self.baseline + 5):
            # the hierarchy no longer fits the tangent: rebuild on the current one
            self._build()
            x, its, ok = self._gmres(A, b)
        if not ok:
            log.info("GMRES+AMG failed on the tangent; falling back to a direct solve")
            self.direct = DirectTangent(self.mesh)
            self.direct.factor(self.system)
            self.builds += 1
            self.negative_pivots = self.direct.negative_pivots
            return self.direct.solve(b)
        if self.baseline is None:
            self.baseline = its
        return x, its

    def _build(self) -> None:
        import scipy.sparse as sp

        A = self.system.A
        sym = (A + A.T) * 0.5
        self.amg = AMGSolver(sp.bsr_matrix(sym, blocksize=(2, 2)), rigid_modes(self.mesh.points))
        self.builds += 1

    def _gmres(self, A, b):
        import scipy.sparse.linalg as spla

        count = [0]

        def cb(_):
            count[0] += 1

        if not np.any(b):
            return np.zeros_like(b), 0, True
        x, status = spla.gmres(
            A,
            b,
            rtol=self.linear_rtol,
            atol=0.0,
            M=self.amg.ml.aspreconditioner(),
            restart=self.restart,
            maxiter=self.cycles,
            callback=cb,
            callback_type="pr_norm",
        )
        ok = status == 0 and np.all(np.isfinite(x))
        if ok:
            true = np.linalg.norm(A @ x - b) / (np.linalg.norm(b) or 1.0)
            ok = true <= max(100 * self.linear_rtol, 1e-12)
        return x, count[0], ok


def tangent_solver(kind: str, mesh: Mesh, rtol: float = 1e-10, maxiter: int = 300) -> TangentSolver:
    """The tangent solver of a linear solver name (``direct`` or ``amg``; the options
    ``rtol`` and ``maxiter`` of GMRES+AMG, as the PETSc engine's Newton honours them)."""
    return DirectTangent(mesh) if kind == "direct" else AMGTangent(mesh, rtol, maxiter)
