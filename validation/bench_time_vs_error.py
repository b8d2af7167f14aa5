"""Run time against error: implicit DV/RV (direct, AMG), the paper's explicit dynamic
relaxation, and scikit-fem P1/P2 on the same triangles.

Problems (lattice meshes, E = 1e5, nu = 0.2):

* ``uniaxial``: unit square, sigma_xx = -1 (paper exp. 3); error = relative L2 of the
  nodal displacement against the analytic solution;
* ``beam``: 4 x 1 clamped at both ends under its own weight (exp. 2); error = relative
  error of the mid-span deflection against P2 elements on a refined mesh.

Time = wall time from the mesh to the displacement (geometry, assembly, set-up,
solve), in one process per size. Dynamic relaxation runs once with check points every
200 steps; its time to "the same error" is the first check point whose error is within
1 % of the implicit (direct) solution's error, check-point time excluded.

Usage::

    python validation/bench_time_vs_error.py            # 1e3 ... 1e6 nodes
    python validation/bench_time_vs_error.py --quick    # 1e3, 1e4 nodes

Writes ``validation/out/bench_time_vs_error.{json,png}`` and prints tables.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from _common import BEAM_H, BEAM_L, E_BEAM, NU_BEAM, parser, write_json

#: method keys for --methods: implicit, explicit (matrix-vector per step), explicit
#: with bond forces from the current geometry per step (as the paper's codes), FE
METHODS = ("direct", "amg", "dr", "dr-bond", "fe")
LIMITS = {"direct": 3.2e5, "dynamic-relaxation": 1.2e5, "fe1": 3.2e5, "fe2": 1.2e5}


def problem(name: str, n_nodes: float):
    import dvstatic as dv

    if name == "uniaxial":
        h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
        mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="lattice")
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        ld = [dv.Traction("right", (-1.0, 0.0))]
    else:
        h = float(np.sqrt(2.0 * BEAM_L * BEAM_H / (np.sqrt(3) * n_nodes)))
        mesh = dv.mesh.rectangle(BEAM_L, BEAM_H, h, kind="lattice")
        sup = [dv.Fix("left"), dv.Fix("right")]
        ld = [dv.BodyForce((0.0, -1.0))]
    return mesh, sup, ld


def _fresh(mesh):
    """The same mesh without its caches (geometry, factorisations), with its recipe and
    domain: a copy without the recipe would be calibrated as an imported mesh, not as
    the generator's."""
    import dvstatic as dv

    return dv.Mesh(
        mesh.points,
        mesh.triangles,
        parts=dict(mesh.parts),
        domain=mesh.domain,
        regions=dict(mesh.regions),
        sampling=mesh.sampling,
    )


def error_fn(name: str, mesh, ref_w: float | None):
    from dvstatic.post import interpolate

    if name == "uniaxial":
        exact = np.c_[-mesh.points[:, 0] / E_BEAM, NU_BEAM * mesh.points[:, 1] / E_BEAM]
        return lambda u: float(np.linalg.norm(u - exact) / np.linalg.norm(exact))
    return lambda u: abs(
        float(interpolate(mesh, u, [[BEAM_L / 2, BEAM_H / 2]])[0, 1]) / ref_w - 1.0
    )


def run_size(
    name: str,
    n_nodes: float,
    ref_w: float | None,
    dr_time_limit: float,
    include_bond_forces: bool = True,
    methods=None,
    models=("DV", "RV"),
) -> list:
    """Every method on one problem size; ``methods`` (default all) is a subset of
    ``METHODS``, ``models`` of ("DV", "RV")."""
    import dvstatic as dv
    from dvstatic import fem
    from dvstatic.problem import constraints, load_vector
    from dvstatic.solvers.relaxation import dynamic_relaxation

    rows = []
    mesh, sup, ld = problem(name, n_nodes)
    err = error_fn(name, mesh, ref_w)
    nodes = mesh.n_points
    methods = METHODS if methods is None else tuple(methods)
    for kind, cls in (("DV", dv.DV), ("RV", dv.RV)):
        if kind not in models:
            continue
        impl_err = None
        for solver in ("direct", "amg"):
            if solver == "direct" and nodes > LIMITS["direct"]:
                continue
            if solver not in methods and impl_err is not None:
                continue
            mesh_copy = _fresh(mesh)
            t0 = time.perf_counter()
            sol = dv.solve(cls(mesh_copy, E_BEAM, NU_BEAM), sup, ld, solver=solver, rtol=1e-8)
            dt = time.perf_counter() - t0
            e = err(sol.u)
            impl_err = e if impl_err is None else impl_err
            rows.append(
                {
                    "problem": name,
                    "nodes": nodes,
                    "method": f"{kind} {solver}",
                    "seconds": dt,
                    "error": e,
                    "iterations": sol.info.iterations,
                }
            )
        for dr_kind in ("dynamic-relaxation", "dynamic-relaxation (bond forces)"):
            key = "dr-bond" if "bond" in dr_kind else "dr"
            if (
                nodes > LIMITS["dynamic-relaxation"]
                or (not include_bond_forces and "bond" in dr_kind)
                or key not in methods
            ):
                continue
            mesh_copy = _fresh(mesh)
            t0 = time.perf_counter()
            model = cls(mesh_copy, E_BEAM, NU_BEAM)
            _ = model.stiffness("bsr")  # assembly counts for the explicit scheme too
            dofs, vals = constraints(mesh_copy, sup)
            f = load_vector(mesh_copy, ld)
            t_setup = time.perf_counter() - t0
            trace = []

            def cb(step, u, trace=trace):
                trace.append((step, err(u.reshape(-1, 2))))

            try:
                _, dinfo = dynamic_relaxation(
                    model,
                    dofs,
                    vals,
                    f,
                    rtol=1e-7,
                    callback=cb,
                    callback_every=200,
                    time_limit=dr_time_limit,
                    nonlinear="bond" in dr_kind,
                )
                steps_total, dr_seconds = dinfo.iterations, dinfo.seconds
            except dv.SolverError as exc:
                steps_total = getattr(exc.info, "iterations", 0) if exc.info else 0
                dr_seconds = dr_time_limit
            per_step = dr_seconds / max(steps_total, 1)
            hit = next((s for s, e in trace if abs(e - impl_err) <= 0.01 * impl_err), None)
            rows.append(
                {
                    "problem": name,
                    "nodes": nodes,
                    "method": f"{kind} {dr_kind}",
                    "seconds": (t_setup + hit * per_step) if hit else None,
                    "error": next((e for s, e in trace if s == hit), None),
                    "iterations": hit,
                    "trace": trace,
                    "seconds_per_step": per_step,
                    "setup_seconds": t_setup,
                }
            )
    for order in (1, 2):
        if nodes > LIMITS[f"fe{order}"] or "fe" not in methods:
            continue
        t0 = time.perf_counter()
        fs = fem.solve(mesh, E_BEAM, NU_BEAM, sup, ld, order=order)
        dt = time.perf_counter() - t0
        e = (
            err(fs.u)
            if name == "uniaxial"
            else abs(float(fs.evaluate([[BEAM_L / 2, BEAM_H / 2]])[0, 1]) / ref_w - 1.0)
        )
        rows.append(
            {
                "problem": name,
                "nodes": nodes,
                "method": f"FE P{order}",
                "seconds": dt,
                "error": e,
                "dof": fs.info.n_dof,
            }
        )
    return rows


def plot(rows: list, path) -> None:
    from dvstatic import plot as dvplot

    fig, axes = dvplot.figure(2, 1, (13, 5))
    styles = {
        "direct": "o-",
        "amg": "s-",
        "dynamic-relaxation": "^--",
        "(bond forces)": "v--",
        "P1": "x:",
        "P2": "d:",
    }
    for ax, name in zip(axes[0], ("uniaxial", "beam"), strict=True):
        methods = sorted({r["method"] for r in rows if r["problem"] == name})
        for mth in methods:
            pts = sorted(
                (r["nodes"], r["seconds"], r["error"])
                for r in rows
                if r["problem"] == name
                and r["method"] == mth
                and r["seconds"] is not None
                and r["error"]
            )
            if not pts:
                continue
            _, t, e = np.array(pts).T
            style = next(v for k, v in styles.items() if mth.endswith(k))
            ax.loglog(t, e, style, label=mth, ms=5)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("relative error")
        ax.set_title(name)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Error against run time (points: growing meshes)")
    dvplot.save(fig, path)


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--nodes", type=float, nargs="+", default=[1e3, 1e4, 1e5, 1e6])
    p.add_argument("--dr-time-limit", type=float, default=1800.0)
    p.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    p.add_argument("--models", nargs="+", choices=("DV", "RV"), default=["DV", "RV"])
    p.add_argument("--name", default="bench_time_vs_error", help="output file stem")
    a = p.parse_args(argv)
    sizes = [1e3, 1e4] if a.quick else a.nodes
    from dvstatic import fem

    ref_mesh = problem("beam", 2e3)[0]
    _, sup, ld = problem("beam", 2e3)
    ref = fem.solve(ref_mesh, E_BEAM, NU_BEAM, sup, ld, order=2, refine=1 if a.quick else 3)
    ref_w = float(ref.evaluate([[BEAM_L / 2, BEAM_H / 2]])[0, 1])
    rows = []
    for name in ("uniaxial", "beam"):
        for n in sizes:
            new = run_size(name, n, ref_w, a.dr_time_limit, methods=a.methods, models=a.models)
            rows += new
            for r in new:
                t = f"{r['seconds']:9.3f}" if r["seconds"] is not None else f"{'>limit':>9}"
                e = f"{r['error']:10.3e}" if r["error"] is not None else f"{'-':>10}"
                print(f"{name:8} {r['nodes']:8d} {r['method']:34} {t} s  error {e}", flush=True)
    ratios = []
    for name in ("uniaxial", "beam"):
        for kind in a.models:
            for n in sorted({r["nodes"] for r in rows if r["problem"] == name}):
                sel = {r["method"]: r for r in rows if r["problem"] == name and r["nodes"] == n}
                impl = [sel[m]["seconds"] for m in (f"{kind} direct", f"{kind} amg") if m in sel]
                for variant in ("dynamic-relaxation", "dynamic-relaxation (bond forces)"):
                    dr = sel.get(f"{kind} {variant}")
                    if not dr or dr["seconds"] is None or not impl:
                        continue
                    ratios.append(
                        {
                            "problem": name,
                            "model": kind,
                            "variant": variant,
                            "nodes": n,
                            "dr_seconds": dr["seconds"],
                            "implicit_seconds": min(impl),
                            "ratio": dr["seconds"] / min(impl),
                        }
                    )
    print("\ndynamic relaxation time / best implicit time, same error:")
    for r in ratios:
        print(
            f"{r['problem']:8} {r['model']} {r['variant']:34} {r['nodes']:8d}: "
            f"{r['dr_seconds']:8.2f} s / {r['implicit_seconds']:6.3f} s = {r['ratio']:6.1f}x"
        )
    data = {
        "benchmark": "bench_time_vs_error",
        "beam_reference_w": ref_w,
        "rows": rows,
        "ratios": ratios,
    }
    write_json(data, a.out / f"{a.name}.json")
    plot(rows, a.out / f"{a.name}.png")
    print(f"wrote {a.out / a.name}.json and .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
