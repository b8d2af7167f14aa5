"""What a solve reports: :class:`SolveInfo` and the typed records in it.

Every path (direct, AMG, dynamic relaxation, Newton, PETSc) fills the same fields;
fields that do not apply keep their defaults (e.g. ``steps == ()`` for linear solves).
For one release, ``info["key"]`` still works (with a ``DeprecationWarning``); use
``info.key``.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field, fields

__all__ = [
    "SolveInfo",
    "NewtonStep",
    "StabilityCheck",
    "Timings",
    "LinearSolve",
    "ParallelInfo",
    "Record",
]


class _Record:
    """Read-only record with the old dict-style access kept for one release."""

    #: old dict keys that are attributes under another name now
    _OLD_KEYS: dict[str, str] = {}

    def __getitem__(self, key: str):
        new = self._OLD_KEYS.get(key, key)
        warnings.warn(
            f"{type(self).__name__}[{key!r}] is deprecated; use the attribute .{new}",
            DeprecationWarning,
            stacklevel=2,
        )
        if new not in self._names():
            raise KeyError(key)
        return _dictish(getattr(self, new))

    def get(self, key: str, default=None):
        """Attribute ``key`` if this record has it, else ``default`` (dict-style)."""
        return getattr(self, key) if key in self._names() else default

    def __contains__(self, key: str) -> bool:
        return key in self._names()

    def keys(self) -> tuple[str, ...]:
        return self._names()

    @classmethod
    def _names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def as_dict(self) -> dict:
        """Plain nested dict (JSON-ready apart from numpy scalars)."""
        return asdict(self)


#: the base of typed records that still answer ``record["key"]`` (deprecated)
Record = _Record


def _dictish(value):
    """Nested records as the plain dicts the old ``info`` held."""
    if isinstance(value, _Record):
        return value.as_dict()
    if isinstance(value, tuple) and value and isinstance(value[0], _Record):
        return [v.as_dict() for v in value]
    return value


@dataclass(frozen=True)
class Timings(_Record):
    """Wall-clock seconds per stage of a solve (0 where a stage did not run).

    ``calibration`` is what the model's calibration took when the model was made (0 if
    it came from a cache); serial solves do not count it in ``total``, the distributed
    engine (which calibrates during the solve) does.
    """

    geometry: float = 0.0
    calibration: float = 0.0
    assembly: float = 0.0
    setup: float = 0.0
    solve: float = 0.0
    partition: float = 0.0
    patch: float = 0.0
    gather: float = 0.0
    total: float = 0.0


@dataclass(frozen=True)
class StabilityCheck(_Record):
    """Positive-definiteness check of the stiffness.

    Attributes
    ----------
    checked : bool
        True if the count below is known.
    method : str
        ``"ldl-inertia"`` (negative pivots of a symmetric factorisation),
        ``"cg-curvature"`` (CG's negative-curvature test only) or ``"none"``.
    negative_eigenvalues : int or None
    seconds : float
    note : str
    """

    checked: bool = False
    method: str = "none"
    negative_eigenvalues: int | None = None
    seconds: float = 0.0
    note: str = ""


@dataclass(frozen=True)
class NewtonStep(_Record):
    """One accepted (or the failed) load step of Newton's method.

    Attributes
    ----------
    load_factor : float
        The load factor the step reached (or aimed at, for a failed step).
    iterations : int
    residuals : tuple of float
        Free-dof residual norm before the first and after every iteration (force).
    line_search : tuple of float
        Step length factor of every iteration.
    linear_iterations : tuple of int
        Iterations of every tangent solve (0 for direct solves).
    tolerance : float
        Residual tolerance of the step (force).
    increment : float
        Last relative increment ``|alpha du| / |u|``.
    reason : str
        Why the step failed ("" for accepted steps).
    """

    load_factor: float
    iterations: int
    residuals: tuple[float, ...]
    line_search: tuple[float, ...] = ()
    linear_iterations: tuple[int, ...] = ()
    tolerance: float = float("nan")
    increment: float = float("nan")
    reason: str = ""


@dataclass(frozen=True)
class LinearSolve(_Record):
    """One iterative linear solve of an engine (PETSc KSP)."""

    iterations: int
    residual: float
    converged: bool
    residuals: tuple[float, ...] = ()
    setup_seconds: float = 0.0
    solve_seconds: float = 0.0
    reason: int = 0


@dataclass(frozen=True)
class ParallelInfo(_Record):
    """Distributed run: ranks, this rank, what it holds (MB), peak memory per rank."""

    ranks: int
    rank: int
    memory: dict = field(default_factory=dict)
    peak_MB_per_rank: tuple[float, ...] = ()


@dataclass(frozen=True)
class SolveInfo(_Record):
    """Report of a solve; the same fields on every path.

    Attributes
    ----------
    solver : str
        What ran: ``"direct"``, ``"amg"``, ``"dynamic-relaxation"``, ``"petsc"``.
    nonlinear : bool
    converged : bool
    n_dof, n_constrained : int
    iterations : int
        Linear iterations (refinement steps for a direct solve), relaxation steps, or
        Newton iterations over all load steps.
    residuals : tuple of float
        Residual history (relative for linear solves; force norms for Newton).
    residual : float
        Final equilibrium residual relative to the load.
    seconds : Timings
    reused : tuple of str
        Stages taken from a cache (geometry, assembly, factorisation, amg hierarchy).
    stability : StabilityCheck
    backward_error : float or None
        Normwise backward error of a direct solve.
    coupling_assembled : bool
        False when the model has no Voronoi coupling (nu_m = 0).
    steps : tuple of NewtonStep
        Nonlinear: the accepted load steps.
    cutbacks, tangent_builds : int
        Nonlinear: halved steps; factorisations or AMG hierarchies built.
    load_factor : float
        The load factor of the returned state (1 when complete).
    failure : str or None
        Why an unconverged state was returned (``best_effort``).
    equilibrium : bool
        False when the returned state is the last iterate of a step that did not
        converge (``best_effort`` when no load step converged).
    failed_step : NewtonStep or None
    linear_solves : tuple of LinearSolve
        The engine's iterative solves (PETSc).
    parallel : ParallelInfo or None
    damping : str or None
        Dynamic relaxation: the damping scheme.
    """

    solver: str
    nonlinear: bool = False
    converged: bool = False
    n_dof: int = 0
    n_constrained: int = 0
    iterations: int = 0
    residuals: tuple[float, ...] = ()
    residual: float = float("nan")
    seconds: Timings = field(default_factory=Timings)
    reused: tuple[str, ...] = ()
    stability: StabilityCheck = field(default_factory=StabilityCheck)
    backward_error: float | None = None
    coupling_assembled: bool = True
    steps: tuple[NewtonStep, ...] = ()
    cutbacks: int = 0
    tangent_builds: int = 0
    load_factor: float = 1.0
    failure: str | None = None
    equilibrium: bool = True
    failed_step: NewtonStep | None = None
    linear_solves: tuple[LinearSolve, ...] = ()
    parallel: ParallelInfo | None = None
    damping: str | None = None

    _OLD_KEYS = {"ksp": "linear_solves"}

    def __getitem__(self, key: str):
        if key == "newton_seconds":
            warnings.warn(
                "SolveInfo['newton_seconds'] is deprecated; use .seconds.solve",
                DeprecationWarning,
                stacklevel=2,
            )
            return self.seconds.solve
        return super().__getitem__(key)
