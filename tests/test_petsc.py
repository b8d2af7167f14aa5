"""The distributed PETSc path (``solver="petsc"``) against the serial direct solve.

The partition and patch logic is tested without PETSc (every rank's rows of the patch
stiffness equal the global rows; calibration sums add up). The solves run on 1 rank in
this process and on 2 ranks under ``mpiexec``; they are skipped, with the reason, when
petsc4py is not installed (``scripts/install_petsc.sh``; CI installs it).
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dvstatic as dv
from dvstatic import parallel as distributed
from dvstatic.lattice import calibration

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import mpi_worker  # noqa: E402

needs_petsc = pytest.mark.skipif(
    not distributed.available(),
    reason="petsc4py is not installed: run scripts/install_petsc.sh (the dvstatic[petsc] extra)",
)


def _force_scale(model, loads, ref):
    """The larger of the reactions and the loads (a self-equilibrated load has
    reactions at round-off)."""
    f = dv.problem.load_vector(model.mesh, loads, thickness=model.t)
    return max(np.abs(ref.reactions).max(), np.abs(f).max())


def _mpiexec():
    exe = shutil.which("mpiexec") or str(Path(sys.executable).with_name("mpiexec"))
    return exe if Path(exe).exists() or shutil.which(exe) else None


def test_rcb_partition_is_balanced_and_compact():
    mesh = dv.mesh.rectangle(2.0, 1.0, 0.05, kind="jittered", seed=0)
    for p in (2, 3, 4, 7):
        part = distributed.rcb_partition(mesh.points, p)
        counts = np.bincount(part, minlength=p)
        assert counts.sum() == mesh.n_points
        assert counts.max() - counts.min() <= 3  # balanced to a point per level
    with pytest.raises(ValueError, match="nparts must be an integer >= 1"):
        distributed.rcb_partition(mesh.points, 0)


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
@pytest.mark.parametrize("bonds", ["uniform", "voronoi"])
def test_patch_rows_equal_global_rows(cls, bonds, monkeypatch):  # the paper's calibration
    """What makes the distributed assembly exact: on every rank's patch, the rows of
    the owned nodes (stiffness, tangent, internal force) equal the global ones, and the
    calibration sums over owned bonds and triangles add up to the global moments."""
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="jittered", seed=4)
    model = cls(mesh, 1e5, 0.35, bonds=bonds, calibration="paper")
    K = model.stiffness()
    rng = np.random.default_rng(0)
    u = 1e-2 * rng.normal(size=(mesh.n_points, 2))
    Kt = model.tangent(u)
    fi = model.internal_force(u)
    size = 3
    sums = np.zeros(4)
    covered = np.zeros(mesh.n_points, dtype=int)
    for rank in range(size):
        lay = distributed.layout(mesh, rank, size)
        pm = distributed.patch_model(model, lay)
        own = lay.local_nodes[: lay.n_owned]
        covered[own] += 1
        gd = np.stack([2 * lay.local_nodes, 2 * lay.local_nodes + 1], axis=1).reshape(-1)
        n2 = 2 * lay.n_owned
        rows = gd[:n2]
        assert abs(pm.stiffness()[:n2] - K[rows][:, gd]).max() < 1e-9 * abs(K).max()
        assert abs(K[rows]).sum() == pytest.approx(abs(K[rows][:, gd]).sum(), rel=1e-12)
        ul = u[lay.local_nodes]
        assert abs(pm.tangent(ul)[:n2] - Kt[rows][:, gd]).max() < 1e-9 * abs(Kt).max()
        assert np.allclose(pm.internal_force(ul)[:n2], fi[rows], rtol=0, atol=1e-9 * abs(fi).max())
        from dvstatic.lattice import geometry, voronoi_weights

        g = geometry.of(lay.patch)
        own_b, own_t = distributed.owned_bonds(lay), distributed.owned_triangles(lay)
        w = voronoi_weights(g) if bonds == "voronoi" else None
        sums += calibration.moment_sums(model.kind, g, w, own_b, own_t)

    assert np.all(covered == 1)
    # the helper the PETSc path uses, on one "rank" (no reduction needed)
    monkeypatch.setenv("PMI_SIZE", "1")  # as under mpiexec: not calibrated at construction
    fresh = cls(mesh, 1e5, 0.35, bonds=bonds, calibration="paper")
    assert not fresh.is_calibrated
    (one,) = distributed.micro_parameters(fresh, distributed.layout(mesh, 0, 1), lambda a: a)
    assert one.k_n == pytest.approx(model.k_n, rel=1e-12)
    assert one.nu_m == pytest.approx(model.nu_m, rel=1e-12)
    mom = calibration.moments_from_sums(sums, mesh.area)
    ref = model.micro.moments
    for name in ("alpha", "beta", "m1", "m2"):
        assert getattr(mom, name) == pytest.approx(getattr(ref, name), rel=1e-12)


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_patch_rows_equal_global_rows_with_the_defaults(cls):
    """The default model's springs (on random points: fabric-corrected, read from the
    whole mesh as the engine does) and its per-triangle clipping: the owned rows of every
    patch equal the global rows (random mesh: many clipped)."""
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.035, kind="random", seed=4)
    nu = 0.2 if cls is dv.DV else 0.45  # where each clips triangles on a random mesh
    model = cls(mesh, 1e5, nu)
    assert model.micro.stabilised and model.clipped_fraction > 0
    assert len(model.cell_triangles) < 0.7 * mesh.n_triangles  # a lattice inside
    assert_patch_rows_are_global(model)


def assert_patch_rows_are_global(model, ranks: int = 3) -> None:
    """The owned rows of every rank's patch model equal the whole model's rows."""
    K = model.stiffness()
    for rank in range(ranks):
        lay = distributed.layout(model.mesh, rank, ranks)
        pm = distributed.patch_model(model, lay)
        gd = np.stack([2 * lay.local_nodes, 2 * lay.local_nodes + 1], axis=1).reshape(-1)
        n2 = 2 * lay.n_owned
        assert abs(pm.stiffness()[:n2] - K[gd[:n2]][:, gd]).max() < 1e-9 * abs(K).max()


@needs_petsc
@pytest.mark.parametrize("case", range(len(mpi_worker.CASES)))
def test_petsc_one_rank_matches_direct(case):
    problem, model, nonlinear = mpi_worker.CASES[case]
    if (nonlinear and problem == "beam") or model.endswith("spread"):
        pytest.skip("covered on 2 ranks below (keeps the default suite short)")
    m, sup, ld = mpi_worker.setup(problem, model, nonlinear)
    sol = dv.solve(m, sup, ld, solver="petsc", nonlinear=nonlinear, **mpi_worker.OPTIONS)
    ref = dv.solve(m, sup, ld, solver="direct", nonlinear=nonlinear, **mpi_worker.OPTIONS)
    assert sol.info.solver == "petsc" and sol.info.converged
    # one Newton for every engine: the same load steps in the same iterations
    assert [st.iterations for st in sol.info.steps] == [st.iterations for st in ref.info.steps]
    assert np.max(np.abs(sol.u - ref.u)) <= 1e-8 * np.max(np.abs(ref.u))
    assert np.max(np.abs(sol.reactions - ref.reactions)) <= 1e-8 * _force_scale(m, ld, ref)


@needs_petsc
def test_petsc_two_ranks_match_direct(tmp_path):
    exe = _mpiexec()
    if exe is None:
        pytest.skip("mpiexec not found next to the interpreter or on PATH")
    out = tmp_path / "mpi.npz"
    run = subprocess.run(
        [exe, "-n", "2", sys.executable, str(HERE / "mpi_worker.py"), str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    data = np.load(out)
    infos = json.loads(str(data["info"]))
    for i, (problem, model, nonlinear) in enumerate(mpi_worker.CASES):
        m, sup, ld = mpi_worker.setup(problem, model, nonlinear)
        ref = dv.solve(m, sup, ld, solver="direct", nonlinear=nonlinear, **mpi_worker.OPTIONS)
        info = infos[str(i)]
        assert info["ranks"] == 2
        assert info["step_iterations"] == [st.iterations for st in ref.info.steps]
        # the calibration summed over two ranks is the serial one
        assert info["k_n"] == pytest.approx(m.k_n, rel=1e-12)
        assert info["nu_m"] == pytest.approx(m.nu_m, rel=1e-12)
        u, r = data[f"u{i}"], data[f"r{i}"]
        what = f"{problem} {model} {'nonlinear' if nonlinear else 'linear'}"
        assert np.max(np.abs(u - ref.u)) <= 1e-8 * np.max(np.abs(ref.u)), what
        assert np.max(np.abs(r - ref.reactions)) <= 1e-8 * _force_scale(m, ld, ref), what


@needs_petsc
def test_petsc_refuses_best_effort_and_reports_stages():
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
    ld = [dv.Traction("right", (-1.0, 0.0))]
    with pytest.raises(ValueError, match="best_effort is not available with solver='petsc'"):
        dv.solve(dv.DV(mesh, 1e5, 0.2), sup, ld, solver="petsc", best_effort=True)
    sol = dv.solve(dv.DV(mesh, 1e5, 0.2), sup, ld, solver="petsc")
    for stage in ("partition", "calibration", "assembly", "setup", "solve", "gather", "total"):
        assert getattr(sol.info.seconds, stage) > 0.0, stage
    assert sol.info.parallel.ranks == 1
    assert sol.info.iterations <= 30


@needs_petsc
def test_cli_run_on_two_ranks_writes_once(tmp_path):
    """``mpiexec -n 2 dvstatic run`` with solver.type = "petsc": rank 0 writes the
    outputs, and they agree with the serial direct run of the same scene."""
    exe = _mpiexec()
    if exe is None:
        pytest.skip("mpiexec not found next to the interpreter or on PATH")
    scene = HERE.parent / "examples" / "uniaxial.toml"
    common = ["run", str(scene), "--quiet", "--set", "output.png=false"]
    common += ["--set", "output.vtu=false"]
    par = subprocess.run(
        [exe, "-n", "2", sys.executable, "-m", "dvstatic", *common, "--out", str(tmp_path / "par")]
        + ["--set", 'solver.type="petsc"', "--set", "solver.rtol=1e-12"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert par.returncode == 0, par.stderr[-3000:]
    ser = subprocess.run(
        [sys.executable, "-m", "dvstatic", *common, "--out", str(tmp_path / "ser")]
        + ["--set", 'solver.type="direct"'],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert ser.returncode == 0, ser.stderr[-3000:]
    files = sorted(p.name for p in (tmp_path / "par").iterdir())
    assert files == [".dvstatic-manifest.json", "uniaxial.json"]
    a = json.loads((tmp_path / "par" / "uniaxial.json").read_text())
    b = json.loads((tmp_path / "ser" / "uniaxial.json").read_text())
    assert a["solver"]["solver"] == "petsc"
    assert a["max_displacement"] == pytest.approx(b["max_displacement"], rel=1e-8)


@needs_petsc
def test_petsc_options_are_pushed_under_a_prefix_and_removed():
    from petsc4py import PETSc

    from dvstatic.parallel.petsc import DEFAULT_OPTIONS, PREFIX

    opts = PETSc.Options()
    opts.setValue(PREFIX + "pc_gamg_threshold", "0.05")  # the user's own setting wins
    try:
        mesh = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="lattice")
        sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0)]
        sol = dv.solve(
            dv.DV(mesh, 1e5, 0.2), sup, dv.Traction("right", (-1.0, 0.0)), solver="petsc"
        )
        assert sol.info.converged
        for key in DEFAULT_OPTIONS:
            if key != "pc_gamg_threshold":
                assert not opts.hasName(PREFIX + key), key
        assert opts.getString(PREFIX + "pc_gamg_threshold") == "0.05"
    finally:
        opts.delValue(PREFIX + "pc_gamg_threshold")


@needs_petsc
def test_petsc_logs_the_calibration_warnings_once(caplog):
    import logging

    from test_calibration_quality import clustered_disc

    model = dv.DV(clustered_disc(), 1e4, 0.3)  # a clustered disc: one calibration flag
    sup = [dv.Fix("left", x=0.0), dv.Fix(at=(0, 0), y=0.0)]
    with caplog.at_level(logging.WARNING, logger="dvstatic"):
        dv.solve(model, sup, [dv.Traction("right", (1.0, 0.0))], solver="petsc")
    warned = [r for r in caplog.records if "calibration:" in r.getMessage()]
    assert len(warned) == len(model.calibration_flags) == 1
