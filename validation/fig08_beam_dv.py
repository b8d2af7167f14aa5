"""Figure 8 of the paper: the DV solution of the beam (exp. 2), deformed and coloured.

Usage::

    python validation/fig08_beam_dv.py            # lattice h = 0.025
    python validation/fig08_beam_dv.py --quick    # h = 0.1

Writes ``validation/out/fig08.png`` and ``fig08.json`` and prints a summary.
"""

from __future__ import annotations

import sys

import numpy as np
from _common import BEAM_H, BEAM_L, E_BEAM, NU_BEAM, PAPER, beam_problem, parser, write_json


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--h", type=float, default=0.025)
    a = p.parse_args(argv)
    import dvstatic as dv
    from dvstatic import plot
    from dvstatic.post import interpolate

    h = 0.1 if a.quick else a.h
    mesh = dv.mesh.rectangle(BEAM_L, BEAM_H, h, kind="lattice")
    sup, ld = beam_problem()
    sol = dv.solve(dv.DV(mesh, E_BEAM, NU_BEAM, **PAPER), sup, ld)
    umag = np.hypot(sol.u[:, 0], sol.u[:, 1])
    scale = 0.1 * BEAM_H / umag.max()
    fig, axes = plot.figure(1, 1, (10, 3.6))
    plot.draw_deformed(axes[0, 0], mesh, sol.u, scale=scale, label="|u|")
    axes[0, 0].set_title(f"Fig. 8: DV beam, deformation x {scale:.0f}, {mesh.n_points} particles")
    mid = interpolate(mesh, sol.u, [[BEAM_L / 2, BEAM_H / 2]])[0]
    data = {
        "figure": "fig08",
        "h": h,
        "nodes": mesh.n_points,
        "scale": scale,
        "max_displacement": float(umag.max()),
        "midspan_uy": float(mid[1]),
        "k_n": sol.model.k_n,
        "nu_m": sol.model.nu_m,
        "solver": sol.info.solver,
        "seconds": sol.info.seconds.total,
    }
    write_json(data, a.out / "fig08.json")
    plot.save(fig, a.out / "fig08.png")
    print(
        f"fig08: DV beam, h = {h}, {mesh.n_points} particles: max |u| = {umag.max():.5e}, "
        f"mid-span u_y = {mid[1]:.5e}, solved in {data['seconds']:.2f} s"
    )
    print(f"wrote {a.out / 'fig08.json'} and fig08.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
