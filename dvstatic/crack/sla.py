"""Event-driven fracture: sequentially linear analysis (SLA) with factorisation updates.

Each event solves the damaged lattice for the reference loads (one unit of the load
factor) and for the held loads (at full value), finds the bond that reaches its
strength (:mod:`.criteria`) at the smallest load factor under held + factor x reference,
records that state and then softens or removes that bond. Every recorded state is an
exact equilibrium of the linear lattice at its load factor with the held loads at full
value; snap-backs appear in the load-displacement curve as they come (the load factor
of the next event may be lower). Bonds the held loads alone overload break first, at
load factor 0, one event each.

Fracture breaks the lattice ``dv.solve`` solves, exact boundary cells and the regional
isotropy's terms included, so that a crack starts from the stresses the elastic
solution has (at a bore's crown on a CVT mesh, a / h = 12.5, the plain lattice's
recovered hoop stress is 17 % low where the model's is 7-11 %). Those terms have no
softening law: a triangle holding one loses its whole coupling at its first damaged
bond (:func:`~dvstatic.lattice.operator.coupling_factor`) and is a set of plain springs
from there on. The choice was measured on Petersson's notched beam (validation/
fracture.py, peak against the cohesive crack's 0.853 kN), jittered h = 14 / 10 / 7 / 5 mm
and CVT 10 / 7 / 5 mm: plain lattice at the boundary 0.931 / 0.918 / 0.902 / 0.895 and
0.885 / 0.874 / 0.874 kN; cells kept in proportion to the weakest bond 1.244 / 0.900 /
0.874 / 0.950 and 1.004 / 0.904 / 0.915; cells dropped at the first damaged bond 0.910 /
0.925 / 0.921 / 0.901 and 0.917 / 0.895 / 0.896 (measured before the criterion's face
stress of surface bonds became their own triangle's; docs/fracture.md has today's numbers).
"""

from __future__ import annotations

import dataclasses
import inspect
import logging
import time

import numpy as np

from ..errors import InputError, UnstableError
from ..lattice import VoronoiModel
from ..lattice.damage import split as _split
from ..mesh import Mesh
from ..problem import Problem
from ..solvers.info import SolveInfo, StabilityCheck
from ..solvers.linear import unstable_message
from ..solvers.options import options_docstring
from .bonds import Bonds, Kept
from .contact import Contact
from .control import criterion_parameters, held_problem, reference
from .criteria import MODES, criterion_for
from .energies import GF_SHEAR_RATIO, fracture_energies, shear_energies
from .options import FractureOptions
from .pieces import Pieces, bond_triangles
from .result import Event, FractureResult, FractureStats, FractureTimings, Snapshot
from .search import EventSearch
from .stops import stop_after
from .strength import Weibull
from .updates import UpdatedSolver

log = logging.getLogger(__name__)

__all__ = ["fracture", "EQUILIBRIUM_TOL"]

#: relative residual every recorded state must reach
EQUILIBRIUM_TOL = 1e-10


def _state(solver, w, g, control, ref, f, fh=None):
    """Solve the damaged lattice per unit load factor (``fh`` None) or for the held
    forces ``fh`` (the supports at rest): displacement, relative residual, and its part
    of the conjugate (load, displacement): the load factor's coefficients, or the held
    part's constant terms (force control: no load, the displacement along ``f``;
    displacement control: the reactions' work on the control, no displacement); ``w,
    g`` the damaged stiffness's factors."""
    x, res = solver.solve(w, g, EQUILIBRIUM_TOL, fh)
    if control == "force":
        return x, res, (0.0 if fh is not None else ref), float(f @ x) / ref
    reaction = solver.prescribed_forces(x, w, g) - (f if fh is None else fh)[solver.dofs]
    return x, res, float(reaction @ solver.values) / ref, (0.0 if fh is not None else ref)


def _check_start(model, start) -> None:
    if start is None:
        return
    if not isinstance(start, FractureResult) or start.bond_state is None:
        raise TypeError(f"start must be the FractureResult of a run, got {type(start).__name__}")
    mesh = start.model.mesh
    same = mesh is model.mesh or (
        mesh.n_bonds == model.mesh.n_bonds and np.array_equal(mesh.points, model.mesh.points)
    )
    if not same:
        raise InputError("start: the run was made on another mesh than the model's", "start")


def _same_friction(state: dict, criterion, sheared: np.ndarray) -> None:
    """Refuse to go on softening sheared faces with another friction angle: their
    thresholds are values of the earlier run's Coulomb measure ``s tau + sigma_n tan``."""
    old, new = state.get("tan"), getattr(criterion, "tan", None)
    if not np.any(sheared) or old is None or new is None:
        return
    if not np.allclose(old[sheared], new[sheared], rtol=1e-12, atol=0.0):
        k = int(np.flatnonzero(sheared & ~np.isclose(old, new, rtol=1e-12, atol=0.0))[0])
        raise InputError(
            f"start: the earlier run softened {int(sheared.sum())} face(s) in shear or "
            f"crushing with friction_angle {np.degrees(np.arctan(old[k])):.6g} deg at bond "
            f"{k}, got {np.degrees(np.arctan(new[k])):.6g} deg: their thresholds are values "
            f"of Coulomb's measure with the earlier angle; go on with the same "
            f"friction_angle",
            "friction_angle",
        )


def _check_options(model, weibull) -> None:
    if not isinstance(model, VoronoiModel):
        raise TypeError(f"model must be a DV or RV model, got {type(model).__name__}")
    if model.mesh.is_periodic:
        raise InputError("fracture needs a bounded mesh, got a periodic one", "model")
    if weibull is not None and not isinstance(weibull, Weibull):
        raise TypeError(f"weibull must be a dvstatic.crack.Weibull, got {type(weibull).__name__}")


def fracture(
    model: VoronoiModel,
    supports,
    loads=None,
    *,
    held=None,
    ft,
    gf=None,
    gf_shear=None,
    cohesion=None,
    friction_angle=None,
    weibull: Weibull | None = None,
    start: FractureResult | None = None,
    options: FractureOptions | None = None,
    **kwargs,
) -> FractureResult:
    opts = FractureOptions.from_kwargs(options, **kwargs)
    _check_options(model, weibull)
    _check_start(model, start)
    params = criterion_parameters(opts.criterion, cohesion=cohesion, friction_angle=friction_angle)
    shear_energy = shear_energies(model, opts.criterion, gf, gf_shear)
    timings: dict[str, float] = {}
    t_start = time.perf_counter()
    problem = Problem.build(model, supports, loads)
    dofs, values, f, control, ref = reference(model, problem)
    kept = held_problem(model, held)
    sp_ = _split(model)
    criterion = criterion_for(opts.criterion, model, sp_)
    s0, s_tension = criterion.prepare(model, ft, weibull, timings, dofs, params)
    energy = None if gf is None else fracture_energies(model, gf, s_tension)
    energy = (energy, shear_energy)
    _warn_rows(model.mesh)
    fh = None if kept is None else kept.f
    res = _run(
        model,
        sp_,
        criterion,
        s0,
        energy,
        (dofs, values, f, control, ref, fh),
        timings,
        t_start,
        opts,
        start,
        problem.supports,
    )
    return dataclasses.replace(
        res,
        supports=problem.supports,
        loads=problem.loads,
        held=() if kept is None else kept.loads,
    )


def _signature() -> inspect.Signature:
    kw = inspect.Parameter.KEYWORD_ONLY
    params = [
        inspect.Parameter("model", inspect.Parameter.POSITIONAL_OR_KEYWORD),
        inspect.Parameter("supports", inspect.Parameter.POSITIONAL_OR_KEYWORD),
        inspect.Parameter("loads", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None),
        inspect.Parameter("held", kw, default=None),
        inspect.Parameter("ft", kw),
        inspect.Parameter("gf", kw, default=None),
        inspect.Parameter("gf_shear", kw, default=None),
        inspect.Parameter("cohesion", kw, default=None),
        inspect.Parameter("friction_angle", kw, default=None),
        inspect.Parameter("weibull", kw, default=None),
        inspect.Parameter("start", kw, default=None),
        inspect.Parameter("options", kw, default=None),
    ]
    defaults = FractureOptions()
    for name in FractureOptions.__dataclass_fields__:
        params.append(inspect.Parameter(name, kw, default=getattr(defaults, name)))
    return inspect.Signature(params, return_annotation=FractureResult)


fracture.__signature__ = _signature()
fracture.__doc__ = f"""Quasi-static fracture by bond breaking, event by event (sequentially linear).

    Parameters
    ----------
    model : DV or RV
        The lattice (its calibration, thickness and materials).
    supports : Fix or list of Fix
        Supports; non-zero prescribed values make the analysis displacement controlled.
    loads : load or list of loads, optional
        Reference loads (``Traction``, ``Pressure``, ``BodyForce``, ``PointLoad``). The
        loads and the prescribed displacements are multiplied by the load factor.
    held : load or list of loads, optional
        Loads applied at full value in every state (self-weight, an in-situ stress, a
        confining pressure), with the supports at rest; only ``loads`` and the
        prescribed displacements grow. Bonds the held loads alone break go first, at
        load factor 0.
    ft : float or dict
        Tensile strength (stress units), or ``{{"default": ft, region: ft_r}}``.
    gf : float or dict, optional
        Fracture energy (energy per unit crack area, e.g. N/m): a bond cracked in
        tension softens in ``teeth`` saw-tooth steps. None: brittle bonds (removed at
        their strength).
    gf_shear : float or dict, optional
        Fracture energy of faces that fail in shear or crushing (``criterion=
        "mohr-coulomb"`` only): their bonds soften in teeth along the face's Coulomb
        measure of its triangles' trial stress, as a crack band one face wide releasing
        ``(pi / 4) gf_shear t r_e`` of the continuum's energy (the lattice itself
        releases only a few % of it through the face's bond: docs/fracture.md). None:
        ``{GF_SHEAR_RATIO:g} gf`` (brittle without ``gf``); 0: such faces lose their bond
        at once.
    cohesion, friction_angle : float or dict, optional
        Cohesion (stress units, > 0) and friction angle (degrees, in [0, 70)) of
        ``criterion="mohr-coulomb"`` (required by it, refused by the others), per region
        like ``ft``. The continuum's uniaxial compressive strength is
        ``2 c cos(phi) / (1 - sin(phi))`` (:func:`dvstatic.crack.ucs`).
    weibull : Weibull, optional
        Random strength field.
    start : FractureResult, optional
        Go on from the end of this earlier run on the same mesh (its cracked and broken
        bonds, their teeth, the faces cracked in tension that can close) under new
        supports and loads: e.g. crack in tension, then compress. Intact bonds take
        the strengths of the new problem; faces softening in shear or crushing need
        the same criterion and ``friction_angle``.
    options : FractureOptions, optional
        All options at once; keywords given as well override it.
{options_docstring(cls=FractureOptions)}

    Returns
    -------
    FractureResult

    Raises
    ------
    InputError
        Bad ``ft``, ``gf`` (or one too small for the mesh) or option, no load, supports
        that leave a rigid motion free, a periodic mesh.
    TypeError
        An unknown option, or an option of the wrong type.
    """


#: mesh kinds already warned about (once per process, as :mod:`warnings` would)
_WARNED: set[str] = set()


def _warn_rows(mesh: Mesh) -> None:
    """Say once that a mesh of lattice rows steers cracks along its rows."""
    sampling = mesh.sampling
    if sampling is not None and sampling.has_rows and sampling.kind not in _WARNED:
        _WARNED.add(sampling.kind)
        log.warning(
            "mesh kind %r has lattice rows: cracks tend to run along them (0, 60 or 120 "
            "degrees); for fracture, kind='cvt' gives paths free of that bias",
            sampling.kind,
        )


class _Analysis(EventSearch):
    """The event loop of :func:`fracture`: state, one event, the result."""

    def __init__(self, model, sp_, criterion, s0, energy, problem, opts):
        self.dofs, self.values, self.f, self.control, self.ref, self.fh = problem
        self.model, self.sp, self.criterion, self.s0, self.opts = model, sp_, criterion, s0, opts
        self.bonds = Bonds(s0, model.operator.spring, energy[0], opts.teeth, energy[1])
        self.solver = UpdatedSolver(
            model.mesh, sp_, self.dofs, self.values, self.f, max_rank=opts.max_rank
        )
        loaded = self.f if self.fh is None else np.abs(self.f) + np.abs(self.fh)
        self.pieces = Pieces(model, self.dofs, self.values, loaded, opts.fragment)
        self.bond_tris = bond_triangles(model.mesh)
        self.contact = Contact(model.mesh.n_bonds, opts.contact)
        self.spring = np.bincount(sp_.tri_bonds.ravel(), sp_.w.ravel(), sp_.n_bonds)
        self.initial = None
        self._factors = None
        self.snaps = Kept(opts.snapshots, opts.snapshot_every)
        self.events: list[Event] = []
        self.broken: list[int] = []
        self.peak = 0.0
        #: faces failing in shear or crushing that broke at once although gf_shear is given
        self.sheared_at_once = 0

    def resume(self, state: dict) -> None:
        """Start from the damage of an earlier run (before :meth:`start`).

        Raises
        ------
        InputError
            The earlier run softened faces in shear or crushing and this criterion has
            no such faces (their teeth count in its Coulomb measure).
        """
        sheared = (state["mode"] != 0) & (state["d"] > 0) & (state["d"] < 1)
        if np.any(sheared) and not self.criterion.shear:
            raise InputError(
                f"start: the earlier run left {int(sheared.sum())} face(s) softening in "
                f"shear or crushing, whose teeth count in Coulomb's measure: go on with "
                f"criterion='mohr-coulomb' (got {self.criterion.name!r})",
                "criterion",
            )
        _same_friction(state, self.criterion, sheared)
        self.bonds.load(state)
        self.contact.cracked[:] = state["cracked"]
        self.initial = self.bonds.d.copy()

    def _state(self) -> dict:
        """The bonds' state for ``start=``, with the friction their measures used."""
        tan = getattr(self.criterion, "tan", None)
        return {**self.bonds.state(self.contact.cracked), "tan": tan}

    @property
    def solved(self) -> np.ndarray:
        """The bond factors as the pieces see them (closed faces hold: 1)."""
        return self.contact.effective(self.bonds.d)

    def factors(self):
        """The damaged stiffness's factors ``(w, g)``, closed cracks with their spring
        (kept while the damage and the contact status stay the same; read only). Only
        the triangles of bonds whose factor or status changed are recomputed."""
        return self._damage_state()[0]

    def _damage_state(self):
        """``((w, g), intact)`` of the current damage and contact status (intact: 1.0 for
        a triangle none of whose bonds is damaged, (M,)), updated on the triangles of the
        bonds that changed since the last call."""
        d, closed = self.bonds.d, self.contact.closed
        memo, tb = self._factors, self.sp.tri_bonds
        if memo is None:
            tris = slice(None)
            w, g, intact = np.empty_like(self.sp.w), np.empty_like(self.sp.g), np.empty(len(tb))
        else:
            moved = np.flatnonzero((memo[0] != d) | (memo[1] != closed))
            if not len(moved):
                return memo[2]
            tris = np.unique(self.bond_tris[moved])
            (w, g), intact = (a.copy() for a in memo[2][0]), memo[2][1].copy()
        w[tris], g[tris] = self.sp.factors(d, closed if closed.any() else None, tris)
        intact[tris] = np.all(d[tb[tris]] >= 1.0, axis=1)
        self._factors = (d.copy(), closed.copy(), ((w, g), intact))
        return self._factors[2]

    def start(self, supports=()) -> None:
        """The first state; ``supports`` name the problem in an instability's message.
        Raises UnstableError where the lattice is not stable with these supports (its
        factorisation's inertia, as ``dv.solve`` checks it; ``check_stability``)."""
        # from the undamaged system the criterion's responses factorised, if this run
        # starts undamaged (else that one is freed before the new one is made)
        fac, self.criterion.factorised = self.criterion.factorised, None
        if self.initial is not None:
            fac = None
        self.solver.rebase(*self.factors(), fac)
        neg = self.solver.negative
        if neg and self.opts.check_stability:
            msg = unstable_message(self.model, neg, supports)
            raise UnstableError(
                ("the damaged " if self.initial is not None else "")
                + msg
                + "; dv.fracture(..., check_stability=False) breaks it anyway",
                SolveInfo("direct", stability=StabilityCheck(True, "ldl-inertia", neg)),
                negative_eigenvalues=neg,
            )
        self._factored = self.solver.factorisations
        self._solve()
        self.x_last = self.x
        self.k_initial = self.p_ref / self.u_ref

    def _solve(self) -> None:
        args = (self.solver, *self.factors(), self.control, self.ref, self.f)
        self.x, self.res, self.p_ref, self.u_ref = _state(*args)
        self.xh, self.p_held, self.u_held = None, 0.0, 0.0
        if self.fh is not None:
            self.xh, res, self.p_held, self.u_held = _state(*args, self.fh)
            self.res = max(self.res, res)

    def step(self, k: int):
        """Event ``k``; returns (reason, message) if the analysis stops, else None. Ctrl-C
        during the event undoes its bond change (the result stays consistent)."""
        bonds = self.bonds
        crit = self._critical()
        x = self.x
        e, lam = crit.bond, crit.factor
        if not np.isfinite(lam):
            return "no_tension", self.criterion.never_fails(k == 0)
        saved = bonds.save(e)
        cracked, closed = bool(self.contact.cracked[e]), self.contact.closed.copy()
        before = (self.res, self.p_ref, self.u_ref, self.xh, self.p_held, self.u_held)
        state = (self._at(lam), self.factors()) if self.fh is not None else None
        try:
            peak, sense, spring = crit.elongation, 1.0, None
            sheared = crit.mode != 0 and bonds.d[e] >= 1.0
            if sheared:
                peak, sense, spring = self.criterion.crack_measure(
                    e, crit.mode, self._at(lam), bonds.d
                )
            removed = bonds.advance(e, peak, crit.mode, sense, spring)
            if sheared and removed and bonds.energy_shear is not None:
                self.sheared_at_once += 1
            if crit.mode == 0:
                self.contact.cracked[e] = True
            self.solver.touch(self.bond_tris[e])
            if self.opts.max_rank == 0:
                self.solver.rebase(*self.factors())
            self._solve()
        except KeyboardInterrupt:  # the event did not happen: undo the bond's change
            bonds.restore(e, saved)
            self.contact.cracked[e] = cracked
            raise
        res, p_ref, u_ref, xh, p_held, u_held = before
        delta = lam * u_ref
        # energy released at fixed control displacement: 1/2 delta (P - P') (of the
        # growing part)
        after = delta * self.p_ref / self.u_ref if self.u_ref else 0.0
        ev = Event(
            index=k,
            load_factor=lam,
            bond=e,
            control_displacement=u_held + delta,
            load=p_held + lam * p_ref,
            tooth=int(saved[1]),
            broken=removed,
            residual=res,
            released=(
                0.5 * delta * (lam * p_ref - after)
                if state is None
                else self._released(lam, *state)
            ),
            elongation=crit.elongation,
            spring_lost=float(saved[0][e] - bonds.d[e]),
            mode=MODES[crit.mode],
            closed=tuple(int(b) for b in np.flatnonzero(closed)),
        )
        self.events.append(ev)
        self.x_last = lam * x if xh is None else xh + lam * x
        if removed:
            self.broken.append(e)
        snap = Snapshot(k, self.x_last.reshape(-1, 2), saved[0], closed if closed.any() else None)
        self.snaps.add(snap, ev.load > self.peak)
        self.peak = max(self.peak, ev.load)
        stop = stop_after(
            self.pieces,
            self.solved,
            removed,
            self.model.mesh.topology.bonds[e],
            self.model,
            ev,
            self.peak,
            self.res,
            self.opts.stop_load_ratio,
            k,
            self.p_ref / self.u_ref / self.k_initial,
        )
        if stop is not None and self.fh is not None and lam == 0.0 and stop[0] == "separated":
            stop = (stop[0], "under the held loads alone (load factor 0): " + stop[1])
        return stop or self._unstable(k)

    def _unstable(self, k: int):
        """("unstable", message) if a factorisation made since the last check finds the
        damaged stiffness indefinite (checked at every fresh factorisation: the updates
        in between are not factorised), else None."""
        if self.solver.factorisations == self._factored or not self.opts.check_stability:
            return None
        self._factored = self.solver.factorisations
        if not self.solver.negative:
            return None
        return "unstable", (
            f"after event {k} the damaged stiffness is not positive definite "
            f"({self.solver.negative} negative eigenvalue(s) of a fresh factorisation): "
            "the damaged lattice is unstable, its states beyond would not be equilibria "
            "of a physical solid"
        )

    def _released(self, lam: float, u0: np.ndarray, factors0) -> float:
        """With held loads: the energy the event releases with every load and prescribed
        displacement fixed, ``F . (u' - u) / 2 + u_p . (R - R') / 2`` (``u``, ``R``
        before the bond's change, ``u'``, ``R'`` after it, at the same load factor)."""
        f = self._loads(lam)
        u1 = self._at(lam)
        r0 = (self.sp.internal(u0, *factors0) - f)[self.dofs]
        r1 = (self.sp.internal(u1, *self.factors()) - f)[self.dofs]
        return float(0.5 * f @ (u1 - u0) + 0.5 * (lam * self.values) @ (r0 - r1))

    def result(self, reason, message, timings, loop: float) -> FractureResult:
        mesh, events = self.model.mesh, self.events
        if self.sheared_at_once:
            log.warning(
                "%d face(s) failing in shear or crushing broke at once despite gf_shear: "
                "their share of gf_shear was below the elastic energy of their part of the "
                "body at failure, or their trial measure was not positive (a larger "
                "gf_shear or a finer mesh softens them)",
                self.sheared_at_once,
            )
        return FractureResult(
            model=self.model,
            events=tuple(events),
            u=self.x_last.reshape(-1, 2) if events else np.zeros((mesh.n_points, 2)),
            stiffness=self.bonds.d.copy(),
            broken=np.array(self.broken, dtype=np.int64),
            initial=self.initial,
            bond_state=self._state(),
            snapshots=self.snaps.states(),
            stop_reason=reason,
            message=message,
            control=self.control,
            strength=self.s0,
            seconds=FractureTimings(**timings),
            stats=FractureStats(
                factorisations=self.solver.factorisations,
                max_rank=self.opts.max_rank,
                events_per_second=len(events) / loop if loop > 0 else float("nan"),
                max_residual=max((ev.residual for ev in events), default=0.0),
            ),
        )


def _run(
    model, sp_, criterion, s0, energy, problem, timings, t_start, opts, start=None, supports=()
) -> FractureResult:
    """The event loop (see :func:`fracture`); Ctrl-C keeps the events so far."""
    run = _Analysis(model, sp_, criterion, s0, energy, problem, opts)
    if start is not None:
        run.resume(start.bond_state)
    n = opts.max_events
    reason, message = "max_events", f"stopped after max_events = {n} events"
    t0 = time.perf_counter()
    timings["setup"] = t0 - t_start
    run.start(supports)
    bar = _bar(opts.progress, n)
    try:
        with _blas_threads(opts.blas_threads):
            stop = _loop(run, n, bar, opts, t0)
        if stop is not None:
            reason, message = stop
    except KeyboardInterrupt:
        reason, message = "interrupted", f"interrupted after {len(run.events)} events"
        log.warning("fracture: %s; returning what was computed", message)
    finally:
        if bar is not None:
            bar.close()
    loop = time.perf_counter() - t0
    timings["events"] = loop
    timings["factorisation"] = run.solver.factor_seconds
    log.info("fracture: %d events, %d bonds broken, %s", len(run.events), len(run.broken), message)
    return run.result(reason, message, timings, loop)


def _loop(run, n: int, bar, opts, t0: float):
    """Events 0 .. n-1 (or until a stop, returned as (reason, message))."""
    for k in range(n):
        stop = run.step(k)
        if bar is not None:
            bar.update(1)
            bar.set_postfix(
                load=f"{run.events[-1].load:.4g}" if run.events else "",
                broken=len(run.broken),
                refresh=False,
            )
        if stop is None and opts.max_seconds and time.perf_counter() - t0 > opts.max_seconds:
            stop = (
                "time_limit",
                (f"stopped at the time limit of {opts.max_seconds:g} s after {k + 1} events"),
            )
        if stop is not None:
            return stop
    return None


def _blas_threads(threads: int | None):
    """The BLAS thread pools limited to ``threads`` (None: left as they are)."""
    import contextlib

    if threads is None:
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=threads, user_api="blas")


def _bar(progress: bool, total: int):
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="events", unit="event")
