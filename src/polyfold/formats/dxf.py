"""DXF sheets: one page per file (R2010, mm), layers CUT, MOUNTAIN, VALLEY, LABELS (ezdxf)."""

from __future__ import annotations

import io as _io
import os

import numpy as np

from ..fabricate.page import Page
from .files import atomic_write
from .sheet_style import CAP_HEIGHT, STYLES, crease_layers, text_baseline


DXF_LAYERS = {  # name: (ACI colour, linetype)
    "CUT": (7, "CONTINUOUS"),
    "MOUNTAIN": (1, "DASHDOT"),
    "VALLEY": (5, "DASHED"),
    "LABELS": (8, "CONTINUOUS"),  # not 7: machines that map colours to tools must not cut the text
}


def dxf_document(page: Page):
    """An ezdxf Drawing (R2010, mm) of one page, y flipped to DXF's y-up convention."""
    import ezdxf
    from ezdxf.enums import TextEntityAlignment

    # setup=False, then our own DASHED / DASHDOT: ezdxf's stock patterns are tiny in mm
    # (~1.3 mm dashes); these use the same mm dash lengths as the SVG and PDF.
    doc = ezdxf.new("R2010", setup=False, units=4)  # $INSUNITS 4 = mm, $MEASUREMENT 1 = metric
    for name, style in (("DASHED", "valley"), ("DASHDOT", "mountain")):
        dash = STYLES[style]["dash"]
        pattern = [sum(dash)] + [v if i % 2 == 0 else -v for i, v in enumerate(dash)]  # gaps are negative
        doc.linetypes.add(name, pattern=pattern, description=f"polyfold {style} fold")
    for name, (color, linetype) in DXF_LAYERS.items():
        doc.layers.add(name, color=color, linetype=linetype)
    doc.header["$LIMMIN"] = (0.0, 0.0)
    doc.header["$LIMMAX"] = (float(page.width), float(page.height))

    def flip(p: np.ndarray) -> list[tuple[float, float]]:
        return [(float(x), float(page.height - y)) for x, y in np.reshape(p, (-1, 2))]

    msp = doc.modelspace()
    for poly in page.cut:
        msp.add_lwpolyline(flip(poly), close=True, dxfattribs={"layer": "CUT"})
    for seg in page.slits:
        a, b = flip(seg)
        msp.add_line(a, b, dxfattribs={"layer": "CUT"})
    for style, _cls, segs in crease_layers(page):
        for seg in segs:
            a, b = flip(seg)
            msp.add_line(a, b, dxfattribs={"layer": style.upper()})
    for t in page.texts:
        bx, by = text_baseline(t)
        # DXF text height is the cap height; the y flip keeps the CCW visual sense of `angle`.
        text = msp.add_text(t.text, height=CAP_HEIGHT * t.size, rotation=t.angle, dxfattribs={"layer": "LABELS"})
        text.set_placement((bx, page.height - by), align=TextEntityAlignment.CENTER)  # centred on the baseline
    return doc


def write_dxf_page(page: Page, path: str | os.PathLike) -> None:
    """Write one page as a DXF file (R2010, mm, layers CUT / MOUNTAIN / VALLEY / LABELS) to
    `path`, atomically."""
    buf = _io.StringIO()
    dxf_document(page).write(buf)  # R2007+ DXF is UTF-8 text; atomic_write encodes it as such
    atomic_write(path, buf.getvalue())
