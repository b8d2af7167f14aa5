"""A mesh that mixes micro-structures: a regular lattice beside random points (issue 28).

A 2 x 1 plate whose left half is a regular lattice and right half random points (one
Delaunay triangulation of both point sets, no generator recipe, as if imported), E = 1e4,
nu = 0.3, plane stress, uniaxial tension 1 on the right edge, the left edge on rollers.
For DV and RV, calibrated class by class of local spread (the default,
docs/theory.md 8.3) and with one calibration from the mesh's overall local spread (what
the class calibration replaces), it prints the relative L2 difference of the
displacement from P2 FE on the same triangles and each half's modulus E_eff / E (from the
slope of u_x over x in 0.2-0.8 and 1.2-1.8, rows 0.2 < y < 0.8); the same for a plate of
random points alone (its recipe: the random half's own error). Then a regular lattice
with a disc of random points (radius 0.15) at its centre, a patch too small for the
percentiles of the local spread (found as a patch, docs/theory.md 8.3): the disc's
modulus from its mean strain, by class and with one calibration, and the calibration
warnings each leaves.

Usage::

    python validation/mixed_mesh.py           # h = 0.025 and 0.0125 (4e3 and 1.5e4 nodes);
                                              # the disc at h = 0.02 and 0.01
    python validation/mixed_mesh.py --quick   # h = 0.05; the disc at 0.02

Writes ``validation/out/mixed_mesh.json`` (``--quick``: ``validation/out/quick/``).
"""

from __future__ import annotations

import time

import numpy as np
from _common import parser, write_json
from scipy.spatial import Delaunay

import dvstatic as dv
from dvstatic.lattice.calibration import calibration_flags, relaxed
from dvstatic.lattice.calibration.relaxed import local_spread

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


def disc(h: float, r: float = 0.15) -> dv.Mesh:
    """The plate as a regular lattice with a disc of random points of radius ``r`` at
    (1, 0.5): a patch too small for the percentiles of the local spread."""
    c = np.array([1.0, 0.5])
    a = dv.mesh.rectangle(2, 1, h, kind="lattice").points
    a = a[np.hypot(*(a - c).T) > r]
    b = dv.mesh.rectangle(2, 1, h, kind="random", seed=3).points
    b = b[np.hypot(*(b - c).T) <= r - 0.3 * h]
    pts = np.vstack([a, b])
    tri = Delaunay(pts).simplices
    edges = dv.Mesh(pts, tri).boundary_edges
    mid = pts[edges].mean(axis=1)
    parts = {"left": edges[mid[:, 0] < 1e-9], "right": edges[mid[:, 0] > 2 - 1e-9]}
    return dv.Mesh(pts, tri, parts=parts)


def mean_exx(mesh: dv.Mesh, u: np.ndarray, sel: np.ndarray) -> float:
    """The area-weighted mean strain e_xx over the triangles ``sel``."""
    x, du = mesh.points[mesh.triangles], u[mesh.triangles]
    d = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=-1)
    g = np.stack([du[:, 1] - du[:, 0], du[:, 2] - du[:, 0]], axis=-1) @ np.linalg.inv(d)
    area = 0.5 * np.abs(np.linalg.det(d))
    return float(np.sum(g[sel, 0, 0] * area[sel]) / area[sel].sum())


def disc_row(h: float, model, calibration: str) -> dict:
    """The disc's modulus (its mean strain, r < 0.1) and its surroundings' (a ring
    0.3 < r < 0.45) under the tension, by class (the default) or one calibration."""
    mesh = disc(h)
    if calibration == "one":
        m = model(mesh, E, NU, calibration=relaxed(model.kind, mesh, E, NU))
        flags = calibration_flags(mesh, np.full(mesh.n_triangles, local_spread(mesh)))
    else:
        m = model(mesh, E, NU)
        flags = m.calibration_flags
    sup = [dv.Fix("left", x=0), dv.Fix(at=(0, 0), y=0)]
    sol = dv.solve(m, sup, [dv.Traction("right", (1.0, 0.0))])
    r = np.hypot(*(mesh.points[mesh.triangles].mean(axis=1) - [1.0, 0.5]).T)
    return {
        "mesh": "disc of random points",
        "nodes": mesh.n_points,
        "model": model.__name__,
        "calibration": calibration,
        "classes": [] if m.micro_field is None else m.micro_field.classes.spread.tolist(),
        "disc_E": 1.0 / (E * mean_exx(mesh, sol.u, r < 0.1)),
        "around_E": 1.0 / (E * mean_exx(mesh, sol.u, (r > 0.3) & (r < 0.45))),
        "flags": [f.as_dict() for f in flags],
    }


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
    discs = []
    for h in (0.02,) if args.quick else (0.02, 0.01):
        for model in (dv.DV, dv.RV):
            for cal in ("by class", "one"):
                r = disc_row(h, model, cal)
                discs.append(r)
                print(
                    f"disc    h {h:<7g} {r['nodes']:6d} nodes {r['model']} {cal:9s} E_eff / E "
                    f"disc {r['disc_E']:.4f} around {r['around_E']:.4f}  classes "
                    f"{np.round(r['classes'], 3).tolist()}  flags {len(r['flags'])}",
                    flush=True,
                )
    data = {"quick": args.quick, "rows": out, "disc": discs}
    path = write_json(data, args.out / "mixed_mesh.json")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    import sys

    sys.exit(main())
