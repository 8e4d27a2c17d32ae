"""Front ends over the API: the command line, the browser viewer, batch runs, the paper benchmark.

    cli.py, cli_options.py, cli_batch.py, cli_view.py   the `polyfold` command (thin)
    view.py       the browser viewer (viser)
    batch.py      make or a study over many meshes, one process each
    benchpaper.py `polyfold bench paper`: the paper's tables and figures, regenerated
"""
