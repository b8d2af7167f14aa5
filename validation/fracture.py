"""Fracture by bond breaking (dv.fracture): first break under uniform tension, the
Brazilian disc over 5 seeds, Petersson's notched beam on seven DV meshes of two kinds
(and one RV) against a cohesive-crack reference, and events per second with
factorisation updates against refactorising at every event. Prints tables, writes
fracture.json and fracture.png.

Brazilian disc (CVT meshes): D = 2, t = 1, E = 3e4, nu = 0.2, ft = 3, loading strips
0.1 D wide, Weibull strengths (m = 24, Bazant's value for concrete; correlation length
0.1 D), saw-tooth softening with gf = 5e-4 (characteristic length E gf / ft^2 = 0.8 D);
also brittle bonds. Reported: 2 P / (pi D t) at the peak over ft, and the share of
broken bonds within 0.1 D of the loaded diameter.

Notched beam (Petersson 1981, as in Rots 1988): span 2000 mm, depth 200 mm, thickness
50 mm, notch 100 mm, E = 30 GPa, nu = 0.2, ft = 3.33 MPa, Gf = 0.124 N/mm, midspan
deflection prescribed. Reference: the fictitious-crack (cohesive) model with linear
softening on the ligament, computed here on a P2 FE half beam (validation/_cohesive.py;
peak 0.853 kN, Petersson's tests peaked at about 0.8 kN). Meshes: the default kind
(jittered lattice rows), h = 14 / 10 / 7 / 5 mm, and CVT meshes, h = 10 / 7 / 5 mm.
"""

from __future__ import annotations

import time

import numpy as np
from _cohesive import petersson_cohesive
from _common import parser, write_json

import dvstatic as dv

E, NU, FT = 3e4, 0.2, 3.0
BEAM = dict(L=2000.0, D=200.0, a=100.0, E=30000.0, nu=0.2, t=50.0, ft=3.33, gf=0.124)


def direct_tension(model_cls, h: float = 0.05) -> float:
    """First break of a 2 x 1 plate pulled by uniform tractions, as sxx / ft."""
    mesh = dv.mesh.rectangle(2.0, 1.0, h, seed=1)
    sup = [dv.Fix(at=(0, 0), x=0, y=0), dv.Fix(at=(2, 0), y=0)]
    loads = [dv.Traction("right", (1.0, 0.0)), dv.Traction("left", (-1.0, 0.0))]
    res = dv.fracture(model_cls(mesh, E=E, nu=NU), sup, loads, ft=FT, max_events=1)
    return res.events[0].load_factor / FT


def brazilian(h: float, seed: int, gf=5e-4, weibull_m: float = 24.0, model=dv.DV, **kw):
    """One Brazilian test; returns the result and the load of one strip per load factor."""
    mesh = dv.mesh.disc(1.0, h, seed=seed, kind="cvt")
    x, be = mesh.points, mesh.boundary_edges
    strip = np.all(np.abs(x[be, 0]) < 0.1, axis=1)
    top = be[strip & np.all(x[be, 1] > 0, axis=1)]
    bottom = be[strip & np.all(x[be, 1] < 0, axis=1)]
    loads = [dv.Pressure(top, 1.0), dv.Pressure(bottom, 1.0)]
    sup = [
        dv.Fix(at=(0, 1), x=0),
        dv.Fix(at=(0, -1), x=0),
        dv.Fix(at=(1, 0), y=0),
        dv.Fix(at=(-1, 0), y=0),
    ]
    weibull = dv.Weibull(weibull_m, 0.2, seed) if weibull_m else None
    res = dv.fracture(model(mesh, E=E, nu=NU), sup, loads, ft=FT, gf=gf, weibull=weibull, **kw)
    p_strip = abs(dv.problem.load_vector(mesh, [loads[0]]).reshape(-1, 2).sum(axis=0)[1])
    return res, p_strip


def brazilian_table(h: float, seeds: int, gf) -> dict:
    rows = []
    for seed in range(seeds):
        t0 = time.perf_counter()
        res, p_strip = brazilian(h, seed, gf=gf, max_events=6000, stop_load_ratio=0.3)
        mesh = res.model.mesh
        p = res.peak.load_factor * p_strip
        mid = mesh.points[mesh.topology.bonds[res.broken]].mean(axis=1)
        rows.append(
            {
                "seed": seed,
                "nodes": mesh.n_points,
                "events": len(res.events),
                "broken": len(res.broken),
                "splitting_over_ft": 2 * p / (np.pi * 2.0) / FT,
                "near_diameter": float(np.mean(np.abs(mid[:, 0]) < 0.2)),
                "max_residual": res.stats.max_residual,
                "seconds": time.perf_counter() - t0,
            }
        )
        r = rows[-1]
        print(
            f"  seed {seed}: {r['nodes']} nodes, {r['events']} events, {r['broken']} broken, "
            f"2P/(pi D t)/ft = {r['splitting_over_ft']:.3f}, broken within 0.1 D of the "
            f"diameter {r['near_diameter']:.0%}, max residual {r['max_residual']:.1e}"
        )
    s = np.array([r["splitting_over_ft"] for r in rows])
    print(f"  2P/(pi D t)/ft: mean {s.mean():.3f}, min {s.min():.3f}, max {s.max():.3f}")
    return {"h": h, "gf": gf, "rows": rows}


def petersson_run(h: float, model=dv.DV, kind: str = "jittered", **kw):
    b = BEAM
    L, D, a, wn = b["L"], b["D"], b["a"], 4.0
    verts = [
        (0, 0),
        (L / 2 - wn / 2, 0),
        (L / 2 - wn / 2, a),
        (L / 2 + wn / 2, a),
        (L / 2 + wn / 2, 0),
        (L, 0),
        (L, D),
        (0, D),
    ]
    mesh = dv.mesh.polygon(verts, h, seed=0, kind=kind)
    # the loading point: the top node nearest midspan (a mesh of lattice rows need not
    # have one exactly there)
    top = int(np.argmin(np.hypot(mesh.points[:, 0] - L / 2, mesh.points[:, 1] - D)))
    sup = [dv.Fix(at=(0, 0), x=0, y=0), dv.Fix(at=(L, 0), y=0), dv.Fix([top], y=-1.0)]
    lattice = model(mesh, E=b["E"], nu=b["nu"], thickness=b["t"])
    return dv.fracture(lattice, sup, ft=b["ft"], gf=b["gf"], **kw)


def petersson(h: float, model=dv.DV, kind: str = "jittered") -> dict:
    b = BEAM
    D, a = b["D"], b["a"]
    t0 = time.perf_counter()
    res = petersson_run(h, model, kind, max_events=50_000, stop_load_ratio=0.02)
    mesh = res.model.mesh
    d, p = res.curve()
    target = b["gf"] * (D - a) * b["t"]
    out = {
        "model": model.__name__,
        "kind": kind,
        "h": h,
        "nodes": mesh.n_points,
        "events": len(res.events),
        "peak_kN": res.peak.load / 1e3,
        "peak_deflection": res.peak.control_displacement,
        "dissipated_Nmm": res.dissipated,
        "gf_ligament_Nmm": target,
        "stop": res.message,
        "max_residual": res.stats.max_residual,
        "seconds": time.perf_counter() - t0,
        "curve": {"deflection": d.tolist(), "load": p.tolist()},
    }
    print(
        f"  {model.__name__} {kind} h = {h:g} mm: {out['nodes']} nodes, "
        f"{out['events']} events, peak {out['peak_kN']:.3f} kN at "
        f"{out['peak_deflection']:.3f} mm, dissipated {out['dissipated_Nmm']:.0f} N mm = "
        f"{out['dissipated_Nmm'] / target:.2f} Gf x ligament x t, "
        f"max residual {out['max_residual']:.1e}"
    )
    return out


def speed(h: float, events: int, ref_events: int) -> dict:
    """Events per second on the notched beam (the first events of the softening run):
    factorisation updates (max_rank 240) against refactorising at every event."""
    out = {}
    for name, rank, n in (("updates", 240, events), ("refactor", 0, ref_events)):
        res = petersson_run(h, max_events=n, max_rank=rank, stop_load_ratio=0.0)
        out[name] = {
            "nodes": res.model.mesh.n_points,
            "events": len(res.events),
            "events_per_second": res.stats.events_per_second,
            "factorisations": res.stats.factorisations,
            "factorisation_seconds": res.seconds.factorisation,
            "bonds": [e.bond for e in res.events],
        }
        print(
            f"  {name:8s}: {out[name]['nodes']} nodes, {len(res.events)} events, "
            f"{out[name]['events_per_second']:.2f} events/s, "
            f"{out[name]['factorisations']} factorisations "
            f"({out[name]['factorisation_seconds']:.1f} s)"
        )
    m = min(len(out["updates"]["bonds"]), len(out["refactor"]["bonds"]))
    out["same_sequence"] = out["updates"]["bonds"][:m] == out["refactor"]["bonds"][:m]
    out["speedup"] = out["updates"]["events_per_second"] / out["refactor"]["events_per_second"]
    print(f"  same first {m} events: {out['same_sequence']}, speed-up {out['speedup']:.1f}x")
    return out


def plot(data: dict, path) -> None:
    from dvstatic import plot as dvplot

    fig, axes = dvplot.figure(2, 1, (13.0, 4.8))
    ref = data["cohesive"]
    for ax, kind in zip(axes[0], ("jittered", "cvt"), strict=True):
        ax.plot(
            ref["deflection"],
            np.array(ref["load"]) / 1e3,
            "k-",
            lw=2.5,
            alpha=0.5,
            label=f"cohesive crack, P2 FE (peak {ref['peak_N'] / 1e3:.3f} kN)",
        )
        for run in data["petersson"]:
            if run["kind"] != kind:
                continue
            c = run["curve"]
            ax.plot(
                c["deflection"],
                np.array(c["load"]) / 1e3,
                lw=0.8,
                label=f"{run['model']} h = {run['h']:g} mm, {run['nodes']} nodes "
                f"(peak {run['peak_kN']:.3f} kN, "
                f"{run['dissipated_Nmm'] / run['gf_ligament_Nmm']:.2f} Gf)",
            )
        ax.set_xlim(0, 1.5)
        ax.set_ylim(0, None)
        ax.set_xlabel("midspan deflection (mm)")
        ax.set_ylabel("load (kN)")
        ax.set_title(f"Petersson's notched beam, {kind} meshes: lattice SLA vs cohesive crack")
        ax.legend(fontsize=7)
    print("wrote", dvplot.save(fig, path))


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    data = {}
    data["direct_tension"] = {m.__name__: direct_tension(m) for m in (dv.DV, dv.RV)}
    print(
        "direct tension, first break sxx / ft:",
        ", ".join(f"{k} {v:.4f}" for k, v in data["direct_tension"].items()),
    )
    h_disc, seeds = (0.08, 2) if args.quick else (0.04, 5)
    print(f"Brazilian disc, saw-tooth softening (h = {h_disc})")
    data["brazilian"] = brazilian_table(h_disc, seeds, 5e-4)
    print(f"Brazilian disc, brittle bonds (h = {h_disc})")
    data["brazilian_brittle"] = brazilian_table(h_disc, seeds, None)
    print("Petersson's notched beam")
    data["cohesive"] = petersson_cohesive(**BEAM, h_near=4.0 if args.quick else 2.0)
    print(
        f"  cohesive crack (P2 FE, {data['cohesive']['ligament_nodes']} ligament nodes): "
        f"peak {data['cohesive']['peak_N'] / 1e3:.3f} kN at "
        f"{data['cohesive']['peak_deflection']:.3f} mm"
    )
    runs = [(20.0, dv.DV, "jittered")]
    if not args.quick:
        runs = [(h, dv.DV, "jittered") for h in (14.0, 10.0, 7.0, 5.0)]
        runs += [(h, dv.DV, "cvt") for h in (10.0, 7.0, 5.0)] + [(10.0, dv.RV, "jittered")]
    data["petersson"] = [petersson(*run) for run in runs]
    print("events per second (notched beam, the first events)")
    runs = ((20.0, 60, 10),) if args.quick else ((7.0, 300, 20), (2.2, 100, 3))
    data["speed"] = [speed(*s) for s in runs]
    plot(data, args.out / "fracture.png")
    print("wrote", write_json(data, args.out / "fracture.json"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
