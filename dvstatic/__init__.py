"""dvstatic: plane stress-strain analysis with deformable (DV) and remeshing (RV)
Voronoi lattice-spring models, solved implicitly and checked against finite elements.

Public API::

    import dvstatic as dv
    mesh = dv.mesh.rectangle(1.0, 1.0, h=0.05, kind="jittered")
    model = dv.DV(mesh, E=1e5, nu=0.2)
    sol = dv.solve(model, [dv.Fix("left", x=0), dv.Fix("bottom", y=0)],
                   [dv.Traction("right", (-1.0, 0.0))])

Layers (each imports only from the ones before it): foundation (``errors``,
``material``, ``linalg``) -> ``mesh`` -> ``lattice`` -> ``problem`` -> ``solvers``,
``parallel`` -> ``post``, ``fem``, ``io``, ``plot`` -> ``scene``, ``cli``
(docs/architecture.md). The names below load their module on first use, so that
``import dvstatic`` stays light.
"""

import importlib

from . import _compat, mesh
from ._version import __version__
from .errors import (
    CalibrationError,
    ConvergenceError,
    InputError,
    MissingDependencyError,
    SingularError,
    SolverError,
    UnknownRegionError,
    UnstableError,
)
from .mesh import Mesh

_compat.install()

#: public name -> the module that defines it (imported on first use)
_LAZY_NAMES = {
    "DV": "lattice",
    "RV": "lattice",
    "Fix": "problem",
    "Traction": "problem",
    "Pressure": "problem",
    "BodyForce": "problem",
    "PointLoad": "problem",
    "At": "problem",
    "solve": "solvers",
    "Solution": "solvers",
    "SolveInfo": "solvers",
    "SolveOptions": "solvers",
    "stability": "solvers",
    "homogenize": "post",
    "elastic_tensor": "post",
    "plane_stress_tensor": "post",
    "compare": "fem",
    "fracture": "crack",
    "FractureOptions": "crack",
    "Weibull": "crack",
    "clear_caches": "_cache",
    "cache_info": "_cache",
}
#: submodules loaded on first use (``dv.io``, ``dv.plot``, ...): their optional
#: dependencies (scipy, scikit-fem, meshio, matplotlib) stay out of ``import dvstatic``
_LAZY_SUBMODULES = frozenset(
    {
        "cli",
        "domain",
        "errors",
        "fem",
        "io",
        "lattice",
        "linalg",
        "material",
        "parallel",
        "plot",
        "post",
        "problem",
        "scene",
        "solvers",
    }
)


def __getattr__(name: str):
    if name in _LAZY_NAMES:
        value = getattr(importlib.import_module(f".{_LAZY_NAMES[name]}", __name__), name)
        globals()[name] = value  # later look-ups are plain attribute reads
        return value
    if name in _LAZY_SUBMODULES or f"{__name__}.{name}" in _compat.MOVED:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'dvstatic' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY_NAMES) | _LAZY_SUBMODULES)


__all__ = [
    "mesh",
    "lattice",
    "problem",
    "solvers",
    "fem",
    "compare",
    "fracture",
    "FractureOptions",
    "Weibull",
    "Mesh",
    "DV",
    "RV",
    "Fix",
    "Traction",
    "Pressure",
    "BodyForce",
    "PointLoad",
    "At",
    "solve",
    "SolveOptions",
    "SolveInfo",
    "stability",
    "Solution",
    "SolverError",
    "InputError",
    "CalibrationError",
    "UnknownRegionError",
    "SingularError",
    "UnstableError",
    "ConvergenceError",
    "MissingDependencyError",
    "homogenize",
    "elastic_tensor",
    "plane_stress_tensor",
    "clear_caches",
    "cache_info",
    "__version__",
]
