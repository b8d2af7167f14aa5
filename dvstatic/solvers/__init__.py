"""Solvers (layer 4): options, results, the linear solve, Newton's method (one, for
every engine), dynamic relaxation, the stability analysis and the engine registry.

``dv.solve(model, supports, loads, **options)`` is :func:`.solve.solve`; its options
are the fields of :class:`SolveOptions`.
"""

from ..errors import ConvergenceError, SingularError, SolverError, UnstableError
from .options import ALIASES, SOLVERS, SolveOptions
from .result import (
    LinearSolve,
    NewtonStep,
    ParallelInfo,
    Solution,
    SolveInfo,
    StabilityCheck,
    Timings,
)
from .solve import solve
from .stability import StabilityReport, stability

__all__ = [
    "solve",
    "Solution",
    "SolveInfo",
    "SolveOptions",
    "SOLVERS",
    "ALIASES",
    "NewtonStep",
    "StabilityCheck",
    "Timings",
    "LinearSolve",
    "ParallelInfo",
    "StabilityReport",
    "stability",
    "SolverError",
    "SingularError",
    "UnstableError",
    "ConvergenceError",
]
