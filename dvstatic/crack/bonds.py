"""The state the event loop carries: every bond's damage (stiffness factor, saw-tooth
step, threshold) and the states kept for the VTU series."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .result import Snapshot
from .strength import MIN_EXCESS, teeth_at

__all__ = ["Bonds", "Kept"]


class Bonds:
    """The damage state of the bonds: stiffness factors, teeth and thresholds.

    ``energy`` and ``energy_shear`` (n_bonds,; None: brittle) are what the teeth of a
    bond cracked in tension, and of one that failed in shear or crushing, release. A
    cracked bond softens along its criterion's softening measure (its elongation in
    tension; the face's Coulomb measure in shear or crushing) times :attr:`sense` (+1 in
    tension; the sign of the face's shear as it failed) and keeps the mode of its first
    failure (:attr:`mode`, an index into the criteria's modes).
    """

    def __init__(self, strength, spring, energy, teeth: int, energy_shear=None):
        n = len(strength)
        self.d = np.ones(n)
        self.tooth = np.zeros(n, dtype=np.int64)
        self.threshold = np.asarray(strength, float).copy()
        self.spring, self.energy, self.teeth = spring, energy, teeth
        self.energy_shear = energy_shear
        self.sense = np.ones(n)
        self.mode = np.zeros(n, dtype=np.int64)
        self.steps: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def state(self, cracked) -> dict:
        """Everything :meth:`load` needs to go on from here (copies)."""
        steps = {e: (a.copy(), b.copy()) for e, (a, b) in self.steps.items()}
        return dict(
            d=self.d.copy(),
            tooth=self.tooth.copy(),
            threshold=self.threshold.copy(),
            sense=self.sense.copy(),
            mode=self.mode.copy(),
            steps=steps,
            cracked=cracked.copy(),
            teeth=self.teeth,
        )

    def load(self, state: dict) -> None:
        """Take the damage of an earlier run; intact bonds keep this run's thresholds.

        Raises
        ------
        InputError
            If the earlier run softened bonds in another number of teeth.
        """
        if state["steps"] and state["teeth"] != self.teeth:
            raise InputError(
                f"start: the earlier run softened bonds in teeth = {state['teeth']} steps; "
                f"go on with the same teeth (got {self.teeth})",
                "teeth",
            )
        self.d[:] = state["d"]
        self.tooth[:] = state["tooth"]
        hit = self.d < 1.0
        self.threshold[hit] = state["threshold"][hit]
        self.sense[:] = state["sense"]
        self.mode[:] = state["mode"]
        self.steps = {e: (a.copy(), b.copy()) for e, (a, b) in state["steps"].items()}

    def save(self, e: int):
        """All stiffness factors and bond ``e``'s tooth state, for :meth:`restore`."""
        keep = (float(self.sense[e]), int(self.mode[e]))
        return self.d.copy(), int(self.tooth[e]), float(self.threshold[e]), e in self.steps, keep

    def restore(self, e: int, saved) -> None:
        d, tooth, threshold, had_steps, (sense, mode) = saved
        self.d[:] = d
        self.tooth[e], self.threshold[e] = tooth, threshold
        self.sense[e], self.mode[e] = sense, mode
        if not had_steps:
            self.steps.pop(e, None)

    def advance(self, e: int, peak: float, mode: int = 0, sense: float = 1.0, spring=None) -> bool:
        """Soften or remove bond ``e`` cracking at ``peak`` of its softening measure in
        ``mode`` (0: tension, with :attr:`energy`, the measure its elongation; else
        shear or crushing, with :attr:`energy_shear`); ``sense`` (+1 or -1) the measure's
        sign kept from here on, ``spring`` its stiffness (energy = ``spring measure^2 /
        2``; default the bond's spring). True if removed (no energy for its mode, or none
        beyond the elastic energy at the crack)."""
        if self.d[e] >= 1.0:
            energy = self.energy if mode == 0 else self.energy_shear
            en = None if energy is None else energy[e]
            k = self.spring[e] if spring is None else spring
            self.mode[e], self.sense[e] = mode, sense
            if en is None or peak <= 0 or k <= 0 or en <= 0.5 * k * peak**2 * (1 + MIN_EXCESS):
                self.d[e] = 0.0
                return True
            d, delta = teeth_at(k, peak, en, self.teeth)
            self.steps[e] = (d[0], delta[0])
        self.tooth[e] += 1
        if self.tooth[e] >= self.teeth:
            self.d[e] = 0.0
            return True
        d, delta = self.steps[e]
        self.d[e] = d[self.tooth[e]]
        self.threshold[e] = delta[self.tooth[e]]
        return False


class Kept:
    """The states kept for the VTU series: every ``every`` events if it is given, else
    about ``target`` spread over the events actually run (the spacing doubles whenever
    the kept states outgrow 4/3 of the target); always the peak and the last."""

    def __init__(self, target: int, every: int | None):
        self.fixed = every is not None
        self.every = every or 1
        self.cap = max(2, math.ceil(4 * target / 3))
        self.kept: list[Snapshot] = []
        self.peak = self.last = None

    def add(self, snap: Snapshot, peak: bool) -> None:
        self.last = snap
        if peak:
            self.peak = snap
        if snap.event % self.every:
            return
        self.kept.append(snap)
        if not self.fixed and len(self.kept) > self.cap:
            self.every *= 2
            self.kept = [s for s in self.kept if s.event % self.every == 0]

    def states(self) -> tuple:
        """The kept states, the peak and the last, in event order."""
        extra = [s for s in (self.peak, self.last) if s is not None]
        by_event = {s.event: s for s in [*self.kept, *extra]}
        return tuple(by_event[k] for k in sorted(by_event))
