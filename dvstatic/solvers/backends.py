"""Engines that live above the solvers layer and load only when asked for.

``solver="petsc"`` runs :mod:`dvstatic.parallel.petsc`; its module is named here and
imported on use, so that neither petsc4py nor the parallel layer is imported by
``dv.solve`` otherwise (and the solvers layer does not depend on the parallel one).
"""

from __future__ import annotations

import importlib

from ..errors import MissingDependencyError

__all__ = ["ENGINES", "engine", "installed"]

#: engine name -> (module, what it needs, pip extra, how to install)
ENGINES = {
    "petsc": (
        "dvstatic.parallel.petsc",
        "petsc4py",
        "petsc",
        "run scripts/install_petsc.sh from a source checkout (PETSc is compiled from "
        "source, about 15 minutes; see docs/parallel.md)",
    ),
}


def installed(name: str) -> bool:
    """True if the optional dependency of engine ``name`` can be imported."""
    try:
        importlib.import_module(ENGINES[name][1])
    except ImportError:
        return False
    return True


def engine(name: str):
    """The module of engine ``name`` (it provides ``solve(model, supports, loads, opts)``).

    Raises
    ------
    MissingDependencyError
        The engine's optional dependency is not installed (names the extra).
    """
    module, needs, extra, how = ENGINES[name]
    if not installed(name):
        raise MissingDependencyError(
            f"solver={name!r} needs {needs} (the dvstatic[{extra}] extra), which is not "
            f"installed: {how}",
            extra,
        )
    return importlib.import_module(module)
