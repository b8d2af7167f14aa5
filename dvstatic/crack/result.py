"""Results of a fracture analysis: the events, the load-displacement curve, snapshots."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from .criteria import MODES

__all__ = ["Event", "Snapshot", "FractureResult", "FractureTimings", "FractureStats"]


@dataclass(frozen=True)
class Event:
    """One bond reaching its strength.

    Attributes
    ----------
    index : int
        Event number (0 first).
    load_factor : float
        The loads (and prescribed displacements) are ``load_factor`` times the given ones.
    bond : int
        The bond that reached its strength.
    control_displacement : float
        Displacement work-conjugate to the load (length): force control, ``f . u /
        F_ref`` (the mean displacement of the loaded points along their loads);
        displacement control, the largest prescribed displacement.
    load : float
        Force work-conjugate to ``control_displacement`` (force): ``load_factor *
        F_ref``, or the reactions' work on the prescribed displacements over the largest.
    tooth : int
        Saw-tooth step the bond reached (0: first crack).
    broken : bool
        True if the bond is removed by this event (its last tooth).
    residual : float
        Relative residual of the equilibrium solve of this state.
    released : float
        Energy released by the event at fixed control displacement (force x length);
        with held loads, with every load and prescribed displacement fixed.
    elongation : float
        The bond's elongation at the event (length).
    spring_lost : float
        The part of the bond's spring the event took: its stiffness factor before the
        event minus after it.
    closed : tuple of int
        The faces cracked in tension that are closed in the recorded state (in contact:
        their bonds carry compression with their whole spring).
    mode : str
        How the bond's face failed: "tension", "shear" (Coulomb's line, the face not in
        compression) or "crushing" (Coulomb's line, the face in compression); the later
        teeth of a softening bond keep the mode of its first failure (a face cracked in
        tension softens along its elongation, one failed in shear or crushing along its
        Coulomb measure, with ``gf_shear``).

    With held loads, ``load`` and ``control_displacement`` are those of the whole state
    (held + ``load_factor`` x reference): force control, the growing load and the
    displacement along it; displacement control, the reactions (the held loads' part
    included) and the control displacement.
    """

    index: int
    load_factor: float
    bond: int
    control_displacement: float
    load: float
    tooth: int
    broken: bool
    residual: float
    released: float = float("nan")
    elongation: float = float("nan")
    spring_lost: float = float("nan")
    mode: str = "tension"
    closed: tuple = ()


@dataclass(frozen=True)
class Snapshot:
    """The state at an event: displacement ``u`` (N, 2) at its critical load, the bond
    stiffness factors ``stiffness`` (n_bonds,) (1 intact, 0 broken) before the event and
    the ``closed`` cracks (bool, n_bonds; in contact, with their whole spring; None:
    none). ``model.damaged(stiffness, closed)`` is the lattice the state solves."""

    event: int
    u: np.ndarray
    stiffness: np.ndarray
    closed: np.ndarray | None = None


@dataclass(frozen=True)
class FractureTimings:
    """Wall time of the stages of a fracture analysis (s)."""

    setup: float = 0.0  #: the problem, the split stiffness, the criterion
    #: the bonds' responses to uniform stress and their strengths (with the first
    #: factorisation, which the event loop takes over when it starts undamaged)
    strength: float = 0.0
    events: float = 0.0  #: the event loop
    factorisation: float = 0.0  #: of which factorising the stiffness afresh


@dataclass(frozen=True)
class FractureStats:
    """How the event loop went."""

    factorisations: int = 0  #: stiffness factorisations (1 + refactorisations)
    max_rank: int = 0  #: the largest low-rank update allowed (FractureOptions.max_rank)
    events_per_second: float = float("nan")
    max_residual: float = 0.0  #: the largest relative residual of a recorded state


@dataclass(frozen=True)
class FractureResult:
    """What :func:`dvstatic.fracture` returns.

    Attributes
    ----------
    events : tuple of Event
    u : ndarray, shape (N, 2)
        Displacement at the last event's critical load.
    stiffness : ndarray, shape (n_bonds,)
        Bond stiffness factors at the end (1 intact, 0 broken).
    broken : ndarray of int
        Broken bonds, in the order they broke.
    snapshots : tuple of Snapshot
    stop_reason : str
        "max_events", "load_drop", "separated", "interrupted", "time_limit"
        (``FractureOptions.max_seconds``) or "no_tension" (no unbroken bond is loaded
        towards its strength).
    message : str
        One line saying why the analysis stopped.
    control : str
        "force" or "displacement".
    strength : ndarray, shape (n_bonds,)
        First-crack strength of every bond (force).
    seconds : FractureTimings
        Wall time per stage.
    stats : FractureStats
        Factorisations, largest update rank, events per second, largest residual.
    supports, loads : tuple
        The problem's supports and reference loads (scaled by each event's load factor).
    held : tuple
        The held loads (at full value in every state).

    Every state is a model: :meth:`stiffness_at` gives the bond factors at an event,
    :meth:`solution` the :class:`~dvstatic.Solution` of the damaged lattice there (its
    ``stress()``, the writers and the checks as for any solve).
    """

    model: object
    events: tuple
    u: np.ndarray
    stiffness: np.ndarray
    broken: np.ndarray
    snapshots: tuple
    stop_reason: str
    message: str
    control: str
    strength: np.ndarray
    seconds: FractureTimings = field(default_factory=FractureTimings)
    stats: FractureStats = field(default_factory=FractureStats)
    supports: tuple = ()
    loads: tuple = ()
    held: tuple = ()
    #: bond factors at the start (None: intact; a run started from another)
    initial: np.ndarray | None = field(default=None, repr=False)
    #: the bonds' damage state at the end (for ``dv.fracture(start=...)``)
    bond_state: dict | None = field(default=None, repr=False, compare=False)

    def _event(self, k: int) -> int:
        n = len(self.events)
        if not isinstance(k, (int, np.integer)) or isinstance(k, bool) or not -n <= k < n:
            raise IndexError(f"event {k!r} out of range: the run has {n} events")
        return int(k) % n

    def stiffness_at(self, k: int) -> np.ndarray:
        """Bond stiffness factors (n_bonds,; 1 intact, 0 broken) at event ``k``, before
        its bond changes (the state whose critical load the event records)."""
        k = self._event(k)
        d = np.ones(self.model.mesh.n_bonds) if self.initial is None else self.initial.copy()
        bonds = np.array([e.bond for e in self.events[:k]], dtype=np.int64)
        lost = np.array([e.spring_lost for e in self.events[:k]], dtype=float)
        np.subtract.at(d, bonds, lost)
        return np.clip(d, 0.0, 1.0)

    def solution(self, k: int = -1):
        """The state at event ``k`` (default the last) as a solve: the damaged lattice
        (``model.damaged(stiffness_at(k))``) in equilibrium under the supports and
        loads times the event's load factor (``dv.solve``; ``u`` is the state the event
        loop recorded, to the solver's tolerance), the held loads at full value."""
        from ..problem import scaled
        from ..solvers import solve

        k = self._event(k)
        lam = self.events[k].load_factor
        closed = np.zeros(self.model.mesh.n_bonds, dtype=bool)
        closed[list(self.events[k].closed)] = True  # cracks in contact: their spring back
        model = self.model.damaged(self.stiffness_at(k), closed)
        loads = scaled(list(self.loads), lam) + list(self.held)
        return solve(model, scaled(list(self.supports), lam), loads)

    def curve(self) -> tuple[np.ndarray, np.ndarray]:
        """The load-displacement curve: ``(control_displacement, load)`` of every event."""
        d = np.array([e.control_displacement for e in self.events])
        p = np.array([e.load for e in self.events])
        return d, p

    @property
    def peak(self) -> Event | None:
        """The event with the largest load (None without events)."""
        return max(self.events, key=lambda e: e.load) if self.events else None

    @property
    def dissipated(self) -> float:
        """Energy released by all events (force x length; per the model's thickness)."""
        return float(sum(e.released for e in self.events if np.isfinite(e.released)))

    def node_damage(self, stiffness: np.ndarray | None = None) -> np.ndarray:
        """Damage per node (N,): the mean loss of stiffness ``1 - d`` of its bonds."""
        d = self.stiffness if stiffness is None else stiffness
        mesh = self.model.mesh
        b = mesh.topology.bonds
        n = mesh.n_points
        loss = np.bincount(b.ravel(), np.repeat(1.0 - d, 2), n)
        return loss / np.maximum(np.bincount(b.ravel(), minlength=n), 1)

    def quantity(self, name: str) -> float | None:
        """A key number: ``peak_load``, ``peak_displacement``, ``released_energy`` or
        ``first_load`` (None without events)."""
        if not self.events:
            return None
        values = {
            "peak_load": lambda: self.peak.load,
            "peak_displacement": lambda: self.peak.control_displacement,
            "released_energy": lambda: self.dissipated,
            "first_load": lambda: self.events[0].load,
        }
        if name not in values:
            raise ValueError(f"unknown quantity {name!r}; expected one of {sorted(values)}")
        return float(values[name]())

    def to_dict(self) -> dict:
        """JSON-ready summary: the events, the curve, why it stopped, timings."""
        peak = self.peak
        return {
            "control": self.control,
            "stop_reason": self.stop_reason,
            "message": self.message,
            "n_events": len(self.events),
            "n_broken": int(len(self.broken)),
            "modes": {m: sum(e.mode == m for e in self.events) for m in MODES},
            "peak": None if peak is None else asdict(peak),
            "dissipated": self.dissipated,
            "events": [_event_dict(e) for e in self.events],
            "seconds": asdict(self.seconds),
            "stats": asdict(self.stats),
        }


def _event_dict(e: Event) -> dict:
    """An event for JSON: the closed faces as their number."""
    d = asdict(e)
    d["closed"] = len(e.closed)
    return d
