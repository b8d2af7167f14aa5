"""Parts of a mesh outside what their calibration was measured on
(dvstatic.lattice.calibration.quality): a patch of another micro-structure is found and
calibrated by class; what no sample reaches is named in a warning."""

import logging

import numpy as np
import pytest
from scipy.spatial import Delaunay

import dvstatic as dv
from dvstatic.lattice.calibration import calibration_flags, classes, grading_flags, spread_classes
from dvstatic.lattice.calibration.quality import TOLERANCE, patches
from dvstatic.lattice.calibration.relaxed import MIXED_SPREAD, local_spread, spread_field

E, NU = 1e4, 0.3
CENTRE = np.array([1.0, 0.5])


def patch_mesh(h=0.02, r=0.15, regions=False):
    """A 2 x 1 regular lattice with a disc of random points of radius ``r`` at its
    centre (no recipe)."""
    a = dv.mesh.rectangle(2, 1, h, kind="lattice").points
    a = a[np.hypot(*(a - CENTRE).T) > r]
    b = dv.mesh.rectangle(2, 1, h, kind="random", seed=3).points
    b = b[np.hypot(*(b - CENTRE).T) <= r - 0.3 * h]
    pts = np.vstack([a, b])
    tri = Delaunay(pts).simplices
    bare = dv.Mesh(pts, tri)
    mid = pts[bare.boundary_edges].mean(axis=1)
    edges = bare.boundary_edges
    parts = {"left": edges[mid[:, 0] < 1e-9], "right": edges[mid[:, 0] > 2 - 1e-9]}
    reg = {}
    if regions:
        c = pts[tri].mean(axis=1)
        reg = {"disc": np.flatnonzero(np.hypot(*(c - CENTRE).T) < r)}
    return dv.Mesh(pts, tri, parts=parts, regions=reg)


def clustered(n=3000, seed=0):
    """Random points in the unit square, each with a satellite 0.004 away: more
    irregular than random points (local spread 0.46 against 0.365)."""
    rng = np.random.default_rng(seed)
    p = rng.random((n, 2))
    p = np.vstack([p, p + rng.normal(0, 0.004, p.shape)])
    p = p[(p > 0).all(axis=1) & (p < 1).all(axis=1)]
    return dv.Mesh(p, Delaunay(p).simplices)


def test_a_patch_too_small_for_the_percentiles_is_found_and_calibrated_by_class():
    mesh = patch_mesh()
    lo, hi = np.percentile(spread_field(mesh), [10, 90])
    assert hi - lo <= MIXED_SPREAD  # the percentile test alone sees one micro-structure
    found = patches(mesh, local_spread(mesh))
    assert len(found) == 1
    c = mesh.points[mesh.triangles[found[0]]].reshape(-1, 2).mean(axis=0)
    assert np.hypot(*(c - CENTRE)) < 0.03
    assert 300 < len(found[0]) < mesh.n_triangles / 10
    assert spread_classes(mesh) is not None


def test_flags_name_the_region_the_descriptor_and_the_values():
    mesh = patch_mesh(regions=True)
    calibrated = np.full(mesh.n_triangles, local_spread(mesh))
    (flag,) = calibration_flags(mesh, calibrated)
    assert flag.kind == "patch" and flag.where == "region 'disc'"
    assert flag.spread > flag.calibrated + TOLERANCE
    assert flag.box[0] > 0.8 and flag.box[2] < 1.2
    assert "local spread" in flag.message() and "region 'disc'" in flag.message()
    # without regions: the place
    (flag,) = calibration_flags(patch_mesh(), calibrated)
    assert flag.where.startswith("triangles around (1")


@pytest.mark.parametrize("kind", ["jittered", "cvt", "random"])
def test_meshes_of_one_micro_structure_raise_no_flag(kind):
    r = dv.mesh.rectangle(2, 1, 0.015, kind=kind, seed=5)
    bare = dv.Mesh(r.points, r.triangles)
    assert calibration_flags(bare, np.full(bare.n_triangles, local_spread(bare))) == ()
    assert spread_classes(bare) is None


def test_a_graded_mesh_raises_no_flag():
    tunnel = dv.domain.Circle((0, 0), 1.0, "tunnel")
    domain = dv.domain.Domain(dv.domain.Circle((0, 0), 10.0, "boundary"), (tunnel,))
    mesh = dv.mesh.generate(domain, dv.mesh.size_near(domain, "tunnel", 0.05, 0.5, 3.0))
    bare = dv.Mesh(mesh.points, mesh.triangles, parts=mesh.parts)  # without its recipe
    assert calibration_flags(bare, np.full(bare.n_triangles, local_spread(bare))) == ()


@pytest.mark.parametrize("kind", ["jittered", "cvt", "random"])
def test_uniform_meshes_of_every_kind_raise_no_grading_flag(kind):
    """The spacing's slope on uniform meshes is noise: no region above the limit (on
    random points the largest node value off the boundary rings reads about 0.1)."""
    for seed in (1, 2):
        r = dv.mesh.rectangle(2, 1, 0.015, kind=kind, seed=seed)
        assert grading_flags(dv.Mesh(r.points, r.triangles)) == []


def test_the_hull_of_raw_points_is_not_taken_for_a_steep_grading():
    """A Delaunay triangulation of raw random points has slivers along its hull, whose
    long bonds read as a spacing growing fast towards the boundary: such a boundary's
    rings are left out (before: six regions flagged on 1e5 points)."""
    p = np.random.default_rng(0).random((20000, 2))
    assert grading_flags(dv.Mesh(p, Delaunay(p).simplices)) == []


def test_an_imported_mesh_graded_too_steeply_is_named_in_a_warning(caplog):
    """A mesh without recipe whose spacing grows by 0.15 per unit length (the tunnel's
    grading that biased its wall's hoop stress by +5 %) is flagged, with the slope and
    the place; the same mesh graded at 0.075 is not."""
    from dvstatic.lattice.calibration.quality import GRADING, slope_field

    tunnel = dv.domain.Circle((0, 0), 1.0, "tunnel")
    domain = dv.domain.Domain(dv.domain.Circle((0, 0), 10.0, "boundary"), (tunnel,))
    slopes = []
    for distance in (3.0, 6.0):
        mesh = dv.mesh.generate(domain, dv.mesh.size_near(domain, "tunnel", 0.05, 0.5, distance))
        bare = dv.Mesh(mesh.points, mesh.triangles, parts=mesh.parts)  # as if imported
        slopes.append(float(slope_field(bare).max()))
        model = dv.DV(bare, E, NU)
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="dvstatic.lattice"):
            flags = [f for f in model.calibration_flags if f.kind == "grading"]
        if distance == 6.0:
            assert flags == []
            continue
        (flag,) = flags
        assert 0.14 < flag.spread < 0.17 and flag.calibrated == GRADING
        x0, y0, x1, y1 = flag.box
        assert x0 < -1 and x1 > 1 and flag.triangles > 500  # the ring around the tunnel
        assert any("grows by up to 0.1" in r.getMessage() for r in caplog.records)
        assert flag.as_dict()["slope"] == flag.spread
    assert slopes[0] > 0.14 and slopes[1] < 0.11  # the size fields' 0.15 and 0.075


def test_a_mesh_beyond_the_samples_reach_is_named_in_a_warning(caplog):
    mesh = clustered()
    model = dv.DV(mesh, E, NU)
    with caplog.at_level(logging.WARNING, logger="dvstatic.lattice.models"):
        _ = model.operator
    (flag,) = model.calibration_flags
    assert flag.kind == "reach" and flag.where == "the whole mesh"
    assert flag.spread > 0.42 and abs(flag.calibrated - 0.365) < 0.01
    assert flag.triangles == mesh.n_triangles
    assert sum("beyond the most irregular" in r.getMessage() for r in caplog.records) == 1
    assert model.damaged(np.ones(mesh.n_bonds)).calibration_flags == model.calibration_flags
    from dvstatic.report import _model_summary

    (entry,) = _model_summary(model)["calibration_flags"]
    assert entry["kind"] == "reach" and entry["message"] == flag.message()


def test_meshes_with_a_recipe_and_given_micro_parameters_are_not_checked():
    mesh = dv.mesh.rectangle(1, 1, 0.05, kind="random")
    assert dv.DV(mesh, E, NU).calibration_flags == ()
    model = dv.DV(clustered(), E, NU, calibration=dv.DV(mesh, E, NU).micro)
    assert model.calibration_flags == ()


def _patch_modulus(model):
    """E_eff / E inside the disc (r < 0.1) from its mean strain under uniaxial tension
    (a soft or stiff disc takes a strain near its own compliance)."""
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0, 0), y=0.0)]
    sol = dv.solve(model, sup, [dv.Traction("right", (1.0, 0.0))])
    mesh = model.mesh
    x, u = mesh.points[mesh.triangles], sol.u[mesh.triangles]
    d = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=-1)
    du = np.stack([u[:, 1] - u[:, 0], u[:, 2] - u[:, 0]], axis=-1)
    exx = (du @ np.linalg.inv(d))[:, 0, 0]
    area = 0.5 * np.abs(np.linalg.det(d))
    sel = np.hypot(*(x.mean(axis=1) - CENTRE).T) < 0.1
    return 1.0 / (E * np.sum(exx[sel] * area[sel]) / area[sel].sum())


@pytest.mark.slow
def test_the_patch_gets_its_modulus_by_class(monkeypatch):
    mesh = patch_mesh(h=0.01)  # 23,686 nodes; the disc 30 spacings across
    assert abs(_patch_modulus(dv.DV(mesh, E, NU)) - 1) < 0.02  # measured 1.004
    monkeypatch.setattr(classes, "patches", lambda *a, **k: [])
    one = dv.DV(mesh, E, NU)
    assert one.micro_field is None and len(one.calibration_flags) == 1
    assert _patch_modulus(one) < 0.95  # measured 0.921


def clustered_disc(h=0.02, r=0.2, materials=False):
    """A 2 x 1 regular lattice with a disc of clustered points (random points, each
    with a satellite 0.1 h away) at its centre: local spread 0.51 in the disc."""
    rng = np.random.default_rng(0)
    a = dv.mesh.rectangle(2, 1, h, kind="lattice").points
    a = a[np.hypot(*(a - CENTRE).T) > r]
    b = dv.mesh.rectangle(2, 1, h, kind="random", seed=3).points
    b = b[np.hypot(*(b - CENTRE).T) <= r - 0.3 * h]
    pts = np.vstack([a, b, b + rng.normal(0, 0.1 * h, b.shape)])
    tri = Delaunay(pts).simplices
    edges = dv.Mesh(pts, tri).boundary_edges
    mid = pts[edges].mean(axis=1)
    parts = {"left": edges[mid[:, 0] < 1e-9], "right": edges[mid[:, 0] > 2 - 1e-9]}
    c = pts[tri].mean(axis=1)
    reg = {"disc": np.flatnonzero(np.hypot(*(c - CENTRE).T) < r)} if materials else {}
    return dv.Mesh(pts, tri, parts=parts, regions=reg)


def test_hull_slivers_of_raw_points_are_not_patches():
    p = np.random.default_rng(0).random((30_000, 2))
    mesh = dv.Mesh(p, Delaunay(p).simplices)  # slivers up to 7 rings deep along the hull
    assert patches(mesh, local_spread(mesh)) == []  # one of 116 triangles, 1 ring off
    assert spread_classes(mesh) is None


def test_an_interface_between_classes_is_not_a_patch():
    h = 0.025
    a = dv.mesh.rectangle(1, 1, h, kind="lattice").points
    b = dv.mesh.rectangle(1, 1, h, kind="random", seed=3).points + [1.0, 0.0]
    pts = np.unique(np.round(np.vstack([a, b]), 9), axis=0)
    mesh = dv.Mesh(pts, Delaunay(pts).simplices)
    x = mesh.points[mesh.triangles].mean(axis=1)[:, 0]
    calibrated = np.where(x < 1, 0.0, 0.365)  # two classes, cut at the interface
    assert calibration_flags(mesh, calibrated) == ()  # unsmoothed: a strip of 186


def test_a_clustered_region_in_a_mesh_calibrated_by_class_is_a_patch():
    model = dv.DV(clustered_disc(), E, NU)
    assert model.micro_field is not None
    (flag,) = model.calibration_flags
    assert flag.kind == "patch" and flag.where.startswith("triangles around (1")
    assert flag.spread > 0.45 and abs(flag.calibrated - 0.365) < 0.01
    assert "measured at" in flag.message()


@pytest.mark.parametrize("n", [151, 300, 524])
def test_small_random_meshes_are_within_reach(n):
    for seed in range(5):
        p = np.random.default_rng(seed).random((n, 2))
        mesh = dv.Mesh(p, Delaunay(p).simplices)
        asked = np.full(mesh.n_triangles, local_spread(mesh))  # 0.36 to 0.39
        flags = calibration_flags(mesh, asked, np.full(mesh.n_triangles, 0.365))
        assert [f for f in flags if f.kind == "reach"] == []
    big = clustered()  # 0.46: beyond reach however it is counted
    asked = np.full(big.n_triangles, local_spread(big))
    (flag,) = calibration_flags(big, asked, np.full(big.n_triangles, 0.365))
    assert flag.kind == "reach"


def test_a_region_covering_nearly_the_whole_mesh_names_no_place():
    bare = patch_mesh()
    mesh = dv.Mesh(bare.points, bare.triangles, regions={"body": np.arange(bare.n_triangles)})
    (flag,) = calibration_flags(mesh, np.full(mesh.n_triangles, local_spread(mesh)))
    assert flag.where.startswith("triangles around (1")


def test_companion_models_do_not_warn_again(caplog):
    mesh = clustered_disc(materials=True)
    model = dv.DV(mesh, E, NU, materials={"disc": (2 * E, NU)})
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0, 0), y=0.0)]
    with caplog.at_level(logging.WARNING, logger="dvstatic"):
        sol = dv.solve(model, sup, [dv.Traction("right", (1.0, 0.0))])
        sol.stress()
    warned = [r for r in caplog.records if "calibration:" in r.getMessage()]
    assert len(warned) == len(model.calibration_flags) >= 1
    other = dv.DV(patch_mesh(), E, NU)
    with pytest.raises(ValueError, match="same mesh"):
        other.share_calibration_flags(model)


def test_the_fracture_criteria_do_not_warn_again(caplog):
    mesh = clustered_disc(materials=True)
    model = dv.DV(mesh, E, NU, materials={"disc": (2 * E, NU)})
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0, 0), y=0.0)]
    with caplog.at_level(logging.WARNING, logger="dvstatic"):
        dv.fracture(model, sup, [dv.Traction("right", (1.0, 0.0))], ft=1.0, max_events=1)
    warned = [r for r in caplog.records if "calibration:" in r.getMessage()]
    assert len(warned) == len(model.calibration_flags) >= 1


def square_grid(alternate: bool, nx: int = 60, ny: int = 30) -> dv.Mesh:
    """A 2 x 1 grid of squares, each split by a diagonal: alternating (every node with 4
    or 8 bonds) or parallel (6 bonds, all diagonals along one direction)."""
    x, y = np.meshgrid(np.linspace(0, 2, nx + 1), np.linspace(0, 1, ny + 1))
    p = np.c_[x.ravel(), y.ravel()]
    tri = []
    for j in range(ny):
        for i in range(nx):
            a, b = j * (nx + 1) + i, j * (nx + 1) + i + 1
            c, d = (j + 1) * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i
            tri += [[a, b, d], [b, c, d]] if alternate and (i + j) % 2 else [[a, b, c], [a, c, d]]
    return dv.Mesh(p, np.array(tri))


def test_cells_of_no_sample_family_are_named_in_a_warning(caplog):
    model = dv.DV(square_grid(alternate=True), E, NU)
    with caplog.at_level(logging.WARNING, logger="dvstatic.lattice.models"):
        (flag,) = model.calibration_flags
    assert flag.kind == "defects" and flag.where == "the whole mesh" and flag.spread == 1.0
    assert "other than six bonds" in flag.message()
    assert dv.DV(patch_mesh(), E, NU).calibration_flags == ()  # lattice beside random


def test_an_anisotropic_fabric_is_named_in_a_warning():
    from dvstatic.lattice.calibration import anisotropy_flags
    from dvstatic.lattice.calibration.quality import ANISOTROPY

    model = dv.DV(square_grid(alternate=False), E, NU)  # 9 % soft along x at 5,151 nodes
    (flag,) = model.calibration_flags
    assert flag.kind == "anisotropy" and flag.where == "the whole mesh"
    assert flag.spread == pytest.approx(0.25) and "anisotropic" in flag.message()
    for kind in ("random", "cvt", "jittered"):  # deviators up to 0.16 at single nodes
        r = dv.mesh.rectangle(2, 1, 0.02, kind=kind, seed=4)
        assert anisotropy_flags(dv.Mesh(r.points, r.triangles)) == [], kind
    assert ANISOTROPY < 0.25


def test_the_fabric_correction_refuses_a_fabric_it_cannot_correct():
    with pytest.raises(ValueError, match="too anisotropic at"):
        _ = dv.DV(square_grid(alternate=False), E, NU, bonds="fabric").operator
