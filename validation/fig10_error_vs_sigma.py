"""Figure 10 of the paper: uniaxial-stress error against the bond-length spread sigma_L.

Paper exp. 3: unit square, sigma_xx = -1, E = 1e5, nu = 0.2; meshes of growing
sigma_L = std(l) / mean(l) made by moving every vertex of a more regular mesh by a
random amount. Here: a lattice of spacing h moved by ``Mesh.perturbed`` with
amplitudes a h (a from 0 to 0.45; boundary nodes slide along their side; Delaunay
re-triangulation), several seeds per amplitude; relative L2 error of the nodal
displacement against the analytic solution. Meshes on which a model is unstable
(the solver refuses them) are counted, not plotted. The paper's model
(``calibration="paper", bonds="uniform", boundary_cells="lattice"``) beside the
defaults (no keywords: relaxed calibration on a periodic sample made by the mesh's
recipe, half springs on the surface, stabilised coupling, exact boundary cells), and
centroidal Voronoi (cvt) meshes of the same spacing.

Usage::

    python validation/fig10_error_vs_sigma.py            # h = 0.02, 5 seeds
    python validation/fig10_error_vs_sigma.py --quick    # h = 0.05, 3 seeds, fewer amplitudes

Writes ``validation/out/fig10.png`` and ``fig10.json`` and prints tables.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import (
    E_BEAM,
    NU_BEAM,
    PAPER,
    parser,
    rel_l2,
    uniaxial_exact,
    uniaxial_problem,
    write_json,
)

AMPLITUDES = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)


def _errors(mesh, models, config, sup, ld) -> dict:
    import dvstatic as dv

    exact = uniaxial_exact(mesh.points)
    kw = PAPER if config == "paper" else {}
    out = {}
    for kind in models:
        cls = dv.DV if kind == "DV" else dv.RV
        try:
            sol = dv.solve(cls(mesh, E_BEAM, NU_BEAM, **kw), sup, ld)
            out[kind] = rel_l2(sol.u, exact)
        except (dv.SolverError, ValueError):
            out[kind] = None  # unstable lattice (refused) or no calibration
    return out


def run(
    h: float,
    seeds: int,
    amplitudes=AMPLITUDES,
    models=("DV", "RV"),
    config: str = "paper",
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
            rec.update(_errors(mesh, models, config, sup, ld))
            rows.append(rec)
    cvt = []
    for seed in range(seeds):
        mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="cvt", seed=seed)
        rec = {"seed": seed, "sigma_L": mesh.edge_length_spread(), "nodes": mesh.n_points}
        rec.update(_errors(mesh, models, config, sup, ld))
        cvt.append(rec)
    summary = []
    for amp in amplitudes:
        sel = [r for r in rows if r["amplitude"] == amp]
        s = {
            "amplitude": amp,
            "sigma_L_mean": float(np.mean([r["sigma_L"] for r in sel])),
            "n": len(sel),
        }
        for kind in models:
            vals = [r[kind] for r in sel if r[kind] is not None]
            s[f"{kind}_mean"] = float(np.mean(vals)) if vals else None
            s[f"{kind}_std"] = float(np.std(vals)) if vals else None
            s[f"{kind}_min"] = float(np.min(vals)) if vals else None
            s[f"{kind}_max"] = float(np.max(vals)) if vals else None
            s[f"{kind}_unstable"] = sum(r[kind] is None for r in sel)
        summary.append(s)
    return {
        "h": h,
        "seeds": seeds,
        "config": config,
        "rows": rows,
        "summary": summary,
        "cvt": cvt,
    }


def plot(data: dict, path) -> None:
    from dvstatic import plot as dvplot

    runs = data["runs"]
    fig, axes = dvplot.figure(len(runs), 1, (7 * len(runs), 4.8))
    top = 0.0
    for ax, (cal, run_) in zip(axes[0], runs.items(), strict=True):
        for kind, style in (("DV", "o"), ("RV", "s")):
            pts = [(r["sigma_L"], r[kind]) for r in run_["rows"] if r[kind] is not None]
            if pts:
                x, y = np.array(pts).T
                ax.plot(x, 100 * y, style, ms=3, alpha=0.35)
                top = max(top, 100 * y.max())
            summ = [s for s in run_["summary"] if s[f"{kind}_mean"] is not None]
            ax.errorbar(
                [s["sigma_L_mean"] for s in summ],
                [100 * s[f"{kind}_mean"] for s in summ],
                yerr=[100 * s[f"{kind}_std"] for s in summ],
                fmt=style + "-",
                capsize=3,
                label=f"{kind} perturbed lattice (mean, std)",
            )
            cv = [(r["sigma_L"], r[kind]) for r in run_["cvt"] if r[kind] is not None]
            if cv:
                x, y = np.array(cv).T
                ax.plot(x, 100 * y, style, ms=9, mfc="none", mew=2, label=f"{kind} cvt mesh")
        ax.set_xlabel("sigma_L = std(l) / mean(l)")
        ax.set_ylabel("relative L2 displacement error [%]")
        ax.set_title("the paper's model" if cal == "paper" else "defaults (no keywords)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    for ax in axes[0]:
        ax.set_ylim(0, 1.05 * top)
    fig.suptitle(f"Fig. 10: uniaxial stress, h = {data['h']}")
    dvplot.save(fig, path)


def _fmt(v) -> str:
    return f"{v:9.3%}" if v is not None else f"{'-':>9}"


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--h", type=float, default=0.02)
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument(
        "--configs", nargs="+", default=["paper", "default"], choices=["paper", "default"]
    )
    a = p.parse_args(argv)
    h, seeds = (0.05, 3) if a.quick else (a.h, a.seeds)
    amps = (0.0, 0.1, 0.2, 0.3, 0.4) if a.quick else AMPLITUDES
    data = {"figure": "fig10", "h": h, "seeds": seeds, "runs": {}}
    for cal in a.configs:
        run_ = run(h, seeds, amps, config=cal)
        data["runs"][cal] = run_
        print(
            f"fig10: uniaxial error against sigma_L (h = {h}, {seeds} seeds, {cal} "
            "configuration; failed = unstable or not calibrated)"
        )
        print(
            f"{'amp/h':>6} {'sigma_L':>8} {'DV mean':>9} {'DV std':>8} {'DV fail':>7} "
            f"{'RV mean':>9} {'RV std':>8} {'RV fail':>7}"
        )
        for s in run_["summary"]:
            print(
                f"{s['amplitude']:6.2f} {s['sigma_L_mean']:8.4f} {_fmt(s['DV_mean'])} "
                f"{_fmt(s['DV_std'])[1:]} {s['DV_unstable']:>4}/{s['n']:<2} "
                f"{_fmt(s['RV_mean'])} {_fmt(s['RV_std'])[1:]} {s['RV_unstable']:>4}/{s['n']:<2}"
            )
        for r in run_["cvt"]:
            print(f"{'cvt':>6} {r['sigma_L']:8.4f} {_fmt(r['DV'])} {'':>16} {_fmt(r['RV'])}")
    # the first configuration's results also at the top level (summary, rows, cvt)
    for key in ("rows", "summary", "cvt"):
        data[key] = data["runs"][a.configs[0]][key]
    write_json(data, a.out / "fig10.json")
    plot(data, a.out / "fig10.png")
    print(f"wrote {a.out / 'fig10.json'} and fig10.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
