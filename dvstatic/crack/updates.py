"""Solving with a damaged stiffness: one factorisation, low-rank updates on top of it.

Damage changes the 3x3 bond matrices ``Q_T`` of a few triangles per event, so the
constrained stiffness is ``A = A0 + U C U^T``: ``A0`` the factorised base, ``U`` the
elongation gradients of the distinct bonds of the changed triangles (a column per
bond, constrained rows zeroed) and ``C`` (bonds x bonds) the sum of the triangles'
``Q_T - Q_T^0`` on their bonds. The Woodbury identity in its capacitance form (no
inverse of ``C`` needed, so a broken bond's rank-deficient change is fine)::

    A^-1 b = y - Z (I + C W)^-1 C U^T y,   y = A0^-1 b,  Z = A0^-1 U,  W = U^T Z.

``Z`` gets a column for every bond a touched triangle brings in (one
multi-right-hand-side triangular solve): along a crack path two per new triangle, where
the triangles' own three bond columns took three, and each column a bond's dipole
(columns of unit dofs, two per new node, are as few but are the Green's functions of
point forces, whose far fields cancel in the correction: their solutions' residuals
came out 10-100 times larger); later teeth of the same triangle only change ``C``.
``Z`` is kept transposed (a row per bond), so a new column is written where it lies.
Once the update passes ``max_rank`` columns the current matrix is factorised afresh
and becomes the base. Every solution is checked against the current matrix and refined
(up to three steps) until its relative residual is below ``tol``.
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
        #: negative eigenvalues of the base (its LDL inertia: 0 for a stable lattice)
        self.negative = int(self.engine.negative_pivots or 0)
        self._b0 = self.f - self.K0 @ self.uc  # forces minus the base's prescribed motion
        self._k0_rows = self.K0.tocsr()[self.dofs]  # the base's rows of the prescribed dofs
        self.touched: set[int] = set()
        self.tris = np.zeros(0, dtype=np.int64)
        self.bonds = np.zeros(0, dtype=np.int64)  # the update's bonds, Z's rows
        self.pos = np.full(self.split.n_bonds, -1, dtype=np.int64)  # bond -> row (or -1)
        self._u = None  # U, (2N, rank) CSC
        self._y0: dict[str, tuple] = {}  # A0^-1 b for each unchanged right-hand side
        self.floor = 0.0  # the residual a direct solve reached where it missed tol
        self.stale = False  # a touch passed max_rank: the next solve factorises afresh
        self.factorisations += 1  # (an adopted factorisation counts: the run's first)
        self.factor_seconds += time.perf_counter() - t0

    @property
    def rank(self) -> int:
        return len(self.bonds)

    @property
    def changed(self) -> bool:
        """Whether any triangle differs from the base (its dofs may all be prescribed)."""
        return bool(len(self.tris))

    def touch(self, tris: np.ndarray) -> None:
        """Make triangles ``tris`` part of the update (new columns of Z for their new
        bonds). Where the update would pass ``max_rank`` columns, nothing is solved: the
        next :meth:`solve` factorises the current matrix afresh."""
        import scipy.sparse as sp

        new = np.array([t for t in np.unique(tris) if int(t) not in self.touched], dtype=np.int64)
        if new.size == 0:
            return
        self.touched.update(int(t) for t in new)
        self.tris = np.concatenate([self.tris, new])
        bonds, first = np.unique(self.split.tri_bonds[new].ravel(), return_index=True)
        fresh = self.pos[bonds] < 0
        bonds, first = bonds[fresh], first[fresh]
        if bonds.size == 0:
            return
        r_old, r = self.rank, self.rank + len(bonds)
        if r > self.max_rank:
            self.stale = True
            return
        self._room(r)
        u_new = self._columns(new[first // 3], first % 3)
        zn = self.engine.apply_columns(u_new, out=self._zt[r_old:r])  # (new, 2N)
        self.columns_solved += len(bonds)
        u_all = u_new if self._u is None else sp.hstack([self._u, u_new], format="csc")
        wn = (zn @ u_all).T  # (r, new): W is symmetric as A0 is
        self._wb[:r, r_old:r] = wn
        self._wb[r_old:r, :r_old] = wn[:r_old].T
        self._u = u_all
        self.pos[bonds] = np.arange(r_old, r)
        self.bonds = np.concatenate([self.bonds, bonds])

    def _room(self, r: int) -> None:
        """Room for ``r`` columns: the buffers of ``max_rank`` columns, made once (the
        memory of a row is only taken when it is written); where the system will not
        map that much at once, buffers that double as they fill (copied)."""
        if r <= len(self._zt):
            return
        rank = self.rank
        try:
            zt = _lazy_rows(self.max_rank, len(self.free))
        except MemoryError:
            zt = np.empty((max(r, min(2 * len(self._zt), self.max_rank), 48), len(self.free)))
        zt[:rank] = self._zt[:rank]
        wb = np.empty((len(zt), len(zt)))
        if rank:
            wb[:rank, :rank] = self._wb[:rank, :rank]
        self._zt, self._wb = zt, wb

    def _columns(self, tri: np.ndarray, k: np.ndarray):
        """U's columns (2N, len(tri)) CSC: the elongation gradients of the local edges
        ``k`` of triangles ``tri``, constrained rows 0."""
        import scipy.sparse as sp

        dofs = self.split.dofs[tri]  # (n, 6)
        vals = self.split.b[tri, k] * self.free[dofs]
        cols = np.repeat(np.arange(len(tri)), 6)
        return sp.csc_matrix((vals.ravel(), (dofs.ravel(), cols)), shape=(len(self.free), len(tri)))

    @property
    def Z(self) -> np.ndarray:
        """``A0^-1 U`` (2N, rank), a view of the transposed buffer."""
        return self._zt[: self.rank].T

    @property
    def W(self) -> np.ndarray:
        """``U^T A0^-1 U`` (rank, rank)."""
        return self._wb[: self.rank, : self.rank]

    # ------------------------------------------------------------ solve
    def _dq(self, w, g) -> np.ndarray:
        """``Q_T - Q_T^0`` (t, 3, 3) of the touched triangles."""
        t = self.tris
        return self.split.q(w, g, t) - self.split.q(self.w0, self.g0, t)

    def _capacitance(self, w, g) -> np.ndarray:
        """``C`` (rank, rank): the touched triangles' ``Q_T - Q_T^0`` on their bonds."""
        p = self.pos[self.split.tri_bonds[self.tris]]  # (t, 3), every bond in the update
        r = self.rank
        flat = (p[:, :, None] * r + p[:, None, :]).ravel()
        return np.bincount(flat, self._dq(w, g).ravel(), r * r).reshape(r, r)

    def apply_matrix(self, x: np.ndarray, w, g) -> np.ndarray:
        """The current constrained matrix times ``x``."""
        y = self.system.A @ x
        if self.rank:
            y = y + self._u @ (self._capacitance(w, g) @ (self._u.T @ x))
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
        return y - self.Z @ np.linalg.solve(small, c @ (self._u.T @ y))

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


def _lazy_rows(rows: int, cols: int) -> np.ndarray:
    """An uninitialised (rows, cols) float array whose memory is taken as it is written,
    in plain pages (Linux: an anonymous map advised ``MADV_NOHUGEPAGE``). numpy advises
    huge pages for its large arrays, and where the kernel compacts memory to find one at
    the first write (``defrag`` on ``madvise``, as here) a new column of ``Z`` cost 3.6 ms
    of page faults at 96,471 nodes against 1.5 ms in plain pages (the same map advised
    huge pages: 3.7 ms)."""
    import mmap

    try:
        buf = mmap.mmap(-1, rows * cols * 8, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    except (AttributeError, ValueError):  # no such map here
        return np.empty((rows, cols))
    except OSError as exc:  # (strict overcommit: not that much at once)
        raise MemoryError(str(exc)) from None
    try:
        buf.madvise(mmap.MADV_NOHUGEPAGE)
    except (AttributeError, OSError):  # no such advice here: the map serves as it is
        pass
    return np.frombuffer(buf, dtype=float).reshape(rows, cols)


def _undamaged(split, w, g, factorised, dofs) -> bool:
    """Whether ``factorised`` (made from the undamaged split with prescribed ``dofs``)
    is the stiffness of ``w, g``."""
    return (
        np.array_equal(factorised.dofs, dofs)
        and np.array_equal(w, split.w)
        and np.array_equal(g, split.g)
    )
