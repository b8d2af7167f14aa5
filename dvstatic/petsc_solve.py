"""PETSc engine of ``solver="petsc"``: owned rows into PETSc (COO), KSP with GAMG,
distributed Newton, gathering on rank 0. The partition and the per-rank patch it works
on are in :mod:`dvstatic.distributed` (which also explains the method)."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from .distributed import (
    Layout,
    layout,
    micro_parameters,
    owned_bonds,
    owned_loads,
    patch_memory,
)

__all__ = ["DEFAULT_OPTIONS", "solve_petsc"]

log = logging.getLogger(__name__)

#: KSP options (prefix ``dvstatic_``); any PETSc option given on the command line
#: (``-dvstatic_ksp_monitor``, ``-dvstatic_pc_type hypre``...) overrides them
DEFAULT_OPTIONS = {
    "pc_gamg_threshold": "0.02",
    "pc_gamg_agg_nsmooths": "1",
    "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi",
}

_INSTALL_HINT = (
    "solver='petsc' needs petsc4py and mpi4py (the dvstatic[petsc] extra): run "
    "scripts/install_petsc.sh from a source checkout (PETSc is compiled from source, "
    "about 15 minutes; see docs/parallel.md)"
)


def _petsc():
    try:
        from petsc4py import PETSc
    except ImportError:
        raise ImportError(_INSTALL_HINT) from None
    return PETSc


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

    def set(self, K, g_local: np.ndarray | None) -> np.ndarray:
        """Load the owned rows of the patch matrix ``K`` (BSR 2x2, 2L x 2L) into PETSc
        with the prescribed dofs eliminated; returns the rhs correction for prescribed
        values ``g_local`` (patch dofs, zero where free)."""
        PETSc = self.PETSc
        n_own = self.lay.n_owned
        n2 = 2 * n_own
        ptr = K.indptr[: n_own + 1]
        nb = int(ptr[-1])
        bcol = K.indices[:nb]
        brow = np.repeat(np.arange(n_own, dtype=np.int64), np.diff(ptr))
        # the 2x2 block (br, bc) holds entries (2br + i, 2bc + j), stored row-major
        r = (2 * brow[:, None] + np.array([0, 0, 1, 1])).ravel()
        c = (2 * bcol[:, None].astype(np.int64) + np.array([0, 1, 0, 1])).ravel()
        del brow
        v = K.data[:nb].reshape(-1).copy()
        row_c = self.row_c[r]
        col_c = self.col_c[c]
        corr = np.zeros(n2)
        if g_local is not None:
            sel = col_c & ~row_c
            corr = -np.bincount(r[sel], v[sel] * g_local[c[sel]], n2)
        diag = r == c  # owned nodes come first in the patch numbering
        self.diag = np.bincount(r[diag], v[diag], n2)
        self.c_entries = (r[row_c], c[row_c], v[row_c].copy())  # for the reactions
        v[(row_c | col_c) & ~diag] = 0.0
        del row_c, col_c, diag
        pattern = (nb, hash(ptr.tobytes()), hash(bcol.tobytes()))
        if self.A is None or pattern != self.pattern:
            A = PETSc.Mat().create(comm=self.comm)
            A.setSizes(((n2, PETSc.DECIDE), (n2, PETSc.DECIDE)), bsize=2)
            A.setType(PETSc.Mat.Type.AIJ)
            rows_g = (r + 2 * self.lay.lo).astype(PETSc.IntType)
            del r
            A.setPreallocationCOO(rows_g, self.gdof[c])
            del rows_g
            coords = A.createVecLeft()
            coords.setBlockSize(2)
            coords.array[:] = self.lay.patch.points[:n_own].reshape(-1)
            A.setNearNullSpace(PETSc.NullSpace().createRigidBody(coords))
            self.A, self.pattern = A, pattern
            self.ksp = None
        self.A.setValuesCOO(v, addv=PETSc.InsertMode.INSERT_VALUES)
        self.A.assemble()
        return corr

    def constrained_rows(self, u_patch: np.ndarray) -> np.ndarray:
        """Original (uneliminated) owned rows at prescribed dofs times ``u_patch``."""
        r, c, v = self.c_entries
        return np.bincount(r, v * u_patch[c], 2 * self.lay.n_owned)

    def solver(self, rtol: float, maxiter: int):
        PETSc = self.PETSc
        if self.ksp is None:
            opts = PETSc.Options()
            for k, val in DEFAULT_OPTIONS.items():
                if not opts.hasName("dvstatic_" + k):
                    opts.setValue("dvstatic_" + k, val)
            ksp = PETSc.KSP().create(comm=self.comm)
            ksp.setOptionsPrefix("dvstatic_")
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
        """Solve for the owned rows; returns (x owned, info)."""
        ksp = self.solver(rtol, maxiter)
        ksp.setOperators(self.A)
        ksp.getPC().setReusePreconditioner(reuse)
        b = self.A.createVecLeft()
        b.array[:] = b_arr
        x = self.A.createVecRight()
        t0 = time.perf_counter()
        ksp.setUp()
        t_setup = time.perf_counter() - t0
        t0 = time.perf_counter()
        ksp.solve(b, x)
        t_solve = time.perf_counter() - t0
        reason = int(ksp.getConvergedReason())
        r = b.duplicate()
        self.A.mult(x, r)
        r.aypx(-1.0, b)
        nb = b.norm() or 1.0
        hist = [float(h) / nb for h in ksp.getConvergenceHistory()]
        info = {
            "iterations": int(ksp.getIterationNumber()),
            "reason": reason,
            "residual": float(r.norm()) / nb,
            "residuals": hist,
            "setup": t_setup,
            "solve": t_solve,
        }
        return x.array.copy(), info


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


def solve_petsc(
    model,
    supports: list,
    loads: list,
    *,
    rtol: float,
    maxiter: int,
    nonlinear: bool,
    steps: int,
    newton_rtol: float,
    max_iter: int,
    max_cutbacks: int,
):
    """Distributed linear or Newton solve; see the module docstring.

    Returns the :class:`~dvstatic.solvers.Solution` on every rank; ``u`` and
    ``reactions`` are filled on rank 0 only (``None`` on the others).
    """
    from .linalg import SolverError, check_restrained
    from .loads import constraints
    from .solvers import Solution

    PETSc = _petsc()
    comm = PETSc.COMM_WORLD
    rank, size = comm.getRank(), comm.getSize()
    t_start = time.perf_counter()
    seconds: dict[str, float] = {}
    mesh = model.mesh

    t0 = time.perf_counter()
    dofs, values = constraints(mesh, supports)
    check_restrained(mesh.points, dofs)
    lay = layout(mesh, rank, size)
    seconds["partition"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    mpi = comm.tompi4py()
    micro = micro_parameters(model, lay, lambda a: mpi.allreduce(np.asarray(a, dtype=float)))
    if "micro" not in model.__dict__:
        model.__dict__["micro"] = micro  # cached_property slot of the frozen model
    seconds["calibration"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    pm = type(model)(lay.patch, model.E, model.nu, calibration=micro, bonds=model.bonds)
    cnew = 2 * lay.new_of[dofs // 2] + dofs % 2
    order = np.argsort(cnew)
    cdofs, cvals = cnew[order], values[order]
    gdof = lay.local_dofs_global
    pos = np.searchsorted(cdofs, gdof)
    pos = np.minimum(pos, max(len(cdofs) - 1, 0))
    is_c = (cdofs[pos] == gdof) if len(cdofs) else np.zeros(len(gdof), dtype=bool)
    g_patch = np.where(is_c, cvals[pos] if len(cdofs) else 0.0, 0.0)
    f_own = owned_loads(mesh, loads, lay)
    kind = "nonlinear" if nonlinear else "linear"
    system = _System(PETSc, comm, lay, cdofs, kind)
    ex = _Exchange(PETSc, comm, lay)
    n2 = 2 * lay.n_owned
    seconds["patch"] = time.perf_counter() - t0

    info: dict = {
        "solver": "petsc",
        "nonlinear": bool(nonlinear),
        "n_dof": int(2 * mesh.n_points),
        "n_constrained": int(len(dofs)),
        "stability": "not checked (solver='petsc'; CG/GMRES fail on an unstable model)",
        "coupling_assembled": micro.nu_m != 0.0,
    }
    ksp_log: list[dict] = []

    def fail(msg, u_owned=None):
        info["converged"] = False
        info["ksp"] = ksp_log
        raise SolverError(msg, info)

    if not nonlinear:
        t0 = time.perf_counter()
        corr = system.set(pm._assemble(None, None, None), g_patch)
        seconds["assembly"] = time.perf_counter() - t0
        b = f_own + corr
        rc = system.row_c
        b[rc] = system.diag[rc] * g_patch[:n2][rc]
        x, kinfo = system.solve(b, rtol, maxiter)
        ksp_log.append(kinfo)
        seconds["setup"], seconds["solve"] = kinfo["setup"], kinfo["solve"]
        if kinfo["reason"] <= 0 or not np.isfinite(kinfo["residual"]):
            fail(
                f"PETSc KSP did not converge (reason {kinfo['reason']}, "
                f"{kinfo['iterations']} iterations, relative residual {kinfo['residual']:.3e}): "
                "the model may be unstable for these micro-parameters"
            )
        info.update(iterations=kinfo["iterations"], residuals=kinfo["residuals"])
        info["residual"] = kinfo["residual"]
        u_patch = ex.patch(x)
        r_own = system.constrained_rows(u_patch) - f_own
    else:
        x, r_own = _newton(
            _Setup(pm, system, ex, lay, comm, g_patch, f_own),
            _NewtonSettings(steps, newton_rtol, max_iter, max_cutbacks, rtol, maxiter),
            info,
            ksp_log,
            seconds,
            fail,
        )
    t0 = time.perf_counter()
    reac = np.zeros(n2)
    reac[system.row_c] = r_own[system.row_c]
    u = ex.root_nodal(x)
    reactions = ex.root_nodal(reac)
    seconds["gather"] = time.perf_counter() - t0
    seconds["total"] = time.perf_counter() - t_start
    mem = patch_memory(lay)
    mem["peak_MB"] = _peak_mb()
    peaks = comm.tompi4py().allgather(mem["peak_MB"])
    info.update(
        converged=True,
        seconds=seconds,
        reused=[],
        ksp=ksp_log,
        parallel={"ranks": size, "rank": rank, "memory": mem, "peak_MB_per_rank": peaks},
    )
    log.info(
        "%s petsc solve on %d rank(s): %d dof, %s iterations, %.3f s",
        model.kind,
        size,
        info["n_dof"],
        info.get("iterations"),
        seconds["total"],
    )
    return Solution(model, u, reactions, info, supports, loads)


@dataclass(frozen=True)
class _Setup:
    """One rank's pieces of a distributed problem."""

    pm: object  # the model on the patch
    system: _System
    ex: _Exchange
    lay: Layout
    comm: object
    g_patch: np.ndarray  # prescribed values on the patch dofs (0 where free)
    f_own: np.ndarray  # external forces on the owned dofs


@dataclass(frozen=True)
class _NewtonSettings:
    steps: int
    newton_rtol: float
    max_iter: int
    max_cutbacks: int
    rtol: float  # KSP
    maxiter: int  # KSP


def _newton(setup: _Setup, opts: _NewtonSettings, info, ksp_log, seconds, fail):
    """Load-stepped Newton with a backtracking line search and cut-backs."""
    pm, system, ex, lay = setup.pm, setup.system, setup.ex, setup.lay
    g_patch, f_own = setup.g_patch, setup.f_own
    steps, newton_rtol, max_iter = opts.steps, opts.newton_rtol, opts.max_iter
    max_cutbacks, rtol, maxiter = opts.max_cutbacks, opts.rtol, opts.maxiter
    n2 = 2 * lay.n_owned
    mpi = setup.comm.tompi4py()
    rc = system.row_c
    n_patch = 2 * lay.patch.n_points

    def gnorm(v):
        return float(np.sqrt(mpi.allreduce(float(v @ v))))

    def residual(x_own, lam):
        u_patch = ex.patch(x_own)
        fi = pm.internal_force(u_patch.reshape(-1, 2))[:n2]
        r = fi - lam * f_own
        react = np.zeros(n2)
        react[rc] = r[rc]
        r[rc] = 0.0
        return r, u_patch, react

    f_scale = gnorm(f_own)
    # absolute floor as in the serial Newton: 1e-10 k_n l_mean sqrt(n_dof)
    own_b = owned_bonds(lay)
    cnt, tot = mpi.allreduce(np.array([own_b.sum(), pm.geometry.length[own_b].sum()], float))
    atol = 1e-10 * pm.k_n * (tot / cnt) * np.sqrt(2.0 * len(lay.new_of))
    x = np.zeros(n2)
    lam, dlam = 0.0, 1.0 / steps
    cutbacks = 0
    steps_info: list[dict] = []
    total_its = 0
    t_asm = 0.0
    while lam < 1.0 - 1e-12:
        target = min(1.0, lam + dlam)
        x_try = x.copy()
        hist = []
        converged = False
        last_inc = np.inf
        for it in range(max_iter):
            r, u_patch, react = residual(x_try, target)
            rn = gnorm(r)
            scale = max(f_scale * target, gnorm(react))
            tol = max(newton_rtol * scale, atol)
            hist.append(rn / max(scale, 1e-300))
            jump = g_patch[:n2] * target - x_try
            jump[~rc] = 0.0
            jumping = gnorm(jump) > 0.0
            small_step = last_inc <= np.sqrt(newton_rtol) or rn <= 1e-3 * tol
            log.debug(
                "petsc Newton: lambda %.4g it %d residual %.3e tol %.3e increment %.3e",
                target,
                it,
                rn,
                tol,
                last_inc,
            )
            if it > 0 and rn <= tol and not jumping and small_step:
                converged = True
                break
            t0 = time.perf_counter()
            up = u_patch.reshape(-1, 2)
            Kt = pm._assemble(up, None, pm._tension(up, None)[0])
            g_inc = np.zeros(n_patch)
            if jumping:
                g_inc = np.where(system.col_c, ex.patch(jump), 0.0)
            corr = system.set(Kt, g_inc)
            del Kt
            t_asm += time.perf_counter() - t0
            b = -r + corr
            b[rc] = system.diag[rc] * jump[rc]
            du, kinfo = system.solve(b, max(rtol, 1e-12), maxiter, reuse=False)
            ksp_log.append(kinfo)
            total_its += 1
            if kinfo["reason"] <= 0:
                break
            alpha = 1.0
            if not jumping:
                while alpha > 1.0 / 64:
                    r_new, _, _ = residual(x_try + alpha * du, target)
                    if gnorm(r_new) < (1.0 - 1e-4 * alpha) * rn:
                        break
                    alpha *= 0.5
            x_try = x_try + alpha * du
            if alpha == 1.0:  # the prescribed values exactly (CG leaves ~rtol there)
                x_try[rc] = g_patch[:n2][rc] * target
            last_inc = gnorm(alpha * du) / max(gnorm(x_try), 1e-300)
        if converged:
            x, lam = x_try, target
            steps_info.append({"load_factor": lam, "iterations": len(hist), "residuals": hist})
            log.info("petsc Newton: load factor %.4g reached in %d iterations", lam, len(hist))
        else:
            cutbacks += 1
            if cutbacks > max_cutbacks:
                info["load_factor"] = lam
                info["steps"] = steps_info
                fail(
                    f"Newton did not converge at load factor {target:.4g} after "
                    f"{max_cutbacks} cut-backs (solver='petsc')"
                )
            dlam *= 0.5
    seconds["assembly"] = t_asm
    seconds["setup"] = float(sum(k["setup"] for k in ksp_log))
    seconds["solve"] = float(sum(k["solve"] for k in ksp_log))
    r, _, react = residual(x, 1.0)
    info.update(
        steps=steps_info,
        iterations=total_its,
        residuals=[h for s in steps_info for h in s["residuals"]],
        residual=steps_info[-1]["residuals"][-1] if steps_info else 0.0,
        cutbacks=cutbacks,
    )
    r_full = r.copy()
    r_full[rc] = react[rc]
    return x, r_full
