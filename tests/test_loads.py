import numpy as np
import pytest

import dvstatic as dv
from dvstatic.problem import constraints, load_vector


def test_body_force_total_is_value_times_area():
    m = dv.mesh.rectangle(2.0, 0.5, 0.05, kind="jittered", seed=1)
    f = load_vector(m, [dv.BodyForce((0.3, -1.0))]).reshape(-1, 2)
    np.testing.assert_allclose(f.sum(axis=0), [0.3, -1.0], rtol=1e-12)
    # one third of the neighbouring triangles' area per node
    assert np.all(f[:, 1] < 0)


def test_traction_total_and_moment():
    m = dv.mesh.rectangle(1.0, 2.0, 0.1, kind="jittered", seed=2)
    f = load_vector(m, [dv.Traction("right", (0.0, 3.0))]).reshape(-1, 2)
    assert f.sum(axis=0)[1] == pytest.approx(3.0 * 2.0, rel=1e-12)
    nodes = np.flatnonzero(f[:, 1])
    assert set(nodes) <= set(m.part_nodes("right"))
    # resultant acts at mid-height (uniform traction, lumped exactly)
    ybar = np.sum(f[:, 1] * m.points[:, 1]) / f[:, 1].sum()
    assert ybar == pytest.approx(1.0, rel=1e-12)


def test_point_load_each_node():
    m = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    f = load_vector(m, [dv.PointLoad([0, 3], (1.0, 2.0))]).reshape(-1, 2)
    np.testing.assert_allclose(f[[0, 3]], [[1, 2], [1, 2]])
    assert np.abs(f).sum() == pytest.approx(6.0)


def test_fix_semantics():
    m = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    dofs, vals = constraints(m, [dv.Fix("left")])
    nodes = m.part_nodes("left")
    np.testing.assert_array_equal(dofs, np.sort(np.r_[2 * nodes, 2 * nodes + 1]))
    assert np.all(vals == 0)
    dofs, vals = constraints(m, [dv.Fix("bottom", y=-0.1)])
    np.testing.assert_array_equal(dofs, 2 * m.part_nodes("bottom") + 1)
    assert np.all(vals == -0.1)
    # the same dof twice with the same value is fine (corner shared by two sides)
    dofs, _ = constraints(m, [dv.Fix("left", x=0), dv.Fix("bottom", x=0)])
    assert len(dofs) == len(np.unique(dofs))


def test_load_scale():
    m = dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")
    a = load_vector(m, dv.BodyForce((0, -1)))
    b = load_vector(m, dv.BodyForce((0, -1)), scale=0.5)
    np.testing.assert_allclose(b, 0.5 * a)
