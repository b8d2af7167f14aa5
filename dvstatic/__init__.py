"""dvstatic: plane stress-strain analysis with deformable (DV) and remeshing (RV)
Voronoi lattice-spring models, solved implicitly and checked against finite elements.

Public API::

    import dvstatic as dv
    mesh = dv.mesh.rectangle(1.0, 1.0, h=0.05, kind="jittered")
    model = dv.DV(mesh, E=1e5, nu=0.2)
    sol = dv.solve(model, [dv.Fix("left", x=0), dv.Fix("bottom", y=0)],
                   [dv.Traction("right", (-1.0, 0.0))])
"""

from . import fem, mesh
from .fem import compare
from .linalg import SolverError
from .loads import BodyForce, Fix, PointLoad, Traction
from .mesh import Mesh
from .models import DV, RV
from .post import elastic_tensor, homogenize, plane_stress_tensor
from .solvers import Solution, solve
from .stability import stability

__version__ = "0.1.0"

#: submodules loaded on first use (``dv.io``, ``dv.plot``, ...): their optional
#: dependencies (meshio, matplotlib) stay out of ``import dvstatic``
_LAZY_SUBMODULES = frozenset(
    {
        "assembly",
        "calibration",
        "cli",
        "distributed",
        "domain",
        "geometry",
        "io",
        "kinematics",
        "linalg",
        "meshgen",
        "models",
        "newton",
        "ordering",
        "periodic",
        "petsc_solve",
        "plot",
        "post",
        "relaxation",
        "scene",
        "solvers",
    }
)


def __getattr__(name: str):
    if name in _LAZY_SUBMODULES:
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'dvstatic' has no attribute {name!r}")


__all__ = [
    "mesh",
    "fem",
    "compare",
    "Mesh",
    "DV",
    "RV",
    "Fix",
    "Traction",
    "BodyForce",
    "PointLoad",
    "solve",
    "stability",
    "Solution",
    "SolverError",
    "homogenize",
    "elastic_tensor",
    "plane_stress_tensor",
    "__version__",
]
