"""Scene files: a whole problem (mesh, material, model, supports, loads, solver,
outputs) as TOML data, read with the standard library and validated against
:data:`SCHEMA`.

Scene values are data: nothing is evaluated as code. Every problem (unknown key,
wrong type, missing required key, impossible value, unknown boundary name, missing
mesh file, ...) raises :class:`SceneError` naming the file and the key path.
The reference of every key is generated from :data:`SCHEMA` (``docs/scenes.md``).
"""

from __future__ import annotations

from pathlib import Path

from .build import Scene
from .parse import parse
from .schema import SCHEMA, SOLVER_KEYS, F, SceneError, reference_markdown

__all__ = ["SceneError", "Scene", "load", "SCHEMA", "SOLVER_KEYS", "F", "reference_markdown"]


def load(path: str | Path, overrides=()) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : str or Path
    overrides : sequence of str
        ``"key.path=value"`` settings applied before validation; the value is a TOML
        value (``mesh.h=0.05``, ``model.type="RV"``, ``solver.nonlinear=true``).

    Raises
    ------
    SceneError
    """
    path = Path(path)
    if path.is_dir():
        raise SceneError(path, "", "is a folder, not a scene file (a .toml file)")
    if not path.is_file():
        raise SceneError(path, "", "scene file not found")
    return Scene(path, parse(path, path.read_bytes(), overrides))
