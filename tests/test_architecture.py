"""The package's structure: layers, no import cycles, the public API, old paths.

The layers (each module imports only from its own layer or those below it):

    0 foundation  _checks _cache _env _planar _version _compat errors material linalg
    1 mesh        dvstatic.mesh.*, dvstatic.domain
    2 lattice     dvstatic.lattice.*
    3 problem     dvstatic.problem, dvstatic.stress.* (stresses of lattice states)
    4 solvers     dvstatic.solvers.*
    5 parallel    dvstatic.parallel.*
    6 outputs     dvstatic.post, fem.*, io, outfolder, plot
    7 front door  dvstatic.scene.*, cli, __main__
    8 facade      dvstatic (the package's __init__)

Every import is read from the source (module level, inside functions, under
TYPE_CHECKING), so a cycle hidden by a late or local import is found too; importing a
module of another package also runs that package's ``__init__`` (an edge to it), and a
module named in a string (``importlib.import_module("dvstatic....")``) counts as
imported, except in the two registries that exist to name modules lazily.
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
    "dvstatic._atomic": 0,
    "dvstatic.errors": 0,
    "dvstatic.material": 0,
    "dvstatic.linalg": 0,
    "dvstatic.mesh": 1,
    "dvstatic.domain": 1,
    "dvstatic.lattice": 2,
    "dvstatic.problem": 3,
    "dvstatic.stress": 3,
    "dvstatic.solvers": 4,
    "dvstatic.parallel": 5,
    "dvstatic.crack": 5,
    "dvstatic.post": 6,
    "dvstatic.fem": 6,
    "dvstatic.io": 6,
    "dvstatic.pictures": 6,
    "dvstatic.outfolder": 6,
    "dvstatic.report": 6,
    "dvstatic.plot": 6,
    "dvstatic.scene": 7,
    "dvstatic.cli": 7,
    "dvstatic.console": 7,
    "dvstatic.__main__": 7,
}
FACADE = "dvstatic"  # the package's __init__: the top, matched exactly
#: modules that name others in strings on purpose: the old-path alias table, and the
#: engine registry that loads solver="petsc" on use (solvers -> parallel at run time)
REGISTRIES = {"dvstatic._compat", "dvstatic.solvers.backends", "dvstatic"}
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


def _parents(target: str, importer: str) -> list[str]:
    """Packages whose ``__init__`` runs when ``importer`` imports ``target`` (those of
    ``target`` that are not packages of ``importer`` itself)."""
    parts = target.split(".")
    out = []
    for k in range(2, len(parts)):
        pkg = ".".join(parts[:k])
        if _is_package(pkg) and not (importer == pkg or importer.startswith(pkg + ".")):
            out.append(pkg)
    return out


def _string_imports(name: str, tree) -> set[str]:
    if name in REGISTRIES:
        return set()
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            mod = node.value.split(":")[0]
            if mod in MODULES and mod.startswith("dvstatic."):
                out.add(mod)
    return out


def _imports() -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text())
        deps = _string_imports(name, tree)
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for d in _resolve(name, node):
                    deps.add(d)
                    deps.update(_parents(d, name))
        deps.discard(name)
        graph[name] = deps
    return graph


def _layer(name: str) -> int:
    if name == FACADE:
        return 8
    best = max((k for k in LAYERS if name == k or name.startswith(k + ".")), key=len)
    return LAYERS[best]


def test_every_module_has_a_layer():
    for name in MODULES:
        assert name == FACADE or any(name == k or name.startswith(k + ".") for k in LAYERS), name


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
    "io.write_bonds_vtu",
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


#: the public names of dvstatic 0.1's modules that still resolve through the old paths
#: (removed: assembly.assemble/assemble_vector/triangle_dofs, dead code; newton.NewtonOptions,
#: replaced by dv.SolveOptions; docs/api.md lists them)
OLD_NAMES = {
    "dvstatic.meshgen": [
        "KINDS",
        "rectangle",
        "generate",
        "polygon",
        "disc",
        "lloyd",
        "with_spread",
        "spatial_order",
        "CVT_ITERATIONS",
        "SQRT3_2",
    ],
    "dvstatic.periodic": ["periodic_square", "periodic_delaunay"],
    "dvstatic.lattice.stress": ["node_stress", "strain_stress", "bond_state", "check_model"],
    "dvstatic.ordering": ["nested_dissection", "mesh_dof_order"],
    "dvstatic.kinematics": ["circumcentres", "barycentric", "edge_frames", "half_sides"],
    "dvstatic.geometry": ["Geometry", "of", "is_cached"],
    "dvstatic.assembly": ["BlockPattern", "pattern", "accumulate"],
    "dvstatic.calibration": [
        "MicroParameters",
        "Moments",
        "moments",
        "moment_sums",
        "moments_from_sums",
        "paper",
        "paper_from_moments",
        "relaxed",
        "admissible_nu",
        "relaxed_moduli",
        "CALIBRATIONS",
    ],
    "dvstatic.models": ["DV", "RV", "VoronoiModel", "voronoi_weights", "BONDS"],
    "dvstatic.loads": [
        "Fix",
        "Traction",
        "BodyForce",
        "PointLoad",
        "load_vector",
        "constraints",
        "as_list",
    ],
    "dvstatic.newton": ["solve_nonlinear"],
    "dvstatic.relaxation": ["dynamic_relaxation"],
    "dvstatic.stability": ["StabilityReport", "stability", "DENSE_MAX_DOF", "CHECK_MAX_DOF"],
    "dvstatic.distributed": [
        "available",
        "launched_under_mpi",
        "rcb_partition",
        "Layout",
        "layout",
        "owned_bonds",
        "owned_triangles",
        "micro_parameters",
        "owned_loads",
        "patch_memory",
    ],
    "dvstatic.petsc_solve": ["DEFAULT_OPTIONS", "solve_petsc"],
}


def test_every_old_module_is_listed():
    assert set(OLD_NAMES) == set(dv._compat.MOVED)


@pytest.mark.parametrize("old", sorted(OLD_NAMES))
def test_old_module_paths_warn_and_work(old):
    import sys

    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mod = importlib.import_module(old)
    assert any(issubclass(w.category, DeprecationWarning) for w in caught), old
    for name in OLD_NAMES[old]:
        assert getattr(mod, name) is not None, f"{old}.{name}"


def test_stability_function_survives_the_old_module_import():
    import sys

    sys.modules.pop("dvstatic.stability", None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        importlib.import_module("dvstatic.stability")
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    rep = dv.stability(dv.DV(mesh, 1e5, 0.2), [dv.Fix("left")])
    assert rep.stable


def test_bounded_cache_keeps_the_most_recent():
    from dvstatic._cache import _REGISTRY, Bounded

    cache = Bounded("test cache", maxsize=2)
    try:
        for k in range(3):
            cache.put(k, k * k)
        assert len(cache) == 2 and cache.get(0) is None and cache.get(2) == 4
        cache.get(1)  # now the most recent
        cache.put(3, 9)
        assert cache.get(1) == 1 and cache.get(2) is None
    finally:
        _REGISTRY.pop("test cache")


def test_caches_are_bounded_and_clearable():
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.2, kind="lattice")
    model = dv.DV(mesh, 1e5, 0.2)
    dv.solve(model, dv.Fix("left"), dv.Traction("right", (1.0, 0.0)))
    info = dv.cache_info()
    assert info["geometry"] >= 1 and info["sparsity pattern"] >= 1
    assert info["factorisations"] >= 1
    dv.clear_caches()
    assert all(n == 0 for n in dv.cache_info().values())
