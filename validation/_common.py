"""Shared set-ups and output helpers of the validation scripts."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent / "out"

#: the paper's model (the figure scripts reproduce the paper's method, not the defaults)
PAPER = {"method": "paper"}

# paper exp. 2 (beam) and exp. 3 (uniaxial) material
E_BEAM, NU_BEAM = 1e5, 0.2
BEAM_L, BEAM_H = 4.0, 1.0


#: where ``--quick`` runs write (ignored by git): the committed full-size results in
#: ``OUT`` change only when a full-size run is made on purpose
QUICK_OUT = OUT / "quick"


class _Parser(argparse.ArgumentParser):
    def parse_args(self, args=None, namespace=None):
        a = super().parse_args(args, namespace)
        if a.out is None:
            a.out = QUICK_OUT if a.quick else OUT
        return a


def parser(doc: str) -> argparse.ArgumentParser:
    """The scripts' command line: ``--quick`` (CI size) and ``--out`` (a folder; default
    ``validation/out``, or ``validation/out/quick`` with ``--quick``)."""
    p = _Parser(description=doc, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--quick", action="store_true", help="CI size (seconds)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default validation/out; validation/out/quick with --quick)",
    )
    return p


def write_json(data: dict, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, default=_jsonable))
    tmp.replace(path)
    return path


def _jsonable(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def beam_problem():
    """Paper exp. 2: clamped at both ends, own weight (body force -1 per area)."""
    import dvstatic as dv

    return [dv.Fix("left"), dv.Fix("right")], [dv.BodyForce((0.0, -1.0))]


def beam_reference(refine: int = 2):
    """P2 FE on a refined lattice triangulation of the beam (converged to ~3e-5)."""
    import dvstatic as dv
    from dvstatic import fem

    sup, ld = beam_problem()
    mesh = dv.mesh.rectangle(BEAM_L, BEAM_H, 0.1, kind="lattice")
    return fem.solve(mesh, E_BEAM, NU_BEAM, sup, ld, order=2, refine=refine)


def uniaxial_problem():
    """Paper exp. 3: unit square, rollers left and bottom, traction -1 on the right."""
    import dvstatic as dv

    return [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)], [dv.Traction("right", (-1.0, 0.0))]


def uniaxial_exact(points: np.ndarray, E: float = E_BEAM, nu: float = NU_BEAM) -> np.ndarray:
    return np.c_[-points[:, 0] / E, nu * points[:, 1] / E]


def rel_l2(u: np.ndarray, ref: np.ndarray) -> float:
    return float(np.linalg.norm(u - ref) / np.linalg.norm(ref))


NUS = (-0.5, -0.4, -0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3, 0.33, 0.4, 0.45)


def moduli_vs_nu(n_points: int, nus=NUS, E: float = 1e7, seed: int = 0) -> dict:
    """Paper exp. 1 at small strain: affine moduli of DV and RV against nu."""
    import dvstatic as dv

    mesh = dv.mesh.periodic_square(n_points, kind="random", seed=seed)
    out = {
        "n_points": mesh.n_points,
        "sigma_L": mesh.edge_length_spread(),
        "E": E,
        "nu": list(nus),
        "target_C1111": [],
        "target_C1122": [],
        "models": {},
    }
    for nu in nus:
        t = dv.plane_stress_tensor(E, nu)
        out["target_C1111"].append(float(t[0, 0]))
        out["target_C1122"].append(float(t[0, 1]))
    for cls in (dv.DV, dv.RV):
        rec = {"C1111": [], "C1122": [], "C1212_mandel": [], "k_n": [], "nu_m": []}
        for nu in nus:
            model = cls(mesh, E, nu, **PAPER)
            C = dv.elastic_tensor(model)
            rec["C1111"].append(float(C[0, 0]))
            rec["C1122"].append(float(C[0, 1]))
            rec["C1212_mandel"].append(float(C[2, 2]))
            rec["k_n"].append(model.k_n)
            rec["nu_m"].append(model.nu_m)
        c11 = np.array(rec["C1111"])
        c12 = np.array(rec["C1122"])
        rec["C1111_rel_error"] = (c11 / np.array(out["target_C1111"]) - 1).tolist()
        # C1122 relative to C1111's scale where the target is ~0 (nu = 0)
        scale = np.maximum(np.abs(out["target_C1122"]), 0.1 * np.array(out["target_C1111"]))
        rec["C1122_rel_error"] = ((c12 - np.array(out["target_C1122"])) / scale).tolist()
        out["models"][cls.kind] = rec
    return out


def plot_moduli(data: dict, key: str, path: Path, title: str) -> None:
    from dvstatic import plot

    fig, axes = plot.figure(2, 1, (11, 4))
    nus = np.array(data["nu"])
    tgt = np.array(data[f"target_{key}"])
    ax = axes[0, 0]
    ax.plot(nus, tgt / 1e7, "k-", label="plane stress target")
    for kind, style in (("DV", "o"), ("RV", "s")):
        ax.plot(nus, np.array(data["models"][kind][key]) / 1e7, style, mfc="none", label=kind)
    ax.set_xlabel("nu")
    ax.set_ylabel(f"{key}  [1e7]")
    ax.grid(alpha=0.3)
    ax.legend()
    ax = axes[0, 1]
    for kind, style in (("DV", "o-"), ("RV", "s--")):
        ax.plot(nus, 100 * np.array(data["models"][kind][f"{key}_rel_error"]), style, label=kind)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("nu")
    ax.set_ylabel("relative error [%]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.suptitle(f"{title} ({data['n_points']} vertices, periodic random, affine strain)")
    plot.save(fig, path)


def print_moduli(data: dict, key: str) -> None:
    print(f"{'nu':>6} {'target':>12} {'DV':>12} {'DV err':>8} {'RV':>12} {'RV err':>8}")
    for i, nu in enumerate(data["nu"]):
        dvr, rvr = data["models"]["DV"], data["models"]["RV"]
        print(
            f"{nu:6.2f} {data[f'target_{key}'][i]:12.6g} {dvr[key][i]:12.6g} "
            f"{dvr[f'{key}_rel_error'][i]:+8.3%} {rvr[key][i]:12.6g} "
            f"{rvr[f'{key}_rel_error'][i]:+8.3%}"
        )
