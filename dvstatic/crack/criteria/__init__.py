"""Breaking criteria of :func:`dvstatic.fracture`, behind one protocol
(:class:`~.base.Criterion`) and a registry: ``stress`` (the default, Rankine on the
bond's face), ``mohr-coulomb`` (Coulomb's line with a tension cut-off on the face and
the out-of-plane planes through it) and ``bond-tension`` (the bond's force, refused where
it is known to be wrong)."""

from . import mohr_coulomb, stress, tension  # noqa: F401  (they register themselves)
from .base import MODES, REGISTRY, Criterion, Critical, criterion_for, register
from .responses import per_bond, positive

#: the criteria's names, the default first
CRITERIA = tuple(sorted(REGISTRY, key=lambda name: name != "stress"))

__all__ = [
    "CRITERIA",
    "MODES",
    "Critical",
    "Criterion",
    "REGISTRY",
    "criterion_for",
    "register",
    "per_bond",
    "positive",
]
