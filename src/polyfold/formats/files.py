"""Writing files safely: `atomic_write` (one file: temp file, then rename), `StagedFolder`
(several files: written into a temporary folder, then moved in together) and `check_outputs`
(output paths checked before any work).

A folder polyfold writes into keeps three hidden files beside the outputs:
- `.polyfold-manifest.json`: the names the last finished run wrote. Only those are ever replaced
  or removed; any other file in the way stops the run with one line, whoever put it there.
- `.polyfold-commit.json`: a commit under way (the staged folder and what it moves in and
  removes), written once everything is staged. A run killed while moving files in leaves it, and
  the next run into the folder finishes that commit first (roll forward), so the folder holds one
  run's set or the other's, never a mix, once anyone writes there again.
- `.polyfold.lock`: held (flock) while a run stages and commits, so two runs into one folder take
  turns. Temporary `.polyfold-*` folders found under the lock are a killed run's and are removed.
  A run that made the folder (and the folders above it) and stops before its commit (an error,
  Ctrl-C) removes them again while they hold nothing but the lock.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Iterable

from ..errors import PolyfoldError


def _default_mode() -> int:
    # The mode a plain open() would give a new file (mkstemp uses 0600).
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


_FILE_MODE = _default_mode()  # read once: os.umask is process-wide, so never toggle it later


def use_umask(mask: int) -> None:
    """Make `mask` this process's umask and the mode new files get from it (a server's child
    takes its client's: `apps.server`), before any writing starts."""
    global _FILE_MODE
    os.umask(mask)
    _FILE_MODE = 0o666 & ~mask


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


MANIFEST = ".polyfold-manifest.json"
JOURNAL = ".polyfold-commit.json"
LOCK = ".polyfold.lock"
TEMP_PREFIX = ".polyfold-"


def _first_missing(folder: Path) -> Path | None:
    """The topmost of `folder` and its parents that does not exist (None: folder exists)."""
    missing = None
    while not folder.exists():
        missing, folder = folder, folder.parent
        if folder == missing:  # (the root)
            break
    return missing


def _same_inode(fd: int, path: Path) -> bool:
    """Whether the open file `fd` is the file at `path` (which may be gone)."""
    try:
        here = os.stat(path)
    except FileNotFoundError:
        return False
    there = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and os.path.samefile(a, b))
    except OSError:
        return False


def check_outputs(outputs: Iterable[str | os.PathLike | None], inputs: Iterable[str | os.PathLike | None]) -> None:
    """Before any work: PolyfoldError (one line, exit 2) when an output file could not be written
    or would replace an input: it is an input file, an existing folder, or its folder is missing
    or not writable. (None entries: options not given.) A run that fails later still writes
    nothing, as every file goes through `atomic_write`; this catches the cases known up front,
    so a first output is not left behind by a second that cannot be written."""
    ins = [Path(p) for p in inputs if p is not None]
    outs = [Path(p) for p in outputs if p is not None]
    for k, out in enumerate(outs):
        for inp in ins:
            if _same_file(out, inp):
                raise PolyfoldError(f"{out}: is the input file {inp}; choose another output path "
                                    "(polyfold never replaces its input)")
        if any(_same_file(out, other) for other in outs[:k]):
            raise PolyfoldError(f"{out}: given for two outputs; choose a path for each")
        if out.is_dir():
            raise PolyfoldError(f"{out}: is a folder; give a file path")
        folder = out.parent if str(out.parent) else Path(".")
        if not folder.is_dir():
            raise PolyfoldError(f"{out}: folder {folder} does not exist")
        if not os.access(folder, os.W_OK | os.X_OK):
            raise PolyfoldError(f"{out}: folder {folder} is not writable")


def check_folder(out_dir: str | os.PathLike, patterns: Iterable[str], inputs: Iterable[str | os.PathLike | None]) -> None:
    """Before any work: PolyfoldError (one line) when the output folder is a file, or an input
    file lies in it under a name the run may write (glob `patterns`): polyfold would replace or
    remove its own input. (`StagedFolder.commit` checks the names actually written again.)"""
    import fnmatch

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise PolyfoldError(f"{out}: is a file, not a folder; give a folder for the outputs")
    for inp in (Path(p) for p in inputs if p is not None):
        if _same_file(inp.parent, out) and any(fnmatch.fnmatchcase(inp.name, p) for p in patterns):
            raise PolyfoldError(f"{inp}: this run's input is named like one of its outputs in {out}; "
                                "choose another output folder (polyfold never replaces its input)")


class StagedFolder:
    """Files written into a temporary folder inside `out_dir` and moved into `out_dir` together by
    `commit` (see the module docstring: manifest, commit journal, lock). Use as a context manager:
    the lock is taken on entry (waiting for another run into the same folder), the temporary
    folder is removed on exit, committed or not. `inputs`: files this run reads, never replaced.

        with StagedFolder(out, "make", inputs=[mesh_path]) as stage:
            stage.write("report.json", text)
            stage.commit()
    """

    def __init__(self, out_dir: str | os.PathLike, purpose: str,
                 inputs: Iterable[str | os.PathLike | None] = ()) -> None:
        self.out = Path(out_dir)
        self.purpose = purpose
        self.inputs = [Path(p) for p in inputs if p is not None]
        self.names: list[str] = []
        self._lock_fd: int | None = None
        self.tmp: Path | None = None
        self._made: Path | None = None  # the topmost folder this run made (`__enter__`)
        self._committed = False

    def __enter__(self) -> StagedFolder:
        import fcntl

        while True:
            try:
                self._made = _first_missing(self.out)  # (removed again if this run writes nothing)
                self.out.mkdir(parents=True, exist_ok=True)
                self._lock_fd = os.open(self.out / LOCK, os.O_RDWR | os.O_CREAT, _FILE_MODE)
            except OSError as exc:
                raise PolyfoldError(f"{self.out}: cannot write into this folder ({exc.strerror or exc})") from None
            fcntl.flock(self._lock_fd, fcntl.LOCK_EX)  # another run into this folder: wait for it
            if _same_inode(self._lock_fd, self.out / LOCK):
                break
            # the run waited for made the folder, wrote nothing and took the folder away: again
            os.close(self._lock_fd)
            self._lock_fd = None
        try:
            self._recover()
            self.previous = set(self._manifest())
            self.tmp = Path(tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{self.purpose}-", dir=self.out))
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            self.tmp = None
        if self._lock_fd is not None:
            if self._made is not None and not self._committed:
                self._remove_empty()
            os.close(self._lock_fd)  # releases the flock
            self._lock_fd = None

    def _remove_empty(self) -> None:
        """Remove the folder this run made, and those it made above it, while it holds nothing
        but the lock (a run stopped before its commit: an error, or Ctrl-C mid-export), under the
        lock: a run waiting for it finds its lock file gone and makes the folder again
        (`__enter__`)."""
        try:
            if [p.name for p in self.out.iterdir()] != [LOCK]:
                return
            (self.out / LOCK).unlink()
            folder = self.out
            while True:
                folder.rmdir()
                if folder == self._made:
                    break
                folder = folder.parent
        except OSError:
            pass

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

    def commit(self) -> tuple[str, ...]:
        """Move the staged files in (in the order they were staged) and remove the files the last
        run wrote that this one does not: first check that none of them is an input or a file
        polyfold did not write (PolyfoldError naming it, nothing changed), then write the commit
        journal, then move. Returns the staged names."""
        for name in self.names:
            target = self.out / name
            for inp in self.inputs:
                if _same_file(target, inp):
                    raise PolyfoldError(f"{target}: is this run's input; polyfold would replace it with its "
                                        "own output: choose another output folder")
            if (target.exists() or target.is_symlink()) and name not in self.previous:
                raise PolyfoldError(f"{target}: exists and was not written by polyfold into this folder; "
                                    "move it or choose another output folder (nothing was written)")
        remove = sorted(self.previous - set(self.names))
        for name in remove:
            for inp in self.inputs:
                if _same_file(self.out / name, inp):
                    raise PolyfoldError(f"{self.out / name}: is this run's input and an earlier run's output "
                                        "that this run would remove: choose another output folder")
        journal = {"staged": self.tmp.name, "files": self.names, "remove": remove}
        self._committed = True  # (from the journal on, the folder holds a run's files, or will)
        atomic_write(self.out / JOURNAL, json.dumps(journal) + "\n")
        self._apply(journal)
        return tuple(self.names)

    def _manifest(self) -> list[str]:
        """Names the last finished run wrote (the manifest; a folder of an older polyfold without
        one: its report.json's `outputs`, when it has them)."""
        for name, key in ((MANIFEST, "files"), ("report.json", "outputs")):
            try:
                doc = json.loads((self.out / name).read_text(encoding="utf-8"))
                files = doc.get(key) if isinstance(doc, dict) else None
            except (OSError, ValueError):
                continue
            if isinstance(files, list) and all(isinstance(f, str) for f in files):
                return [f for f in files if f and "/" not in f and "\\" not in f and not f.startswith(".")]
        return []

    def _apply(self, journal: dict) -> None:
        """Carry out a commit journal: remove the old names, move the staged files in (those already
        moved by an interrupted run are gone from the staged folder), write the manifest, drop the
        journal and the staged folder."""
        staged = self.out / journal["staged"]
        for name in journal["remove"]:
            try:
                (self.out / name).unlink()
            except FileNotFoundError:
                pass
        for name in journal["files"]:
            if (staged / name).exists():
                os.replace(staged / name, self.out / name)
        atomic_write(self.out / MANIFEST, json.dumps({"writer": "polyfold", "files": journal["files"]}) + "\n")
        (self.out / JOURNAL).unlink()
        shutil.rmtree(staged, ignore_errors=True)

    def _recover(self) -> None:
        """Under the lock: finish a killed run's commit (its journal), then remove every temporary
        folder left by killed runs."""
        try:
            journal = json.loads((self.out / JOURNAL).read_text(encoding="utf-8"))
        except FileNotFoundError:
            journal = None
        except (OSError, ValueError):
            journal = None  # unreadable: it was being written when the run died, before any move
            (self.out / JOURNAL).unlink()
        if journal is not None:
            self._apply(journal)
        for old in self.out.glob(f"{TEMP_PREFIX}*"):
            if old.is_dir() and not old.is_symlink():
                shutil.rmtree(old, ignore_errors=True)
