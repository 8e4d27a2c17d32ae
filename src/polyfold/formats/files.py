"""Writing files safely: `atomic_write` (one file: temp file, then rename) and `StagedFolder`
(several files: written into a temporary folder, then moved in together)."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from typing import Iterable


def _default_mode() -> int:
    # The mode a plain open() would give a new file (mkstemp uses 0600).
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


_FILE_MODE = _default_mode()  # read once: os.umask is process-wide, so never toggle it later


def atomic_write(path: str | os.PathLike, data: str | bytes) -> None:
    """Write `data` to `path` via a temp file in the same directory and os.replace.

    Readers see the old file or the new one, never a half-written one; on failure the temp file
    is removed and the old file is left untouched.
    """
    path = os.fspath(path)
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        mode = os.stat(path).st_mode & 0o7777 if os.path.exists(path) else _FILE_MODE
        os.chmod(tmp, mode)
        os.replace(tmp, path)  # atomic on POSIX and Windows (same filesystem)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


class StagedFolder:
    """Files written into a temporary folder inside `out_dir` and moved into `out_dir` together by
    `commit`, so an error never leaves half the files. Use as a context manager: the temporary
    folder is removed on exit, committed or not.

        with StagedFolder(out, "make") as stage:
            stage.write("report.json", text)
            stage.commit(stale=["part-*.obj"])
    """

    def __init__(self, out_dir: str | os.PathLike, purpose: str) -> None:
        self.out = Path(out_dir)
        self.out.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=f".polyfold-{purpose}-", dir=self.out))
        self.names: list[str] = []

    def path(self, name: str) -> Path:
        """Where to write file `name` (for writers that take a path); it is committed with the rest."""
        if name not in self.names:
            self.names.append(name)
        return self.tmp / name

    def write(self, name: str, data: str | bytes) -> None:
        """Stage file `name` with `data` (text is written as UTF-8)."""
        target = self.path(name)
        if isinstance(data, str):
            target.write_text(data, encoding="utf-8")
        else:
            target.write_bytes(data)

    def commit(self, stale: Iterable[str] = ()) -> tuple[str, ...]:
        """Move the staged files in (in the order they were staged), after removing the files of
        out_dir that match a `stale` glob pattern and are not staged (an earlier run's outputs that
        this run does not produce). Returns the staged names."""
        for pattern in stale:
            for old in self.out.glob(pattern):
                if old.name not in self.names:
                    old.unlink()
        for name in self.names:
            os.replace(self.tmp / name, self.out / name)
        return tuple(self.names)

    def __enter__(self) -> StagedFolder:
        return self

    def __exit__(self, *exc) -> None:
        shutil.rmtree(self.tmp, ignore_errors=True)
