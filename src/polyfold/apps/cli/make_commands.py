"""The verbs that make folders: make, view (a folder or a mesh, in the browser), batch (many
meshes), bench paper."""

from __future__ import annotations

import time
from pathlib import Path
from typing import List, Optional

import typer

from ...fabricate.paper import BUILDABLE_EDGE_MM, size_for_edge
from . import options
from .app import app, bench_app, fail, guard, load, say


@app.command()
@guard
def make(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Folder for sheets, FOLD files, instructions and report."),
    inflate_mode: str = options.INFLATE,
    segment_mode: str = options.SEGMENT,
    tau: Optional[float] = options.TAU,
    parts: Optional[int] = options.PARTS,
    approximate: str = options.APPROXIMATE,
    paper: str = options.PAPER,
    size: float = options.SIZE,
    margin: float = options.MARGIN,
    tabs: str = options.TABS,
    seed: int = typer.Option(1, "--seed", min=0, help="Random seed (same seed, same sheets)."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the whole run: the searches (unfold, fold) share it with the layout; a mesh too fine to lay out in it stops with one line (exit 1)."),
    fold: bool = options.FOLD,
    marks: bool = options.MARKS,
    contact_tol: float = options.CONTACT_TOL_OPTION,
    thickness: float = options.THICKNESS_MM_OPTION,
    min_label_mm: float = options.MIN_LABEL,
    faces: str = options.FACES,
    color: str = options.COLOR,
    dpi: float = options.DPI,
    guide: bool = options.GUIDE,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No warnings or progress, only errors."),
) -> None:
    """Mesh in, printable sheets out: simplify, inflate, segment, unfold, fold, lay out with tabs and labels, export."""
    opts = options.make_options(fail, inflate=inflate_mode, segment=segment_mode, tau=tau, parts=parts,
                                    paper=paper, size=size, margin=margin, tabs=tabs, seed=seed,
                                    time_limit=time_limit, fold=fold, contact_tol=contact_tol,
                                    marks=marks, min_label_mm=min_label_mm, thickness=thickness, faces=faces,
                                    color=color, dpi=dpi, guide=guide, approximate=approximate)
    from contextlib import nullcontext

    from ...pipeline.make import make as run_make
    from ..warmup import compile_beside, kernels_cached

    first_run = kernels_cached() is False
    beside = compile_beside(opts.before_unfold) if first_run and fold else None
    if not quiet and first_run:
        say("first run: compiling polyfold's kernels (once: about 20 s with two cores, 40 s with one"
            + (", twice that with inflation or segmentation" if opts.before_unfold else "")
            + "; `polyfold warm-up` does it ahead)"
            + ("; the folding stage's in a second process" if beside is not None else ""))
    t0 = time.perf_counter()
    with options.make_progress(say, quiet, "polyfold make") as progress, beside or nullcontext():
        result = run_make(mesh, output, opts, progress, ready=beside.ready if beside is not None else None)
    rep = result.report
    lay = rep.stages.layout
    if not quiet:
        for w in rep.input.warnings:
            say(f"warning: {mesh.name}: {w}")
        simp = rep.stages.simplify
        if simp is not None:
            from ...mesh.simplify import summary

            say(summary(simp.spec, simp.faces_before, simp.faces_after, simp.hausdorff, simp.min_angle_deg))
        for row in rep.pieces:
            if not row.path_verified and fold:
                say(f"warning: piece {row.piece}: no verified folding path ({row.note})")
        if lay.untabbed_edges:
            say(f"warning: {len(lay.untabbed_edges)} glue edge(s) without a tab (no room on either side): "
                 f"{', '.join(lay.untabbed_edges[:10])}{' ...' if len(lay.untabbed_edges) > 10 else ''}")
        strips = [label for label, why in lay.reduced_tabs if why == "glue strip"]
        if strips:
            say(f"{len(strips)} seam(s) had no room for a tab and get a glue strip (piece S + label): "
                f"{', '.join(strips[:10])}{' ...' if len(strips) > 10 else ''}")
        if lay.seam_runs:
            say(f"no room for a {lay.min_label_mm:g} mm label beside every glue edge: {lay.seam_runs} seam run(s) of "
                "consecutive edges have one label each, their ends ticked (see instructions.html)")
        if lay.small_labels:
            say(f"warning: {lay.small_labels} label(s) found no free place at {lay.min_label_mm:g} mm and are "
                "printed over their face (try a larger --size or a smaller --min-label-mm"
                f"{', or a longer --time-limit: it stopped the cuts that make room for them' if lay.labels_ran_out else ''})")
        if lay.smallest_edge_mm < BUILDABLE_EDGE_MM:
            from ...mesh.simplify import AUTO_EDGE_MM

            # a sliver's edge asks for a size no sheet holds: fewer, larger faces are the way out
            simpler = (f", or simplify the mesh to faces about {AUTO_EDGE_MM:g} mm across: --faces {lay.faces_for_size}"
                       if lay.faces_for_size else "")
            say(f"warning: the smallest printed edge is {lay.smallest_edge_mm:.3g} mm, under {BUILDABLE_EDGE_MM:g} mm "
                f"(hard to fold and glue): --size {size_for_edge(size, lay.smallest_edge_mm)} would make it "
                f"{BUILDABLE_EDGE_MM:g} mm{simpler}")
        if lay.splits_for_page:
            say(f"split {lay.splits_for_page} crease(s) so every piece fits on {paper} paper at {size:g} mm")
        if lay.splits_for_labels:
            say(f"split {lay.splits_for_labels} crease(s) where labels had no room: pieces cut through their most "
                "crowded spot")
        if lay.splits_for_packing:
            say(f"split {lay.splits_for_packing} more crease(s) so the pieces fill fewer pages")
        look = rep.stages.color
        printed = ""
        if look is not None and look.printed != "none":
            printed = (f", printed in its {'texture' if look.printed == 'texture' else 'colours'} "
                       f"({look.dpi:g} dpi, sheets.pdf {rep.stages.export.pdf_bytes / 1e6:.1f} MB)"
                       if look.printed == "texture" else ", printed in flat colours")
        guide = rep.stages.guide
        if guide is not None:
            say(f"assembly guide: {guide.steps} steps in instructions.html and guide.pdf ({guide.pdf_pages} pages)"
                + (f"; seam(s) {', '.join(guide.closing_seams)} close the model from outside" if guide.closing_seams
                   else ""))
        approx = rep.stages.approximate
        if approx is not None:
            glue = "; glue them face to face where they touch: " + ", ".join(
                f"{i + 1}-{j + 1}" for i, j, _ in approx.contacts) + (
                " (each side marked \"glue to\" its piece on the sheets" + (
                    f", but {approx.unmarked_sides} too small for the note)" if approx.unmarked_sides else ")")
            ) if approx.contacts else ""
            say(f"convex approximation: {approx.parts} polyhedra of {min(approx.facets)}-{max(approx.facets)} sides, "
                f"none overlapping (independent check), {approx.clip_planes} cut apart; error (Hausdorff) up to "
                f"{approx.hausdorff_max:.1%} of the model's diagonal"
                + (f", volume {approx.volume_ratio:.0%} of the model's" if approx.volume_ratio is not None else "")
                + glue)
        say(f"{mesh.name}: {rep.stages.segment.parts} part(s), {len(rep.pieces)} piece(s), {lay.pages} "
             f"page(s) ({lay.utilisation:.0%} of their printable area){printed}, {lay.glue_edges} glue edges, "
             f"smallest edge {lay.smallest_edge_mm:.3g} mm, narrowest face {lay.smallest_face_mm:.3g} mm, "
             f"{rep.checks.paths_verified}/{len(rep.pieces)} folding paths verified "
             f"(independent check, {opts.thickness:g} mm paper), "
             f"{time.perf_counter() - t0:.2f} s -> {output}")
        if rep.compile_seconds:
            say(f"of that, {sum(c.seconds for c in rep.compile_seconds):.1f} s compiling polyfold's kernels (once; "
                f"{', '.join(f'{c.stage} {c.seconds:.1f} s' for c in rep.compile_seconds)}), not counted against "
                "--time-limit")


@app.command(name="view")
@guard
def view(
    path: Path = typer.Argument(..., help="Output folder of `polyfold make`, or a mesh file (made into a folder first)."),
    port: int = typer.Option(8080, "--port", min=0, max=65535, help="Port; 0 = any free port (a taken port moves to the next free one)."),
    host: Optional[str] = typer.Option(None, "--host", help="Address to listen on. Default 127.0.0.1 (this machine only); other addresses (e.g. 0.0.0.0) only when given here."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="With a mesh: keep the make output in this folder (default: a temporary folder, removed on exit)."),
    parts: Optional[int] = typer.Option(None, "--parts", min=1, help="With a mesh: segment into this many parts."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="With a mesh: seconds for make (see make --time-limit)."),
) -> None:
    """Show a make folder (or a mesh, made first) in the browser: parts, nets, folding animation, inflation."""
    import shutil
    import sys
    import tempfile

    from ...pipeline.folder import load_folder, make_folder
    from ..view import DEFAULT_HOST, check_host, serve, wait

    # Check the address before any slow work: a refused --host should fail at once.
    check_host(host if host is not None else DEFAULT_HOST, explicit=host is not None)
    if not path.exists():
        fail(f"{path}: no such file or folder", 2)
    temp_dir: Optional[Path] = None
    try:
        source = source_path = None
        if path.is_dir():
            if output is not None or parts is not None:
                say("warning: -o/--output and --parts apply to a mesh file only; showing the folder as it is")
            folder = load_folder(path)
        else:
            from ...pipeline.options import MakeOptions

            loaded = load(path)
            if output is None:
                temp_dir = Path(tempfile.mkdtemp(prefix="polyfold-view-"))
            out_dir = output if output is not None else temp_dir
            opts = MakeOptions(parts=parts, time_limit=time_limit)
            with options.make_progress(say, False, f"polyfold make {path.name}") as progress:
                folder = make_folder(loaded, out_dir, opts, progress)
            source, source_path = loaded.mesh, path
        viewer = serve(folder, host if host is not None else DEFAULT_HOST, port,
                       allow_remote=host is not None, source=source, source_path=source_path)
        if host is not None and not _is_loopback(viewer.server.get_host()):
            say(f"warning: listening on {host}: anyone who can reach this machine and has the URL below (its "
                f"token) can view the model and run make into {folder.path}")
        say(f"viewer at {viewer.url}")
        sys.stderr.flush()
        wait(viewer)
    finally:
        if temp_dir is not None:
            shutil.rmtree(temp_dir, ignore_errors=True)


def _is_loopback(host: str) -> bool:
    import ipaddress

    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


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
    inflate_mode: str = options.INFLATE,
    segment_mode: str = options.SEGMENT,
    tau: Optional[float] = options.TAU,
    parts: Optional[int] = options.PARTS,
    paper: str = options.PAPER,
    size: float = options.SIZE,
    margin: float = options.MARGIN,
    tabs: str = options.TABS,
    seed: int = typer.Option(1, "--seed", min=0, help="Random seed (same seed, same sheets; --study cspace: the net and samples)."),
    fold: bool = options.FOLD,
    marks: bool = options.MARKS,
    contact_tol: float = options.CONTACT_TOL_OPTION,
    thickness: float = options.THICKNESS_MM_OPTION,
    guide: bool = options.GUIDE,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress and no table: only the summary line and errors."),
) -> None:
    """Make (or study) every mesh matching GLOB, each in its own process, locally or on Dask.

    Writes summary.csv/.jsonl (or study-NAME.csv/.svg) into the output folder; exit 1 if any
    mesh failed (error, timeout, crashed)."""
    import time

    opts = options.make_options(fail, inflate=inflate_mode, segment=segment_mode, tau=tau, parts=parts,
                                    paper=paper, size=size, margin=margin, tabs=tabs, seed=seed,
                                    time_limit=time_limit, fold=fold, contact_tol=contact_tol,
                                    marks=marks, thickness=thickness, guide=guide)
    if study is not None and study not in ("cspace", "unfold"):
        fail(f"--study must be 'cspace' or 'unfold', not {study!r}", 2)
    from ..batch import run_batch
    from ..study import run_study

    t0 = time.perf_counter()
    progress, close = _batch_progress(quiet)
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
        _batch_table(result.rows, make=study is None)
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


def _batch_progress(quiet: bool):
    """(progress callback for run_batch / run_study, close function): a rich bar on a terminal,
    else one stderr line per finished mesh; nothing when quiet."""
    if quiet:
        return None, lambda: None
    from .app import terminal_console

    console = terminal_console()
    if console is None:
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


def _batch_table(rows, make: bool) -> None:
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


@bench_app.command("paper")
@guard
def bench_paper(
    output: Path = typer.Option(Path("out/bench-paper"), "-o", "--output", help="Folder for report.md, report.json, fig3.png, fig5.png."),
    runs: int = typer.Option(20, "--runs", min=1, help="Runs (seeds) per row; the paper used 20."),
    quick: bool = typer.Option(False, "--quick", help="3 runs, 5 s limits, 200 samples: a smoke test (under 3 minutes)."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.1, help="Seconds per search (one unfold or one path)."),
    samples: int = typer.Option(1000, "--samples", min=1, help="Fig. 5 samples per net and strategy."),
    models: Optional[Path] = typer.Option(None, "--models", help="Benchmark models folder (default: $POLYFOLD_MODELS or ../shared/models)."),
) -> None:
    """Regenerate the paper's Tables 1-2 and Figs. 3 and 5 next to the paper's numbers."""
    import os

    from ..benchpaper import BenchSettings, quick_settings, run

    st = quick_settings() if quick else BenchSettings(runs=runs, time_limit=time_limit, samples=samples)
    if models is None:
        env = os.environ.get("POLYFOLD_MODELS")
        models = Path(env) if env else Path.cwd().parent / "shared" / "models"
    t0 = time.perf_counter()
    data = run(models, output, st, progress=lambda line: say(line))
    if not data["figures"]:
        say("warning: matplotlib is not installed (pip install polyfold[bench]): no figures, tables only")
    say(f"bench paper: {time.perf_counter() - t0:.0f} s -> {output / 'report.md'}")


@app.command("warm-up")
@guard
def warm_up() -> None:
    """Compile the numba kernels into numba's cache now (under a minute, once per install), so the
    first real command does not wait for them; `make setup` runs it."""
    from ..warmup import warm_up as run

    t0 = time.perf_counter()
    seconds = run(progress=say)
    parts = ", ".join(f"{k} {v:.1f} s" for k, v in seconds.items())
    say(f"warm-up: kernels compiled and cached in {time.perf_counter() - t0:.1f} s ({parts})")
