"""Paper exp. 1: moduli recovered from imposed homogeneous strain (affine)."""

import numpy as np
import pytest

import dvstatic as dv

E = 1e7
#: the paper's model: calibrated under affine strain, as exp. 1 measures
PAPER = {
    "calibration": "paper",
    "bonds": "uniform",
    "boundary_cells": "lattice",
    "anisotropy": "keep",
}
NUS = [-0.5, -0.2, 0.0, 0.2, 0.33, 0.45]


@pytest.fixture(scope="module")
def periodic_random():
    return dv.mesh.periodic_square(20000, kind="random", seed=11)


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
@pytest.mark.parametrize("nu", NUS)
def test_elastic_tensor_periodic_random(periodic_random, cls, nu):
    C = dv.elastic_tensor(cls(periodic_random, E, nu, **PAPER))
    target = dv.plane_stress_tensor(E, nu)
    assert C[0, 0] == pytest.approx(target[0, 0], rel=0.015)
    # C1122 relative to its own target; where nu ~ 0 the target vanishes, so compare
    # with C1111 as the scale there
    tol = 0.015 * max(abs(target[0, 1]), 0.1 * target[0, 0])
    assert abs(C[0, 1] - target[0, 1]) <= tol
    assert C[2, 2] == pytest.approx(target[2, 2], rel=0.015)
    # symmetric up to round-off
    assert abs(C[0, 1] - C[1, 0]) <= 1e-10 * C[0, 0]


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_elastic_tensor_bounded_random(cls):
    m = dv.mesh.rectangle(1.0, 1.0, 0.01, kind="random", seed=3)
    C = dv.elastic_tensor(cls(m, E, 0.2, **PAPER))
    target = dv.plane_stress_tensor(E, 0.2)
    assert C[0, 0] == pytest.approx(target[0, 0], rel=0.03)
    assert C[0, 1] == pytest.approx(target[0, 1], rel=0.03)


def test_homogenize_is_linear_at_small_strain(periodic_random):
    model = dv.DV(periodic_random, E, 0.2)
    eps = np.array([[1e-6, 0.0], [0.0, 0.0]])
    s = dv.homogenize(model, eps)
    C = dv.elastic_tensor(model)
    assert s[0, 0] / 1e-6 == pytest.approx(C[0, 0], rel=1e-4)


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_homogenize_rigid_rotation_gives_zero_stress(cls):
    m = dv.mesh.periodic_square(2000, kind="random", seed=1)
    model = cls(m, E, 0.2)
    th = 0.7
    F = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    s = dv.homogenize(model, F - np.eye(2))
    assert np.abs(s).max() <= 1e-9 * E


def test_plane_stress_tensor_mandel_form():
    C = dv.plane_stress_tensor(2.0, 0.25)
    c = 2.0 / (1 - 0.25**2)
    np.testing.assert_allclose(C, c * np.array([[1, 0.25, 0], [0.25, 1, 0], [0, 0, 0.75]]))
