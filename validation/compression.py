"""Fracture in compression (dv.fracture with criterion "mohr-coulomb", held loads):
uniaxial compression of a 1 x 2 prism between frictionless platens on CVT meshes,
the emergent strength for three (c, phi) pairs, biaxial compression under a held
lateral pressure (the Coulomb slope), and the Brazilian disc with the Mohr-Coulomb
criterion. Prints tables, writes compression.json and compression.png.

Prism: E = 2e4, nu = 0.2, ft = 2, c = 6, phi = 30 deg (the continuum's UCS =
2 c cos(phi) / (1 - sin(phi)) = 20.78), displacement control (the top platen moves
down), brittle bonds. The load is the platen force over the width: the axial stress.
Biaxial: the lateral pressure p = 0, 0.1, 0.2, 0.4 UCS is held at full value in every
state (dv.fracture(..., held=[...])); the envelope says sigma_1 = UCS + p (1 + sin phi)
/ (1 - sin phi). Every recorded state is re-solved from scratch to check that it is in
equilibrium with the held pressure at full value.
"""

from __future__ import annotations

import time

import numpy as np
from _common import parser, write_json
from fracture import brazilian

import dvstatic as dv
from dvstatic.crack import ucs
from dvstatic.lattice.damage import split
from dvstatic.linalg import ConstrainedSystem
from dvstatic.problem import constraints, load_vector

E, NU, FT, C, PHI = 2e4, 0.2, 2.0, 6.0, 30.0


def platens(mesh, d: float = 1e-3):
    """Frictionless platens: the bottom fixed, the top moved down by ``d``, the bottom
    node nearest the middle held sideways."""
    mid = int(np.argmin(np.hypot(mesh.points[:, 0] - 0.5, mesh.points[:, 1])))
    return [dv.Fix("bottom", y=0.0), dv.Fix("top", y=-d), dv.Fix([mid], x=0.0)]


def prism_run(h: float, c=C, phi=PHI, p=0.0, seed=1, max_events=4000):
    """One prism: the result, the largest equilibrium error of its snapshots, seconds."""
    mesh = dv.mesh.rectangle(1.0, 2.0, h, kind="cvt", seed=seed)
    model = dv.DV(mesh, E=E, nu=NU)
    held = [dv.Pressure("left", p), dv.Pressure("right", p)] if p else None
    t0 = time.perf_counter()
    res = dv.fracture(
        model,
        platens(mesh),
        None,
        held=held,
        ft=FT,
        criterion="mohr-coulomb",
        cohesion=c,
        friction_angle=phi,
        max_events=max_events,
        stop_load_ratio=0.05,
    )
    seconds = time.perf_counter() - t0
    return res, _held_equilibrium(model, res, held), seconds


def _held_equilibrium(model, res, held) -> float:
    """The largest relative residual ``|A u - b| / |b|`` of the constrained system of
    every snapshot (the damaged stiffness assembled afresh, ``b`` the held pressure at
    full value and the platens at the event's load factor; 0 without held loads)."""
    if not held:
        return 0.0
    mesh = model.mesh
    s = split(model)
    dofs, values = constraints(mesh, platens(mesh))
    fh = load_vector(mesh, held)
    worst = 0.0
    for snap in res.snapshots:
        lam = res.events[snap.event].load_factor
        system = ConstrainedSystem(s.stiffness(mesh, *s.factors(snap.stiffness, snap.closed)), dofs)
        b = system.rhs(fh, lam * values)
        r = system.A @ snap.u.ravel() - b
        worst = max(worst, float(np.linalg.norm(r) / np.linalg.norm(b)))
    return worst


def row(res, seconds, c=C, phi=PHI, p=0.0, eq=0.0) -> dict:
    strength = ucs(c, phi)
    k = (1 + np.sin(np.radians(phi))) / (1 - np.sin(np.radians(phi)))
    env = strength + k * p
    first, peak = res.events[0], res.peak
    return {
        "nodes": res.model.mesh.n_points,
        "c": c,
        "phi": phi,
        "p": p,
        "ucs": strength,
        "envelope": env,
        "first": first.load,
        "first_mode": first.mode,
        "peak": peak.load,
        "peak_event": peak.index,
        "peak_over_envelope": peak.load / env,
        "ucs_over_ft": peak.load / FT if p == 0 else None,
        "events": len(res.events),
        "broken": len(res.broken),
        "modes": res.to_dict()["modes"],
        "stop": res.stop_reason,
        "held_equilibrium": eq,
        "seconds": seconds,
    }


def uniaxial(hs) -> tuple[list, list]:
    rows, results = [], []
    print("uniaxial compression, c = 6, phi = 30 deg (UCS 20.78)")
    print("   nodes  first   mode      peak   peak/UCS events  tension shear crushing")
    for h in hs:
        res, _, s = prism_run(h)
        r = row(res, s)
        rows.append(r)
        results.append(res)
        m = r["modes"]
        print(
            f"  {r['nodes']:6d} {r['first']:6.2f}  {r['first_mode']:8s} {r['peak']:6.2f}  "
            f"{r['peak_over_envelope']:7.3f}  {r['events']:5d}  {m['tension']:6d} "
            f"{m['shear']:5d} {m['crushing']:7d}   ({s:.1f} s)"
        )
    return rows, results


def pairs(h) -> list:
    out = []
    print("emergent strength for three (c, phi) pairs")
    print("      c   phi    UCS   peak  peak/UCS  peak/ft")
    for c, phi in ((6.0, 30.0), (4.0, 40.0), (10.0, 20.0)):
        res, _, s = prism_run(h, c, phi)
        r = row(res, s, c, phi)
        out.append(r)
        print(
            f"  {c:5.1f} {phi:5.1f} {r['ucs']:6.2f} {r['peak']:6.2f}  "
            f"{r['peak_over_envelope']:7.3f}  {r['ucs_over_ft']:6.2f}"
        )
    return out


def biaxial(h) -> dict:
    strength = ucs(C, PHI)
    rows = []
    print("biaxial compression, held lateral pressure p")
    print("   p/UCS     p   envelope   first    peak  peak/env  held equilibrium")
    for frac in (0.0, 0.1, 0.2, 0.4):
        p = frac * strength
        res, eq, s = prism_run(h, p=p)
        r = row(res, s, p=p, eq=eq)
        rows.append(r)
        print(
            f"  {frac:5.2f} {p:6.2f} {r['envelope']:8.2f} {r['first']:7.2f} {r['peak']:7.2f}  "
            f"{r['peak_over_envelope']:7.3f}   {eq:.1e}"
        )
    p = np.array([r["p"] for r in rows])
    slope_peak = float(np.polyfit(p, [r["peak"] for r in rows], 1)[0])
    slope_first = float(np.polyfit(p, [r["first"] for r in rows], 1)[0])
    k = (1 + np.sin(np.radians(PHI))) / (1 - np.sin(np.radians(PHI)))
    print(
        f"  slope of sigma_1 against p: peak {slope_peak:.3f}, first failure {slope_first:.3f} "
        f"(Mohr-Coulomb {k:.3f})"
    )
    return {"rows": rows, "slope_peak": slope_peak, "slope_first": slope_first, "slope_mc": k}


def brazilian_mc(h: float) -> dict:
    """The Brazilian disc (fracture.py's set-up, ft = 3) with Mohr-Coulomb, c such that
    UCS = 10 ft (phi = 30 deg)."""
    phi = 30.0
    c = 10 * 3.0 * (1 - np.sin(np.radians(phi))) / (2 * np.cos(np.radians(phi)))
    t0 = time.perf_counter()
    res, p_strip = brazilian(
        h,
        0,
        gf=5e-4,
        criterion="mohr-coulomb",
        cohesion=c,
        friction_angle=phi,
        max_events=6000,
        stop_load_ratio=0.3,
    )
    mesh = res.model.mesh
    mid = mesh.points[mesh.topology.bonds[res.broken]].mean(axis=1)
    out = {
        "nodes": mesh.n_points,
        "cohesion": c,
        "phi": phi,
        "splitting_over_ft": 2 * res.peak.load_factor * p_strip / (np.pi * 2.0) / 3.0,
        "near_diameter": float(np.mean(np.abs(mid[:, 0]) < 0.2)),
        "modes": res.to_dict()["modes"],
        "events": len(res.events),
        "seconds": time.perf_counter() - t0,
    }
    print(
        f"Brazilian disc, Mohr-Coulomb (c = {c:.2f}, phi = 30, UCS = 10 ft; "
        f"{out['nodes']} nodes): 2P/(pi D t) at the peak {out['splitting_over_ft']:.3f} ft, "
        f"{100 * out['near_diameter']:.0f} % of broken bonds within 0.1 D of the diameter, "
        f"modes {out['modes']}"
    )
    return out, res


def plot(results, bz, path) -> None:
    from matplotlib.collections import LineCollection

    from dvstatic import plot as dvplot
    from dvstatic.pictures import crack_faces

    fig, axes = dvplot.figure(len(results) + 2, 1, (4.0 * (len(results) + 2), 5.5))
    for ax, res in zip(axes[0], results, strict=False):
        mesh = res.model.mesh
        x = mesh.points
        ax.add_collection(LineCollection(x[mesh.boundary_edges], colors="k", linewidths=0.8))
        faces = crack_faces(res)[0]
        modes = {e.bond: e.mode for e in res.events}
        colour = {"tension": "tab:blue", "shear": "tab:green", "crushing": "tab:red"}
        ax.add_collection(
            LineCollection(
                faces, colors=[colour[modes[int(b)]] for b in res.broken], linewidths=1.2
            )
        )
        ax.set_aspect("equal")
        ax.autoscale()
        ax.set_title(f"{mesh.n_points} nodes: blue tension, green shear, red crushing", fontsize=8)
    ax = axes[0][len(results)]
    for res in results:
        d, p = res.curve()
        ax.plot(d, p, ".", ms=2, label=f"{res.model.mesh.n_points} nodes")
    ax.axhline(ucs(C, PHI), color="k", ls="--", lw=0.8, label="Mohr-Coulomb UCS")
    ax.set_xlabel("platen displacement")
    ax.set_ylabel("axial stress")
    ax.legend(fontsize=7)
    ax = axes[0][len(results) + 1]
    rows = bz["rows"]
    p = [r["p"] for r in rows]
    ax.plot(p, [r["peak"] for r in rows], "o", label="lattice peak")
    ax.plot(p, [r["first"] for r in rows], "x", label="first failure")
    pp = np.linspace(0, max(p), 20)
    ax.plot(pp, ucs(C, PHI) + bz["slope_mc"] * pp, "k--", lw=0.8, label="Mohr-Coulomb")
    ax.set_xlabel("held lateral pressure p")
    ax.set_ylabel("sigma_1 at failure")
    ax.legend(fontsize=7)
    print("wrote", dvplot.save(fig, path))


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    hs = (0.06,) if args.quick else (0.04, 0.02)
    data = {}
    data["uniaxial"], results = uniaxial(hs)
    data["pairs"] = pairs(hs[0])
    data["biaxial"] = biaxial(hs[0])
    data["brazilian"], _ = brazilian_mc(0.08 if args.quick else 0.04)
    plot(results, data["biaxial"], args.out / "compression.png")
    print("wrote", write_json(data, args.out / "compression.json"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
