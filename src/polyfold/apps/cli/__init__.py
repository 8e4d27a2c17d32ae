"""The `polyfold` command: a thin layer over the API, one module per group of verbs.

    app.py            the typer app, one-line errors and exit codes, `main`
    options.py        options shared by several verbs (make and batch), defaults from the API
    mesh_commands.py  info, inflate, segment
    net_commands.py   unfold, fold, cspace
    make_commands.py  make, view, batch, bench paper

Heavy modules (numpy, numba, trimesh) are imported inside the commands, so `polyfold --help`
answers at once. Every user-facing failure is one line on stderr and a non-zero exit code: 2 for
bad input, 1 when the requested result was not found (e.g. --max-pieces 1).
"""
