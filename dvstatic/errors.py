"""The exceptions dvstatic raises, classified by type (never by message text).

::

    ValueError
      InputError                 bad input at the public boundary (``param`` names it)
        CalibrationError         nu has no calibration on this mesh
    RuntimeError
      SolverError                a solve was refused or failed (``info`` says what ran)
        SingularError            the system is singular (a mechanism, missing supports)
        UnstableError            the stiffness is not positive definite (unstable lattice)
        ConvergenceError         an iteration did not converge (``state``: the last state)
    ImportError
      MissingDependencyError     an optional engine is not installed (``extra`` names it)

``scene.SceneError`` (an ``InputError``) adds the scene file and key path.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "InputError",
    "CalibrationError",
    "UnknownRegionError",
    "SolverError",
    "SingularError",
    "UnstableError",
    "ConvergenceError",
    "MissingDependencyError",
]


class InputError(ValueError):
    """Bad input at the public boundary.

    Attributes
    ----------
    param : str or None
        The argument (or option) the problem is about, e.g. ``"nu"``, ``"h"``,
        ``"supports"``; callers such as scene files map it to their own key.
    """

    def __init__(self, message: str, param: str | None = None):
        super().__init__(message)
        self.param = param


class UnknownRegionError(InputError):
    """A region name the mesh does not have (``param`` names the option, ``region`` the
    name)."""

    def __init__(self, message: str, param: str | None = None, region: str | None = None):
        super().__init__(message, param)
        self.region = region


class CalibrationError(InputError):
    """Poisson's ratio (or another constant) has no calibration on this mesh."""


class SolverError(RuntimeError):
    """A solve was refused or failed.

    Attributes
    ----------
    info : object
        What was tried: a :class:`~dvstatic.solvers.SolveInfo` (or a partial record).
    """

    def __init__(self, message: str, info: Any = None):
        super().__init__(message)
        self.info = info


class SingularError(SolverError):
    """The system is singular: a lattice mechanism or a part not held by supports."""


class UnstableError(SolverError):
    """The stiffness (or a Newton tangent) is not positive definite.

    Attributes
    ----------
    negative_eigenvalues : int or None
        How many, where the factorisation's inertia tells (None: a negative-curvature
        direction was met instead).
    """

    def __init__(self, message: str, info: Any = None, negative_eigenvalues: int | None = None):
        super().__init__(message, info)
        self.negative_eigenvalues = negative_eigenvalues


class ConvergenceError(SolverError):
    """An iteration stopped before its tolerance (iteration limit, failed load step).

    Attributes
    ----------
    state : ndarray, shape (2N,), or None
        The last iterate (interleaved dofs): ``best_effort`` returns it.
    load_factor : float
        The load factor ``state`` belongs to (1 for linear solves).
    equilibrium : bool
        True if ``state`` is a converged load step (in equilibrium with
        ``load_factor`` times the load); False if it is the last iterate of a step that
        did not converge (Newton, when no load step converged).
    """

    def __init__(
        self,
        message: str,
        info: Any = None,
        state=None,
        load_factor: float = 1.0,
        equilibrium: bool = False,
    ):
        super().__init__(message, info)
        self.state = state
        self.load_factor = float(load_factor)
        self.equilibrium = bool(equilibrium)


class MissingDependencyError(ImportError):
    """An optional engine is not installed.

    Attributes
    ----------
    extra : str
        The pip extra that provides it (``dvstatic[<extra>]``).
    """

    def __init__(self, message: str, extra: str):
        super().__init__(message)
        self.extra = extra
