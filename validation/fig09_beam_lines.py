"""Figure 9 of the paper: u_x and u_y along the beam (exp. 2), FE against DV and RV.

FE: P2 elements on a lattice triangulation (h = 0.1) refined twice (converged to
about 3e-5 in the mid-span deflection). DV and RV on lattice meshes of spacing h.
Lines: mid-height (y = 0.5) and bottom fibre (y = 0).

Usage::

    python validation/fig09_beam_lines.py            # h = 0.025
    python validation/fig09_beam_lines.py --quick    # h = 0.05, FE refined once

Writes ``validation/out/fig09.png`` and ``fig09.json`` and prints errors.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import (
    BEAM_H,
    BEAM_L,
    E_BEAM,
    NU_BEAM,
    PAPER,
    beam_problem,
    beam_reference,
    parser,
    write_json,
)


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--h", type=float, default=0.025)
    a = p.parse_args(argv)
    import dvstatic as dv
    from dvstatic import plot
    from dvstatic.post import interpolate

    h = 0.05 if a.quick else a.h
    ref = beam_reference(refine=1 if a.quick else 2)
    mesh = dv.mesh.rectangle(BEAM_L, BEAM_H, h, kind="lattice")
    sup, ld = beam_problem()
    xs = np.linspace(0.0, BEAM_L, 81)
    lines = {"mid": BEAM_H / 2, "bottom": 0.0}
    data = {
        "figure": "fig09",
        "h": h,
        "nodes": mesh.n_points,
        "fe_dof": ref.info.n_dof,
        "x": xs,
        "lines": {},
        "midspan": {},
    }
    fe_mid = ref.evaluate([[BEAM_L / 2, BEAM_H / 2]])[0]
    data["midspan"]["FE"] = fe_mid[1]
    sols = {
        kind: dv.solve(cls(mesh, E_BEAM, NU_BEAM, **PAPER), sup, ld)
        for kind, cls in (("DV", dv.DV), ("RV", dv.RV))
    }
    fig, axes = plot.figure(2, 2, (11, 7))
    for row, (name, y) in enumerate(lines.items()):
        pts = np.c_[xs, np.full_like(xs, y)]
        rec = {"y": y, "FE": ref.evaluate(pts)}
        for kind, sol in sols.items():
            rec[kind] = interpolate(mesh, sol.u, pts)
        for col, comp in enumerate(("u_x", "u_y")):
            ax = axes[row, col]
            ax.plot(xs, rec["FE"][:, col], "k-", lw=2, label="FE P2 (refined)")
            ax.plot(xs, rec["DV"][:, col], "o", ms=3, mfc="none", label="DV")
            ax.plot(xs, rec["RV"][:, col], "s", ms=3, mfc="none", label="RV")
            ax.set_title(f"{comp} along y = {y:g}")
            ax.set_xlabel("x")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        for kind in sols:
            d = rec[kind] - rec["FE"]
            rec[f"{kind}_rel_error_uy"] = float(
                np.linalg.norm(d[:, 1]) / np.linalg.norm(rec["FE"][:, 1])
            )
            rec[f"{kind}_rel_error_ux"] = float(
                np.linalg.norm(d[:, 0]) / max(np.linalg.norm(rec["FE"][:, 0]), 1e-300)
            )
        data["lines"][name] = rec
    for kind, sol in sols.items():
        data["midspan"][kind] = interpolate(mesh, sol.u, [[BEAM_L / 2, BEAM_H / 2]])[0, 1]
        data["midspan"][f"{kind}_rel_error"] = data["midspan"][kind] / fe_mid[1] - 1
    fig.suptitle(f"Fig. 9: beam, lattice h = {h} ({mesh.n_points} particles) against FE")
    write_json(data, a.out / "fig09.json")
    plot.save(fig, a.out / "fig09.png")
    print(f"fig09: beam, lattice h = {h}: mid-span u_y FE {fe_mid[1]:.6e}")
    print(
        f"{'model':>5} {'mid-span u_y':>13} {'error':>8} {'L2 u_y mid':>11} {'L2 u_y bottom':>14} "
        f"{'L2 u_x bottom':>14}"
    )
    for kind in sols:
        print(
            f"{kind:>5} {data['midspan'][kind]:13.6e} {data['midspan'][kind + '_rel_error']:+8.3%} "
            f"{data['lines']['mid'][kind + '_rel_error_uy']:11.3%} "
            f"{data['lines']['bottom'][kind + '_rel_error_uy']:14.3%} "
            f"{data['lines']['bottom'][kind + '_rel_error_ux']:14.3%}"
        )
    print(f"wrote {a.out / 'fig09.json'} and fig09.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
