"""`polyfold batch`: make over many meshes, locally or on Dask (issue 9).

Only typer is imported at module level: `polyfold --help` must stay fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from . import cli_options


def register(app, guard, say, fail) -> None:
    """Add the command to the typer `app`. guard: wraps a command body (one-line errors, exit
    codes); say(line): one line on stderr; fail(message, code): one error line and exit."""

    @app.command(name="batch")
    @guard
    def batch(
        patterns: List[str] = typer.Argument(..., metavar="GLOB", help="Mesh files or quoted glob patterns ('models/*.obj', '**' allowed)."),
        output: Path = typer.Option(..., "-o", "--output", help="Folder: one subfolder per mesh, summary.csv, summary.jsonl."),
        workers: Optional[int] = typer.Option(None, "--workers", min=1, help="Meshes at once, each in its own process (default: CPUs)."),
        scheduler: Optional[str] = typer.Option(None, "--scheduler", envvar="POLYFOLD_SCHEDULER", help="Dask scheduler address (tcp://host:8786): run the meshes on that cluster (needs dask.distributed)."),
        time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the searches, per mesh (passed to make / unfold)."),
        hard_limit: Optional[float] = typer.Option(None, "--hard-limit", min=0.0, help="Kill a mesh's task after this many seconds (default 2 x time limit + 30; studies: 2 x their budget + 30)."),
        force: bool = typer.Option(False, "--force", help="Redo meshes that already have a finished report.json with the same options."),
        study: Optional[str] = typer.Option(None, "--study", help="cspace | unfold: run a study over the meshes instead of make (CSV + SVG plot)."),
        runs: int = typer.Option(5, "--runs", min=1, help="--study unfold: seeds 1..N per component."),
        samples: int = typer.Option(1000, "--samples", min=1, help="--study cspace: configurations per strategy."),
        inflate_mode: str = cli_options.INFLATE,
        segment_mode: str = cli_options.SEGMENT,
        tau: Optional[float] = cli_options.TAU,
        parts: Optional[int] = cli_options.PARTS,
        paper: str = cli_options.PAPER,
        size: float = cli_options.SIZE,
        margin: float = cli_options.MARGIN,
        tabs: str = cli_options.TABS,
        seed: int = typer.Option(1, "--seed", help="Random seed (same seed, same sheets; --study cspace: the net and samples)."),
        fold: bool = cli_options.FOLD,
        contact_tol: float = cli_options.CONTACT_TOL,
        quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress and no table: only the summary line and errors."),
    ) -> None:
        """Make (or study) every mesh matching GLOB, each in its own process, locally or on Dask.

        Writes summary.csv/.jsonl (or study-NAME.csv/.svg) into the output folder; exit 1 if any
        mesh failed (error, timeout, crashed)."""
        import time

        opts = cli_options.make_options(fail, inflate=inflate_mode, segment=segment_mode, tau=tau, parts=parts,
                                        paper=paper, size=size, margin=margin, tabs=tabs, seed=seed,
                                        time_limit=time_limit, fold=fold, contact_tol=contact_tol)
        if study is not None and study not in ("cspace", "unfold"):
            fail(f"--study must be 'cspace' or 'unfold', not {study!r}", 2)
        from .batch import run_batch, run_study

        t0 = time.perf_counter()
        progress, close = _progress(quiet, say)
        try:
            if study is None:
                result = run_batch(patterns, output, opts, workers=workers, scheduler=scheduler,
                                   hard_limit=hard_limit, force=force, progress=progress)
            else:
                result = run_study(study, patterns, output, runs=runs, samples=samples, seed=seed,
                                   time_limit=time_limit, contact_tol=contact_tol, workers=workers,
                                   scheduler=scheduler, hard_limit=hard_limit, progress=progress)
        finally:
            close()
        if not quiet:
            _table(result.rows, make=study is None)
        counts = result.counts()
        ran = len(result.rows) - counts["skipped"]
        minutes = (time.perf_counter() - t0) / 60
        parts_text = ", ".join(f"{n} {s}" for s, n in counts.items() if n)
        rate = f", {ran / minutes:.1f} meshes/min" if ran and minutes > 0 else ""
        what = "batch" if study is None else f"study {study}"
        files = " ".join(str(f) for f in result.files)
        say(f"{what}: {len(result.rows)} mesh(es): {parts_text}; {minutes * 60:.1f} s{rate} -> {files}")
        if result.failed:
            raise typer.Exit(1)


def _progress(quiet: bool, say):
    """(progress callback for run_batch / run_study, close function): a rich bar on a terminal,
    else one stderr line per finished mesh; nothing when quiet."""
    if quiet:
        return None, lambda: None
    from rich.console import Console

    console = Console(stderr=True)
    if not console.is_terminal:
        def line(row, done: int, total: int) -> None:
            detail = f": {row.error}" if row.error else f", {row.total_s:.1f} s"
            say(f"[{done}/{total}] {Path(row.mesh).name}: {row.status}{detail}")

        return line, lambda: None
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn("polyfold batch"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   TextColumn("{task.description}"), console=console, transient=True)
    task = bar.add_task("", total=None)
    bar.start()

    def update(row, done: int, total: int) -> None:
        if row.status not in ("ok", "skipped"):
            bar.console.print(f"polyfold: {Path(row.mesh).name}: {row.status}: {row.error}", markup=False,
                              highlight=False)
        bar.update(task, completed=done, total=total, description=f"{Path(row.mesh).name}: {row.status}")

    return update, bar.stop


def _table(rows, make: bool) -> None:
    """The summary table on stdout: one row per mesh, the columns that matter for the kind."""
    from dataclasses import fields

    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    if not rows:
        return
    if make:
        cols = ["out", "status", "faces", "parts", "pieces", "pages", "unfold_s", "fold_s", "total_s", "error"]
    else:
        skip = {"mesh", "mean_s", "max_s", "discrete_valid", "continuous_valid"}
        cols = [f.name for f in fields(rows[0]) if f.name not in skip]
    table = Table(box=None, pad_edge=False)
    table.add_column("mesh")
    for c in cols[0 if not make else 1:]:
        table.add_column(c, justify="left" if c in ("status", "error") else "right",
                         overflow="fold" if c == "error" else "ellipsis")
    for r in rows:
        name = r.out if make else Path(r.mesh).stem
        cells = []
        for c in cols[0 if not make else 1:]:
            v = getattr(r, c)
            cells.append("" if v is None else f"{v:.3g}" if isinstance(v, float) and not c.endswith("_s")
                         else f"{v:.2f}" if isinstance(v, float) else str(v))
        table.add_row(Text(name), *map(Text, cells))  # Text: error messages are not rich markup
    Console(width=160).print(table, markup=False, highlight=False)
