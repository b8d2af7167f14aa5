"""The package's structure: layers, no import cycles, the public API, old paths.

The layers (each module imports only from its own layer or those below it):

    0 foundation  _checks _cache _env _planar _version _compat errors material linalg
    1 mesh        dvstatic.mesh.*, dvstatic.domain
    2 lattice     dvstatic.lattice.*
    3 problem     dvstatic.problem
    4 solvers     dvstatic.solvers.*, dvstatic.parallel.*
    5 outputs     dvstatic.post, fem, io, plot
    6 front door  dvstatic.scene, cli, __main__
    7 facade      dvstatic (the package's __init__)

Every import is read from the source (module level, inside functions, under
TYPE_CHECKING), so a cycle hidden by a late or local import is found too.
"""

import ast
import importlib
import warnings
from pathlib import Path

import pytest

import dvstatic as dv

ROOT = Path(dv.__file__).resolve().parent
LAYERS = {
    "dvstatic._checks": 0,
    "dvstatic._cache": 0,
    "dvstatic._env": 0,
    "dvstatic._planar": 0,
    "dvstatic._version": 0,
    "dvstatic._compat": 0,
    "dvstatic.errors": 0,
    "dvstatic.material": 0,
    "dvstatic.linalg": 0,
    "dvstatic.mesh": 1,
    "dvstatic.domain": 1,
    "dvstatic.lattice": 2,
    "dvstatic.problem": 3,
    "dvstatic.solvers": 4,
    "dvstatic.parallel": 4,
    "dvstatic.post": 5,
    "dvstatic.fem": 5,
    "dvstatic.io": 5,
    "dvstatic.plot": 5,
    "dvstatic.scene": 6,
    "dvstatic.cli": 6,
    "dvstatic.__main__": 6,
    "dvstatic": 7,
}
#: optional or heavy packages: imported inside functions only, never at module level
ON_USE = ("scipy", "pyamg", "skfem", "matplotlib", "meshio", "petsc4py", "mpi4py", "tqdm")


def _modules() -> dict[str, Path]:
    out = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES.get(name, Path()).name == "__init__.py"


def _resolve(module: str, node) -> list[str]:
    """The dvstatic modules an import statement loads."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "dvstatic"]
    if node.level:
        pkg = module if _is_package(module) else module.rsplit(".", 1)[0]
        for _ in range(node.level - 1):
            pkg = pkg.rsplit(".", 1)[0]
        base = f"{pkg}.{node.module}" if node.module else pkg
    else:
        base = node.module or ""
    if base.split(".")[0] != "dvstatic":
        return []
    out = []
    for a in node.names:
        sub = f"{base}.{a.name}"
        out.append(sub if sub in MODULES else base)
    return out


def _imports() -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text())
        deps = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                deps.update(d for d in _resolve(name, node) if d != name)
        graph[name] = deps
    return graph


def _layer(name: str) -> int:
    best = max((k for k in LAYERS if name == k or name.startswith(k + ".")), key=len)
    return LAYERS[best]


def test_every_module_has_a_layer():
    for name in MODULES:
        assert any(name == k or name.startswith(k + ".") for k in LAYERS), name


def test_no_import_goes_up_a_layer():
    bad = [
        f"{m} (layer {_layer(m)}) imports {d} (layer {_layer(d)})"
        for m, deps in _imports().items()
        for d in deps
        if _layer(d) > _layer(m)
    ]
    assert not bad, "\n".join(bad)


def test_no_import_cycles():
    graph = _imports()
    state: dict[str, int] = {}
    cycles = []

    def visit(node, stack):
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph.get(node, ())):
            if state.get(dep) == 1:
                cycles.append(stack[stack.index(dep) :] + [dep])
            elif dep not in state:
                visit(dep, stack)
        stack.pop()
        state[node] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name, [])
    assert not cycles, "\n".join(" -> ".join(c) for c in cycles)


def test_optional_packages_load_on_use():
    bad = []
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text())
        for node in tree.body:  # module level only (TYPE_CHECKING blocks are skipped)
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                mods = [node.module or ""]
            else:
                continue
            bad += [f"{name}: {m}" for m in mods if m.split(".")[0] in ON_USE]
    assert not bad, bad


PUBLIC = [
    "mesh.rectangle",
    "mesh.polygon",
    "mesh.disc",
    "mesh.generate",
    "mesh.periodic_square",
    "mesh.with_spread",
    "mesh.lloyd",
    "mesh.Mesh",
    "mesh.KINDS",
    "domain.Circle",
    "domain.Polygon",
    "domain.Domain",
    "Mesh",
    "DV",
    "RV",
    "Fix",
    "Traction",
    "BodyForce",
    "PointLoad",
    "solve",
    "SolveOptions",
    "SolveInfo",
    "Solution",
    "stability",
    "homogenize",
    "elastic_tensor",
    "plane_stress_tensor",
    "compare",
    "fem.solve",
    "fem.FESolution",
    "fem.lame_plane_stress",
    "io.read_mesh",
    "io.write_vtu",
    "io.write_json",
    "io.write_png",
    "io.summary",
    "plot.draw_mesh",
    "plot.draw_deformed",
    "post.virial_stress",
    "post.node_stress",
    "post.strain_stress",
    "post.square_stress",
    "post.interpolate",
    "scene.load",
    "parallel.rcb_partition",
    "parallel.layout",
    "SolverError",
    "InputError",
    "CalibrationError",
    "UnstableError",
    "SingularError",
    "ConvergenceError",
    "MissingDependencyError",
    "clear_caches",
    "cache_info",
    "__version__",
]


@pytest.mark.parametrize("path", PUBLIC)
def test_public_names_resolve(path):
    obj = dv
    for part in path.split("."):
        obj = getattr(obj, part)
    assert obj is not None


def test_errors_are_classified_by_type():
    assert issubclass(dv.InputError, ValueError)
    assert issubclass(dv.CalibrationError, dv.InputError)
    for cls in (dv.UnstableError, dv.SingularError, dv.ConvergenceError):
        assert issubclass(cls, dv.SolverError)
    assert issubclass(dv.SolverError, RuntimeError)
    assert issubclass(dv.MissingDependencyError, ImportError)


@pytest.mark.parametrize("old", sorted(importlib.import_module("dvstatic._compat").MOVED))
def test_old_module_paths_warn_and_work(old):
    import sys

    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mod = importlib.import_module(old)
    assert any(issubclass(w.category, DeprecationWarning) for w in caught), old
    new = importlib.import_module(dv._compat.MOVED[old])
    name = next(n for n in dir(new) if not n.startswith("_"))
    assert getattr(mod, name) is getattr(new, name)


def test_stability_function_survives_the_old_module_import():
    import sys

    sys.modules.pop("dvstatic.stability", None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        importlib.import_module("dvstatic.stability")
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    rep = dv.stability(dv.DV(mesh, 1e5, 0.2), [dv.Fix("left")])
    assert rep.stable


def test_caches_are_bounded_and_clearable():
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.2, kind="lattice")
    model = dv.DV(mesh, 1e5, 0.2)
    dv.solve(model, dv.Fix("left"), dv.Traction("right", (1.0, 0.0)))
    info = dv.cache_info()
    assert info["geometry"] >= 1 and info["sparsity pattern"] >= 1
    assert info["factorisations"] >= 1
    dv.clear_caches()
    assert all(n == 0 for n in dv.cache_info().values())
