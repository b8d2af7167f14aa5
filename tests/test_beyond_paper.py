"""Beyond the paper: the defaults (relaxed calibration from the mesh's recipe, surface
springs, stabilised coupling) against the paper's model, CVT meshes, stability."""

import numpy as np
import pytest
import scipy.linalg

import dvstatic as dv
from conftest import E_BEAM, NU, rel_l2, uniaxial_exact, uniaxial_problem
from dvstatic.post import interpolate
from dvstatic.problem import constraints

#: the paper's model (calibrated under affine strain, uniform springs)
PAPER = {
    "calibration": "paper",
    "bonds": "uniform",
    "boundary_cells": "lattice",
    "anisotropy": "keep",
}


@pytest.fixture(scope="module")
def spread_meshes():
    """h = 0.01 meshes (about 1.2e4 nodes) made like the paper's exp. 3: random moves."""
    base = dv.mesh.rectangle(1.0, 1.0, 0.01, kind="lattice")
    return {s: dv.mesh.with_spread(base, s, seed=7) for s in (0.17, 0.3)}


def _uniaxial(model):
    sup, ld = uniaxial_problem()
    sol = dv.solve(model, sup, ld)
    m = model.mesh
    err = rel_l2(sol.u, uniaxial_exact(m.points))
    exx = sol.u[m.part_nodes("right"), 0].mean()  # unit square: strain = displacement
    eyy = sol.u[m.part_nodes("top"), 1].mean()
    return err, (-1.0 / exx) / E_BEAM, -eyy / exx


def test_with_spread_reaches_target(spread_meshes):
    for target, m in spread_meshes.items():
        assert m.edge_length_spread() == pytest.approx(target, rel=0.05)
        assert 9000 < m.n_points < 15000


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_relaxed_calibration_sigma_017(spread_meshes, cls):
    m = spread_meshes[0.17]
    try:
        err_paper = _uniaxial(cls(m, E_BEAM, NU, **PAPER))[0]
    except dv.UnstableError:  # the paper's DV is often unstable on such meshes
        err_paper = np.inf
    model = cls(m, E_BEAM, NU)  # the defaults
    err, e_app, nu_app = _uniaxial(model)
    assert err_paper > 0.07  # the paper's calibration: about 10 % here (or unstable)
    assert err <= 0.01
    assert e_app == pytest.approx(1.0, abs=0.01)
    assert nu_app == pytest.approx(NU, abs=0.01)
    d = model.micro.details
    # a perturbed lattice: measured on a periodic sample made by the same recipe
    assert d["source"] == "recipe" and d["evaluations"] >= 2
    # cached: a second model on a mesh of the same recipe is free
    again = cls(m, E_BEAM, NU)
    assert again.nu_m == model.nu_m and again.micro.details["seconds"] == 0.0


def test_relaxed_calibration_sigma_03(spread_meshes):
    m = spread_meshes[0.3]
    err_paper, _, _ = _uniaxial(dv.RV(m, E_BEAM, NU, **PAPER))
    assert err_paper > 0.15  # the paper's calibration: about 24 % here
    # the paper's DV is unstable on such a mesh: refused, not silently wrong
    with pytest.raises(dv.SolverError, match="positive definite"):
        _uniaxial(dv.DV(m, E_BEAM, NU, **PAPER))
    for cls in (dv.RV, dv.DV):  # the defaults: stable and within 2 %
        err, e_app, nu_app = _uniaxial(cls(m, E_BEAM, NU))
        assert err <= 0.02
        assert e_app == pytest.approx(1.0, abs=0.01)
        assert nu_app == pytest.approx(NU, abs=0.01)


def test_relaxed_beam_on_jittered_mesh():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation"))
    from _common import beam_problem, beam_reference

    w_ref = beam_reference(2).evaluate([[2.0, 0.5]])[0, 1]
    sup, ld = beam_problem()
    m = dv.mesh.rectangle(4.0, 1.0, 0.025, kind="jittered", jitter=0.3, seed=0)
    sol = dv.solve(dv.RV(m, E_BEAM, NU), sup, ld)
    w = interpolate(m, sol.u, [[2.0, 0.5]])[0, 1]
    assert abs(w / w_ref - 1) <= 0.015
    paper = dv.solve(dv.RV(m, E_BEAM, NU, **PAPER), sup, ld)
    assert abs(interpolate(m, paper.u, [[2.0, 0.5]])[0, 1] / w_ref - 1) > 0.05


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_surface_correction_slender_cantilever(cls):
    L, H = 10.0, 0.5
    m = dv.mesh.rectangle(L, H, H / (16 * np.sqrt(3) / 2), kind="lattice")  # 16 rows
    inertia = H**3 / 12
    P = 1e-3 * E_BEAM * inertia / L**2
    G = E_BEAM / (2 * (1 + NU))
    timoshenko = P * L**3 / (3 * E_BEAM * inertia) + P * L / (5 / 6 * G * H)
    tip = {}
    plain = {"boundary_cells": "lattice"}  # the springs themselves at the surface
    configs = {
        "paper": PAPER | plain,
        "voronoi": {"calibration": "paper", "bonds": "voronoi"} | plain,
        "surface": plain,
        "default": {},
    }
    for name, kw in configs.items():
        sol = dv.solve(
            cls(m, E_BEAM, NU, **kw), dv.Fix("left"), dv.Traction("right", (0.0, -P / H))
        )
        tip[name] = -sol.u[m.part_nodes("right"), 1].mean()
    assert abs(tip["voronoi"] / timoshenko - 1) <= 0.03
    assert abs(tip["surface"] / timoshenko - 1) <= 0.03  # half springs on the surface
    assert abs(tip["default"] / timoshenko - 1) <= 0.03  # exact boundary cells
    assert tip["paper"] / timoshenko - 1 < -0.10  # the paper's uniform k_n: too stiff


def test_voronoi_bonds_keep_stiffness_symmetric(jittered_small):
    for cls in (dv.DV, dv.RV):
        model = cls(jittered_small, E_BEAM, NU, bonds="voronoi", calibration="paper")
        K = model.stiffness()
        assert abs(K - K.T).max() <= 1e-13 * abs(K).max()
        w = model.bond_weight
        interior = jittered_small.topology.n_tris_per_bond == 2
        assert np.all(w > 0) and 0.5 < np.median(w[interior]) < 1.5


def test_cvt_meshes():
    sup, ld = uniaxial_problem()
    for seed in (0, 1):
        jit = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="jittered", jitter=0.3, seed=seed)
        cvt = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="cvt", seed=seed)
        assert cvt.edge_length_spread() < 0.8 * jit.edge_length_spread()
        for m in (jit, cvt):
            assert np.all(np.isin(m.part_nodes("left"), np.flatnonzero(m.points[:, 0] == 0)))
        errs = [
            rel_l2(dv.solve(dv.RV(m, E_BEAM, NU, **PAPER), sup, ld).u, uniaxial_exact(m.points))
            for m in (jit, cvt)
        ]
        assert errs[1] < 0.5 * errs[0]  # the paper's model is more accurate on CVT meshes


@pytest.mark.parametrize("cls,nu", [(dv.DV, 0.2), (dv.RV, 0.45), (dv.RV, 0.2)])
def test_stability_matches_dense_eigenvalues(cls, nu):
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="random", seed=0)
    sup, _ = uniaxial_problem()
    model = cls(m, E_BEAM, nu, **PAPER)
    rep = dv.stability(model, sup)
    # direct dense computation of the generalised problem K1 v = lambda K0 v
    from dvstatic.solvers.stability import stiffness_parts as _parts

    K0, K1 = _parts(model)
    dofs, _ = constraints(m, sup)
    keep = np.setdiff1d(np.arange(2 * m.n_points), dofs)
    lam = scipy.linalg.eigvalsh(K1[keep][:, keep].toarray(), K0[keep][:, keep].toarray())
    assert rep.lambda_min == pytest.approx(lam[0], rel=1e-8)
    assert rep.lambda_max == pytest.approx(lam[-1], rel=1e-8)
    K = model.stiffness()[keep][:, keep].toarray()
    n_neg = int(np.sum(np.linalg.eigvalsh(K) < 0))
    assert rep.stable == (n_neg == 0)
    assert rep.nu_m_range[0] < rep.nu_m_range[1]


def test_unstable_refused_with_range_and_edge_case_solves():
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="random", seed=0)
    sup, ld = uniaxial_problem()
    with pytest.raises(dv.SolverError, match=r"admissible .* nu in \("):
        dv.solve(dv.DV(m, E_BEAM, NU, **PAPER), sup, ld)
    rep = dv.stability(dv.DV(m, E_BEAM, NU, **PAPER), sup)
    lo, hi = rep.nu_range
    assert lo < hi
    # just inside the admissible range: stable and solved
    nu_edge = lo + 0.02 * (hi - lo)
    model = dv.DV(m, E_BEAM, nu_edge, **PAPER)
    assert dv.stability(model, sup).stable
    sol = dv.solve(model, sup, ld)
    assert sol.info.stability.negative_eigenvalues == 0
    assert sol.info.stability.method == "ldl-inertia"


def test_stability_check_cost_reported_for_amg():
    m = dv.mesh.rectangle(1.0, 1.0, 0.05, kind="lattice")
    sup, ld = uniaxial_problem()
    sol = dv.solve(dv.RV(m, E_BEAM, NU), sup, ld, solver="amg")
    st = sol.info.stability
    assert st.checked and st.negative_eigenvalues == 0 and st.seconds >= 0
