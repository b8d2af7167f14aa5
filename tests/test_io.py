"""Files: VTU round trip, gmsh import, JSON summary, PNG."""

import json

import meshio
import numpy as np
import pytest

import dvstatic as dv
from conftest import E_BEAM, NU, uniaxial_problem
from dvstatic import io


@pytest.fixture(scope="module")
def solution():
    m = dv.mesh.rectangle(1.0, 1.0, 0.1, kind="jittered", seed=2)
    sup, ld = uniaxial_problem()
    return dv.solve(dv.RV(m, E_BEAM, NU), sup, ld)


def test_vtu_round_trip(solution, tmp_path):
    """Continuum fields on the triangles, bonds in their own file: no padded zeros (a
    new user found ``tension`` 0 on every triangle and ``area`` 0 on every line)."""
    path = io.write_vtu(tmp_path / "s.vtu", solution)
    back = meshio.read(path)
    mesh = solution.model.mesh
    np.testing.assert_allclose(back.points[:, :2], mesh.points)
    assert np.all(back.points[:, 2] == 0)
    assert [c.type for c in back.cells] == ["triangle"]
    np.testing.assert_array_equal(back.cells[0].data, mesh.triangles)
    np.testing.assert_allclose(back.point_data["displacement"][:, :2], solution.u)
    np.testing.assert_allclose(back.cell_data["area"][0], mesh.triangle_areas)
    assert set(back.cell_data) == {"area", "material"}
    s9 = back.point_data["stress"].reshape(-1, 3, 3)
    np.testing.assert_allclose(s9[:, :2, :2], solution.stress())
    assert back.point_data["von_mises"].shape == (mesh.n_points,)

    bonds = meshio.read(io.write_bonds_vtu(tmp_path / "s_bonds.vtu", solution))
    assert [c.type for c in bonds.cells] == ["line"]
    np.testing.assert_array_equal(bonds.cells[0].data, mesh.topology.bonds)
    np.testing.assert_allclose(bonds.cell_data["tension"][0], solution.tension())
    assert np.all(bonds.cell_data["length"][0] > 0)
    assert not list(tmp_path.glob(".*tmp"))  # no temporary file left behind


def test_gmsh_mesh_loads_and_solves(tmp_path):
    base = dv.mesh.rectangle(2.0, 1.0, 0.2, kind="jittered", seed=1)
    left, right = base.part_edges("left"), base.part_edges("right")
    # an unused point too (gmsh files often carry geometry points)
    pts = np.vstack([np.c_[base.points, np.zeros(base.n_points)], [[9.0, 9.0, 0.0]]])
    m = meshio.Mesh(
        pts,
        [("triangle", base.triangles), ("line", np.vstack([left, right]))],
        cell_data={
            "gmsh:physical": [
                np.full(base.n_triangles, 3),
                np.r_[np.full(len(left), 1), np.full(len(right), 2)],
            ],
            "gmsh:geometrical": [
                np.full(base.n_triangles, 1),
                np.r_[np.full(len(left), 1), np.full(len(right), 2)],
            ],
        },
        field_data={"clamp": np.array([1, 1]), "pull": np.array([2, 1]), "body": np.array([3, 2])},
    )
    path = tmp_path / "plate.msh"
    meshio.write(path, m, file_format="gmsh22", binary=False)
    mesh = io.read_mesh(path)
    assert mesh.n_points == base.n_points
    assert {"clamp", "pull"} <= set(mesh.parts)
    np.testing.assert_allclose(np.sort(mesh.part_nodes("pull")), np.sort(mesh.part_nodes("pull")))
    sol = dv.solve(dv.DV(mesh, E_BEAM, NU), dv.Fix("clamp"), dv.Traction("pull", (1.0, 0.0)))
    assert sol.u[mesh.part_nodes("pull"), 0].mean() > 0
    assert sol.reactions.sum(axis=0)[0] == pytest.approx(-1.0, rel=1e-9)


def test_gmsh_physical_surfaces_become_regions_with_their_materials(tmp_path):
    """A bar of two layers (lower soft, upper stiff) pulled along its length: the gmsh
    surfaces are regions, each with its material; the stretch is that of the layers in
    parallel."""
    base = dv.mesh.rectangle(2.0, 0.5, 0.1, kind="lattice")
    left, right = base.part_edges("left"), base.part_edges("right")
    rows = np.unique(base.points[:, 1])
    split = rows[len(rows) // 2]  # a row of the lattice: the layers' interface
    stiff = base.triangle_coordinates()[:, :, 1].mean(axis=1) > split
    order = np.r_[np.flatnonzero(~stiff), np.flatnonzero(stiff)]
    m = meshio.Mesh(
        np.c_[base.points, np.zeros(base.n_points)],
        [
            ("triangle", base.triangles[order[: (~stiff).sum()]]),
            ("triangle", base.triangles[order[(~stiff).sum() :]]),
            ("line", np.vstack([left, right])),
        ],
        cell_data={
            "gmsh:physical": [
                np.full((~stiff).sum(), 3),
                np.full(stiff.sum(), 4),
                np.r_[np.full(len(left), 1), np.full(len(right), 2)],
            ],
            "gmsh:geometrical": [
                np.full((~stiff).sum(), 1),
                np.full(stiff.sum(), 2),
                np.r_[np.full(len(left), 1), np.full(len(right), 2)],
            ],
        },
        field_data={
            "clamp": np.array([1, 1]),
            "pull": np.array([2, 1]),
            "soft": np.array([3, 2]),
            "stiff": np.array([4, 2]),
        },
    )
    path = tmp_path / "bar.msh"
    meshio.write(path, m, file_format="gmsh22", binary=False)
    mesh = io.read_mesh(path)
    assert set(mesh.regions) == {"soft", "stiff"}
    cy = mesh.triangle_coordinates()[:, :, 1].mean(axis=1)
    assert np.all(cy[mesh.regions["stiff"]] > split) and np.all(cy[mesh.regions["soft"]] < split)
    # both ends moved apart by 2 eps (nu = 0): equal strain in both layers, so each
    # layer carries its own E eps and the lattice's reaction is their sum
    eps = 1e-3
    pin = [int(np.argmin(np.hypot(*mesh.points.T)))]
    sup = [dv.Fix("clamp", x=0.0), dv.Fix(pin, y=0.0), dv.Fix("pull", x=2 * eps)]
    force = eps * (1e3 * split + 4e3 * (0.5 - split))
    fe = dv.fem.solve(mesh, 1e3, 0.0, sup, [], materials={"stiff": (4e3, 0.0)})
    np.testing.assert_allclose(fe.u[:, 0], eps * mesh.points[:, 0], atol=1e-12)
    sol = dv.solve(dv.RV(mesh, 1e3, 0.0, materials={"stiff": (4e3, 0.0)}), sup)
    assert sol.reactions[mesh.part_nodes("pull"), 0].sum() == pytest.approx(force, rel=0.03)


def test_write_mesh_round_trip_keeps_parts_and_regions(tmp_path):
    """A .vtu round trip loses the boundary names (a new user's finding); write_mesh's
    gmsh file keeps points, triangles (in order), parts and regions."""
    base = dv.mesh.rectangle(2.0, 1.0, 0.1, kind="cvt", seed=1)
    half = np.flatnonzero(base.points[base.triangles].mean(axis=1)[:, 0] > 1.0)
    mesh = dv.Mesh(base.points, base.triangles, parts=base.parts, regions={"half": half})
    back = io.read_mesh(io.write_mesh(tmp_path / "m.msh", mesh))
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.triangles, mesh.triangles)
    assert set(back.parts) == set(mesh.parts)
    for name, edges in mesh.parts.items():
        assert {tuple(e) for e in np.sort(edges, axis=1)} == {
            tuple(e) for e in np.sort(back.parts[name], axis=1)
        }
    assert np.array_equal(np.sort(back.regions["half"]), half)
    assert len(back.regions["body"]) == mesh.n_triangles - len(half)
    assert [p.name for p in tmp_path.iterdir()] == ["m.msh"]  # no temporary left
    with pytest.raises(dv.InputError, match=".msh"):
        io.write_mesh(tmp_path / "m.vtu", mesh)
    same = dv.Mesh(mesh.points, mesh.triangles, parts=mesh.parts, regions={"left": half})
    with pytest.raises(dv.InputError, match="same name 'left'"):
        io.write_mesh(tmp_path / "s.msh", same)
    with pytest.raises(dv.InputError, match="periodic"):
        io.write_mesh(tmp_path / "p.msh", dv.mesh.periodic_square(100, seed=1))


def test_read_mesh_errors(tmp_path):
    with pytest.raises(ValueError, match="mesh file not found"):
        io.read_mesh(tmp_path / "none.msh")
    bad = tmp_path / "lines.vtu"
    meshio.write(bad, meshio.Mesh(np.zeros((2, 3)), [("line", np.array([[0, 1]]))]))
    with pytest.raises(ValueError, match="no triangle cells"):
        io.read_mesh(bad)


def test_summary_json_and_png(solution, tmp_path):
    fe = dv.fem.solve(solution.model.mesh, E_BEAM, NU, solution.supports, solution.loads)
    d = io.summary(solution, fe=fe, probes=[[0.5, 0.5]], part_stress=["right"])
    for key in (
        "mesh",
        "model",
        "max_displacement",
        "reactions",
        "strain_energy",
        "solver",
        "fe",
        "probes",
        "part_stress",
    ):
        assert key in d
    assert d["mesh"]["sigma_L"] == pytest.approx(solution.model.mesh.edge_length_spread())
    assert d["model"]["cell_rings"] == 3  # the exact cells' depth, with their count
    assert d["model"]["exact_cells"] == len(solution.model.cell_triangles) > 0
    assert d["reactions"]["left"]["x"] == pytest.approx(1.0, rel=1e-9)

    path = io.write_json(tmp_path / "s.json", d)
    assert json.loads(path.read_text())["model"]["type"] == "RV"
    png = io.write_png(tmp_path / "s.png", solution, field="von_mises")
    assert png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="unknown field"):
        io.write_png(tmp_path / "t.png", solution, field="temperature")


def test_reactions_per_prescribed_component_without_double_counting(tmp_path):
    """Rollers left (x) and bottom (y) share the corner node: each support reports only
    the component it prescribes, and the components add up to the total (a defect of
    0.1: bottom showed an x reaction and left + bottom x was 1.0192 for a total of 1)."""
    mesh = dv.mesh.rectangle(1.0, 1.0, 0.1)
    sup = [dv.Fix("left", x=0.0), dv.Fix("bottom", y=0.0), dv.Fix("left", x=0.0)]
    sol = dv.solve(dv.RV(mesh, E_BEAM, NU), sup, [dv.Traction("right", (1.0, 0.2))])
    r = io.summary(sol)["reactions"]
    assert set(r["left"]) == {"x"} and set(r["bottom"]) == {"y"}
    assert r["left"]["x"] == pytest.approx(r["total"][0], rel=1e-12)
    assert r["bottom"]["y"] == pytest.approx(r["total"][1], rel=1e-12)
    assert r["left"]["x"] == pytest.approx(-1.0, rel=1e-9)


def test_unreadable_mesh_file_is_one_clear_line(tmp_path, capsys):
    """meshio printed its own "Error: ..." lines and the message ended in ": 1" (an exit
    status): now one line, nothing from meshio on the terminal."""
    from dvstatic import cli

    (tmp_path / "bad.msh").write_text("garbage\n")
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[mesh]\ntype = "file"\npath = "bad.msh"\n[material]\nE = 1e5\nnu = 0.2\n'
        '[[supports]]\nwhere = "left"\n'
    )
    code = cli.main(["run", str(scene), "--quiet"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("error: ") and "mesh.path" in err and "bad.msh" in err
    assert not err.rstrip().endswith(": 1") and "Error:" not in err


def test_pictures_frame_the_deformed_body_and_clip_colour_peaks():
    """The large-deflection cantilever was drawn in a frame of its undeformed box (left
    half empty, the beam squeezed); the Brazilian disc's colour range went to the load
    points. Frames follow the deformed body; colours clip to robust percentiles."""
    from dvstatic import plot

    straight = np.c_[np.linspace(0, 10, 50), np.linspace(0, 0.5, 50)]
    curled = np.c_[6 * np.sin(np.linspace(0, 1.2, 50)), -7 * np.linspace(0, 1, 50) ** 2]
    w, h = io.figure_size(straight)
    assert w == 9.0 and h == 3.0
    w, h = io.figure_size(curled)
    assert h > w  # taller than wide, as the deformed beam is
    rng = np.random.default_rng(0)
    f = rng.normal(0.0, 1.0, 2000)
    assert plot.robust_range(f)[2] == "neither"  # no peaks: the full range
    f[:5] = -400.0  # five nodes under a point load
    vmin, vmax, extend = plot.robust_range(f)
    assert extend == "min" and vmin > -4.0 and vmax == f.max()
    f[:5] = 9.0  # a stress concentration of about twice the range: shown, not clipped
    assert plot.robust_range(f)[2] == "neither"
