import numpy as np
import pytest

import dvstatic as dv
from dvstatic.mesh import Mesh


@pytest.mark.parametrize("kind", ["lattice", "jittered", "random"])
def test_rectangle_boundary_nodes_on_sides(kind):
    w, hgt, h = 2.0, 1.0, 0.1
    m = dv.mesh.rectangle(w, hgt, h, kind=kind, seed=1)
    assert m.area == pytest.approx(w * hgt, rel=1e-12)
    on = {
        "left": lambda p: p[:, 0] == 0.0,
        "right": lambda p: p[:, 0] == w,
        "bottom": lambda p: p[:, 1] == 0.0,
        "top": lambda p: p[:, 1] == hgt,
    }
    covered = 0.0
    for name, test in on.items():
        nodes = m.part_nodes(name)
        assert np.all(test(m.points[nodes])), name
        e = m.part_edges(name)
        lengths = np.hypot(*(m.points[e[:, 1]] - m.points[e[:, 0]]).T)
        covered += lengths.sum()
        # spacing about h (jittered slides along the side; encroachment splits halve)
        assert 0.2 * h < lengths.mean() < 1.5 * h
    assert covered == pytest.approx(2 * (w + hgt), rel=1e-12)
    # every boundary node belongs to a part
    assert set(m.boundary_nodes) == set(np.unique(np.vstack(list(m.parts.values()))))


def test_lattice_is_regular_when_size_fits():
    h = 0.1
    ny = 8
    m = dv.mesh.rectangle(1.0, ny * h * np.sqrt(3) / 2, h, kind="lattice")
    lengths = m.bond_lengths()
    interior = lengths[np.isclose(lengths, h, rtol=1e-9)]
    assert interior.size > 0.8 * lengths.size
    assert m.edge_length_spread() < 0.2


def test_sigma_l_grows_with_irregularity():
    s = [
        dv.mesh.rectangle(1, 1, 0.05, kind=k, seed=0).edge_length_spread()
        for k in ("lattice", "jittered", "random")
    ]
    assert s[0] < s[1] < s[2]


def test_perturbed_keeps_boundary_and_corners():
    m = dv.mesh.rectangle(1, 1, 0.1, kind="lattice")
    p = m.perturbed(0.03, seed=2)
    corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    for c in corners:
        assert np.any(np.all(p.points == c, axis=1))
    for name, axis, value in [
        ("left", 0, 0.0),
        ("right", 0, 1.0),
        ("bottom", 1, 0.0),
        ("top", 1, 1.0),
    ]:
        assert np.all(p.points[p.part_nodes(name), axis] == value)
    assert p.area == pytest.approx(1.0, rel=1e-12)
    assert p.edge_length_spread() > m.edge_length_spread()
    # deterministic for a seed
    q = m.perturbed(0.03, seed=2)
    np.testing.assert_array_equal(p.points, q.points)


@pytest.mark.parametrize("kind", ["random", "jittered", "lattice"])
def test_periodic_square_closes(kind):
    m = dv.mesh.periodic_square(500, kind=kind, seed=4)
    assert m.is_periodic
    assert m.area == pytest.approx(1.0, rel=1e-12)
    assert m.boundary_edges.size == 0
    assert np.all(m.topology.n_tris_per_bond == 2)
    # Euler characteristic of the torus: V - E + F = 0
    assert m.n_points - m.n_bonds + m.n_triangles == 0
    assert np.any(m.topology.bond_image != 0)


def test_mesh_orients_triangles_ccw():
    p = np.array([[0, 0], [1, 0], [0, 1], [1, 1.0]])
    t = np.array([[0, 2, 1], [1, 2, 3]])
    m = Mesh(p, t)
    assert np.all(m.triangle_areas > 0)
    assert m.area == pytest.approx(1.0)
    assert m.boundary_edges.shape == (4, 2)


def test_mesh_arrays_are_read_only(lattice_small):
    with pytest.raises(ValueError):
        lattice_small.points[0, 0] = 3.0


def test_graded_mesh_follows_the_size_field():
    """A size field h(x): boundary edges and cells follow it (a CVT mesh)."""

    def h(x):
        return 0.02 + 0.06 * x[:, 0]  # from 0.02 at x = 0 to 0.08 at x = 1

    mesh = dv.mesh.rectangle(1.0, 1.0, h)
    assert mesh.sampling.kind == "cvt"
    for part in ("bottom", "top"):
        e = mesh.part_edges(part)
        mid = mesh.points[e].mean(axis=1)
        length = np.hypot(*(mesh.points[e[:, 1]] - mesh.points[e[:, 0]]).T)
        np.testing.assert_allclose(length, h(mid), rtol=0.15)
    # node density ~ 1 / h^2: the left tenth holds many more nodes than the right one
    x = mesh.points[:, 0]
    left, right = np.sum(x < 0.1), np.sum(x > 0.9)
    ratio = (h(np.array([[0.95, 0]])) / h(np.array([[0.05, 0]])))[0] ** 2
    assert 0.6 * ratio < left / right < 1.4 * ratio
    # the bonds follow it too (about h(x) everywhere, no sliver)
    d = mesh.bond_vectors()
    mid = mesh.points[mesh.topology.bonds].mean(axis=1)
    rel = np.hypot(*d.T) / h(mid)
    assert 0.6 < np.median(rel) < 1.3 and rel.max() < 2.5


@pytest.mark.parametrize(
    "h,match",
    [
        (lambda x: np.ones(3), "must return shape"),
        (lambda x: -np.ones(len(x)), "finite and > 0"),
        (lambda x: np.full(len(x), np.nan), "finite and > 0"),
        (lambda x: np.full(len(x), 5.0), "larger than the domain"),
    ],
)
def test_bad_size_field_is_refused(h, match):
    with pytest.raises(ValueError, match=match):
        dv.mesh.rectangle(1.0, 1.0, h)


def test_size_near_a_hole():
    domain = dv.domain.Domain(
        dv.domain.Polygon([[0, 0], [2, 0], [2, 2], [0, 2]], ("b", "r", "t", "l")),
        (dv.domain.Circle((1.0, 1.0), 0.2, "hole"),),
    )
    h = dv.mesh.size_near(domain, "hole", 0.02, 0.1, 0.5)
    np.testing.assert_allclose(
        h(np.array([[1.2, 1.0], [1.45, 1.0], [2.0, 2.0]])), [0.02, 0.06, 0.1]
    )
    mesh = dv.mesh.generate(domain, h)
    e = mesh.part_edges("hole")
    length = np.hypot(*(mesh.points[e[:, 1]] - mesh.points[e[:, 0]]).T)
    assert abs(length.mean() / 0.02 - 1) < 0.1
    with pytest.raises(ValueError, match="unknown part"):
        dv.mesh.size_near(domain, "bore", 0.02, 0.1, 0.5)
    with pytest.raises(ValueError, match="must not exceed"):
        dv.mesh.size_near(domain, "hole", 0.2, 0.1, 0.5)
