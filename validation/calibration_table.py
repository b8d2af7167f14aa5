"""Make the relaxed-calibration table of the built-in generators' micro-structures.

For DV and RV and each recipe (regular lattice, jittered lattices at jitters 0.05 ...
0.45, random points, CVT with the generators' Lloyd iterations), the relaxed moduli
``nu_eff`` and ``E_eff`` (at k_n = 1, stabilised coupling) are measured on periodic
samples made by the recipe (``dv.mesh.periodic_sample``), averaged over seeds, on a
grid of nu_m. The full run writes the package's table
``dvstatic/lattice/calibration/relaxed_table.json`` (about 30 min on 2 cores); the
quick run writes a small table to ``validation/out/relaxed_table_quick.json`` and never
touches the package's.

    python validation/calibration_table.py            # full size, both cores
    python validation/calibration_table.py --quick    # seconds, smoke test
"""

from __future__ import annotations

import multiprocessing as mp
import time
from pathlib import Path

import numpy as np
from _common import parser, write_json

PACKAGE_TABLE = (
    Path(__file__).resolve().parents[1]
    / "dvstatic"
    / "lattice"
    / "calibration"
    / "relaxed_table.json"
)
JITTERS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)
NU_M = np.round(np.arange(-1.6, 1.6 + 1e-9, 0.05), 4)


def _task(args):
    """(model, recipe fields, points, seeds) -> nu_eff and E_eff over NU_M (seed means)
    and their spread over seeds."""
    import dvstatic as dv
    from dvstatic.lattice.calibration import relaxed_moduli

    model, fields, n_points, seeds, nu_m, bonds = args
    sampling = dv.mesh.Sampling(**fields)
    t0 = time.perf_counter()
    nus, Es = [], []
    for seed in seeds:
        rev = dv.mesh.periodic_sample(sampling, n_points, seed)
        res = [relaxed_moduli(model, rev, float(x), bonds=bonds) for x in nu_m]
        nus.append([r["nu"] for r in res])
        Es.append([r["E"] for r in res])
        if not all(r["stable"] for r in res):
            raise RuntimeError(f"{model} {sampling}: a stabilised sample is unstable")
    nus, Es = np.array(nus), np.array(Es)
    return {
        "model": model,
        "bonds": bonds,
        "recipe": fields,
        "nu": nus.mean(axis=0),
        "E": Es.mean(axis=0),
        "nu_seed_spread": float(np.max(np.ptp(nus, axis=0))) if len(seeds) > 1 else 0.0,
        "E_seed_spread": float(np.max(np.ptp(Es, axis=0) / Es.mean(axis=0)))
        if len(seeds) > 1
        else 0.0,
        "seconds": time.perf_counter() - t0,
    }


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--points", type=int, default=20_000, help="points per sample")
    p.add_argument("--seeds", type=int, default=2, help="samples per recipe")
    p.add_argument("--processes", type=int, default=2)
    p.add_argument(
        "--cvt-family",
        action="store_true",
        help="only the curves of CVT samples at several Lloyd iterations (the samples of"
        " CVT-like meshes without recipe), merged into the existing table",
    )
    p.add_argument(
        "--fabric",
        action="store_true",
        help="only the fabric-corrected curves of the point-set recipes (random, CVT),"
        " merged into the existing table",
    )
    a = p.parse_args()
    from dvstatic.lattice.stabilise import MARGIN
    from dvstatic.mesh.generators import CVT_ITERATIONS

    jitters, nu_m, points, seeds = JITTERS, NU_M, a.points, list(range(a.seeds))
    if a.quick:
        jitters, nu_m, points, seeds = (0.0, 0.3), np.round(np.arange(-1.6, 1.61, 0.4), 4), 800, [0]
    recipes = [{"kind": "jittered", "jitter": j} for j in jitters[1:]]
    recipes += [
        {"kind": "lattice"},
        {"kind": "random"},
        {"kind": "cvt", "iterations": CVT_ITERATIONS},
    ]
    if a.cvt_family:
        return _cvt_family(a, points, seeds, "fabric" if a.fabric else "uniform")
    if a.fabric:
        return _fabric(a, recipes[-2:], nu_m, points, seeds)
    tasks = [(m, r, points, seeds, nu_m, "uniform") for m in ("DV", "RV") for r in recipes]
    t0 = time.perf_counter()
    results = _run(tasks, a.processes)
    curves: dict = {"DV": {}, "RV": {}}
    for res in results:
        curves[res["model"]][res["recipe"]["kind"]] = res
    table = {
        "format": 1,
        "made_by": "validation/calibration_table.py" + (" --quick" if a.quick else ""),
        "margin": MARGIN,
        "cvt_iterations": CVT_ITERATIONS,
        "sample_points": points,
        "seeds": seeds,
        "nu_m": nu_m,
        "curves": {},
        "seed_spread": {},
        "seconds": time.perf_counter() - t0,
    }
    for model, c in curves.items():
        by_jitter = {0.0: c["lattice"]} | {
            r["recipe"]["jitter"]: r
            for r in results
            if r["model"] == model and r["recipe"]["kind"] == "jittered"
        }
        grid = sorted(by_jitter)
        table["curves"][model] = {
            "lattice": {"nu": c["lattice"]["nu"], "E": c["lattice"]["E"]},
            "jittered": {
                "jitter": grid,
                "nu": [by_jitter[j]["nu"] for j in grid],
                "E": [by_jitter[j]["E"] for j in grid],
            },
            "random": {"nu": c["random"]["nu"], "E": c["random"]["E"]},
            "cvt": {"nu": c["cvt"]["nu"], "E": c["cvt"]["E"]},
        }
        table["seed_spread"][model] = {
            "nu": max(r["nu_seed_spread"] for r in results if r["model"] == model),
            "E": max(r["E_seed_spread"] for r in results if r["model"] == model),
        }
    path = a.out / "relaxed_table_quick.json" if a.quick else PACKAGE_TABLE
    write_json(table, path)
    print(f"wrote {path} in {table['seconds']:.0f} s")


def _run(tasks, processes: int) -> list[dict]:
    with mp.get_context("spawn").Pool(processes) as pool:
        results = []
        for res in pool.imap_unordered(_task, tasks):
            results.append(res)
            print(
                f"{res['model']} {res['bonds']} {res['recipe']}: nu_eff in "
                f"[{res['nu'].min():.3f}, {res['nu'].max():.3f}], seed spread nu "
                f"{res['nu_seed_spread']:.1e} E {res['E_seed_spread']:.1e}, "
                f"{res['seconds']:.0f} s",
                flush=True,
            )
    return results


def _fabric(a, recipes, nu_m, points, seeds) -> None:
    """The fabric-corrected curves (``bonds="fabric"``) of the point-set recipes,
    added to the table (the package's, or the quick one) on its own grid of nu_m."""
    import json

    path = a.out / "relaxed_table_quick.json" if a.quick else PACKAGE_TABLE
    table = json.loads(path.read_text())
    nu_m = np.asarray(table["nu_m"], dtype=float)
    t0 = time.perf_counter()
    tasks = [(m, r, points, seeds, nu_m, "fabric") for m in ("DV", "RV") for r in recipes]
    for res in _run(tasks, a.processes):
        table["curves"][res["model"]].setdefault("fabric", {})[res["recipe"]["kind"]] = {
            "nu": res["nu"],
            "E": res["E"],
        }
    table["fabric_seconds"] = time.perf_counter() - t0
    write_json(table, path)
    print(f"wrote {path} (fabric curves) in {table['fabric_seconds']:.0f} s")


#: Lloyd iterations of the CVT family (0: random points); local spread 0.365 down to 0.051
FAMILY_ITERATIONS = (0, 1, 2, 4, 8, 15, 30, 60, 120, 240, 480)
#: perturbation amplitudes (relative to the spacing) whose defect fractions are tabulated
PERTURBATIONS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.6)


def _cvt_family(a, points, seeds, bonds: str) -> None:
    """The curves of the CVT family (random points Lloyd-relaxed 0 ... 480 times) on a
    grid of nu_m twice as coarse as the recipes', with every member's local spread and
    defect fraction, and those of perturbed lattices: what the calibration of a mesh
    without recipe interpolates (``table.family_curve``). Merged into the table (the
    package's, or the quick one). With ``--fabric``: the fabric-corrected curves of the
    same members, added to the family already there."""
    import json

    import dvstatic as dv
    from dvstatic.lattice.calibration.relaxed import defect_fraction, local_spread

    path = a.out / "relaxed_table_quick.json" if a.quick else PACKAGE_TABLE
    table = json.loads(path.read_text())
    iterations = (0, 2, 30) if a.quick else FAMILY_ITERATIONS
    nu_m = np.round(np.arange(-1.6, 1.6 + 1e-9, 0.8 if a.quick else 0.1), 4)
    recipes = [{"kind": "cvt", "iterations": k} if k else {"kind": "random"} for k in iterations]
    t0 = time.perf_counter()
    tasks = [(m, r, points, seeds, nu_m, bonds) for m in ("DV", "RV") for r in recipes]
    results = _run(tasks, a.processes)
    if bonds == "fabric":
        family = table["cvt_family"]
        if family["iterations"] != list(iterations) or family["nu_m"] != list(nu_m):
            raise SystemExit("the table's CVT family has other members: rerun --cvt-family")
        family["fabric"] = {
            model: {
                "nu": [_member(results, model, k)["nu"] for k in iterations],
                "E": [_member(results, model, k)["E"] for k in iterations],
            }
            for model in ("DV", "RV")
        }
        family["fabric_seconds"] = time.perf_counter() - t0
        write_json(table, path)
        print(f"wrote {path} (CVT family, fabric) in {family['fabric_seconds']:.0f} s")
        return
    family: dict = {
        "iterations": list(iterations),
        "sample_points": points,
        "seeds": seeds,
        "nu_m": nu_m,
        "spread": [],
        "defects": [],
    }
    for r in recipes:
        rev = dv.mesh.periodic_sample(dv.mesh.Sampling(**r), points, seeds[0])
        family["spread"].append(local_spread(rev))
        family["defects"].append(defect_fraction(rev))
    for model in ("DV", "RV"):
        family[model] = {
            "nu": [_member(results, model, k)["nu"] for k in iterations],
            "E": [_member(results, model, k)["E"] for k in iterations],
        }
    pert = {"amplitude": list(PERTURBATIONS), "spread": [], "defects": []}
    for amp in PERTURBATIONS:
        rev = dv.mesh.periodic_sample(
            dv.mesh.Sampling("lattice", perturbations=(amp,) if amp else ()), points, seeds[0]
        )
        pert["spread"].append(local_spread(rev))
        pert["defects"].append(defect_fraction(rev))
    family["perturbed"] = pert
    family["seconds"] = time.perf_counter() - t0
    table["cvt_family"] = family
    write_json(table, path)
    print(f"wrote {path} (CVT family) in {family['seconds']:.0f} s")


def _member(results, model: str, iterations: int) -> dict:
    """The result of ``model`` on the family's member of ``iterations`` (0: random)."""
    return next(
        r for r in results if r["model"] == model and r["recipe"].get("iterations", 0) == iterations
    )


if __name__ == "__main__":
    main()
