"""Figure 10 of the paper: uniaxial-stress error against the bond-length spread sigma_L.

Paper exp. 3: unit square, sigma_xx = -1, E = 1e5, nu = 0.2; meshes of growing
sigma_L = std(l) / mean(l) made by moving every vertex of a more regular mesh by a
random amount. Here: a lattice of spacing h moved by ``Mesh.perturbed`` with
amplitudes a h (a from 0 to 0.45; boundary nodes slide along their side; Delaunay
re-triangulation), several seeds per amplitude; relative L2 error of the nodal
displacement against the analytic solution. Meshes on which a model is unstable
(the solver refuses them) are counted, not plotted.

Usage::

    python validation/fig10_error_vs_sigma.py            # h = 0.02, 5 seeds
    python validation/fig10_error_vs_sigma.py --quick    # h = 0.05, 3 seeds

Writes ``validation/out/fig10.png`` and ``fig10.json`` and prints a table.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import E_BEAM, NU_BEAM, parser, rel_l2, uniaxial_exact, uniaxial_problem, write_json

AMPLITUDES = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)


def run(
    h: float, seeds: int, amplitudes=AMPLITUDES, models=("DV", "RV"), calibration: str = "paper"
) -> dict:
    import dvstatic as dv

    base = dv.mesh.rectangle(1.0, 1.0, h, kind="lattice")
    sup, ld = uniaxial_problem()
    rows = []
    for amp in amplitudes:
        for seed in range(seeds if amp > 0 else 1):
            mesh = base.perturbed(amp * h, seed=seed) if amp > 0 else base
            rec = {
                "amplitude": amp,
                "seed": seed,
                "sigma_L": mesh.edge_length_spread(),
                "nodes": mesh.n_points,
            }
            exact = uniaxial_exact(mesh.points)
            for kind in models:
                cls = dv.DV if kind == "DV" else dv.RV
                try:
                    sol = dv.solve(cls(mesh, E_BEAM, NU_BEAM, calibration=calibration), sup, ld)
                    rec[kind] = rel_l2(sol.u, exact)
                except dv.SolverError:
                    rec[kind] = None  # unstable lattice: refused by the solver
            rows.append(rec)
    summary = []
    for amp in amplitudes:
        sel = [r for r in rows if r["amplitude"] == amp]
        s = {"amplitude": amp, "sigma_L_mean": float(np.mean([r["sigma_L"] for r in sel]))}
        for kind in models:
            vals = [r[kind] for r in sel if r[kind] is not None]
            s[f"{kind}_mean"] = float(np.mean(vals)) if vals else None
            s[f"{kind}_std"] = float(np.std(vals)) if vals else None
            s[f"{kind}_min"] = float(np.min(vals)) if vals else None
            s[f"{kind}_max"] = float(np.max(vals)) if vals else None
            s[f"{kind}_unstable"] = sum(r[kind] is None for r in sel)
            s["n"] = len(sel)
        summary.append(s)
    return {"h": h, "seeds": seeds, "calibration": calibration, "rows": rows, "summary": summary}


def plot(data: dict, path) -> None:
    from dvstatic import plot as dvplot

    fig, axes = dvplot.figure(1, 1, (7, 4.5))
    ax = axes[0, 0]
    for kind, style in (("DV", "o"), ("RV", "s")):
        pts = [(r["sigma_L"], r[kind]) for r in data["rows"] if r[kind] is not None]
        if pts:
            x, y = np.array(pts).T
            ax.plot(x, 100 * y, style, ms=3, alpha=0.35)
        summ = [s for s in data["summary"] if s[f"{kind}_mean"] is not None]
        ax.errorbar(
            [s["sigma_L_mean"] for s in summ],
            [100 * s[f"{kind}_mean"] for s in summ],
            yerr=[100 * s[f"{kind}_std"] for s in summ],
            fmt=style + "-",
            capsize=3,
            label=f"{kind} (mean, std over seeds)",
        )
    ax.set_xlabel("sigma_L = std(l) / mean(l)")
    ax.set_ylabel("relative L2 displacement error [%]")
    ax.set_title(f"Fig. 10: uniaxial stress, h = {data['h']}, {data['calibration']} calibration")
    ax.grid(alpha=0.3)
    ax.legend()
    dvplot.save(fig, path)


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--h", type=float, default=0.02)
    p.add_argument("--seeds", type=int, default=5)
    a = p.parse_args(argv)
    data = run(0.05 if a.quick else a.h, 3 if a.quick else a.seeds)
    data["figure"] = "fig10"
    print(f"fig10: uniaxial error against sigma_L (h = {data['h']}, {data['seeds']} seeds)")
    print(
        f"{'amp/h':>6} {'sigma_L':>8} {'DV mean':>9} {'DV std':>8} {'DV unst':>7} "
        f"{'RV mean':>9} {'RV std':>8} {'RV unst':>7}"
    )
    for s in data["summary"]:

        def f(v):
            return f"{v:9.3%}" if v is not None else f"{'-':>9}"

        print(
            f"{s['amplitude']:6.2f} {s['sigma_L_mean']:8.4f} {f(s['DV_mean'])} "
            f"{f(s['DV_std'])[1:]} {s['DV_unstable']:>4}/{s['n']:<2} {f(s['RV_mean'])} "
            f"{f(s['RV_std'])[1:]} {s['RV_unstable']:>4}/{s['n']:<2}"
        )
    write_json(data, a.out / "fig10.json")
    plot(data, a.out / "fig10.png")
    print(f"wrote {a.out / 'fig10.json'} and fig10.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
