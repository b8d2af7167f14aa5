"""Linear solve benchmark: time per stage and peak memory against mesh size.

For jittered meshes (jitter 0.3) of about 1e4, 1e5 and 1e6 nodes: mesh generation,
geometry, DV calibration and assembly, AMG set-up and CG solve (rtol 1e-8), a direct
solve (up to --direct-max nodes), and the P1 plane-stress elasticity assembly of the
same triangles by scikit-fem, timed in the same run as the yardstick. Every size runs
in a fresh process so that the peak resident memory is per size.

Usage::

    python validation/bench_linear.py              # 1e4, 1e5, 1e6 nodes
    python validation/bench_linear.py --quick      # 1e4, 3e4 nodes
    python validation/bench_linear.py --nodes 2e5  # chosen sizes

Writes ``validation/out/bench_linear.json`` and prints a table.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np
from _common import parser


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run_dv(n_nodes: float, direct_max: float, model_kind: str) -> dict:
    import dvstatic as dv
    from dvstatic import linalg
    from dvstatic.lattice import assembly, geometry
    from dvstatic.problem import constraints, load_vector

    h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
    rec: dict = {"target_nodes": n_nodes, "h": h, "model": model_kind}
    t0 = time.perf_counter()
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", jitter=0.3, seed=0)
    rec["mesh_s"] = time.perf_counter() - t0
    rec["nodes"] = mesh.n_points
    rec["triangles"] = mesh.n_triangles
    rec["dof"] = 2 * mesh.n_points
    t0 = time.perf_counter()
    geometry.of(mesh)
    rec["geometry_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = (dv.DV if model_kind == "DV" else dv.RV)(mesh, 1e5, 0.2)
    rec["calibration_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    assembly.pattern(mesh)
    rec["pattern_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    K = model.stiffness("bsr")
    rec["assembly_s"] = time.perf_counter() - t0
    rec["nnz"] = int(K.nnz)
    rec["geometry_plus_assembly_s"] = (
        rec["geometry_s"] + rec["calibration_s"] + rec["pattern_s"] + rec["assembly_s"]
    )
    dofs, vals = constraints(mesh, [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)])
    f = load_vector(mesh, [dv.Traction("right", (-1.0, 0.0))])
    system = linalg.ConstrainedSystem(K, dofs)
    b = system.rhs(f, vals)
    t0 = time.perf_counter()
    amg = linalg.AMGSolver(system.A, linalg.rigid_modes(mesh.points))
    rec["amg_setup_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    x, info = amg.solve(b, rtol=1e-8)
    rec["amg_solve_s"] = time.perf_counter() - t0
    rec["amg_iterations"] = info["iterations"]
    rec["amg_residual"] = info["residuals"][-1]
    rec["amg_levels"] = len(amg.ml.levels)
    rec["amg_operator_complexity"] = float(amg.ml.operator_complexity())
    exact = np.c_[-mesh.points[:, 0] / 1e5, 0.2 * mesh.points[:, 1] / 1e5]
    rec["l2_error"] = float(np.linalg.norm(x.reshape(-1, 2) - exact) / np.linalg.norm(exact))
    del amg
    if mesh.n_points <= direct_max:
        t0 = time.perf_counter()
        from dvstatic.mesh import mesh_dof_order

        lu = linalg.DirectSolver(system.A, order=mesh_dof_order(mesh))
        xd, _ = lu.solve(b)
        rec["direct_s"] = time.perf_counter() - t0
        rec["direct_vs_amg"] = float(np.linalg.norm(xd - x) / np.linalg.norm(xd))
        rec["direct_negative_pivots"] = lu.negative_pivots
        del lu
    rec["peak_mb"] = _peak_mb()
    return rec


def run_skfem(n_nodes: float) -> dict:
    import dvstatic as dv

    h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", jitter=0.3, seed=0)
    import skfem
    from skfem.models.elasticity import linear_elasticity

    E, nu = 1e5, 0.2
    lam, mu = E * nu / (1 - nu**2), E / (2 * (1 + nu))
    t0 = time.perf_counter()
    fm = skfem.MeshTri(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.triangles.T))
    t1 = time.perf_counter()
    basis = skfem.Basis(fm, skfem.ElementVector(skfem.ElementTriP1()))
    t2 = time.perf_counter()
    K = skfem.asm(linear_elasticity(lam, mu), basis)
    t3 = time.perf_counter()
    return {
        "skfem_mesh_s": t1 - t0,
        "skfem_basis_s": t2 - t1,
        "skfem_asm_s": t3 - t2,
        "skfem_assembly_s": t3 - t1,
        "skfem_nnz": int(K.nnz),
        "skfem_peak_mb": _peak_mb(),
    }


def _child(args: list[str]) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, *args], capture_output=True, text=True, check=False
    )
    if out.returncode != 0:
        raise RuntimeError(f"benchmark child failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--nodes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    p.add_argument("--direct-max", type=float, default=3e5, help="largest mesh for direct solve")
    p.add_argument("--model", choices=["DV", "RV"], default="DV")
    p.add_argument("--child", choices=["dv", "skfem"], help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.child == "dv":
        print(json.dumps(run_dv(a.nodes[0], a.direct_max, a.model)))
        return 0
    if a.child == "skfem":
        print(json.dumps(run_skfem(a.nodes[0])))
        return 0
    sizes = [1e4, 3e4] if a.quick else a.nodes
    rows = []
    for n in sizes:
        rec = _child(
            [
                "--child",
                "dv",
                "--nodes",
                str(n),
                "--direct-max",
                str(a.direct_max),
                "--model",
                a.model,
            ]
        )
        rec.update(_child(["--child", "skfem", "--nodes", str(n)]))
        rec["ratio_geometry_assembly_vs_skfem"] = (
            rec["geometry_plus_assembly_s"] / rec["skfem_assembly_s"]
        )
        rows.append(rec)
        _print_row(rec, header=len(rows) == 1)
    path = a.out / "bench_linear.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps({"benchmark": "bench_linear", "rows": rows}, indent=2))
    tmp.replace(path)
    print(f"wrote {path}")
    return 0


def _print_row(r: dict, header: bool) -> None:
    cols = [
        ("nodes", "{:>9d}", "nodes"),
        ("mesh", "{:>7.2f}", "mesh_s"),
        ("geom", "{:>6.2f}", "geometry_s"),
        ("calib", "{:>6.2f}", "calibration_s"),
        ("patt", "{:>6.2f}", "pattern_s"),
        ("asm", "{:>6.2f}", "assembly_s"),
        ("skfem", "{:>6.2f}", "skfem_assembly_s"),
        ("ratio", "{:>6.3f}", "ratio_geometry_assembly_vs_skfem"),
        ("amgset", "{:>7.2f}", "amg_setup_s"),
        ("amgsol", "{:>7.2f}", "amg_solve_s"),
        ("its", "{:>4d}", "amg_iterations"),
        ("direct", "{:>7}", "direct_s"),
        ("peakMB", "{:>7.0f}", "peak_mb"),
        ("L2err", "{:>9.2e}", "l2_error"),
    ]
    if header:
        print(
            " ".join(
                f"{c[0]:>{len(c[1].format(0) if 'd' in c[1] else c[1].format(0.0))}}" for c in cols
            )
        )
    vals = []
    for _, fmt, key in cols:
        v = r.get(key)
        if v is None:
            vals.append(f"{'-':>7}")
        elif key == "direct_s":
            vals.append(f"{v:>7.2f}")
        else:
            vals.append(fmt.format(v))
    print(" ".join(vals), flush=True)


if __name__ == "__main__":
    sys.exit(main())
