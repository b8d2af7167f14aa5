"""``criterion="bond-tension"``: a bond breaks when its tension reaches its strength (the
bond-force criterion of classical lattice models), refused where it breaks a bond the
continuum would not.

A bond's tension is not the continuum's tension across its face: compression along the
face raises it through the Voronoi coupling (under tension ``s`` and compression ``3 s``
a bond cracks at about ``ft / 2.6``), and a surface bond's tension at a bore under
in-situ compression is far from the hoop stress (the first crack came on the wall, not
at the crown, at 41 % of the load). The criterion keeps the bond force under a name that
says what it is, and refuses a run whose first event it would put more than
:data:`EARLY` below the first event of the face stress (``criterion="stress"``, the
default) in the same state: there its answer is known to be wrong. The name
``"tension"`` it had is refused with the alternatives.
"""

from __future__ import annotations

import numpy as np

from ...errors import InputError
from .base import Critical, register
from .ratios import linear_factors
from .stress import Stress

__all__ = ["BondTension", "EARLY", "RENAMED"]

#: a first event this much below the face stress's is refused
EARLY = 0.05

#: old criterion names -> the message that refuses them
RENAMED = {
    "tension": (
        "criterion 'tension' compared a bond's force with ft, which compression along the "
        "face raises (at a bore under in-situ compression it broke the wall at 41 % of the "
        "load): use criterion='stress' (the default, the normal stress across the face), "
        "or 'bond-tension' for the bond-force criterion of classical lattice models "
        "(refused where it would break a bond the face stress does not)"
    ),
}


@register
class BondTension(Stress):
    """The bond's tension ``T_e`` against its tension-based strength; refused (InputError,
    before any event) where its first event comes more than :data:`EARLY` below the
    ``stress`` criterion's in the same state."""

    name = "bond-tension"
    #: whether the first event has been compared with the face stress's (a subclass
    #: with thresholds of its own is not compared)
    _checked = True

    def thresholds(self, s_tension, ftb, factors):
        self._face_thresholds = super().thresholds(s_tension, ftb, factors)
        self._checked = False
        return s_tension

    def __call__(self, x, w, g, intact=None, bonds=None):
        if bonds is not None:
            return self.sp.local_measures(x, w, g, self.length, self.area, None, bonds)[0]
        return self.sp.tension(x, w, g, self.sp.forces(x, w, g))

    def lipschitz(self):
        """Per bond, how far its tension can move per unit of the largest elongation
        change over its own triangles while they are undamaged: their sum of
        ``|Q_T|_inf`` (n_bonds,)."""
        sp_ = self.sp
        q = np.repeat(sp_.q_norms(sp_.w, sp_.g), 3)
        return np.bincount(sp_.tri_bonds.ravel(), q, sp_.n_bonds)

    def critical(self, xh, xg, w, g, intact, d, threshold, sense=1.0, modes=0) -> Critical:
        crit = super().critical(xh, xg, w, g, intact, d, threshold, sense, modes)
        if not self._checked:
            self._checked = True
            if np.all(d >= 1.0):  # the first event of an undamaged run
                self._refuse_if_early(crit, xh, xg, w, g, intact)
        return crit

    def _refuse_if_early(self, crit: Critical, xh, xg, w, g, intact) -> None:
        """Raise if ``crit`` comes more than :data:`EARLY` below the face stress's first
        event in the same state."""
        vg = Stress.__call__(self, xg, w, g, intact)
        vh = 0.0 if xh is None else Stress.__call__(self, xh, w, g, intact)
        ratio, excess = linear_factors(vh, vg, self._face_thresholds)
        if np.any(excess >= 1.0) or not ratio.max() > 0:
            face = 0.0 if np.any(excess >= 1.0) else np.inf
        else:
            face = 1.0 / ratio.max()
        if crit.factor < (1.0 - EARLY) * face:
            where = "no face" if not np.isfinite(face) else f"the first face at {face:.6g}"
            raise InputError(
                f"criterion 'bond-tension' would break bond {crit.bond} first at load "
                f"factor {crit.factor:.6g}, where the normal stress across its face is "
                f"below ft ({where} reaches it): compression along the faces raises the "
                f"bond forces, so the bond force is not the continuum's tension here; use "
                f"criterion='stress'",
                "criterion",
            )
