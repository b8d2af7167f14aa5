"""Static solves: :func:`solve` and the :class:`Solution` it returns."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from . import geometry as _geometry
from . import linalg
from ._checks import check_choice, check_int, check_positive
from .loads import constraints, load_vector
from .models import VoronoiModel
from .newton import NewtonOptions, _residual, solve_nonlinear
from .ordering import mesh_dof_order
from .stability import CHECK_MAX_DOF

#: the refusal message includes the admissible nu range up to this many dofs
RANGE_IN_MESSAGE_MAX_DOF = 20_000
#: Largest normwise backward error accepted from a direct solve whose residual relative
#: to the load is above 1e-8 (ill-conditioned meshes with slivers): about 500 eps.
BACKWARD_LIMIT = 1e-13

log = logging.getLogger(__name__)

__all__ = ["Solution", "solve"]


@dataclass(frozen=True, eq=False)
class Solution:
    """Result of :func:`solve`.

    Attributes
    ----------
    model : DV or RV
    u : ndarray, shape (N, 2)
        Nodal displacements (length units). ``None`` on MPI ranks other than 0 with
        ``solver="petsc"`` (rank 0 gathers the solution; so are ``reactions``).
    reactions : ndarray, shape (N, 2)
        Support reactions (force per unit thickness), non-zero at constrained dofs:
        the force the supports exert on the body.
    info : dict
        ``solver`` ("direct" | "amg"), ``converged``, ``iterations``, ``residuals``
        (relative residual history), ``residual`` (final relative equilibrium
        residual), ``seconds`` per stage (geometry, assembly, setup, solve, total),
        ``reused`` (stages taken from a cache), ``n_dof``, ``n_constrained``.
    supports, loads : list
        What was solved.
    """

    model: VoronoiModel
    u: np.ndarray
    reactions: np.ndarray
    info: dict
    supports: list = field(default_factory=list)
    loads: list = field(default_factory=list)

    @property
    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude."""
        return float(np.max(np.hypot(self.u[:, 0], self.u[:, 1])))

    def tension(self) -> np.ndarray:
        """Bond tensions, shape (E,) (linearised for a linear solve)."""
        if self.info.get("nonlinear"):
            return self.model.bond_tension(self.u)
        return self.model.linear_tension(self.u)

    def stress(self, method: str = "virial") -> np.ndarray:
        """Per-node stress, shape (N, 2, 2).

        Parameters
        ----------
        method : {"virial", "strain"}
            ``virial``: the lattice's own force-based stress over each Voronoi cell
            (:func:`dvstatic.post.node_stress`); ``strain``: the plane-stress law
            applied to the area-averaged lattice strain
            (:func:`dvstatic.post.strain_stress`), better at free surfaces.
        """
        from .post import node_stress, strain_stress

        if method == "virial":
            return node_stress(self.model, self.u, linear=not self.info.get("nonlinear", False))
        if method == "strain":
            return strain_stress(self.model, self.u)
        raise ValueError(f"unknown stress method {method!r}; accepted: virial, strain")

    def energy(self) -> float:
        """Strain energy ``u.K.u / 2`` of the linear model (energy per unit thickness)."""
        from .post import energy

        return energy(self.model, self.u)


def solve(
    model: VoronoiModel,
    supports=None,
    loads=None,
    *,
    solver: str = "auto",
    rtol: float = 1e-10,
    maxiter: int | None = None,
    nonlinear: bool = False,
    steps: int = 10,
    newton_rtol: float = 1e-8,
    max_iter: int = 25,
    max_cutbacks: int = 8,
    line_search: bool = True,
    allow_unstable: bool = False,
    progress: bool = False,
    check_stability: bool = True,
    best_effort: bool = False,
) -> Solution:
    """Solve the static problem: linear ``K u = f``, or geometrically exact equilibrium.

    Parameters
    ----------
    model : DV or RV
    supports : Fix or list of Fix
        Must prevent all rigid-body motion.
    loads : Traction, BodyForce, PointLoad or a list of them
    solver : {"auto", "direct", "amg", "dynamic-relaxation", "petsc"}
        ``direct``: sparse LU (SuperLU, nested-dissection ordering); ``amg``: CG
        preconditioned by smoothed-aggregation AMG with the rigid-body modes; ``auto``:
        direct up to :data:`dvstatic.linalg.AUTO_DIRECT_MAX_DOF` dofs, AMG above;
        ``dynamic-relaxation``: the explicit pseudo-dynamic scheme of the paper
        (:mod:`dvstatic.relaxation`), linear or nonlinear, as a baseline; ``petsc``:
        distributed over the MPI ranks this script runs on (``mpiexec -n P``), KSP
        CG (GMRES for Newton tangents) with GAMG (:mod:`dvstatic.distributed`; needs
        the ``dvstatic[petsc]`` extra); ``u`` and ``reactions`` are then returned on
        rank 0 only (``None`` on the others). The factorisation or AMG hierarchy is
        cached on the model: later solves with the same supports reuse it.
    rtol : float
        Stopping tolerance on the residual relative to the right-hand side (AMG) or
        to the load (dynamic relaxation), in (0, 1).
    maxiter : int, optional
        AMG iteration limit (default 1000) or dynamic-relaxation steps (default 1e6).
    nonlinear : bool
        Solve ``internal_force(u) = f`` on the current geometry (large displacements
        and rotations) by Newton iterations with load stepping instead of the linear
        system.
    steps : int
        Nonlinear: initial number of load steps (loads and prescribed displacements
        are scaled together); a step that fails is halved and retried, a step that
        converges fast lets the next grow back.
    newton_rtol : float
        Nonlinear: residual tolerance relative to the applied load (or, with only
        prescribed displacements, to the reactions), with an absolute floor of
        ``1e-10 k_n l_mean sqrt(n_dof)``; the increment must also be small.
    max_iter : int
        Nonlinear: Newton iterations per step before the step is cut back.
    max_cutbacks : int
        Nonlinear: how many times a step may be halved in total before giving up.
    line_search : bool
        Nonlinear: backtracking line search on the residual norm.
    allow_unstable : bool
        Nonlinear with the direct solver: accept converged states whose tangent has
        negative pivots (otherwise they raise: buckling or a limit point).
    progress : bool
        Nonlinear: show a progress bar of the load factor on stderr (tqdm).
    check_stability : bool
        Linear: refuse a stiffness that is not positive definite (an unstable lattice).
        With the direct solver the factorisation's inertia gives this for free; with
        AMG, systems up to :data:`dvstatic.stability.CHECK_MAX_DOF` dofs get one extra
        factorisation (its cost is ``info["stability"]["seconds"]``), larger ones rely
        on CG's negative-curvature test. The error gives the admissible nu range for
        systems up to 20,000 dofs.
    best_effort : bool
        When an iteration does not converge (AMG iteration limit, a Newton step that
        fails after every cut-back, dynamic relaxation out of steps or time), return
        the last state instead of raising, marked ``info["converged"] = False`` with
        the reason (``info["failure"]``; for Newton ``info["load_factor"]`` reached).
        Refusals (unstable lattice, non-finite results, singular systems) still raise.

    Returns
    -------
    Solution

    Raises
    ------
    ValueError
        Bad input, or supports that leave a rigid-body motion free.
    SolverError
        The system is singular (a lattice mechanism), not positive definite (an
        unstable lattice or, nonlinear, a buckled or limit state), AMG did not
        converge, or a load step could not be completed after cut-backs; the error
        says which and carries what was tried in ``.info``.
    """
    options = dict(locals())
    if solver == "petsc" and best_effort:
        raise ValueError("best_effort is not available with solver='petsc'")
    # every keyword option, passed on as given (the signature above is the one place
    # they are listed with defaults)
    kwargs = {k: v for k, v in options.items() if k not in _POSITIONAL + ("best_effort",)}
    try:
        return _solve(model, supports, loads, **kwargs)
    except linalg.SolverError as exc:
        if not best_effort or "u" not in exc.info:
            raise
        return _unconverged(model, supports, loads, exc, nonlinear)


_POSITIONAL = ("model", "supports", "loads")


def _listify(items) -> list:
    """None, one item, or a list/tuple of items, as a list."""
    if isinstance(items, (list, tuple)):
        return list(items)
    return [] if items is None else [items]


def _unconverged(model, supports, loads, exc, nonlinear) -> Solution:
    """The last state of a failed iteration, marked unconverged (best effort)."""
    mesh = model.mesh
    supports_l, loads_l = _listify(supports), _listify(loads)
    dofs, _ = constraints(mesh, supports_l)
    lam = exc.info.get("load_factor", 1.0)
    f = lam * load_vector(mesh, loads_l)
    x = np.asarray(exc.info["u"], dtype=float).reshape(-1)
    if nonlinear:
        r_full = model.internal_force(x.reshape(-1, 2)) - f
    else:
        r_full = model._stiffness_bsr @ x - f
    reactions = np.zeros_like(x)
    reactions[dofs] = r_full[dofs]
    info = {k: v for k, v in exc.info.items() if k != "u"}
    info.update(converged=False, failure=str(exc), nonlinear=bool(nonlinear))
    info.setdefault("solver", "unknown")
    log.warning("best effort: returning an unconverged state (%s)", exc)
    return Solution(model, x.reshape(-1, 2), reactions.reshape(-1, 2), info, supports_l, loads_l)


def _solve(
    model: VoronoiModel,
    supports,
    loads,
    *,
    solver,
    rtol,
    maxiter,
    nonlinear,
    steps,
    newton_rtol,
    max_iter,
    max_cutbacks,
    line_search,
    allow_unstable,
    progress,
    check_stability,
) -> Solution:
    """The body of :func:`solve` (options as documented there, defaults set there)."""
    if not isinstance(model, VoronoiModel):
        raise TypeError(f"model must be a dvstatic DV or RV model, got {type(model).__name__}")
    check_choice("solver", solver, linalg.SOLVERS)
    rtol = _unit_interval("rtol", rtol)
    if maxiter is None:
        maxiter = 1_000_000 if solver == "dynamic-relaxation" else 1000
    maxiter = check_int("maxiter", maxiter, minimum=1)
    mesh = model.mesh
    if mesh.is_periodic:
        raise ValueError("solve() needs a bounded mesh; use homogenize() on periodic meshes")
    t_start = time.perf_counter()
    seconds: dict[str, float] = {}
    reused: list[str] = []

    supports_l, loads_l = _listify(supports), _listify(loads)
    if solver == "petsc":
        from .petsc_solve import solve_petsc

        return solve_petsc(
            model,
            supports_l,
            loads_l,
            rtol=rtol,
            maxiter=maxiter,
            nonlinear=bool(nonlinear),
            steps=check_int("steps", steps, minimum=1),
            newton_rtol=_unit_interval("newton_rtol", newton_rtol),
            max_iter=check_int("max_iter", max_iter, minimum=1),
            max_cutbacks=check_int("max_cutbacks", max_cutbacks, minimum=0),
        )
    dofs, values = constraints(mesh, supports_l)
    linalg.check_restrained(mesh.points, dofs)
    f = load_vector(mesh, loads_l)

    t0 = time.perf_counter()
    if _geometry.is_cached(mesh):
        reused.append("geometry")
        seconds["geometry"] = 0.0
    else:
        _geometry.of(mesh)
        seconds["geometry"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    if "_stiffness_bsr" in model.__dict__:
        reused.append("assembly")
    K = model._stiffness_bsr
    seconds["assembly"] = time.perf_counter() - t0

    n = K.shape[0]
    kind = solver
    if kind == "auto":
        kind = "direct" if n <= linalg.AUTO_DIRECT_MAX_DOF else "amg"
    if kind == "dynamic-relaxation":
        return _solve_relaxation(
            model,
            dofs,
            values,
            f,
            rtol,
            maxiter,
            nonlinear,
            seconds,
            reused,
            t_start,
            supports_l,
            loads_l,
        )
    if nonlinear:
        opts = NewtonOptions(
            steps=check_int("steps", steps, minimum=1),
            rtol=_unit_interval("newton_rtol", newton_rtol),
            max_iter=check_int("max_iter", max_iter, minimum=1),
            max_cutbacks=check_int("max_cutbacks", max_cutbacks, minimum=0),
            line_search=bool(line_search),
            solver=kind,
            allow_unstable=bool(allow_unstable),
            progress=bool(progress),
        )
        t0 = time.perf_counter()
        x, ninfo = solve_nonlinear(model, dofs, values, f, opts)
        seconds["solve"] = time.perf_counter() - t0
        state, _ = _residual(model, x, f, dofs)
        r_full = state[1]
        u = x.reshape(-1, 2)
        reactions = np.zeros(n)
        reactions[dofs] = r_full[dofs]
        seconds["total"] = time.perf_counter() - t_start
        info = {
            "solver": kind,
            "nonlinear": True,
            "n_dof": n,
            "n_constrained": int(dofs.size),
            "converged": True,
            "seconds": seconds,
            "reused": reused,
        }
        info.update(ninfo)
        info["residuals"] = [s for st in ninfo["steps"] for s in st["residuals"]]
        return Solution(model, u, reactions.reshape(-1, 2), info, supports_l, loads_l)
    t0 = time.perf_counter()
    system, engine, stab = _engine(model, kind, dofs, check_stability, supports_l, reused)
    b = system.rhs(f, values)
    seconds["setup"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    if kind == "direct":
        x, sinfo = engine.solve(b)
    else:
        x, sinfo = engine.solve(b, rtol=rtol, maxiter=maxiter)
    seconds["solve"] = time.perf_counter() - t0

    info = {
        "solver": kind,
        "nonlinear": False,
        "n_dof": n,
        "n_constrained": int(dofs.size),
        "iterations": sinfo["iterations"],
        "residuals": sinfo["residuals"],
        "stability": stab,
        "coupling_assembled": model.nu_m != 0.0,
    }
    if sinfo.get("indefinite"):
        info["converged"] = False
        raise linalg.SolverError(_unstable_message(model, None, supports_l), info)
    residual = sinfo["residuals"][-1]
    limit = 1e-8 if kind == "direct" else max(10 * rtol, 1e-14)
    backward = sinfo.get("backward_error")
    if backward is not None:
        info["backward_error"] = backward
    # a direct solve is accepted at the rounding floor too: with slivers the internal
    # forces are ~(R/l) times the load and cancel, so |r| / |f| cannot reach 1e-8 while
    # the normwise backward error |r| / (|K| |u| + |f|) is still at machine level
    at_floor = kind == "direct" and backward is not None and backward <= BACKWARD_LIMIT
    if not np.all(np.isfinite(x)) or not (residual <= limit or at_floor):
        info["converged"] = False
        reason = (
            "a non-finite result"
            if not np.all(np.isfinite(x))
            else (f"relative residual {residual:.3e} > {limit:.1e}")
        )
        if np.all(np.isfinite(x)):
            info.update(u=x.copy(), residual=residual)
        raise linalg.SolverError(
            f"{kind} solve failed with {reason} after {sinfo['iterations']} iteration(s): the "
            "system is singular or badly conditioned (lattice mechanism or unstable "
            "micro-parameters)" + ("; try solver='direct'" if kind == "amg" else ""),
            info,
        )
    u = x.reshape(-1, 2)
    r_full = K @ x - f
    reactions = np.zeros(n)
    reactions[dofs] = r_full[dofs]
    seconds["total"] = time.perf_counter() - t_start
    info.update(converged=True, residual=residual, seconds=seconds, reused=reused)
    log.info(
        "%s %s solve: %d dof, %d iterations, residual %.2e, %.3f s",
        model.kind,
        kind,
        n,
        info["iterations"],
        residual,
        seconds["total"],
    )
    return Solution(model, u, reactions.reshape(-1, 2), info, supports_l, loads_l)


def _engine(model, kind, dofs, check_stability, supports, reused):
    """Constrained system and factorisation / AMG hierarchy, cached on the model.

    The cache holds the last engine per model, keyed by solver and constrained dofs:
    new load cases or prescribed values with the same supports reuse it.
    """
    key = (kind, dofs.tobytes(), bool(check_stability))
    cache = model.__dict__.setdefault("_engine_cache", {})
    if key in cache:
        reused.append("factorisation" if kind == "direct" else "amg hierarchy")
        return cache[key]
    mesh = model.mesh
    K = model._stiffness_bsr
    n = K.shape[0]
    system = linalg.ConstrainedSystem(K, dofs)
    if kind == "direct":
        engine = linalg.DirectSolver(system.A, order=mesh_dof_order(mesh))
    else:
        engine = linalg.AMGSolver(system.A, linalg.rigid_modes(mesh.points))
    stab = {"checked": False, "method": "none", "negative_eigenvalues": None, "seconds": 0.0}
    if check_stability:
        t_st = time.perf_counter()
        if kind == "direct":
            stab.update(
                checked=engine.negative_pivots is not None,
                method="ldl-inertia",
                negative_eigenvalues=engine.negative_pivots,
            )
        elif n <= CHECK_MAX_DOF:
            probe = linalg.DirectSolver(system.A, order=mesh_dof_order(mesh))
            stab.update(
                checked=probe.negative_pivots is not None,
                method="ldl-inertia",
                negative_eigenvalues=probe.negative_pivots,
            )
            del probe
        else:
            stab.update(method="cg-curvature")
        stab["seconds"] = time.perf_counter() - t_st
        if stab["negative_eigenvalues"]:
            raise linalg.SolverError(
                _unstable_message(model, stab["negative_eigenvalues"], supports),
                {"solver": kind, "stability": stab},
            )
    cache.clear()
    cache[key] = (system, engine, stab)
    return cache[key]


def _solve_relaxation(
    model, dofs, values, f, rtol, maxiter, nonlinear, seconds, reused, t_start, supports, loads
) -> Solution:
    from .relaxation import dynamic_relaxation

    t0 = time.perf_counter()
    x, dinfo = dynamic_relaxation(
        model, dofs, values, f, rtol=rtol, max_steps=maxiter, nonlinear=nonlinear
    )
    seconds["solve"] = time.perf_counter() - t0
    if nonlinear:
        r_full = model.internal_force(x.reshape(-1, 2)) - f
    else:
        r_full = model._stiffness_bsr @ x - f
    reactions = np.zeros_like(x)
    reactions[dofs] = r_full[dofs]
    seconds["total"] = time.perf_counter() - t_start
    info = {
        "solver": "dynamic-relaxation",
        "nonlinear": bool(nonlinear),
        "n_dof": len(x),
        "n_constrained": int(dofs.size),
        "converged": True,
        "seconds": seconds,
        "reused": reused,
        "coupling_assembled": model.nu_m != 0.0,
        **dinfo,
    }
    info["seconds"] = seconds
    return Solution(model, x.reshape(-1, 2), reactions.reshape(-1, 2), info, supports, loads)


def _unstable_message(model: VoronoiModel, count: int | None, supports) -> str:
    what = f"{count} negative eigenvalue(s)" if count else "a negative curvature direction"
    msg = (
        f"the {model.kind} stiffness with these supports is not positive definite ({what}): "
        f"the lattice is unstable for nu = {model.nu} (nu_m = {model.nu_m:.4g}) on this mesh, "
        "so its equilibrium would not be a physical solution"
    )
    if 2 * model.mesh.n_points <= RANGE_IN_MESSAGE_MAX_DOF:
        from .stability import stability

        try:
            rep = stability(model, supports)
            msg += (
                f"; admissible for this mesh and these supports: nu_m in "
                f"({rep.nu_m_range[0]:.4g}, {rep.nu_m_range[1]:.4g}), i.e. nu in "
                f"({rep.nu_range[0]:.4g}, {rep.nu_range[1]:.4g})"
            )
        except Exception as exc:  # the range is a courtesy; the refusal stands
            log.warning("stability range not computed: %s", exc)
    else:
        msg += "; call dv.stability(model, supports) for the admissible nu range"
    return msg + (
        ". Irregular meshes (obtuse triangles) shrink the stable range, DV more "
        "than RV: use a more regular mesh (lattice, cvt) or the RV model"
    )


def _unit_interval(name: str, value) -> float:
    v = check_positive(name, value)
    if v >= 1:
        raise ValueError(f"{name} must be in (0, 1), got {v}")
    return v
