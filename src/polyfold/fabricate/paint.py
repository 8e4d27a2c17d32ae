"""The model's look on its pieces: every printed face shows its texture (each printed triangle is
the image triangle under the affine map its corners' UVs give) or its colours.

In: placed `SheetPiece`s (page mm), the mesh's `Appearance` (per face of the mesh make laid out),
a `--color` mode and a dpi. Out: per page the fill colour of every face and one `PageImage` per
piece whose faces are textured or shaded, rastered at the dpi over the piece's bounding box and
clipped to its faces (tabs stay as they are: white or their light tint).

Modes (`paper.COLOR_MODES`): "texture" prints textures and colours as the file has them; "flat" fills
every face with its mean colour (vector fills, small files, a low-poly look); "none" prints the
sheets plain, as for a model without colour.

Raster: pixel centres inside a face take its colour (bilinear texture samples at the UVs
interpolated there); pixels up to BLEED_PX outside every face take the nearest face's edge
colour, so the clip path, not the pixel grid, makes the printed edge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

from ..mesh.appearance import Appearance, texel, texel_coords
from .page import PageImage
from .paper import DPI
from .pieces import SheetPiece

BLEED_PX = 1.5
MAX_PICTURE_PX = 60e6  # a larger picture (a page-sized piece at over 900 dpi) is rastered coarser: 180 MB is enough


@njit(cache=True)
def _paint(out, level, tri, uv, colors, image, textured, bleed):
    """Paint triangles into out (H, W, 3) uint8. tri (n, 3, 2) pixel coordinates (x right, y
    down); uv (n, 3, 2) texel coordinates in `image` (used when `textured`); colors (n, 3, 3)
    corner colours (used otherwise). level (H, W) uint8: 2 where a pixel centre lies in a face
    painted so far, 1 within `bleed` px outside, 0 unpainted; a pixel is only painted over by a
    level at least as high."""
    H, W = level.shape
    for t in range(tri.shape[0]):
        ax, ay = tri[t, 0, 0], tri[t, 0, 1]
        bx, by = tri[t, 1, 0], tri[t, 1, 1]
        cx, cy = tri[t, 2, 0], tri[t, 2, 1]
        area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if abs(area2) < 1e-12:
            continue
        la = math.hypot(cx - bx, cy - by)  # side opposite each corner
        lb = math.hypot(ax - cx, ay - cy)
        lc = math.hypot(bx - ax, by - ay)
        x0 = max(0, int(math.floor(min(ax, bx, cx) - bleed)))
        x1 = min(W - 1, int(math.ceil(max(ax, bx, cx) + bleed)))
        y0 = max(0, int(math.floor(min(ay, by, cy) - bleed)))
        y1 = min(H - 1, int(math.ceil(max(ay, by, cy) + bleed)))
        for py in range(y0, y1 + 1):
            sy = py + 0.5
            for px in range(x0, x1 + 1):
                sx = px + 0.5
                wa = ((bx - sx) * (cy - sy) - (by - sy) * (cx - sx)) / area2
                wb = ((cx - sx) * (ay - sy) - (cy - sy) * (ax - sx)) / area2
                wc = 1.0 - wa - wb
                # signed distances (px) to the sides opposite a, b, c: negative outside
                d = min(wa * abs(area2) / la, wb * abs(area2) / lb, wc * abs(area2) / lc)
                if d >= -1e-9:
                    lev = 2
                elif d >= -bleed:
                    lev = 1
                else:
                    continue
                if lev < level[py, px]:
                    continue
                if lev == 1:  # outside: the nearest point of the face (clamped and renormalised)
                    wa, wb, wc = max(wa, 0.0), max(wb, 0.0), max(wc, 0.0)
                    s = wa + wb + wc
                    wa, wb, wc = wa / s, wb / s, wc / s
                if textured:
                    tx = wa * uv[t, 0, 0] + wb * uv[t, 1, 0] + wc * uv[t, 2, 0]
                    ty = wa * uv[t, 0, 1] + wb * uv[t, 1, 1] + wc * uv[t, 2, 1]
                    rgb = texel(image, tx, ty)
                    for k in range(3):
                        out[py, px, k] = min(255, max(0, int(rgb[k] + 0.5)))
                else:
                    for k in range(3):
                        v = wa * colors[t, 0, k] + wb * colors[t, 1, k] + wc * colors[t, 2, k]
                        out[py, px, k] = min(255, max(0, int(v + 0.5)))
                level[py, px] = lev


def piece_image(piece: SheetPiece, look: Appearance, dpi: float = DPI) -> PageImage:
    """The piece's faces as a picture at `dpi` (see the module docstring; at most MAX_PICTURE_PX
    pixels): its bounding box grown by a pixel, clipped to its faces."""
    xy = np.asarray(piece.faces_xy, dtype=np.float64)
    extent = np.ptp(xy.reshape(-1, 2), axis=0)
    per_mm = min(dpi / 25.4, math.sqrt(MAX_PICTURE_PX / max(float(extent[0] * extent[1]), 1e-9)))
    lo = xy.reshape(-1, 2).min(axis=0) - 1.0 / per_mm
    hi = xy.reshape(-1, 2).max(axis=0) + 1.0 / per_mm
    w, h = (int(math.ceil(v)) for v in (hi - lo) * per_mm)
    out = np.full((h, w, 3), 255, dtype=np.uint8)
    level = np.zeros((h, w), dtype=np.uint8)
    tri = (xy - lo) * per_mm
    fids = np.asarray(piece.face_ids, dtype=np.int64)
    img = look.face_image[fids]
    blank = np.zeros((1, 1, 3), dtype=np.uint8)
    colors = look.colors[fids].astype(np.float64)
    on = np.flatnonzero(img < 0)
    if len(on):
        _paint(out, level, np.ascontiguousarray(tri[on]), np.zeros((len(on), 3, 2)), np.ascontiguousarray(colors[on]),
               blank, False, BLEED_PX)
    for k, image in enumerate(look.images):
        on = np.flatnonzero(img == k)
        if len(on):
            uv = texel_coords(look.uv[fids[on]], image.shape)
            _paint(out, level, np.ascontiguousarray(tri[on]), np.ascontiguousarray(uv), colors[on], image, True,
                   BLEED_PX)
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
