"""Scene-file schema: every key with its kind, default, choices and meaning
(:data:`SCHEMA`), its validation and the generated reference (``docs/scenes.md``).
The ``[solver]`` table is derived from :class:`~dvstatic.solvers.SolveOptions`."""

from __future__ import annotations

import copy
import dataclasses
import logging
import numbers
import tomllib
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..solvers.options import ALIASES, SolveOptions

log = logging.getLogger(__name__)

__all__ = ["SceneError", "F", "SCHEMA", "SOLVER_KEYS", "parse", "reference_markdown"]


class SceneError(InputError):
    """A scene file problem: ``str(err)`` is ``"<file>: <key path>: <problem>"``."""

    def __init__(self, file, key: str, message: str):
        self.file = str(file)
        self.key = key
        self.problem = message
        super().__init__(f"{file}: {key}: {message}" if key else f"{file}: {message}", key)


@dataclass(frozen=True)
class F:
    """One key: kind, default (None = no default), whether required, choices, doc."""

    kind: str
    doc: str
    default: object = None
    required: bool = False
    choices: tuple = ()
    schema: dict | None = None  # for "table" and "tables"


HOLE = {
    "type": F("string", "hole shape", required=True, choices=("circle", "polygon")),
    "name": F("string", "boundary part name of the hole", default="hole"),
    "center": F("point", "circle centre (length)"),
    "radius": F("number", "circle radius (length)"),
    "vertices": F("points", "polygon corners (length)"),
}

SCHEMA: dict[str, F] = {
    "title": F("string", "free text shown in the summary", default=""),
    "mesh": F(
        "table",
        "the body and its triangulation",
        required=True,
        schema={
            "type": F(
                "string", "domain", required=True, choices=("rectangle", "polygon", "disc", "file")
            ),
            "h": F("number", "node spacing (length); required except for type = file"),
            "kind": F(
                "string",
                "interior points",
                default="jittered",
                choices=("lattice", "jittered", "random", "cvt"),
            ),
            "jitter": F("number", "relative jitter of kind = jittered, in [0, 0.5)", default=0.3),
            "seed": F("int", "random seed", default=0),
            "width": F(
                "number", "rectangle: size along x (length); parts bottom, right, top, left"
            ),
            "height": F("number", "rectangle: size along y (length)"),
            "vertices": F("points", "polygon: corners in order (length)"),
            "names": F("strings", "polygon: name of every edge (default edge0, edge1, ...)"),
            "radius": F("number", "disc: radius (length); part 'boundary'"),
            "center": F("point", "disc: centre (length)", default=[0.0, 0.0]),
            "path": F(
                "string",
                "file: gmsh .msh (or other meshio) file, relative to the scene; "
                "physical line groups become parts",
            ),
            "holes": F("tables", "holes of a rectangle, polygon or disc", default=[], schema=HOLE),
        },
    ),
    "material": F(
        "table",
        "plane-stress continuum",
        required=True,
        schema={
            "E": F("number", "Young's modulus (force/area), > 0", required=True),
            "nu": F("number", "Poisson's ratio, -1 < nu < 1", required=True),
        },
    ),
    "model": F(
        "table",
        "lattice model",
        default={},
        schema={
            "type": F(
                "string",
                "DV (deformable) or RV (remeshing Voronoi)",
                default="DV",
                choices=("DV", "RV"),
            ),
            "calibration": F(
                "string",
                "micro-parameters: paper (closed form, affine strain) or "
                "relaxed (matches E and nu in equilibrium on a periodic sample "
                "with the mesh's bond-length spread)",
                default="paper",
                choices=("paper", "relaxed"),
            ),
            "bonds": F(
                "string",
                "normal-spring stiffness: uniform (the paper's k_n) or "
                "voronoi (k_n sqrt(3) r/l: no stiff surface layer)",
                default="uniform",
                choices=("uniform", "voronoi"),
            ),
        },
    ),
    "supports": F(
        "tables",
        "prescribed displacements",
        default=[],
        schema={
            "where": F("nodes", "boundary part name or list of node indices"),
            "at": F("point", "instead of where: the node nearest to this point"),
            "x": F("number", "prescribed u_x (length); omit to leave free"),
            "y": F(
                "number",
                "prescribed u_y (length); omit to leave free. Neither x nor y: clamp (both 0)",
            ),
        },
    ),
    "loads": F(
        "tables",
        "applied loads (dead loads, per unit thickness)",
        default=[],
        schema={
            "type": F(
                "string",
                "traction: force/length on a part; body: force/area; point: force on nodes",
                required=True,
                choices=("traction", "body", "point"),
            ),
            "where": F("nodes", "traction: part name; point: part name or node indices"),
            "at": F("point", "point: instead of where, the node nearest to this point"),
            "value": F("point", "force vector (fx, fy)", required=True),
        },
    ),
    "solver": F("table", "how to solve (the options of dv.solve)", default={}, schema=None),
    "output": F(
        "table",
        "what to write",
        default={},
        schema={
            "vtu": F("bool", "<name>.vtu: displacement, stress, bond tensions", default=True),
            "png": F("bool", "<name>.png: deformed mesh coloured by `field`", default=True),
            "json": F("bool", "<name>.json: summary (mesh, model, results, timings)", default=True),
            "field": F(
                "string",
                "colour of the picture",
                default="|u|",
                choices=("|u|", "ux", "uy", "sxx", "syy", "sxy", "von_mises"),
            ),
            "stress": F(
                "string",
                "stress recovery of the picture: virial (the lattice's bond "
                "forces) or strain (plane-stress law on the lattice strain; better at free "
                "surfaces)",
                default="virial",
                choices=("virial", "strain"),
            ),
            "scale": F("number", "displacement magnification of the picture (default: auto)"),
            "name": F("string", "file name stem (default: the scene file's stem)"),
            "fe_compare": F(
                "bool", "solve the FE reference on the same triangles and compare", default=False
            ),
            "fe_order": F("int", "FE element order, 1 or 2", default=2),
            "fe_refine": F("int", "uniform refinements of the FE reference", default=1),
            "probes": F("points", "points where displacement and stress are reported", default=[]),
            "part_stress": F(
                "strings", "boundary parts whose nodal stress extremes are reported", default=[]
            ),
        },
    ),
}


def _solver_schema() -> dict[str, F]:
    """The ``[solver]`` table, derived from :class:`~dvstatic.solvers.SolveOptions`."""
    out = {}
    for f in dataclasses.fields(SolveOptions):
        meta = f.metadata
        if not meta["scene"]:
            continue
        out[meta["scene_key"] or f.name] = F(
            meta["kind"], meta["doc"], default=f.default, choices=meta["choices"]
        )
    return out


#: scene key of every option in ``[solver]`` (``type`` is ``solver``)
SOLVER_KEYS = {
    (f.metadata["scene_key"] or f.name): f.name
    for f in dataclasses.fields(SolveOptions)
    if f.metadata["scene"]
}
SCHEMA["solver"] = dataclasses.replace(SCHEMA["solver"], schema=_solver_schema())


def parse(path, content: bytes, overrides=()) -> dict:
    """Validated scene data (every key, defaults filled in) from TOML ``content``.

    Raises
    ------
    SceneError
    """
    try:
        raw = tomllib.loads(content.decode())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(path, "", f"not valid TOML: {exc}") from None
    for item in overrides:
        _apply_override(path, raw, item)
    _rename_aliases(path, raw)
    data = _validate(path, raw, SCHEMA, "")
    _check_rules(path, data)
    return data


def _apply_override(path, raw: dict, item: str) -> None:
    if "=" not in item:
        raise SceneError(path, item, "override must look like key.path=value")
    key, value = item.split("=", 1)
    key = key.strip()
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    node = raw
    parts = key.split(".")
    for i, p in enumerate(parts[:-1]):
        if isinstance(node, list):
            if not p.isdigit() or int(p) >= len(node):
                raise SceneError(path, ".".join(parts[: i + 1]), "no such list element")
            node = node[int(p)]
        else:
            node = node.setdefault(p, {})
        if not isinstance(node, (dict, list)):
            raise SceneError(path, ".".join(parts[: i + 1]), "is not a table")
    if isinstance(node, list):
        raise SceneError(path, key, "cannot set a whole list element")
    node[parts[-1]] = parsed


def _rename_aliases(path, raw: dict) -> None:
    """Deprecated ``[solver]`` keys under their new names (with a warning)."""
    solver = raw.get("solver")
    if not isinstance(solver, dict):
        return
    for old, new in ALIASES.items():
        if old in solver:
            if new in solver:
                raise SceneError(path, f"solver.{old}", f"give solver.{new} only (its new name)")
            log.warning("%s: solver.%s is deprecated; use solver.%s", path, old, new)
            solver[new] = solver.pop(old)


def _type_name(v) -> str:
    return {
        bool: "boolean",
        int: "integer",
        float: "number",
        str: "string",
        list: "array",
        dict: "table",
    }.get(type(v), type(v).__name__)


def _validate(path, raw, schema: dict, prefix: str) -> dict:
    if not isinstance(raw, dict):
        raise SceneError(path, prefix or "scene", f"expected a table, got {_type_name(raw)}")
    out = {}
    for key in raw:
        if key not in schema:
            where = f"{prefix}.{key}" if prefix else key
            raise SceneError(
                path, where, f"unknown key; accepted keys: {', '.join(sorted(schema))}"
            )
    for key, f in schema.items():
        where = f"{prefix}.{key}" if prefix else key
        if key not in raw:
            if f.required:
                raise SceneError(path, where, "required key is missing")
            out[key] = copy.deepcopy(f.default)
            if f.kind == "table" and f.default is not None:
                out[key] = _validate(path, {}, f.schema, where)
            continue
        out[key] = _check_value(path, where, raw[key], f)
    return out


def _check_value(path, where: str, v, f: F):
    def fail(expected):
        raise SceneError(path, where, f"expected {expected}, got {_type_name(v)} {v!r}")

    k = f.kind
    if k == "number":
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not np.isfinite(v):
            fail("a finite number")
        return float(v)
    if k == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            fail("an integer")
        return int(v)
    if k == "bool":
        if not isinstance(v, bool):
            fail("true or false")
        return v
    if k == "string":
        if not isinstance(v, str):
            fail("a string")
        if f.choices and v not in f.choices:
            raise SceneError(path, where, f"{v!r} is not one of: {', '.join(map(str, f.choices))}")
        return v
    if k == "strings":
        if not isinstance(v, list) or not all(isinstance(s, str) for s in v):
            fail("an array of strings")
        return list(v)
    if k == "point":
        if (
            not isinstance(v, list)
            or len(v) != 2
            or not all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in v)
        ):
            fail("two numbers [x, y]")
        return [float(x) for x in v]
    if k == "points":
        if not isinstance(v, list) or not all(
            isinstance(p, list)
            and len(p) == 2
            and all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in p)
            for p in v
        ):
            fail("an array of [x, y] pairs")
        return [[float(x) for x in p] for p in v]
    if k == "nodes":
        if isinstance(v, str):
            return v
        if (
            isinstance(v, list)
            and v
            and all(isinstance(i, int) and not isinstance(i, bool) for i in v)
        ):
            return list(v)
        fail("a boundary part name or a non-empty array of node indices")
    if k == "table":
        return _validate(path, v, f.schema, where)
    if k == "tables":
        if not isinstance(v, list):
            fail("an array of tables ([[...]])")
        return [_validate(path, item, f.schema, f"{where}[{i}]") for i, item in enumerate(v)]
    raise AssertionError(k)  # pragma: no cover - schema kinds are fixed above


def _check_rules(path, d: dict) -> None:
    """Cross-key rules the schema cannot express."""
    m = d["mesh"]
    need = {
        "rectangle": ("width", "height", "h"),
        "polygon": ("vertices", "h"),
        "disc": ("radius", "h"),
        "file": ("path",),
    }[m["type"]]
    for key in need:
        if m[key] is None:
            raise SceneError(path, f"mesh.{key}", f"required for mesh type {m['type']!r}")
    for i, h in enumerate(m["holes"]):
        need_h = ("center", "radius") if h["type"] == "circle" else ("vertices",)
        for key in need_h:
            if h[key] is None:
                raise SceneError(path, f"mesh.holes[{i}].{key}", f"required for a {h['type']} hole")
    if m["type"] == "file" and m["holes"]:
        raise SceneError(path, "mesh.holes", "holes cannot be added to a mesh read from a file")
    nu = d["material"]["nu"]
    if not -1.0 < nu < 1.0:
        raise SceneError(path, "material.nu", f"{nu} is outside the plane-stress range -1 < nu < 1")
    if d["material"]["E"] <= 0:
        raise SceneError(path, "material.E", f"must be > 0, got {d['material']['E']}")
    for i, s in enumerate(d["supports"]):
        if (s["where"] is None) == (s["at"] is None):
            raise SceneError(path, f"supports[{i}]", "give exactly one of `where` or `at`")
    for i, ld in enumerate(d["loads"]):
        if ld["type"] == "traction":
            if not isinstance(ld["where"], str) or ld["at"] is not None:
                raise SceneError(
                    path, f"loads[{i}].where", "a traction needs `where` = a boundary part name"
                )
        elif ld["type"] == "point":
            if (ld["where"] is None) == (ld["at"] is None):
                raise SceneError(path, f"loads[{i}]", "give exactly one of `where` or `at`")
        elif ld["where"] is not None or ld["at"] is not None:
            raise SceneError(path, f"loads[{i}]", "a body force acts everywhere: no where/at")
    if not d["supports"]:
        raise SceneError(
            path, "supports", "no supports: add [[supports]] tables that prevent rigid-body motion"
        )
    o = d["output"]
    if o["fe_order"] not in (1, 2):
        raise SceneError(path, "output.fe_order", f"must be 1 or 2, got {o['fe_order']}")
    if not 0 <= o["fe_refine"] <= 6:
        raise SceneError(path, "output.fe_refine", f"must be in [0, 6], got {o['fe_refine']}")
    if o["scale"] is not None and o["scale"] <= 0:
        raise SceneError(path, "output.scale", f"must be > 0, got {o['scale']}")


def reference_markdown() -> str:
    """Markdown reference of every scene key (generated from :data:`SCHEMA`)."""
    lines = ["| key | type | default | meaning |", "|---|---|---|---|"]

    def walk(schema, prefix):
        for key, f in schema.items():
            name = f"{prefix}{key}"
            if f.kind == "tables":
                name_t = f"[[{name}]]"
            elif f.kind == "table":
                name_t = f"[{name}]"
            else:
                name_t = f"`{name}`"
            if f.required:
                default = "required"
            elif f.kind in ("table", "tables") or f.default in (None, [], {}):
                default = "-"
            else:
                default = f"`{f.default!r}`".replace("'", '"')
            doc = f.doc + (f" ({' / '.join(map(str, f.choices))})" if f.choices else "")
            lines.append(f"| {name_t} | {f.kind} | {default} | {doc} |")
            if f.schema:
                walk(f.schema, f"{name}.")

    walk(SCHEMA, "")
    return "\n".join(lines)
