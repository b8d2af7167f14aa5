"""Distributed solve on PETSc: strong and weak scaling on this machine, iterations
against mesh size, memory per rank.

Uniaxial stress on jittered meshes (jitter 0.3) of the unit square, DV, nu = 0.2,
``solver="petsc"`` (KSP CG + GAMG with rigid-body near null space, rtol 1e-8), run
as ``mpiexec -n P python validation/bench_mpi.py --worker ...`` for every case. Each
case reports seconds per stage (mesh generation, which every rank does for the
replicated mesh; partition; calibration; patch; assembly; GAMG set-up; CG solve;
gather on rank 0), CG iterations, the error against the serial AMG solution where the
serial run is affordable, and the peak resident memory of every rank.

* strong scaling: the same mesh on 1 and 2 ranks;
* weak scaling: nodes per rank fixed;
* iterations against size: 2 ranks from 1e4 to the largest size.

Usage::

    python validation/bench_mpi.py                 # 1e4 ... 1e6 nodes
    python validation/bench_mpi.py --quick         # 1e4, 3e4 nodes (CI size)

Writes ``validation/out/bench_mpi.json`` and prints tables. Needs the ``dvstatic[petsc]``
extra (see docs/parallel.md).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _common import parser, write_json


def worker(n_nodes: float, check: bool) -> None:
    import resource

    from petsc4py import PETSc

    import dvstatic as dv

    comm = PETSc.COMM_WORLD
    h = float(np.sqrt(2.0 / (np.sqrt(3) * n_nodes)))
    t = time.perf_counter()
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", jitter=0.3, seed=0)
    t_mesh = time.perf_counter() - t
    mesh_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    model = dv.DV(mesh, 1e5, 0.2)
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
    ld = [dv.Traction("right", (-1.0, 0.0))]
    comm.barrier()
    t = time.perf_counter()
    sol = dv.solve(model, sup, ld, solver="petsc", rtol=1e-8)
    t_solve = time.perf_counter() - t
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    peaks = comm.tompi4py().gather(peak)
    mesh_peaks = comm.tompi4py().gather(mesh_mb)
    if comm.getRank() != 0:
        return
    rec = {
        "ranks": comm.getSize(),
        "nodes": mesh.n_points,
        "dof": 2 * mesh.n_points,
        "mesh": t_mesh,
        "solve_total": t_solve,
        "iterations": sol.info.iterations,
        "residual": sol.info.residual,
        "seconds": sol.info.seconds.as_dict(),
        "peak_MB_per_rank": peaks,
        "peak_MB_after_mesh_per_rank": mesh_peaks,
        "rank0_memory": sol.info.parallel.memory,
    }
    if check:
        ref = dv.solve(dv.DV(mesh, 1e5, 0.2), sup, ld, solver="amg", rtol=1e-12)
        rec["rel_diff_vs_serial"] = float(np.max(np.abs(sol.u - ref.u)) / np.max(np.abs(ref.u)))
    print("JSON" + json.dumps(rec))


def run_case(ranks: int, n_nodes: float, check: bool) -> dict:
    mpiexec = shutil.which("mpiexec") or str(Path(sys.executable).with_name("mpiexec"))
    cmd = [mpiexec, "-n", str(ranks), sys.executable, __file__, "--worker", str(n_nodes)]
    if check:
        cmd.append("--check")
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    for line in out.stdout.splitlines():
        if line.startswith("JSON"):
            return json.loads(line[4:])
    raise RuntimeError(f"case ranks={ranks} nodes={n_nodes:g} failed:\n{out.stderr[-3000:]}")


def _row(rec: dict) -> str:
    s = rec["seconds"]
    return (
        f"{rec['ranks']:>5} {rec['nodes']:>9} {rec['mesh']:>7.2f} {s['partition']:>7.2f} "
        f"{s['calibration']:>7.2f} {s['patch']:>7.2f} {s['assembly']:>7.2f} {s['setup']:>7.2f} "
        f"{s['solve']:>7.2f} {s['gather']:>6.2f} {s['total']:>7.2f} {rec['iterations']:>4} "
        + " ".join(
            f"{p:>6.0f} ({m:.0f})"
            for p, m in zip(
                rec["peak_MB_per_rank"], rec["peak_MB_after_mesh_per_rank"], strict=True
            )
        )
    )


HEADER = (
    "ranks     nodes    mesh  partit   calib   patch  assem   setup   solve gather   total "
    " its  peak MB per rank (after mesh generation)"
)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--worker":
        worker(float(argv[1]), "--check" in argv)
        return 0
    p = parser(__doc__)
    a = p.parse_args(argv)
    from dvstatic import parallel as distributed

    if not distributed.available():
        print("bench_mpi skipped: petsc4py is not installed (scripts/install_petsc.sh)")
        return 0
    sizes = (1e4, 3e4) if a.quick else (1e4, 1e5, 1e6)
    per_rank = 1.5e4 if a.quick else 5e5
    results: dict = {"benchmark": "bench_mpi", "strong": [], "weak": [], "sizes": []}
    print("strong scaling (same mesh on 1 and 2 ranks)")
    print(HEADER)
    for ranks in (1, 2):
        rec = run_case(ranks, sizes[-1], check=False)
        results["strong"].append(rec)
        print(_row(rec))
    s1, s2 = results["strong"][0]["seconds"], results["strong"][1]["seconds"]
    results["strong_speedup_solve_total"] = s1["total"] / s2["total"]
    print(f"speed-up of the distributed solve on 2 ranks: {s1['total'] / s2['total']:.2f}x")
    print("\nweak scaling (fixed nodes per rank)")
    print(HEADER)
    for ranks in (1, 2):
        rec = run_case(ranks, per_rank * ranks, check=False)
        results["weak"].append(rec)
        print(_row(rec))
    print("\niterations against size (2 ranks; difference from the serial AMG solution)")
    print(HEADER + "  rel. diff")
    for n in sizes:
        rec = run_case(2, n, check=n <= 1e5)
        results["sizes"].append(rec)
        diff = rec.get("rel_diff_vs_serial")
        print(_row(rec) + (f"  {diff:.1e}" if diff is not None else ""))
    path = write_json(results, a.out / "bench_mpi.json")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
