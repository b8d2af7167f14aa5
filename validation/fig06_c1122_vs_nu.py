"""Figure 6 of the paper: C1122 recovered at small strain against nu, DV and RV.

Paper exp. 1: homogeneous (affine) strain imposed on every node of a triangulation
of 1e5 vertices (E = 1e7); the moduli are recovered from the bond-force stress.
Here: a periodic random triangulation, nu from -0.5 to 0.45, the linearised model
(exact small-strain limit, ``dv.elastic_tensor``), against plane stress.

Usage::

    python validation/fig06_c1122_vs_nu.py           # 1e5 vertices
    python validation/fig06_c1122_vs_nu.py --quick   # 2e4 vertices

Writes ``validation/out/fig06.png`` and ``fig06.json`` and prints a table.
"""

from __future__ import annotations

import sys

from _common import moduli_vs_nu, parser, plot_moduli, print_moduli, write_json


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--points", type=int, default=100_000)
    a = p.parse_args(argv)
    data = moduli_vs_nu(20_000 if a.quick else a.points)
    data["figure"] = "fig06"
    print(f"fig06: C1122 against nu ({data['n_points']} vertices)")
    print_moduli(data, "C1122")
    write_json(data, a.out / "fig06.json")
    plot_moduli(data, "C1122", a.out / "fig06.png", "Fig. 6: C1122 against nu")
    print(f"wrote {a.out / 'fig06.json'} and fig06.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
