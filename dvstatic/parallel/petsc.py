"""PETSc engine of ``solver="petsc"``: owned rows into PETSc (COO), KSP with GAMG,
Newton through the one Newton of :mod:`dvstatic.solvers.newton`, gathering on rank 0.
The partition and the per-rank patch it works on are in :mod:`.partition` (which also
explains the method).

KSP options live under the prefix ``dvstatic_``: the defaults below are pushed into
PETSc's options database for the solve and removed afterwards; any option given on
the command line (``-dvstatic_ksp_monitor``, ``-dvstatic_pc_type hypre``...) wins.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ConvergenceError, InputError, MissingDependencyError, SolverError
from ..lattice.operator import scatter_bond_forces
from ..problem import FollowerPressures, check_restrained, constraints
from ..problem.follower import split_followers
from ..solvers.newton import State, absolute_floor, solve_nonlinear
from ..solvers.result import LinearSolve, ParallelInfo, Solution, SolveInfo, StabilityCheck, Timings
from .partition import (
    Layout,
    layout,
    micro_parameters,
    owned_bonds,
    owned_loads,
    patch_memory,
    patch_model,
)

__all__ = ["DEFAULT_OPTIONS", "PREFIX", "solve"]

log = logging.getLogger(__name__)

#: prefix of every option dvstatic's KSP reads
PREFIX = "dvstatic_"
#: KSP options pushed (under :data:`PREFIX`) for the duration of a solve
DEFAULT_OPTIONS = {
    "pc_gamg_threshold": "0.02",
    "pc_gamg_agg_nsmooths": "1",
    "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi",
}


def _petsc():
    try:
        from petsc4py import PETSc
    except ImportError:
        raise MissingDependencyError(
            "solver='petsc' needs petsc4py and mpi4py (the dvstatic[petsc] extra): run "
            "scripts/install_petsc.sh from a source checkout (PETSc is compiled from source, "
            "about 15 minutes; see docs/parallel.md)",
            "petsc",
        ) from None
    return PETSc


@contextlib.contextmanager
def pushed_options(PETSc, defaults: dict[str, str] = DEFAULT_OPTIONS):
    """Push ``defaults`` under :data:`PREFIX` where the user set nothing; remove them
    (only them) afterwards."""
    opts = PETSc.Options()
    pushed = []
    for key, value in defaults.items():
        name = PREFIX + key
        if not opts.hasName(name):
            opts.setValue(name, value)
            pushed.append(name)
    try:
        yield
    finally:
        for name in pushed:
            opts.delValue(name)


class _System:
    """Owned rows of a patch matrix in PETSc, with prescribed dofs eliminated."""

    def __init__(self, PETSc, comm, lay: Layout, cdofs: np.ndarray, kind: str):
        self.PETSc, self.comm, self.lay = PETSc, comm, lay
        self.cdofs = cdofs  # PETSc numbers of all prescribed dofs, sorted (replicated)
        self.gdof = lay.local_dofs_global.astype(PETSc.IntType)
        n2 = 2 * lay.n_owned
        self.col_c = np.isin(lay.local_dofs_global, cdofs)  # prescribed patch dofs
        self.row_c = self.col_c[:n2]
        self.A = None
        self.pattern = None
        self.kind = kind
        self.ksp = None

    def set(self, K) -> None:
        """Load the owned rows of the patch matrix ``K`` (BSR 2x2, 2L x 2L) into PETSc
        with the prescribed dofs eliminated; keep the coupling to prescribed columns
        (:meth:`column_correction`) and the original prescribed rows (reactions)."""
        n_own = self.lay.n_owned
        ptr = K.indptr[: n_own + 1]
        nb = int(ptr[-1])
        bcol = K.indices[:nb]
        brow = np.repeat(np.arange(n_own, dtype=np.int64), np.diff(ptr))
        # the 2x2 block (br, bc) holds entries (2br + i, 2bc + j), stored row-major
        r = (2 * brow[:, None] + np.array([0, 0, 1, 1])).ravel()
        c = (2 * bcol[:, None].astype(np.int64) + np.array([0, 1, 0, 1])).ravel()
        v = K.data[:nb].reshape(-1).copy()
        row_c, col_c = self.row_c[r], self.col_c[c]
        sel = col_c & ~row_c
        self.c_columns = (r[sel], c[sel], v[sel].copy())
        diag = r == c  # owned nodes come first in the patch numbering
        self.diag = np.bincount(r[diag], v[diag], 2 * n_own)
        self.c_entries = (r[row_c], c[row_c], v[row_c].copy())
        v[(row_c | col_c) & ~diag] = 0.0
        self._load(r, c, v, (nb, hash(ptr.tobytes()), hash(bcol.tobytes())))

    def _load(self, r, c, v, pattern) -> None:
        from mpi4py import MPI

        PETSc = self.PETSc
        changed = self.A is None or pattern != self.pattern
        # a new matrix is a collective operation: every rank must agree
        if self.comm.tompi4py().allreduce(changed, MPI.LOR):
            self.close()
            n2 = 2 * self.lay.n_owned
            A = PETSc.Mat().create(comm=self.comm)
            A.setSizes(((n2, PETSc.DECIDE), (n2, PETSc.DECIDE)), bsize=2)
            A.setType(PETSc.Mat.Type.AIJ)
            A.setPreallocationCOO((r + 2 * self.lay.lo).astype(PETSc.IntType), self.gdof[c])
            coords = A.createVecLeft()
            coords.setBlockSize(2)
            coords.array[:] = self.lay.patch.points[: self.lay.n_owned].reshape(-1)
            A.setNearNullSpace(PETSc.NullSpace().createRigidBody(coords))
            self.A, self.pattern = A, pattern
            self.ksp = None
        self.A.setValuesCOO(v, addv=PETSc.InsertMode.INSERT_VALUES)
        self.A.assemble()

    def close(self) -> None:
        """Destroy the PETSc matrix and solver (collective)."""
        for obj in (self.ksp, self.A):
            if obj is not None:
                obj.destroy()
        self.ksp = self.A = None

    def column_correction(self, g_patch: np.ndarray) -> np.ndarray:
        """``-K[:, prescribed] g`` on the owned rows, for prescribed patch values ``g``."""
        r, c, v = self.c_columns
        return -np.bincount(r, v * g_patch[c], 2 * self.lay.n_owned)

    def constrained_rows(self, u_patch: np.ndarray) -> np.ndarray:
        """Original (uneliminated) owned rows at prescribed dofs times ``u_patch``."""
        r, c, v = self.c_entries
        return np.bincount(r, v * u_patch[c], 2 * self.lay.n_owned)

    def _solver(self, rtol: float, maxiter: int):
        PETSc = self.PETSc
        if self.ksp is None:
            ksp = PETSc.KSP().create(comm=self.comm)
            ksp.setOptionsPrefix(PREFIX)
            ksp.setType("cg" if self.kind == "linear" else "gmres")
            if self.kind != "linear":
                ksp.setPCSide(PETSc.PC.Side.RIGHT)  # GMRES on the true residual
            ksp.getPC().setType("gamg")
            ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
            ksp.setOperators(self.A)
            ksp.setFromOptions()
            self.ksp = ksp
        self.ksp.setTolerances(rtol=rtol, atol=0.0, max_it=maxiter)
        self.ksp.setConvergenceHistory()
        return self.ksp

    def solve(self, b_arr: np.ndarray, rtol: float, maxiter: int, reuse: bool = False):
        """Solve for the owned rows; returns (x owned, LinearSolve)."""
        ksp = self._solver(rtol, maxiter)
        ksp.setOperators(self.A)
        ksp.getPC().setReusePreconditioner(reuse)
        b = self.A.createVecLeft()
        b.array[:] = b_arr
        x = self.A.createVecRight()
        t0 = time.perf_counter()
        ksp.setUp()
        t1 = time.perf_counter()
        ksp.solve(b, x)
        t2 = time.perf_counter()
        reason = int(ksp.getConvergedReason())
        r = b.duplicate()
        self.A.mult(x, r)
        r.aypx(-1.0, b)
        nb = b.norm() or 1.0
        rec = LinearSolve(
            iterations=int(ksp.getIterationNumber()),
            residual=float(r.norm()) / nb,
            converged=reason > 0,
            residuals=tuple(float(h) / nb for h in ksp.getConvergenceHistory()),
            setup_seconds=t1 - t0,
            solve_seconds=t2 - t1,
            reason=reason,
        )
        return x.array.copy(), rec


class _Exchange:
    """Owned pieces <-> patch values (every rank) and <-> rank 0 (mesh order)."""

    def __init__(self, PETSc, comm, lay: Layout):
        self.PETSc, self.lay = PETSc, lay
        self.vec = PETSc.Vec().createMPI((2 * lay.n_owned, PETSc.DECIDE), bsize=2, comm=comm)
        gd = lay.local_dofs_global.astype(PETSc.IntType)
        idx = PETSc.IS().createGeneral(gd, comm=PETSc.COMM_SELF)
        self.local = PETSc.Vec().createSeq(len(gd), comm=PETSc.COMM_SELF)
        self.to_patch = PETSc.Scatter().create(self.vec, idx, self.local, None)
        self.to_root, self.root = PETSc.Scatter.toZero(self.vec)

    def close(self) -> None:
        """Destroy the vectors and scatters (collective)."""
        for obj in (self.to_patch, self.to_root, self.vec, self.local, self.root):
            obj.destroy()

    def patch(self, owned: np.ndarray) -> np.ndarray:
        """Values of the patch dofs, shape (2L,), from the owned pieces on all ranks."""
        P = self.PETSc
        self.vec.array[:] = owned
        self.to_patch.scatter(
            self.vec, self.local, addv=P.InsertMode.INSERT_VALUES, mode=P.ScatterMode.FORWARD
        )
        return self.local.array.copy()

    def root_nodal(self, owned: np.ndarray) -> np.ndarray | None:
        """Owned pieces gathered on rank 0 in mesh order, shape (N, 2); None elsewhere."""
        P = self.PETSc
        self.vec.array[:] = owned
        self.to_root.scatter(
            self.vec, self.root, addv=P.InsertMode.INSERT_VALUES, mode=P.ScatterMode.FORWARD
        )
        if self.lay.rank != 0:
            return None
        return self.root.array.reshape(-1, 2)[self.lay.new_of].copy()


def _peak_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


@dataclass(frozen=True, eq=False)
class _Setup:
    """One rank's pieces of a distributed problem."""

    pm: object  # the model on the patch
    system: _System
    ex: _Exchange
    lay: Layout
    mpi: object  # mpi4py communicator
    g_patch: np.ndarray  # prescribed values on the patch dofs (0 where free)
    f_own: np.ndarray  # external (dead) forces on the owned dofs
    n_dof: int
    n_constrained: int
    follower: FollowerPressures  # follower pressures on the patch (patch numbering)


def _prepare(PETSc, comm, model, supports, loads, opts, seconds: dict) -> _Setup:
    """Partition, calibration (summed over ranks), patch model, prescribed values."""
    rank, size = comm.getRank(), comm.getSize()
    mesh = model.mesh
    t0 = time.perf_counter()
    dofs, values = constraints(mesh, supports)
    check_restrained(mesh.points, dofs)
    lay = layout(mesh, rank, size)
    seconds["partition"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    mpi = comm.tompi4py()
    micros = micro_parameters(model, lay, lambda a: mpi.allreduce(np.asarray(a, dtype=float)))
    if not model.is_calibrated:
        model.set_micro(micros)
    if rank == 0:  # the calibration warnings, once (every rank holds the whole mesh)
        model.calibration_flags  # noqa: B018 (the cached_property, logged on first use)
    seconds["calibration"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    pm = patch_model(model, lay, micros)
    cnew = 2 * lay.new_of[dofs // 2] + dofs % 2
    order = np.argsort(cnew)
    cdofs, cvals = cnew[order], values[order]
    gdof = lay.local_dofs_global
    pos = np.minimum(np.searchsorted(cdofs, gdof), max(len(cdofs) - 1, 0))
    is_c = (cdofs[pos] == gdof) if len(cdofs) else np.zeros(len(gdof), dtype=bool)
    g_patch = np.where(is_c, cvals[pos] if len(cdofs) else 0.0, 0.0)
    kind = "nonlinear" if opts.nonlinear else "linear"
    system = _System(PETSc, comm, lay, cdofs, kind)
    # follower pressures follow the deformed boundary in Newton; dead loads otherwise
    dead, follow = split_followers(loads) if opts.nonlinear else (loads, [])
    local_of = np.full(mesh.n_points, -1, dtype=np.int64)
    local_of[lay.local_nodes] = np.arange(len(lay.local_nodes))
    follower = FollowerPressures.from_loads(mesh, follow, model.t).restricted(local_of)
    setup = _Setup(
        pm,
        system,
        _Exchange(PETSc, comm, lay),
        lay,
        mpi,
        g_patch,
        owned_loads(mesh, dead, lay, model.t),
        int(2 * mesh.n_points),
        int(len(dofs)),
        follower,
    )
    seconds["patch"] = time.perf_counter() - t0
    return setup


def solve(model, supports: list, loads: list, opts) -> Solution:
    """Distributed linear or Newton solve; see the module docstring.

    Returns the :class:`~dvstatic.solvers.Solution` on every rank; ``u`` and
    ``reactions`` are filled on rank 0 only (``None`` on the others).
    """
    PETSc = _petsc()
    comm = PETSc.COMM_WORLD
    t_start = time.perf_counter()
    seconds: dict[str, float] = {}
    # progress bars and step logs on rank 0 only
    opts = dataclasses.replace(opts, progress=opts.progress and comm.getRank() == 0)
    with pushed_options(PETSc):
        s = _prepare(PETSc, comm, model, supports, loads, opts, seconds)
        try:
            if opts.nonlinear:
                x, r_own, record = _nonlinear(s, opts, seconds)
            else:
                x, r_own, record = _linear(s, opts, seconds)
            t0 = time.perf_counter()
            reac = np.zeros(2 * s.lay.n_owned)
            reac[s.system.row_c] = r_own[s.system.row_c]
            u = s.ex.root_nodal(x)
            reactions = s.ex.root_nodal(reac)
            seconds["gather"] = time.perf_counter() - t0
        finally:  # the same destroys in the same order on every rank
            s.system.close()
            s.ex.close()
    seconds["total"] = time.perf_counter() - t_start
    mem = patch_memory(s.lay)
    mem["peak_MB"] = _peak_mb()
    peaks = tuple(s.mpi.allgather(mem["peak_MB"]))
    info = SolveInfo(
        "petsc",
        nonlinear=opts.nonlinear,
        converged=True,
        n_dof=s.n_dof,
        n_constrained=s.n_constrained,
        seconds=Timings(**seconds),
        stability=StabilityCheck(
            note="not checked (solver='petsc'; CG/GMRES fail on an unstable model)"
        ),
        coupling_assembled=s.pm.operator.has_coupling,
        parallel=ParallelInfo(comm.getSize(), comm.getRank(), mem, peaks),
        **record,
    )
    log.info(
        "%s petsc solve on %d rank(s): %d dof, %d iterations, %.3f s",
        model.kind,
        comm.getSize(),
        info.n_dof,
        info.iterations,
        seconds["total"],
    )
    return Solution(model, u, reactions, info, supports, loads)


def _linear(s: _Setup, opts, seconds: dict):
    n2 = 2 * s.lay.n_owned
    t0 = time.perf_counter()
    s.system.set(s.pm.operator.stiffness_bsr)
    corr = s.system.column_correction(s.g_patch)
    seconds["assembly"] = time.perf_counter() - t0
    b = s.f_own + corr
    rc = s.system.row_c
    b[rc] = s.system.diag[rc] * s.g_patch[:n2][rc]
    x, rec = s.system.solve(b, opts.rtol, opts.linear_maxiter())
    seconds["setup"], seconds["solve"] = rec.setup_seconds, rec.solve_seconds
    if not rec.converged or not np.isfinite(rec.residual):
        raise ConvergenceError(
            f"PETSc KSP did not converge (reason {rec.reason}, {rec.iterations} iterations, "
            f"relative residual {rec.residual:.3e}): the model may be unstable for these "
            "micro-parameters",
            SolveInfo("petsc", linear_solves=(rec,)),
        )
    r_own = s.system.constrained_rows(s.ex.patch(x)) - s.f_own
    record = dict(
        iterations=rec.iterations,
        residuals=rec.residuals,
        residual=rec.residual,
        linear_solves=(rec,),
    )
    return x, r_own, record


class PatchProblem:
    """:class:`~dvstatic.solvers.newton.NewtonProblem` on this rank's owned dofs;
    residuals and tangents from the patch model, norms summed over ranks."""

    def __init__(self, s: _Setup, opts):
        self.s = s
        self.opts = opts
        n2 = 2 * s.lay.n_owned
        self.n2 = n2
        self.constrained = s.system.row_c
        self.targets = np.where(self.constrained, s.g_patch[:n2], 0.0)
        self.f_ext = s.f_own
        own_b = owned_bonds(s.lay)
        cnt, tot = s.mpi.allreduce(
            np.array([own_b.sum(), s.pm.geometry.length[own_b].sum()], float)
        )
        self.atol = absolute_floor(s.pm.k_n * s.pm.t, tot / cnt, s.n_dof)  # as serially
        self.log: list[LinearSolve] = []
        self.assembly_seconds = 0.0
        self._builds = 0
        self._fresh = False

    def norm(self, v: np.ndarray) -> float:
        return float(np.sqrt(self.s.mpi.allreduce(float(v @ v))))

    def max_abs(self, v: np.ndarray) -> float:
        from mpi4py import MPI

        return float(self.s.mpi.allreduce(float(np.max(np.abs(v))) if v.size else 0.0, MPI.MAX))

    def load_norm(self) -> float:
        return self.norm(self.f_ext + self._follow(self.s.lay.patch.points, 1.0))

    def _follow(self, x_patch: np.ndarray, lam: float) -> np.ndarray:
        """Follower forces on the owned dofs at current patch positions."""
        if not self.s.follower or lam == 0.0:
            return np.zeros(self.n2)
        return lam * self.s.follower.forces(x_patch)[: self.n2]

    def evaluate(self, u: np.ndarray, lam: float) -> State | None:
        from mpi4py import MPI

        up = self.s.ex.patch(u).reshape(-1, 2)
        op = self.s.pm.operator
        bad = op.inverted(up)
        if not bad:
            try:
                t, d, length = op.bond_state(up)
            except InputError:
                bad = True
        if self.s.mpi.allreduce(bool(bad), MPI.LOR):
            return None
        fi = scatter_bond_forces(op.mesh.topology.bonds, (t / length)[:, None] * d, len(up))
        r = fi[: self.n2] - lam * self.f_ext - self._follow(self.s.lay.patch.points + up, lam)
        if self.s.mpi.allreduce(not bool(np.all(np.isfinite(r))), MPI.LOR):
            return None
        r_free = r.copy()
        r_free[self.constrained] = 0.0
        return State(r_free, r, (up, t, lam))

    def factor(self, u: np.ndarray, state: State) -> None:
        import scipy.sparse as sp

        t0 = time.perf_counter()
        up, t, lam = state.aux
        kt = self.s.pm.operator.assemble(up, None, t)
        if self.s.follower and lam != 0.0:
            ft = self.s.follower.tangent(len(up))
            kt = sp.bsr_matrix(kt.tocsr() - lam * ft, blocksize=(2, 2))
        self.s.system.set(kt)
        self.assembly_seconds += time.perf_counter() - t0
        self._builds += 1
        self._fresh = True

    def solve(self, rhs_free: np.ndarray, du_c: np.ndarray) -> tuple[np.ndarray, int]:
        sys_ = self.s.system
        b = rhs_free.copy()
        if self.max_abs(du_c) > 0.0:
            g = np.where(sys_.col_c, self.s.ex.patch(du_c), 0.0)
            b += sys_.column_correction(g)
        rc = self.constrained
        b[rc] = sys_.diag[rc] * du_c[rc]
        x, rec = sys_.solve(
            b, max(self.opts.rtol, 1e-12), self.opts.linear_maxiter(), reuse=not self._fresh
        )
        self._fresh = False
        self.log.append(rec)
        if not rec.converged:
            raise SolverError(
                f"PETSc KSP did not converge (reason {rec.reason})",
                SolveInfo("petsc", nonlinear=True, linear_solves=tuple(self.log)),
            )
        return x, rec.iterations

    def negative_pivots(self) -> int | None:
        return None

    @property
    def builds(self) -> int:
        return self._builds


def _nonlinear(s: _Setup, opts, seconds: dict):
    problem = PatchProblem(s, opts)
    x, rep = solve_nonlinear(problem, opts, "petsc", "petsc (GMRES + GAMG)")
    seconds["assembly"] = problem.assembly_seconds
    seconds["setup"] = float(sum(k.setup_seconds for k in problem.log))
    seconds["solve"] = float(sum(k.solve_seconds for k in problem.log))
    state = problem.evaluate(x, 1.0)  # reactions of the dead and follower loads
    record = dict(
        iterations=rep.iterations,
        residuals=tuple(r for st in rep.steps for r in st.residuals),
        residual=rep.residual,
        steps=rep.steps,
        cutbacks=rep.cutbacks,
        tangent_builds=rep.tangent_builds,
        linear_solves=tuple(problem.log),
    )
    return x, state.r_all, record
