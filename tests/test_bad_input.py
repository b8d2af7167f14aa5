"""Catalogue of bad inputs: each raises a precise ValueError/TypeError.

Each row: (id, callable, exception type, regex the message must match).
"""

import numpy as np
import pytest

import dvstatic as dv

SQ = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
TRI = np.array([[0, 1, 2], [0, 2, 3]])


def _lattice():
    return dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")


CASES = [
    (
        "points non-finite",
        lambda: dv.Mesh(np.r_[SQ[:3], [[np.nan, 1]]], TRI),
        ValueError,
        "non-finite",
    ),
    ("points wrong shape", lambda: dv.Mesh(np.zeros((4, 3)), TRI), ValueError, r"shape \(N, 2\)"),
    ("points not numeric", lambda: dv.Mesh([["a", "b"]] * 4, TRI), TypeError, "numeric"),
    (
        "duplicate points",
        lambda: dv.Mesh(np.r_[SQ, [[1, 1.0]]], np.r_[TRI, [[1, 2, 4]]]),
        ValueError,
        "duplicate point",
    ),
    (
        "degenerate triangle",
        lambda: dv.Mesh(np.r_[SQ, [[0.5, 0.0]]], np.r_[TRI, [[0, 4, 1]]]),
        ValueError,
        "zero area",
    ),
    ("unused point", lambda: dv.Mesh(np.r_[SQ, [[5, 5.0]]], TRI), ValueError, "not used"),
    (
        "triangle index out of range",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 7]])),
        ValueError,
        r"indices must be in \[0, 4\)",
    ),
    ("float triangles", lambda: dv.Mesh(SQ, TRI.astype(float)), TypeError, "integer"),
    (
        "triangles wrong shape",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 2, 3]])),
        ValueError,
        r"shape \(M, 3\)",
    ),
    (
        "overlapping triangles",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 2], [0, 1, 3]])),
        ValueError,
        "overlap",
    ),
    ("E zero", lambda: dv.DV(_lattice(), 0.0, 0.2), ValueError, "E must be > 0"),
    ("E negative", lambda: dv.RV(_lattice(), -1.0, 0.2), ValueError, "E must be > 0"),
    ("E not a number", lambda: dv.DV(_lattice(), "1e5", 0.2), TypeError, "E must be a real"),
    ("nu = 1", lambda: dv.DV(_lattice(), 1e5, 1.0), ValueError, "-1 < nu < 1"),
    ("nu = -1", lambda: dv.RV(_lattice(), 1e5, -1.0), ValueError, "-1 < nu < 1"),
    ("nu nan", lambda: dv.DV(_lattice(), 1e5, float("nan")), ValueError, "finite"),
    (
        "unknown calibration",
        lambda: dv.DV(_lattice(), 1e5, 0.2, calibration="magic"),
        ValueError,
        "accepted: relaxed, paper",
    ),
    ("mesh not a Mesh", lambda: dv.DV(SQ, 1e5, 0.2), TypeError, "dvstatic Mesh"),
    (
        "unknown side name",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("west"), []),
        ValueError,
        "unknown boundary part 'west'; known parts: 'bottom'",
    ),
    (
        "no supports",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), [], dv.Traction("right", (1, 0))),
        ValueError,
        "no supports",
    ),
    (
        "only one direction",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left", x=0), dv.Traction("right", (1, 0))
        ),
        ValueError,
        "translation along",
    ),
    (
        "single pinned node",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix([0]), dv.Traction("right", (1, 0))),
        ValueError,
        "rotation about",
    ),
    (
        "u wrong shape",
        lambda: dv.DV(_lattice(), 1e5, 0.2).internal_force(np.zeros(7)),
        ValueError,
        "must have shape",
    ),
    (
        "eps wrong shape",
        lambda: dv.homogenize(dv.DV(_lattice(), 1e5, 0.2), np.zeros(3)),
        ValueError,
        r"shape \(2, 2\)",
    ),
    ("traction value wrong", lambda: dv.Traction("right", (1, 2, 3)), ValueError, "two numbers"),
    (
        "traction on interior edge",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), [dv.Fix("left")], dv.Traction(np.array([[0, 6]]), (1, 0))
        ),
        ValueError,
        "not a boundary edge",
    ),
    (
        "fix node out of range",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix([999]), []),
        ValueError,
        r"must lie in \[0, ",
    ),
    (
        "conflicting supports",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), [dv.Fix("left", x=0), dv.Fix("left", x=1)], []
        ),
        ValueError,
        "conflicting supports",
    ),
    ("fix where wrong type", lambda: dv.Fix(3.5), TypeError, "part name, an index array or At"),
    ("fix at not finite", lambda: dv.Fix(at=(float("nan"), 0.0)), ValueError, "at must be finite"),
    (
        "fix at far from every node",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), [dv.Fix(at=(5.0, 5.0))], []),
        ValueError,
        "no node at",
    ),
    (
        "traction at a point",
        lambda: dv.Traction(dv.At(1.0, 0.5), (1.0, 0.0)),
        TypeError,
        "At selects a node",
    ),
    ("point load without nodes", lambda: dv.PointLoad(value=(0, 1)), TypeError, "give `nodes`"),
    (
        "stress outside the mesh",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), [dv.Fix("left")], [dv.Traction("right", (1.0, 0.0))]
        ).stress_at([[3.0, 3.0]]),
        ValueError,
        "outside the mesh",
    ),
    (
        "load in supports",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), [dv.BodyForce((0, 1))], []),
        TypeError,
        "supports must be Fix",
    ),
    (
        "unknown solver",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), [], solver="cholesky"),
        ValueError,
        "accepted: auto",
    ),
    (
        "rtol out of range",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), [], rtol=2.0),
        ValueError,
        r"rtol must be in \(0, 1\)",
    ),
    (
        "rectangle h too large",
        lambda: dv.mesh.rectangle(1.0, 0.5, 0.8),
        ValueError,
        "larger than the domain",
    ),
    (
        "rectangle negative width",
        lambda: dv.mesh.rectangle(-1.0, 1.0, 0.1),
        ValueError,
        "width must be > 0",
    ),
    (
        "rectangle unknown kind",
        lambda: dv.mesh.rectangle(1, 1, 0.1, kind="hex"),
        ValueError,
        "accepted: lattice, jittered, random",
    ),
    (
        "jitter too large",
        lambda: dv.mesh.rectangle(1, 1, 0.1, jitter=0.7),
        ValueError,
        r"jitter must be in \[0, 0.5\)",
    ),
    (
        "periodic too few points",
        lambda: dv.mesh.periodic_square(5),
        ValueError,
        "n_points must be >= 16",
    ),
    (
        "perturbed negative amplitude",
        lambda: _lattice().perturbed(-0.1),
        ValueError,
        "amplitude must be >= 0",
    ),
    (
        "fracture ft <= 0",
        lambda: dv.fracture(
            dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), dv.Traction("right", (1.0, 0.0)), ft=0.0
        ),
        ValueError,
        "ft must be a finite number > 0",
    ),
    (
        "fracture gf too small for the mesh",
        lambda: dv.fracture(
            dv.DV(_lattice(), 1e5, 0.2),
            dv.Fix("left"),
            dv.Traction("right", (1.0, 0.0)),
            ft=1.0,
            gf=1e-12,
        ),
        ValueError,
        "gf = .* is too small for this mesh",
    ),
    (
        "fracture without a load",
        lambda: dv.fracture(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), [], ft=1.0),
        ValueError,
        "nothing loads the body",
    ),
    (
        "strain on bounded mesh",
        lambda: dv.DV(_lattice(), 1e5, 0.2).internal_force(
            np.zeros((_lattice().n_points, 2)), strain=np.eye(2)
        ),
        ValueError,
        "periodic meshes only",
    ),
]


def _cli(args):
    from dvstatic import cli

    code = cli.main(args)
    if code != 0:
        raise SystemExit(code)


def _garbage_msh(tmp):
    p = tmp / "bad.msh"
    p.write_text("$MeshFormat\nthis is not gmsh\n")
    return p


CLI_CASES = [
    (
        "scene file missing",
        lambda tmp: dv.scene.load(tmp / "none.toml"),
        ValueError,
        "scene file not found",
    ),
    (
        "unreadable mesh file",
        lambda tmp: dv.io.read_mesh(_garbage_msh(tmp)),
        ValueError,
        "cannot read mesh file",
    ),
    (
        "bad --set syntax",
        lambda tmp: dv.scene.load(_scene(tmp), ["mesh.h"]),
        ValueError,
        "key.path=value",
    ),
    (
        "--set unknown key",
        lambda tmp: dv.scene.load(_scene(tmp), ["mesh.size=2"]),
        ValueError,
        "mesh.size: unknown key",
    ),
    (
        "--set wrong type",
        lambda tmp: dv.scene.load(_scene(tmp), ['mesh.h="fine"']),
        ValueError,
        "mesh.h: expected a finite number",
    ),
    (
        "cli run missing scene",
        lambda tmp: _cli(["run", str(tmp / "none.toml"), "--quiet"]),
        SystemExit,
        "2",
    ),
    (
        "cli validate without scripts",
        lambda tmp: _cli(["validate", "--dir", str(tmp)]),
        SystemExit,
        "2",
    ),
    (
        "unknown png field",
        lambda tmp: dv.io.nodal_field(None, "temperature"),
        ValueError,
        "accepted: |u|",
    ),
    (
        "unknown stress method",
        lambda tmp: dv.solve(
            dv.RV(_lattice(), 1e5, 0.2), dv.Fix("left"), dv.Traction("right", (1, 0))
        ).stress("average"),
        ValueError,
        "accepted: recovered, virial, strain",
    ),
    (
        "FE order 5",
        lambda tmp: dv.fem.solve(_lattice(), 1e5, 0.2, dv.Fix("left"), [], order=5),
        ValueError,
        "order must be <= 4",
    ),
    (
        "with_spread below start",
        lambda tmp: dv.mesh.with_spread(dv.mesh.rectangle(1, 1, 0.1, kind="random", seed=1), 0.05),
        ValueError,
        "below the spread",
    ),
    (
        "stability wrong model",
        lambda tmp: dv.stability("DV", None),
        TypeError,
        "dvstatic DV or RV model",
    ),
    (
        "relaxed nu unreachable",
        lambda tmp: dv.DV(dv.mesh.rectangle(1, 1, 0.1, kind="random", seed=0), 1e5, -0.5),
        ValueError,
        r"nu = -0.5 cannot be reached by the relaxed DV lattice of a random mesh: its "
        r"nu_eff lies in \[-0.278, 0.709\]",
    ),
]


def _scene(tmp):
    p = tmp / "s.toml"
    p.write_text(
        '[mesh]\ntype = "rectangle"\nwidth = 1.0\nheight = 1.0\nh = 0.25\n'
        '[material]\nE = 1e5\nnu = 0.2\n[[supports]]\nwhere = "left"\n'
    )
    return p


@pytest.mark.parametrize("case", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_bad_input_files_and_cli(tmp_path, capsys, case):
    _, fn, exc, pattern = case
    with pytest.raises(exc, match=pattern):
        fn(tmp_path)
    if exc is SystemExit:
        err = capsys.readouterr().err
        assert err.startswith("error: ") and "Traceback" not in err


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input(case):
    _, fn, exc, pattern = case
    with pytest.raises(exc, match=pattern):
        fn()


def test_catalogue_is_documented():
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "errors.md").read_text()
    for name, *_ in CASES + CLI_CASES:
        assert f"| {name} |" in doc, name


def _write_doc() -> None:  # python tests/test_bad_input.py regenerates docs/errors.md
    import tempfile
    from pathlib import Path

    rows = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for name, fn, exc, _ in CASES + CLI_CASES:
            try:
                fn(tmp) if (name, fn, exc, _) in CLI_CASES else fn()
                msg = "(no error)"
            except BaseException as err:  # noqa: BLE001 - recording what is raised
                msg = str(err).replace("|", "\\|").replace("\n", " ")
                if isinstance(err, SystemExit):
                    msg = f"exit code {err.code}; stderr: one line starting with `error:`"
            rows.append(f"| {name} | `{exc.__name__}` | {msg} |")
    text = (
        "# Errors\n\n"
        "Every bad input is refused at the public boundary with a `ValueError` or `TypeError`\n"
        "(or `dvstatic.SolverError` for a solve that is refused or fails) whose message names\n"
        "the problem and, where there is one, the accepted range. The command line prints\n"
        "the message as one line starting with `error:` (no traceback) and exits with code 2\n"
        "(bad input), 3 (solver refused or failed), 4 (best effort: unconverged result\n"
        "written) or 130 (interrupted). Scene-file errors are listed in\n"
        "[scenes.md](scenes.md) and tested in `tests/test_scene.py`.\n\n"
        "This catalogue is generated by running every case of `tests/test_bad_input.py`\n"
        "(`python tests/test_bad_input.py`), which also checks each type and message.\n\n"
        "| case | exception | message |\n|---|---|---|\n" + "\n".join(rows) + "\n"
    )
    (Path(__file__).resolve().parents[1] / "docs" / "errors.md").write_text(text)


if __name__ == "__main__":
    _write_doc()
