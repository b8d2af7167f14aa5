"""AMG cost in units of one matrix-vector product with the same K.

The DV stiffness of a jittered unit square under uniaxial stress, constrained as in
``dv.solve``, solved by CG to rtol 1e-8 with pyamg smoothed aggregation (rigid-body
modes as near-null space), starting from pyamg's defaults and adding dvstatic's
settings (``dvstatic.linalg.AMG_OPTIONS``) one knob at a time. Set-up and solve are
reported separately (best of two runs), in seconds and in matvec units.

Usage::

    python validation/bench_amg.py               # 3.7e5 and 1e6 nodes
    python validation/bench_amg.py --quick       # 2e4 nodes
    python validation/bench_amg.py --nodes 2e6

Writes ``validation/out/bench_amg.json`` and prints a table.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from _common import parser, write_json

BASE = dict(
    strength=("symmetric", {"theta": 0.05}),
    improve_candidates=None,
    max_coarse=500,
    coarse_solver="splu",
)
GS = dict(
    presmoother=("block_gauss_seidel", {"sweep": "forward"}),
    postsmoother=("block_gauss_seidel", {"sweep": "backward"}),
)
CONFIGS = [
    ("pyamg defaults", {}),
    ("+ strength theta 0.05", dict(strength=("symmetric", {"theta": 0.05}))),
    ("+ no candidate improvement, LU coarse", BASE),
    ("+ forward/backward GS sweeps", {**BASE, **GS}),
    (
        "+ block weighting (dvstatic)",
        {**BASE, **GS, "smooth": ("jacobi", {"omega": 4 / 3, "weighting": "block"})},
    ),
]


def measure(n_nodes: float, repeats: int = 2) -> list:
    import pyamg

    import dvstatic as dv
    from dvstatic import linalg
    from dvstatic.problem import constraints, load_vector

    h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", seed=0)
    model = dv.DV(mesh, 1e5, 0.2)
    dofs, vals = constraints(mesh, [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)])
    f = load_vector(mesh, [dv.Traction("right", (-1.0, 0.0))])
    system = linalg.ConstrainedSystem(model.stiffness("bsr"), dofs)
    A, b = system.A, system.rhs(f, vals)
    B = linalg.rigid_modes(mesh.points)
    x = np.random.default_rng(0).random(A.shape[0])
    reps = max(10, int(2e7 / A.nnz))
    t = time.perf_counter()
    for _ in range(reps):
        A @ x
    mv = (time.perf_counter() - t) / reps
    rows = []
    for name, cfg in CONFIGS:
        opts = {"symmetry": "hermitian", **cfg}
        ts = tsol = np.inf
        for _ in range(repeats):
            t = time.perf_counter()
            ml = pyamg.smoothed_aggregation_solver(A, B=B, **opts)
            ts = min(ts, time.perf_counter() - t)
            res: list = []
            t = time.perf_counter()
            xx = ml.solve(b, tol=1e-8, accel="cg", residuals=res, maxiter=500)
            tsol = min(tsol, time.perf_counter() - t)
        true = float(np.linalg.norm(A @ xx - b) / np.linalg.norm(b))
        rows.append(
            {
                "nodes": mesh.n_points,
                "dof": A.shape[0],
                "config": name,
                "matvec_seconds": mv,
                "setup_seconds": ts,
                "solve_seconds": tsol,
                "setup_matvecs": ts / mv,
                "solve_matvecs": tsol / mv,
                "total_matvecs": (ts + tsol) / mv,
                "iterations": len(res) - 1,
                "operator_complexity": float(ml.operator_complexity()),
                "true_residual": true,
            }
        )
    d = rows[0]["total_matvecs"]
    for r in rows:
        r["fraction_of_defaults"] = r["total_matvecs"] / d
    return rows


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--nodes", type=float, nargs="+", default=[3.7e5, 1e6])
    a = p.parse_args(argv)
    sizes = [2e4] if a.quick else a.nodes
    rows = []
    print(
        f"{'nodes':>8} {'config':38} {'its':>4} {'setup mv':>9} {'solve mv':>9} "
        f"{'total mv':>9} {'x defaults':>10} {'setup s':>8} {'solve s':>8}"
    )
    for n in sizes:
        for r in measure(n, repeats=1 if a.quick else 2):
            rows.append(r)
            print(
                f"{r['nodes']:8d} {r['config']:38} {r['iterations']:4d} "
                f"{r['setup_matvecs']:9.0f} {r['solve_matvecs']:9.0f} {r['total_matvecs']:9.0f} "
                f"{r['fraction_of_defaults']:10.2f} {r['setup_seconds']:8.2f} "
                f"{r['solve_seconds']:8.2f}",
                flush=True,
            )
    write_json({"benchmark": "bench_amg", "rows": rows}, a.out / "bench_amg.json")
    print(f"wrote {a.out / 'bench_amg.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
