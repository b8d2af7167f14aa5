"""Performance features: dynamic relaxation baseline, reuse, skipped work."""

import numpy as np
import pytest

import dvstatic as dv
from conftest import E_BEAM, NU, uniaxial_problem


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_dynamic_relaxation_matches_direct(cls):
    m = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="jittered", seed=1)
    model = cls(m, E_BEAM, NU)
    sup, ld = uniaxial_problem()
    ref = dv.solve(model, sup, ld, solver="direct")
    dr = dv.solve(model, sup, ld, solver="dynamic-relaxation", rtol=1e-9)
    assert dr.info.solver == "dynamic-relaxation" and dr.info.iterations > 100
    assert np.linalg.norm(dr.u - ref.u) <= 1e-7 * np.linalg.norm(ref.u)
    np.testing.assert_allclose(dr.reactions.sum(axis=0), ref.reactions.sum(axis=0), atol=1e-6)


def test_dynamic_relaxation_nonlinear_matches_newton():
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
    model = dv.RV(m, E_BEAM, NU)
    sup, _ = uniaxial_problem()
    ld = dv.Traction("right", (-3e3, 0.0))  # 3 % strain
    newton = dv.solve(model, sup, ld, nonlinear=True)
    dr = dv.solve(model, sup, ld, nonlinear=True, solver="dynamic-relaxation", rtol=1e-9)
    assert np.linalg.norm(dr.u - newton.u) <= 1e-6 * np.linalg.norm(newton.u)


def test_dynamic_relaxation_refuses_unstable_lattice():
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="random", seed=0)
    sup, ld = uniaxial_problem()
    with pytest.raises(dv.SolverError, match="blew up|did not reach"):
        dv.solve(
            dv.DV(m, E_BEAM, -0.5, calibration="paper", bonds="uniform", boundary_cells="lattice"),
            sup,
            ld,
            solver="dynamic-relaxation",
            maxiter=20000,
        )


@pytest.mark.parametrize("solver,what", [("direct", "factorisation"), ("amg", "amg hierarchy")])
def test_factorisation_reused_across_load_cases(solver, what):
    m = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="lattice")
    model = dv.DV(m, E_BEAM, NU)
    sup, _ = uniaxial_problem()
    a = dv.solve(model, sup, dv.Traction("right", (-1.0, 0.0)), solver=solver)
    b = dv.solve(model, sup, dv.Traction("right", (-2.0, 0.0)), solver=solver)
    assert what not in a.info.reused and what in b.info.reused
    assert "assembly" in b.info.reused and "geometry" in b.info.reused
    np.testing.assert_allclose(b.u, 2 * a.u, rtol=1e-7, atol=1e-14)
    # other supports: a new factorisation
    c = dv.solve(model, [dv.Fix("left")], dv.Traction("right", (-1.0, 0.0)), solver=solver)
    assert what not in c.info.reused


def test_coupling_skipped_when_nu_m_is_zero():
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="jittered", seed=1)
    sup, ld = uniaxial_problem()
    # the paper's DV has nu_m = 0 at nu = 1/3
    sol = dv.solve(dv.DV(m, E_BEAM, 1.0 / 3.0, calibration="paper", bonds="uniform"), sup, ld)
    assert sol.info.coupling_assembled is False
    assert dv.solve(dv.DV(m, E_BEAM, NU), sup, ld).info.coupling_assembled is True


def test_newton_preconditioner_rebuilt_at_most_once_per_step():
    m = dv.mesh.rectangle(1.0, 1.0, 0.04, kind="jittered", seed=2)
    model = dv.RV(m, E_BEAM, NU)
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0), dv.Fix("right", x=0.05)]
    sol = dv.solve(model, sup, [], nonlinear=True, steps=2, solver="amg")
    steps = sol.info.steps
    assert all(s.iterations <= 5 for s in steps)
    assert sol.info.tangent_builds <= len(steps)
