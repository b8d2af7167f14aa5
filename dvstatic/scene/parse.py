"""Scene files read and validated against :data:`~dvstatic.scene.schema.SCHEMA`: TOML,
``--set`` overrides, old key names, every value's kind and range, and the rules that
join keys (which keys a mesh type or a load type needs, profiles, materials).
"""

from __future__ import annotations

import copy
import logging
import numbers
import tomllib

import numpy as np

from ..fem import MAX_REFINE
from ..solvers.options import ALIASES
from .schema import SCHEMA, F, SceneError

log = logging.getLogger(__name__)

__all__ = ["parse"]


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
    if k == "box":
        if not isinstance(v, list) or len(v) != 4 or not all(_finite(x) for x in v):
            fail("four finite numbers [x0, x1, y0, y1]")
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
    _check_picture(path, d["output"], d["material"]["plane"])
    if d["material"]["thickness"] is not None and d["material"]["thickness"] <= 0:
        raise SceneError(
            path, "material.thickness", f"must be > 0, got {d['material']['thickness']}"
        )
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
    if o["fe_order"] not in (1, 2, 3, 4):
        raise SceneError(path, "output.fe_order", f"must be 1 to 4, got {o['fe_order']}")
    if not 0 <= o["fe_refine"] <= MAX_REFINE:
        raise SceneError(
            path, "output.fe_refine", f"must be in [0, {MAX_REFINE}], got {o['fe_refine']}"
        )
    if o["scale"] is not None and o["scale"] <= 0:
        raise SceneError(path, "output.scale", f"must be > 0, got {o['scale']}")
    if d["fracture"] is not None:
        _check_fracture_outputs(path, d)
        for i, ld in enumerate(d["fracture"]["held"]):
            _check_load(path, f"fracture.held[{i}]", ld)


def _check_fracture_outputs(path, d: dict) -> None:
    """Keys a ``[fracture]`` run does not use are refused, not ignored."""
    o = d["output"]
    unused = {
        "output.fe_compare": o["fe_compare"],
        "output.probes": bool(o["probes"]),
        "output.part_stress": bool(o["part_stress"]),
        "output.checks": bool(o["checks"]),
    }
    for key, given in unused.items():
        if given:
            raise SceneError(
                path, key, "not used by a [fracture] run (fracture.checks holds its key numbers)"
            )
    solver = d["solver"]
    if solver.get("type", "auto") not in ("auto", "direct"):
        raise SceneError(
            path, "solver.type", "a [fracture] run solves directly (factorisation updates)"
        )


def _check_picture(path, o: dict, plane: str) -> None:
    if o["field"] == "szz" and plane == "stress":
        raise SceneError(
            path,
            "output.field",
            "szz is zero in plane stress: pick another field or material.plane = strain",
        )
    v = o["view"]
    if v is not None and not (v[0] < v[1] and v[2] < v[3]):
        raise SceneError(path, "output.view", f"needs x0 < x1 and y0 < y1, got {v}")


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
    "traction": ("where", "within", "value", "value_at"),
    "pressure": ("where", "within", "p", "p_at", "gamma", "level", "follower"),
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
    w = ld["within"]
    if w is not None and not (w[0] < w[1] and w[2] < w[3]):
        raise SceneError(path, f"{key}.within", f"needs x0 < x1 and y0 < y1, got {w}")
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
