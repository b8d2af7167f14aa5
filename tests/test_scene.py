"""Scene files: bad input gives one clear message naming the file and key path."""

import textwrap

import numpy as np
import pytest

import dvstatic as dv
from dvstatic import cli, scene

GOOD = """
[mesh]
type = "rectangle"
width = 1.0
height = 1.0
h = 0.25
kind = "lattice"

[material]
E = 1e5
nu = 0.2

[[supports]]
where = "left"

[[loads]]
type = "traction"
where = "right"
value = [1.0, 0.0]
"""


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


BAD = [
    ("unknown key", GOOD.replace("kind = ", "knid = "), "mesh.knid", "unknown key"),
    ("wrong type", GOOD.replace("E = 1e5", 'E = "1e5"'), "material.E", "expected a finite"),
    ("missing E", GOOD.replace("E = 1e5\n", ""), "material.E", "required key is missing"),
    ("nu out of range", GOOD.replace("nu = 0.2", "nu = 1.5"), "material.nu", "plane-stress range"),
    (
        "unknown boundary name",
        GOOD.replace('where = "right"', 'where = "east"'),
        "loads[0].where",
        "unknown boundary part 'east'",
    ),
    (
        "empty domain",
        GOOD.replace(
            'type = "rectangle"\nwidth = 1.0\nheight = 1.0',
            'type = "polygon"\nvertices = [[0, 0], [1, 0], [2, 0]]',
        ),
        "mesh.vertices",
        "zero area",
    ),
    (
        "hole outside the polygon",
        GOOD.replace(
            "[material]",
            '[[mesh.holes]]\ntype = "circle"\ncenter = [3.0, 3.0]\nradius = 0.2\n\n[material]',
        ),
        "mesh.holes",
        "not strictly inside",
    ),
    (
        "self-intersecting polygon",
        GOOD.replace(
            'type = "rectangle"\nwidth = 1.0\nheight = 1.0',
            'type = "polygon"\nvertices = [[0, 0], [1, 1], [1, 0], [0, 1]]',
        ),
        "mesh.vertices",
        "intersect",
    ),
    (
        "missing mesh file",
        GOOD.replace(
            'type = "rectangle"\nwidth = 1.0\nheight = 1.0', 'type = "file"\npath = "nowhere.msh"'
        ),
        "mesh.path",
        "mesh file not found",
    ),
    (
        "h larger than the domain",
        GOOD.replace("h = 0.25", "h = 5.0"),
        "mesh.h",
        "larger than the domain",
    ),
    (
        "bad choice",
        GOOD.replace('kind = "lattice"', 'kind = "hexagonal"'),
        "mesh.kind",
        "is not one of",
    ),
    ("missing width", GOOD.replace("width = 1.0\n", ""), "mesh.width", "required for mesh type"),
    ("unknown table", GOOD + "\n[solvers]\ntype = 'amg'\n", "solvers", "unknown key"),
    ("no supports", GOOD.replace('[[supports]]\nwhere = "left"\n', ""), "supports", "no supports"),
    (
        "both where and at",
        GOOD.replace('where = "left"', 'where = "left"\nat = [0.0, 0.0]'),
        "supports[0]",
        "exactly one of",
    ),
    (
        "bad value vector",
        GOOD.replace("value = [1.0, 0.0]", "value = [1.0]"),
        "loads[0].value",
        "two finite numbers",
    ),
    (
        "free rigid motion",
        GOOD.replace('where = "left"', 'where = "left"\nx = 0.0'),
        "supports",
        "rigid-body motion",
    ),
    ("not toml", "this is = = not toml", "", "not valid TOML"),
    (
        "plane strain nu",
        GOOD.replace("nu = 0.2", 'nu = 0.6\nplane = "strain"'),
        "material.nu",
        "plane-strain range",
    ),
    (
        "unknown material region",
        GOOD + '\n[[materials]]\nregion = "core"\nE = 1e6\nnu = 0.3\n',
        "materials[0].region",
        "unknown region 'core'",
    ),
    (
        "pressure without p",
        GOOD.replace('type = "traction"', 'type = "pressure"').replace("value = [1.0, 0.0]", ""),
        "loads[0]",
        "exactly one of `p`",
    ),
    (
        "key of another load type",
        GOOD.replace("value = [1.0, 0.0]", "value = [1.0, 0.0]\np = 2.0"),
        "loads[0].p",
        "not a key of a traction load",
    ),
    (
        "bad profile",
        GOOD.replace("value = [1.0, 0.0]", "value_at = [[0.0, 0.0, 1.0]]"),
        "loads[0].value_at",
        "two rows",
    ),
    (
        "hydrostatic without level",
        GOOD.replace('type = "traction"', 'type = "pressure"').replace(
            "value = [1.0, 0.0]", "gamma = 10.0"
        ),
        "loads[0]",
        "both `gamma` and `level`",
    ),
    (
        "region missing radius",
        GOOD.replace(
            "[material]",
            '[[mesh.regions]]\ntype = "circle"\nname = "c"\ncenter = [0.5, 0.5]\n\n[material]',
        ),
        "mesh.regions[0].radius",
        "required for a circle region",
    ),
]


@pytest.mark.parametrize("case", BAD, ids=[c[0] for c in BAD])
def test_bad_scene_gives_one_clear_message(tmp_path, capsys, case):
    _, text, key, fragment = case
    path = write(tmp_path, text)
    code = cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert str(path) in err
    assert key in err
    assert fragment in err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_good_scene_and_overrides(tmp_path):
    path = write(tmp_path, GOOD)
    sc = scene.load(path, ["mesh.h=0.1", 'model.type="RV"', "solver.nonlinear=true"])
    assert sc.data["mesh"]["h"] == 0.1
    assert sc.data["model"]["type"] == "RV" and sc.data["solver"]["nonlinear"] is True
    assert sc.data["output"]["vtu"] is True  # defaults filled in
    mesh = sc.build_mesh()
    assert set(mesh.parts) == {"left", "right", "bottom", "top"}
    with pytest.raises(scene.SceneError, match="no such list element"):
        scene.load(path, ["supports.3.x=1.0"])
    sc = scene.load(path, ["supports.0.x=0.0"])
    assert sc.data["supports"][0]["x"] == 0.0
    assert scene.load(path, ["output.fe_order=4"]).data["output"]["fe_order"] == 4
    for bad in (0, 5):
        with pytest.raises(scene.SceneError, match="output.fe_order.*must be 1 to 4"):
            scene.load(path, [f"output.fe_order={bad}"])


def test_scene_reference_covers_every_key():
    ref = scene.reference_markdown()
    for key in (
        "mesh.type",
        "mesh.holes.radius",
        "material.E",
        "supports.at",
        "loads.value",
        "solver.nonlinear",
        "output.fe_compare",
        "output.part_stress",
    ):
        assert key in ref


LINED_BORE = """
title = "lined bore under internal pressure"

[mesh]
type = "disc"
radius = 2.0
h = 0.1
[[mesh.holes]]
type = "circle"
name = "bore"
center = [0.0, 0.0]
radius = 0.5
[[mesh.regions]]
type = "circle"
name = "lining"
center = [0.0, 0.0]
radius = 0.7

[material]
E = 1e4
nu = 0.3
plane = "strain"
thickness = 2.0

[[materials]]
region = "lining"
E = 3e4
nu = 0.2

[[supports]]
where = "boundary"

[[loads]]
type = "pressure"
where = "bore"
p = 10.0

[output]
field = "szz"
fe_compare = true
fe_order = 2
fe_refine = 0
"""


def test_real_problem_scene_runs_and_matches_fe(tmp_path, capsys):
    """Plane strain, a thickness, a second material on a region and a pressure, all
    from the scene file: the lattice agrees with FE on the same triangles."""
    path = write(tmp_path, LINED_BORE)
    code = cli.main(["run", str(path), "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "plane strain, thickness 2" in out and "lining: E = 30000" in out
    import json

    d = json.loads((tmp_path / "out" / "s.json").read_text())
    assert d["model"]["materials"]["lining"]["E"] == 3e4
    # about 1,400 nodes around a bore of 0.5 (a / h = 5): the lattice's O(h) surface
    # layer; a missing plane strain, thickness or material would give 40 %
    assert d["fe"]["rel_l2_difference"] < 0.1
    assert (tmp_path / "out" / "s.png").stat().st_size > 1000


def test_profiles_and_hydrostatic_pressure(tmp_path):
    text = GOOD.replace(
        'type = "traction"\nwhere = "right"\nvalue = [1.0, 0.0]',
        'type = "pressure"\nwhere = "right"\ngamma = 10.0\nlevel = 0.75\np = 1.0',
    ).replace(
        'where = "left"', 'where = "left"\nx_at = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.01]]\ny = 0.0'
    )
    sc = scene.load(write(tmp_path, text))
    mesh = sc.build_mesh()
    (load,) = sc.build_loads(mesh)
    y = np.array([[1.0, 0.0], [1.0, 0.5], [1.0, 0.75], [1.0, 1.0]])
    np.testing.assert_allclose(load.p(y), [8.5, 3.5, 1.0, 1.0])
    (fix,) = sc.build_supports(mesh)
    np.testing.assert_allclose(fix.x(np.array([[0.0, 0.25], [0.0, 2.0]])), [0.0025, 0.01])
    sol = dv.solve(sc.build_model(mesh), sc.build_supports(mesh), sc.build_loads(mesh))
    left = mesh.part_nodes("left")
    np.testing.assert_allclose(sol.u[left, 0], 0.01 * mesh.points[left, 1], atol=1e-15)


def test_output_probes_are_checked_before_the_solve(tmp_path, capsys, monkeypatch):
    """A probe outside the mesh used to be found after the whole solve (16 s), with no
    key; it is now refused before solving, naming output.probes[i]."""
    from dvstatic import cli, solvers

    def no_solve(*a, **k):
        raise AssertionError("solve() ran before the outputs were checked")

    monkeypatch.setattr(solvers, "solve", no_solve)
    path = write(tmp_path, GOOD)
    code = cli.main(
        ["run", str(path), "--set", "output.probes=[[0.5, 0.5], [5.0, 0.5]]", "--quiet"]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert "output.probes[1]" in err and "outside the mesh" in err
    code = cli.main(["run", str(path), "--set", 'output.part_stress=["rim"]', "--quiet"])
    assert code == 2 and "output.part_stress[0]" in capsys.readouterr().err
