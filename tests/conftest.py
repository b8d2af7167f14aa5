"""Shared fixtures: small meshes and the uniaxial problem of the paper's exp. 3."""

import numpy as np
import pytest

import dvstatic as dv

E_BEAM = 1e5
NU = 0.2


def uniaxial_problem():
    """Unit square, rollers on left and bottom, traction -1 on the right side."""
    supports = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
    loads = [dv.Traction("right", (-1.0, 0.0))]
    return supports, loads


def uniaxial_exact(points, E=E_BEAM, nu=NU, sxx=-1.0):
    """Plane-stress solution of uniform sigma_xx: u = (s x / E, -nu s y / E)."""
    return np.c_[sxx * points[:, 0] / E, -nu * sxx * points[:, 1] / E]


def rel_l2(u, ref):
    return float(np.linalg.norm(u - ref) / np.linalg.norm(ref))


@pytest.fixture(scope="session")
def jittered_small():
    return dv.mesh.rectangle(1.0, 1.0, 0.1, kind="jittered", seed=3)


@pytest.fixture(scope="session")
def lattice_small():
    return dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
