"""Output folders that never lose a user's files.

A run writes its files into a hidden staging folder inside the output folder and,
once every file is complete, renames each one onto its final name (a rename within
one file system is atomic). Only the files the run writes are replaced; nothing else
in the folder is touched. A manifest (``.dvstatic-manifest.json``) records what
dvstatic wrote there (path, size, modification time, the scene that wrote it), so
that a later run of the same scene can remove the files it wrote before and does not
write now (a picture turned off), and only if they are unchanged since: a file the
user edited, or one dvstatic never wrote, is never removed.

::

    folder = OutputFolder(out, overwrite=False, protect=[scene_file, mesh_file])
    folder.check(["beam.vtu", "beam.png", "beam.json"])   # before the solve
    with folder.staging() as stage:                       # write into stage / name
        ...
        folder.commit(names, owner="examples/beam.toml")

Refusals (:class:`OutputError`, an :class:`~dvstatic.errors.InputError`): the
output path is a file; a file the run writes exists and ``overwrite`` is off; a file
the run writes is one of the protected inputs (the scene, its mesh file).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import signal
import threading
from collections.abc import Iterable, Iterator
from datetime import UTC, datetime
from pathlib import Path

from .errors import InputError

log = logging.getLogger(__name__)

__all__ = ["OutputFolder", "OutputError", "MANIFEST"]

#: the file in an output folder that lists what dvstatic wrote there
MANIFEST = ".dvstatic-manifest.json"
_STAGE_PREFIX = ".dvstatic-staging-"


class OutputError(InputError):
    """The output folder cannot take this run's files (``param`` is ``"out"``)."""

    def __init__(self, message: str):
        super().__init__(message, "out")


class OutputFolder:
    """The folder a run writes into.

    Parameters
    ----------
    path : str or Path
        The output folder; made (with its parents) when the first file is committed.
    overwrite : bool
        Replace files of the names this run writes when they exist already.
    protect : iterable of paths
        Input files (the scene, a mesh file) that no output may replace.
    """

    def __init__(self, path: str | Path, overwrite: bool = False, protect: Iterable = ()):
        self.path = Path(path)
        self.overwrite = bool(overwrite)
        self._protect = {_identity(Path(p)) for p in protect if Path(p).exists()}
        self._protect.discard(None)
        if self.path.exists() and not self.path.is_dir():
            raise OutputError(f"output folder {self.path} is a file, not a folder; choose --out")
        self._made = not self.path.exists()
        self._stage: Path | None = None

    # -- before the run ------------------------------------------------------------
    def check(self, names: Iterable[str]) -> None:
        """Refuse now (before any work) if the files ``names`` (paths relative to the
        folder) cannot be written: a protected input among them, or an existing file
        without ``overwrite``.

        Raises
        ------
        OutputError
        """
        names = list(names)
        for name in names:
            target = self.path / name
            if target.exists() and _identity(target) in self._protect:
                raise OutputError(
                    f"output {target} would replace an input of this run; choose another --out"
                )
            if target.is_dir():
                raise OutputError(f"output {target} is a folder; choose another --out")
        if self.overwrite:
            return
        taken = [n for n in names if (self.path / n).is_file()]
        if taken:
            shown = ", ".join(taken[:4]) + (", ..." if len(taken) > 4 else "")
            raise OutputError(
                f"output folder {self.path} already has {shown}; pass --overwrite to "
                "replace these files (nothing else in the folder is touched) or choose --out"
            )

    # -- writing -------------------------------------------------------------------
    @contextlib.contextmanager
    def staging(self) -> Iterator[Path]:
        """A fresh staging folder inside the output folder; removed when the block
        ends (committed files have left it by then). On an error or Ctrl-C inside the
        block nothing in the output folder has changed."""
        self.path.mkdir(parents=True, exist_ok=True)
        stage = self.path / f"{_STAGE_PREFIX}{os.getpid()}"
        shutil.rmtree(stage, ignore_errors=True)  # ours: a crashed run of this process id
        stage.mkdir()
        self._stage = stage
        try:
            yield stage
        except BaseException:
            self._discard_if_made()
            raise
        finally:
            shutil.rmtree(stage, ignore_errors=True)
            self._stage = None

    def commit(self, names: Iterable[str], owner: str) -> list[Path]:
        """Move the staged files ``names`` onto their final names and record them in
        the manifest under ``owner`` (the scene file). Files this ``owner`` wrote before
        and does not write now are removed if unchanged since. Ctrl-C during the renames
        is held until they are done.

        Returns
        -------
        list of Path
            The final paths, in the order given.
        """
        if self._stage is None:
            raise RuntimeError("commit() outside staging()")
        names = list(names)
        with _sigint_deferred():
            manifest = _read_manifest(self.path)
            final = []
            for name in names:
                target = self.path / name
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self._stage / name, target)
                final.append(target)
            stale = [
                n for n, rec in manifest.items() if rec.get("owner") == owner and n not in names
            ]
            for name in stale:
                if self._remove_if_unchanged(name, manifest.pop(name)):
                    log.info("removed %s (written by an earlier run of %s)", name, owner)
            stamp = datetime.now(UTC).isoformat(timespec="seconds")
            for name, target in zip(names, final, strict=True):
                st = target.stat()
                manifest[name] = {
                    "owner": owner,
                    "size": st.st_size,
                    "mtime_ns": st.st_mtime_ns,
                    "written": stamp,
                }
            _write_manifest(self.path, manifest)
        return final

    def _remove_if_unchanged(self, name: str, rec: dict) -> bool:
        target = self.path / name
        try:
            st = target.stat()
        except FileNotFoundError:
            return False
        if not target.is_file() or (st.st_size, st.st_mtime_ns) != (
            rec.get("size"),
            rec.get("mtime_ns"),
        ):
            log.warning("kept %s: changed since dvstatic wrote it", target)
            return False
        target.unlink()
        with contextlib.suppress(OSError):  # a series folder left empty: ours, remove it
            if target.parent != self.path:
                target.parent.rmdir()
        return True

    def _discard_if_made(self) -> None:
        """The output folder, if this run made it and it holds nothing else."""
        if not self._made:
            return
        with contextlib.suppress(OSError):
            for p in self.path.iterdir():
                if not p.name.startswith(_STAGE_PREFIX):
                    return
            shutil.rmtree(self.path)

    def state(self) -> str:
        """How the folder stands, for messages: "left unchanged" or "not created"."""
        return "left unchanged" if self.path.exists() else "not created"


def _identity(path: Path):
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def _read_manifest(folder: Path) -> dict:
    try:
        data = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError):
        return {}
    files = data.get("files") if isinstance(data, dict) else None
    return dict(files) if isinstance(files, dict) else {}


def _write_manifest(folder: Path, files: dict) -> None:
    path = folder / MANIFEST
    tmp = path.with_name(f"{MANIFEST}.{os.getpid()}.tmp")
    text = json.dumps({"about": "files dvstatic wrote in this folder", "files": files}, indent=1)
    tmp.write_text(text)
    os.replace(tmp, path)


@contextlib.contextmanager
def _sigint_deferred():
    """Hold Ctrl-C until the block ends (the main thread only), then raise it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list = []
    previous = signal.signal(signal.SIGINT, lambda *a: caught.append(a))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            raise KeyboardInterrupt
