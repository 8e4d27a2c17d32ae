"""PNG files: the encoder, sheet previews drawn from a `fabricate.page.Page`, and mesh pictures.

The sheet preview is drawn like the other sheet writers draw a Page (same colours as
`sheet_style`): faces filled one light colour per piece, glue tabs light grey, cut lines black,
mountains red, valleys and tab folds blue, the scale bar and registration marks black. Labels
are not drawn (no font rasteriser here).
"""

from __future__ import annotations

import math
import os
import struct
import zlib

import numpy as np

from ..fabricate.page import Page
from .files import atomic_write
from .raster import draw_segments, fill_triangles, part_colors, render_mesh
from .sheet_style import STYLES, TAB_RGB, TEXT_RGB, crease_layers

PIECE_SATURATION = 0.28  # light piece fills (part_colors' hues), so the lines stay readable
PIECE_VALUE = 0.98


def png_bytes(img: np.ndarray) -> bytes:
    """(H, W, 3) uint8 RGB image -> PNG file bytes (8-bit truecolour, no filtering)."""
    h, w = img.shape[:2]
    raw = np.zeros((h, 1 + 3 * w), dtype=np.uint8)  # filter byte 0 per row
    raw[:, 1:] = np.ascontiguousarray(img, dtype=np.uint8).reshape(h, 3 * w)

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
            + chunk(b"IEND", b""))


def piece_colors(n: int) -> np.ndarray:
    """(n, 3) uint8 light fill colour of each piece of a sheet preview, in page.faces order."""
    return part_colors(n, saturation=PIECE_SATURATION, value=PIECE_VALUE)


def page_image(page: Page, width_px: int = 1200) -> np.ndarray:
    """The page drawn as an (H, width_px, 3) uint8 image, H from the page's aspect ratio; pixel
    (i, j) covers [j, j + 1) x [i, i + 1) in page mm times width_px / page.width."""
    if int(width_px) < 16:
        raise ValueError(f"PNG width must be at least 16 px, got {width_px}")
    s = int(width_px) / page.width
    img = np.full((max(1, math.ceil(page.height * s)), int(width_px), 3), 255, dtype=np.uint8)
    if page.tabs:  # trapezoids or clipped (non-convex) tabs: constrained triangulations
        import shapely

        parts = shapely.constrained_delaunay_triangles(np.array([shapely.Polygon(t) for t in page.tabs]))
        tris = np.array([np.asarray(tri.exterior.coords)[:3] for g in parts for tri in g.geoms]) * s
        fill_triangles(img, tris.reshape(-1, 3, 2), np.tile(np.array(TAB_RGB, dtype=np.uint8), (len(tris), 1)))
    if page.faces:
        colors = piece_colors(len(page.faces))
        piece = np.repeat(np.arange(len(page.faces)), [len(f) for f in page.faces])
        fill_triangles(img, np.concatenate(page.faces) * s, colors[piece])
    for style, _cls, segs in crease_layers(page):
        draw_segments(img, segs * s, STYLES[style]["rgb"])
    rings = [np.stack([r, np.roll(r, -1, axis=0)], axis=1) for r in page.cut]
    cuts = np.concatenate([*rings, page.slits]) if rings else page.slits
    draw_segments(img, cuts * s, STYLES["cut"]["rgb"], thick=2)
    if page.scale_bar is not None:
        draw_segments(img, page.scale_bar.segments() * s, TEXT_RGB)
    draw_segments(img, page.leaders * s, TEXT_RGB)
    if page.marks is not None:
        sq = page.marks.square * s
        fill_triangles(img, np.array([sq[[0, 1, 2]], sq[[0, 2, 3]]]), np.array([TEXT_RGB, TEXT_RGB], dtype=np.uint8))
        legs = np.concatenate([np.stack([c[:-1], c[1:]], axis=1) for c in page.marks.corners])
        draw_segments(img, legs * s, TEXT_RGB, thick=2)
    return img


def write_page_png(page: Page, path: str | os.PathLike, width_px: int = 1200) -> None:
    """`page_image` written atomically as a PNG file."""
    atomic_write(path, png_bytes(page_image(page, width_px)))


def write_mesh_png(path, vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray, **kw) -> None:
    """`raster.render_mesh` written atomically as a PNG file."""
    atomic_write(path, png_bytes(render_mesh(vertices, faces, face_colors, **kw)))
