"""The verbs on nets: unfold (a mesh into nets), fold (a path for a net), cspace (its valid
configuration ratio)."""

from __future__ import annotations

import sys
import time
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from .app import app, fail, guard, load, say
from . import options
from .options import Planner, contact_tol_option


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


@app.command()
@guard
def unfold(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Net as a FOLD file (.fold)."),
    svg: Optional[Path] = typer.Option(None, "--svg", help="Also write an SVG cut sheet (mm units)."),
    png: Optional[Path] = typer.Option(None, "--png", help="Also write a PNG preview."),
    method: Method = typer.Option(Method.auto, "--method", help="Search method."),
    seed: int = typer.Option(1, "--seed", min=0, help="Random seed (results are reproducible per seed)."),
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
    contact_tol: float = contact_tol_option(),
    thickness: float = options.THICKNESS_REL_OPTION,
    faces: str = options.FACES,
) -> None:
    """Unfold a mesh into overlap-free nets: one piece per component when one is found in time."""
    if max_pieces not in ("auto", "1"):
        fail(f"--max-pieces must be 'auto' or '1', not {max_pieces!r}", 2)
    from ...deadline import Deadline
    from ...errors import NoNetFound
    from ...formats.files import check_outputs
    from ...formats.fold import write_fold
    from ...mesh.simplify import check_faces_spec
    from ...pipeline.nets import NetsOptions, unfold_nets

    check_outputs([output, svg, png], [mesh])
    check_faces_spec(faces)
    t0 = time.perf_counter()
    deadline = Deadline.after(time_limit)
    loaded = load(mesh, quiet, faces, size)
    opts = NetsOptions(method=method.value, seed=seed, max_pieces=1 if max_pieces == "1" else None, fold=fold,
                       prefer_linear=prefer_linear, planner=planner.value, resolution_deg=resolution_deg,
                       contact_tol=contact_tol, thickness=thickness)
    show = not quiet and sys.stderr.isatty()
    n = len(loaded.components)

    def progress(component: int, gen: int, best: float) -> None:
        if show:
            label = f"component {component + 1}/{n} " if n > 1 else ""
            print(f"\rpolyfold: {label}generation {gen}, best overlaps {-best:.0f}   ", end="", file=sys.stderr, flush=True)

    try:
        result = unfold_nets(loaded, mesh.stem, opts, deadline, progress)
    except NoNetFound as exc:
        raise NoNetFound(f"{mesh.name}: {exc}") from None
    finally:
        if show:
            print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    write_fold(output, result.fold)
    if result.path_error is not None:
        raise NoNetFound(f"{mesh.name}: {result.path_error} (the flat net was written to {output.name})")
    if svg is not None or png is not None:
        _write_sheet(result, mesh.name, svg, png, size, labels, tabs, quiet)
    _say_unfolded(mesh.name, result, time.perf_counter() - t0)


def _write_sheet(result, title: str, svg: Optional[Path], png: Optional[Path], size: float, labels: bool,
                 tabs: bool, quiet: bool) -> None:
    """The --svg cut sheet and the --png preview of the nets: one page, as make draws its sheets."""
    from ...fabricate.sheet import net_sheet
    from ...formats.png import write_page_png
    from ...formats.svg import write_svg_page

    sheet = net_sheet(result.nets, size, labels=labels, tabs=tabs, title=title)
    if svg is not None:
        if sheet.oversize and not quiet:
            say(f"warning: sheet is {sheet.page.width:.0f} x {sheet.page.height:.0f} mm, larger than 300 x 300 mm; "
                "lower --size")
        write_svg_page(sheet.page, svg)
    if png is not None:
        write_page_png(sheet.page, png)


def _say_unfolded(name: str, result, seconds: float) -> None:
    """The summary line of `unfold`."""
    stats = result.stats
    pieces = sum(s.pieces for s in stats)
    gens = sum(s.generations for s in stats)
    methods = ",".join(sorted({s.method for s in stats}))
    path = result.path
    note = "" if path is None else f", folding path {len(path.frames)} frames ({path.planner}, {path.seconds:.2f} s)"
    if result.linear is not None:
        note += ", linearly foldable" if result.linear else ", no linearly foldable net found in time"
    reasons = sorted({s.no_single_net for s in stats if s.no_single_net})
    if reasons:
        note += f" ({'; '.join(reasons)}; cut into the fewest overlap-free pieces found)"
    elif any(s.timed_out for s in stats):
        note += " (no single net within the time limit: fell back to several overlap-free pieces)"
    say(f"{name}: {pieces} piece{'s' if pieces != 1 else ''}, {seconds:.2f} s, {gens} generations, "
        f"method {methods}{note}")


@app.command("fold")
@guard
def fold_cmd(
    net: Path = typer.Argument(..., help="Net as a FOLD file (from `polyfold unfold`)."),
    output: Path = typer.Option(..., "-o", "--output", help="FOLD file with the path added as polyfold:path."),
    planner: Planner = typer.Option(Planner.auto, "--planner", help="auto: straight line, then two-phase (one crease out of step), then crease-by-crease unfolding, then Lazy PRM."),
    resolution_deg: float = typer.Option(1.0, "--resolution-deg", min=1e-3, help="Collision-check step along path segments, degrees."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="Seconds for the planner."),
    seed: int = typer.Option(1, "--seed", min=0, help="Random seed of the sampling planner."),
    contact_tol: float = contact_tol_option(),
    thickness: float = options.THICKNESS_REL_OPTION,
) -> None:
    """Plan a continuous, collision-free folding path from the flat net to the folded shape, at the
    material's thickness, and check it again with an independent checker before writing it."""
    from ...errors import NoNetFound
    from ...formats.files import check_outputs
    from ...formats.fold import read_net, write_fold
    from ...pipeline.folding import plan_checked

    check_outputs([output], [net])
    fold, tree = read_net(net, contact_tol)
    written, path, why = plan_checked(fold, tree, planner=planner.value, resolution_deg=resolution_deg,
                                      time_limit=time_limit, seed=seed, contact_tol=contact_tol,
                                      thickness_rel=thickness)
    if path is None:
        raise NoNetFound(f"{net.name}: {why} ({len(tree.creases)} DOF, thickness {thickness:g} of the model size); "
                         "the flat net itself is still valid")
    write_fold(output, written)
    say(f"{net.name}: {len(tree.creases)} DOF, {'linearly foldable' if path.linear else 'not linearly foldable'}, "
         f"path {len(path.frames)} frames, {path.seconds:.2f} s, planner {path.planner}, "
         f"{path.edges_checked} segments / {path.configs_checked} configurations checked, "
         f"verified by the independent check at thickness {thickness:g} of the model size")


@app.command()
@guard
def cspace(
    net: Path = typer.Argument(..., help="Net as a FOLD file."),
    samples: int = typer.Option(1000, "--samples", min=1, help="Configurations to sample."),
    strategy: Strategy = typer.Option(Strategy.discrete, "--strategy", help="discrete: each crease flat or at its goal; continuous: uniform between."),
    seed: int = typer.Option(1, "--seed", min=0),
    contact_tol: float = contact_tol_option(),
) -> None:
    """Print the valid configuration ratio |C_valid| / |C_sampled| of a net (paper Fig. 5)."""
    from ...fold.cspace import sample_ratio
    from ...formats.fold import read_net

    _, tree = read_net(net, contact_tol)
    valid, total = sample_ratio(tree, samples, strategy.value, seed)
    print(f"{net.name}: DOF {len(tree.creases)}, strategy {strategy.value}, valid {valid} / {total} = {valid / total:.6g}")
