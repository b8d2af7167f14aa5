"""Run under ``mpiexec -n P``: the cases of tests/test_petsc.py with solver="petsc".

Usage: ``mpiexec -n 2 python tests/mpi_worker.py OUT.npz``; rank 0 writes every
case's displacements, reactions and info summary.
"""

import json
import sys

import numpy as np

import dvstatic as dv

CASES = [
    (problem, model, nonlinear)
    for problem in ("uniaxial", "beam")
    for model in ("DV", "RV")
    for nonlinear in (False, True)
] + [
    # prescribed displacements (eliminated with non-zero values, Newton jumps)
    ("stretch", "RV", False),
    ("stretch", "RV", True),
    # the paper's model: its calibration sums over owned bonds and triangles
    ("uniaxial", "DV-paper", False),
    # a mesh without recipe: the relaxed calibration's bond-length spread summed
    ("uniaxial", "RV-spread", False),
    # pressure on a bore lined by a second material (and, nonlinear, following it)
    ("lined-bore", "RV", False),
    ("lined-bore", "DV", True),
]


def setup(problem: str, model: str, nonlinear: bool):
    """Mesh, model, supports and loads of one case (the same in the test process)."""
    cls = dv.DV if model.startswith("DV") else dv.RV
    nu = 0.35 if model.startswith("DV") else 0.2
    # the defaults (relaxed, stabilised, surface bonds) unless the paper's model is asked
    paper = {
        "calibration": "paper",
        "bonds": "uniform",
        "boundary_cells": "lattice",
        "anisotropy": "keep",
    }
    kw = paper if model.endswith("paper") else {}
    if problem == "lined-bore":
        lining = dv.domain.Circle((0.0, 0.0), 0.55, name="lining")
        bore = dv.domain.Circle((0.0, 0.0), 0.4, "bore")
        mesh = dv.mesh.disc(1.0, 0.08, name="outer", holes=[bore], regions=[lining])
        p = mesh.points
        near = [int(np.argmin(np.hypot(*(p - q).T))) for q in ([1, 0], [-1, 0], [0, 1])]
        sup = [dv.Fix(near[:2], y=0.0), dv.Fix(near[2:], x=0.0)]
        ld = [dv.Pressure("bore", 2e3 if nonlinear else 1.0, follower=nonlinear)]
        materials = {"lining": (3e5, 0.25)}
        return cls(mesh, 1e5, nu, materials=materials, **kw), sup, ld
    if problem == "stretch":
        mesh = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="jittered", seed=5)
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0), dv.Fix("right", x=0.03)]
        ld = []
    elif problem == "uniaxial":
        mesh = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="jittered", seed=1)
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        ld = [dv.Traction("right", (-1000.0 if nonlinear else -1.0, 0.0))]
    else:
        mesh = dv.mesh.rectangle(4.0, 1.0, 0.1, kind="jittered", seed=2)
        sup = [dv.Fix("left"), dv.Fix("right", x=0.0, y=0.0)]
        ld = [dv.BodyForce((0.0, -300.0 if nonlinear else -1.0))]
    if model.endswith("spread"):  # as if read from a file: no generator recipe
        mesh = dv.Mesh(mesh.points, mesh.triangles, parts=dict(mesh.parts))
    return cls(mesh, 1e5, nu, **kw), sup, ld


OPTIONS = dict(rtol=1e-12, newton_rtol=1e-10, steps=4)


def main(out: str) -> None:
    from petsc4py import PETSc

    rank = PETSc.COMM_WORLD.getRank()
    arrays, infos = {}, {}
    for i, (problem, model, nonlinear) in enumerate(CASES):
        m, sup, ld = setup(problem, model, nonlinear)
        if i == 0 and rank == 0:
            print(m)  # calibrates on rank 0 only: the solve must still agree on all ranks
        sol = dv.solve(m, sup, ld, solver="petsc", nonlinear=nonlinear, **OPTIONS)
        if rank == 0:
            arrays[f"u{i}"] = sol.u
            arrays[f"r{i}"] = sol.reactions
            infos[i] = {
                "iterations": sol.info.iterations,
                "step_iterations": [st.iterations for st in sol.info.steps],
                "ranks": sol.info.parallel.ranks,
                "k_n": m.k_n,
                "nu_m": m.nu_m,
            }
        elif sol.u is not None:
            raise AssertionError("only rank 0 receives the solution")
    if rank == 0:
        np.savez(out, info=json.dumps(infos), **arrays)


if __name__ == "__main__":
    main(sys.argv[1])
