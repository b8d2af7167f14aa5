"""Finding the next event: the critical bond, with the contact status of the closed
cracks consistent (:mod:`.contact`), under held + factor x growing loads.

A mixin of the event loop's analysis (:mod:`.sla`): it uses its current solves
(``x``, ``xh``), the updated solver, the bonds' damage and the contact status.
"""

from __future__ import annotations

import logging

import numpy as np

from ..lattice.damage import RESIDUAL
from .contact import MAX_ITERATIONS, TOLERANCE, line_search

log = logging.getLogger(__name__)

__all__ = ["EventSearch", "OUTER"]

#: segments of the load factor (held loads and closed cracks: the factors at which a
#: cracked face opens or closes) followed for one event before the last status is kept
OUTER = 500


class EventSearch:
    """The next event's critical bond (see :meth:`_critical`)."""

    def _critical(self):
        """The next event's critical bond with the contact status consistent. Without
        held loads the contact problem is positively homogeneous (zero gaps), so the
        status of the state at load factor 1 is that of every factor: settle it there,
        then find the critical bond. With held loads, follow the load factor up from 0
        (:meth:`_follow`)."""
        if not self.contact.active:
            return self._criterion()
        if self.xh is None:
            self._settle(1.0)
            return self._criterion()
        return self._follow()

    def _follow(self):
        """With held loads and closed cracks, the state is linear in the load factor
        only between the factors where a cracked face opens or closes. Settle the status
        at factor 0, then walk up segment by segment: the first bond that fails within
        a segment (counted from the segment's start) is the event; otherwise turn the
        faces at the segment's end and go on (at most :data:`OUTER` segments, then the
        last status is kept, with a warning)."""
        lam, soft = 0.0, self.criterion.softening
        self._settle(lam)
        for _ in range(OUTER):
            self._leave_consistently(lam)
            start = self._at(lam)
            crit = self._criterion(start)
            crit = crit._replace(factor=lam + crit.factor)
            c = np.flatnonzero(self.contact.cracked)
            dh, dg = soft(start)[c], soft(self.x)[c]
            closed = self.contact.closed[c]
            with np.errstate(divide="ignore", invalid="ignore"):
                ahead = -dh / dg  # beyond the segment's start
            # a closed face opens as its elongation rises through 0, an open one closes
            # as it falls through 0
            turns = np.where(closed, dg > 0, dg < 0) & (ahead > 1e-12 * max(lam, 1.0))
            nxt = lam + float(ahead[turns].min()) if turns.any() else np.inf
            if crit.factor <= nxt:
                return crit
            self._flip(c[turns & (lam + ahead <= nxt * (1 + 1e-12))])
            lam = nxt
            self._settle(lam)
        log.warning(
            "fracture: the closed cracks changed status more than %d times below the load "
            "factor of the next event; keeping the last status",
            OUTER,
        )
        return self._criterion()

    def _leave_consistently(self, lam: float) -> None:
        """Faces at the turn (elongation zero to :data:`.contact.TOLERANCE`) at factor
        ``lam`` keep their status in the state there, but the status must also hold as
        the factor grows: a closed face whose elongation rises opens, an open one whose
        elongation falls closes (they carry no force at ``lam``, so the state there
        stays). Flip them and solve again until none moves the wrong way (a few passes;
        the status of the others changes the rates)."""
        soft, c = self.criterion.softening, np.flatnonzero(self.contact.cracked)
        for _ in range(MAX_ITERATIONS):
            el, rate = soft(self._at(lam)), soft(self.x)
            at_turn = np.abs(el[c]) <= TOLERANCE * (float(np.max(np.abs(el))) or 1.0)
            tol = TOLERANCE * (float(np.max(np.abs(rate))) or 1.0)
            closed = self.contact.closed[c]
            wrong = at_turn & np.where(closed, rate[c] > tol, rate[c] < -tol)
            if not wrong.any():
                return
            self._flip(c[wrong])
        log.warning(
            "fracture: faces at the turn kept flipping (%d passes); keeping the last status",
            MAX_ITERATIONS,
        )

    def _flip(self, faces: np.ndarray) -> None:
        """Turn the contact status of cracked ``faces`` and solve again."""
        status = self.contact.closed.copy()
        status[faces] = ~status[faces]
        self.contact.set(status)
        self.solver.touch(np.unique(self.bond_tris[faces]))
        if self.opts.max_rank == 0:
            self.solver.rebase(*self.factors())
        self._solve()

    def _criterion(self, held=None):
        """The criterion's next event under ``held + lambda x`` (``held`` default: the
        held loads' state)."""
        bonds = self.bonds
        (w, g), intact = self._damage_state()
        held = self.xh if held is None else held
        return self.criterion.critical(
            held, self.x, w, g, intact, bonds.d, bonds.threshold, bonds.sense, bonds.mode
        )

    def _at(self, lam: float) -> np.ndarray:
        """The state (2N,) at load factor ``lam``."""
        return lam * self.x if self.xh is None else self.xh + lam * self.x

    def _loads(self, lam: float) -> np.ndarray:
        """The nodal forces (2N,) at load factor ``lam`` (held ones at full value)."""
        return lam * self.f if self.fh is None else self.fh + lam * self.f

    def _settle(self, lam: float) -> bool:
        """Make the contact status consistent with the state at load factor ``lam``
        (semismooth Newton on the contact energy, :mod:`.contact`): set the status from
        the state and solve; take the new state while the energy falls, else step only as
        far as it falls along the way; True if the status changed. Where the passes come
        back to a status they took, or the damped step stalls on a kink of the energy,
        the few faces in dispute are settled by trying their statuses
        (:meth:`_settle_among`)."""
        contact, soft = self.contact, self.criterion.softening
        z, newton, moved = self._at(lam), True, False
        energy = None  # of z; only needed once the status changes (most events: never)
        seen = [contact.closed.copy()]  # the statuses taken, to catch a cycle
        disputed, tried = None, False
        for _ in range(MAX_ITERATIONS):
            status = contact.status(soft(z))
            if newton and np.array_equal(status, contact.closed):
                return moved
            changed = np.flatnonzero(status != contact.closed)
            faces = None if tried else _disputed(seen, status, changed, disputed, newton)
            if faces is not None:
                tried = True
                if self._settle_among(faces, lam):
                    return True
                moved = True
                z, energy, newton = self._at(lam), None, True
                continue
            if len(changed):
                seen.append(status)
                self._take(status, changed)
                moved = True
            zn = self._at(lam)
            disputed = np.flatnonzero(contact.status(soft(zn)) != contact.closed)
            if not len(disputed):
                return moved
            if energy is None:
                energy = self._energy(z, lam)
            e_new = self._energy(zn, lam)
            if e_new < energy:  # a full Newton step that lowers the energy
                z, energy, newton = zn, e_new, True
                continue
            alpha = self._step(z, zn - z, lam)
            z = z + alpha * (zn - z)
            energy, newton = self._energy(z, lam), alpha >= 1.0
        log.warning(
            "fracture: the contact status of the closed cracks did not settle in %d passes; "
            "keeping the last one",
            MAX_ITERATIONS,
        )
        return moved

    def _take(self, status: np.ndarray, changed: np.ndarray) -> None:
        """Take the contact ``status`` (``changed``: the faces that turned) and solve
        (nothing to do if none turned: the current solve is that status's)."""
        if not len(changed):
            return
        self.contact.set(status)
        self.solver.touch(np.unique(self.bond_tris[changed]))
        if self.opts.max_rank == 0:
            self.solver.rebase(*self.factors())
        self._solve()

    def _settle_among(self, faces: np.ndarray, lam: float) -> bool:
        """The Newton passes came back to a status or stalled on a kink: try every
        status of the few ``faces`` in dispute (those that changed since the status was
        taken, or those the last solve would turn; the others kept) and take a
        consistent one of least energy (the convex problem's solution; True); if none is
        consistent, keep the status of least energy and return False (the damped passes
        go on from there)."""
        soft, base = self.criterion.softening, self.contact.closed.copy()
        best = None
        for bits in range(2 ** len(faces)):
            status = base.copy()
            status[faces] = [(bits >> k) & 1 == 1 for k in range(len(faces))]
            self._take(status, np.flatnonzero(status != self.contact.closed))
            z = self._at(lam)
            ok = np.array_equal(self.contact.status(soft(z)), status)
            key = (not ok, self._energy(z, lam))
            if best is None or key < best[0]:
                best = (key, status)
        self._take(best[1], np.flatnonzero(best[1] != self.contact.closed))
        return not best[0][0]

    def _open(self):
        """The stiffness factors with every cracked face open, and every cracked face's
        missing spring (the contact's penalty)."""
        w, g = self.sp.factors(self.bonds.d)
        c = self.contact.cracked
        return w, g, c, self.spring[c] * (1.0 - np.maximum(self.bonds.d[c], RESIDUAL))

    def _energy(self, z: np.ndarray, lam: float) -> float:
        """The contact energy of state ``z`` at load factor ``lam``: the lattice with the
        cracked faces open, their missing springs where they are shortened, minus the
        loads' work."""
        w, g, c, extra = self._open()
        f = self._loads(lam)
        short = np.minimum(self.criterion.softening(z)[c], 0.0)
        return float(0.5 * z @ self.sp.internal(z, w, g) - f @ z + 0.5 * extra @ short**2)

    def _step(self, z: np.ndarray, d: np.ndarray, lam: float) -> float:
        """The damped Newton step from ``z`` along ``d`` (:func:`.contact.line_search`)."""
        w, g, c, extra = self._open()
        f = self._loads(lam)
        kz, kd = self.sp.internal(z, w, g), self.sp.internal(d, w, g)
        soft = self.criterion.softening
        return line_search(float((kz - f) @ d), float(kd @ d), soft(z)[c], soft(d)[c], extra)


#: a cycle over more faces than this is left to the damped passes
CYCLE_FACES = 6


def _disputed(seen: list, status, changed, disputed, newton: bool) -> np.ndarray | None:
    """The few faces (at most :data:`CYCLE_FACES`) to settle by trial, or None: those
    whose status changed since the passes took ``status`` before (a cycle), or, when a
    damped step (``newton`` False) ends where the status it came from still holds (no
    face ``changed``: it stalls on a kink), the faces ``disputed`` by the last solve."""
    if not len(changed):
        faces = disputed if not newton and disputed is not None else None
    else:
        k = next((k for k in range(len(seen) - 1, -1, -1) if np.array_equal(seen[k], status)), None)
        faces = (
            None if k is None else np.flatnonzero(np.any([w != status for w in seen[k:]], axis=0))
        )
    return faces if faces is not None and 0 < len(faces) <= CYCLE_FACES else None
