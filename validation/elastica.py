"""Large-deflection benchmark: slender cantilever against the inextensible elastica.

Cantilever of length 10 and height 0.5 (lattice mesh, ``rows`` triangle layers through
the height), clamped at x = 0, a dead end load P spread uniformly over the free end
(traction -P/H), with P L^2/(E I) in {1, 2, 5, 10}, I = H^3 / 12 per unit thickness.

The reference is the inextensible elastica ``theta'' = alpha cos(theta)`` (arc length
normalised by L, theta(0) = 0, theta'(1) = 0), solved by shooting on theta'(0) with
scipy (``solve_ivp`` + ``brentq``), not a table.

Reported separately:

(a) geometric nonlinearity: the lattice's nonlinear tip deflection divided by its own
    small-load (linear) deflection at the same load, against the elastica's deflection
    divided by P L^3 / (3 E I); and the ratio of horizontal to vertical tip deflection;
(b) absolute error of the tip deflection against the elastica, which also contains the
    lattice's bending-stiffness error (the stiff surface layer of the paper's uniform
    k_n), against the number of rows.

Usage::

    python validation/elastica.py            # rows 8, 16, 32; DV and RV
    python validation/elastica.py --quick    # rows 16 only

Writes ``validation/out/elastica.json`` and prints tables.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from _common import parser
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

LENGTH, HEIGHT, E, NU = 10.0, 0.5, 1e5, 0.2
ALPHAS = (1.0, 2.0, 5.0, 10.0)


def elastica_tip(alpha: float) -> tuple[float, float]:
    """Tip deflections (vertical, horizontal) / L of the inextensible elastica.

    Parameters
    ----------
    alpha : float
        P L^2 / (E I) > 0.
    """

    def rhs(_s, y):
        return [y[1], alpha * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])]

    def end(k0):
        sol = solve_ivp(rhs, (0.0, 1.0), [0.0, -k0, 0.0, 0.0], rtol=1e-12, atol=1e-14)
        return sol.y[:, -1]

    k0 = brentq(lambda k: end(k)[1], 0.0, alpha, xtol=1e-14, rtol=1e-14)
    _, _, x_tip, y_tip = end(k0)
    return float(-y_tip), float(1.0 - x_tip)


def cantilever_mesh(rows: int):
    import dvstatic as dv

    h = HEIGHT / (rows * np.sqrt(3) / 2)
    return dv.mesh.rectangle(LENGTH, HEIGHT, h, kind="lattice")


def lattice_tip(model, alpha: float, nonlinear: bool, steps: int = 10) -> tuple[float, float]:
    """Mean tip deflections (vertical down, horizontal shortening) of the free end."""
    import dvstatic as dv

    inertia = HEIGHT**3 / 12.0
    load = alpha * E * inertia / LENGTH**2
    sol = dv.solve(
        model,
        dv.Fix("left"),
        dv.Traction("right", (0.0, -load / HEIGHT)),
        nonlinear=nonlinear,
        steps=steps,
    )
    tip = sol.u[model.mesh.part_nodes("right")].mean(axis=0)
    return float(-tip[1]), float(-tip[0]), sol


def run(rows_list, models=("DV", "RV"), alphas=ALPHAS) -> dict:
    import dvstatic as dv

    ref = {a: elastica_tip(a) for a in alphas}
    rows_out = []
    for rows in rows_list:
        mesh = cantilever_mesh(rows)
        for kind in models:
            model = (dv.DV if kind == "DV" else dv.RV)(mesh, E, NU)
            for a in alphas:
                t0 = time.perf_counter()
                v_lin, _, _ = lattice_tip(model, a, nonlinear=False)
                v, hz, sol = lattice_tip(model, a, nonlinear=True, steps=max(4, int(2 * a)))
                ev, eh = ref[a]
                rec = {
                    "rows": rows,
                    "nodes": mesh.n_points,
                    "model": kind,
                    "alpha": a,
                    "lattice_v_over_L": v / LENGTH,
                    "lattice_h_over_L": hz / LENGTH,
                    "lattice_linear_v_over_L": v_lin / LENGTH,
                    "elastica_v_over_L": ev,
                    "elastica_h_over_L": eh,
                    "nonlinear_ratio_lattice": v / v_lin,
                    "nonlinear_ratio_elastica": ev / (a / 3.0),
                    "h_over_v_lattice": hz / v,
                    "h_over_v_elastica": eh / ev,
                    "linear_stiffness_error": (a / 3.0) / (v_lin / LENGTH) - 1.0,
                    "newton_steps": len(sol.info.steps),
                    "newton_iterations": sol.info.iterations,
                    "seconds": time.perf_counter() - t0,
                }
                # the lattice behaves as an elastica with its own bending stiffness
                # EI_eff = P L^3 / (3 v_lin): alpha_eff = 3 v_lin / L
                a_eff = 3.0 * v_lin / LENGTH
                fv, fh = elastica_tip(a_eff)
                rec["alpha_eff"] = a_eff
                rec["nonlinear_ratio_elastica_eff"] = fv / (a_eff / 3.0)
                rec["h_over_v_elastica_eff"] = fh / fv
                rec["a_error_nominal"] = (
                    rec["nonlinear_ratio_lattice"] / rec["nonlinear_ratio_elastica"] - 1
                )
                rec["a_error"] = (
                    rec["nonlinear_ratio_lattice"] / rec["nonlinear_ratio_elastica_eff"] - 1
                )
                rec["h_over_v_error_nominal"] = (
                    rec["h_over_v_lattice"] / rec["h_over_v_elastica"] - 1
                )
                rec["h_over_v_error"] = rec["h_over_v_lattice"] / rec["h_over_v_elastica_eff"] - 1
                rec["b_error"] = rec["lattice_v_over_L"] / ev - 1
                rows_out.append(rec)
    return {
        "benchmark": "elastica",
        "length": LENGTH,
        "height": HEIGHT,
        "E": E,
        "nu": NU,
        "rows": rows_out,
    }


def print_table(data: dict) -> None:
    print("(a) geometric nonlinearity: lattice NL/linear tip deflection against the elastica's")
    print("    v / (P L^3 / 3 E I), at the nominal alpha and at the lattice's own alpha_eff")
    print("    = 3 v_lin / L (its bending stiffness); h/v = horizontal / vertical tip deflection")
    print("(b) absolute tip deflection error against the elastica (includes the stiffness error)")
    print(
        f"{'rows':>4} {'model':>5} {'alpha':>5} {'a_eff':>6} {'NL/lin':>7} {'elas':>7} "
        f"{'elas_eff':>8} {'(a)nom':>8} {'(a)eff':>8} {'h/v nom':>8} {'h/v eff':>8} "
        f"{'(b) err':>8} {'stiff':>7} {'steps':>5} {'its':>4}"
    )
    for r in data["rows"]:
        print(
            f"{r['rows']:4d} {r['model']:>5} {r['alpha']:5.0f} {r['alpha_eff']:6.3f} "
            f"{r['nonlinear_ratio_lattice']:7.4f} {r['nonlinear_ratio_elastica']:7.4f} "
            f"{r['nonlinear_ratio_elastica_eff']:8.4f} {r['a_error_nominal']:+8.2%} "
            f"{r['a_error']:+8.2%} {r['h_over_v_error_nominal']:+8.2%} "
            f"{r['h_over_v_error']:+8.2%} {r['b_error']:+8.2%} "
            f"{r['linear_stiffness_error']:+7.2%} {r['newton_steps']:5d} "
            f"{r['newton_iterations']:4d}"
        )


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--rows", type=int, nargs="+", default=[8, 16, 32])
    a = p.parse_args(argv)
    data = run([16] if a.quick else a.rows)
    print_table(data)
    path = a.out / "elastica.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=2))
    tmp.replace(path)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
