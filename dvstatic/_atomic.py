"""Atomic writes: a file is written to a temporary sibling and renamed into place, so a
crash never leaves a half-written file under its final name."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["atomic_path", "finish"]


def atomic_path(path: Path) -> Path:
    """Temporary sibling of ``path`` (same folder, so the final rename is atomic)."""
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def finish(tmp: Path, path: Path) -> Path:
    """Rename the finished temporary ``tmp`` onto ``path``; returns ``path``."""
    os.replace(tmp, path)
    return path
