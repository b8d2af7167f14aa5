"""Numerical stability at the extremes: conditioning and residuals where things get hard.

1. nu approaching the admissible limits of a mesh (``dv.stability``) with the paper's
   model (the defaults are stable for every nu they reach): DV and RV on a lattice and
   on a jittered mesh (h = 0.05), nu at a distance 1e-1 ... 1e-4 (relative to the width
   of the admissible nu interval) inside each limit;
2. slivers: a point a distance ``bump`` above the middle of a boundary edge, joined to
   the edge as a flat triangle (its circumcentre runs away like 1 / bump), as user
   meshes can contain;
3. size: uniaxial stress up to 1e6 nodes (AMG).

Reported: a 1-norm condition estimate of the constrained stiffness (LU-based, Hager's
estimator) where a direct solve runs, the relative equilibrium residual of the solution,
the normwise backward error of a direct solve ``|r| / (|K| |u| + |f|)``
and the error against the analytic uniaxial solution, or the refusal.

Usage::

    python validation/extremes.py            # everything (the 1e6 case takes minutes)
    python validation/extremes.py --quick    # no 1e6 case, fewer distances

Writes ``validation/out/extremes.json`` and prints the table.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import E_BEAM, PAPER, parser, write_json


def _cond_and_solve(model, sup, ld, solver="direct"):
    import scipy.sparse.linalg as spla

    import dvstatic as dv
    from dvstatic import linalg
    from dvstatic.mesh import mesh_dof_order
    from dvstatic.problem import constraints

    rec = {}
    try:
        sol = dv.solve(model, sup, ld, solver=solver, rtol=1e-10)
    except dv.SolverError as exc:
        rec["status"] = "refused: " + str(exc).split(":")[0]
        return rec
    mesh = model.mesh
    x = mesh.points
    exact = np.c_[-x[:, 0] / E_BEAM, model.nu * x[:, 1] / E_BEAM]
    rec.update(
        status="solved",
        residual=sol.info.residual,
        backward_error=sol.info.get("backward_error"),
        error=float(np.linalg.norm(sol.u - exact) / np.linalg.norm(exact)),
    )
    if solver == "direct":
        dofs, _ = constraints(mesh, sup)
        A = linalg.ConstrainedSystem(model.stiffness("bsr"), dofs).A.tocsc()
        lu = linalg.DirectSolver(A, order=mesh_dof_order(mesh))
        inv = spla.LinearOperator(
            A.shape, matvec=lambda v: lu.solve(v)[0], rmatvec=lambda v: lu.solve(v)[0], dtype=float
        )
        rec["cond1"] = float(spla.norm(A, 1) * spla.onenormest(inv))
    return rec


def near_limits(fractions) -> list:
    import dvstatic as dv

    rows = []
    for kind in ("lattice", "jittered"):
        mesh = dv.mesh.rectangle(1.0, 1.0, 0.05, kind=kind, seed=1)
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        ld = [dv.Traction("right", (-1.0, 0.0))]
        for name, cls in (("DV", dv.DV), ("RV", dv.RV)):
            rep = dv.stability(cls(mesh, E_BEAM, 0.2, **PAPER), sup)
            lo, hi = rep.nu_range
            width = hi - lo
            for side, edge, sign in (("lower", lo, 1), ("upper", hi, -1)):
                for fr in fractions:
                    nu = edge + sign * fr * width
                    rec = {
                        "case": "nu near limit",
                        "mesh": kind,
                        "model": name,
                        "side": side,
                        "nu_range": [lo, hi],
                        "distance": fr,
                        "nu": nu,
                    }
                    try:
                        rec.update(_cond_and_solve(cls(mesh, E_BEAM, nu, **PAPER), sup, ld))
                    except ValueError as exc:
                        rec["status"] = "no calibration: " + str(exc)[:60]
                    rows.append(rec)
    return rows


def slivers(bumps) -> list:
    import dvstatic as dv

    base = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
    rows = []
    for bump in bumps:
        p, t = base.points, base.triangles
        top = base.part_edges("top")
        a, b = top[len(top) // 2]
        apex = 0.5 * (p[a] + p[b]) + np.array([0.0, bump])
        pts = np.vstack([p, apex])
        tri = np.vstack([t, [a, b, len(p)]])
        parts = {k: base.part_edges(k) for k in ("left", "bottom", "right")}
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        ld = [dv.Traction("right", (-1.0, 0.0))]
        for name, cls in (("DV", dv.DV), ("RV", dv.RV)):
            rec = {"case": "boundary sliver", "bump": bump, "model": name}
            try:
                mesh = dv.Mesh(pts, tri, parts=parts)
                from dvstatic.lattice import geometry

                g = geometry.of(mesh)
                rec["max_half_side_over_l"] = float(np.max(np.abs(g.tri_r) / g.tri_l))
                rec.update(_cond_and_solve(cls(mesh, E_BEAM, 0.2), sup, ld))
            except ValueError as exc:
                rec["status"] = "refused: " + str(exc)[:70]
            rows.append(rec)
    return rows


def sizes(nodes) -> list:
    import dvstatic as dv

    rows = []
    for n in nodes:
        h = float(np.sqrt(2.0 / (np.sqrt(3) * n)))
        mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="jittered", seed=0)
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        ld = [dv.Traction("right", (-1.0, 0.0))]
        for name, cls in (("DV", dv.DV), ("RV", dv.RV)):
            rec = {"case": "size", "nodes": mesh.n_points, "model": name}
            rec.update(
                _cond_and_solve(
                    cls(mesh, E_BEAM, 0.2), sup, ld, solver="direct" if n <= 1e5 else "amg"
                )
            )
            rows.append(rec)
    return rows


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    a = p.parse_args(argv)
    fr = (1e-1, 1e-2) if a.quick else (1e-1, 1e-2, 1e-3, 1e-4)
    bumps = (1e-3, 1e-6, 1e-12) if a.quick else (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    n = (1e4,) if a.quick else (1e4, 1e5, 1e6)
    rows = near_limits(fr) + slivers(bumps) + sizes(n)
    for r in rows:
        desc = {k: r[k] for k in ("mesh", "side", "distance", "nu", "bump", "nodes") if k in r}
        vals = ", ".join(
            f"{k} {r[k]:.3g}"
            for k in ("cond1", "residual", "backward_error", "error", "max_half_side_over_l")
            if r.get(k) is not None
        )
        print(f"{r['case']:15} {r['model']} {desc}: {r['status']}" + (f"; {vals}" if vals else ""))
    write_json({"benchmark": "extremes", "rows": rows}, a.out / "extremes.json")
    print(f"wrote {a.out / 'extremes.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
