"""Writing files safely: `atomic_write` (temp file, then rename)."""

from __future__ import annotations

import os
import tempfile


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
