import numpy as np
import pytest
import scipy.sparse as sp

import dvstatic as dv
from dvstatic.linalg import rigid_modes

# the paper's model
PAPER = {
    "calibration": "paper",
    "bonds": "uniform",
    "boundary_cells": "lattice",
    "anisotropy": "keep",
}

MODELS = [dv.DV, dv.RV]


def _pattern(a):
    a = sp.csr_matrix(a)
    a.sort_indices()
    return sp.csr_matrix((np.ones(a.indices.size), a.indices, a.indptr), shape=a.shape)


@pytest.mark.parametrize("cls", MODELS)
@pytest.mark.parametrize("nu", [-0.3, 0.2, 0.45])
def test_stiffness_symmetric_and_rigid_modes(cls, nu, jittered_small):
    model = cls(jittered_small, E=1e5, nu=nu)
    K = model.stiffness()
    scale = abs(K).max()
    assert abs(K - K.T).max() <= 1e-13 * scale
    B = rigid_modes(jittered_small.points)
    assert np.abs(K @ B).max() <= 1e-10 * scale


@pytest.mark.parametrize("cls", MODELS)
def test_pattern_equals_p1_finite_elements(cls, jittered_small):
    import skfem

    m = jittered_small
    fm = skfem.MeshTri(m.points.T.copy(), m.triangles.T.copy())
    basis = skfem.Basis(fm, skfem.ElementVector(skfem.ElementTriP1()))
    from skfem.models.elasticity import linear_elasticity

    Kfe = skfem.asm(linear_elasticity(1.0, 1.0), basis)
    nd = basis.nodal_dofs  # (2, N)
    perm = np.empty(2 * m.n_points, dtype=np.int64)
    perm[0::2] = nd[0]
    perm[1::2] = nd[1]
    Kfe = sp.csr_matrix(Kfe)[perm][:, perm]
    K = cls(m, 1e5, 0.2).stiffness()
    diff = _pattern(K) - _pattern(Kfe)
    assert diff.count_nonzero() == 0


@pytest.mark.parametrize("cls", MODELS)
@pytest.mark.parametrize("nu", [-0.5, 0.0, 0.2, 0.45])
def test_periodic_lattice_homogeneous_strain_has_no_residual(cls, nu):
    m = dv.mesh.periodic_square(600, kind="lattice")
    model = cls(m, 1e7, nu)
    eps = np.array([[1e-3, 4e-4], [4e-4, -7e-4]])
    u = m.points @ eps.T
    f = model.internal_force(u, strain=eps)
    scale = model.k_n * m.h * 1e-3
    assert np.abs(f).max() <= 1e-10 * scale
    # linearised: K acting on the affine field through the period
    t = model.linear_tension(u, strain=eps)
    b = m.topology.bonds
    fl = np.zeros((m.n_points, 2))
    from dvstatic.lattice import geometry

    d = geometry.of(m).direction
    for c in range(2):
        fl[:, c] = np.bincount(b[:, 1], t * d[:, c], m.n_points) - np.bincount(
            b[:, 0], t * d[:, c], m.n_points
        )
    assert np.abs(fl).max() <= 1e-10 * np.abs(t).max()


def test_dv_calibration_is_paper_eqs_9_10(jittered_small):
    E, nu = 2e5, 0.27
    model = dv.DV(jittered_small, E, nu, **PAPER)
    from dvstatic.lattice import geometry

    g = geometry.of(jittered_small)
    area = jittered_small.area
    alpha = np.sum(g.length**2) / (8 * area)
    beta = np.sum(g.length * g.r) / (8 * area)
    assert model.k_n == pytest.approx(E * (3 - nu) / (8 * alpha * (1 - nu**2)), rel=1e-12)
    assert model.nu_m == pytest.approx(alpha * (3 * nu - 1) / (beta * (3 - nu)), rel=1e-12)
    assert beta == pytest.approx(0.25, rel=1e-12)  # sum l r / 2 = area


def test_rv_moments_from_linearised_circumcentre():
    """RV: tau = r and sum l rho = -sum l r, so M1 = -beta, M2 = 5 beta on any mesh."""
    for m in [
        dv.mesh.rectangle(1, 1, 0.1, kind="random", seed=2),
        dv.mesh.periodic_square(400, kind="jittered", seed=2),
    ]:
        mom = dv.RV(m, 1e5, 0.2, **PAPER).micro.moments
        assert mom.m1 == pytest.approx(-mom.beta, rel=1e-10)
        assert mom.m2 == pytest.approx(5 * mom.beta, rel=1e-10)


@pytest.mark.parametrize("cls", MODELS)
def test_rv_and_dv_moments_match_probed_stress(cls):
    """Calibration moments agree with stresses measured under imposed strains."""
    m = dv.mesh.periodic_square(3000, kind="random", seed=5)
    model = cls(m, 1e7, 0.2, **PAPER)
    C = dv.elastic_tensor(model)
    mom = model.micro.moments
    k, num = model.k_n, model.nu_m
    assert C[0, 0] == pytest.approx(3 * mom.alpha * k + mom.m1 * k * num, rel=0.02)
    assert C[0, 1] == pytest.approx(mom.alpha * k + mom.m2 * k * num, rel=0.02)


@pytest.mark.parametrize("cls", MODELS)
def test_internal_force_matches_stiffness_for_small_u(cls, jittered_small):
    model = cls(jittered_small, 1e5, 0.2)
    rng = np.random.default_rng(0)
    u = rng.normal(size=(jittered_small.n_points, 2)) * 1e-9
    f = model.internal_force(u)
    Ku = model.stiffness() @ u.reshape(-1)
    assert np.linalg.norm(f - Ku) <= 1e-6 * np.linalg.norm(Ku)


def test_nu_m_zero_skips_coupling_and_still_matches():
    m = dv.mesh.rectangle(1, 1, 0.1, kind="jittered", seed=1)
    model = dv.DV(m, 1e5, 1.0 / 3.0, **PAPER)
    assert model.nu_m == pytest.approx(0.0, abs=1e-15)
    K = model.stiffness()
    assert abs(K - K.T).max() <= 1e-13 * abs(K).max()


def test_method_paper_is_the_four_keywords_of_the_paper(jittered_small):
    """``method="paper"`` is the paper's model: the same calibration, springs, cells and
    tensors as the four keywords, kept by ``replaced``; a keyword that contradicts it is
    refused, naming it."""
    paper = dv.DV(jittered_small, 1e5, 0.2, method="paper")
    four = dv.DV(
        jittered_small,
        1e5,
        0.2,
        calibration="paper",
        bonds="uniform",
        boundary_cells="lattice",
        anisotropy="keep",
    )
    assert (paper.calibration, paper.bonds, paper.boundary_cells, paper.anisotropy) == (
        "paper",
        "uniform",
        "lattice",
        "keep",
    )
    assert abs(paper.stiffness() - four.stiffness()).max() == 0.0
    assert paper.replaced(damage=None).bonds == "uniform"
    with pytest.raises(dv.InputError) as info:
        dv.DV(jittered_small, 1e5, 0.2, method="paper", bonds="surface")
    assert info.value.param == "bonds"
    with pytest.raises(dv.InputError) as info:
        dv.DV(jittered_small, 1e5, 0.2, method="exact")
    assert info.value.param == "method"
