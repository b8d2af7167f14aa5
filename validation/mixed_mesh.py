"""A mesh that mixes micro-structures: a regular lattice beside random points (issue 28).

A 2 x 1 plate whose left half is a regular lattice and right half random points (one
Delaunay triangulation of both point sets, no generator recipe, as if imported), E = 1e4,
nu = 0.3, plane stress, uniaxial tension 1 on the right edge, the left edge on rollers.
For DV and RV, calibrated class by class of local spread (the default,
docs/theory.md 8.3) and with one calibration from the mesh's overall local spread (what
the class calibration replaces), it prints the relative L2 difference of the
displacement from P2 FE on the same triangles and each half's modulus E_eff / E (from the
slope of u_x over x in 0.2-0.8 and 1.2-1.8, rows 0.2 < y < 0.8); the same for a plate of
random points alone (its recipe: the random half's own error).

Usage::

    python validation/mixed_mesh.py           # h = 0.025 and 0.0125 (4e3 and 1.5e4 nodes)
    python validation/mixed_mesh.py --quick   # h = 0.05

Writes ``validation/out/mixed_mesh.json`` (``--quick``: ``validation/out/quick/``).
"""

from __future__ import annotations

import time

import numpy as np
from _common import parser, write_json
from scipy.spatial import Delaunay

import dvstatic as dv
from dvstatic.lattice.calibration import relaxed

E, NU = 1e4, 0.3


def mixed(h: float) -> dv.Mesh:
    """The plate: a regular lattice on the left half, random points on the right."""
    a = dv.mesh.rectangle(1, 1, h, kind="lattice").points
    b = dv.mesh.rectangle(1, 1, h, kind="random", seed=3).points + [1.0, 0.0]
    pts = np.unique(np.round(np.vstack([a, b]), 9), axis=0)
    tri = Delaunay(pts).simplices
    x = pts[tri]
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    tri = tri[np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) > 1e-12]
    edges = dv.Mesh(pts, tri).boundary_edges
    mid = pts[edges].mean(axis=1)
    parts = {"left": edges[mid[:, 0] < 1e-9], "right": edges[mid[:, 0] > 2 - 1e-9]}
    return dv.Mesh(pts, tri, parts=parts)


def row(mesh: dv.Mesh, model, label: str, calibration: str) -> dict:
    sup = [dv.Fix("left", x=0), dv.Fix(at=(0, 0), y=0)]
    loads = [dv.Traction("right", (1.0, 0.0))]
    t0 = time.perf_counter()
    if calibration == "one":
        m = model(mesh, E, NU, calibration=relaxed(model.kind, mesh, E, NU))
    else:
        m = model(mesh, E, NU)
    _ = m.operator  # the calibration, classes included
    seconds = time.perf_counter() - t0
    sol = dv.solve(m, sup, loads)
    l2 = dv.compare(sol, dv.fem.solve(m, sup, loads, order=2)).l2
    p = mesh.points
    rows = (p[:, 1] > 0.2) & (p[:, 1] < 0.8)
    halves = []
    for lo in (0.2, 1.2):
        sel = rows & (p[:, 0] > lo) & (p[:, 0] < lo + 0.6)
        halves.append(1.0 / (np.polyfit(p[sel, 0], sol.u[sel, 0], 1)[0] * E))
    field = m.micro_field
    return {
        "mesh": label,
        "nodes": mesh.n_points,
        "model": model.__name__,
        "calibration": calibration,
        "classes": [] if field is None else field.classes.spread.tolist(),
        "l2": l2,
        "left_E": halves[0],
        "right_E": halves[1],
        "calibration_seconds": seconds,
    }


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    out = []
    for h in (0.05,) if args.quick else (0.025, 0.0125):
        cases = [(mixed(h), "mixed", ("by class", "one"))]
        cases.append((dv.mesh.rectangle(2, 1, h, kind="random", seed=3), "random", ("recipe",)))
        for mesh, label, calibrations in cases:
            for model in (dv.DV, dv.RV):
                for cal in calibrations:
                    r = row(mesh, model, label, cal)
                    out.append(r)
                    print(
                        f"{label:7s} h {h:<7g} {r['nodes']:6d} nodes {r['model']} "
                        f"{cal:9s} L2 from P2 {r['l2']:6.2%}  E_eff / E left "
                        f"{r['left_E']:.4f} right {r['right_E']:.4f}  classes "
                        f"{np.round(r['classes'], 3).tolist()}",
                        flush=True,
                    )
    path = write_json({"quick": args.quick, "rows": out}, args.out / "mixed_mesh.json")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    import sys

    sys.exit(main())
