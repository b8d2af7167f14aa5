"""Micro-parameters ``k_n`` and ``nu_m`` from the macroscopic E and nu.

* ``"relaxed"`` (:mod:`.relaxed`, the default): matches E and nu of the equilibrium
  (non-affinely relaxed) response of a periodic sample with the mesh's micro-structure
  (tabulated for the built-in generators, :mod:`.table`), with the coupling
  stabilised per triangle;
* ``"paper"`` (:mod:`.paper`): the paper's closed form under affine strain
  (eqs. 9-10 for DV, 19-20 for RV with derived RV moments).
"""

from .base import CALIBRATIONS, MicroParameters, Moments
from .classes import MicroField, SpreadClasses, calibrate_classes, spread_classes
from .paper import (
    admissible_nu,
    moment_sums,
    moments,
    moments_from_sums,
    paper,
    paper_from_moments,
)
from .quality import (
    QualityFlag,
    anisotropy_flags,
    calibration_flags,
    defect_flags,
    grading_flags,
)
from .relaxed import (
    REV_POINTS,
    SPREAD_STEP,
    interior_spread,
    relaxed,
    relaxed_moduli,
    rev_for_spread,
    sample_for,
)

__all__ = [
    "CALIBRATIONS",
    "MicroParameters",
    "Moments",
    "admissible_nu",
    "moment_sums",
    "moments",
    "moments_from_sums",
    "paper",
    "paper_from_moments",
    "REV_POINTS",
    "SPREAD_STEP",
    "interior_spread",
    "relaxed",
    "relaxed_moduli",
    "rev_for_spread",
    "sample_for",
    "MicroField",
    "SpreadClasses",
    "calibrate_classes",
    "spread_classes",
    "QualityFlag",
    "anisotropy_flags",
    "calibration_flags",
    "grading_flags",
    "defect_flags",
]
