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


def _dense_in_polygon(v, p):
    """The even-odd test against every edge (the code before the sorted sweep)."""
    w = np.roll(v, -1, axis=0)
    x, y = p[:, 0:1], p[:, 1:2]
    cond = (v[None, :, 1] > y) != (w[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = v[None, :, 0] + (y - v[None, :, 1]) * (w[None, :, 0] - v[None, :, 0]) / (
            w[None, :, 1] - v[None, :, 1]
        )
    return (np.count_nonzero(cond & (x < xc), axis=1) % 2) == 1


def test_in_polygon_tests_only_the_edges_a_ray_can_cross():
    """The sorted sweep gives the all-edges answer, on polygons and points that share
    coordinates (points on vertices' heights, horizontal edges) too."""
    from dvstatic.mesh.polygons import in_polygon

    rng = np.random.default_rng(7)
    for trial in range(120):
        v = rng.random((int(rng.integers(3, 30)), 2))
        p = rng.random((300, 2))
        if trial % 2:  # a grid: shared heights, horizontal and collinear edges
            v, p = np.round(v * 4) / 4, np.round(p * 8) / 8
        np.testing.assert_array_equal(in_polygon(v, p), _dense_in_polygon(v, p))
    assert in_polygon(v, np.zeros((0, 2))).shape == (0,)


def _ellipse_domain():
    return dv.domain.Domain(
        dv.domain.Path(
            (
                dv.domain.Line((2.0, 0.0), (3.25, 0.0), "bottom"),
                dv.domain.EllipseArc((0.0, 0.0), 3.25, 2.75, 0.0, 0.0, 90.0, "outer"),
                dv.domain.Line((0.0, 2.75), (0.0, 1.0), "left"),
                dv.domain.EllipseArc((0.0, 0.0), 2.0, 1.0, 0.0, 90.0, 0.0, "inner"),
            )
        ),
        regions=[dv.domain.Circle((2.0, 1.5), 0.3, "disc")],
    )


def test_distance_beyond_a_reach_is_only_bounded():
    """Points certainly farther than the reach get inf (their exact distance is beyond
    it), every other point its exact distance: the mesher's tests ``d > reach`` come out
    as with every distance computed."""
    from dvstatic.mesh.distance import distance_to_boundary

    domain = _ellipse_domain()
    p = np.random.default_rng(3).random((4000, 2)) * (3.3, 2.8)
    exact = distance_to_boundary(domain, p)
    for reach in (1e-9, 0.02, 0.2, np.full(len(p), 0.05)):
        d = distance_to_boundary(domain, p, reach)
        near = np.isfinite(d)
        np.testing.assert_array_equal(d[near], exact[near])
        assert np.all(exact[~near] > reach if np.ndim(reach) == 0 else exact[~near] > 0.05)
        assert np.array_equal(d > reach, exact > reach)
        assert 0 < near.sum() < len(p)


def test_cvt_mesh_on_curves_unchanged_by_the_distance_bound(monkeypatch):
    """A CVT mesh of an ellipse domain with a region is the same, to the last bit, with
    every distance computed exactly (the bound switched off)."""
    from dvstatic.mesh import distance

    domain = _ellipse_domain()
    fast = dv.mesh.generate(domain, 0.08, kind="cvt", seed=4).points
    monkeypatch.setattr(distance, "_boundary_bound", lambda d, p, reach: np.full(len(p), -1.0))
    slow = dv.mesh.generate(domain, 0.08, kind="cvt", seed=4).points
    np.testing.assert_array_equal(fast, slow)
