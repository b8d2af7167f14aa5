"""Convergence under mesh refinement: error against the number of nodes.

Problems (``_benchmarks.py``): uniaxial stress (paper exp. 3) and Timoshenko's
cantilever at nu in {-0.3, 0, 0.2, 0.33, 0.45}, the clamped beam under its own weight
(paper exp. 2), the thick-walled (Lame) cylinder under internal pressure in plane
strain, Kirsch's plate with a hole, and Cook's membrane. Meshes: the default mesh kind
at about 1e3, 4e3, 1.6e4 and 6.4e4 nodes (three halvings of h). Configurations: the
defaults of DV and RV (no keywords), the paper's model (``calibration="paper",
bonds="uniform", boundary_cells="lattice", anisotropy="keep"``), and P1 and P2 finite
elements on the same nodes. Imported meshes (gmsh, uniform and graded, at two
refinements each: the plate with a hole, the Lame cylinder, Cook's membrane) converge
in ``validation/imported.py``: gmsh is not a dependency of dvstatic, so they have a
script of their own.

Measured: the relative L2 error of the nodal displacements (against the exact field,
or a fine P2 FE solution), the key values (a displacement, or a stress at a boundary
point from each method's default stress recovery), the calibration and solve times.

Usage::

    python validation/convergence.py            # full size (about 20 min on 2 cores)
    python validation/convergence.py --quick    # two small meshes per problem
    python validation/convergence.py --markdown # the docs' tables from the JSON

Writes ``validation/out/convergence.json`` and ``convergence.png`` (``--quick``:
``convergence_quick.*``) and prints the tables.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from _benchmarks import beam, cantilever, cook, kirsch, lame, uniaxial
from _common import PAPER, parser, rel_l2, write_json

NODES = (1_000, 4_000, 16_000, 64_000)
QUICK_NODES = (300, 1_200)
NUS = (-0.3, 0.0, 0.2, 0.33, 0.45)
LATTICES = {
    "DV": ("DV", {}),
    "RV": ("RV", {}),
    "DV paper": ("DV", PAPER),
    "RV paper": ("RV", PAPER),
}
FE = {"P1": 1, "P2": 2}


def problems(quick: bool) -> list:
    nus = (0.2,) if quick else NUS
    out = [uniaxial(nu) for nu in nus] + [cantilever(nu) for nu in nus]
    out += [beam(), lame(0.3), kirsch(0.3), cook()]
    if not quick:
        out.insert(len(out) - 3, lame(0.45))
    return out


def _node_at(mesh, xy) -> int:
    d = np.hypot(*(mesh.points - np.asarray(xy)).T)
    i = int(np.argmin(d))
    if d[i] > 1e-9 * mesh.h:
        raise RuntimeError(f"no node at {xy} (nearest {d[i]:.3g} away)")
    return i


def _key_values(bm, mesh, u, stress_at) -> dict:
    out = {}
    for k in bm.keys:
        i = _node_at(mesh, k.where)
        if k.what == "uy":
            v = float(u[i, 1])
        else:
            s = stress_at(i, k.where)
            v = float(s[0, 0] if k.what == "sxx" else s[1, 1])
        out[k.name] = {"value": v, "error": v / k.reference - 1.0}
    return out


def _boundary_stress_error(bm, mesh, stress) -> float | None:
    """Relative L2 error of the tangential stress over the nodes of ``bm.stress_part``
    (corners included), against the exact stress."""
    if bm.stress_part is None:
        return None
    e = mesh.part_edges(bm.stress_part)
    nodes = np.unique(e)
    d = np.zeros((mesh.n_points, 2))
    for a, b in e:  # tangent at a node: the mean direction of its edges on the part
        v = mesh.points[b] - mesh.points[a]
        d[a] += v / np.hypot(*v)
        d[b] += v / np.hypot(*v)
    t = d[nodes] / np.hypot(*d[nodes].T)[:, None]
    got = np.einsum("mi,mij,mj->m", t, stress[nodes], t)
    ref = np.einsum("mi,mij,mj->m", t, bm.stress_exact(mesh.points[nodes]), t)
    return float(np.linalg.norm(got - ref) / np.linalg.norm(ref))


def _lattice(bm, mesh, sup, loads, cls_name, kw) -> dict:
    import dvstatic as dv

    cls = dv.DV if cls_name == "DV" else dv.RV
    t0 = time.perf_counter()
    try:
        model = cls(mesh, bm.E, bm.nu, plane=bm.plane, **kw)
        t_model = time.perf_counter() - t0
        sol = dv.solve(model, sup, loads)
    except (dv.SolverError, dv.CalibrationError) as exc:
        return {"failed": f"{type(exc).__name__}: {str(exc)[:160]}"}
    stress = sol.stress()
    rec = {
        "boundary_stress_error": _boundary_stress_error(bm, mesh, stress),
        "u": sol.u,
        "calibration_seconds": float((model.micro.details or {}).get("seconds", 0.0)),
        "calibration_source": (model.micro.details or {}).get("source", model.micro.calibration),
        "model_seconds": t_model,
        "solve_seconds": float(sol.info.seconds.total),
        "clipped": model.clipped_fraction,
        "nu_m": model.nu_m,
    }
    rec["keys"] = _key_values(bm, mesh, sol.u, lambda i, xy: stress[i])
    return rec


def _fe(bm, mesh, sup, loads, order) -> dict:
    import dvstatic as dv

    fe = dv.fem.solve(mesh, bm.E, bm.nu, sup, loads, order=order, plane=bm.plane)
    rec = {"u": fe.u, "solve_seconds": fe.info.seconds.total}
    if bm.stress_part is not None:
        nodes = mesh.part_nodes(bm.stress_part)
        full = np.zeros((mesh.n_points, 2, 2))
        full[nodes] = fe.stress(mesh.points[nodes])
        rec["boundary_stress_error"] = _boundary_stress_error(bm, mesh, full)
    rec["keys"] = _key_values(bm, mesh, fe.u, lambda i, xy: fe.stress(np.array([xy]))[0])
    return rec


def run_problem(bm, nodes) -> dict:
    ref_fe = bm.fe_reference() if bm.exact is None else None
    levels = []
    for n in nodes:
        mesh = bm.make_mesh(bm.h_for(n))
        sup, loads = bm.problem(mesh)
        ref = bm.exact(mesh.points) if ref_fe is None else ref_fe.evaluate(mesh.points)
        level = {"nodes": mesh.n_points, "h": bm.h_for(n), "results": {}}
        runs = [(name, _lattice, (c, kw)) for name, (c, kw) in LATTICES.items()]
        runs += [(name, _fe, (order,)) for name, order in FE.items()]
        for name, fn, args in runs:
            rec = fn(bm, mesh, sup, loads, *args)
            if "u" in rec:
                rec["error"] = rel_l2(rec.pop("u"), ref)
            level["results"][name] = rec
        levels.append(level)
        _print_level(bm, level)
    return {
        "problem": bm.name,
        "E": bm.E,
        "nu": bm.nu,
        "plane": bm.plane,
        "reference": "exact" if bm.exact is not None else "fine P2 FE",
        "keys": [{"name": k.name, "reference": k.reference, "source": k.source} for k in bm.keys],
        "levels": levels,
        "decreasing": _decreasing(levels),
    }


def _decreasing(levels) -> dict:
    out = {}
    for name in levels[0]["results"]:
        errs = [lv["results"][name].get("error") for lv in levels]
        # errors at round-off (the exact solution is in the FE space) count as converged
        errs = [None if e is None else max(e, 1e-9) for e in errs]
        out[name] = None if None in errs else bool(np.all(np.diff(errs) <= 0))
    return out


def _print_level(bm, level) -> None:
    cells = []
    for name, r in level["results"].items():
        if "failed" in r:
            cells.append(f"{name} --")
            continue
        s = f"{name} {100 * r['error']:.3g}%"
        if r.get("boundary_stress_error") is not None:
            s += f" [bnd stress {100 * r['boundary_stress_error']:.2g}%]"
        for k, v in r.get("keys", {}).items():
            s += f" [{k.split()[0]} {100 * v['error']:+.2g}%]"
        cells.append(s)
    print(f"{bm.name:42s} N {level['nodes']:6d}: " + " | ".join(cells), flush=True)


def plot(data: dict, path) -> None:
    from dvstatic import plot as dvplot

    probs = data["problems"]
    ncol = 4
    nrow = int(np.ceil(len(probs) / ncol))
    fig, axes = dvplot.figure(ncol, nrow, (4 * ncol, 3.2 * nrow))
    styles = {
        "DV": "o-",
        "RV": "s-",
        "DV paper": "o:",
        "RV paper": "s:",
        "P1": "k^--",
        "P2": "kv-.",
    }
    from matplotlib.ticker import NullFormatter

    for ax, pr in zip(axes.ravel(), probs, strict=False):
        exact = []
        for name, st in styles.items():
            pts = [(lv["nodes"], lv["results"][name].get("error")) for lv in pr["levels"]]
            # errors at round-off (the exact solution is in the FE space) are not drawn
            if all(e is not None and e < 1e-9 for _, e in pts):
                exact.append(name)
                continue
            pts = [(n, 100 * e) for n, e in pts if e is not None]
            if pts:
                ax.loglog(*zip(*pts, strict=True), st, label=name, mfc="none", ms=4)
        if exact:
            ax.text(
                0.03,
                0.04,
                f"{', '.join(exact)}: exact (round-off)",
                transform=ax.transAxes,
                fontsize=7,
            )
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_title(pr["problem"], fontsize=9)
        ax.set_xlabel("nodes")
        ax.set_ylabel("rel. L2 error of u [%]")
        ax.grid(alpha=0.3, which="both")
    for ax in axes.ravel()[len(probs) :]:
        ax.set_visible(False)
    fullest = max(axes.ravel()[: len(probs)], key=lambda a: len(a.get_lines()))
    fullest.legend(fontsize=7)
    fig.suptitle(
        "Error against nodes: defaults (DV, RV), the paper's model, P1/P2 FE on the same nodes"
    )
    dvplot.save(fig, path)


def _cell(r: dict | None) -> str:
    if r is None or "failed" in r or r.get("error") is None:
        return "failed"
    e = 100 * r["error"]
    return "exact" if e < 1e-6 else f"{e:.3g}"


def _per_level(p: dict, value, names) -> str:
    parts = []
    for lv in p["levels"]:
        res = lv["results"]
        cells = [f"{n} {value(res[n])}" for n in names if n in res and "failed" not in res[n]]
        parts.append(f"{lv['nodes']:,}: " + ", ".join(cells))
    return "; ".join(parts)


def markdown(data: dict) -> str:
    """The per-problem tables of docs/validation.md (the ``<details>`` block) from the
    JSON: L2 errors in %, key values, boundary stress, monotonicity."""
    out = []
    for p in data["problems"]:
        names = list(p["levels"][0]["results"])
        out.append(
            f"**{p['problem']}** (reference: {p['reference']}); relative L2 error of u in %\n"
        )
        out.append("| nodes | " + " | ".join(names) + " |")
        out.append("|---" * (len(names) + 1) + "|")
        for lv in p["levels"]:
            row = [_cell(lv["results"].get(n)) for n in names]
            out.append(f"| {lv['nodes']:,} | " + " | ".join(row) + " |")
        shown = [n for n in names if "paper" not in n]
        for k in p["keys"]:
            err = _per_level(p, lambda r, k=k: f"{100 * r['keys'][k['name']]['error']:+.2f}", shown)
            ref = f"{k['reference']:.5g}"
            out.append(f"\n{k['name']} (reference {ref}, {k['source']}), error in %: {err}")
        if any(lv["results"]["DV"].get("boundary_stress_error") is not None for lv in p["levels"]):
            err = _per_level(p, lambda r: f"{100 * r['boundary_stress_error']:.2g}", shown)
            out.append(f"\nboundary stress (tangential, L2 along the boundary) error in %: {err}")
        dec = {True: "yes", False: "no", None: "-"}
        flags = ", ".join(f"{n} {dec[v]}" for n, v in p["decreasing"].items())
        out.append(f"\ndecreasing under every refinement: {flags}\n")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    pa = parser(__doc__)
    pa.add_argument(
        "--markdown",
        action="store_true",
        help="print the docs' per-problem tables from the existing JSON (no run)",
    )
    a = pa.parse_args(argv)
    if a.markdown:
        stem = "convergence_quick" if a.quick else "convergence"
        print(markdown(json.loads((a.out / f"{stem}.json").read_text())))
        return 0
    nodes = QUICK_NODES if a.quick else NODES
    t0 = time.perf_counter()
    data = {"nodes_target": nodes, "problems": []}
    for bm in problems(a.quick):
        data["problems"].append(run_problem(bm, nodes))
    data["seconds"] = time.perf_counter() - t0
    stem = "convergence_quick" if a.quick else "convergence"
    write_json(data, a.out / f"{stem}.json")
    plot(data, a.out / f"{stem}.png")
    print(f"\nwrote {a.out / stem}.json/.png in {data['seconds']:.0f} s")
    bad = [
        (p["problem"], k)
        for p in data["problems"]
        for k, v in p["decreasing"].items()
        if v is False
    ]
    print("error not decreasing at every refinement:", bad or "none")
    return 0


if __name__ == "__main__":
    sys.exit(main())
