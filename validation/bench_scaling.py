"""Scaling: time per stage and peak memory from 1e4 nodes to the largest mesh that fits.

For jittered meshes (jitter 0.3) of the unit square under uniaxial stress with DV:
mesh generation, geometry, calibration, assembly, AMG set-up, AMG-CG solve (rtol
1e-8), nodal stress recovery; peak resident memory per size (one process per size).
The growth of every stage with N is fitted as ``t ~ N^p`` (log-log least squares).

Usage::

    python validation/bench_scaling.py                 # 1e4 ... 4e6 nodes
    python validation/bench_scaling.py --quick         # 1e4, 3e4
    python validation/bench_scaling.py --nodes 1e4 1e5 1e6

Writes ``validation/out/bench_scaling.json`` and prints tables.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import time

import numpy as np
from _common import parser, write_json

STAGES = ("mesh", "geometry", "calibration", "assembly", "amg_setup", "amg_solve", "stress")


def run_one(n_nodes: float) -> dict:
    import dvstatic as dv
    from dvstatic import linalg
    from dvstatic.lattice import assembly, geometry
    from dvstatic.post import node_stress
    from dvstatic.problem import constraints, load_vector

    rec: dict = {"target_nodes": n_nodes}
    h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
    t = time.perf_counter()
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", jitter=0.3, seed=0)
    rec["mesh"] = time.perf_counter() - t
    rec["nodes"], rec["dof"] = mesh.n_points, 2 * mesh.n_points
    t = time.perf_counter()
    geometry.of(mesh)
    rec["geometry"] = time.perf_counter() - t
    t = time.perf_counter()
    model = dv.DV(mesh, 1e5, 0.2)
    rec["calibration"] = time.perf_counter() - t
    t = time.perf_counter()
    assembly.pattern(mesh)
    K = model.stiffness("bsr")
    rec["assembly"] = time.perf_counter() - t
    dofs, vals = constraints(mesh, [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)])
    f = load_vector(mesh, [dv.Traction("right", (-1.0, 0.0))])
    system = linalg.ConstrainedSystem(K, dofs)
    b = system.rhs(f, vals)
    t = time.perf_counter()
    amg = linalg.AMGSolver(system.A, linalg.rigid_modes(mesh.points))
    rec["amg_setup"] = time.perf_counter() - t
    t = time.perf_counter()
    x, info = amg.solve(b, rtol=1e-8)
    rec["amg_solve"] = time.perf_counter() - t
    rec["iterations"] = info["iterations"]
    del amg
    t = time.perf_counter()
    node_stress(model, x.reshape(-1, 2))
    rec["stress"] = time.perf_counter() - t
    rec["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return rec


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--nodes", type=float, nargs="+", default=[1e4, 3e4, 1e5, 3e5, 1e6, 2e6, 4e6])
    p.add_argument("--child", type=float, help=json.dumps("internal"))
    a = p.parse_args(argv)
    if a.child:
        print(json.dumps(run_one(a.child)))
        return 0
    sizes = [1e4, 3e4] if a.quick else a.nodes
    rows = []
    print(f"{'nodes':>9} " + " ".join(f"{s:>10}" for s in STAGES) + f" {'its':>4} {'peak MB':>8}")
    for n in sizes:
        out = subprocess.run(
            [sys.executable, __file__, "--child", str(n)],
            capture_output=True,
            text=True,
            check=False,
        )
        if out.returncode != 0:
            print(f"{n:9.0f} failed: {out.stderr.strip().splitlines()[-1]}")
            break
        rec = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(rec)
        print(
            f"{rec['nodes']:9d} "
            + " ".join(f"{rec[s]:10.3f}" for s in STAGES)
            + f" {rec['iterations']:4d} {rec['peak_mb']:8.0f}",
            flush=True,
        )
    growth = {}
    if len(rows) >= 3:
        n = np.log([r["nodes"] for r in rows])
        for s in (*STAGES, "peak_mb"):
            y = np.log([max(r[s], 1e-6) for r in rows])
            big = n >= np.log(3e4)  # small sizes are dominated by fixed overheads
            growth[s] = float(np.polyfit(n[big], y[big], 1)[0]) if big.sum() >= 2 else None
        print(
            "growth exponent p in t ~ N^p (sizes >= 3e4): "
            + ", ".join(f"{k} {v:.2f}" for k, v in growth.items() if v is not None)
        )
    write_json(
        {"benchmark": "bench_scaling", "rows": rows, "growth": growth}, a.out / "bench_scaling.json"
    )
    print(f"wrote {a.out / 'bench_scaling.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
