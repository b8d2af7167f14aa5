"""What a new user meets first: the command line's help and messages, supports and
loads at a point, stresses at points and over regions (issue 16)."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dvstatic as dv
from dvstatic import cli

E, NU = 1e5, 0.3
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def plate():
    """A 2 x 1 plate under uniaxial tension 1, held at two points (exact: sxx = 1)."""
    m = dv.mesh.rectangle(2.0, 1.0, 0.05, kind="lattice")
    sup = [dv.Fix(at=(0.0, 0.0)), dv.Fix(at=(0.0, 1.0), x=0.0)]
    loads = [dv.Traction("right", (1.0, 0.0)), dv.Traction("left", (-1.0, 0.0))]
    return dv.solve(dv.DV(m, E, NU), sup, loads)


def test_supports_and_point_loads_at_a_coordinate(plate):
    m = plate.model.mesh
    assert np.abs(plate.reactions).max() < 1e-8  # self-equilibrated load, point supports
    corner = dv.problem.nearest_node(m, (0.0, 0.0))
    np.testing.assert_allclose(plate.u[corner], 0.0, atol=1e-15)
    sol = dv.solve(plate.model, [dv.Fix("left")], [dv.PointLoad(at=(2.0, 0.5), value=(0.0, -1.0))])
    assert sol.reactions[:, 1].sum() == pytest.approx(1.0, rel=1e-9)
    with pytest.raises(dv.InputError, match="no node at"):
        dv.solve(plate.model, [dv.Fix(at=(5.0, 5.0))], [])
    with pytest.raises(TypeError, match="not both"):
        dv.Fix("left", at=(0.0, 0.0))
    with pytest.raises(TypeError, match="value"):
        dv.PointLoad(at=(0.0, 0.0))


def test_stress_at_points_and_mean_over_a_region(plate):
    s = plate.stress_at([[1.0, 0.5], [0.3, 0.7]])
    assert s.shape == (2, 2, 2)
    np.testing.assert_allclose(s[:, 0, 0], 1.0, atol=0.03)
    np.testing.assert_allclose(plate.stress_at([1.0, 0.5]), s[:1])
    mean = plate.mean_stress()
    assert mean[0, 0] == pytest.approx(1.0, abs=0.02)  # the lattice's first-order error
    assert abs(mean[1, 1]) < 0.02 and abs(mean[0, 1]) < 0.02
    with pytest.raises(dv.InputError, match="outside the mesh"):
        plate.stress_at([[3.0, 0.5]])
    with pytest.raises(dv.InputError, match="unknown region 'core'"):
        plate.mean_stress("core")


def test_mean_stress_of_a_region_in_a_bimaterial_strip():
    """Layers in parallel under a prescribed stretch: each layer carries its own E."""
    regions = (dv.domain.Polygon(((0, 0), (2, 0), (2, 0.5), (0, 0.5)), name="soft"),)
    m = dv.mesh.rectangle(2.0, 1.0, 0.05, kind="lattice", regions=regions)
    model = dv.DV(m, E, 0.0, materials={"soft": (E / 2, 0.0)})
    sup = [dv.Fix("left", x=0.0), dv.Fix("right", x=0.01), dv.Fix(at=(0.0, 0.0), y=0.0)]
    sol = dv.solve(model, sup, [])
    soft, whole = sol.mean_stress("soft"), sol.mean_stress()
    assert soft[0, 0] == pytest.approx(E / 2 * 0.005, rel=0.03)
    assert whole[0, 0] == pytest.approx(0.75 * E * 0.005, rel=0.03)


def test_help_has_no_markup_and_verbose_works_after_the_command(capsys, tmp_path):
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    out = capsys.readouterr().out
    assert "::" not in out and "Command line" in out and "4 best" in out
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[mesh]\ntype = "rectangle"\nwidth = 1.0\nheight = 1.0\nh = 0.2\n'
        "[material]\nE = 1e5\nnu = 0.2\n"
        '[[supports]]\nwhere = "left"\n[[loads]]\ntype = "traction"\nwhere = "right"\n'
        "value = [1.0, 0.0]\n[output]\npng = false\nvtu = false\n"
    )
    assert cli.main(["run", str(scene), "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "building the mesh" in err and "solving" in err  # stage lines
    code = cli.main(["run", str(scene), "--quiet", "--out", str(tmp_path / "o"), "--overwrite"])
    assert code == 0 and capsys.readouterr().err == ""
    # -v after the command (it was refused there): a real process, for the log set-up
    for args, logged in ((["run", "-v"], True), (["-v", "run"], True), (["run"], False)):
        proc = subprocess.run(
            [sys.executable, "-m", "dvstatic", *args, str(scene), "--overwrite", "-q"]
            + ["--out", str(tmp_path / "v")],
            capture_output=True,
            text=True,
            check=False,
        )
        assert proc.returncode == 0, proc.stderr
        assert ("INFO dvstatic" in proc.stderr) is logged, (args, proc.stderr)


def test_solver_refusals_name_the_scene_file(capsys, tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[mesh]\ntype = "rectangle"\nwidth = 4.0\nheight = 0.5\nh = 0.125\nkind = "lattice"\n'
        "[material]\nE = 1e3\nnu = 0.2\n"
        '[[supports]]\nwhere = "left"\n[[loads]]\ntype = "traction"\nwhere = "right"\n'
        "value = [0.0, -50.0]\n[solver]\nnonlinear = true\nsteps = 1\nnewton_maxiter = 1\n"
        "max_cutbacks = 0\n[output]\npng = false\nvtu = false\n"
    )
    code = cli.main(["run", str(scene), "--quiet", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 3
    assert err.startswith(f"error: the solver refused or failed: {scene}: ")
    assert len(err.strip().splitlines()) == 1


def test_points_on_a_curved_boundary_snap_and_bad_points_are_refused():
    from dvstatic.mesh.locate import snap_point

    m = dv.mesh.disc(1.0, 0.04)
    theta = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    for t in theta:  # every point of the true circle (45 of 720 were refused before)
        snap_point(m, [np.cos(t), np.sin(t)])
    with pytest.raises(dv.InputError, match="outside the mesh"):
        snap_point(m, [1.2, 0.0])
    with pytest.raises(dv.InputError, match="not finite"):
        snap_point(m, [np.nan, 0.0])
    with pytest.raises(dv.InputError, match="finite"):
        dv.Fix(at=(np.nan, 0.0))
    with pytest.raises(TypeError, match="at must be a point"):
        dv.Fix(at=("a", "b"))
    with pytest.raises(TypeError, match="At selects a node"):
        dv.Traction(dv.At(1.0, 0.0), (1.0, 0.0))
    with pytest.raises(TypeError, match="give `nodes`"):
        dv.PointLoad(value=(0.0, 1.0))


def test_check_values_report_value_difference_and_fe(plate):
    from dvstatic import io

    fe = dv.fem.solve(plate.model.mesh, E, NU, plate.supports, plate.loads, order=1)
    checks = [
        {"name": "sxx", "at": [1.0, 0.5], "quantity": "sxx", "reference": 1.0},
        {"name": "syy", "at": [1.0, 0.5], "quantity": "syy", "reference": 0.0},
        {"name": "ux", "at": [2.0, 0.5], "quantity": "ux", "reference": 2.0 / E},
    ]
    out = io.check_values(plate, checks, fe=fe)
    assert [c["name"] for c in out] == ["sxx", "syy", "ux"]
    assert out[0]["value"] == pytest.approx(plate.stress_at([1.0, 0.5])[0, 0, 0])
    assert out[0]["difference"] == pytest.approx(out[0]["value"] - 1.0)  # relative to |1|
    assert out[1]["difference"] == pytest.approx(out[1]["value"])  # absolute, reference 0
    assert abs(out[0]["difference"]) < 0.03 and abs(out[2]["difference"]) < 0.03
    assert out[2]["fe_value"] == pytest.approx(2.0 / E, rel=1e-9)  # P1 is exact here
    with pytest.raises(dv.InputError, match="unknown quantity 'szz'"):
        io.check_values(plate, [dict(checks[0], quantity="szz")])
    with pytest.raises(dv.InputError, match="missing reference"):
        io.check_values(plate, [{"name": "a", "at": [1, 0.5], "quantity": "ux"}])
    with pytest.raises(TypeError, match="reference must be a number"):
        io.check_values(plate, [dict(checks[0], reference="1")])
    assert plate.stress_at(np.zeros((0, 2))).shape == (0, 2, 2)


def test_missing_petsc_is_one_error_line_with_the_fix(tmp_path):
    """`--set solver.type='"petsc"'` without petsc4py printed a traceback and exit 1."""
    code = (
        "import sys; sys.modules['petsc4py'] = None; sys.modules['mpi4py'] = None\n"
        "from dvstatic.cli import main\n"
        f"sys.exit(main(['run', {str(EXAMPLES / 'uniaxial.toml')!r}, '--set',"
        f" 'solver.type=\"petsc\"', '--out', {str(tmp_path / 'o')!r}, '-q']))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in proc.stderr
    assert "install_petsc.sh" in lines[0] and "dvstatic[petsc]" in lines[0]


@pytest.mark.parametrize("value", ["0", "-1", "2"])
def test_mesh_h_errors_name_the_key(value, capsys):
    code = cli.main(["run", str(EXAMPLES / "uniaxial.toml"), "--set", f"mesh.h={value}", "-q"])
    err = capsys.readouterr().err
    assert code == 2 and ": mesh.h: " in err and len(err.strip().splitlines()) == 1


def test_stress_is_recovered_once_per_solution(monkeypatch):
    """Every check, probe and picture asked for the recovery again (about a solve's
    time each at 1e5 nodes); it is computed once per method and copies are returned."""
    from dvstatic import io
    from dvstatic.solvers import result

    calls = []
    real = result.recovered_stress
    monkeypatch.setattr(result, "recovered_stress", lambda *a: calls.append(1) or real(*a))
    m = dv.mesh.rectangle(2.0, 1.0, 0.1, kind="lattice")
    sol = dv.solve(dv.DV(m, E, NU), [dv.Fix("left")], [dv.Traction("right", (0.0, -1.0))])
    s = sol.stress()
    s[:] = 0.0  # the caller's copy
    assert np.abs(sol.stress()).max() > 0
    sol.stress_at([[1.0, 0.5]])
    sol.mean_stress()
    checks = [{"name": "a", "at": [1.0, 0.5], "quantity": "sxx", "reference": 1.0}]
    io.summary(sol, probes=[[1.0, 0.5]], part_stress=["top"], checks=checks)
    assert len(calls) == 1
