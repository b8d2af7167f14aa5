"""Scene files: bad input gives one clear message naming the file and key path."""

import textwrap

import pytest

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
        "two numbers",
    ),
    (
        "free rigid motion",
        GOOD.replace('where = "left"', 'where = "left"\nx = 0.0'),
        "supports",
        "rigid-body motion",
    ),
    ("not toml", "this is = = not toml", "", "not valid TOML"),
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
