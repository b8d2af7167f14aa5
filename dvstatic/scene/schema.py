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
from ..mesh.generators import DEFAULT_JITTER
from ..report import CHECK_QUANTITIES
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

REGION = {
    "type": F("string", "region shape", required=True, choices=("circle", "polygon")),
    "name": F("string", "region name", required=True),
    "center": F("point", "circle centre (length)"),
    "radius": F("number", "circle radius (length)"),
    "vertices": F("points", "polygon corners (length)"),
}

#: a linear profile between two points: rows [x, y, value...]
PROFILE_DOC = (
    "linear profile [[x0, y0, {v}], [x1, y1, {v}]]: the value at a point is interpolated "
    "along the line from (x0, y0) to (x1, y1) (constant beyond its ends)"
)


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
            "jitter": F(
                "number", "relative jitter of kind = jittered, in [0, 0.5)", default=DEFAULT_JITTER
            ),
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
            "refine_near": F(
                "strings",
                "graded mesh: names of boundary curves or regions (a hole, a loaded side) "
                "near which the spacing is h_near, growing to h over `grading` (a CVT mesh)",
                default=[],
            ),
            "h_near": F("number", "graded mesh: spacing on the refine_near curves (length)"),
            "grading": F(
                "number", "graded mesh: distance over which the spacing grows to h (length)"
            ),
            "regions": F(
                "tables",
                "named regions inside the body (the triangles conform to them); give each "
                "its own material with [[materials]] or its own body force",
                default=[],
                schema=REGION,
            ),
        },
    ),
    "material": F(
        "table",
        "the continuum (of the triangles outside the [[materials]] regions)",
        required=True,
        schema={
            "E": F("number", "Young's modulus (force/area), > 0", required=True),
            "nu": F(
                "number",
                "Poisson's ratio: -1 < nu < 1 in plane stress, -1 < nu < 0.5 in plane strain",
                required=True,
            ),
            "plane": F(
                "string",
                "plane stress (thin plate) or plane strain (long body: tunnels, dams, "
                "cylinders; szz = nu (sxx + syy) is reported)",
                default="stress",
                choices=("stress", "strain"),
            ),
            "thickness": F(
                "number",
                "out-of-plane thickness (length): forces become totals (tractions, "
                "pressures and body forces stay per area and volume, point loads are "
                "total forces); omit for per unit thickness",
            ),
        },
    ),
    "materials": F(
        "tables",
        "other materials on named regions of the mesh ([[mesh.regions]], or physical "
        "surfaces of a gmsh file)",
        default=[],
        schema={
            "region": F("string", "region name", required=True),
            "E": F("number", "Young's modulus (force/area), > 0", required=True),
            "nu": F("number", "Poisson's ratio", required=True),
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
                "micro-parameters: relaxed (the lattice in equilibrium matches E and nu "
                "on a periodic sample made like the mesh; stabilised coupling) or paper "
                "(the paper's closed form under affine strain)",
                default="relaxed",
                choices=("relaxed", "paper"),
            ),
            "bonds": F(
                "string",
                "normal-spring stiffness: surface (k_n, half on boundary bonds: no stiff "
                "surface layer), uniform (the paper's k_n) or voronoi (k_n sqrt(3) r/l). "
                "The paper's model: calibration = paper, bonds = uniform",
                default="surface",
                choices=("surface", "uniform", "voronoi"),
            ),
        },
    ),
    "supports": F(
        "tables",
        "prescribed displacements",
        default=[],
        schema={
            "where": F("nodes", "boundary part name or list of node indices"),
            "at": F(
                "point",
                "instead of where: the node nearest to this point (refused if no node lies "
                "within the local spacing)",
            ),
            "x": F("number", "prescribed u_x (length); omit to leave free"),
            "y": F(
                "number",
                "prescribed u_y (length); omit to leave free. Neither x nor y (nor their "
                "profiles): clamp (both 0)",
            ),
            "x_at": F("rows", "instead of x: u_x as a " + PROFILE_DOC.format(v="ux")),
            "y_at": F("rows", "instead of y: u_y as a " + PROFILE_DOC.format(v="uy")),
        },
    ),
    "loads": F(
        "tables",
        "applied loads (per unit thickness, or per area with a thickness)",
        default=[],
        schema={
            "type": F(
                "string",
                "traction: force/length on a part; pressure: normal pressure on a part "
                "(positive pushes into the body); body: force/area; point: force on nodes",
                required=True,
                choices=("traction", "pressure", "body", "point"),
            ),
            "where": F("nodes", "traction, pressure: part name; point: part name or node indices"),
            "at": F(
                "point",
                "point: instead of where, the node nearest to this point (refused if no "
                "node lies within the local spacing)",
            ),
            "value": F("point", "force vector (fx, fy): traction, body, point"),
            "value_at": F(
                "rows", "traction: instead of value, a " + PROFILE_DOC.format(v="tx, ty")
            ),
            "p": F("number", "pressure: its value (force/area); with gamma, at the level"),
            "p_at": F("rows", "pressure: instead of p, a " + PROFILE_DOC.format(v="p")),
            "gamma": F(
                "number",
                "pressure: hydrostatic, p + gamma (level - y) below the level, p above "
                "(gamma: unit weight of the fluid, force/volume)",
            ),
            "level": F("number", "pressure with gamma: the free-surface height y (length)"),
            "follower": F(
                "bool",
                "pressure: follows the deformed boundary in nonlinear solves",
                default=False,
            ),
            "region": F("string", "body: only on this region of the mesh"),
        },
    ),
    "solver": F("table", "how to solve (the options of dv.solve)", default={}, schema=None),
    "output": F(
        "table",
        "what to write",
        default={},
        schema={
            "vtu": F(
                "bool",
                "<name>.vtu (triangles: displacement, stress tensors, von Mises, area, "
                "material) and <name>_bonds.vtu (bonds: tension, length)",
                default=True,
            ),
            "png": F("bool", "<name>.png: deformed mesh coloured by `field`", default=True),
            "json": F("bool", "<name>.json: summary (mesh, model, results, timings)", default=True),
            "field": F(
                "string",
                "colour of the picture",
                default="|u|",
                choices=("|u|", "ux", "uy", "sxx", "syy", "sxy", "szz", "von_mises"),
            ),
            "stress": F(
                "string",
                "stress recovery of the picture, probes, checks and part stresses (the VTU "
                "holds recovered and virial): recovered (patch fits with "
                "the continuum law, equilibrated fits at boundaries: right at free and curved "
                "edges), virial (the lattice's bond forces over each Voronoi cell) or strain "
                "(area-averaged lattice strain); nonlinear solves use virial",
                default="recovered",
                choices=("recovered", "virial", "strain"),
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
            "checks": F(
                "tables",
                "key numbers printed (and written to the JSON) against a reference value, "
                "e.g. a closed form: the lattice value, with fe_compare the FE value, and "
                "their differences from the reference",
                default=[],
                schema={
                    "name": F("string", "what is checked (a label)", required=True),
                    "at": F(
                        "point",
                        "where (length): inside the mesh, or on its boundary within half the "
                        "local spacing of a node (the node's value is taken)",
                        required=True,
                    ),
                    "quantity": F(
                        "string",
                        "displacement or stress component (stress: output.stress recovery)",
                        required=True,
                        choices=CHECK_QUANTITIES,
                    ),
                    "reference": F("number", "the value to compare with", required=True),
                    "source": F("string", "where the reference comes from", default=""),
                },
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
        if not isinstance(v, list) or len(v) != 2 or not all(_finite(x) for x in v):
            fail("two finite numbers [x, y]")
        return [float(x) for x in v]
    if k == "points":
        if not isinstance(v, list) or not all(
            isinstance(p, list) and len(p) == 2 and all(_finite(x) for x in p) for p in v
        ):
            fail("an array of [x, y] pairs of finite numbers")
        return [[float(x) for x in p] for p in v]
    if k == "rows":
        if not isinstance(v, list) or not all(
            isinstance(r, list)
            and r
            and all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in r)
            for r in v
        ):
            fail("an array of arrays of numbers")
        return [[float(x) for x in r] for r in v]
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


def _finite(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and bool(np.isfinite(x))


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
    graded = [m["h_near"] is not None, m["grading"] is not None, bool(m["refine_near"])]
    if any(graded) and not all(graded):
        raise SceneError(
            path, "mesh.refine_near", "a graded mesh needs refine_near, h_near and grading"
        )
    if all(graded) and m["type"] == "file":
        raise SceneError(path, "mesh.refine_near", "a mesh read from a file cannot be graded")
    for i, h in enumerate(m["holes"]):
        need_h = ("center", "radius") if h["type"] == "circle" else ("vertices",)
        for key in need_h:
            if h[key] is None:
                raise SceneError(path, f"mesh.holes[{i}].{key}", f"required for a {h['type']} hole")
    if m["type"] == "file" and m["holes"]:
        raise SceneError(path, "mesh.holes", "holes cannot be added to a mesh read from a file")
    _check_material(path, "material", d["material"], d["material"]["plane"])
    if d["material"]["thickness"] is not None and d["material"]["thickness"] <= 0:
        raise SceneError(path, "material.thickness", "must be > 0")
    seen = set()
    for i, mat in enumerate(d["materials"]):
        _check_material(path, f"materials[{i}]", mat, d["material"]["plane"])
        if mat["region"] in seen:
            raise SceneError(path, f"materials[{i}].region", f"{mat['region']!r} given twice")
        seen.add(mat["region"])
    for i, r in enumerate(m["regions"]):
        need_r = ("center", "radius") if r["type"] == "circle" else ("vertices",)
        for key in need_r:
            if r[key] is None:
                raise SceneError(
                    path, f"mesh.regions[{i}].{key}", f"required for a {r['type']} region"
                )
    if m["type"] == "file" and m["regions"]:
        raise SceneError(
            path, "mesh.regions", "a mesh file brings its regions (gmsh physical surfaces)"
        )
    for i, s in enumerate(d["supports"]):
        if (s["where"] is None) == (s["at"] is None):
            raise SceneError(path, f"supports[{i}]", "give exactly one of `where` or `at`")
        for c in ("x", "y"):
            if s[c] is not None and s[f"{c}_at"] is not None:
                raise SceneError(path, f"supports[{i}].{c}_at", f"give {c} or {c}_at, not both")
            if s[f"{c}_at"] is not None:
                _check_profile(path, f"supports[{i}].{c}_at", s[f"{c}_at"], 1)
    for i, ld in enumerate(d["loads"]):
        _check_load(path, f"loads[{i}]", ld)
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


def _check_material(path, key: str, mat: dict, plane: str) -> None:
    if mat["E"] <= 0:
        raise SceneError(path, f"{key}.E", f"must be > 0, got {mat['E']}")
    hi = 1.0 if plane == "stress" else 0.5
    if not -1.0 < mat["nu"] < hi:
        raise SceneError(
            path, f"{key}.nu", f"{mat['nu']} is outside the plane-{plane} range -1 < nu < {hi:g}"
        )


def _check_profile(path, key: str, rows: list, n_values: int) -> None:
    """A linear profile: two rows [x, y, value...] at two different points."""
    if len(rows) != 2 or any(len(r) != 2 + n_values for r in rows):
        vals = ", ".join(["v"] * n_values)
        raise SceneError(path, key, f"expected two rows [x, y, {vals}], got {rows!r}")
    if rows[0][:2] == rows[1][:2]:
        raise SceneError(path, key, "the two points of a profile must differ")


#: keys each load type accepts (besides type)
_LOAD_KEYS = {
    "traction": ("where", "value", "value_at"),
    "pressure": ("where", "p", "p_at", "gamma", "level", "follower"),
    "body": ("value", "region"),
    "point": ("where", "at", "value"),
}


def _check_load(path, key: str, ld: dict) -> None:
    kind = ld["type"]
    for k, v in ld.items():
        given = v is not None and v is not False
        if k != "type" and given and k not in _LOAD_KEYS[kind]:
            raise SceneError(path, f"{key}.{k}", f"not a key of a {kind} load")
    if kind in ("traction", "pressure") and not isinstance(ld["where"], str):
        raise SceneError(path, f"{key}.where", f"a {kind} needs `where` = a boundary part name")
    if kind == "point" and (ld["where"] is None) == (ld["at"] is None):
        raise SceneError(path, key, "give exactly one of `where` or `at`")
    if kind in ("body", "point") and ld["value"] is None:
        raise SceneError(path, f"{key}.value", f"required for a {kind} load")
    if kind == "traction":
        if (ld["value"] is None) == (ld["value_at"] is None):
            raise SceneError(path, key, "give exactly one of `value` or `value_at`")
        if ld["value_at"] is not None:
            _check_profile(path, f"{key}.value_at", ld["value_at"], 2)
    if kind == "pressure":
        if (ld["p"] is None) == (ld["p_at"] is None) and ld["gamma"] is None:
            raise SceneError(path, key, "give exactly one of `p`, `p_at` (or `gamma`)")
        if ld["p_at"] is not None:
            if ld["p"] is not None or ld["gamma"] is not None:
                raise SceneError(path, f"{key}.p_at", "give p_at alone (no p, no gamma)")
            _check_profile(path, f"{key}.p_at", ld["p_at"], 1)
        if (ld["gamma"] is None) != (ld["level"] is None):
            raise SceneError(path, key, "a hydrostatic pressure needs both `gamma` and `level`")


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
