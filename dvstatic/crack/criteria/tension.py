"""``criterion="tension"``: a bond breaks when its tension reaches its strength."""

from __future__ import annotations

from .base import Criterion, register

__all__ = ["Tension"]


@register
class Tension(Criterion):
    """The bond's tension ``T_e`` against its tension-based strength (which compression
    along the face raises: under tension ``s`` and compression ``3 s`` it cracks at
    about ``ft / 2.6``)."""

    name = "tension"

    def thresholds(self, s_tension, ftb, factors):
        return s_tension

    def __call__(self, x, w, g, intact=None, bonds=None):
        if bonds is not None:
            return self.sp.local_measures(x, w, g, self.length, self.area, None, bonds)[0]
        return self.sp.tension(x, w, g, self.sp.forces(x, w, g))

    def lipschitz(self):
        """Per bond, how far its tension can move per unit of the largest elongation
        change over its patch while the patch is undamaged: the patch sum of
        ``|Q_T|_inf`` (n_bonds,)."""
        return self.sp.patch_total(self.sp.q_norms(self.sp.w, self.sp.g))
