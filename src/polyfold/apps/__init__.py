"""Front ends over the API: the command line, the browser viewer, batch runs, the paper benchmark.

    cli/          the `polyfold` command (thin: each verb calls the API)
    view.py       the browser viewer (viser) of a make folder
    batch.py      make, or a study, over many meshes, one process each, locally or on Dask
    benchpaper.py `polyfold bench paper`: the paper's tables and figures, regenerated
"""
