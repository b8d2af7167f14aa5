"""Scene-file schema: every key with its kind, default, choices and meaning
(:data:`SCHEMA`) and the generated reference (``docs/scenes.md``); the validation is in
:mod:`dvstatic.scene.parse`. The ``[solver]`` table is derived from
:class:`~dvstatic.solvers.SolveOptions`."""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass

from ..crack.options import FractureOptions
from ..errors import InputError
from ..lattice.cells import CELL_RINGS
from ..mesh.generators import DEFAULT_JITTER
from ..report import CHECK_QUANTITIES
from ..solvers.options import SolveOptions

log = logging.getLogger(__name__)

__all__ = ["SceneError", "F", "SCHEMA", "SOLVER_KEYS", "FRACTURE_KEYS", "reference_markdown"]


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

#: key numbers of a fracture analysis that ``[[fracture.checks]]`` can compare
FRACTURE_QUANTITIES = ("peak_load", "peak_displacement", "released_energy", "first_load")

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
                "interior points: auto is jittered, and cvt for a graded mesh (refine_near), "
                "which can be cvt or random only",
                default="auto",
                choices=("auto", "lattice", "jittered", "random", "cvt"),
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
                "number",
                "graded mesh: distance over which the spacing grows to h (length); keep "
                "(h - h_near) / grading <= 0.1 (warned): a steeper grading biases the "
                "stresses near the fine region by several percent",
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
                "normal-spring stiffness: auto (fabric on the generators' graded meshes and "
                "cvt / random point sets, surface otherwise), surface (k_n, half on "
                "boundary bonds: no stiff surface layer), fabric (surface springs with "
                "the local anisotropy of the cells taken out), uniform (the paper's k_n) "
                "or voronoi (k_n sqrt(3) r/l). The paper's model: calibration = paper, "
                "bonds = uniform, boundary_cells = lattice, anisotropy = keep",
                default="auto",
                choices=("auto", "surface", "fabric", "uniform", "voronoi"),
            ),
            "boundary_cells": F(
                "string",
                f"exact (the triangles with a vertex within {CELL_RINGS} rings of bonds of the "
                "boundary carry the material's isotropic tensor through a coupling of "
                "their three bonds: exactly P1 where the cells are cut to fit the "
                "boundary and where a mesher's rows meet its interior) or lattice (the plain "
                "lattice everywhere). The paper's model: calibration = paper, bonds = "
                "uniform, boundary_cells = lattice",
                default="exact",
                choices=("exact", "lattice"),
            ),
            "anisotropy": F(
                "string",
                "regional (every lattice triangle takes out the anisotropy of its "
                "region's mean tensor, which a mesher's graded cells leave), keep (the "
                "lattice's tensors as they are) or auto (regional on imported meshes and the "
                "generators' graded cvt meshes, keep on the others). The paper's model: "
                "anisotropy = keep",
                default="auto",
                choices=("auto", "regional", "keep"),
            ),
            "method": F(
                "string",
                "a preset of the four keys above: paper (the paper's model exactly: "
                "calibration = paper, bonds = uniform, boundary_cells = lattice, "
                "anisotropy = keep; a key given otherwise is refused). Unset: the keys "
                "as given",
                choices=("paper",),
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
            "within": F(
                "box",
                "traction, pressure: only the part's edges with both ends in [x0, x1, y0, y1] "
                "(length): a loading strip or platen (its width is that of the edges taken, "
                "so it moves with h; the reported loads are the actual forces)",
            ),
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
    "fracture": F(
        "table",
        "fracture by bond breaking (dv.fracture) instead of one elastic solve: the loads and "
        "prescribed displacements are scaled event by event; writes <name>_fracture.json, "
        "<name>_curve.png (load against displacement), <name>_crack.png (the broken bonds) "
        "and the VTU series <name>_fracture/<name>.pvd ([solver] and "
        "output.fe_compare, field, stress, probes, part_stress and checks do not apply)",
        default=None,
        schema={
            "ft": F("number", "tensile strength (stress units)", required=True),
            "cohesion": F("number", "criterion mohr-coulomb: the cohesion c (stress units, > 0)"),
            "friction_angle": F(
                "number", "criterion mohr-coulomb: the friction angle phi (degrees, [0, 70))"
            ),
            "gf": F(
                "number",
                "fracture energy (energy per crack area): saw-tooth softening of cracked bonds; "
                "omit for brittle bonds",
            ),
            "gf_shear": F(
                "number",
                "criterion mohr-coulomb: fracture energy of faces failing in shear or "
                "crushing (>= 0; 0: they break at once; default 10 gf, brittle without gf)",
            ),
            "weibull_m": F(
                "number", "Weibull modulus of a random strength field (omit: uniform strength)"
            ),
            "weibull_length": F(
                "number",
                "correlation length of the field (length; 0: independent bonds)",
                default=0.0,
            ),
            "seed": F("int", "seed of the random field", default=0),
            "checks": F(
                "tables",
                "key numbers of the analysis printed (and written to the JSON) against a "
                "reference value",
                default=[],
                schema={
                    "name": F("string", "what is checked (a label)", required=True),
                    "quantity": F(
                        "string",
                        "peak_load, peak_displacement (at the peak), released_energy (all "
                        "events) or first_load (the first event's load)",
                        required=True,
                        choices=FRACTURE_QUANTITIES,
                    ),
                    "reference": F("number", "the value to compare with", required=True),
                    "source": F("string", "where the reference comes from", default=""),
                },
            ),
            "regions": F(
                "tables",
                "other strengths on mesh regions (a bond between regions takes the smaller)",
                default=[],
                schema={
                    "name": F("string", "region name", required=True),
                    "ft": F("number", "tensile strength there", required=True),
                    "gf": F("number", "fracture energy there (default: the table's gf)"),
                },
            ),
        },
    ),
    "output": F(
        "table",
        "what to write",
        default={},
        schema={
            "vtu": F(
                "bool",
                "<name>.vtu (triangles: displacement, stress tensors, von Mises, area, "
                "material; with fe_compare the FE fields and the differences) and "
                "<name>_bonds.vtu (bonds: tension, length)",
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
                "holds recovered and virial): recovered (a continuum field over 4 local "
                "spacings, exact for uniform stress at every node: docs/theory.md 8.6), "
                "virial (the lattice's bond forces over each Voronoi cell) or strain "
                "(area-averaged lattice strain); nonlinear solves use virial",
                default="recovered",
                choices=("recovered", "virial", "strain"),
            ),
            "scale": F("number", "displacement magnification of the picture (default: auto)"),
            "view": F(
                "box",
                "region of the picture [x0, x1, y0, y1] (length; its colour range is taken "
                "there); default: the whole body, or a hole (else a loaded part) framed when "
                "it is a small part of the body and the peaks of `field` and of the von Mises "
                "stress lie in the frame",
            ),
            "name": F("string", "file name stem (default: the scene file's stem)"),
            "fe_compare": F(
                "bool", "solve the FE reference on the same triangles and compare", default=False
            ),
            "fe_order": F(
                "int",
                "FE element order, 1 to 4 (2 and up: quadratic geometry on curved boundaries)",
                default=2,
            ),
            "fe_refine": F(
                "int",
                "uniform refinements of the FE reference (0: elements of order fe_order on the "
                "lattice's own triangles)",
                default=0,
            ),
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
                    "relative_to": F(
                        "point",
                        "ux or uy only: the value at `at` minus the value here (length), a "
                        "closure or a stretch that no rigid motion changes",
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


def _fracture_schema() -> dict[str, F]:
    """The ``[fracture]`` table: the strengths and checks, and the options derived from
    :class:`~dvstatic.crack.FractureOptions`."""
    out = dict(SCHEMA["fracture"].schema)
    out["held"] = F(
        "tables",
        "loads held at full value in every state (self-weight, in-situ stress, confinement), "
        "the same tables as [[loads]]; only [[loads]] and the prescribed displacements grow",
        default=[],
        schema=SCHEMA["loads"].schema,
    )
    for f in dataclasses.fields(FractureOptions):
        meta = f.metadata
        if meta["scene"]:
            out[f.name] = F(meta["kind"], meta["doc"], default=f.default, choices=meta["choices"])
    return out


#: the keys of ``[fracture]`` that are options of :class:`~dvstatic.crack.FractureOptions`
FRACTURE_KEYS = tuple(f.name for f in dataclasses.fields(FractureOptions) if f.metadata["scene"])
SCHEMA["fracture"] = dataclasses.replace(SCHEMA["fracture"], schema=_fracture_schema())


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
