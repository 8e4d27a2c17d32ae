"""Front ends over the API: the command line, the browser viewer, batch runs, the paper benchmark.

    cli/          the `polyfold` command (thin: each verb calls the API)
    view.py       the browser viewer (viser) of a make folder
    batch.py      make over many meshes (`polyfold batch`): inputs, rows, summary.csv / .jsonl
    study.py      a study over many meshes (`batch --study unfold | cspace`): its tasks, CSV and SVG plot
    isolation.py  one process per task, locally (forkserver pool) or on Dask; outcomes of crashed /
                  killed tasks; the `python -m polyfold.apps.isolation` entry of a Dask task
    benchpaper.py `polyfold bench paper`: the paper's experiments, measured
    benchpaper_report.py  its report.md and figures, beside the paper's numbers
"""
