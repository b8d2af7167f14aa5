"""Solving with a damaged stiffness: one factorisation, low-rank updates on top of it.

Damage changes the 3x3 bond matrices ``Q_T`` of a few triangles per event, so the
constrained stiffness changes only in the rows and columns of those triangles' free
dofs ``S``: ``A = A0 + E_S C E_S^T``, ``A0`` the factorised base, ``E_S`` the unit
columns of ``S`` and ``C`` (``|S| x |S|``) the sum of the changed triangles'
``B_T^T (Q_T - Q_T^0) B_T``. The Woodbury identity in its capacitance form (no inverse
of ``C`` needed, so a broken bond's rank-deficient change is fine)::

    A^-1 b = y - Z (I + C W)^-1 C y_S,   y = A0^-1 b,  Z = A0^-1 E_S,  W = Z_S.

``Z`` gets two columns for every node a touched triangle brings into ``S`` (one
multi-right-hand-side triangular solve): along a crack path that is one node, two
columns, per new triangle (three columns per triangle when the columns were the
triangles' bond elongations); later teeth of the same triangle only change ``C``.
``Z`` is kept transposed (a row per dof of ``S``), so a new column is written where it
lies. Once ``|S|`` passes ``max_rank`` the current matrix is factorised afresh and
becomes the base. Every solution is checked against the current matrix and refined (up
to three steps) until its relative residual is below ``tol``.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING

import numpy as np

from ..linalg import ConstrainedSystem, DirectSolver
from ..mesh import mesh_dof_order

if TYPE_CHECKING:
    from .criteria.responses import Factorised

log = logging.getLogger(__name__)

__all__ = ["UpdatedSolver", "FLOOR_FACTOR", "FLOOR_CAP"]

#: after a fresh factorisation missed the tolerance (residual ``floor``), an update is
#: refactorised only when it misses ``FLOOR_FACTOR * floor``, and always above
#: ``FLOOR_CAP`` (a tenth of the residual at which fracture stops)
FLOOR_FACTOR = 10.0
FLOOR_CAP = 1e-7


class UpdatedSolver:
    """``A(w, g) x = b`` for a damaged lattice, with factorisation updates.

    Parameters
    ----------
    mesh : Mesh
    split : TriangleSplit
    dofs, values : ndarray
        Constrained dofs and their prescribed values (per unit load factor).
    f : ndarray, shape (2N,)
        External forces per unit load factor.
    max_rank : int
        Refactorise when the update has more columns (free dofs of touched triangles;
        0: refactorise every change).
    """

    def __init__(self, mesh, split, dofs, values, f, max_rank: int = 240):
        self.mesh, self.split = mesh, split
        self.dofs, self.values, self.f = dofs, values, f
        self.max_rank = int(max_rank)
        n = 2 * mesh.n_points
        self.free = np.ones(n, dtype=bool)
        self.free[dofs] = False
        self.uc = np.zeros(n)
        self.uc[dofs] = values
        self.factorisations = 0
        self.factor_seconds = 0.0
        self.columns_solved = 0  # columns of A0^-1 computed for S
        self._zt = np.empty((0, n))
        self._order = mesh_dof_order(mesh)

    # ------------------------------------------------------------ base
    def rebase(self, w: np.ndarray, g: np.ndarray, factorised: Factorised | None = None):
        """Make the stiffness of ``w, g`` the base: factorise it, or take ``factorised``,
        that stiffness with the same prescribed dofs factorised already (the criterion's
        uniform-stress responses solved with it)."""
        t0 = time.perf_counter()
        self.w0, self.g0 = w.copy(), g.copy()
        if factorised is not None and not _undamaged(self.split, w, g, factorised, self.dofs):
            log.debug("the given factorisation is not of this stiffness: factorising afresh")
            factorised = None
        if factorised is None:
            self.K0 = self.split.stiffness(self.mesh, w, g)  # BSR, as ConstrainedSystem takes
            self.system = ConstrainedSystem(self.K0, self.dofs)
            self.engine = DirectSolver(self.system.A, order=self._order)
        else:  # (its time counts in the strengths' setup)
            self.K0, self.system, self.engine = factorised[1:]
        self._b0 = self.f - self.K0 @ self.uc  # forces minus the base's prescribed motion
        self._k0_rows = self.K0.tocsr()[self.dofs]  # the base's rows of the prescribed dofs
        self.touched: set[int] = set()
        self.tris = np.zeros(0, dtype=np.int64)
        self.cols = np.zeros(0, dtype=np.int64)  # S, in the order of Z's rows
        self.pos = np.full(len(self.free), -1, dtype=np.int64)  # dof -> row of Z (or -1)
        self._w = None  # W for the current S (kept until S grows)
        self._y0: dict[str, tuple] = {}  # A0^-1 b for each unchanged right-hand side
        self.floor = 0.0  # the residual a direct solve reached where it missed tol
        self.stale = False  # a touch passed max_rank: the next solve factorises afresh
        self.factorisations += 1  # (an adopted factorisation counts: the run's first)
        self.factor_seconds += time.perf_counter() - t0

    @property
    def rank(self) -> int:
        return len(self.cols)

    @property
    def changed(self) -> bool:
        """Whether any triangle differs from the base (its dofs may all be prescribed)."""
        return bool(len(self.tris))

    def touch(self, tris: np.ndarray) -> None:
        """Make triangles ``tris`` part of the update (new rows of Z for their new dofs).
        Where the update would pass ``max_rank`` columns, nothing is solved: the next
        :meth:`solve` factorises the current matrix afresh."""
        new = np.array([t for t in np.unique(tris) if int(t) not in self.touched], dtype=np.int64)
        if new.size == 0:
            return
        self.touched.update(int(t) for t in new)
        self.tris = np.concatenate([self.tris, new])
        d = np.unique(self.split.dofs[new].ravel())
        d = d[self.free[d] & (self.pos[d] < 0)]
        if d.size == 0:
            return
        r_old, r = self.rank, self.rank + len(d)
        if r > self.max_rank:
            self.stale = True
            return
        if r > len(self._zt):  # the buffer doubles, up to max_rank rows
            zt = np.empty((max(r, min(2 * len(self._zt), self.max_rank), 48), len(self.free)))
            zt[:r_old] = self._zt[:r_old]
            self._zt = zt
        e = np.zeros((len(self.free), len(d)))
        e[d, np.arange(len(d))] = 1.0
        self._zt[r_old:r] = self.engine.apply(e).T
        self.columns_solved += len(d)
        self.pos[d] = np.arange(r_old, r)
        self.cols = np.concatenate([self.cols, d])
        self._w = None

    @property
    def Z(self) -> np.ndarray:
        """``A0^-1 E_S`` (2N, rank), a view of the transposed buffer."""
        return self._zt[: self.rank].T

    @property
    def W(self) -> np.ndarray:
        """``Z_S`` (rank, rank): the base's inverse on the touched dofs."""
        if self._w is None:
            self._w = self._zt[: self.rank][:, self.cols]
        return self._w

    # ------------------------------------------------------------ solve
    def _dq(self, w, g) -> np.ndarray:
        """``Q_T - Q_T^0`` (t, 3, 3) of the touched triangles."""
        t = self.tris
        return self.split.q(w, g, t) - self.split.q(self.w0, self.g0, t)

    def _capacitance(self, w, g) -> np.ndarray:
        """``C`` (rank, rank): the touched triangles' change of stiffness on ``S``."""
        sp_, t = self.split, self.tris
        ke = np.einsum("tki,tkl,tlj->tij", sp_.b[t], self._dq(w, g), sp_.b[t])  # (t, 6, 6)
        p = self.pos[sp_.dofs[t]]  # (t, 6), -1 at constrained dofs
        keep = (p[:, :, None] >= 0) & (p[:, None, :] >= 0)
        r = self.rank
        flat = (p[:, :, None] * r + p[:, None, :])[keep]
        return np.bincount(flat, ke[keep], r * r).reshape(r, r)

    def apply_matrix(self, x: np.ndarray, w, g) -> np.ndarray:
        """The current constrained matrix times ``x``."""
        y = self.system.A @ x
        if self.rank:
            y[self.cols] += self._capacitance(w, g) @ x[self.cols]
        return y

    def delta_full(self, x: np.ndarray, w, g) -> np.ndarray:
        """``(K - K0) x`` on all dofs (constrained rows included)."""
        sp_, t = self.split, self.tris
        elong = np.einsum("tkj,tj->tk", sp_.b[t], x[sp_.dofs[t]])
        fq = np.einsum("tkl,tl->tk", self._dq(w, g), elong)
        fe = np.einsum("tkj,tk->tj", sp_.b[t], fq)
        return np.bincount(sp_.dofs[t].ravel(), fe.ravel(), len(x))

    def prescribed_forces(self, x: np.ndarray, w, g) -> np.ndarray:
        """``(K x)`` at the prescribed dofs (len(dofs),), for the current ``K``."""
        out = self._k0_rows @ x
        if self.changed:
            out = out + self.delta_full(x, w, g)[self.dofs]
        return out

    def rhs(self, w, g, f=None) -> np.ndarray:
        """Right-hand side of the current matrix: forces minus the prescribed motion; or,
        with ``f``, the forces ``f`` with the constrained dofs held at zero."""
        if f is not None:
            b = np.array(f, dtype=float)
            b[self.dofs] = 0.0
            return b
        b = self._b0.copy()
        if self.changed and np.any(self.values):
            b -= self.delta_full(self.uc, w, g)
        b[self.dofs] = self.system.diag_value * self.values
        return b

    def _woodbury(self, b: np.ndarray, w, g, y=None) -> np.ndarray:
        y = self.engine.apply(b) if y is None else y
        if not self.rank:
            return y
        c = self._capacitance(w, g)
        small = np.eye(self.rank) + c @ self.W
        return y - self.Z @ np.linalg.solve(small, c @ y[self.cols])

    def solve(self, w, g, tol: float = 1e-10, f=None):
        """Displacement (2N,) per unit load factor and its relative residual; with ``f``
        (2N,), the displacement under the forces ``f`` alone, the constrained dofs at 0
        (a held load).

        The update is refined up to three times; if it still misses ``tol`` (an update
        that leaves the matrix nearly singular, e.g. a node hanging on collinear bonds,
        makes the capacitance matrix ill-conditioned) the current matrix is factorised
        afresh and solved directly. Where that direct solve misses ``tol`` too (near a
        mechanism), the residual it reached is the floor until the next factorisation:
        later updates are held to :data:`FLOOR_FACTOR` times it (at most
        :data:`FLOOR_CAP`) instead of refactorising at every solve.
        """
        if self.stale:
            self.rebase(w, g)
        x, res = self._refined(w, g, tol, f)
        if res > max(tol, min(FLOOR_FACTOR * self.floor, FLOOR_CAP)) and self.rank:
            log.debug("update missed the tolerance (%.2e): refactorising", res)
            self.rebase(w, g)
            x, res = self._refined(w, g, tol, f)
            # a fresh factorisation that misses tol too: the state is near a mechanism
            # and this is what a direct solve reaches; later updates are held to it
            # instead of refactorising at every solve
            self.floor = res if res > tol else 0.0
        return x, res

    def _refined(self, w, g, tol: float, f=None):
        b = self.rhs(w, g, f)
        nb = float(np.linalg.norm(b)) or 1.0
        key = "grow" if f is None else "held"
        cached = self._y0.get(key)
        if cached is None or not np.array_equal(b, cached[0]):
            self._y0[key] = cached = (b, self.engine.apply(b))
        x = self._woodbury(b, w, g, cached[1])
        res = np.inf
        for _ in range(4):
            r = b - self.apply_matrix(x, w, g)
            res = float(np.linalg.norm(r)) / nb
            if res <= tol or not np.isfinite(res):
                break
            x = x + self._woodbury(r, w, g)
        return x, res


def _undamaged(split, w, g, factorised, dofs) -> bool:
    """Whether ``factorised`` (made from the undamaged split with prescribed ``dofs``)
    is the stiffness of ``w, g``."""
    return (
        np.array_equal(factorised.dofs, dofs)
        and np.array_equal(w, split.w)
        and np.array_equal(g, split.g)
    )
