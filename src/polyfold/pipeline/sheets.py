"""make's layout and check stages: the pieces on paper, packed onto pages, checked before
anything is written.

Scale: the model's longest bounding-box side becomes `--size` mm. Parts whose pieces (with room
for their tabs) do not fit a page are split along creases first (`fit_parts`), before folding.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

from ..deadline import Deadline
from ..errors import PolyfoldError
from ..fabricate.fit import PieceTooLarge, split_to_fit
from ..fabricate.pack import Packing, pack_outlines
from ..fabricate.page import place
from ..fabricate.paper import FOOTER_MM, GAP_MM
from ..fabricate.pieces import GlueEdge, LayoutStats, PieceInput, SheetPiece, build_sheet_pieces, piece_input
from ..mesh.mesh import Mesh
from .folding import FoldedPiece
from .options import MakeOptions
from .parts import Part


def printable(width: float, height: float) -> tuple[float, float]:
    """The page area pieces are packed into (the footer strip excluded), mm."""
    return width, height - FOOTER_MM


def fit_parts(parts: list[Part], scale: float, opts: MakeOptions, page: tuple[float, float],
              name: str) -> tuple[list[Part], int]:
    """The parts with their nets split along creases until every piece (with room for its tabs)
    fits the page; the number of creases cut. PolyfoldError naming the largest size that fits when
    a single face does not."""
    fitted, splits = [], 0
    for part in parts:
        try:
            net, cuts = split_to_fit(part.net, scale, page, opts.margin)
        except PieceTooLarge as exc:
            largest = math.floor(opts.size * exc.factor * 10) / 10
            raise PolyfoldError(f"{name}: at --size {opts.size:g} mm face {exc.face} alone (with its tabs) does not "
                                f"fit on {opts.paper} paper with {opts.margin:g} mm margins; the largest size that "
                                f"fits is {largest:g} mm (or use larger --paper)") from None
        splits += cuts
        fitted.append(Part(part.faces, net))
    return fitted, splits


@dataclass(frozen=True, eq=False)
class Sheets:
    """The pieces in mm, placed on their pages (pieces[i] is folded[i]), the glue pairs, the
    layout facts, the packing (page of each piece), the page size and the scale (mm per model
    unit)."""

    pieces: tuple[SheetPiece, ...]
    glue: tuple[GlueEdge, ...]
    stats: LayoutStats
    packing: Packing
    width: float
    height: float
    seconds: float
    scale: float

    def page_of_piece(self) -> list[int]:
        """0-based page of every piece."""
        return [pl.page for pl in self.packing.placements]


def piece_inputs(mesh: Mesh, folded: list[FoldedPiece]) -> list[PieceInput]:
    """What fabricate needs of every piece: its net, part, and its vertices and faces in the mesh."""
    return [piece_input(fp.net, fp.part, mesh.faces[fp.mesh_faces], fp.mesh_faces) for fp in folded]


def lay_out(mesh: Mesh, folded: list[FoldedPiece], scale: float, opts: MakeOptions, width: float, height: float,
            deadline: Deadline, say: Callable[[str, str], None]) -> Sheets:
    """Tabs and labels for every piece, then the pieces packed onto as few pages as possible."""
    tl = time.perf_counter()
    say("layout", f"tabs and labels for {len(folded)} pieces")
    pieces, glue, stats = build_sheet_pieces(piece_inputs(mesh, folded), scale, tabs=opts.tabs)
    say("layout", f"packing {len(pieces)} pieces onto {opts.paper} pages")
    packing = pack_outlines([p.outline for p in pieces], printable(width, height), margin=opts.margin,
                            gap=GAP_MM, seed=opts.seed, time_limit=max(2.0, min(10.0, deadline.left())))
    placed = tuple(place(p, packing.placements[i]) for i, p in enumerate(pieces))
    return Sheets(placed, tuple(glue), stats, packing, width, height, time.perf_counter() - tl, scale)
