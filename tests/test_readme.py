"""The README's Python examples run as written."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_blocks_run(tmp_path, monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert blocks, "README has no python examples"
    monkeypatch.chdir(tmp_path)  # it writes out/fracture.pvd
    namespace: dict = {}
    exec(compile("\n".join(blocks), str(README), "exec"), namespace)  # noqa: S102
    assert namespace["sol"].info.converged
    assert namespace["res"].events and (tmp_path / "out" / "fracture.pvd").is_file()


def test_quickstart_python_blocks_run(tmp_path, monkeypatch):
    quickstart = README.parent / "docs" / "quickstart.md"
    blocks = re.findall(r"```python\n(.*?)```", quickstart.read_text(), re.S)
    assert blocks, "the quickstart has no python examples"
    monkeypatch.chdir(tmp_path)  # it writes beam.vtu
    namespace: dict = {}
    exec(compile("\n".join(blocks), str(quickstart), "exec"), namespace)  # noqa: S102
    assert namespace["sol"].info.converged and (tmp_path / "beam.vtu").is_file()
