"""Figure 7 of the paper: the beam of exp. 2 (1 x 4, clamped ends, own weight).

Usage::

    python validation/fig07_beam_setup.py [--quick]

Writes ``validation/out/fig07.png`` and ``fig07.json`` (the set-up parameters).
"""

from __future__ import annotations

import sys

from _common import BEAM_H, BEAM_L, E_BEAM, NU_BEAM, parser, write_json


def main(argv: list[str] | None = None) -> int:
    a = parser(__doc__).parse_args(argv)
    from dvstatic import plot

    fig, axes = plot.figure(1, 1, (9, 3.6))
    plot.draw_beam_setup(axes[0, 0], BEAM_L, BEAM_H, body_force=-1.0)
    axes[0, 0].set_title(f"Fig. 7: exp. 2 beam, E = {E_BEAM:g}, nu = {NU_BEAM:g}, plane stress")
    data = {
        "figure": "fig07",
        "length": BEAM_L,
        "height": BEAM_H,
        "E": E_BEAM,
        "nu": NU_BEAM,
        "body_force": [0.0, -1.0],
        "supports": "both ends clamped (u = 0)",
    }
    write_json(data, a.out / "fig07.json")
    plot.save(fig, a.out / "fig07.png")
    print("fig07: beam 4 x 1 clamped at x = 0 and x = 4, body force (0, -1), E = 1e5, nu = 0.2")
    print(f"wrote {a.out / 'fig07.json'} and fig07.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
