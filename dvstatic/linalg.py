"""Sparse linear algebra for lattice and FE systems (no dependency on meshes).

Solver objects follow pyamg's pattern: build once (factorisation or AMG hierarchy),
then ``solve(b)`` any number of times, each returning the solution and a record with
its residual history. Supports are imposed by symmetric elimination that keeps the
2x2 block structure: constrained rows and columns are replaced by a scaled identity
and their coupling moved to the right-hand side. :func:`nested_dissection` gives the
fill-reducing order of direct factorisations.

SuperLU's built-in minimum-degree ordering is fast on regular lattices but became
pathologically slow on jittered meshes of 1e5 nodes (79 s instead of 3 s for the
same factor size). Nested dissection by recursive coordinate bisection needs only the
node coordinates and the bonds, costs a fraction of a second per 1e5 nodes, and gives
the optimal O(N log N) fill order for 2-D meshes.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .errors import InputError, SingularError, SolverError

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = [
    "SolveRecord",
    "rigid_modes",
    "check_restrained",
    "ConstrainedSystem",
    "DirectSolver",
    "AMGSolver",
    "SolverError",
    "nested_dissection",
    "AMG_OPTIONS",
    "AUTO_DIRECT_MAX_DOF",
]


@dataclass(frozen=True)
class SolveRecord:
    """What one linear solve of :class:`DirectSolver` or :class:`AMGSolver` reports.

    Attributes
    ----------
    iterations : int
        CG iterations, or the direct solver's refinement steps.
    residuals : list of float
        Relative residual history (the last one recomputed from ``A x - b``).
    backward_error : float
        Normwise backward error (direct solves; NaN otherwise).
    indefinite : bool
        CG met a direction of non-positive curvature (AMG solves).
    """

    iterations: int
    residuals: list
    backward_error: float = float("nan")
    indefinite: bool = False

    def __getitem__(self, key: str):  # the dict these records were
        if key not in self.__dataclass_fields__:
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default=None):
        return getattr(self, key) if key in self.__dataclass_fields__ else default


#: pyamg smoothed-aggregation settings, each measured against pyamg's defaults on the DV
#: stiffness at 1e6 nodes (2e6 dof), in units of one matrix-vector product with K
#: (validation/bench_amg.py): defaults 358 (set-up) + 788 (26 CG iterations) = 1146;
#: strength threshold 0.05 halves the iterations (13; 756 in all, together with the two
#: set-up savings below); one forward Gauss-Seidel sweep before and one backward after
#: (a symmetric V-cycle for CG) instead of two symmetric sweeps: 598; block-diagonal
#: weighting of the prolongation smoother instead of a Krylov spectral-radius estimate on
#: every level: 559 (0.49 of the defaults).
AMG_OPTIONS = dict(
    symmetry="hermitian",
    strength=("symmetric", {"theta": 0.05}),
    smooth=("jacobi", {"omega": 4.0 / 3.0, "weighting": "block"}),
    presmoother=("block_gauss_seidel", {"sweep": "forward"}),
    postsmoother=("block_gauss_seidel", {"sweep": "backward"}),
    improve_candidates=None,  # the rigid-body modes are exact near-null vectors already
    max_coarse=500,
    coarse_solver="splu",  # sparse LU instead of a dense pseudo-inverse of the coarse level
)
#: ``solver="auto"`` uses a sparse direct factorisation up to this many dofs, AMG above.
AUTO_DIRECT_MAX_DOF = 200_000


def rigid_modes(points: np.ndarray) -> np.ndarray:
    """The three rigid-body modes on interleaved dofs, shape (2N, 3).

    Columns: translation x, translation y, rotation about the centroid (scaled by
    the mesh size so all three columns have comparable norms).
    """
    x = np.asarray(points, dtype=float)
    c = x.mean(axis=0)
    scale = max(float(np.max(np.ptp(x, axis=0))), np.finfo(float).tiny)
    b = np.zeros((2 * len(x), 3))
    b[0::2, 0] = 1.0
    b[1::2, 1] = 1.0
    b[0::2, 2] = -(x[:, 1] - c[1]) / scale
    b[1::2, 2] = (x[:, 0] - c[0]) / scale
    return b


def check_restrained(points: np.ndarray, dofs: np.ndarray) -> None:
    """Raise :class:`~dvstatic.errors.InputError` (``param="supports"``) if the
    constrained dofs leave a rigid-body motion free."""
    if dofs.size == 0:
        raise InputError(
            "no supports: the body can translate and rotate freely; add Fix supports "
            "that prevent rigid-body motion (e.g. Fix('left', x=0) and Fix('bottom', y=0))",
            "supports",
        )
    b = rigid_modes(points)[dofs]
    _, s, vt = np.linalg.svd(b, full_matrices=True)
    s = np.concatenate([s, np.zeros(3 - len(s))])
    if s[-1] > 1e-8 * max(s[0], 1e-300):
        return
    tx, ty, w = vt[-1]
    x = np.asarray(points)
    c = x.mean(axis=0)
    scale = float(np.max(np.ptp(x, axis=0)))
    if abs(w) < 1e-8:
        what = f"translation along ({tx:.3g}, {ty:.3g})"
    else:
        px, py = c[0] - ty * scale / w, c[1] + tx * scale / w
        what = f"rotation about ({px:.4g}, {py:.4g})"
    raise InputError(
        f"the supports do not prevent rigid-body motion ({what} is free; the system is "
        "singular); add supports that restrain it",
        "supports",
    )


@dataclass
class ConstrainedSystem:
    """K with prescribed dofs eliminated symmetrically (block structure kept).

    Parameters
    ----------
    K : scipy.sparse.bsr_matrix, shape (n, n), blocksize (2, 2)
    dofs : ndarray of int
        Constrained dofs.
    """

    K: sp.bsr_matrix
    dofs: np.ndarray
    A: sp.bsr_matrix = field(init=False)
    diag_value: float = field(init=False)

    def __post_init__(self) -> None:
        import scipy.sparse as sp

        K = self.K
        n = K.shape[0]
        mask = np.zeros(n, dtype=bool)
        mask[self.dofs] = True
        nb = K.shape[0] // 2
        brow = np.repeat(np.arange(nb), np.diff(K.indptr))
        data = K.data.copy()
        rows = 2 * brow[:, None, None] + np.arange(2)[None, :, None]
        cols = 2 * K.indices[:, None, None] + np.arange(2)[None, None, :]
        kill = mask[rows] | mask[cols]
        free_diag = K.diagonal()[~mask]
        self.diag_value = float(np.mean(np.abs(free_diag))) if free_diag.size else 1.0
        data[kill] = 0.0
        is_diag_block = brow == K.indices
        for c in range(2):
            sel = is_diag_block & mask[2 * brow + c]
            data[sel, c, c] = self.diag_value
        self.A = sp.bsr_matrix((data, K.indices, K.indptr), shape=K.shape)
        self.mask = mask

    def rhs(self, f: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Right-hand side for loads ``f`` (n,) and prescribed ``values`` (k,)."""
        uc = np.zeros(self.K.shape[0])
        uc[self.dofs] = values
        b = f - self.K @ uc
        b[self.dofs] = self.diag_value * values
        return b


class DirectSolver:
    """Sparse LU factorisation (SuperLU) with a fill-reducing ordering.

    With ``symmetric=True`` (the default; the lattice stiffness is symmetric)
    SuperLU runs in symmetric mode with preference for diagonal pivots; when the
    row and column permutations come out equal the factorisation is an LDL^T in
    disguise and :attr:`negative_pivots` is the number of negative eigenvalues of
    ``A`` (Sylvester's law of inertia), a free stability check.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
    symmetric : bool
    order : ndarray of int, shape (n,), optional
        Symmetric fill-reducing permutation (e.g. from :func:`nested_dissection`);
        without it SuperLU's minimum-degree ordering on ``A^T + A`` is used.

    Raises
    ------
    SingularError
        The matrix is exactly singular.
    """

    name = "direct"

    def __init__(self, A: sp.spmatrix, symmetric: bool = True, order: np.ndarray | None = None):
        import scipy.sparse as sp
        import scipy.sparse.linalg as spla

        t0 = time.perf_counter()
        opts: dict = {"permc_spec": "MMD_AT_PLUS_A"}
        if symmetric:
            opts.update(diag_pivot_thresh=1e-3, options=dict(SymmetricMode=True))
        self.order = order
        Ap = sp.csr_matrix(A)
        if order is not None:
            Ap = Ap[order][:, order]
            opts["permc_spec"] = "NATURAL"
        try:
            self.lu = spla.splu(sp.csc_matrix(Ap), **opts)
        except RuntimeError as exc:
            raise SingularError(
                f"the stiffness matrix is singular ({exc}): the lattice has a mechanism "
                "(a node or a part not held by bonds and supports) or is unstable for these "
                "micro-parameters",
            ) from None
        self.A = A
        self._norm_inf: float | None = None
        self.negative_pivots: int | None = None
        if symmetric:
            if np.array_equal(self.lu.perm_r, self.lu.perm_c):
                self.negative_pivots = int(np.count_nonzero(self.lu.U.diagonal() < 0))
            else:
                # threshold pivoting left the diagonal: the matrix is not comfortably
                # positive definite. Count the inertia with pure diagonal pivoting
                # (symmetric elimination, Sylvester's law); keep the accurate factors.
                self.negative_pivots = _inertia_negative(Ap, opts["permc_spec"])
        self.setup_seconds = time.perf_counter() - t0

    def solve(self, b: np.ndarray, x0: np.ndarray | None = None, rtol: float | None = None):
        """Solve ``A x = b``; returns ``x`` and its :class:`SolveRecord` (iterations,
        residuals, backward error).

        Up to three steps of iterative refinement (``x += LU^-1 (b - A x)``) are taken
        while the relative residual is above 1e-13 and keeps falling: they cost one
        triangular solve each and rescue ill-conditioned systems (slivers, ``nu`` near
        the stability limit) where the plain solve stalls near 1e-8. ``iterations``
        counts the refinement steps.
        """
        nb = float(np.linalg.norm(b)) or 1.0
        x = self._apply(b)
        if not np.all(np.isfinite(x)):
            return x, SolveRecord(0, [np.inf], np.inf)
        r = b - self.A @ x
        residuals = [float(np.linalg.norm(r)) / nb]
        steps = 0
        while steps < 3 and residuals[-1] > 1e-13:
            x_new = x + self._apply(r)
            r_new = b - self.A @ x_new
            res = float(np.linalg.norm(r_new)) / nb
            if not np.isfinite(res) or res >= 0.5 * residuals[-1]:
                break
            x, r = x_new, r_new
            residuals.append(res)
            steps += 1
        if self._norm_inf is None:
            self._norm_inf = float(abs(self.A).sum(axis=1).max())
        # normwise backward error: x solves (A + dA) x = b with |dA| / |A| this small
        denom = self._norm_inf * float(np.max(np.abs(x))) + float(np.max(np.abs(b)))
        backward = float(np.max(np.abs(r))) / denom if denom > 0 else 0.0
        return x, SolveRecord(steps, residuals, backward)

    def apply(self, b: np.ndarray) -> np.ndarray:
        """``A^-1 b`` from the factors alone (no refinement); ``b`` (n,) or (n, k)."""
        return self._apply(b)

    def apply_columns(self, u, out: np.ndarray | None = None) -> np.ndarray:
        """``(A^-1 u)^T``, shape (k, n), for the sparse columns ``u`` (n, k): each
        column's solution as a row (written into ``out`` (k, n), if given), the
        right-hand sides placed in the factor's order directly."""
        u = u.tocoo()
        u.sum_duplicates()
        b = np.zeros(u.shape, order="F")
        b[u.row if self.order is None else self._inverse[u.row], u.col] = u.data
        x = self.lu.solve(b).T  # (k, n), C-contiguous (SuperLU answers in Fortran order)
        if out is None:
            out = np.empty(x.shape)
        if self.order is None:
            out[...] = x
        else:
            for row, sol in zip(out, x, strict=True):  # (1-D gathers: a 2-D take is slow)
                np.take(sol, self._inverse, out=row)
        return out

    @property
    def _inverse(self) -> np.ndarray:
        """Where every unknown sits in the factor's order."""
        inv = getattr(self, "_inv", None)
        if inv is None:
            inv = self._inv = np.empty_like(self.order)
            inv[self.order] = np.arange(len(self.order))
        return inv

    def _apply(self, b: np.ndarray) -> np.ndarray:
        if self.order is None:
            return self.lu.solve(b)
        x = np.empty_like(b)
        x[self.order] = self.lu.solve(b[self.order])
        return x


def _inertia_negative(A: sp.spmatrix, permc_spec: str) -> int | None:
    """Negative eigenvalues of symmetric ``A`` from an LU without off-diagonal pivots."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    try:
        lu = spla.splu(
            sp.csc_matrix(A),
            permc_spec=permc_spec,
            diag_pivot_thresh=0.0,
            options=dict(SymmetricMode=True),
        )
    except RuntimeError:
        return None
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return int(np.count_nonzero(lu.U.diagonal() < 0))


class AMGSolver:
    """Smoothed-aggregation AMG (pyamg) with the rigid-body near-null space, as a
    preconditioner for CG.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        The operator used to build the hierarchy (symmetric positive definite).
    B : ndarray, shape (n, 3)
        Near-null space (rigid-body modes).
    **options
        pyamg ``smoothed_aggregation_solver`` options overriding :data:`AMG_OPTIONS`.
    """

    name = "amg"

    def __init__(self, A: sp.spmatrix, B: np.ndarray, **options):
        import pyamg

        t0 = time.perf_counter()
        opts = dict(AMG_OPTIONS)
        opts.update(options)
        self.ml = pyamg.smoothed_aggregation_solver(A, B=B, **opts)
        self.A = A
        self.setup_seconds = time.perf_counter() - t0
        log.debug(
            "AMG hierarchy: %d levels, operator complexity %.2f, %.3f s",
            len(self.ml.levels),
            self.ml.operator_complexity(),
            self.setup_seconds,
        )

    def solve(
        self, b: np.ndarray, x0: np.ndarray | None = None, rtol: float = 1e-10, maxiter: int = 500
    ):
        """CG preconditioned by one V-cycle; stops at ``|r| <= rtol |b|``.

        Returns ``x`` and its :class:`SolveRecord` (relative residual history;
        ``indefinite`` when CG met a direction of non-positive curvature, i.e. the
        operator is not positive definite).
        """
        M = self.ml.aspreconditioner(cycle="V")
        return preconditioned_cg(self.A, b, M, x0=x0, rtol=rtol, maxiter=maxiter)


def preconditioned_cg(A, b, M, x0=None, rtol: float = 1e-10, maxiter: int = 500):
    """Preconditioned conjugate gradients that reports non-positive curvature.

    Parameters
    ----------
    A, M : linear operators (``@``)
        The operator and the preconditioner (an approximation of ``A^-1``).
    b : ndarray, shape (n,)
    rtol : float
        Stop when the true recursive residual ``|r| <= rtol |b|``.

    Returns
    -------
    x : ndarray
    record : dict
        ``iterations``, ``residuals`` (relative to |b|; the last one recomputed as
        ``|b - A x|``), ``indefinite`` (a curvature ``p.A.p <= 0`` or ``r.M.r < 0`` was
        met: the operator or the preconditioner is not positive definite).
    """
    nb = float(np.linalg.norm(b)) or 1.0
    x = np.zeros_like(b) if x0 is None else np.array(x0, dtype=float)
    r = b - A @ x
    hist = [float(np.linalg.norm(r)) / nb]
    indefinite = False
    it = 0
    if hist[-1] > rtol:
        z = M @ r
        rz = float(r @ z)
        p = z.copy()
        while it < maxiter:
            Ap = A @ p
            pap = float(p @ Ap)
            if pap <= 0.0 or rz < 0.0:
                indefinite = True
                break
            alpha = rz / pap
            x += alpha * p
            r -= alpha * Ap
            it += 1
            hist.append(float(np.linalg.norm(r)) / nb)
            if hist[-1] <= rtol:
                break
            z = M @ r
            rz_new = float(r @ z)
            p *= rz_new / rz
            p += z
            rz = rz_new
    true = float(np.linalg.norm(A @ x - b)) / nb if np.all(np.isfinite(x)) else np.inf
    hist[-1] = true
    return x, SolveRecord(it, hist, indefinite=bool(indefinite))


def nested_dissection(points: np.ndarray, edges: np.ndarray, leaf: int = 16) -> np.ndarray:
    """Node order: each part split at the median of its longer extent, then
    ``[order(left), order(right), separator]``, recursively.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    edges : ndarray, shape (n_edges, 2)
        Graph edges (bonds).
    leaf : int
        Parts with at most this many nodes are not split further.

    Returns
    -------
    ndarray of int, shape (N,)
        A permutation of ``range(N)``.
    """
    import scipy.sparse as sp

    n = len(points)
    adj = sp.coo_matrix(
        (
            np.ones(2 * len(edges), dtype=np.int8),
            (np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]]),
        ),
        shape=(n, n),
    ).tocsr()
    in_left = np.zeros(n, dtype=bool)
    out: list[np.ndarray] = []
    # explicit stack of (nodes, separator-or-None); separators are emitted after both halves
    stack: list[tuple[np.ndarray | None, np.ndarray | None]] = [(np.arange(n), None)]
    while stack:
        idx, sep = stack.pop()
        if idx is None:
            out.append(sep)
            continue
        if len(idx) <= leaf:
            out.append(idx)
            continue
        p = points[idx]
        ax = int(np.argmax(np.ptp(p, axis=0)))
        left = p[:, ax] < np.median(p[:, ax])
        if left.all() or not left.any():
            out.append(idx)
            continue
        in_left[idx[left]] = True
        right = idx[~left]
        touch = _touches(adj[right], in_left)
        in_left[idx[left]] = False
        # emitted in stack order: left, right, separator
        stack.append((None, right[touch]))
        stack.append((right[~touch], None))
        stack.append((idx[left], None))
    return np.concatenate(out) if out else np.zeros(0, np.int64)


def _touches(sub, in_left: np.ndarray) -> np.ndarray:
    """Rows of the adjacency ``sub`` with at least one neighbour flagged in ``in_left``."""
    counts = np.diff(sub.indptr)
    touch = np.zeros(sub.shape[0], dtype=bool)
    if sub.indices.size:
        hits = in_left[sub.indices].astype(np.int64)
        csum = np.concatenate([[0], np.cumsum(hits)])
        touch = (csum[sub.indptr[1:]] - csum[sub.indptr[:-1]]) > 0
    return touch & (counts > 0)
