"""make's layout and check stages: the pieces on paper, packed onto pages, checked before
anything is written.

Scale: the model's longest bounding-box side becomes `--size` mm. Parts whose pieces (with room
for their tabs) do not fit a page are split along creases first (`fit_parts`), before folding.

Where pieces go on a page (`pack_box`): inside the margins and above the footer strip; with
`--marks` the top and left margins grow to `paper.MARK_CLEAR_MM` so the registration marks'
corners (top-left, top-right, bottom-left) stay free. That gives up a strip along two sides
rather than only the three corner squares, but keeps the packing a rectangle, so fitting,
packing and the check all reason about one box.
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
from ..fabricate.paper import FOOTER_MM, GAP_MM, MARK_CLEAR_MM
from ..fabricate.pieces import GlueEdge, LayoutStats, PieceInput, SheetPiece, build_sheet_pieces, piece_input
from ..mesh.mesh import Mesh
from .folding import FoldedPiece
from .options import MakeOptions
from .parts import Part


def pack_box(width: float, height: float, opts: MakeOptions) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) mm: the part of a width x height page that pieces are packed into (see
    the module docstring); the footer strip is the FOOTER_MM below y1."""
    near = max(opts.margin, MARK_CLEAR_MM) if opts.marks else opts.margin
    return near, near, width - opts.margin, height - opts.margin - FOOTER_MM


def _packer_page(box: tuple[float, float, float, float]) -> tuple[tuple[float, float], float]:
    """The (page size, margin) that the packer and `split_to_fit`, which know one margin all
    round, are given for `box`: x0 == y0, so a (x1 + x0) x (y1 + y0) mm page with margin x0 has
    exactly `box` inside its margins."""
    x0, y0, x1, y1 = box
    return (x1 + x0, y1 + y0), x0


def fit_parts(parts: list[Part], scale: float, opts: MakeOptions, box: tuple[float, float, float, float],
              name: str) -> tuple[list[Part], int]:
    """The parts with their nets split along creases until every piece (with room for its tabs)
    fits `box` (`pack_box`); the number of pieces that added (`split_to_fit`). PolyfoldError naming
    the largest size that fits when a single face (or flat polygon) does not."""
    fitted, splits = [], 0
    for part in parts:
        try:
            net, cuts = split_to_fit(part.net, scale, *_packer_page(box))
        except PieceTooLarge as exc:
            largest = math.floor(opts.size * exc.factor * 10) / 10
            raise PolyfoldError(f"{name}: at --size {opts.size:g} mm {exc.what} alone (with its tabs) does not "
                                f"fit on {opts.paper} paper with {opts.margin:g} mm margins"
                                f"{' and registration marks' if opts.marks else ''}; the largest size that "
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
    pieces, glue, stats = build_sheet_pieces(piece_inputs(mesh, folded), scale, tabs=opts.tabs,
                                             min_label_mm=opts.min_label_mm)
    say("layout", f"packing {len(pieces)} pieces onto {opts.paper} pages")
    page, margin = _packer_page(pack_box(width, height, opts))
    packing = pack_outlines([p.footprint for p in pieces], page, margin=margin, gap=GAP_MM, seed=opts.seed,
                            time_limit=max(2.0, min(10.0, deadline.left())))
    placed = tuple(place(p, packing.placements[i]) for i, p in enumerate(pieces))
    return Sheets(placed, tuple(glue), stats, packing, width, height, time.perf_counter() - tl, scale)
