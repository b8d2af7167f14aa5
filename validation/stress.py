"""Stresses at every node (issue 24): the default recovery against exact fields.

Tables:

* **uniform**: uniaxial, biaxial and shear stress on 2 x 1 plates (rollers or points,
  tractions on the rest), every mesh kind (lattice, jittered, cvt, random, graded),
  about 4e3 and 1.6e4 nodes, DV and RV: bias (largest mean error of a component), std
  over ALL nodes, worst node, the rows next to the loaded edges (mean), the corners
  (worst), relative to the applied traction;
* **lame**: the hoop stress at every bore node of a thick cylinder (a = 0.5, b = 1,
  plane strain, three point supports) at about 2e4 nodes, with one ``Pressure`` and
  with one ``Traction`` per bore edge; and the quarter cylinder of the convergence
  study (symmetry rollers, corners on the bore);
* **peaks**: NAFEMS LE1 at point D and Kirsch's hole (the top, a corner on a symmetry
  line) at three sizes (two halvings of h), one mesh seed (validation/refinement.py
  has the same peaks over seeds 0-3, and Cook's and the cantilever's displacement);
* **tunnel**: the tunnel example's checks and the hoop stress at every wall node as
  h_near halves twice, seeds 0-3, with the size growing over 3 m (0.16 per metre, the
  example's grading until 2026-12-05) and over 6 m (0.08, the example's now);
* **tension**: the first break in direct tension between roller grips.

Usage::

    python validation/stress.py            # full size (about 13 min on 2 cores)
    python validation/stress.py --quick    # small meshes

Writes ``validation/out/stress.json`` (``--quick``: ``validation/out/quick/``) and
prints the tables.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from _benchmarks import kirsch, lame, le1
from _common import parser, write_json

import dvstatic as dv
from dvstatic.report import check_values

E, NU = 1e4, 0.3
KINDS = ("lattice", "jittered", "cvt", "random", "graded")
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


# ------------------------------------------------------------------ uniform states
def plate(kind: str, nodes: int) -> dv.Mesh:
    h = float(np.sqrt(2.0 / (np.sqrt(3) / 2 * nodes)))
    if kind == "graded":  # finer at the loaded (right) edge, 2.5 h to h
        return dv.mesh.rectangle(
            2.0, 1.0, lambda x: h * (2.5 - 1.5 * x[:, 0] / 2.0) / 1.6, kind="cvt", seed=1
        )
    return dv.mesh.rectangle(2.0, 1.0, h, kind=kind, seed=1)


def uniform_case(case: str):
    """Supports, loads, exact stress and the loaded sides."""
    if case == "uniaxial":
        sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0.0, 0.0), y=0.0)]
        return sup, [dv.Traction("right", (1.0, 0.0))], np.diag([1.0, 0.0]), ("right",)
    if case == "biaxial":
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        loads = [dv.Traction("right", (1.0, 0.0)), dv.Traction("top", (0.0, 1.0))]
        return sup, loads, np.eye(2), ("right", "top")
    loads = [
        dv.Traction("right", (0.0, 1.0)),
        dv.Traction("left", (0.0, -1.0)),
        dv.Traction("top", (1.0, 0.0)),
        dv.Traction("bottom", (-1.0, 0.0)),
    ]
    sup = [dv.Fix(at=(0.0, 0.0)), dv.Fix(at=(2.0, 0.0), y=0.0)]
    return sup, loads, np.array([[0.0, 1.0], [1.0, 0.0]]), ("right", "left", "top", "bottom")


def uniform_row(kind: str, nodes: int, case: str, cls) -> dict:
    mesh = plate(kind, nodes)
    sup, loads, target, sides = uniform_case(case)
    sol = dv.solve(cls(mesh, E, NU), sup, loads)
    t0 = time.perf_counter()
    s = sol.stress()
    seconds = time.perf_counter() - t0
    err = np.stack(
        [s[:, 0, 0] - target[0, 0], s[:, 1, 1] - target[1, 1], s[:, 0, 1] - target[0, 1]], 1
    )
    x, y = mesh.points.T
    h = mesh.h
    near = np.zeros(mesh.n_points, bool)
    dist = {"right": 2.0 - x, "left": x, "top": 1.0 - y, "bottom": y}
    for side in sides:
        near |= (dist[side] > 0.5 * h) & (dist[side] < 1.5 * h)
    corners = [
        int(np.argmin(np.hypot(*(mesh.points - c).T))) for c in ((0, 0), (2, 0), (2, 1), (0, 1))
    ]
    return {
        "kind": kind,
        "model": cls.kind,
        "case": case,
        "nodes": mesh.n_points,
        "bias": float(np.abs(err.mean(0)).max()),
        "std": float(err.std(0).max()),
        "worst": float(np.abs(err).max()),
        "row_next_to_loaded_edge": float(np.abs(err[near].mean(0)).max()),
        "corners": float(np.abs(err[corners]).max()),
        "recovery_seconds": seconds,
    }


# ------------------------------------------------------------------ Lame bore
def ring(kind: str, nodes: int) -> dv.Mesh:
    area = np.pi * (1.0 - 0.25)
    h = float(np.sqrt(area / (np.sqrt(3) / 2 * nodes)))
    return dv.mesh.disc(1.0, h, kind=kind, holes=[dv.domain.Circle((0, 0), 0.5, "bore")], seed=2)


def bore_row(kind: str, nodes: int, written: str) -> dict:
    mesh = ring(kind, nodes)
    sup = [
        dv.Fix(at=(1.0, 0.0), y=0.0),
        dv.Fix(at=(-1.0, 0.0), y=0.0),
        dv.Fix(at=(0.0, 1.0), x=0.0),
    ]
    if written == "pressure":
        loads = [dv.Pressure("bore", 1.0)]
    else:
        loads = []
        for a, b in mesh.part_edges("bore"):
            d = mesh.points[b] - mesh.points[a]
            n = np.array([d[1], -d[0]]) / np.hypot(*d)
            loads.append(dv.Traction(np.array([[a, b]]), tuple(-n)))
    sol = dv.solve(dv.DV(mesh, E, NU, plane="strain"), sup, loads)
    bore = mesh.part_nodes("bore")
    p = mesh.points[bore]
    t = np.c_[-p[:, 1], p[:, 0]] / 0.5
    hoop = np.einsum("ni,nij,nj->n", t, sol.stress()[bore], t) / (1.25 / 0.75) - 1
    return {
        "kind": kind,
        "load": written,
        "nodes": mesh.n_points,
        "bore_nodes": len(bore),
        "hoop_rms": float(np.sqrt(np.mean(hoop**2))),
        "hoop_max": float(np.abs(hoop).max()),
        "hoop_mean": float(hoop.mean()),
    }


def quarter_bore_row(kind: str, nodes: int) -> dict:
    bm = lame(0.3)
    mesh = bm.make_mesh(bm.h_for(nodes), kind=kind, seed=1)
    sol = dv.solve(dv.DV(mesh, bm.E, bm.nu, plane="strain"), *bm.problem(mesh))
    bore = mesh.part_nodes("bore")
    p = mesh.points[bore]
    t = np.c_[-p[:, 1], p[:, 0]]
    ex = np.einsum("ni,nij,nj->n", t, bm.stress_exact(p), t)
    hoop = np.einsum("ni,nij,nj->n", t, sol.stress()[bore], t) / ex - 1
    corner = int(np.argmin(np.hypot(*(p - (0.0, 1.0)).T)))
    return {
        "kind": kind,
        "nodes": mesh.n_points,
        "hoop_rms": float(np.sqrt(np.mean(hoop**2))),
        "hoop_max": float(np.abs(hoop).max()),
        "corner_on_symmetry_line": float(hoop[corner]),
    }


# ------------------------------------------------------------------ peaks
def peak_row(name: str, kind: str, nodes: int) -> dict:
    bm = le1() if name == "LE1" else kirsch(0.3)
    mesh = bm.make_mesh(bm.h_for(nodes), kind=kind, seed=1)
    sol = dv.solve(dv.DV(mesh, bm.E, bm.nu), *bm.problem(mesh))
    key = bm.keys[0]
    i = int(np.argmin(np.hypot(*(mesh.points - np.array(key.where)).T)))
    s = sol.stress()[i]
    v = s[1, 1] if key.what == "syy" else s[0, 0]
    return {
        "problem": name,
        "kind": kind,
        "nodes": mesh.n_points,
        "value": float(v),
        "reference": key.reference,
        "error": float(v / key.reference - 1),
    }


# ------------------------------------------------------------------ examples
def run_example(name: str, overrides=()):
    """An example's scene, mesh and linear solution."""
    sc = dv.scene.load(EXAMPLES / f"{name}.toml", overrides)
    mesh = sc.build_mesh()
    sol = dv.solve(sc.build_model(mesh), sc.build_supports(mesh), sc.build_loads(mesh))
    return sc, mesh, sol


def example_checks(name: str, overrides=(), run=None) -> dict:
    """An example's printed checks (relative differences); ``run``: its
    :func:`run_example` when already solved."""
    sc, mesh, sol = run or run_example(name, overrides)
    checks = check_values(sol, sc.data["output"]["checks"])
    return {
        "example": name,
        "overrides": list(overrides),
        "nodes": mesh.n_points,
        "checks": {c["name"]: c["difference"] for c in checks},
    }


def tunnel_row(h_near: str, grading: str, seed: int) -> dict:
    """The tunnel example's checks and the hoop stress at EVERY wall node (relative to
    Lame's -2 p0 b^2 / (b^2 - a^2)) for one h_near, grading and seed."""
    over = [f"mesh.h_near={h_near}", f"mesh.grading={grading}", f"mesh.seed={seed}"]
    sc, mesh, sol = run = run_example("tunnel", over)
    rec = example_checks("tunnel", over, run)
    wall = mesh.part_nodes("tunnel")
    t = np.arctan2(mesh.points[wall, 1], mesh.points[wall, 0])
    s = sol.stress()[wall]
    c, si = np.cos(t), np.sin(t)
    hoop = s[:, 0, 0] * si**2 + s[:, 1, 1] * c**2 - 2 * s[:, 0, 1] * si * c
    p0 = float(sc.data["loads"][0]["p"])
    b = float(sc.data["mesh"]["radius"])
    err = hoop / (-2 * p0 * b**2 / (b**2 - 1.0)) - 1
    rec.update(
        h_near=float(h_near),
        grading=float(grading),
        seed=seed,
        wall_nodes=len(wall),
        wall_mean=float(err.mean()),
        wall_rms=float(np.sqrt(np.mean(err**2))),
        wall_worst=float(np.abs(err).max()),
    )
    return rec


# ------------------------------------------------------------------ direct tension
def tension_row(kind: str, cls) -> dict:
    ft, stretch = 2.0, 1e-3
    mesh = dv.mesh.rectangle(2.0, 1.0, 0.05, kind=kind, seed=1)
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0.0, 0.0), y=0.0), dv.Fix("right", x=stretch)]
    res = dv.fracture(cls(mesh, E=E, nu=0.2), sup, ft=ft, max_events=1)
    e = res.events[0]
    where = mesh.points[mesh.topology.bonds[e.bond]].mean(axis=0)
    return {
        "kind": kind,
        "model": cls.kind,
        "first_break_over_ft": e.load_factor * stretch * E / 2 / ft,
        "at": where.tolist(),
    }


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    quick = args.quick
    sizes = (1000,) if quick else (4000, 16000)
    out: dict = {"quick": quick}
    t0 = time.perf_counter()
    out["uniform"] = [
        uniform_row(k, n, c, cls)
        for k in KINDS
        for n in sizes
        for c in ("uniaxial", "biaxial", "shear")
        for cls in (dv.DV, dv.RV)
    ]
    _table(
        "uniform stress (relative to the applied traction)",
        out["uniform"],
        [
            "kind",
            "model",
            "case",
            "nodes",
            "bias",
            "std",
            "worst",
            "row_next_to_loaded_edge",
            "corners",
        ],
    )
    n_bore = 3000 if quick else 20000
    out["lame"] = [
        bore_row(k, n_bore, w)
        for k in ("jittered", "cvt", "random")
        for w in ("pressure", "tractions")
    ]
    _table(
        "Lame bore, hoop stress at every bore node",
        out["lame"],
        ["kind", "load", "nodes", "bore_nodes", "hoop_mean", "hoop_rms", "hoop_max"],
    )
    out["lame_quarter"] = [quarter_bore_row(k, n_bore) for k in ("jittered", "cvt", "random")]
    _table(
        "quarter Lame cylinder (symmetry rollers)",
        out["lame_quarter"],
        ["kind", "nodes", "hoop_rms", "hoop_max", "corner_on_symmetry_line"],
    )
    peak_sizes = (1000, 4000) if quick else (5000, 20000, 80000)
    out["peaks"] = [
        peak_row(p, k, n)
        for p in ("LE1", "Kirsch")
        for k in ("jittered", "cvt")
        for n in peak_sizes
    ]
    _table(
        "peaks (LE1 syy at D, Kirsch sxx at the hole's top)",
        out["peaks"],
        ["problem", "kind", "nodes", "value", "reference", "error"],
    )
    near = ("0.05", "0.025") if quick else ("0.05", "0.025", "0.0125")
    seeds = (0,) if quick else (0, 1, 2, 3)
    out["tunnel"] = [tunnel_row(v, g, seed) for g in ("3.0", "6.0") for v in near for seed in seeds]
    _table(
        "tunnel wall: hoop stress at every wall node (grading 3.0 was the example's until "
        "2026-12-05, 6.0 is now)",
        out["tunnel"],
        ["grading", "h_near", "seed", "nodes", "wall_mean", "wall_rms", "wall_worst"],
    )
    out["examples"] = [example_checks(n) for n in ("thick_cylinder", "tunnel", "plate_with_hole")]
    for rec in out["tunnel"] + out["examples"]:
        print(
            rec["example"],
            rec["overrides"],
            rec["nodes"],
            {k: f"{v:+.2%}" for k, v in rec["checks"].items()},
        )
    out["tension"] = [
        tension_row(k, cls) for k in ("lattice", "jittered", "cvt") for cls in (dv.DV, dv.RV)
    ]
    _table(
        "direct tension between roller grips: first break",
        out["tension"],
        ["kind", "model", "first_break_over_ft", "at"],
    )
    out["seconds"] = time.perf_counter() - t0
    path = write_json(out, args.out / "stress.json")
    print(f"wrote {path} ({out['seconds']:.0f} s)")
    return 0


def _table(title: str, rows: list[dict], cols: list[str]) -> None:
    print(f"\n{title}")
    print("  ".join(f"{c:>14}" for c in cols))
    for r in rows:
        cells = []
        for c in cols:
            v = r[c]
            if isinstance(v, float) and c not in ("value", "reference", "h_near", "grading"):
                cells.append(
                    f"{v:>+14.2%}"
                    if c in ("error", "hoop_mean", "corner_on_symmetry_line", "wall_mean")
                    else f"{v:>14.2%}"
                )
            elif isinstance(v, float):
                cells.append(f"{v:>14.4g}")
            else:
                cells.append(f"{str(v):>14}")
        print("  ".join(cells))


if __name__ == "__main__":
    sys.exit(main())
