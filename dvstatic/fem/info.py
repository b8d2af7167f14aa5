"""What an FE reference reports: :class:`FEInfo` and :class:`FETimings` (typed; the old
``info["key"]`` still answers, with a DeprecationWarning)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solvers.info import Record

__all__ = ["FEInfo", "FETimings"]


@dataclass(frozen=True)
class FETimings(Record):
    """Wall-clock seconds of an FE reference's stages."""

    mesh: float = 0.0  #: refinement, the FE mesh and its basis
    assembly: float = 0.0  #: stiffness, loads, supports
    solve: float = 0.0  #: the solve (direct with iterative refinement, or AMG-CG)
    total: float = 0.0


@dataclass(frozen=True)
class FEInfo(Record):
    """What an FE reference reports (``info["key"]`` still works, deprecated)."""

    n_dof: int
    n_elements: int
    lame: tuple  #: in-plane (lambda, mu) of the first element
    plane: str
    thickness: float
    load_resultant: np.ndarray  #: total applied force (fx, fy)
    seconds: FETimings
    solver: str = "direct"  #: "direct" (SuperLU) or "amg-cg" (above ``FE_AMG_ENTRIES`` entries)
    iterations: int = 0  #: CG iterations, or the direct solve's refinement steps
