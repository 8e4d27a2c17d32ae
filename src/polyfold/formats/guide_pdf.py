"""guide.pdf: the assembly guide (`guide.guide.Guide`) as pages of the make folder's paper size
(reportlab): where each piece goes (the model from six sides, pieces lettered, per part the
same), then the build steps, each with its picture, its folding pictures and what to glue."""

from __future__ import annotations

import functools
import io
from html import escape

from .pdf import binary_streams
from .sheet_style import MM_TO_PT


def _image(pic, width_pt: float):
    """A reportlab Image flowable of a guide Picture, width_pt wide: its JPEG, embedded as it is
    (DCTDecode), and named by its bytes.

    reportlab names every image it embeds (its XObject) by a digest of its reader's
    `getRGBData()`, the decoded pixels: for a JPEG, embedded undecoded, that is a decode and a
    hash of 200 KB a picture for the name alone, a third of a 1,500-face model's guide.pdf at the
    end of its make. The flowable's reader here gives the JPEG's own bytes instead, which name
    it as well (tests/formats/test_guide_pdf.py: every image embedded is its picture's JPEG)."""
    from reportlab.platypus import Image

    h, w = pic.shape
    flowable = Image(io.BytesIO(pic.jpeg), width=width_pt, height=width_pt * h / w)
    flowable._img = _jpeg_reader()(io.BytesIO(pic.jpeg))
    flowable._img._dataA = None  # (no transparency mask, as getRGBData finds for a JPEG)
    return flowable


@functools.lru_cache(maxsize=1)
def _jpeg_reader() -> type:
    """reportlab's ImageReader of a JPEG whose `getRGBData` gives the file's bytes (`_image`): a
    class made once, when reportlab is first needed here."""
    from reportlab.lib.utils import ImageReader

    class JpegReader(ImageReader):
        def getRGBData(self) -> bytes:
            return self.fp.getvalue()  # (the JPEG: reportlab reads files into memory, BytesIO)

    return JpegReader


def _grid(pics, per_row: int, width_pt: float):
    """Pictures in rows of per_row, each with its caption under it."""
    from reportlab.lib.styles import getSampleStyleSheet
    from reportlab.platypus import Paragraph, Table, TableStyle

    small = getSampleStyleSheet()["BodyText"].clone("caption", fontSize=7, leading=8.5, alignment=1)
    cell = width_pt / per_row
    rows = []
    for i in range(0, len(pics), per_row):
        chunk = list(pics[i:i + per_row])
        row = [[_image(p, cell - 4), Paragraph(escape(p.caption), small)] for p in chunk]
        rows.append(row + [""] * (per_row - len(chunk)))
    table = Table(rows, colWidths=[cell] * per_row)
    table.setStyle(TableStyle([("VALIGN", (0, 0), (-1, -1), "TOP"), ("LEFTPADDING", (0, 0), (-1, -1), 2),
                               ("RIGHTPADDING", (0, 0), (-1, -1), 2)]))
    return table


def guide_pdf_bytes(guide, title: str, page_mm: tuple[float, float], intro: list[str]) -> tuple[bytes, int]:
    """(the guide as a PDF of pages page_mm (width, height) in mm, its page count); intro:
    paragraphs before the pictures (plain text)."""
    from reportlab.lib.styles import getSampleStyleSheet
    from reportlab.platypus import (KeepTogether, ListFlowable, ListItem, PageBreak, Paragraph, SimpleDocTemplate, Spacer,
                                    Table, TableStyle)

    buf = io.BytesIO()
    w, h = page_mm[0] * MM_TO_PT, page_mm[1] * MM_TO_PT
    margin = 12 * MM_TO_PT
    # invariant: no timestamp or random file id (the same guide, the same bytes)
    doc = SimpleDocTemplate(buf, pagesize=(w, h), leftMargin=margin, rightMargin=margin, topMargin=margin,
                            bottomMargin=margin, title=title, author="polyfold", invariant=1)
    styles = getSampleStyleSheet()
    body = styles["BodyText"].clone("guide-body", fontSize=9, leading=11.5)
    width = w - 2 * margin
    story = [Paragraph(escape(title), styles["Title"])]
    story += [Paragraph(escape(p), body) for p in intro]
    story.append(Paragraph("Where each piece goes", styles["Heading2"]))
    story.append(Paragraph("Every piece in its own colour with its letter and the sheet it is printed on.", body))
    story.append(_grid(guide.overview, 3, width))
    for k, pics in enumerate(guide.parts):
        story.append(KeepTogether([Paragraph(f"Part {k + 1}", styles["Heading3"]), _grid(pics, 3, width * 0.8)]))
    story.append(PageBreak())
    story.append(Paragraph("Build steps", styles["Heading2"]))
    for st in guide.steps:
        text = [Paragraph(escape(st.title), styles["Heading3"])]
        text += [Paragraph(escape(line), body) for line in st.lines]
        if st.glue:
            text.append(ListFlowable([ListItem(Paragraph(escape(g), body), leftIndent=12) for g in st.glue],
                                     bulletType="1", leftIndent=14, bulletFontSize=8))
        text += [Paragraph(f"<b>{escape(n)}</b>", body) for n in st.notes]
        # the words beside the picture of the model after the step, the folding pictures under both
        row = Table([[text, _image(st.picture, width * 0.45 - 6)]], colWidths=[width * 0.55, width * 0.45])
        row.setStyle(TableStyle([("VALIGN", (0, 0), (-1, -1), "TOP"), ("LEFTPADDING", (0, 0), (-1, -1), 0)]))
        block = [row]
        if st.folding:
            block.append(_grid(st.folding, max(4, len(st.folding)), width))
        block.append(Spacer(1, 10))
        story.append(KeepTogether(block))
    with binary_streams():
        doc.build(story)
    return buf.getvalue(), int(doc.page)
