"""Output folders never lose a user's files (issue 23, part 1): only the files a run
writes are replaced; foreign files, subfolders and the scene itself stay; a second
run replaces its own files; bad ``--out`` values are one line and exit 2."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from dvstatic import cli
from dvstatic.outfolder import MANIFEST, OutputError, OutputFolder

SCENE = """
[mesh]
type = "rectangle"
width = 1.0
height = 1.0
h = 0.25
[material]
E = 1e5
nu = 0.2
[[supports]]
where = "left"
[[loads]]
type = "traction"
where = "right"
value = [1.0, 0.0]
[output]
png = false
"""
OUTPUTS = ["s.json", "s.vtu", "s_bonds.vtu"]


def _files(folder: Path) -> list[str]:
    """Every file under ``folder`` (relative, sorted), the manifest left out."""
    return sorted(
        p.relative_to(folder).as_posix()
        for p in folder.rglob("*")
        if p.is_file() and p.name != MANIFEST
    )


@pytest.fixture
def user_folder(tmp_path):
    """A folder of the user's with notes, a subfolder and the scene inside it."""
    p = tmp_path / "p"
    (p / "sub").mkdir(parents=True)
    (p / "notes.txt").write_text("x")
    (p / "sub" / "keep.dat").write_text("y")
    (p / "s.toml").write_text(textwrap.dedent(SCENE))
    return p


def test_overwrite_replaces_only_what_the_run_writes(user_folder):
    p = user_folder
    scene = p / "s.toml"
    assert cli.main(["run", str(scene), "--out", str(p), "--quiet", "--overwrite"]) == 0
    assert _files(p) == sorted(["notes.txt", "sub/keep.dat", "s.toml", *OUTPUTS])
    before = (p / "s.json").stat().st_mtime_ns
    # a second run replaces its own files and nothing else
    assert cli.main(["run", str(scene), "--out", str(p), "--quiet", "--overwrite"]) == 0
    assert _files(p) == sorted(["notes.txt", "sub/keep.dat", "s.toml", *OUTPUTS])
    assert (p / "s.json").stat().st_mtime_ns >= before
    assert (p / "notes.txt").read_text() == "x" and (p / "sub" / "keep.dat").read_text() == "y"
    assert not [q for q in p.iterdir() if q.name.startswith(".dvstatic-staging")]


def test_a_foreign_folder_is_fine_without_overwrite_but_own_names_are_not(user_folder, capsys):
    p, scene = user_folder, user_folder / "s.toml"
    # nothing of the run's names is there: no --overwrite needed, nothing removed
    assert cli.main(["run", str(scene), "--out", str(p), "--quiet"]) == 0
    assert "notes.txt" in _files(p)
    capsys.readouterr()
    assert cli.main(["run", str(scene), "--out", str(p), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--overwrite" in err and "s.json" in err and "Traceback" not in err


def test_files_of_an_earlier_run_that_this_run_does_not_write(user_folder):
    """A VTU turned off: the earlier VTU (ours, unchanged) goes; an edited one stays."""
    p, scene = user_folder, user_folder / "s.toml"
    run = ["run", str(scene), "--out", str(p), "--quiet", "--overwrite"]
    assert cli.main(run) == 0
    assert cli.main([*run, "--set", "output.vtu=false"]) == 0
    assert "s.vtu" not in _files(p) and "s.json" in _files(p)
    assert cli.main(run) == 0
    (p / "s_bonds.vtu").write_text("edited by the user")
    assert cli.main([*run, "--set", "output.vtu=false"]) == 0
    assert "s.vtu" not in _files(p)
    assert (p / "s_bonds.vtu").read_text() == "edited by the user"


def test_a_run_into_the_examples_folder_keeps_every_scene(tmp_path):
    ex = Path(__file__).resolve().parents[1] / "examples"
    copy = tmp_path / "examples"
    copy.mkdir()
    for f in ex.glob("*.toml"):
        (copy / f.name).write_bytes(f.read_bytes())
    scenes = sorted(f.name for f in copy.iterdir())
    args = ["run", str(copy / "uniaxial.toml"), "--out", str(copy), "--quiet", "--overwrite"]
    assert cli.main([*args, "--set", "mesh.h=0.25", "--set", "output.png=false"]) == 0
    assert set(scenes) <= set(_files(copy))


def test_an_output_that_would_replace_an_input_is_refused(tmp_path, capsys):
    scene = tmp_path / "s.json"  # a scene whose name is one of the outputs
    scene.write_text(textwrap.dedent(SCENE))
    text = scene.read_text()
    code = cli.main(["run", str(scene), "--out", str(tmp_path), "--quiet", "--overwrite"])
    assert code == 2
    assert "input" in capsys.readouterr().err
    assert scene.read_text() == text


@pytest.mark.parametrize("out", [".", ".."])
def test_out_dot_and_dotdot(tmp_path, out):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    (work / "s.toml").write_text(textwrap.dedent(SCENE))
    (tmp_path / "a" / "mine.txt").write_text("keep")
    proc = subprocess.run(
        [sys.executable, "-m", "dvstatic", "run", "s.toml", "--out", out, "--overwrite", "-q"],
        cwd=work,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    target = (work / out).resolve()
    assert (target / "s.json").is_file()
    assert (tmp_path / "a" / "mine.txt").read_text() == "keep"
    assert (work / "s.toml").is_file()


def test_out_an_existing_file_is_one_line_and_exit_2(tmp_path):
    (tmp_path / "s.toml").write_text(textwrap.dedent(SCENE))
    (tmp_path / "f").write_text("a file")
    proc = subprocess.run(
        [sys.executable, "-m", "dvstatic", "run", "s.toml", "--out", "f", "--overwrite", "-q"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("error:") and "is a file" in proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert (tmp_path / "f").read_text() == "a file"


def test_a_scene_that_is_a_folder(tmp_path, capsys):
    assert cli.main(["run", str(tmp_path), "--quiet"]) == 2
    assert "is a folder" in capsys.readouterr().err


def test_a_failed_write_leaves_the_folder_as_it_was(user_folder, monkeypatch, capsys):
    p, scene = user_folder, user_folder / "s.toml"
    run = ["run", str(scene), "--out", str(p), "--quiet", "--overwrite"]
    assert cli.main(run) == 0
    stamps = {n: (p / n).stat().st_mtime_ns for n in OUTPUTS}
    from dvstatic import io

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(io, "write_json", boom)
    assert cli.main(run) == 130
    assert {n: (p / n).stat().st_mtime_ns for n in OUTPUTS} == stamps
    assert "nothing was written" in capsys.readouterr().err
    assert not [q for q in p.iterdir() if q.name.startswith(".dvstatic-staging")]


def test_a_new_folder_is_not_left_behind_by_a_failed_run(tmp_path, monkeypatch):
    scene = tmp_path / "s.toml"
    scene.write_text(textwrap.dedent(SCENE))
    from dvstatic import io

    monkeypatch.setattr(io, "write_json", lambda *a, **k: (_ for _ in ()).throw(OSError("full")))
    assert cli.main(["run", str(scene), "--out", str(tmp_path / "new"), "--quiet"]) == 2
    assert not (tmp_path / "new").exists()


def test_output_folder_api(tmp_path):
    with pytest.raises(OutputError, match="is a file"):
        (tmp_path / "f").write_text("x")
        OutputFolder(tmp_path / "f")
    folder = OutputFolder(tmp_path / "o")
    folder.check(["a.txt", "d/b.txt"])
    with folder.staging() as stage:
        (stage / "a.txt").write_text("1")
        (stage / "d").mkdir()
        (stage / "d" / "b.txt").write_text("2")
        final = folder.commit(["a.txt", "d/b.txt"], owner="me")
    assert [f.read_text() for f in final] == ["1", "2"]
    with pytest.raises(OutputError, match="already has a.txt"):
        folder.check(["a.txt"])
    # another owner's files are never removed as stale
    with folder.staging() as stage:
        (stage / "c.txt").write_text("3")
        folder.commit(["c.txt"], owner="someone else")
    assert sorted(os.listdir(tmp_path / "o")) == sorted([MANIFEST, "a.txt", "c.txt", "d"])
