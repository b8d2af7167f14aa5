"""The options of :func:`dvstatic.solve`, listed once.

:class:`SolveOptions` is the single source: ``dv.solve``'s keywords and docstring, the
scene schema's ``[solver]`` table, the command line's ``--set solver.<key>=`` and the
option table in ``docs/api.md`` are all derived from its fields.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._checks import check_choice, check_int, check_positive
from ..errors import InputError
from ..linalg import AUTO_DIRECT_MAX_DOF

__all__ = [
    "SOLVERS",
    "SolveOptions",
    "ALIASES",
    "option",
    "options_markdown",
    "options_docstring",
]

#: linear solvers / engines of ``solver=``
SOLVERS = ("auto", "direct", "amg", "dynamic-relaxation", "petsc")
#: deprecated option names and what they are now called
ALIASES = {"max_iter": "newton_maxiter"}


def option(default, doc: str, kind: str, choices=(), scene: bool = True, scene_key=None):
    """A field of an options dataclass with what the scene schema, the docstring and
    the docs table are made from: ``doc`` (markdown), ``kind`` (a scene kind: string,
    number, int, bool), ``choices``, whether the scene has it, and its scene key."""
    meta = {"doc": doc, "kind": kind, "choices": tuple(choices), "scene": scene}
    meta["scene_key"] = scene_key
    return field(default=default, metadata=meta)


_option = option


@dataclass(frozen=True)
class SolveOptions:
    """How to solve (validated on construction; see each field's doc)."""

    solver: str = _option(
        "auto",
        "linear solver or engine: `direct` (sparse LU, nested dissection), `amg` (CG with "
        "smoothed-aggregation AMG and the rigid-body modes), `auto` (direct up to 200,000 "
        "dofs, AMG above), `dynamic-relaxation` (the paper's explicit scheme, a baseline), "
        "`petsc` (distributed over the MPI ranks of `mpiexec -n P`; needs the "
        "`dvstatic[petsc]` extra; `u` and `reactions` on rank 0 only)",
        "string",
        SOLVERS,
        scene_key="type",
    )
    nonlinear: bool = _option(
        False,
        "large displacements and rotations: Newton's method with load stepping on the "
        "exact (current-geometry) internal forces",
        "bool",
    )
    rtol: float = _option(
        1e-10,
        "tolerance of iterative solves (AMG, PETSc, dynamic relaxation) on the residual "
        "relative to the right-hand side, in (0, 1)",
        "number",
    )
    maxiter: int | None = _option(
        None,
        "iteration limit of iterative solves (default 1000; dynamic relaxation: steps, "
        "default 1,000,000)",
        "int",
    )
    steps: int = _option(
        10,
        "nonlinear: initial number of load steps (loads and prescribed displacements are "
        "scaled together); a failed step is halved and retried, a fast one lets the next "
        "grow back",
        "int",
    )
    newton_rtol: float = _option(
        1e-8,
        "nonlinear: residual tolerance relative to the applied load (or, with only "
        "prescribed displacements, the reactions), with an absolute floor of "
        "1e-10 k_n l_mean sqrt(n_dof); the increment must also be small",
        "number",
    )
    newton_maxiter: int = _option(
        25, "nonlinear: Newton iterations per load step before it is cut back", "int"
    )
    max_cutbacks: int = _option(
        8, "nonlinear: how many times a step may be halved in total before giving up", "int"
    )
    line_search: bool = _option(
        True,
        "nonlinear: backtracking line search with Deuflhard's natural monotonicity test",
        "bool",
    )
    allow_unstable: bool = _option(
        False,
        "nonlinear: accept converged states whose tangent has negative pivots (otherwise "
        "they raise: buckling or a limit point)",
        "bool",
    )
    check_stability: bool = _option(
        True,
        "linear: refuse a stiffness that is not positive definite (an unstable lattice); "
        "free with the direct solver (the factorisation's inertia), one extra "
        "factorisation with AMG up to 200,000 dofs, CG's curvature test above",
        "bool",
    )
    best_effort: bool = _option(
        False,
        "when an iteration does not converge (iteration limit, a Newton step failing "
        "after every cut-back), return the last state marked `info.converged = False` "
        "with `info.failure` and `info.load_factor` instead of raising; refusals "
        "(unstable lattice, singular system) still raise; `dvstatic run` then exits with "
        "code 4",
        "bool",
    )
    progress: bool = _option(False, "show progress bars on stderr (tqdm)", "bool", scene=False)

    def __post_init__(self) -> None:
        check_choice("solver", self.solver, SOLVERS)
        for f in dataclasses.fields(self):
            if f.metadata["kind"] == "bool":
                _check_bool(f.name, getattr(self, f.name))
                object.__setattr__(self, f.name, bool(getattr(self, f.name)))
        _unit_interval("rtol", self.rtol)
        _unit_interval("newton_rtol", self.newton_rtol)
        if self.maxiter is not None:
            check_int("maxiter", self.maxiter, minimum=1)
        check_int("steps", self.steps, minimum=1)
        check_int("newton_maxiter", self.newton_maxiter, minimum=1)
        check_int("max_cutbacks", self.max_cutbacks, minimum=0)
        if self.solver == "petsc" and self.best_effort:
            raise InputError("best_effort is not available with solver='petsc'", "best_effort")

    @classmethod
    def from_kwargs(cls, base: SolveOptions | None = None, **kwargs) -> SolveOptions:
        """Options from keywords (deprecated names accepted with a warning), on top of
        ``base``.

        Raises
        ------
        TypeError
            An unknown keyword (the message lists the accepted ones).
        """
        names = {f.name for f in dataclasses.fields(cls)}
        for old, new in ALIASES.items():
            if old in kwargs:
                warnings.warn(
                    f"option {old!r} is deprecated; use {new!r}", DeprecationWarning, stacklevel=3
                )
                if new in kwargs:
                    raise TypeError(f"give {new!r} only (not also its old name {old!r})")
                kwargs[new] = kwargs.pop(old)
        unknown = sorted(set(kwargs) - names)
        if unknown:
            raise TypeError(
                f"unknown solve option(s) {', '.join(map(repr, unknown))}; accepted: "
                + ", ".join(sorted(names))
            )
        return dataclasses.replace(base or cls(), **kwargs)

    def resolved_solver(self, n_dof: int) -> str:
        """The solver that runs for ``n_dof`` unknowns (``auto``: direct up to
        :data:`~dvstatic.linalg.AUTO_DIRECT_MAX_DOF`, AMG above)."""
        if self.solver != "auto":
            return self.solver
        return "direct" if n_dof <= AUTO_DIRECT_MAX_DOF else "amg"

    def linear_maxiter(self) -> int:
        """The iteration limit of the chosen iterative solver."""
        if self.maxiter is not None:
            return self.maxiter
        return 1_000_000 if self.solver == "dynamic-relaxation" else 1000


def _check_bool(name: str, value) -> None:
    """True/False (numpy booleans and the integers 0 and 1 too, as dvstatic 0.1 took)."""
    if isinstance(value, (bool, np.bool_)) or (isinstance(value, int) and value in (0, 1)):
        return
    raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")


def _unit_interval(name: str, value) -> float:
    v = check_positive(name, value)
    if v >= 1:
        raise InputError(f"{name} must be in (0, 1), got {v}", name)
    return v


def options_markdown(cls=None, aliases=None) -> str:
    """Markdown table of every option of ``cls`` (default :class:`SolveOptions`; name,
    default, meaning): docs/api.md holds it."""
    cls = SolveOptions if cls is None else cls
    aliases = ALIASES if cls is SolveOptions and aliases is None else (aliases or {})
    lines = ["| option | default | meaning |", "|---|---|---|"]
    for f in dataclasses.fields(cls):
        lines.append(f"| `{f.name}` | `{f.default!r}` | {f.metadata['doc']} |")
    for old, new in aliases.items():
        lines.append(f"| `{old}` | | deprecated name of `{new}` |")
    return "\n".join(lines)


def options_docstring(indent: str = "    ", cls=None) -> str:
    """numpydoc ``Parameters`` entries of every option of ``cls`` (default
    :class:`SolveOptions`; for ``dv.solve.__doc__``)."""
    import textwrap

    out = []
    for f in dataclasses.fields(SolveOptions if cls is None else cls):
        kind = {"string": "str", "number": "float", "int": "int", "bool": "bool"}[
            f.metadata["kind"]
        ]
        out.append(f"{indent}{f.name} : {kind}, default {f.default!r}")
        text = f.metadata["doc"].replace("`", "``")
        out.extend(textwrap.wrap(text, 88, initial_indent=indent * 2, subsequent_indent=indent * 2))
    return "\n".join(out)
