"""PDF sheets: all pages in one document, each exactly its own size (reportlab): the print file,
drawn like the print SVG (preview fills, creases, cut lines, labels, the scale bar and, with
--marks, the registration marks)."""

from __future__ import annotations

import contextlib
import io as _io
import os
from collections.abc import Iterator, Sequence

import numpy as np

from ..fabricate.page import Page, TextItem
from .files import atomic_write
from .sheet_style import (HALO_MM, HALO_RGB, HALO_TEXT, LEADER_MM, MM_TO_PT, PREVIEW_RGB, STROKE_MM, STYLES, TAB_RGB,
                          TEXT_RGB, coloured, crease_layers, text_baseline)


def _pt(page: Page, pts: np.ndarray) -> np.ndarray:
    """(n, 2) page mm (y down) -> PDF points (y up, origin bottom-left)."""
    out = np.empty_like(pts, dtype=np.float64)
    out[..., 0] = pts[..., 0] * MM_TO_PT
    out[..., 1] = (page.height - pts[..., 1]) * MM_TO_PT
    return out


def _pdf_stroke(c, style: str) -> None:
    """Set stroke colour, hairline width and dash pattern (converted to points) on canvas `c`."""
    st = STYLES[style]
    c.setStrokeColorRGB(*(v / 255 for v in st["rgb"]))
    c.setLineWidth(STROKE_MM * MM_TO_PT)
    c.setDash([v * MM_TO_PT for v in st["dash"]] if st["dash"] else [], 0)


def _pdf_polygon(c, pts_pt: np.ndarray, stroke: int, fill: int) -> None:
    """One closed polygon (points already in PDF points) on reportlab canvas `c`."""
    p = c.beginPath()
    p.moveTo(*pts_pt[0])
    for x, y in pts_pt[1:]:
        p.lineTo(x, y)
    p.close()
    c.drawPath(p, stroke=stroke, fill=fill)


def _pdf_text(c, page: Page, t: TextItem, halo: bool = False) -> None:
    """One centred text item (fill colour already set); with `halo` a white outline under it."""
    bx, by = text_baseline(t)
    c.saveState()
    c.translate(bx * MM_TO_PT, (page.height - by) * MM_TO_PT)
    c.rotate(t.angle)  # PDF rotation is CCW with y up: the same visual sense as ours
    c.setFont("Helvetica", t.size * MM_TO_PT)
    if halo:  # (in its own graphics state: the stroke-only render mode must not outlive it)
        c.saveState()
        outline = c.beginText()
        outline.setTextRenderMode(1)  # stroke the glyphs only
        outline.setFont("Helvetica", t.size * MM_TO_PT)
        outline.setTextOrigin(-c.stringWidth(t.text, "Helvetica", t.size * MM_TO_PT) / 2, 0)
        c.setStrokeColorRGB(*(v / 255 for v in HALO_RGB))
        c.setLineWidth(HALO_TEXT * t.size * MM_TO_PT)
        c.setLineJoin(1)
        c.setDash([], 0)
        outline.textOut(t.text)
        c.drawText(outline)
        c.restoreState()
    c.drawCentredString(0, 0, t.text)
    c.restoreState()


def _pdf_pictures(c, page: Page) -> None:
    """The model's texture: each piece's picture (embedded as its JPEG), clipped to its faces."""
    from reportlab.lib.utils import ImageReader

    for im in page.images:
        c.saveState()
        p = c.beginPath()
        for ring in im.clip:
            pts = _pt(page, ring)
            p.moveTo(*pts[0])
            for x, y in pts[1:]:
                p.lineTo(x, y)
            p.close()
        c.clipPath(p, stroke=0, fill=0, fillMode=1)  # even-odd: holes stay out
        c.drawImage(ImageReader(_io.BytesIO(im.jpeg)), im.x * MM_TO_PT, (page.height - im.y - im.height) * MM_TO_PT,
                    im.width * MM_TO_PT, im.height * MM_TO_PT)
        c.restoreState()


def _pdf_halos(c, page: Page) -> None:
    """A white stroke under every line of a coloured page."""
    c.setStrokeColorRGB(*(v / 255 for v in HALO_RGB))
    c.setLineWidth((STROKE_MM + HALO_MM) * MM_TO_PT)
    c.setDash([], 0)
    c.setLineCap(1)
    c.setLineJoin(1)
    for _style, _cls, segs in crease_layers(page):
        for (x0, y0), (x1, y1) in _pt(page, segs):
            c.line(x0, y0, x1, y1)
    for poly in page.cut:
        _pdf_polygon(c, _pt(page, poly), stroke=1, fill=0)
    for (x0, y0), (x1, y1) in _pt(page, page.slits):
        c.line(x0, y0, x1, y1)
    c.setLineCap(0)


def _draw_furniture(c, page: Page) -> None:
    """The scale bar (solid black hairlines and its label) and the registration marks (a filled
    square, L-shaped corners `marks.line` wide with sharp corners), when the page has them."""
    black = [v / 255 for v in TEXT_RGB]
    if page.scale_bar is not None:
        c.setStrokeColorRGB(*black)
        c.setLineWidth(STROKE_MM * MM_TO_PT)
        c.setDash([], 0)
        c.setLineCap(0)
        for (x0, y0), (x1, y1) in _pt(page, page.scale_bar.segments()):
            c.line(x0, y0, x1, y1)
        c.setFillColorRGB(*black)
        _pdf_text(c, page, page.scale_bar.label)
    if page.marks is not None:
        c.setFillColorRGB(*black)
        _pdf_polygon(c, _pt(page, page.marks.square), stroke=0, fill=1)
        c.setStrokeColorRGB(*black)
        c.setLineWidth(page.marks.line * MM_TO_PT)
        c.setDash([], 0)
        c.setLineJoin(0)  # miter: a sharp corner, as the cutter's sensor expects
        c.setLineCap(0)
        for corner in page.marks.corners:
            pts = _pt(page, corner)
            p = c.beginPath()
            p.moveTo(*pts[0])
            for x, y in pts[1:]:
                p.lineTo(x, y)
            c.drawPath(p, stroke=1, fill=0)


def _draw_pdf_page(c, page: Page) -> None:
    """Draw `page` on the current page of reportlab canvas `c` (page size already set)."""
    c.setFillColorRGB(*(v / 255 for v in TAB_RGB))
    for t in page.tabs:
        _pdf_polygon(c, _pt(page, t), stroke=0, fill=1)
    c.setFillColorRGB(*(v / 255 for v in PREVIEW_RGB))
    for i, tris in enumerate(page.faces):
        for j, tri in enumerate(_pt(page, tris)):
            if page.face_colors:  # the model's colour of every face
                c.setFillColorRGB(*(int(v) / 255 for v in page.face_colors[i][j]))
            _pdf_polygon(c, tri, stroke=0, fill=1)
    _pdf_pictures(c, page)
    halo = coloured(page)
    if halo:
        _pdf_halos(c, page)

    for style, _cls, segs in crease_layers(page):
        if not len(segs):
            continue
        _pdf_stroke(c, style)
        for (x0, y0), (x1, y1) in _pt(page, segs):
            c.line(x0, y0, x1, y1)

    _pdf_stroke(c, "cut")
    c.setLineJoin(1)  # round, as in the SVG
    for poly in page.cut:
        _pdf_polygon(c, _pt(page, poly), stroke=1, fill=0)
    for (x0, y0), (x1, y1) in _pt(page, page.slits):
        c.line(x0, y0, x1, y1)

    c.setFillColorRGB(*(v / 255 for v in TEXT_RGB))
    for t in page.texts:
        _pdf_text(c, page, t, halo)
    if len(page.leaders):
        c.setStrokeColorRGB(*(v / 255 for v in TEXT_RGB))
        c.setLineWidth(LEADER_MM * MM_TO_PT)
        c.setDash([], 0)
        for (x0, y0), (x1, y1) in _pt(page, page.leaders):
            c.line(x0, y0, x1, y1)
    _draw_furniture(c, page)


@contextlib.contextmanager
def binary_streams() -> Iterator[None]:
    """reportlab writes its streams without the ASCII85 filter while this is on (restored after):
    that filter is pure Python here, a third of the time of a PDF full of pictures, and a quarter
    bigger."""
    from reportlab import rl_config

    old = rl_config.useA85
    rl_config.useA85 = 0
    try:
        yield
    finally:
        rl_config.useA85 = old


def pdf_bytes(pages: Sequence[Page], title: str = "polyfold net") -> bytes:
    """The PDF document (bytes): one PDF page per Page, each exactly its own mm size."""
    from reportlab.pdfgen.canvas import Canvas  # lazy: reportlab is slow to import

    if not pages:
        raise ValueError("write_pdf needs at least one page")
    buf = _io.BytesIO()
    # invariant: no timestamp / random file ID, so the same pages give byte-identical files.
    c = Canvas(buf, pagesize=(pages[0].width * MM_TO_PT, pages[0].height * MM_TO_PT), invariant=1)
    c.setTitle(title)
    c.setCreator("polyfold")
    with binary_streams():
        for page in pages:
            c.setPageSize((page.width * MM_TO_PT, page.height * MM_TO_PT))
            _draw_pdf_page(c, page)
            c.showPage()
        c.save()
    return buf.getvalue()


def write_pdf(pages: Sequence[Page], path: str | os.PathLike, title: str = "polyfold net") -> None:
    """Write all `pages` into one PDF at `path` (atomically); `title` goes into the metadata."""
    atomic_write(path, pdf_bytes(pages, title))
