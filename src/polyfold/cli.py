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

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Turn 3D triangle meshes into verified paper nets (FOLD, SVG, PNG).",
)


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
        from .errors import PolyfoldError

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
    from .io import load_mesh

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

    from .io import describe

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
) -> None:
    """Unfold a mesh into overlap-free nets: one piece per component when one is found in time."""
    if max_pieces not in ("auto", "1"):
        _fail(f"--max-pieces must be 'auto' or '1', not {max_pieces!r}", 2)
    from .errors import NoNetFound
    from .foldfile import dumps, net_to_fold
    from .io import atomic_write
    from .unfold import unfold as unfold_mesh

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

        try:
            net, st = unfold_mesh(comp, method=method.value, seed=seed + i, time_limit=budget,
                                  max_pieces=1 if max_pieces == "1" else None, progress=progress)
        except NoNetFound as exc:
            if show:
                print(file=sys.stderr)
            raise NoNetFound(f"{mesh.name}: {label}{exc}") from None
        if show:
            print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
        nets.append(net)
        stats.append(st)
    fold = net_to_fold(nets, title=mesh.stem)
    atomic_write(output, dumps(fold))
    if svg is not None or png is not None:
        from .sheet import sheet_layout, write_png, write_svg

        if svg is not None:
            layout = sheet_layout(fold, size)
            if layout.oversize and not quiet:
                _say(f"warning: sheet is {layout.width:.0f} x {layout.height:.0f} mm, larger than 300 x 300 mm; lower --size")
            write_svg(fold, svg, size_mm=size, labels=labels, tabs=tabs)
        if png is not None:
            write_png(fold, png)
    pieces = sum(s.pieces for s in stats)
    gens = sum(s.generations for s in stats)
    methods = ",".join(sorted({s.method for s in stats}))
    seconds = time.perf_counter() - t0
    note = ""
    if any(s.timed_out for s in stats):
        note = " (no single net within the time limit: fell back to several overlap-free pieces)"
    _say(f"{mesh.name}: {pieces} piece{'s' if pieces != 1 else ''}, {seconds:.2f} s, {gens} generations, "
         f"method {methods}{note}")


def main() -> None:
    app()


if __name__ == "__main__":
    main()
