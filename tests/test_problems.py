"""Real problems: pressure, loads varying along the boundary, prescribed displacement
fields, curved boundaries (closed forms and exact resultants)."""

import numpy as np
import pytest

import dvstatic as dv
from dvstatic.problem import load_vector

E, NU = 1e5, 0.3


def cantilever_exact(points, L=4.0, D=1.0, P=1.0, E=E, nu=NU):
    """Timoshenko & Goodier's end-loaded cantilever (plane stress): free end x = 0
    loaded by a parabolic shear of resultant P (upwards), clamped end x = L; the mesh
    spans 0 <= y <= D (the formulas use y - D/2)."""
    x = points[:, 0]
    y = points[:, 1] - D / 2
    inertia = D**3 / 12
    G = E / (2 * (1 + nu))
    u = (
        -P * x**2 * y / (2 * E * inertia)
        - nu * P * y**3 / (6 * E * inertia)
        + P * y**3 / (6 * inertia * G)
        + (P * L**2 / (2 * E * inertia) - P * D**2 / (8 * inertia * G)) * y
    )
    v = (
        nu * P * x * y**2 / (2 * E * inertia)
        + P * x**3 / (6 * E * inertia)
        - P * L**2 * x / (2 * E * inertia)
        + P * L**3 / (3 * E * inertia)
    )
    return np.c_[u, v]


def cantilever_shear(points, D=1.0, P=1.0):
    """The end traction at x = 0 (outward normal -x): (0, P (D^2/4 - y^2) / (2 I))."""
    y = points[:, 1] - D / 2
    return np.c_[np.zeros(len(y)), P * (D**2 / 4 - y**2) / (2 * D**3 / 12)]


def _annulus(h=0.1):
    return dv.mesh.disc(1.0, h, name="outer", holes=[dv.domain.Circle((0, 0), 0.4, "bore")])


def test_pressure_on_a_curved_boundary_has_the_exact_resultant():
    mesh = _annulus()
    p = 2.5
    bore = mesh.part_edges("bore")
    upper = bore[(mesh.points[bore].mean(axis=1)[:, 1] > 0)]
    f = load_vector(mesh, [dv.Pressure(upper, p)]).reshape(-1, 2)
    # pushing into the body: radially away from the bore's centre, 2 p a upwards
    np.testing.assert_allclose(f.sum(axis=0), [0.0, 2 * p * 0.4], atol=1e-12)
    # a closed boundary under uniform pressure: zero resultant and zero moment
    f = load_vector(mesh, [dv.Pressure("outer", p)]).reshape(-1, 2)
    assert np.abs(f.sum(axis=0)).max() < 1e-12
    assert abs(np.sum(mesh.points[:, 0] * f[:, 1] - mesh.points[:, 1] * f[:, 0])) < 1e-12
    # FE (refined boundary on the true circle, quadratic geometry for P2): the
    # reactions of the clamped outer boundary balance the arc's resultant 2 p a
    for order in (1, 2):
        fe = dv.fem.solve(
            mesh, E, NU, [dv.Fix("outer")], [dv.Pressure(upper, p)], order=order, refine=1
        )
        assert fe.u[:, 1].max() > 0  # pushed up, away from the bore's centre
        np.testing.assert_allclose(fe.info["load_resultant"], [0.0, 2 * p * 0.4], atol=1e-12)


def test_linear_traction_has_the_exact_resultant_and_moment():
    mesh = dv.mesh.rectangle(1.0, 2.0, 0.1, kind="jittered", seed=3)
    t = dv.Traction("right", lambda x: np.c_[3.0 * x[:, 1] - 1.0, 0.5 * x[:, 1]])
    f = load_vector(mesh, [t]).reshape(-1, 2)
    # integrals over y in [0, 2]: tx = 3y - 1 -> 4, ty = y/2 -> 1
    np.testing.assert_allclose(f.sum(axis=0), [4.0, 1.0], rtol=1e-12)
    moment = np.sum(mesh.points[:, 0] * f[:, 1] - mesh.points[:, 1] * f[:, 0])
    # about the origin on x = 1: int (x ty - y tx) dy = int y/2 - 3y^2 + y = 1 - 8 + 2
    assert moment == pytest.approx(-5.0, rel=1e-12)
    body = dv.BodyForce(lambda x: np.c_[x[:, 0], 2.0 * x[:, 1]])
    f = load_vector(mesh, [body]).reshape(-1, 2)
    np.testing.assert_allclose(f.sum(axis=0), [1.0, 4.0], rtol=1e-12)


def test_a_bad_callable_is_refused_with_the_load_named():
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    with pytest.raises(dv.InputError, match=r"Traction on 'right'.*shape \(3,\)"):
        load_vector(mesh, [dv.Traction("right", lambda x: np.ones(3))])
    with pytest.raises(dv.InputError, match="Pressure on 'top'.*non-finite"):
        load_vector(mesh, [dv.Pressure("top", lambda x: np.full(len(x), np.nan))])
    with pytest.raises(dv.InputError, match="Fix on 'left': y.*non-finite"):
        dv.solve(
            dv.DV(mesh, E, NU),
            [dv.Fix("left", x=0.0, y=lambda x: x[:, 0] * np.nan)],
            [],
        )


def test_prescribed_affine_field_is_reproduced_inside():
    eps = np.array([[1e-3, 4e-4], [4e-4, -2e-4]])

    def field(c):
        return lambda x: x @ eps[c]

    mesh = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
    everywhere = ("left", "right", "bottom", "top")
    sup = [dv.Fix(side, x=field(0), y=field(1)) for side in everywhere]
    exact = mesh.points @ eps.T
    for order in (1, 2):
        fe = dv.fem.solve(mesh, E, NU, sup, [], order=order, refine=1)
        assert np.abs(fe.u - exact).max() < 1e-12
    # the lattice: exact for a periodic lattice; the rectangle's side columns are not
    # (half cells at the sides), so within 2 %
    for cls in (dv.DV, dv.RV):
        sol = dv.solve(cls(mesh, E, NU), sup, [])
        assert np.abs(sol.u - exact).max() < 0.02 * np.abs(exact).max()


def test_fe_clamps_every_dof_of_a_prescribed_field():
    """The exact cantilever field prescribed at the clamped end (a function, or per-node
    values on node indices): P2 with the mid-edge dofs prescribed too is exact to
    the discretisation, not 2.8 % off as with the vertex dofs only."""
    mesh = dv.mesh.rectangle(4.0, 1.0, 0.25, kind="lattice")
    right = mesh.part_nodes("right")
    exact = cantilever_exact(mesh.points)
    loads = [dv.Traction("left", lambda x: cantilever_shear(x))]
    by_function = [
        dv.Fix(
            "right",
            x=lambda x: cantilever_exact(x)[:, 0],
            y=lambda x: cantilever_exact(x)[:, 1],
        )
    ]
    by_nodes = [dv.Fix(right, x=exact[right, 0], y=exact[right, 1])]
    scale = np.abs(exact).max()
    fe = dv.fem.solve(mesh, E, NU, by_function, loads, order=2, refine=1)
    assert np.abs(fe.u - exact).max() < 1e-4 * scale
    fe = dv.fem.solve(mesh, E, NU, by_nodes, loads, order=2, refine=1)
    assert np.abs(fe.u - exact).max() < 2e-3 * scale


def test_refined_fe_converges_around_a_hole():
    """New boundary nodes lie on the circle: the peak hoop stress converges (it
    diverged when refined nodes stayed on the polygon)."""
    dom = dv.domain.Domain(
        dv.domain.rectangle_domain(2.0, 1.0).outer, (dv.domain.Circle((1.0, 0.5), 0.1, "hole"),)
    )
    mesh = dv.mesh.generate(dom, 0.05, kind="jittered")
    near = [np.argmin(np.hypot(*(mesh.points - q).T)) for q in ([1, 0], [1, 1], [0, 0.5])]
    sup = [dv.Fix(near[:1], x=0.0), dv.Fix(near[1:2], x=0.0), dv.Fix(near[2:], y=0.0)]
    ld = [dv.Traction("left", (-1.0, 0.0)), dv.Traction("right", (1.0, 0.0))]
    peaks = [
        dv.fem.solve(mesh, E, 0.2, sup, ld, order=2, refine=r).stress([[1.0, 0.6]])[0, 0, 0]
        for r in (0, 1, 2)
    ]
    steps = np.diff(peaks)
    assert np.all(steps > 0) and steps[1] < 0.6 * steps[0]
    assert 3.0 < peaks[-1] < 3.2
