"""`polyfold batch`: make over many meshes, locally or on Dask (issue 9).

Only typer is imported at module level: `polyfold --help` must stay fast.
"""

from __future__ import annotations


def register(app, guard, say, fail) -> None:
    """Add the command to the typer `app`. guard: wraps a command body (one-line errors, exit
    codes); say(line): one line on stderr; fail(message, code): one error line and exit."""
