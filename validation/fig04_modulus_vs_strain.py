"""Figure 4 of the paper: C1111 recovered at growing strain magnitude, DV and RV.

Paper exp. 1: a triangulation of 1e5 vertices of the unit square, E = 1e7, nu = 0.2;
the same homogeneous strain is imposed on every node and the stress measured from
the bond forces. Here: a periodic random triangulation (no boundary), uniaxial strain
``eps = diag(s, 0)`` with s from +-1e-4 to +-0.3, bond forces on the deformed geometry
(``dv.homogenize``: exact DV/RV kinematics), mean Cauchy stress, and
``C1111 = sigma11 / eps11`` against the plane-stress value ``E / (1 - nu^2)``.

Usage::

    python validation/fig04_modulus_vs_strain.py            # 1e5 vertices
    python validation/fig04_modulus_vs_strain.py --quick    # 1e4 vertices

Writes ``validation/out/fig04.png`` and ``fig04.json`` and prints a table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from _common import PAPER, parser

E, NU = 1e7, 0.2


def run(n_points: int, seed: int = 0, n_strains: int = 12) -> dict:
    import dvstatic as dv

    mesh = dv.mesh.periodic_square(n_points, kind="random", seed=seed)
    target = E / (1 - NU**2)
    mags = np.logspace(-4, np.log10(0.3), n_strains)
    strains = np.concatenate([-mags[::-1], mags])
    out = {
        "figure": "fig04",
        "n_points": mesh.n_points,
        "sigma_L": mesh.edge_length_spread(),
        "E": E,
        "nu": NU,
        "target_C1111": target,
        "strain": strains.tolist(),
        "models": {},
    }
    for cls in (dv.DV, dv.RV):
        model = cls(mesh, E, NU, **PAPER)  # the paper's model
        c_small = float(dv.elastic_tensor(model)[0, 0])
        c = []
        for s in strains:
            sig = dv.homogenize(model, np.array([[s, 0.0], [0.0, 0.0]]))
            c.append(float(sig[0, 0] / s))
        c = np.array(c)
        out["models"][cls.kind] = {
            "C1111": c.tolist(),
            "relative_error": (c / target - 1).tolist(),
            "C1111_small_strain_linear": c_small,
            "k_n": model.k_n,
            "nu_m": model.nu_m,
        }
    return out


def plot(data: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.array(data["strain"])
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for kind, style in (("DV", "o-"), ("RV", "s--")):
        c = np.array(data["models"][kind]["C1111"])
        for ax, sel in ((axes[0], s < 0), (axes[1], s > 0)):
            ax.semilogx(np.abs(s[sel]), c[sel] / 1e7, style, label=kind, ms=4)
    for ax, title in zip(axes, ("compression", "tension"), strict=True):
        ax.axhline(data["target_C1111"] / 1e7, color="k", lw=1, label="plane stress E/(1-nu^2)")
        ax.set_xlabel("|eps11|")
        ax.set_ylabel("C1111 = sigma11/eps11  [1e7]")
        ax.set_title(f"uniaxial strain, {title}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle(f"Fig. 4: C1111 against strain ({data['n_points']} vertices, periodic random)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = parser(__doc__)
    p.add_argument("--points", type=int, default=100_000)
    a = p.parse_args(argv)
    data = run(10_000 if a.quick else a.points)
    a.out.mkdir(parents=True, exist_ok=True)
    print(
        f"fig04: C1111 / target - 1 ({data['n_points']} vertices, target "
        f"{data['target_C1111']:.6g})"
    )
    print(f"{'eps11':>10} {'DV':>10} {'RV':>10}")
    for i, s in enumerate(data["strain"]):
        print(
            f"{s:10.2e} {data['models']['DV']['relative_error'][i]:+10.4%} "
            f"{data['models']['RV']['relative_error'][i]:+10.4%}"
        )
    tmp = a.out / "fig04.json.tmp"
    tmp.write_text(json.dumps(data, indent=2))
    tmp.replace(a.out / "fig04.json")
    plot(data, a.out / "fig04.png")
    print(f"wrote {a.out / 'fig04.json'} and fig04.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
