"""Docs stay in sync with the code."""

from pathlib import Path

from dvstatic import scene
from dvstatic.solvers.options import options_markdown

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_scene_reference_is_current():
    assert scene.reference_markdown() in (DOCS / "scenes.md").read_text()


def test_solve_options_table_is_current():
    assert options_markdown() in (DOCS / "api.md").read_text()


def test_docs_exist_and_link():
    readme = (DOCS.parent / "README.md").read_text()
    for name in (
        "quickstart.md",
        "scenes.md",
        "api.md",
        "theory.md",
        "validation.md",
        "architecture.md",
    ):
        assert (DOCS / name).is_file()
        assert f"docs/{name}" in readme
