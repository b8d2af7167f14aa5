"""Reports of a solution: nodal fields by name, the JSON-ready summary (mesh, model,
solver, reactions, probes, part stresses, FE comparison) and key numbers checked against
references. :mod:`dvstatic.io` writes them to files.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError
from .fem import compare
from .lattice.cells import CELL_RINGS
from .mesh import Mesh
from .mesh.locate import interpolate, snap_point

__all__ = [
    "FIELDS",
    "CHECK_QUANTITIES",
    "nodal_field",
    "summary",
    "check_values",
    "fracture_checks",
    "fracture_lines",
]


#: nodal fields for pictures
FIELDS = ("|u|", "ux", "uy", "sxx", "syy", "sxy", "szz", "von_mises")


def _szz(solution, s: np.ndarray) -> np.ndarray:
    from .stress import out_of_plane_stress

    return out_of_plane_stress(solution.model, s)


def nodal_field(solution, name: str, stress: str | None = None) -> np.ndarray:
    """A nodal scalar field of a solution by name (see :data:`FIELDS`); stress fields
    use the recovery ``stress`` (see ``Solution.stress``; None: its default)."""
    if name not in FIELDS:
        raise InputError(f"unknown field {name!r}; accepted: {', '.join(FIELDS)}", "field")
    u = solution.u
    if name == "|u|":
        return np.hypot(u[:, 0], u[:, 1])
    if name == "ux":
        return u[:, 0]
    if name == "uy":
        return u[:, 1]
    if name in ("sxx", "syy", "sxy", "szz", "von_mises"):
        s = solution.stress(stress)
        sxx, syy, sxy = s[:, 0, 0], s[:, 1, 1], 0.5 * (s[:, 0, 1] + s[:, 1, 0])
        szz = solution.out_of_plane_stress(stress)
        fields = {"sxx": sxx, "syy": syy, "sxy": sxy, "szz": szz}
        if name in fields:
            return fields[name]
        # von Mises of the 3-D state (szz = 0 in plane stress)
        return np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3 * sxy**2)
    raise InputError(f"unknown field {name!r}; accepted: {', '.join(FIELDS)}", "field")


def summary(
    solution, fe=None, probes=None, part_stress=(), stress: str | None = None, checks=()
) -> dict:
    """JSON-ready summary of a solution (and of an FE comparison, if given).

    Parameters
    ----------
    solution : Solution
    fe : FESolution, optional
        Reference on the same mesh; adds relative L2 and max differences.
    probes : array_like, shape (n, 2), optional
        Points where displacement and stress (lattice and FE) are reported; a point
        outside the mesh within half the local spacing of a node (on a curved boundary) is
        moved to that node.
    part_stress : sequence of str
        Boundary parts whose nodal stress extremes are reported (max/min of sxx,
        syy and of the largest principal stress over the part's nodes): the default
        recovery of :meth:`Solution.stress` (``lattice``), the virial stress
        (``lattice_virial``, high at surfaces) and, with ``fe``, the FE stress at the same
        nodes.
    stress : str, optional
        Stress recovery of the probes, the checks and ``lattice`` (see
        :meth:`Solution.stress`; None: its default).
    checks : sequence of dict
        Key numbers against references (see :func:`check_values`).
    """
    info = solution.info
    out = {
        "mesh": _mesh_summary(solution.model.mesh),
        "model": _model_summary(solution.model),
        "max_displacement": solution.max_displacement,
        "reactions": _reactions(solution),
        "solver": _solver_summary(info),
    }
    if not info.nonlinear:
        out["strain_energy"] = solution.energy()
    else:
        out["solver"]["steps"] = len(info.steps)
        out["solver"]["cutbacks"] = info.cutbacks
    method = stress
    stress = None
    if (probes is not None and len(probes)) or part_stress:
        stress = solution.stress(method)
    if probes is not None and len(probes):
        mesh = solution.model.mesh
        p = np.asarray(probes, dtype=float).reshape(-1, 2)
        p = np.concatenate([snap_point(mesh, q[None]) for q in p])
        out["probes"] = _probes(solution, stress, p, fe)
        out["probes"]["stress_recovery"] = method or "default"
    if part_stress:
        out["part_stress"] = _part_stress(solution, stress, part_stress, fe)
    if checks:
        out["checks"] = check_values(solution, checks, stress=method, fe=fe)
    if fe is not None:
        out["fe"] = _fe_summary(solution, fe)
    return out


def check_values(solution, checks, stress: str | None = None, fe=None) -> list[dict]:
    """Key numbers of a solution against reference values.

    Parameters
    ----------
    solution : Solution
    checks : sequence of dict
        Each with ``name``, ``at`` (point, length), ``quantity`` (``ux``, ``uy``,
        ``|u|``, ``sxx``, ``syy`` or ``sxy``) and ``reference``; optional ``source``
        and, for ``ux``/``uy``, ``relative_to`` (a point: the value at ``at`` minus the
        value there, which no rigid motion changes).
        A point outside the mesh but within half the local spacing of a node (a point on a
        curved boundary) takes that node's value.
    stress : str, optional
        Stress recovery (see :meth:`Solution.stress`).
    fe : FESolution, optional
        Adds the FE value at the same point.

    Returns
    -------
    list of dict
        The check with ``value``, ``difference`` (relative to ``|reference|``, or
        absolute where the reference is 0) and, with ``fe``, ``fe_value`` and
        ``fe_difference``.
    """
    mesh = solution.model.mesh
    out = []
    for c in checks:
        _check_check(c)
        points = [np.asarray(c["at"], dtype=float).reshape(1, 2)]
        if c.get("relative_to") is not None:
            points.append(np.asarray(c["relative_to"], dtype=float).reshape(1, 2))
        field = nodal_field(solution, c["quantity"], stress)
        values = [float(_value_at(mesh, field, p, c["name"])) for p in points]
        value = values[0] - (values[1] if len(values) > 1 else 0.0)
        rec = dict(c, at=points[0][0].tolist(), value=value)
        if len(points) > 1:
            rec["relative_to"] = points[1][0].tolist()
        rec["difference"] = _difference(value, c["reference"])
        if fe is not None:
            fv = [_fe_value(fe, c["quantity"], snap_point(mesh, p), mesh) for p in points]
            rec["fe_value"] = fv[0] - (fv[1] if len(fv) > 1 else 0.0)
            rec["fe_difference"] = _difference(rec["fe_value"], c["reference"])
        out.append(rec)
    return out


#: quantities a check can name
CHECK_QUANTITIES = ("ux", "uy", "|u|", "sxx", "syy", "sxy")


def _check_check(c) -> None:
    """Validate one check (a mapping with name, at, quantity, reference)."""
    if not isinstance(c, dict):
        raise TypeError(f"a check must be a dict, got {type(c).__name__}")
    missing = [k for k in ("name", "at", "quantity", "reference") if k not in c]
    if missing:
        raise InputError(f"check {c.get('name', c)!r}: missing {', '.join(missing)}", "checks")
    if c.get("relative_to") is not None and c["quantity"] not in ("ux", "uy"):
        raise InputError(
            f"check {c['name']!r}: relative_to applies to ux and uy only, not {c['quantity']!r}",
            "relative_to",
        )
    if c["quantity"] not in CHECK_QUANTITIES:
        raise InputError(
            f"check {c['name']!r}: unknown quantity {c['quantity']!r}; accepted: "
            + ", ".join(CHECK_QUANTITIES),
            "quantity",
        )
    ref = c["reference"]
    if isinstance(ref, bool) or not isinstance(ref, (int, float, np.number)):
        raise TypeError(f"check {c['name']!r}: reference must be a number, got {ref!r}")
    if not np.isfinite(ref):
        raise InputError(f"check {c['name']!r}: reference must be finite, got {ref}", "reference")


def _difference(value: float, reference: float) -> float:
    return (value - reference) / abs(reference) if reference != 0 else value - reference


def _value_at(mesh: Mesh, field: np.ndarray, point: np.ndarray, name: str) -> float:
    try:
        return float(interpolate(mesh, field, snap_point(mesh, point))[0])
    except InputError as exc:
        raise InputError(f"check {name!r}: {exc}", "at") from None


def _fe_value(fe, quantity: str, point: np.ndarray, mesh: Mesh) -> float:
    if quantity in ("ux", "uy", "|u|"):
        u = _fe_at(fe.evaluate, point, mesh)[0]
        return float({"ux": u[0], "uy": u[1], "|u|": np.hypot(*u)}[quantity])
    s = _fe_at(fe.stress, point, mesh)[0]
    return float({"sxx": s[0, 0], "syy": s[1, 1], "sxy": 0.5 * (s[0, 1] + s[1, 0])}[quantity])


def _fe_at(method, points: np.ndarray, mesh: Mesh) -> np.ndarray:
    """``method(points)`` of an FE solution; points on a curved boundary that lie
    outside the curved FE elements (between chord and arc) take the nearest node."""
    try:
        return method(points)
    except InputError:
        near = [int(np.argmin(np.hypot(*(mesh.points - p).T))) for p in points]
        return method(mesh.points[near])


def _mesh_summary(mesh: Mesh) -> dict:
    return {
        "nodes": mesh.n_points,
        "bonds": mesh.n_bonds,
        "triangles": mesh.n_triangles,
        "area": mesh.area,
        "mean_bond_length": mesh.h,
        "sigma_L": mesh.edge_length_spread(),
        "kind": mesh.sampling.kind if mesh.sampling is not None else "imported",
        "graded": bool(mesh.sampling is not None and mesh.sampling.graded),
        "parts": sorted(mesh.parts),
    }


def _model_summary(model) -> dict:
    details = model.micro.details or {}
    out = {
        "type": model.kind,
        "E": model.E,
        "nu": model.nu,
        "plane": model.plane,
        "thickness": model.thickness,
        "calibration": model.micro.calibration,
        "calibration_source": details.get("source", model.micro.calibration),
        "calibration_seconds": sum(
            float((m.details or {}).get("seconds", 0.0)) for m in model.micros
        ),
        "bonds": model.bonds,
        "boundary_cells": model.boundary_cells,
        "anisotropy": model.anisotropy,
        "exact_cells": int(len(model.cell_triangles)),
        "cell_rings": CELL_RINGS if len(model.cell_triangles) else None,
        "k_n": model.k_n,
        "nu_m": model.nu_m,
        "stabilised": model.micro.stabilised,
        "clipped_fraction": model.clipped_fraction,
    }
    for key in ("local_spread", "defect_fraction", "cvt_family_weight"):
        if key in details:  # a mesh without recipe: its descriptors
            out[key] = float(details[key])
    field = model.micro_field
    if field is not None:  # a mesh that mixes micro-structures, calibrated class by class
        c = field.classes
        out["calibration_seconds"] = sum(
            float((m.details or {}).get("seconds", 0.0)) for m in field.micros.values()
        )
        out["calibration_classes"] = {
            "spread": c.spread.tolist(),
            "triangles": np.bincount(c.of_triangle, minlength=c.n_classes).tolist(),
            "k_n": [field.micros[k].k_n for k in sorted(field.micros)],
            "nu_m": [field.micros[k].nu_m for k in sorted(field.micros)],
            "pairs": [list(k) for k in sorted(field.micros)],
        }
    if model.calibration_flags:  # parts outside what their calibration measured
        out["calibration_flags"] = [
            {**f.as_dict(), "message": f.message()} for f in model.calibration_flags
        ]
    if model.materials:
        out["materials"] = {
            name: {"E": m.E, "nu": m.nu, "k_n": micro.k_n, "nu_m": micro.nu_m}
            for (name, m), micro in zip(model.materials.items(), model.micros[1:], strict=True)
        }
    return out


def _solver_summary(info) -> dict:
    out = {
        "solver": info.solver,
        "nonlinear": info.nonlinear,
        "converged": info.converged,
        "iterations": info.iterations,
        "residual": info.residual,
        "seconds": info.seconds.as_dict(),
        "reused": list(info.reused),
        "n_dof": info.n_dof,
    }
    out["load_factor"] = info.load_factor
    if not info.converged:
        out["failure"] = info.failure
        out["equilibrium"] = info.equilibrium
    if info.steps:  # Newton: the history of every accepted load step
        out["newton_steps"] = [
            {
                "load_factor": st.load_factor,
                "iterations": st.iterations,
                "residuals": list(st.residuals),
                "tolerance": st.tolerance,
            }
            for st in info.steps
        ]
    if info.parallel is not None:
        out["parallel"] = info.parallel.as_dict()
    return out


def _reactions(solution) -> dict:
    """The total reaction, and per support the reaction of each component it
    prescribes (``{"x": ..., "y": ...}``); a node component prescribed by two supports
    counts for the first one only, so the supports' reactions add up to the total."""
    from .problem import support_components

    mesh = solution.model.mesh
    out: dict = {"total": solution.reactions.sum(axis=0).tolist()}
    taken = np.zeros((mesh.n_points, 2), dtype=bool)
    names: dict[int, str] = {}
    for i, s in enumerate(solution.supports):
        names[id(s)] = s.where if isinstance(s.where, str) else f"support{i}"
    for s in solution.supports:
        rec = out.setdefault(names[id(s)], {})
        for c in support_components(mesh, [s]):
            nodes = c.nodes[~taken[c.nodes, c.component]]
            taken[nodes, c.component] = True
            rec["xy"[c.component]] = rec.get("xy"[c.component], 0.0) + float(
                solution.reactions[nodes, c.component].sum()
            )
    return out


def _probes(solution, stress: np.ndarray, p: np.ndarray, fe) -> dict:
    mesh = solution.model.mesh
    out = {
        "points": p.tolist(),
        "displacement": interpolate(mesh, solution.u, p).tolist(),
        "stress": interpolate(mesh, stress.reshape(-1, 4), p).reshape(-1, 2, 2).tolist(),
    }
    if fe is not None:
        out["fe_displacement"] = _fe_at(fe.evaluate, p, mesh).tolist()
        out["fe_stress"] = _fe_at(fe.stress, p, mesh).tolist()
    return out


def _part_stress(solution, stress: np.ndarray, names, fe) -> dict:
    mesh = solution.model.mesh
    virial = solution.stress("virial")
    out = {}
    for name in names:
        nodes = mesh.part_nodes(name)
        rec = {
            "nodes": int(nodes.size),
            "lattice": _stress_extremes(stress[nodes], mesh.points[nodes]),
            "lattice_virial": _stress_extremes(virial[nodes]),
        }
        if fe is not None:
            rec["fe"] = _stress_extremes(fe.stress(mesh.points[nodes]))
        out[name] = rec
    return out


def _fe_summary(solution, fe) -> dict:
    c = compare(solution, fe)
    r = compare(solution, fe, rigid=True)
    return {
        "order": fe.order,
        "refine": fe.refine,
        "n_dof": fe.info.n_dof,
        "solver": fe.info.solver,
        "iterations": fe.info.iterations,
        "seconds": fe.info.seconds.as_dict(),
        "rel_l2_difference": c.l2,
        "rel_max_difference": c.max,
        # a body held at points floats on the lattice's fluctuations there: the rigid
        # motion that moves it is no strain, and is taken out here
        "rel_l2_difference_without_rigid_motion": r.l2,
        "rigid_motion": r.rigid,
        "max_displacement": fe.max_displacement,
    }


def _stress_extremes(s: np.ndarray, points: np.ndarray | None = None) -> dict:
    """Largest and smallest sxx, syy and principal stresses (and where, with
    ``points``)."""
    sxx, syy, sxy = s[:, 0, 0], s[:, 1, 1], 0.5 * (s[:, 0, 1] + s[:, 1, 0])
    r = np.sqrt(0.25 * (sxx - syy) ** 2 + sxy**2)
    p1, p2 = 0.5 * (sxx + syy) + r, 0.5 * (sxx + syy) - r
    out = {}
    for name, v in (("sxx", sxx), ("syy", syy), ("principal", p1), ("min_principal", p2)):
        for kind, k in (("max", int(np.argmax(v))), ("min", int(np.argmin(v)))):
            key = f"{kind}_{name}" if name != "min_principal" else f"{kind}_{name}"
            out[key] = float(v[k])
            if points is not None:
                out[f"{key}_at"] = points[k].tolist()
    return out


def fracture_checks(result, checks) -> list[dict]:
    """Key numbers of a fracture analysis (``result.quantity``) against references: each
    check (``name``, ``quantity``, ``reference``, ``source``) with ``value`` and
    ``difference`` (relative to ``|reference|``, absolute where it is 0)."""
    out = []
    for c in checks:
        value = result.quantity(c["quantity"])
        ref = c["reference"]
        if value is None:
            diff = None
        else:
            diff = (value - ref) / abs(ref) if ref else value - ref
        out.append({**c, "value": value, "difference": diff})
    return out


def fracture_lines(result, checks: list[dict], title: str, written=()) -> list[str]:
    """The printed summary of a fracture analysis, one string per line."""
    m, peak, t = result.model, result.peak, result.seconds
    lines = [
        f"{title}: fracture of {m.kind}, {m.mesh.n_points} nodes, {result.control} control",
        f"  events    {len(result.events)}, bonds broken {len(result.broken)}",
    ]
    if peak is not None:
        lines += [
            f"  peak      load {peak.load:.6g} at displacement {peak.control_displacement:.6g} "
            f"(load factor {peak.load_factor:.6g}, event {peak.index})",
            f"  energy    released {result.dissipated:.6g} (force x length)",
            f"  residual  largest relative residual {result.stats.max_residual:.1e}",
        ]
    lines.append(f"  stopped   {result.message}")
    for c in checks:
        src = f" ({c['source']})" if c.get("source") else ""
        if c["value"] is None:
            diff, value = "no events", "-"
        else:
            value = f"{c['value']:.6g}"
            rel = c["reference"] != 0
            diff = f"{100 * c['difference']:+.1f} %" if rel else f"{c['difference']:+.6g}"
        lines.append(
            f"  check: {c['name']}: lattice {value}, reference {c['reference']:.6g}{src}: {diff}"
        )
    if checks:
        lines.append("  differences in %: (value - reference) / |reference|")
    lines.append(
        f"  time      strengths {t.strength:.2f} s, events {t.events:.2f} s "
        f"({result.stats.events_per_second:.1f} events/s, "
        f"{result.stats.factorisations} factorisation"
        f"{'' if result.stats.factorisations == 1 else 's'})"
    )
    lines += [f"  wrote     {w}" for w in written]
    return lines
