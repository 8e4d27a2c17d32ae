"""The model's look on its pieces: every printed face shows its texture (each printed triangle is
the image triangle under the affine map its corners' UVs give) or its colours.

In: placed `SheetPiece`s (page mm), the mesh's `Appearance` (per face of the mesh make laid out),
a `--color` mode and a dpi. Out: per page the fill colour of every face and one `PageImage` per
piece whose faces are textured or shaded, rastered at the dpi over the piece's bounding box and
clipped to its faces (tabs stay as they are: white or their light tint).

Modes (`paper.COLOR_MODES`): "texture" prints textures and colours as the file has them; "flat" fills
every face with its mean colour (vector fills, small files, a low-poly look); "none" prints the
sheets plain, as for a model without colour.

Raster (`mesh.bake.cover_triangles`, then `Appearance.sample`): pixel centres inside a face take
its colour (bilinear texture samples at the UVs interpolated there); pixels up to BLEED_PX
outside every face take a face's edge colour, so the clip path, not the pixel grid, makes the
printed edge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from ..mesh.appearance import Appearance
from ..mesh.bake import cover_triangles
from .page import PageImage
from .paper import DPI
from .pieces import SheetPiece

BLEED_PX = 1.5
MAX_PICTURE_PX = 60e6  # a larger picture (a page-sized piece at over 900 dpi) is rastered coarser: 180 MB is enough


def piece_image(piece: SheetPiece, look: Appearance, dpi: float = DPI) -> PageImage:
    """The piece's faces as a picture at `dpi` (see the module docstring; at most MAX_PICTURE_PX
    pixels): its bounding box grown by a pixel, clipped to its faces."""
    xy = np.asarray(piece.faces_xy, dtype=np.float64)
    extent = np.ptp(xy.reshape(-1, 2), axis=0)
    per_mm = min(dpi / 25.4, math.sqrt(MAX_PICTURE_PX / max(float(extent[0] * extent[1]), 1e-9)))
    lo = xy.reshape(-1, 2).min(axis=0) - 1.0 / per_mm
    hi = xy.reshape(-1, 2).max(axis=0) + 1.0 / per_mm
    w, h = (int(math.ceil(v)) for v in (hi - lo) * per_mm)
    owner = np.full((h, w), -1, dtype=np.int64)
    bary = np.zeros((h, w, 3))
    cover_triangles(np.ascontiguousarray((xy - lo) * per_mm), owner, bary, BLEED_PX)
    out = np.full((h, w, 3), 255, dtype=np.uint8)
    on = owner >= 0
    out[on] = look.sample(np.asarray(piece.face_ids, dtype=np.int64)[owner[on]], bary[on])
    rings = tuple(np.asarray(r.coords)[:-1] for g in getattr(piece.body, "geoms", [piece.body])
                  for r in (g.exterior, *g.interiors))
    return PageImage(float(lo[0]), float(lo[1]), w / per_mm, h / per_mm, out, rings)


def page_looks(pieces: Sequence[SheetPiece], look: Appearance | None, mode: str,
               dpi: float = DPI) -> tuple[tuple[np.ndarray, ...], tuple[PageImage, ...]]:
    """(fill colour (n, 3) uint8 of every face of every piece, the pictures of the pieces that
    need one) for a page's pieces in `mode`; nothing in mode "none" or without a look."""
    if look is None or mode == "none" or not pieces:
        return (), ()
    mean = look.mean_colors
    fills = tuple(mean[np.asarray(p.face_ids, dtype=np.int64)] for p in pieces)
    if mode == "flat":
        return fills, ()
    shaded = look.shaded
    images = tuple(piece_image(p, look, dpi) for p in pieces
                   if len(p.face_ids) and shaded[np.asarray(p.face_ids, dtype=np.int64)].any())
    return fills, images
