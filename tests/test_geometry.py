import numpy as np
import pytest

import dvstatic as dv
from dvstatic.lattice import geometry


@pytest.mark.parametrize(
    "mesh",
    [
        dv.mesh.rectangle(1.0, 0.7, 0.05, kind="lattice"),
        dv.mesh.rectangle(1.0, 0.7, 0.05, kind="jittered", seed=1),
        dv.mesh.rectangle(1.0, 0.7, 0.05, kind="random", seed=1),
        dv.mesh.periodic_square(800, kind="random", seed=1),
    ],
    ids=["lattice", "jittered", "random", "periodic"],
)
def test_sum_lr_over_2_is_area(mesh):
    g = geometry.of(mesh)
    assert np.sum(g.length * g.r) / 2 == pytest.approx(mesh.area, rel=1e-12)
    assert g.cell_area.sum() == pytest.approx(mesh.area, rel=1e-12)
    assert g.dual_area.sum() == pytest.approx(mesh.area, rel=1e-12)
    assert np.all(g.dual_area > 0)


def test_lattice_interior_r_is_l_over_sqrt3():
    h = 0.1
    m = dv.mesh.rectangle(1.0, 6 * h * np.sqrt(3) / 2, h, kind="lattice")
    g = geometry.of(m)
    interior = m.topology.n_tris_per_bond == 2
    equilateral = np.isclose(g.length, h, rtol=1e-12) & interior
    # interior bonds whose two triangles are equilateral
    both_eq = equilateral & np.isclose(g.half_sides[:, 0], g.half_sides[:, 1], rtol=1e-12)
    assert both_eq.sum() > 50
    np.testing.assert_allclose(g.r[both_eq], g.length[both_eq] / np.sqrt(3), rtol=1e-12)


def test_half_side_is_half_l_cot_opposite_angle(jittered_small):
    g = geometry.of(jittered_small)
    x = g.x_tri
    for k in range(3):
        a = x[:, (k + 1) % 3] - x[:, k]
        b = x[:, (k + 2) % 3] - x[:, k]
        cos = np.einsum("ij,ij->i", a, b)
        sin = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        np.testing.assert_allclose(
            g.tri_r[:, k], 0.5 * g.tri_l[:, k] * cos / sin, rtol=1e-10, atol=1e-14
        )


def test_barycentric_reproduces_circumcentre(jittered_small):
    g = geometry.of(jittered_small)
    h = np.einsum("mv,mvi->mi", g.bary, g.x_tri)
    np.testing.assert_allclose(h, g.circumcentre, atol=1e-12)
    np.testing.assert_allclose(g.bary.sum(axis=1), 1.0, rtol=1e-12)
    # equidistant from the three vertices
    d = np.linalg.norm(g.x_tri - g.circumcentre[:, None, :], axis=2)
    np.testing.assert_allclose(d, d[:, :1].repeat(3, 1), rtol=1e-10)


def test_geometry_is_cached(jittered_small):
    assert geometry.of(jittered_small) is geometry.of(jittered_small)
