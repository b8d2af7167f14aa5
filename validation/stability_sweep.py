"""Stability stress test: where do DV and RV solve, and where are they unstable?

Uniaxial stress (paper exp. 3 set-up: unit square, rollers, traction -1, E = 1e5) for
nu in {-0.9, ..., 0.9} x mesh {lattice, cvt, sigma_L 0.1, 0.2, 0.3, random} x model
{DV, RV} x configuration {the paper's model (``calibration="paper", bonds="uniform",
boundary_cells="lattice"``), the defaults (relaxed calibration, stabilised coupling,
half springs on the surface, exact boundary cells)}.
For every case the admissible nu range of that mesh and these supports is computed
(``dv.stability``); a stable case is solved (residual <= 1e-10 checked) and its error
against the analytic solution reported; an unstable one is reported with its
admissible range; "no calibration" where the lattice cannot reach nu.

Usage::

    python validation/stability_sweep.py            # h = 0.05, every case
    python validation/stability_sweep.py --quick    # h = 0.1, a subset

Writes ``validation/out/stability_sweep.png`` (heat maps) and ``.json``.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import E_BEAM, PAPER, parser, rel_l2, uniaxial_problem, write_json

NUS = (-0.9, -0.7, -0.5, -0.3, 0.0, 0.2, 0.33, 0.45, 0.6, 0.8, 0.9)
MESHES = ("lattice", "cvt", "sigma 0.1", "sigma 0.2", "sigma 0.3", "random")


def make_mesh(name: str, h: float):
    import dvstatic as dv

    if name in ("lattice", "cvt", "random"):
        return dv.mesh.rectangle(1.0, 1.0, h, kind=name, seed=1)
    base = dv.mesh.rectangle(1.0, 1.0, h, kind="lattice")
    return dv.mesh.with_spread(base, float(name.split()[1]), seed=1)


CONFIGS = ("paper", "default")


def run(h: float, nus, meshes) -> dict:
    import dvstatic as dv

    sup, ld = uniaxial_problem()
    cases = []
    for mname in meshes:
        mesh = make_mesh(mname, h)
        for kind, cls in (("DV", dv.DV), ("RV", dv.RV)):
            for cal in CONFIGS:
                for nu in nus:
                    rec = {
                        "mesh": mname,
                        "sigma_L": mesh.edge_length_spread(),
                        "model": kind,
                        "calibration": cal,
                        "nu": nu,
                        "nodes": mesh.n_points,
                    }
                    try:
                        model = cls(mesh, E_BEAM, nu, **(PAPER if cal == "paper" else {}))
                    except ValueError as exc:
                        rec.update(status="no calibration", reason=str(exc))
                        cases.append(rec)
                        continue
                    rep = dv.stability(model, sup)
                    rec.update(
                        nu_m=model.nu_m,
                        nu_range=rep.nu_range,
                        nu_m_range=rep.nu_m_range,
                        margin=rep.margin,
                        stability_seconds=rep.seconds,
                    )
                    if not rep.stable:
                        rec["status"] = "unstable"
                    else:
                        sol = dv.solve(model, sup, ld, solver="direct")
                        exact = np.c_[-mesh.points[:, 0] / E_BEAM, nu * mesh.points[:, 1] / E_BEAM]
                        rec.update(
                            status="solved",
                            error=rel_l2(sol.u, exact),
                            residual=sol.info.residual,
                        )
                        assert sol.info.residual <= 1e-10
                    cases.append(rec)
    return {
        "h": h,
        "nus": list(nus),
        "meshes": list(meshes),
        "cases": cases,
    }


def plot(data: dict, path) -> None:
    from matplotlib.colors import LogNorm

    from dvstatic import plot as dvplot

    fig, axes = dvplot.figure(2, 2, (13, 8))
    nus, meshes = data["nus"], data["meshes"]
    for i, kind in enumerate(("DV", "RV")):
        for j, cal in enumerate(CONFIGS):
            ax = axes[i, j]
            grid = np.full((len(meshes), len(nus)), np.nan)
            for c in data["cases"]:
                if c["model"] == kind and c["calibration"] == cal and c["status"] == "solved":
                    grid[meshes.index(c["mesh"]), nus.index(c["nu"])] = max(c["error"], 1e-4)
            im = ax.imshow(100 * grid, cmap="viridis", norm=LogNorm(0.1, 100), aspect="auto")
            for c in data["cases"]:
                if c["model"] != kind or c["calibration"] != cal:
                    continue
                r, q = meshes.index(c["mesh"]), nus.index(c["nu"])
                if c["status"] == "solved":
                    txt = f"{100 * c['error']:.1f}"
                else:
                    txt = "U" if c["status"] == "unstable" else "-"
                ax.text(
                    q,
                    r,
                    txt,
                    ha="center",
                    va="center",
                    fontsize=7,
                    color="w" if c["status"] == "solved" else "r",
                )
            ax.set_xticks(range(len(nus)), [f"{v:g}" for v in nus])
            ax.set_yticks(range(len(meshes)), meshes)
            ax.set_xlabel("nu")
            what = "the paper's model" if cal == "paper" else "defaults"
            ax.set_title(f"{kind}, {what}: L2 error [%] (U unstable, - none)")
            dvplot.pyplot().colorbar(im, ax=ax, shrink=0.8)
    fig.suptitle(f"Stability sweep, uniaxial stress, h = {data['h']}")
    dvplot.save(fig, path)


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--h", type=float, default=0.05)
    a = p.parse_args(argv)
    if a.quick:
        data = run(0.1, (-0.5, 0.2, 0.45, 0.8), ("lattice", "sigma 0.2", "random"))
    else:
        data = run(a.h, NUS, MESHES)
    data["figure"] = "stability_sweep"
    print(f"stability sweep (h = {data['h']}): status / error / admissible nu range")
    for c in data["cases"]:
        if c["status"] == "solved":
            txt = f"solved, error {c['error']:7.3%}"
        elif c["status"] == "unstable":
            txt = f"UNSTABLE, admissible nu in ({c['nu_range'][0]:.3f}, {c['nu_range'][1]:.3f})"
        else:
            txt = "no calibration"
        print(f"{c['mesh']:>10} {c['model']} {c['calibration']:>7} nu={c['nu']:5.2f}: {txt}")
    write_json(data, a.out / "stability_sweep.json")
    plot(data, a.out / "stability_sweep.png")
    print(f"wrote {a.out / 'stability_sweep.json'} and stability_sweep.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
