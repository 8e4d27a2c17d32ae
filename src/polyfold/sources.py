"""polyfold's own code as it is now, for what is made from it and must not outlive it (a server's
socket name, the ahead-of-time kernels' stamp): every .py file of the package, its path, size and
modification time. Standard library only (the command line's server client imports it first)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

PACKAGE = Path(__file__).resolve().parent


def hash_sources(h: Any) -> None:
    """Feed each .py file of the package (path, size, mtime; sorted) to h (a hashlib object)."""
    for dirpath, dirnames, filenames in os.walk(PACKAGE):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for name in sorted(filenames):
            if name.endswith(".py"):
                st = os.stat(os.path.join(dirpath, name))
                h.update(f"{dirpath}/{name}:{st.st_size}:{st.st_mtime_ns}\n".encode())
