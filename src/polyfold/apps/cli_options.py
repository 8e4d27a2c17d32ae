"""Command-line options shared by `polyfold make` and `polyfold batch`: declared once, checked
once, turned into `make.MakeOptions` once. Only typer is imported here (start-up stays fast)."""

from __future__ import annotations

from typing import Callable, Optional

import typer

INFLATE = typer.Option("none", "--inflate", help="none | constrained | uniform: inflate the mesh first (paper Sec. 3).")
SEGMENT = typer.Option("auto", "--segment", help="auto (one part per component unless no single net is found) | none.")
TAU = typer.Option(None, "--tau", min=0.0, help="Segment into parts of concavity <= tau (fraction of the bbox diagonal).")
PARTS = typer.Option(None, "--parts", min=1, help="Segment into this many parts.")
PAPER = typer.Option("a4", "--paper", help="a4 | letter | a3 | 12x12in | WxHmm.")
SIZE = typer.Option(150.0, "--size", min=1e-6, help="Longest dimension of the built model, mm.")
MARGIN = typer.Option(10.0, "--margin", min=0.0, help="Page margin, mm.")
TABS = typer.Option("auto", "--tabs", help="auto (glue tabs where they fit) | none.")
FOLD = typer.Option(True, "--fold/--no-fold", help="Plan and verify a folding path for every piece.")
CONTACT_TOL = typer.Option(1e-7, "--contact-tol", min=0.0, help="Faces closer than this (fraction of the model size) touch rather than cross.")


def make_options(fail: Callable[[str, int], None], *, inflate: str, segment: str, tau: Optional[float],
                 parts: Optional[int], paper: str, size: float, margin: float, tabs: str, seed: int,
                 time_limit: float, fold: bool, contact_tol: float):
    """The `MakeOptions` of the command line; fail(message, 2) on option conflicts."""
    if tau is not None and parts is not None:
        fail("give --tau or --parts, not both", 2)
    if tabs not in ("auto", "none"):
        fail(f"--tabs must be 'auto' or 'none', not {tabs!r}", 2)
    from ..pipeline.options import MakeOptions

    return MakeOptions(inflate=inflate, segment=segment, tau=tau, parts=parts, paper=paper, size=size,
                       margin=margin, tabs=tabs == "auto", seed=seed, time_limit=time_limit, fold=fold,
                       contact_tol=contact_tol)
