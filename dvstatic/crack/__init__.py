"""Quasi-static fracture of DV/RV lattices by bond breaking, event by event.

``dv.fracture(model, supports, loads, held=None, ft=..., gf=None, max_events=...)`` (options:
:class:`.FractureOptions`, :mod:`.options`) runs a
sequentially linear analysis (:mod:`.sla`) with bond strengths derived from the
material's tensile strength (:mod:`.strength`), optional saw-tooth softening with a
fracture energy, and factorisation updates between events (:mod:`.updates`). What
breaking a bond does to the DV/RV force law is in :mod:`dvstatic.lattice.damage`.
"""

from .criteria.mohr_coulomb import ucs
from .energies import GF_SHEAR_RATIO
from .options import FractureOptions
from .result import Event, FractureResult, FractureStats, FractureTimings, Snapshot
from .sla import EQUILIBRIUM_TOL, fracture
from .strength import Weibull

__all__ = [
    "fracture",
    "FractureOptions",
    "Weibull",
    "Event",
    "FractureResult",
    "FractureTimings",
    "FractureStats",
    "Snapshot",
    "EQUILIBRIUM_TOL",
    "GF_SHEAR_RATIO",
    "ucs",
]
