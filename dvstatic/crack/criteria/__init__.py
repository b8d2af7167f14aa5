"""Breaking criteria of :func:`dvstatic.fracture`, behind one protocol
(:class:`~.base.Criterion`) and a registry: ``stress`` (the default, Rankine on the
bond's face) and ``tension`` (the bond's tension)."""

from . import stress, tension  # noqa: F401  (they register themselves)
from .base import REGISTRY, Criterion, criterion_for, register
from .responses import per_bond, positive

#: the criteria's names, the default first
CRITERIA = tuple(sorted(REGISTRY, key=lambda name: name != "stress"))

__all__ = ["CRITERIA", "Criterion", "REGISTRY", "criterion_for", "register", "per_bond", "positive"]
