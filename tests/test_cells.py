"""Exact boundary cells (dvstatic.lattice.cells, the default ``boundary_cells="exact"``):
the triangles at the boundary carry the isotropic tensor, consistently in every path."""

import numpy as np
import pytest

import dvstatic as dv
from dvstatic.lattice.cells import boundary_triangles, isotropic_tensor
from dvstatic.lattice.damage import split

E, NU = 1e4, 0.3
MODELS = [dv.DV, dv.RV]


@pytest.fixture(scope="module")
def plate():
    return dv.mesh.rectangle(2.0, 1.0, 0.1, kind="jittered", seed=1)


@pytest.mark.parametrize("cls", MODELS)
def test_cells_carry_the_isotropic_tensor(cls, plate):
    model = cls(plate, E, NU)
    cells = model.cell_triangles
    on = np.zeros(plate.n_points, dtype=bool)
    on[plate.boundary_nodes] = True
    assert np.array_equal(cells, np.flatnonzero(on[plate.triangles].any(axis=1)))
    c = model.triangle_tensors()
    target = isotropic_tensor(E, NU)
    assert np.abs(c[cells] - target).max() < 1e-12 * np.abs(target).max()
    plain = cls(plate, E, NU, boundary_cells="lattice")
    assert len(plain.cell_triangles) == 0
    inner = np.setdiff1d(np.arange(plate.n_triangles), cells)
    np.testing.assert_allclose(c[inner], plain.triangle_tensors()[inner], rtol=1e-12, atol=1e-9)
    # the cut cells of the plain lattice are not isotropic: the term is not trivial
    assert np.abs(plain.triangle_tensors()[cells] - target).max() > 0.05 * target.max()


@pytest.mark.parametrize("cls", MODELS)
def test_split_tensions_and_tangent_agree_with_the_operator(cls, plate):
    model = cls(plate, E, NU)
    rng = np.random.default_rng(3)
    s = split(model)
    K = model.stiffness()
    assert abs(K - s.stiffness(plate, s.w, s.g).tocsr()).max() < 1e-12 * abs(K).max()
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()
    u = 1e-3 * rng.normal(size=(plate.n_points, 2))
    t = model.linear_tension(u)
    np.testing.assert_allclose(s.tension(u.ravel(), s.w, s.g), t, atol=1e-12 * np.abs(t).max())
    # the nonlinear tensions linearise to the linear ones
    small = model.bond_tension(1e-5 * u) * 1e5
    assert np.abs(small - t).max() < 1e-4 * np.abs(t).max()
    # the exact tangent against central differences of the internal force
    u0 = 2e-2 * rng.normal(size=(plate.n_points, 2))
    v = rng.normal(size=2 * plate.n_points)
    eps = 1e-6
    fd = model.internal_force(u0.ravel() + eps * v) - model.internal_force(u0.ravel() - eps * v)
    fd /= 2 * eps
    assert np.abs(model.tangent(u0) @ v - fd).max() < 1e-7 * np.abs(fd).max()


def test_a_uniform_stress_is_exact_on_the_regular_lattice():
    """The regular lattice's interior is P1 with the isotropic tensor to 0.3 %; with exact
    cells its boundary is too, so uniaxial tension is (nearly) exact at every node."""
    m = dv.mesh.rectangle(2.0, 1.0, 0.05, kind="lattice")
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0.0, 0.0), y=0.0)]
    load = [dv.Traction("right", (1.0, 0.0))]
    exact = np.c_[m.points[:, 0] / E, -NU * (m.points[:, 1] - 0.0) / E]
    err = {}
    for cells in ("exact", "lattice"):
        u = dv.solve(dv.DV(m, E, NU, boundary_cells=cells), sup, load).u
        err[cells] = np.linalg.norm(u - exact) / np.linalg.norm(exact)
    assert err["exact"] < 0.006 and err["exact"] < 0.5 * err["lattice"]  # 0.36 %, 1.36 %


@pytest.mark.parametrize("cls", MODELS)
def test_a_cracked_cell_falls_back_to_its_springs(cls, plate):
    model = cls(plate, E, NU)
    cell = model.cell_triangles[0]
    bond = plate.topology.tri_bonds[cell, 0]
    d = np.ones(plate.n_bonds)
    d[bond] = 0.0
    cracked = model.damaged(d)
    op = cracked.operator
    assert np.abs(op.cell_dq[0]).max() == 0.0  # the coupling and the cell term are gone
    sol = dv.solve(cracked, dv.Fix("left"), dv.Traction("right", (1.0, 0.0)))
    t = cracked.linear_tension(sol.u)
    assert abs(t[bond]) < 1e-6 * np.abs(t).max()  # a broken bond carries nothing
    lam = np.linalg.eigvalsh(cracked.stiffness().toarray())
    assert lam.min() > -1e-9 * lam.max()  # still positive semi-definite


def test_slivers_and_periodic_meshes_have_no_cells():
    per = dv.mesh.periodic_square(64, kind="random", seed=1)
    assert len(boundary_triangles(per)) == 0
    assert dv.DV(per, E, NU).operator.cells is None
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.01], [0.5, -1.0]])
    sliver = dv.Mesh(x, np.array([[0, 1, 2], [0, 3, 1]]))
    assert list(boundary_triangles(sliver)) == [1]


def test_boundary_cells_is_checked_and_recorded(plate):
    with pytest.raises(ValueError, match="boundary_cells"):
        dv.DV(plate, E, NU, boundary_cells="p1")
    assert "boundary_cells='lattice'" in repr(dv.DV(plate, E, NU, boundary_cells="lattice"))
