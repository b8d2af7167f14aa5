"""Old module paths of dvstatic 0.1, kept importable for one release.

``import dvstatic.loads`` (or ``from dvstatic.models import DV``) still works and
warns with a ``DeprecationWarning`` naming the new place. The alias is a thin module
whose attributes are read from the new module; nothing is copied.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings

__all__ = ["MOVED", "RENAMED", "install"]

#: old module -> new module
MOVED = {
    "dvstatic.meshgen": "dvstatic.mesh.generators",
    "dvstatic.periodic": "dvstatic.mesh.periodic",
    "dvstatic.ordering": "dvstatic.mesh.ordering",
    "dvstatic.kinematics": "dvstatic.lattice.kinematics",
    "dvstatic.geometry": "dvstatic.lattice.geometry",
    "dvstatic.assembly": "dvstatic.lattice.assembly",
    "dvstatic.calibration": "dvstatic.lattice.calibration",
    "dvstatic.models": "dvstatic.lattice.models",
    "dvstatic.loads": "dvstatic.problem",
    "dvstatic.newton": "dvstatic.solvers.newton",
    "dvstatic.relaxation": "dvstatic.solvers.relaxation",
    "dvstatic.stability": "dvstatic.solvers.stability",
    "dvstatic.distributed": "dvstatic.parallel.partition",
    "dvstatic.petsc_solve": "dvstatic.parallel.petsc",
    "dvstatic.lattice.stress": "dvstatic.stress.virial",
}
#: names that moved to another name or module: (old module, name) -> "module:name"
RENAMED = {
    ("dvstatic.petsc_solve", "solve_petsc"): "dvstatic.parallel.petsc:solve",
    ("dvstatic.meshgen", "spatial_order"): "dvstatic.mesh.ordering:spatial_order",
}
#: old modules whose name is also a public function of ``dvstatic`` (calling the
#: module calls it, so that ``dv.stability(...)`` survives ``import dvstatic.stability``)
_CALLABLE = {"dvstatic.stability": "stability"}


class _Alias(types.ModuleType):
    """A module that reads every attribute from its new module."""

    def __init__(self, name: str, target: str):
        super().__init__(name, f"deprecated alias of {target}")
        self.__dict__["_target"] = target

    def _module(self):
        return importlib.import_module(self.__dict__["_target"])

    def __getattr__(self, attr: str):
        moved = RENAMED.get((self.__name__, attr))
        if moved is not None:
            module, name = moved.split(":")
            return getattr(importlib.import_module(module), name)
        return getattr(self._module(), attr)

    def __dir__(self):
        return dir(self._module())

    def __call__(self, *args, **kwargs):
        fn = _CALLABLE.get(self.__name__)
        if fn is None:
            raise TypeError(f"module {self.__name__!r} is not callable")
        return getattr(self._module(), fn)(*args, **kwargs)


class _Loader(importlib.abc.Loader):
    def create_module(self, spec):
        return _Alias(spec.name, MOVED[spec.name])

    def exec_module(self, module) -> None:
        warnings.warn(
            f"{module.__name__} is deprecated; import {MOVED[module.__name__]} instead",
            DeprecationWarning,
            stacklevel=2,
        )


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.machinery.ModuleSpec(fullname, _Loader())
        return None


def install() -> None:
    """Make the old module paths importable (idempotent)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
