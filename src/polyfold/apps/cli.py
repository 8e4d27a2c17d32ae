"""The `polyfold` command line: a thin layer over the API.

Heavy modules (numpy, numba, trimesh) are imported inside the commands so `polyfold --help`
answers at once. Every user-facing failure is one line on stderr and a non-zero exit code:
2 for bad input, 1 when the requested result was not found (e.g. --max-pieces 1).
"""

from __future__ import annotations

import sys
import time
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from . import cli_options

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Turn 3D triangle meshes into verified paper nets (FOLD, SVG, PNG).",
)


class Planner(str, Enum):
    auto = "auto"
    linear = "linear"
    sequential = "sequential"
    lazy_prm = "lazy-prm"


class Strategy(str, Enum):
    discrete = "discrete"
    continuous = "continuous"
    continuous_full = "continuous-full"


class Method(str, Enum):
    auto = "auto"
    ga = "ga"
    steepest_edge = "steepest-edge"
    flat_tree = "flat-tree"
    unflat_tree = "unflat-tree"
    min_perimeter = "min-perimeter"
    max_perimeter = "max-perimeter"
    random = "random"


def _say(line: str) -> None:
    print(f"polyfold: {line}", file=sys.stderr, flush=True)


def _fail(message: str, code: int) -> None:
    _say(f"error: {message}")
    raise typer.Exit(code)


def _guard(func):
    """Run a command body; turn known errors into one line + exit code, never a traceback."""
    from functools import wraps

    @wraps(func)
    def wrapper(*args, **kwargs):
        from ..errors import PolyfoldError

        try:
            return func(*args, **kwargs)
        except PolyfoldError as exc:
            _fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__, exc.exit_code)
        except KeyboardInterrupt:
            _fail("interrupted", 130)
        except typer.Exit:
            raise
        except Exception as exc:  # last resort: still one line, no traceback
            _fail(f"internal error ({type(exc).__name__}): {str(exc).splitlines()[0] if str(exc) else ''}", 3)

    return wrapper


def _load(path: Path, quiet: bool = False):
    from ..formats.meshes import load_mesh

    loaded = load_mesh(path)
    if not quiet:
        for w in loaded.warnings:
            _say(f"warning: {path.name}: {w}")
    return loaded


@app.command()
@_guard
def info(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    json_out: bool = typer.Option(False, "--json", help="Print the report as JSON."),
) -> None:
    """Load and check a mesh; report its topology, hyperbolic vertices and concavity."""
    import json

    from ..mesh.repair import describe

    loaded = _load(mesh)
    report = describe(loaded)
    if json_out:
        print(json.dumps(report, indent=2))
        return
    width = max(len(k) for k in report)
    for key, value in report.items():
        if key == "warnings":
            continue
        if isinstance(value, float):
            value = f"{value:.6g}"
        print(f"{key:<{width}}  {value}")


@app.command()
@_guard
def unfold(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Net as a FOLD file (.fold)."),
    svg: Optional[Path] = typer.Option(None, "--svg", help="Also write an SVG cut sheet (mm units)."),
    png: Optional[Path] = typer.Option(None, "--png", help="Also write a PNG preview."),
    method: Method = typer.Option(Method.auto, "--method", help="Search method."),
    seed: int = typer.Option(1, "--seed", help="Random seed (results are reproducible per seed)."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the whole search."),
    max_pieces: str = typer.Option("auto", "--max-pieces", help="'auto': fall back to several pieces; '1': fail instead."),
    size: float = typer.Option(100.0, "--size", min=1e-6, help="Longest model dimension on the sheet, in mm."),
    labels: bool = typer.Option(True, "--labels/--no-labels", help="Print matching edge labels on the SVG."),
    tabs: bool = typer.Option(True, "--tabs/--no-tabs", help="Add glue tabs on the SVG."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No warnings or progress, only errors."),
    fold: bool = typer.Option(False, "--fold", help="Also plan a collision-free folding path (see `polyfold fold`)."),
    prefer_linear: bool = typer.Option(False, "--prefer-linear", help="Keep searching (within the time limit) for a net whose straight-line fold is collision-free."),
    planner: Planner = typer.Option(Planner.auto, "--planner", help="With --fold: folding planner."),
    resolution_deg: float = typer.Option(1.0, "--resolution-deg", min=1e-3, help="With --fold: collision-check step along path segments, degrees."),
    contact_tol: float = typer.Option(1e-7, "--contact-tol", min=0.0, help="Faces closer than this (fraction of the model size) touch rather than cross."),
) -> None:
    """Unfold a mesh into overlap-free nets: one piece per component when one is found in time."""
    if max_pieces not in ("auto", "1"):
        _fail(f"--max-pieces must be 'auto' or '1', not {max_pieces!r}", 2)
    from ..errors import NoNetFound, PolyfoldError
    from ..formats.fold import dumps, net_to_fold
    from ..formats.files import atomic_write
    from ..unfold.search import unfold as unfold_mesh

    t0 = time.perf_counter()
    loaded = _load(mesh, quiet)
    comps = loaded.components
    nets, stats = [], []
    show = not quiet and sys.stderr.isatty()
    for i, comp in enumerate(comps):
        remaining = max(0.0, time_limit - (time.perf_counter() - t0))
        budget = remaining / (len(comps) - i)  # share what is left among the components still to do
        label = f"component {i + 1}/{len(comps)} " if len(comps) > 1 else ""

        def progress(gen: int, best: float, _label=label) -> None:
            if show:
                print(f"\rpolyfold: {_label}generation {gen}, best overlaps {-best:.0f}   ", end="", file=sys.stderr, flush=True)

        accept = None
        if prefer_linear:
            hopeless = []

            def accept(candidate, _res=resolution_deg) -> bool:
                from ..fold.plan import is_linearly_foldable
                from ..fold.tree import collides, fold_tree

                tree = fold_tree(net_to_fold([candidate]), contact_tol)
                if hopeless or collides(tree, tree.goal):
                    hopeless.append(True)  # the shape itself intersects: no net can fold, stop looking
                    return True
                return is_linearly_foldable(tree, _res)
        try:
            net, st = unfold_mesh(comp, method=method.value, seed=seed + i, time_limit=budget,
                                  max_pieces=1 if max_pieces == "1" else None, progress=progress, accept=accept)
        except NoNetFound as exc:
            if show:
                print(file=sys.stderr)
            raise NoNetFound(f"{mesh.name}: {label}{exc}") from None
        if show:
            print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
        nets.append(net)
        stats.append(st)
    fold_dict = net_to_fold(nets, title=mesh.stem)
    path_note = ""
    if fold:
        from ..fold.plan import plan_fold
        from ..formats.fold import with_path
        from ..fold.tree import fold_tree

        remaining = max(1.0, time_limit - (time.perf_counter() - t0))
        try:
            path = plan_fold(fold_tree(fold_dict, contact_tol), planner=planner.value, resolution_deg=resolution_deg,
                             time_limit=remaining, seed=seed)
        except PolyfoldError as exc:  # e.g. the goal shape itself intersects: keep the valid flat net
            atomic_write(output, dumps(fold_dict))
            raise NoNetFound(f"{mesh.name}: {exc} (the flat net was written to {output.name})") from None
        if path is None:
            atomic_write(output, dumps(fold_dict))
            raise NoNetFound(f"{mesh.name}: no folding path found within the time limit "
                             f"(the flat net was written to {output.name})")
        fold_dict = with_path(fold_dict, path, resolution_deg, contact_tol)
        path_note = f", folding path {len(path.frames)} frames ({path.planner}, {path.seconds:.2f} s)"
    if prefer_linear:
        from ..fold.plan import is_linearly_foldable
        from ..fold.tree import fold_tree

        lc = is_linearly_foldable(fold_tree(fold_dict, contact_tol), resolution_deg)
        path_note += ", linearly foldable" if lc else ", no linearly foldable net found in time"
    atomic_write(output, dumps(fold_dict))
    if svg is not None or png is not None:
        from ..fabricate.sheet import net_sheet
        from ..formats.png import write_page_png
        from ..formats.svg import write_svg_page

        sheet = net_sheet(nets, size, labels=labels, tabs=tabs, title=mesh.name)
        if svg is not None:
            if sheet.oversize and not quiet:
                _say(f"warning: sheet is {sheet.page.width:.0f} x {sheet.page.height:.0f} mm, larger than 300 x 300 mm; lower --size")
            write_svg_page(sheet.page, svg)
        if png is not None:
            write_page_png(sheet.page, png)
    pieces = sum(s.pieces for s in stats)
    gens = sum(s.generations for s in stats)
    methods = ",".join(sorted({s.method for s in stats}))
    seconds = time.perf_counter() - t0
    note = ""
    if any(s.timed_out for s in stats):
        note = " (no single net within the time limit: fell back to several overlap-free pieces)"
    _say(f"{mesh.name}: {pieces} piece{'s' if pieces != 1 else ''}, {seconds:.2f} s, {gens} generations, "
         f"method {methods}{path_note}{note}")


@app.command("fold")
@_guard
def fold_cmd(
    net: Path = typer.Argument(..., help="Net as a FOLD file (from `polyfold unfold`)."),
    output: Path = typer.Option(..., "-o", "--output", help="FOLD file with the path added as polyfold:path."),
    planner: Planner = typer.Option(Planner.auto, "--planner", help="auto: straight line, then crease-by-crease unfolding, then Lazy PRM."),
    resolution_deg: float = typer.Option(1.0, "--resolution-deg", min=1e-3, help="Collision-check step along path segments, degrees."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the planner."),
    seed: int = typer.Option(1, "--seed", help="Random seed of the sampling planner."),
    contact_tol: float = typer.Option(1e-7, "--contact-tol", min=0.0, help="Faces closer than this (fraction of the model size) touch rather than cross."),
) -> None:
    """Plan a continuous, collision-free folding path from the flat net to the folded shape."""
    from ..errors import NoNetFound
    from ..fold.plan import plan_fold
    from ..formats.fold import with_path
    from ..formats.fold import dumps, read_fold
    from ..formats.files import atomic_write
    from ..fold.tree import fold_tree

    fold = read_fold(net)
    tree = fold_tree(fold, contact_tol)
    path = plan_fold(tree, planner=planner.value, resolution_deg=resolution_deg, time_limit=time_limit, seed=seed)
    if path is None:
        raise NoNetFound(f"{net.name}: no folding path found in {time_limit:g} s with planner {planner.value} "
                         f"({len(tree.creases)} DOF); the flat net itself is still valid")
    atomic_write(output, dumps(with_path(fold, path, resolution_deg, contact_tol)))
    _say(f"{net.name}: {len(tree.creases)} DOF, {'linearly foldable' if path.linear else 'not linearly foldable'}, "
         f"path {len(path.frames)} frames, {path.seconds:.2f} s, planner {path.planner}, "
         f"{path.edges_checked} segments / {path.configs_checked} configurations checked")


@app.command()
@_guard
def cspace(
    net: Path = typer.Argument(..., help="Net as a FOLD file."),
    samples: int = typer.Option(1000, "--samples", min=1, help="Configurations to sample."),
    strategy: Strategy = typer.Option(Strategy.discrete, "--strategy", help="discrete: each crease flat or at its goal; continuous: uniform between."),
    seed: int = typer.Option(1, "--seed"),
    contact_tol: float = typer.Option(1e-7, "--contact-tol", min=0.0, help="Faces closer than this (fraction of the model size) touch rather than cross."),
) -> None:
    """Print the valid configuration ratio |C_valid| / |C_sampled| of a net (paper Fig. 5)."""
    from ..fold.cspace import sample_ratio
    from ..formats.fold import read_fold
    from ..fold.tree import fold_tree

    tree = fold_tree(read_fold(net), contact_tol)
    valid, total = sample_ratio(tree, samples, strategy.value, seed)
    print(f"{net.name}: DOF {len(tree.creases)}, strategy {strategy.value}, valid {valid} / {total} = {valid / total:.6g}")


@app.command()
@_guard
def inflate(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Inflated mesh as OBJ (same faces, same order, input units)."),
    mode: str = typer.Option("constrained", "--mode", help="constrained (keeps convex and deep concave features) or uniform (plain balloon)."),
    pressure: float = typer.Option(0.5, "--pressure", min=0.0, help="Pressure p (UI range 0.1-1)."),
    stiffness_ratio: float = typer.Option(10.0, "--stiffness-ratio", min=0.0, help="Stiff-edge multiplier (constrained mode)."),
    vertex_stiffness: float = typer.Option(1.0, "--vertex-stiffness", min=0.0, help="Rest-spring factor (constrained mode)."),
    until_hv: int = typer.Option(0, "--until-hv", min=0, help="Stop once at most this many hyperbolic vertices remain."),
    max_steps: int = typer.Option(20000, "--max-steps", min=0, help="Stop after this many steps."),
    log: Optional[Path] = typer.Option(None, "--log", help="Write step,IF,HV,volume_change every 50 steps to this CSV."),
) -> None:
    """Inflate a mesh to remove hyperbolic (saddle) vertices while keeping its faces (paper Sec. 3)."""
    if mode not in ("constrained", "uniform"):
        _fail(f"--mode must be 'constrained' or 'uniform', not {mode!r}", 2)
    from ..inflate.inflate import inflate as inflate_mesh
    from ..formats.files import atomic_write
    from ..formats.meshes import obj_text

    t0 = time.perf_counter()
    loaded = _load(mesh)
    show = sys.stderr.isatty()

    def progress(step: int, rate: float, hv: int) -> None:
        if show:
            print(f"\rpolyfold: step {step}, IF {rate:.4f}, HV {hv}   ", end="", file=sys.stderr, flush=True)

    res = inflate_mesh(loaded.mesh, mode=mode, pressure=pressure, stiffness_ratio=stiffness_ratio,
                       vertex_stiffness=vertex_stiffness, until_hv=until_hv, max_steps=max_steps, progress=progress)
    if show:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    for note in res.notes:
        _say(f"warning: {mesh.name}: {note}")
    atomic_write(output, obj_text(res.mesh.vertices, res.mesh.faces,
                                  f"{mesh.name} inflated by polyfold ({mode}): {res.steps} steps, {res.stop_reason}"))
    if log is not None:
        rows = ["step,IF,HV,volume_change"]
        rows += [f"{int(s)},{r!r},{int(h)},{v!r}" for s, r, h, v in res.history.tolist()]
        atomic_write(log, "\n".join(rows) + "\n")
    seconds = time.perf_counter() - t0
    _say(f"{mesh.name}: {res.steps} steps, {seconds:.2f} s, stopped: {res.stop_reason}, "
         f"HV {res.hyperbolic_start} -> {res.hyperbolic}, IF {res.inflation_rate:.4f}")


@app.command()
@_guard
def segment(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Folder for part-K.obj, labels.json, segments.ply/.glb/.png."),
    tau: Optional[float] = typer.Option(None, "--tau", min=0.0, help="Concavity bound per part, fraction of the bounding-box diagonal (default 0.05)."),
    parts: Optional[int] = typer.Option(None, "--parts", min=1, help="Pick tau so that there are this many parts (instead of --tau)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the surface samples of the concavity measure."),
    png: bool = typer.Option(True, "--png/--no-png", help="Also draw segments.png."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No warnings or table, only errors."),
) -> None:
    """Split a mesh into few connected, nearly convex parts (concavity <= tau each), ready to unfold."""
    if tau is not None and parts is not None:
        _fail("give --tau or --parts, not both", 2)
    from ..formats.segmentation import write_segmentation
    from ..segment.segment import DEFAULT_TAU, segment as segment_mesh

    t0 = time.perf_counter()
    loaded = _load(mesh, quiet)
    seg = segment_mesh(loaded.mesh, tau=DEFAULT_TAU if tau is None else tau, parts=parts, seed=seed)
    seconds = time.perf_counter() - t0
    if parts is not None and seg.n_parts != parts and not quiet:
        why = ("even tau 0 gives fewer: the parts are already convex" if seg.n_parts < parts
               else "the mesh has that many separate components")
        _say(f"warning: {mesh.name}: {seg.n_parts} parts instead of {parts} ({why})")
    write_segmentation(seg, loaded.mesh, output, n_input_faces=loaded.n_input_faces, source_name=mesh.name, png=png)
    if not quiet:
        print(f"{'part':>4} {'faces':>6} {'concavity':>10}")
        for k, (p, c) in enumerate(zip(seg.parts, seg.concavity)):
            print(f"{k:>4} {p.n_faces:>6} {c:>10.4f}")
        _say(f"{mesh.name}: {seg.n_parts} parts, tau {seg.tau:.4g}, {seconds:.2f} s -> {output}")


@app.command()
@_guard
def make(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Folder for sheets, FOLD files, instructions and report."),
    inflate_mode: str = cli_options.INFLATE,
    segment_mode: str = cli_options.SEGMENT,
    tau: Optional[float] = cli_options.TAU,
    parts: Optional[int] = cli_options.PARTS,
    paper: str = cli_options.PAPER,
    size: float = cli_options.SIZE,
    margin: float = cli_options.MARGIN,
    tabs: str = cli_options.TABS,
    seed: int = typer.Option(1, "--seed", help="Random seed (same seed, same sheets)."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the searches (unfold, fold)."),
    fold: bool = cli_options.FOLD,
    contact_tol: float = cli_options.CONTACT_TOL,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No warnings or progress, only errors."),
) -> None:
    """Mesh in, printable sheets out: inflate, segment, unfold, fold, lay out with tabs and labels, export."""
    opts = cli_options.make_options(_fail, inflate=inflate_mode, segment=segment_mode, tau=tau, parts=parts,
                                    paper=paper, size=size, margin=margin, tabs=tabs, seed=seed,
                                    time_limit=time_limit, fold=fold, contact_tol=contact_tol)
    from ..pipeline.make import make as run_make

    t0 = time.perf_counter()
    if quiet:
        result = run_make(mesh, output, opts)
    else:
        from rich.console import Console

        console = Console(stderr=True)
        if console.is_terminal:
            with console.status("polyfold make") as status:
                result = run_make(mesh, output, opts,
                                  lambda stage, msg: status.update(f"[bold]{stage}[/bold]: {msg}"))
        else:
            last = [None]

            def progress(stage: str, msg: str) -> None:
                if stage != last[0]:
                    _say(f"{stage}: {msg}")
                    last[0] = stage

            result = run_make(mesh, output, opts, progress)
    rep = result.report
    if not quiet:
        for w in rep["input"]["warnings"]:
            _say(f"warning: {mesh.name}: {w}")
        for row in rep["pieces"]:
            if not row["path_verified"] and fold:
                _say(f"warning: piece {row['piece']}: no verified folding path ({row['note']})")
        lay = rep["stages"]["layout"]
        if lay["untabbed_edges"]:
            _say(f"warning: {len(lay['untabbed_edges'])} glue edge(s) without a tab (no room on either side): "
                 f"{', '.join(lay['untabbed_edges'][:10])}{' ...' if len(lay['untabbed_edges']) > 10 else ''}")
        if lay["splits_for_page"]:
            _say(f"split {lay['splits_for_page']} crease(s) so every piece fits on {paper} paper at {size:g} mm")
    seg = rep["stages"]["segment"]
    if not quiet:
        _say(f"{mesh.name}: {seg['parts']} part(s), {len(rep['pieces'])} piece(s), {rep['stages']['layout']['pages']} "
             f"page(s), {rep['checks']['paths_verified']}/{len(rep['pieces'])} folding paths verified, "
             f"{time.perf_counter() - t0:.2f} s -> {output}")


bench_app = typer.Typer(no_args_is_help=True, help="Benchmarks against the paper.")
app.add_typer(bench_app, name="bench")


@bench_app.command("paper")
@_guard
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

    from .benchpaper import BenchSettings, quick_settings, run

    st = quick_settings() if quick else BenchSettings(runs=runs, time_limit=time_limit, samples=samples)
    if models is None:
        env = os.environ.get("POLYFOLD_MODELS")
        models = Path(env) if env else Path.cwd().parent / "shared" / "models"
    t0 = time.perf_counter()
    data = run(models, output, st, progress=lambda line: _say(line))
    if not data["figures"]:
        _say("warning: matplotlib is not installed (pip install polyfold[bench]): no figures, tables only")
    _say(f"bench paper: {time.perf_counter() - t0:.0f} s -> {output / 'report.md'}")


# Commands that live in their own modules (each registers itself on `app`).
from . import cli_batch
from . import cli_view

cli_view.register(app, _guard, _say, _fail)
cli_batch.register(app, _guard, _say, _fail)


def main() -> None:
    app()


if __name__ == "__main__":
    main()
