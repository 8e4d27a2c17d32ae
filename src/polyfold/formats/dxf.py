"""DXF sheets: one page per file (R2010, mm), layers CUT, MOUNTAIN, VALLEY, LABELS (ezdxf).

The drawing is the page at 1:1 in mm ($INSUNITS 4, $MEASUREMENT 1): limits ($LIMMIN/$LIMMAX)
and extents ($EXTMIN/$EXTMAX) are the page, and the paper-space layout is set up for the page's
paper size with no margins at 1:1, so a CAD program opens and plots the page, not its default
A3. The scale bar and registration marks of the printed pages are not drawn: a DXF is measured
in its own units, and marks would be cut.

Linetypes: DASHED (valley) and DASHDOT (mountain) have the SVG's mm dash patterns (2.5 and
5.5 mm long, starting with a 1.5 and a 3 mm dash). A crease shows a gap only if it holds a whole
pattern and the next dash (a 3 mm mountain at scale 1 is one solid dash, and AutoCAD draws a
line shorter than its pattern solid), so a crease shorter than pattern + first dash (4 mm valley,
8.5 mm mountain) gets a per-entity linetype scale (group code 48) of length / (pattern + first
dash): dash, gap(s), dash exactly. A 3 mm valley then has 1.1 mm dashes and 0.75 mm gaps, a 3 mm
mountain 1.1 mm dashes, 0.35 mm gaps and a 0.18 mm dot. Longer creases keep scale 1 ($LTSCALE 1),
like the SVG and PDF.
"""

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
    w, h = float(page.width), float(page.height)
    doc.header["$LTSCALE"] = 1.0
    msp = doc.modelspace()
    # ezdxf writes the header's limits from the layout objects (and the extents from the header
    # for model space, from the layout for paper space): set both
    msp.reset_limits((0.0, 0.0), (w, h))
    msp.reset_extents((0.0, 0.0, 0.0), (w, h, 0.0))
    doc.header["$EXTMIN"] = (0.0, 0.0, 0.0)
    doc.header["$EXTMAX"] = (w, h, 0.0)
    paper = doc.layouts.get("Layout1")
    paper.page_setup(size=(w, h), margins=(0, 0, 0, 0), units="mm", scale=(1, 1))
    paper.reset_limits((0.0, 0.0), (w, h))
    paper.reset_extents((0.0, 0.0, 0.0), (w, h, 0.0))

    def flip(p: np.ndarray) -> list[tuple[float, float]]:
        return [(float(x), float(page.height - y)) for x, y in np.reshape(p, (-1, 2))]

    for poly in page.cut:
        msp.add_lwpolyline(flip(poly), close=True, dxfattribs={"layer": "CUT"})
    for seg in page.slits:
        a, b = flip(seg)
        msp.add_line(a, b, dxfattribs={"layer": "CUT"})
    for style, _cls, segs in crease_layers(page):
        dash = STYLES[style]["dash"]
        shows_gap = sum(dash) + dash[0]  # shortest crease that shows a gap at scale 1
        for seg in segs:
            a, b = flip(seg)
            attribs = {"layer": style.upper()}
            length = float(np.hypot(*(seg[1] - seg[0])))
            if 0 < length < shows_gap:
                attribs["ltscale"] = length / shows_gap
            msp.add_line(a, b, dxfattribs=attribs)
    for seg in page.leaders:
        a, b = flip(seg)
        msp.add_line(a, b, dxfattribs={"layer": "LABELS"})
    for t in page.texts:
        bx, by = text_baseline(t)
        # DXF text height is the cap height; the y flip keeps the CCW visual sense of `angle`.
        text = msp.add_text(t.text, height=CAP_HEIGHT * t.size, rotation=t.angle, dxfattribs={"layer": "LABELS"})
        text.set_placement((bx, page.height - by), align=TextEntityAlignment.CENTER)  # centred on the baseline
    return doc


def dxf_string(page: Page) -> str:
    """One page as DXF text (R2010, mm, layers CUT / MOUNTAIN / VALLEY / LABELS): what a .dxf file
    holds (R2007+ DXF is UTF-8 text). The same page gives the same text, as the PDF the same bytes:
    ezdxf's fixed metadata (its option for comparing documents) instead of the time of writing
    and random GUIDs ($TDCREATE, $TDUPDATE, $VERSIONGUID, $FINGERPRINTGUID, its own stamp), and
    its CLASSES in one order, so a make run again with the same seed writes every file but
    report.json alike."""
    import ezdxf

    buf = _io.StringIO()
    kept = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True  # (stamps are made at ezdxf.new and at write)
    try:
        doc = dxf_document(page)
        # ezdxf adds a CLASS for each entity type in use in the order of a set of strings, which
        # Python's hash seed changes from process to process: added sorted first, they keep it
        for dxftype in sorted(doc.entitydb.dxf_types_in_use()):
            doc.classes.add_class(dxftype)
        doc.write(buf)
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = kept
    return buf.getvalue()


def write_dxf_page(page: Page, path: str | os.PathLike) -> None:
    """Write one page as a DXF file (`dxf_string`) to `path`, atomically."""
    atomic_write(path, dxf_string(page))
