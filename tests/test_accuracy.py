"""Accuracy by default: the defaults converge under refinement on irregular meshes,
their calibration comes from the table for the built-in generators, and the lattice is
stable for every nu the calibration reaches."""

import numpy as np
import pytest

import dvstatic as dv
from dvstatic.lattice import calibration
from dvstatic.lattice.calibration import table
from dvstatic.lattice.stabilise import MARGIN, triangle_modes

E = 1e5
PAPER = {
    "calibration": "paper",
    "bonds": "uniform",
    "boundary_cells": "lattice",
    "anisotropy": "keep",
}


def _uniaxial_error(mesh, cls, nu, **kw):
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
    sol = dv.solve(cls(mesh, E, nu, **kw), sup, [dv.Traction("right", (-1.0, 0.0))])
    x, y = mesh.points.T
    exact = np.c_[-x / E, nu * y / E]
    return np.linalg.norm(sol.u - exact) / np.linalg.norm(exact)


def _cantilever_error(mesh, cls, nu, **kw):
    """Timoshenko & Goodier's end-loaded cantilever 4 x 1, exact field prescribed on
    the clamped end x = 4, parabolic shear on the free end x = 0."""
    L, D, inertia = 4.0, 1.0, 1.0 / 12.0
    G = E / (2 * (1 + nu))

    def exact(p):
        x, y = p[:, 0], p[:, 1] - D / 2
        u = (
            -(x**2) * y / (2 * E * inertia)
            - nu * y**3 / (6 * E * inertia)
            + y**3 / (6 * inertia * G)
            + (L**2 / (2 * E * inertia) - D**2 / (8 * inertia * G)) * y
        )
        v = (
            nu * x * y**2 / (2 * E * inertia)
            + x**3 / (6 * E * inertia)
            - L**2 * x / (2 * E * inertia)
            + L**3 / (3 * E * inertia)
        )
        return np.c_[u, v]

    def shear(p):
        y = p[:, 1] - D / 2
        return np.c_[np.zeros(len(y)), (D**2 / 4 - y**2) / (2 * inertia)]

    sup = [dv.Fix("right", x=lambda p: exact(p)[:, 0], y=lambda p: exact(p)[:, 1])]
    sol = dv.solve(cls(mesh, E, nu, **kw), sup, [dv.Traction("left", shear)])
    ref = exact(mesh.points)
    return np.linalg.norm(sol.u - ref) / np.linalg.norm(ref)


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_default_error_decreases_under_refinement_uniaxial(cls):
    errs = [_uniaxial_error(dv.mesh.rectangle(1, 1, h), cls, 0.2) for h in (1 / 12, 1 / 24, 1 / 48)]
    assert np.all(np.diff(errs) < 0), errs
    assert errs[-1] < 0.015  # about 2,900 nodes
    # converging: two halvings of h remove at least half of the error (0.68 of it per
    # halving here; the exact cells make the coarse meshes' error the smaller: DV 1.01 /
    # 0.69 / 0.47 %, one layer of cells 1.49 / 0.89 / 0.53 %)
    assert errs[2] < 0.5 * errs[0]


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_default_error_decreases_under_refinement_cantilever(cls):
    errs = [
        _cantilever_error(dv.mesh.rectangle(4, 1, h), cls, 0.3) for h in (1 / 6, 1 / 12, 1 / 24)
    ]
    assert np.all(np.diff(errs) < 0), errs
    assert errs[-1] < 0.02  # about 2,700 nodes


def test_the_default_is_the_accurate_configuration():
    mesh = dv.mesh.rectangle(1, 1, 1 / 32)
    for cls in (dv.DV, dv.RV):
        model = cls(mesh, E, 0.2)
        assert model.micro.calibration == "relaxed" and model.bonds == "surface"
        assert model.micro.stabilised and model.micro.details["source"] == "table"
        default = _uniaxial_error(mesh, cls, 0.2)
        paper = _uniaxial_error(mesh, cls, 0.2, **PAPER)
        assert default < 0.25 * paper, (cls.kind, default, paper)


@pytest.mark.parametrize("nu", [-0.3, 0.0, 0.45])
def test_defaults_reach_the_whole_nu_range_on_the_default_mesh(nu):
    mesh = dv.mesh.rectangle(1, 1, 1 / 24)
    for cls in (dv.DV, dv.RV):
        assert _uniaxial_error(mesh, cls, nu) < 0.03


def test_table_agrees_with_a_fresh_sample():
    """The package's table against an independent sample (other seed) of one recipe."""
    s = dv.mesh.Sampling("jittered", 0.15)
    rev = dv.mesh.periodic_sample(s, 6000, seed=7)
    for kind in ("DV", "RV"):
        curve = table.curve(kind, s)
        assert curve is not None
        for nu_m in (-0.6, 0.0, 0.3):
            nu_t, E_t = curve(nu_m)
            r = calibration.relaxed_moduli(kind, rev, nu_m)
            assert abs(r["nu"] - nu_t) < 3e-3, (kind, nu_m, r["nu"], nu_t)
            assert abs(r["E"] / E_t - 1) < 5e-3, (kind, nu_m, r["E"], E_t)


def test_calibration_source_follows_the_mesh():
    mesh = dv.mesh.rectangle(1, 1, 0.1, kind="cvt", seed=2)
    assert dv.DV(mesh, E, 0.3).micro.details["source"] == "table"
    moved = mesh.perturbed(0.02, seed=1)
    assert moved.sampling.perturbations and moved.sampling.kind == "cvt"
    micro = dv.RV(moved, E, 0.3).micro
    assert micro.details["source"] == "recipe" and micro.details["evaluations"] >= 2
    bare = dv.Mesh(mesh.points, mesh.triangles)
    assert bare.sampling is None
    assert dv.RV(bare, E, 0.3).micro.details["source"] == "local spread"


def test_unreachable_nu_is_refused_with_the_range():
    mesh = dv.mesh.rectangle(1, 1, 0.1, kind="random", seed=0)
    with pytest.raises(dv.CalibrationError, match=r"cannot be reached.*lies in \["):
        dv.DV(mesh, E, 0.9)


def test_stabilised_lattice_is_stable_where_the_paper_model_is_not():
    mesh = dv.mesh.rectangle(1, 1, 0.1, kind="random", seed=1)
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
    assert not dv.stability(dv.DV(mesh, E, 0.2, **PAPER), sup).stable
    # the stabilised coupling on its own (the exact cells would cover this small mesh)
    model = dv.DV(mesh, E, 0.2, boundary_cells="lattice")
    rep = dv.stability(model, sup)
    assert rep.stable and rep.margin > 0
    # every triangle keeps at least MARGIN of its springs
    op = model.operator
    lam = triangle_modes(mesh, op.spring, True)
    worst = np.min(1 + op.coupling[:, None] * lam)
    assert worst >= MARGIN - 1e-9
    assert 0 < model.clipped_fraction < 1


def test_surface_bonds_are_half_springs():
    mesh = dv.mesh.rectangle(1, 1, 0.2)
    w = dv.DV(mesh, E, 0.2).bond_weight
    one = mesh.topology.n_tris_per_bond == 1
    assert np.all(w[one] == 0.5) and np.all(w[~one] == 1.0)


@pytest.mark.parametrize("size", [(1, 1, 0.1), (4, 1, 1 / 16), (48, 44, 2.0), (2, 0.3, 0.02)])
def test_rectangle_lattice_rows_are_nearly_equilateral(size):
    mesh = dv.mesh.rectangle(*size, kind="lattice")
    d = mesh.bond_vectors()
    length = np.hypot(*d.T)
    bnd = np.zeros(mesh.n_points, dtype=bool)
    bnd[mesh.boundary_nodes] = True
    inner = ~bnd[mesh.topology.bonds].any(axis=1)
    # equilateral: every bond away from the sides has the same length
    assert np.std(length[inner]) / np.mean(length[inner]) < 0.025


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_the_linear_lattice_is_p1_with_per_triangle_tensors(cls):
    """K equals the P1 stiffness assembled with the triangles' own tensors (to round-off),
    and on equilateral triangles those are isotropic."""
    import scipy.sparse as sp

    mesh = dv.mesh.rectangle(1, 1, 0.2, kind="random", seed=3)
    # the plain lattice: on so small a mesh the exact cells would be every triangle
    model = cls(mesh, 1e3, 0.25, boundary_cells="lattice")
    C = model.triangle_tensors()
    x = mesh.triangle_coordinates()
    area = np.asarray(mesh.triangle_areas)
    S = np.zeros((mesh.n_triangles, 3, 6))  # Mandel strain of the P1 field
    for v in range(3):
        o, a = (v + 1) % 3, (v + 2) % 3
        dy, dx = x[:, o, 1] - x[:, a, 1], x[:, a, 0] - x[:, o, 0]
        S[:, 0, 2 * v], S[:, 1, 2 * v + 1] = dy, dx
        S[:, 2, 2 * v], S[:, 2, 2 * v + 1] = dx / np.sqrt(2), dy / np.sqrt(2)
    S /= (2 * area)[:, None, None]
    Ke = area[:, None, None] * np.einsum("mji,mjk,mkl->mil", S, C, S)
    dofs = np.stack([2 * mesh.triangles, 2 * mesh.triangles + 1], -1).reshape(-1, 6)
    rows, cols = np.repeat(dofs, 6, 1).ravel(), np.tile(dofs, (1, 6)).ravel()
    K_p1 = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(model.n_dof,) * 2).tocsr()
    K = model.stiffness()
    assert abs(K - K_p1).max() < 1e-12 * abs(K).max()
    lattice = cls(dv.mesh.periodic_square(400, kind="lattice"), 1e3, 0.25, **PAPER)
    Ct = lattice.triangle_tensors()
    lam_mu = Ct[:, 0, 1], 0.5 * (Ct[:, 0, 0] - Ct[:, 0, 1])
    np.testing.assert_allclose(Ct[:, 2, 2], 2 * lam_mu[1], rtol=0.02)  # isotropic
    np.testing.assert_allclose(Ct[:, 0, 2], 0.0, atol=1e-9 * Ct[:, 0, 0].max())


@pytest.mark.parametrize("kind", ["lattice", "jittered", "cvt", "random"])
@pytest.mark.parametrize("barycentric", [True, False])
def test_coupling_matrices_in_closed_form_equal_the_fitted_half_side_gradients(kind, barycentric):
    # M = r r^T / A - diag(r / l) (DV) and its RV counterpart against the least-squares
    # fit dr B^T (B B^T)^-1 of the half sides' derivatives, and against finite
    # differences of the half sides under a random strain of each triangle
    from dvstatic.lattice import geometry
    from dvstatic.lattice.kinematics import edge_frames, half_sides
    from dvstatic.lattice.stabilise import _fitted_matrices, coupling_matrices

    mesh = dv.mesh.rectangle(1, 1, 0.08, kind=kind, seed=4)
    g = geometry.of(mesh)
    bary = g.bary if barycentric else None
    m = coupling_matrices(mesh, barycentric)
    fit = _fitted_matrices(g.x_tri, bary)
    assert np.abs(m - 0.5 * (fit + fit.transpose(0, 2, 1))).max() <= 1e-11 * np.abs(m).max()
    eps = 1e-7 * np.random.default_rng(0).normal(size=(mesh.n_triangles, 2, 2))
    eps = 0.5 * (eps + eps.transpose(0, 2, 1))
    y = g.x_tri + np.einsum("mij,mvj->mvi", eps, g.x_tri)
    dr = half_sides(y, bary)[0] - half_sides(g.x_tri, bary)[0]
    dl = edge_frames(y)[1] - edge_frames(g.x_tri)[1]
    pred = np.einsum("mkj,mj->mk", m, dl)
    assert np.abs(pred - dr).max() <= 1e-5 * np.abs(dr).max()


def test_closed_form_eigenvalues_of_symmetric_3x3_matrices():
    from dvstatic.lattice.stabilise import eigvalsh3

    rng = np.random.default_rng(1)
    a = rng.normal(size=(2000, 3, 3))
    a = a + a.transpose(0, 2, 1)
    a[:5] = np.eye(3) * 2.0  # a triple eigenvalue
    a[5:10] = np.diag([1.0, 1.0, -3.0])  # a double one
    scale = np.abs(a).max(axis=(1, 2))[:, None]
    assert np.abs(eigvalsh3(a) - np.linalg.eigvalsh(a)).max(axis=None) <= 1e-12 * scale.max()
    assert np.all(np.abs(eigvalsh3(a) - np.linalg.eigvalsh(a)) <= 1e-12 * scale)
