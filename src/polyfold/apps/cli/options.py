"""Command-line options shared by several verbs: declared once, checked once, turned into
`MakeOptions` once; their defaults are the API's (`MakeOptions`, `CONTACT_TOL`). Only light
modules are imported here (start-up stays fast)."""

from __future__ import annotations

import contextlib
from enum import Enum
from typing import Callable, Iterator, Optional

import typer

from ...collide.tolerance import CONTACT_TOL, THICKNESS_REL
from ...pipeline.options import MakeOptions

_D = MakeOptions()


class Planner(str, Enum):
    auto = "auto"
    linear = "linear"
    two_phase = "two-phase"
    sequential = "sequential"
    lazy_prm = "lazy-prm"


def contact_tol_option() -> typer.models.OptionInfo:
    return typer.Option(CONTACT_TOL, "--contact-tol", min=0.0,
                        help="Faces closer than this (fraction of the model size) touch rather than cross.")


INFLATE = typer.Option(_D.inflate, "--inflate", help="none | constrained | uniform: inflate the mesh first (paper Sec. 3).")
SEGMENT = typer.Option(_D.segment, "--segment", help="auto (one part per component unless no single net is found) | none.")
TAU = typer.Option(None, "--tau", min=0.0, help="Segment into parts of concavity <= tau (fraction of the bbox diagonal).")
PARTS = typer.Option(None, "--parts", min=1, help="Segment into this many parts.")
APPROXIMATE = typer.Option(_D.approximate, "--approximate",
                           help="none | hulls: build every part (--tau / --parts) as a convex polyhedron, the parts glued face to face (a low-poly model; errors in report.json).")
PAPER = typer.Option(_D.paper, "--paper", help="a4 | letter | a3 | 12x12in | WxHmm.")
SIZE = typer.Option(_D.size, "--size", min=1e-6, help="Longest dimension of the built model, mm.")
MARGIN = typer.Option(_D.margin, "--margin", min=0.0, help="Page margin, mm.")
TABS = typer.Option("auto", "--tabs", help="auto (glue tabs where they fit) | none.")
FOLD = typer.Option(_D.fold, "--fold/--no-fold", help="Plan and verify a folding path for every piece.")
MARKS = typer.Option(_D.marks, "--marks/--no-marks",
                     help="Print-and-cut registration marks (Silhouette Studio 'Type 1', 10 mm inset) on the printed "
                          "pages; pieces keep out of the marked corners.")
CONTACT_TOL_OPTION = contact_tol_option()
THICKNESS_MM_OPTION = typer.Option(_D.thickness, "--thickness", min=0.0, max=5.0,
                                   help="Paper thickness, mm: faces closer than this with overlapping projections collide (every path is re-checked at it).")
THICKNESS_REL_OPTION = typer.Option(THICKNESS_REL, "--thickness", min=0.0, max=0.1,
                                    help="Material thickness as a fraction of the model size (bounding-box diagonal): faces closer than this with overlapping projections collide.")
FACES = typer.Option(_D.faces, "--faces",
                     help="Simplify the mesh first to about N faces (quadric edge collapse); auto: meshes over 3,000 faces to faces about 12 mm across at --size (segment: 150 mm); none: never.")
COLOR = typer.Option(_D.color, "--color",
                     help="The model's look on the sheets: texture (the file's texture or colours, if it has any), "
                          "flat (one mean colour per face) or none (plain).")
DPI = typer.Option(_D.dpi, "--dpi", min=30.0, max=1200.0, help="Resolution of printed textures (dots per inch).")
GUIDE = typer.Option(_D.guide, "--guide/--no-guide",
                     help="Write the assembly guide: guide.pdf and the build steps in instructions.html.")
MIN_LABEL = typer.Option(_D.min_label_mm, "--min-label-mm", min=0.5, max=10.0,
                         help="Least cap height of every label, mm; a label that does not fit its face goes on its tab or beside its edge.")


def make_options(fail: Callable[[str, int], None], *, inflate: str, segment: str, tau: Optional[float],
                 parts: Optional[int], paper: str, size: float, margin: float, tabs: str, seed: int,
                 time_limit: float, fold: bool, contact_tol: float, marks: bool,
                 min_label_mm: float = _D.min_label_mm, thickness: float = _D.thickness,
                 faces: str = _D.faces, color: str = _D.color, dpi: float = _D.dpi,
                 guide: bool = _D.guide, approximate: str = _D.approximate) -> MakeOptions:
    """The `MakeOptions` of the command line; fail(message, 2) on option conflicts."""
    if tau is not None and parts is not None:
        fail("give --tau or --parts, not both", 2)
    if tabs not in ("auto", "none"):
        fail(f"--tabs must be 'auto' or 'none', not {tabs!r}", 2)
    return MakeOptions(inflate=inflate, segment=segment, tau=tau, parts=parts, paper=paper, size=size,
                       margin=margin, tabs=tabs == "auto", seed=seed, time_limit=time_limit, fold=fold,
                       contact_tol=contact_tol, marks=marks, min_label_mm=min_label_mm, thickness=thickness,
                       faces=faces, color=color, dpi=dpi, guide=guide, approximate=approximate)


@contextlib.contextmanager
def make_progress(say: Callable[[str], None], quiet: bool, title: str) -> Iterator[Callable[[str, str], None] | None]:
    """The progress(stage, message) of a make run: a live status line on a terminal, else one
    stderr line per stage; None when quiet."""
    if quiet:
        yield None
        return
    from .app import terminal_console

    console = terminal_console()
    if console is not None:
        with console.status(title) as status:
            yield lambda stage, msg: status.update(f"[bold]{stage}[/bold]: {msg}")
        return
    last = [None]

    def progress(stage: str, msg: str) -> None:
        if stage != last[0]:
            say(f"{stage}: {msg}")
            last[0] = stage

    yield progress
