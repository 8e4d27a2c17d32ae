"""One sheet for a whole net (`polyfold unfold --svg / --png`), drawn by the code `make` draws with.

In: the nets of a model's components (`unfold.Net`, one per component) and the model's size in
mm. Every piece is drawn by `pieces.build_sheet_pieces` (creases, glue tabs, labels), scaled so
the model's longest bounding-box side is `size_mm`, and placed on shelves `GAP_MM` apart inside
a `MARGIN_MM` margin; the page is as large as that needs (with a footer line). Out: a `NetSheet`
whose `page` the writers of formats/ draw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import PolyfoldError
from ..shelves import shelf_offsets
from ..unfold.net import Net, piece_net
from .labels import text_width
from .fit import model_scale
from .pack import Placement
from .paper import FOOTER_FONT_MM, FOOTER_MM, GAP_MM
from .page import Page, page_of, place
from .pieces import GlueEdge, LayoutStats, PieceInput, SheetPiece, build_sheet_pieces, piece_input

MARGIN_MM = 10.0
MAX_SHEET_MM = 300.0  # larger sheets do not fit common printers and cutting machines


@dataclass(frozen=True, eq=False)
class NetSheet:
    """The sheet of a net: the `page`, its placed pieces, the glue pairs, the layout counts and
    the scale (mm per model unit)."""

    page: Page
    pieces: tuple[SheetPiece, ...]
    glue: tuple[GlueEdge, ...]
    stats: LayoutStats
    scale: float

    @property
    def oversize(self) -> bool:
        """True when the sheet exceeds MAX_SHEET_MM x MAX_SHEET_MM (common printers and cutters)."""
        return self.page.width > MAX_SHEET_MM or self.page.height > MAX_SHEET_MM


def net_pieces(nets: Sequence[Net]) -> list[PieceInput]:
    """Every piece of every net as a PieceInput (part = the net's index). Vertex and face ids
    run on from one net to the next, so cut edges pair up only within their own component."""
    inputs = []
    v_off = f_off = 0
    for part, net in enumerate(nets):
        for k in range(net.n_pieces):
            pnet, fids = piece_net(net, k)
            inputs.append(piece_input(pnet, part, net.mesh.faces[fids] + v_off, fids + f_off))
        v_off += net.mesh.n_vertices
        f_off += net.mesh.n_faces
    return inputs


def _shelves(pieces: list[SheetPiece]) -> tuple[list[Placement], float, float]:
    """Placements of the pieces on rows about as wide as the pieces' total area is deep (unturned,
    GAP_MM apart), and the (width, height) mm the rows take."""
    bounds = np.array([p.footprint.bounds for p in pieces])  # (n, 4): xmin, ymin, xmax, ymax
    sizes = bounds[:, 2:] - bounds[:, :2]
    row = max(float(sizes[:, 0].max()), math.sqrt(float(np.prod(sizes + GAP_MM, axis=1).sum())))
    offsets = shelf_offsets(sizes.tolist(), row, math.inf, GAP_MM)
    placements = [Placement(0, 0.0, (MARGIN_MM + x - lo[0], MARGIN_MM + y - lo[1]))
                  for (_, x, y), lo in zip(offsets, bounds[:, :2])]
    far = np.array([(x, y) for _, x, y in offsets]) + sizes
    return placements, float(far[:, 0].max()), float(far[:, 1].max())


def net_sheet(nets: Sequence[Net], size_mm: float, *, labels: bool = True, tabs: bool = True,
              title: str | None = None) -> NetSheet:
    """The sheet of `nets` (one per component) with the model's longest side `size_mm` mm: glue
    tabs unless `tabs` is False, glue labels and piece names unless `labels` is False, and a
    footer naming `title`, the piece count and the size. Raises PolyfoldError for a size that is
    not a positive number or a model of zero size."""
    if not (size_mm > 0 and math.isfinite(size_mm)):
        raise PolyfoldError(f"sheet size must be a positive number of mm, got {size_mm}")
    scale = model_scale([net.mesh for net in nets], size_mm)
    pieces, glue, stats = build_sheet_pieces(net_pieces(nets), scale, tabs=tabs)
    if not labels:
        pieces = [replace(p, texts=()) for p in pieces]
    placements, used_w, used_h = _shelves(pieces)
    placed = [place(p, pl) for p, pl in zip(pieces, placements)]
    n = len(placed)
    footer = f"{title + ' - ' if title else ''}{n} piece{'s' if n != 1 else ''} - {size_mm:g} mm - polyfold"
    width = max(used_w, text_width(footer, FOOTER_FONT_MM)) + 2 * MARGIN_MM
    height = used_h + FOOTER_MM + 2 * MARGIN_MM
    page = page_of(placed, width, height, footer, height - MARGIN_MM - FOOTER_MM / 2)
    return NetSheet(page, tuple(placed), tuple(glue), stats, scale)
