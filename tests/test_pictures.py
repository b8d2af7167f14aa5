"""Pictures and files a run writes (issue 23's friction): the region a picture frames,
its colour range, material interfaces, fields that are refused, the FE reference in the
VTU, what Ctrl-C keeps, and how long validation takes."""

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

import dvstatic as dv
from dvstatic import cli, io, pictures, plot
from dvstatic.scene import SceneError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _hole_plate(radius: float):
    holes = [dv.domain.Circle((10.0, 10.0), radius, "hole")]
    mesh = dv.mesh.rectangle(20.0, 20.0, 0.5, holes=holes)
    sup = [dv.Fix(at=(0.0, 0.0)), dv.Fix(at=(0.0, 20.0), x=0.0)]
    loads = [dv.Traction("right", (1.0, 0.0)), dv.Traction("left", (-1.0, 0.0))]
    return dv.solve(dv.DV(mesh, 1e4, 0.3), sup, loads)


def test_a_small_hole_is_framed_and_a_large_one_is_not():
    small = io.picture_view(_hole_plate(1.0), field="sxx")  # the peak at the hole
    assert small == pytest.approx((5.0, 15.0, 5.0, 15.0), abs=0.3)  # 2.5 diameters around it
    assert io.picture_view(_hole_plate(4.0)) == pytest.approx((0, 20, 0, 20))
    assert io.picture_view(_hole_plate(1.0), "body") == pytest.approx((0, 20, 0, 20))
    with pytest.raises(dv.InputError, match="x0 < x1"):
        io.picture_view(_hole_plate(1.0), (1, 0, 0, 1))


def test_the_colour_range_is_that_of_the_nodes_in_view(tmp_path, monkeypatch):
    sol = _hole_plate(1.0)
    seen = {}
    real = plot.robust_range
    monkeypatch.setattr(plot, "robust_range", lambda f: seen.setdefault("n", len(f)) and real(f))
    io.write_png(tmp_path / "a.png", sol, field="sxx")
    inside = pictures._inside(sol.model.mesh.points, io.picture_view(sol, field="sxx"))
    assert seen["n"] == inside.sum() < sol.model.mesh.n_points


def test_point_load_neighbourhoods_do_not_take_the_colour_range():
    mesh = dv.mesh.disc(1.0, 0.05)
    sup = [dv.Fix(at=(0, 1), x=0), dv.Fix(at=(0, -1), x=0), dv.Fix(at=(1, 0), y=0)]
    loads = [dv.PointLoad(at=(0, 1), value=(0, -1.0)), dv.PointLoad(at=(0, -1), value=(0, 1.0))]
    sol = dv.solve(dv.DV(mesh, 1e5, 0.2), sup, loads)
    near = pictures.near_point_loads(sol)
    assert 0 < near.sum() < 0.1 * mesh.n_points
    sxx = sol.stress()[:, 0, 0]
    lo, hi, _ = plot.robust_range(sxx[~near])
    assert lo > -1.0 and hi == pytest.approx(2 / (np.pi * 2.0), rel=0.05)  # 2P / (pi D)
    assert sxx.min() < 3 * lo  # what the point loads would have taken


def test_material_interfaces_are_the_edges_between_materials():
    mesh = dv.mesh.rectangle(2.0, 2.0, 0.05, regions=[dv.domain.Circle((1, 1), 0.3, "inc")])
    model = dv.DV(mesh, 1e4, 0.3, materials={"inc": (1e5, 0.3)})
    edges = plot.interface_edges(mesh, model.material_of_triangle)
    r = np.hypot(*(mesh.points[edges] - 1.0).transpose(2, 0, 1))
    assert len(edges) > 20 and np.allclose(r, 0.3, atol=0.03)


def test_szz_in_plane_stress_is_refused(tmp_path):
    sol = _hole_plate(1.0)
    with pytest.raises(dv.InputError, match="szz is zero"):
        io.write_png(tmp_path / "a.png", sol, field="szz")
    with pytest.raises(SceneError, match="output.field"):
        dv.scene.load(EXAMPLES / "uniaxial.toml", ["output.field=szz"])
    with pytest.raises(SceneError, match="output.view"):
        dv.scene.load(EXAMPLES / "uniaxial.toml", ["output.view=[1, 0, 0, 1]"])


def test_the_vtu_carries_the_fe_reference_and_the_difference(tmp_path):
    mesh = dv.mesh.rectangle(2.0, 1.0, 0.1)
    sup, loads = [dv.Fix("left")], [dv.Traction("right", (0.0, -1.0))]
    sol = dv.solve(dv.DV(mesh, 1e4, 0.3), sup, loads)
    fe = dv.fem.solve(sol.model, sup, loads)
    data = meshio.read(io.write_vtu(tmp_path / "a.vtu", sol, fe=fe)).point_data
    np.testing.assert_allclose(data["fe_displacement"][:, :2], fe.u, rtol=1e-12)
    np.testing.assert_allclose(data["displacement_difference"][:, :2], sol.u - fe.u, atol=1e-15)
    assert data["fe_stress"].shape == data["stress_difference"].shape == (mesh.n_points, 9)
    assert "fe_stress" not in meshio.read(io.write_vtu(tmp_path / "b.vtu", sol)).point_data


def _scene(tmp_path) -> Path:
    text = (EXAMPLES / "uniaxial.toml").read_text()
    scene = tmp_path / "uniaxial.toml"
    scene.write_text(text)
    return scene


def test_ctrl_c_in_the_fe_reference_keeps_the_lattice_result(tmp_path, monkeypatch, capsys):
    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_fe_solve", interrupted)
    out = tmp_path / "out"
    args = ["run", str(_scene(tmp_path)), "--out", str(out), "-q", "--set", "mesh.h=0.1"]
    assert cli.main([*args, "--set", "output.fe_compare=true"]) == 0
    assert (out / "uniaxial.json").is_file() and (out / "uniaxial.vtu").is_file()
    assert "interrupted" in json.loads((out / "uniaxial.json").read_text())["fe_reference"]
    assert "FE reference was interrupted" in capsys.readouterr().err


def test_ctrl_c_in_the_solve_says_nothing_was_written(tmp_path, monkeypatch, capsys):
    from dvstatic import solvers

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(solvers, "solve", interrupted)
    out = tmp_path / "out"
    assert cli.main(["run", str(_scene(tmp_path)), "--out", str(out), "-q"]) == 130
    assert "before any output was written" in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_validate_says_how_long_each_script_took(tmp_path, capsys):
    (tmp_path / "_common.py").write_text("")
    (tmp_path / "fig01_x.py").write_text("print('table')\n")
    assert cli.main(["validate", "--dir", str(tmp_path), "--only", "fig01"]) == 0
    cap = capsys.readouterr()
    assert "-- fig01_x:" in cap.out + cap.err and "script(s) in" in cap.err


def test_the_documented_scene_api_solves_a_scene():
    sc = dv.scene.load(EXAMPLES / "uniaxial.toml", ["mesh.h=0.1"])
    m = sc.build_mesh()
    sol = dv.solve(sc.build_model(m), sc.build_supports(m), sc.build_loads(m), **sc.solve_options())
    assert sc.name == "uniaxial" and sc.fracture_options() is None
    assert np.all(np.isfinite(sol.u)) and np.abs(sol.u).max() > 0


def test_crack_faces_are_the_voronoi_sides_of_the_broken_bonds(tmp_path):
    mesh = dv.mesh.rectangle(2.0, 1.0, 0.1, kind="cvt", seed=3)
    sup = [dv.Fix(at=(0, 0), x=0, y=0), dv.Fix(at=(2, 0), y=0)]
    loads = [dv.Traction("right", (1.0, 0.0)), dv.Traction("left", (-1.0, 0.0))]
    res = dv.fracture(dv.DV(mesh, 3e4, 0.2), sup, loads, ft=3.0, max_events=30)
    faces, bonds = io.crack_faces(res)
    assert len(faces) == len(res.broken) > 0 and np.array_equal(bonds, res.broken)
    ends = mesh.points[mesh.topology.bonds[bonds]]
    along = ends[:, 1] - ends[:, 0]
    face = faces[:, 1] - faces[:, 0]
    cos = np.abs(np.einsum("ij,ij->i", along, face)) / (
        np.hypot(*along.T) * np.maximum(np.hypot(*face.T), 1e-300)
    )
    assert cos.max() < 1e-9  # a Voronoi side is perpendicular to its bond
    mid = ends.mean(axis=1)
    # ... and on the bond's perpendicular bisector: its midpoint is equidistant
    d0 = np.hypot(*(faces[:, 0] - ends[:, 0]).T) - np.hypot(*(faces[:, 0] - ends[:, 1]).T)
    assert np.abs(d0).max() < 1e-9 and np.all(np.isfinite(mid))
    png = io.write_crack_png(tmp_path / "c.png", res)
    curve = io.write_fracture_curve(
        tmp_path / "k.png",
        res,
        references=[{"quantity": "peak_load", "reference": 1.0, "name": "x"}],
    )
    assert png.stat().st_size > 1000 and curve.stat().st_size > 1000


@pytest.mark.parametrize(
    ("within", "match"),
    [("[0.1, -0.1, 0.5, 1.1]", "x0 < x1"), ("[5.0, 6.0, 5.0, 6.0]", "no edge of part")],
)
def test_a_load_within_a_bad_box_names_the_key(within, match, tmp_path):
    text = (EXAMPLES / "brazilian_fracture.toml").read_text()
    scene = tmp_path / "b.toml"
    scene.write_text(text.replace("within = [-0.1, 0.1, 0.5, 1.1]", f"within = {within}", 1))
    with pytest.raises(SceneError, match=match) as err:
        sc = dv.scene.load(scene)
        sc.build_loads(sc.build_mesh())
    assert err.value.key == "loads[0].within"


def test_a_loaded_end_is_not_framed_when_the_stress_peaks_elsewhere():
    """A cantilever's loaded tip is small, but its stresses peak at the clamp: the whole
    beam is shown. A small hole whose frame misses the largest displacement is not
    framed either."""
    mesh = dv.mesh.rectangle(10.0, 0.5, 0.05)
    sol = dv.solve(dv.DV(mesh, 1e4, 0.3), dv.Fix("left"), dv.Traction("right", (0.0, -1.0)))
    assert io.picture_view(sol) == pytest.approx((0, 10, 0, 0.5))
    holes = [dv.domain.Circle((1.0, 1.0), 0.15, "bolt")]
    mesh = dv.mesh.rectangle(10.0, 2.0, 0.1, holes=holes)
    sol = dv.solve(dv.DV(mesh, 1e4, 0.3), dv.Fix("left"), dv.Traction("top", (0.0, -1.0)))
    assert io.picture_view(sol) == pytest.approx((0, 10, 0, 2))


def test_a_view_without_nodes_is_refused_before_the_solve(tmp_path, capsys):
    args = ["run", str(EXAMPLES / "uniaxial.toml"), "--out", str(tmp_path / "o"), "-q"]
    assert cli.main([*args, "--set", "output.view=[5, 6, 5, 6]"]) == 2
    assert "output.view" in capsys.readouterr().err and not (tmp_path / "o").exists()
    with pytest.raises(dv.InputError, match="holds no node"):
        io.write_png(tmp_path / "a.png", _hole_plate(1.0), view=(30, 31, 30, 31))
