"""The `polyfold` command: a thin layer over the API, one module per group of verbs.

    app.py              the typer app, one-line errors and exit codes, `main`
    options.py          options shared by several verbs (make and batch), defaults from the API
    mesh_commands.py    info, inflate, segment
    net_commands.py     unfold, fold, cspace
    make_commands.py    make, view, batch, bench paper
    server_commands.py  server start | stop | status | run

Heavy modules (numpy, numba, trimesh) are imported inside the commands, so `polyfold --help`
answers at once. Every user-facing failure is one line on stderr and a non-zero exit code: 2 for
bad input, 1 when the requested result was not found (e.g. --max-pieces 1).
"""

from __future__ import annotations


def main() -> None:
    """The `polyfold` entry point: a compute verb goes to this installation's server when one
    runs (`apps.server.forward`: nothing but the standard library imported first), else runs here."""
    import sys

    from ..server import forward

    code = forward(sys.argv[1:])
    if code is not None:
        sys.exit(code)
    from ...processes import collect_less, exit_status, in_roomy_stack, leave
    from .app import main as run_here

    collect_less()
    try:
        in_roomy_stack(run_here)
    except SystemExit as done:  # how `main` ends (always with an int code: its errors are said already)
        leave(exit_status(done))
