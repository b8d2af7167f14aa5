"""A mesh that mixes micro-structures (a lattice beside random points, no recipe) is
calibrated class by class of its local spread (dvstatic.lattice.calibration.classes)."""

import numpy as np
import pytest
from scipy.spatial import Delaunay

import dvstatic as dv
from dvstatic import parallel as distributed
from dvstatic.lattice.calibration import relaxed, spread_classes

E, NU = 1e4, 0.3


def mixed(h=0.05):
    """A 2 x 1 plate: a regular lattice on the left half, random points on the right."""
    a = dv.mesh.rectangle(1, 1, h, kind="lattice").points
    b = dv.mesh.rectangle(1, 1, h, kind="random", seed=3).points + [1.0, 0.0]
    pts = np.unique(np.round(np.vstack([a, b]), 9), axis=0)
    tri = Delaunay(pts).simplices
    x = pts[tri]
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    tri = tri[np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) > 1e-12]
    bare = dv.Mesh(pts, tri)
    mid = pts[bare.boundary_edges].mean(axis=1)
    edges = bare.boundary_edges
    parts = {"left": edges[mid[:, 0] < 1e-9], "right": edges[mid[:, 0] > 2 - 1e-9]}
    return dv.Mesh(pts, tri, parts=parts)


def moduli_of_halves(model):
    """E_eff / E of each half from the slope of u_x under uniaxial tension."""
    sup = [dv.Fix("left", x=0), dv.Fix(at=(0, 0), y=0)]
    sol = dv.solve(model, sup, [dv.Traction("right", (1.0, 0.0))])
    p = model.mesh.points
    rows = (p[:, 1] > 0.2) & (p[:, 1] < 0.8)
    out = []
    for lo in (0.2, 1.2):
        sel = rows & (p[:, 0] > lo) & (p[:, 0] < lo + 0.6)
        out.append(1.0 / (np.polyfit(p[sel, 0], sol.u[sel, 0], 1)[0] * E))
    return out


@pytest.mark.parametrize("model", [dv.DV, pytest.param(dv.RV, marks=pytest.mark.slow)])
def test_a_lattice_beside_random_points_gets_each_side_right(model):
    """The lattice half's modulus within 1 % (DV) / 1.5 % (RV) at 1,045 nodes, where one
    calibration for the whole mesh (its overall spread 0.27) makes it 8-10 % stiff
    (3,845 nodes: L2 from P2 5.2 -> 1.4 %). The random half is as noisy as random points
    are at this size (a random mesh of its own, with its recipe: 1.13 in one half, 0.99
    in the other), so it is held to 5 %."""
    mesh = mixed()
    m = model(mesh, E, NU)
    field = m.micro_field
    assert field is not None and field.classes.n_classes >= 2
    centre_x = mesh.points[mesh.triangles].mean(axis=1)[:, 0]
    lattice_side = field.classes.of_triangle[centre_x < 0.7]
    random_side = field.classes.of_triangle[centre_x > 1.3]
    assert np.median(field.classes.spread[lattice_side]) < 0.05
    assert np.median(field.classes.spread[random_side]) > 0.25
    left, right = moduli_of_halves(m)
    assert left == pytest.approx(1.0, abs=0.01 if model is dv.DV else 0.015)
    assert right == pytest.approx(1.0, abs=0.05)
    # one calibration for all, from the mesh's overall local spread (what it replaces)
    one = model(mesh, E, NU, calibration=relaxed(model.kind, mesh, E, NU))
    assert one.micro_field is None
    assert moduli_of_halves(one)[0] > 1.05
    biggest = np.bincount(field.classes.of_triangle).argmax()
    assert m.micro is field.micros[(0, biggest)]  # the record: the largest class


def test_meshes_of_one_micro_structure_keep_one_calibration():
    cvt = dv.mesh.rectangle(2, 1, 0.05, kind="cvt", seed=1)
    bare = dv.Mesh(cvt.points, cvt.triangles)  # as if imported: no recipe
    assert spread_classes(bare) is None
    assert dv.DV(cvt, E, NU).micro_field is None  # a recipe


def test_the_classes_go_with_damage_and_into_the_stress_recovery():
    """The damaged lattice (fracture's states) keeps the field; under a uniform stress
    the recovered stress is exact at every node (the responses are the field's)."""
    mesh = mixed()
    m = dv.DV(mesh, E, NU)
    d = np.ones(mesh.n_bonds)
    d[:5] = 0.5
    dm = m.damaged(d)
    assert dm.micro_field is m.micro_field
    k_intact = m.operator.spring[5:]
    assert np.allclose(dm.operator.spring[5:], k_intact, rtol=1e-12)
    sup = [dv.Fix("left", x=0), dv.Fix(at=(0, 0), y=0)]
    s = dv.solve(m, sup, [dv.Traction("right", (1.0, 0.0))]).stress()
    assert np.max(np.abs(s[:, 0, 0] - 1.0)) < 1e-6
    assert np.max(np.abs(s[:, 1, 1])) < 1e-6


def test_patches_find_their_triangles():
    from dvstatic.parallel.partition import layout, patch_triangles

    mesh = mixed()
    for rank in range(2):
        lay = layout(mesh, rank, 2)
        idx = patch_triangles(mesh, lay)
        got = np.sort(lay.local_nodes[lay.patch.triangles], axis=1)
        assert np.array_equal(got, np.sort(mesh.triangles[idx], axis=1))


def test_the_summary_says_the_mesh_was_calibrated_by_class():
    from dvstatic.console import _model_line
    from dvstatic.report import _model_summary

    m = dv.DV(mixed(), E, NU)
    md = _model_summary(m)
    classes = md["calibration_classes"]
    assert len(classes["spread"]) == m.micro_field.classes.n_classes
    assert sum(classes["triangles"]) == m.mesh.n_triangles
    assert "mixes micro-structures" in _model_line(md)


@pytest.mark.skipif(
    not distributed.available(),
    reason="petsc4py is not installed: run scripts/install_petsc.sh (the dvstatic[petsc] extra)",
)
def test_petsc_solves_a_mesh_calibrated_by_class_as_the_direct_solver_does():
    m = dv.DV(mixed(), E, NU)
    sup = [dv.Fix("left", x=0), dv.Fix(at=(0, 0), y=0)]
    loads = [dv.Traction("right", (1.0, 0.0))]
    sol = dv.solve(m, sup, loads, solver="petsc", rtol=1e-12)
    ref = dv.solve(m, sup, loads, solver="direct")
    assert sol.info.solver == "petsc" and sol.info.converged
    assert np.max(np.abs(sol.u - ref.u)) <= 1e-8 * np.max(np.abs(ref.u))


def test_patch_rows_equal_global_rows_on_a_mesh_calibrated_by_class():
    """The patches take their triangles' k_n and nu_m (the distributed engine's way)."""
    from dvstatic.parallel.partition import layout, patch_model

    mesh = mixed()
    model = dv.DV(mesh, E, NU)
    K = model.stiffness()
    for rank in range(2):
        lay = layout(mesh, rank, 2)
        pm = patch_model(model, lay)
        assert pm.micro_field is not None
        gd = np.stack([2 * lay.local_nodes, 2 * lay.local_nodes + 1], axis=1).reshape(-1)
        n2 = 2 * lay.n_owned
        assert abs(pm.stiffness()[:n2] - K[gd[:n2]][:, gd]).max() < 1e-9 * abs(K).max()
