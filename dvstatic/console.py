"""What ``dvstatic run`` prints: the summary of a solve, a row per item (mesh, model,
solver, reactions, FE, probes, part stresses, checks, files)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["print_summary"]


#: said once under the checks: how every printed difference is signed
SIGN_CONVENTION = "in %: (value - reference) / |reference|; + means above the reference"


_SPRINGS = {
    "surface": "surface springs",
    "fabric": "fabric-corrected springs",
    "uniform": "the paper's uniform springs",
    "voronoi": "Voronoi-weighted springs",
}


def _model_line(md: dict) -> str:
    """One line on the model: material, plane, thickness, calibration and its cost."""
    txt = f"{md['type']} E = {md['E']:g}, nu = {md['nu']:g}, plane {md['plane']}"
    if md.get("thickness") is not None:
        txt += f", thickness {md['thickness']:g}"
    txt += f": k_n = {md['k_n']:.6g}, nu_m = {md['nu_m']:.6g} ({md['calibration']}"
    if md["calibration"] == "relaxed":
        txt += f" from the {md['calibration_source']}"
        if "defect_fraction" in md:  # a mesh without recipe
            txt += (
                f" {md['local_spread']:.3f} and defect fraction {md['defect_fraction']:.2f}"
                f", {md.get('cvt_family_weight', 0.0):.2f} CVT-like"
            )
        txt += f", {md['calibration_seconds']:.2f} s"
    txt += f"; {_SPRINGS.get(md['bonds'], md['bonds'] + ' springs')}"
    if md.get("exact_cells"):
        txt += f"; {md['exact_cells']} exact boundary cells"
    if md.get("anisotropy") == "regional":
        txt += "; regional isotropy"
    txt += ")"
    classes = md.get("calibration_classes")
    if classes:  # k_n, nu_m above: the largest class's
        sp = classes["spread"]
        txt += (
            f"; the mesh mixes micro-structures: calibrated in {len(sp)} classes of local "
            f"spread {min(sp):.3f} to {max(sp):.3f} (k_n, nu_m of the largest)"
        )
    for name, m in md.get("materials", {}).items():
        txt += f"; {name}: E = {m['E']:g}, nu = {m['nu']:g}"
    return txt


def _solver_line(s: dict) -> str:
    """The solver, its iterations (where it iterates), residual and time."""
    parts = [s["solver"]]
    if s.get("nonlinear"):
        parts.append(
            f"Newton: {s['iterations']} iterations in {s.get('steps', 0)} load steps"
            + (f" ({s['cutbacks']} cut-backs)" if s.get("cutbacks") else "")
        )
    elif s["solver"] != "direct":
        parts.append(f"{s['iterations']} iterations")
    parts.append(f"relative residual {s['residual']:.2e}")
    parts.append(f"{s['seconds'].get('total', float('nan')):.3f} s")
    return ", ".join(parts)


def _check_text(c: dict) -> str:
    """A key number against its reference (and the FE value, if any)."""

    def diff(v: float) -> str:
        return f"{v:+.2%}" if c["reference"] != 0 else f"{v:+.3g}"

    txt = (
        f"{c['quantity']} = {c['value']:.5g} against {c['reference']:.5g} "
        f"({diff(c['difference'])}{', ' + c['source'] if c.get('source') else ''})"
    )
    if "fe_value" in c:
        txt += f"; FE {c['fe_value']:.5g} ({diff(c['fe_difference'])})"
    return txt


def print_summary(sc, d: dict, written: list[Path]) -> None:
    """The summary of a run, a row per item, on stdout."""
    m, md, s = d["mesh"], d["model"], d["solver"]
    rows = [
        ("scene", f"{sc.path}" + (f"  ({sc.data['title']})" if sc.data["title"] else "")),
        *([("overrides", ", ".join(d["scene"]["overrides"]))] if d["scene"]["overrides"] else []),
        (
            "mesh",
            f"{m['nodes']} nodes ({'graded ' if m.get('graded') else ''}{m['kind']}), "
            f"{m['bonds']} bonds, sigma_L = {m['sigma_L']:.4f}",
        ),
        ("model", _model_line(md)),
        *[("calibration range", f["message"]) for f in md.get("calibration_flags", ())],
        ("solver", _solver_line(s)),
        ("max |u|", f"{d['max_displacement']:.6e}"),
    ]
    if not s["converged"]:
        state = (
            "the last converged load step"
            if s.get("equilibrium", True)
            else "the last iterate of a step that did not converge, not in equilibrium"
        )
        after = [r[0] for r in rows].index("solver") + 1
        rows.insert(after, ("NOT converged", f"load factor {s['load_factor']:.4g} of 1: {state}"))
    if "strain_energy" in d:
        rows.append(("energy", f"{d['strain_energy']:.6e}"))
    for key, r in d["reactions"].items():
        if key == "total":
            rows.append(("reaction total", f"(Rx, Ry) = ({r[0]:.6g}, {r[1]:.6g})"))
        else:  # the components the support prescribes
            rows.append((f"reaction {key}", ", ".join(f"R{c} = {v:.6g}" for c, v in r.items())))
    if "fe" in d:
        f = d["fe"]
        refined = {0: "", 1: ", refined once"}.get(f["refine"], f", refined {f['refine']} times")
        rows.append(
            (
                f"FE (P{f['order']}{refined})",
                f"{f['n_dof']} dof: relative L2 difference {f['rel_l2_difference']:.3%} "
                f"({f['rel_l2_difference_without_rigid_motion']:.3%} without the rigid "
                f"motion), max {f['rel_max_difference']:.3%}",
            )
        )
    if "probes" in d:
        pr = d["probes"]
        for i, p in enumerate(pr["points"]):
            u, st = pr["displacement"][i], pr["stress"][i]
            rows.append(
                (
                    f"probe ({p[0]:g}, {p[1]:g})",
                    f"(ux, uy) = ({u[0]:.6e}, {u[1]:.6e}), "
                    f"(sxx, syy, sxy) = ({st[0][0]:.4g}, {st[1][1]:.4g}, {st[0][1]:.4g})",
                )
            )
            if "fe_displacement" in pr:
                fu, fs = pr["fe_displacement"][i], pr["fe_stress"][i]
                rows.append(
                    (
                        "  FE",
                        f"(ux, uy) = ({fu[0]:.6e}, {fu[1]:.6e}), "
                        f"(sxx, syy, sxy) = ({fs[0][0]:.4g}, {fs[1][1]:.4g}, {fs[0][1]:.4g})",
                    )
                )
    for name, rec in d.get("part_stress", {}).items():
        lat, lv = rec["lattice"], rec["lattice_virial"]

        def at(key, lat=lat):
            return "({:.3g}, {:.3g})".format(*lat[f"{key}_at"])

        txt = (
            f"sxx {lat['min_sxx']:.4g} at {at('min_sxx')} to {lat['max_sxx']:.4g} at "
            f"{at('max_sxx')}, syy {lat['min_syy']:.4g} to {lat['max_syy']:.4g}, principal "
            f"{lat['min_min_principal']:.4g} to {lat['max_principal']:.4g}"
            f" (virial sxx to {lv['max_sxx']:.4g})"
        )
        if "fe" in rec:
            fe_ = rec["fe"]
            txt += (
                f"; FE sxx {fe_['min_sxx']:.4g} to {fe_['max_sxx']:.4g}, syy {fe_['min_syy']:.4g}"
                f" to {fe_['max_syy']:.4g}, principal {fe_['min_min_principal']:.4g} to "
                f"{fe_['max_principal']:.4g}"
            )
        rows.append((f"stress on {name}", txt))
    rows += [(f"check: {c['name']}", _check_text(c)) for c in d.get("checks", [])]
    if d.get("checks") or "fe" in d:
        rows.append(("differences", SIGN_CONVENTION))
    rows.append(("files", ", ".join(str(w) for w in written) or "none"))
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:>{width}}  {v}")
