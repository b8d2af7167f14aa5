import numpy as np
import pytest

import dvstatic as dv
from conftest import E_BEAM, NU, uniaxial_problem
from dvstatic.post import node_stress, square_stress, virial_stress


@pytest.fixture(scope="module")
def uniaxial_solution():
    m = dv.mesh.rectangle(1.0, 1.0, 0.025, kind="jittered", seed=4)
    sup, ld = uniaxial_problem()
    return dv.solve(dv.RV(m, E_BEAM, NU), sup, ld)


def test_virial_stress_of_uniaxial_solution(uniaxial_solution):
    sol = uniaxial_solution
    s = virial_stress(sol.model, sol.u, linear=True)
    # exact for any lattice in equilibrium: A sigma = sum over nodes of F (x) x, with F
    # all external forces (loads and reactions)
    from dvstatic.problem import load_vector

    f = load_vector(sol.model.mesh, sol.loads).reshape(-1, 2) + sol.reactions
    expected = np.einsum("ni,nj->ij", f, sol.model.mesh.points) / sol.model.mesh.area
    np.testing.assert_allclose(s, expected, atol=1e-9)
    assert s[0, 0] == pytest.approx(-1.0, rel=1e-9)


def test_node_stress_area_average_is_virial(uniaxial_solution):
    sol = uniaxial_solution
    s = node_stress(sol.model, sol.u)
    from dvstatic.lattice import geometry

    g = geometry.of(sol.model.mesh)
    area = np.where(g.cell_area > 0.25 * g.dual_area, g.cell_area, g.dual_area)
    mean = np.einsum("n,nij->ij", area, s) / sol.model.mesh.area
    np.testing.assert_allclose(mean, virial_stress(sol.model, sol.u, linear=True), atol=1e-9)


def test_square_stress_tiles_to_virial(uniaxial_solution):
    sol = uniaxial_solution
    h = 0.1
    centres, sig, covered = square_stress(sol.model, sol.u, h)
    assert sig.shape == (10, 10, 2, 2) and centres.shape == (10, 10, 2)
    mean = sig.reshape(-1, 2, 2).mean(axis=0)  # h^2 * sum sigma^h over the unit square
    np.testing.assert_allclose(mean, virial_stress(sol.model, sol.u, linear=True), atol=1e-9)
    inner = sig[covered]
    assert np.median(inner[:, 0, 0]) == pytest.approx(-1.0, rel=0.1)


def test_energy_of_affine_field_matches_continuum():
    m = dv.mesh.periodic_square(5000, kind="random", seed=0)
    model = dv.DV(m, 1e7, 0.2)
    C = dv.elastic_tensor(model)
    eps_v = np.array([1e-3, -2e-4, 0.0])
    # affine strain energy per area = eps.C.eps / 2
    sig = C @ eps_v
    assert 0.5 * eps_v @ sig > 0
