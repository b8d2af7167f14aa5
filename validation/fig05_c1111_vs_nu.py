"""Figure 5 of the paper: C1111 recovered at small strain against nu, DV and RV.

Paper exp. 1: homogeneous (affine) strain imposed on every node of a triangulation
of 1e5 vertices (E = 1e7); the moduli are recovered from the bond-force stress.
Here: a periodic random triangulation, nu from -0.5 to 0.45, the linearised model
(exact small-strain limit, ``dv.elastic_tensor``), against plane stress.

Usage::

    python validation/fig05_c1111_vs_nu.py           # 1e5 vertices
    python validation/fig05_c1111_vs_nu.py --quick   # 2e4 vertices

Writes ``validation/out/fig05.png`` and ``fig05.json`` and prints a table.
"""

from __future__ import annotations

import sys

from _common import moduli_vs_nu, parser, plot_moduli, print_moduli, write_json


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--points", type=int, default=100_000)
    a = p.parse_args(argv)
    data = moduli_vs_nu(20_000 if a.quick else a.points)
    data["figure"] = "fig05"
    print(f"fig05: C1111 against nu ({data['n_points']} vertices)")
    print_moduli(data, "C1111")
    write_json(data, a.out / "fig05.json")
    plot_moduli(data, "C1111", a.out / "fig05.png", "Fig. 5: C1111 against nu")
    print(f"wrote {a.out / 'fig05.json'} and fig05.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
