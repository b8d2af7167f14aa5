"""Solving with a damaged stiffness: one factorisation, low-rank updates on top of it.

Damage changes the 3x3 bond matrices ``Q_T`` of a few triangles per event, so the
constrained stiffness is ``A = A0 + U C U^T``: ``A0`` the factorised base, ``U`` the
elongation gradients of the changed triangles (three columns each, constrained rows
zeroed) and ``C`` the block diagonal of their ``Q_T - Q_T^0``. The Woodbury identity in
its capacitance form (no inverse of ``C`` needed, so a broken bond's rank-deficient
change is fine)::

    A^-1 b = y - Z (I + C W)^-1 C U^T y,   y = A0^-1 b,  Z = A0^-1 U,  W = U^T Z.

``Z`` gets three columns when a triangle is first touched (one multi-right-hand-side
triangular solve); later teeth of the same triangle only change ``C``. Once the rank
passes ``max_rank`` the current matrix is factorised afresh and becomes the base.
Every solution is checked against the current matrix and refined (up to three steps)
until its relative residual is below ``tol``.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ..linalg import ConstrainedSystem, DirectSolver
from ..mesh import mesh_dof_order

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
        Refactorise when the update has more columns (0: refactorise every change).
    """

    def __init__(self, mesh, split, dofs, values, f, max_rank: int = 240):
        self.mesh, self.split = mesh, split
        self.dofs, self.values, self.f = dofs, values, f
        self.max_rank = int(max_rank)
        self.free = np.ones(2 * mesh.n_points, dtype=bool)
        self.free[dofs] = False
        self.uc = np.zeros(2 * mesh.n_points)
        self.uc[dofs] = values
        self.factorisations = 0
        self.factor_seconds = 0.0
        self._z = np.empty((len(self.free), 0))
        self._order = mesh_dof_order(mesh)

    # ------------------------------------------------------------ base
    def rebase(self, w: np.ndarray, g: np.ndarray) -> None:
        """Factorise the stiffness of ``w, g`` and make it the base."""
        t0 = time.perf_counter()
        self.w0, self.g0 = w.copy(), g.copy()
        self.K0 = self.split.stiffness(self.mesh, w, g)  # BSR, as ConstrainedSystem takes it
        self.system = ConstrainedSystem(self.K0, self.dofs)
        self.engine = DirectSolver(self.system.A, order=self._order)
        self.touched: set[int] = set()
        self.tris = np.zeros(0, dtype=np.int64)
        # the buffers grow (doubling, up to max_rank + 12 columns) as triangles are touched
        if self._z.shape[1] == 0:
            self._z = np.empty((len(self.free), 48))
            self._w = np.empty((48, 48))
        self._u_cols = None
        self._y0: dict[str, tuple] = {}  # A0^-1 b for each unchanged right-hand side
        self.floor = 0.0  # the residual a direct solve reached where it missed tol
        self.factorisations += 1
        self.factor_seconds += time.perf_counter() - t0

    @property
    def rank(self) -> int:
        return 3 * len(self.tris)

    def _columns(self, tris: np.ndarray):
        """U's columns for triangles ``tris``: sparse (2N, 3 len(tris)), constrained rows 0."""
        import scipy.sparse as sp

        b = self.split.b[tris] * self.free[self.split.dofs[tris]][:, None, :]  # (t, 3, 6)
        rows = np.broadcast_to(self.split.dofs[tris][:, None, :], b.shape).ravel()
        cols = np.broadcast_to(np.arange(3 * len(tris)).reshape(-1, 3, 1), b.shape).ravel()
        return sp.csc_matrix((b.ravel(), (rows, cols)), shape=(len(self.free), 3 * len(tris)))

    def touch(self, tris: np.ndarray) -> None:
        """Make triangles ``tris`` part of the update (new columns of Z and W)."""
        import scipy.sparse as sp

        new = np.array([t for t in np.unique(tris) if int(t) not in self.touched], dtype=np.int64)
        if new.size == 0:
            return
        self.touched.update(int(t) for t in new)
        r_old = self.rank
        self.tris = np.concatenate([self.tris, new])
        r = self.rank
        if r > self._z.shape[1]:
            cap = max(r, min(2 * self._z.shape[1], self.max_rank + 12))
            z = np.empty((len(self.free), cap))
            z[:, :r_old] = self._z[:, :r_old]
            w = np.empty((cap, cap))
            w[:r_old, :r_old] = self._w[:r_old, :r_old]
            self._z, self._w = z, w
        u_new = self._columns(new)
        zn = self.engine.apply(u_new.toarray())
        u_all = u_new if self._u_cols is None else sp.hstack([self._u_cols, u_new], format="csc")
        wn = u_all.T @ zn  # (rank, 3 len(new)): W is symmetric as A0 is
        self._z[:, r_old:r] = zn
        self._w[:r, r_old:r] = wn
        self._w[r_old:r, :r_old] = wn[:r_old].T
        self._u_cols = u_all

    @property
    def Z(self) -> np.ndarray:
        return self._z[:, : self.rank]

    @property
    def W(self) -> np.ndarray:
        return self._w[: self.rank, : self.rank]

    # ------------------------------------------------------------ solve
    def _capacitance(self, w, g) -> np.ndarray:
        t = self.tris
        return self.split.q(w, g, t) - self.split.q(self.w0, self.g0, t)

    def apply_matrix(self, x: np.ndarray, w, g) -> np.ndarray:
        """The current constrained matrix times ``x``."""
        y = self.system.A @ x
        if self.rank:
            c = self._capacitance(w, g)
            ut = (self._u_cols.T @ x).reshape(-1, 3)
            y = y + self._u_cols @ np.einsum("tij,tj->ti", c, ut).ravel()
        return y

    def delta_full(self, x: np.ndarray, w, g) -> np.ndarray:
        """``(K - K0) x`` on all dofs (constrained rows included)."""
        sp_, t = self.split, self.tris
        elong = np.einsum("tkj,tj->tk", sp_.b[t], x[sp_.dofs[t]])
        fq = np.einsum("tkl,tl->tk", self._capacitance(w, g), elong)
        fe = np.einsum("tkj,tk->tj", sp_.b[t], fq)
        return np.bincount(sp_.dofs[t].ravel(), fe.ravel(), len(x))

    def rhs(self, w, g, f=None) -> np.ndarray:
        """Right-hand side of the current matrix: forces minus the prescribed motion; or,
        with ``f``, the forces ``f`` with the constrained dofs held at zero."""
        if f is not None:
            b = np.array(f, dtype=float)
            b[self.dofs] = 0.0
            return b
        b = self.f - self.K0 @ self.uc
        if self.rank and np.any(self.values):
            b -= self.delta_full(self.uc, w, g)
        b[self.dofs] = self.system.diag_value * self.values
        return b

    def _woodbury(self, b: np.ndarray, w, g, y=None) -> np.ndarray:
        y = self.engine.apply(b) if y is None else y
        if not self.rank:
            return y
        c = self._capacitance(w, g)
        cb = np.zeros((self.rank, self.rank))
        i = 3 * np.arange(len(self.tris))[:, None, None]
        cb[i + np.arange(3)[:, None], i + np.arange(3)[None, :]] = c
        uy = self._u_cols.T @ y
        small = np.eye(self.rank) + cb @ self.W
        return y - self.Z @ np.linalg.solve(small, cb @ uy)

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
        if self.rank > self.max_rank:
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
