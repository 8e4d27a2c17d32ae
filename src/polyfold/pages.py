"""Cut-sheet pages (pieces already laid out) and their writers: SVG, PDF and DXF.

Page coordinates are millimetres with the origin at the page's top-left corner and y pointing
down (as in SVG). PDF and DXF have y pointing up, so their writers flip y (y' = height - y): the
drawing looks the same in every format, never mirrored.

Text placement, the same in all three writers: (x, y) is the centre of the text, `size` is the
font size (em) in mm, `angle` is the reading direction in degrees, counter-clockwise as seen on
the page. The baseline is placed explicitly (half a cap height below the centre) rather than via
SVG's dominant-baseline, which cutting-machine software ignores.

Line styles: cut = solid black; mountain = red dash-dot; valley = blue dashed; glue-tab folds
are scored like valleys. Every file is written atomically (`io.atomic_write`).
"""

from __future__ import annotations

import io as _io
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .io import atomic_write

MM_TO_PT = 72.0 / 25.4
CAP_HEIGHT = 0.718  # Helvetica's cap height per em: centres text vertically, gives the DXF text height
TEXT_KINDS = frozenset({"edge-label", "piece-label", "title"})

SVG_NS = "http://www.w3.org/2000/svg"
INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"

# One style table for all writers so SVG, PDF and DXF agree. Pure red / blue because cutting
# software (Silhouette "cut by colour", DXF ACI 1 / 5) maps exact colours to tools.
STROKE_MM = 0.25
STYLES = {
    "cut": {"rgb": (0, 0, 0), "dash": ()},
    "mountain": {"rgb": (255, 0, 0), "dash": (3.0, 1.0, 0.5, 1.0)},
    "valley": {"rgb": (0, 0, 255), "dash": (1.5, 1.0)},
}
PREVIEW_RGB = (225, 232, 245)  # light fill under the lines, for on-screen / printed previews
TAB_RGB = (236, 236, 236)  # glue tabs, lighter than the faces
TEXT_RGB = (0, 0, 0)


@dataclass(frozen=True)
class TextItem:
    """A label: `text` centred at (x, y) mm, `angle` degrees CCW as seen on the page, `size` mm
    font size, `kind` one of "edge-label", "piece-label", "title"."""

    text: str
    x: float
    y: float
    angle: float
    size: float
    kind: str

    def __post_init__(self) -> None:
        if self.kind not in TEXT_KINDS:
            raise ValueError(f"TextItem kind must be one of {sorted(TEXT_KINDS)}, got {self.kind!r}")
        if not all(math.isfinite(v) for v in (self.x, self.y, self.angle, self.size)) or self.size <= 0:
            raise ValueError(f"TextItem {self.text!r}: position/angle must be finite and size > 0")


# eq=False: numpy fields make a generated __eq__/__hash__ meaningless (ambiguous truth values).
@dataclass(frozen=True, eq=False)
class Page:
    """One sheet, `width` x `height` mm, origin top-left, y down.

    cut: closed polylines (k, 2), k >= 3, piece outlines incl. tabs, not repeating the first point
    (a repeated closing point is dropped); mountain / valley / tab_folds: (n, 2, 2) segments;
    texts: labels; faces: optional (n, 3, 2) triangles per piece, filled light in previews only;
    slits: (n, 2, 2) cut segments inside an outline (two faces of one piece that touch along a cut
    edge: the outline alone would not separate them). Arrays are coerced to float64 and validated on construction.
    """

    width: float
    height: float
    cut: tuple[np.ndarray, ...]
    mountain: np.ndarray
    valley: np.ndarray
    tab_folds: np.ndarray
    texts: tuple[TextItem, ...]
    faces: tuple[np.ndarray, ...] = ()
    slits: np.ndarray = ()  # type: ignore[assignment]
    tabs: tuple[np.ndarray, ...] = ()  # optional (4, 2) glue-tab polygons, shaded in previews only

    def __post_init__(self) -> None:
        if not (math.isfinite(self.width) and math.isfinite(self.height) and self.width > 0 and self.height > 0):
            raise ValueError(f"page size must be positive, got {self.width} x {self.height} mm")
        cut = []
        for i, poly in enumerate(self.cut):
            p = _finite(poly, f"cut[{i}]", (-1, 2))
            if len(p) > 1 and np.array_equal(p[0], p[-1]):
                p = p[:-1]  # writers close outlines themselves; a doubled vertex would be a zero-length edge
            if len(p) < 3:
                raise ValueError(f"cut[{i}] needs at least 3 distinct points, got {len(p)}")
            cut.append(p)
        object.__setattr__(self, "cut", tuple(cut))
        for name in ("mountain", "valley", "tab_folds", "slits"):
            object.__setattr__(self, name, _finite(getattr(self, name), name, (-1, 2, 2)))
        faces = tuple(_finite(f, f"faces[{i}]", (-1, 3, 2)) for i, f in enumerate(self.faces))
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "tabs", tuple(_finite(t, f"tabs[{i}]", (-1, 2)) for i, t in enumerate(self.tabs)))
        object.__setattr__(self, "texts", tuple(self.texts))


def _finite(a, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """`a` as a float64 array reshaped to `shape` (-1 first); ValueError if it does not fit or
    holds NaN / inf (which would silently corrupt every output format)."""
    arr = np.asarray(a, dtype=np.float64)
    try:
        arr = arr.reshape(shape)
    except ValueError:
        raise ValueError(f"{name}: expected shape {('n',) + shape[1:]}, got {arr.shape}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: coordinates must be finite")
    return arr


def _baseline(t: TextItem) -> tuple[float, float]:
    """Page point (mm, y down) where the centred baseline of `t` starts: half a cap height
    'below' the centre in the text's own frame, so the glyphs end up centred on (x, y)."""
    a = math.radians(t.angle)
    down = (math.sin(a), math.cos(a))  # text-frame "down" on a y-down page, for CCW angle a
    shift = 0.5 * CAP_HEIGHT * t.size
    return t.x + shift * down[0], t.y + shift * down[1]


def _crease_layers(page: Page) -> tuple[tuple[str, str, np.ndarray], ...]:
    """(layer style, class, segments) for every scored line; tab folds are scored like valleys."""
    return (
        ("mountain", "mountain", page.mountain),
        ("valley", "valley", page.valley),
        ("valley", "tab-fold", page.tab_folds),
    )


# ----------------------------------------------------------------------------------------------
# SVG


def _num(v: float) -> str:
    """Millimetre coordinate with 0.1 µm resolution and no trailing zeros (no "-0")."""
    s = f"{v:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _hex(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def _layer(parent: ET.Element, name: str, **attrs: str) -> ET.Element:
    """A top-level <g> that Inkscape, Cricut Design Space and Silhouette Studio show as a layer."""
    return ET.SubElement(parent, "g", {"id": name, "inkscape:groupmode": "layer", "inkscape:label": name, **attrs})


def svg_page_string(page: Page) -> str:
    """The SVG document (str) for one page: layers preview, labels, valley, mountain, cut
    (bottom to top, so cut lines are drawn over everything)."""
    # Namespace declarations are written as plain attributes: ET.register_namespace would change
    # serialisation globally for every other user of ElementTree in the process.
    root = ET.Element("svg", {
        "xmlns": SVG_NS,
        "xmlns:inkscape": INKSCAPE_NS,
        "version": "1.1",
        "width": f"{_num(page.width)}mm",
        "height": f"{_num(page.height)}mm",
        "viewBox": f"0 0 {_num(page.width)} {_num(page.height)}",
    })

    if page.faces or page.tabs:
        g = _layer(root, "preview", **{"class": "no-cut", "fill": _hex(PREVIEW_RGB), "stroke": "none"})
        ET.SubElement(g, "desc").text = "preview fill: print only, do not cut"
        for i, tris in enumerate(page.faces):
            d = " ".join(f"M{_num(a)},{_num(b)} L{_num(c)},{_num(e)} L{_num(f)},{_num(h)} Z"
                         for (a, b), (c, e), (f, h) in tris)
            if d:
                ET.SubElement(g, "path", {"id": f"preview-{i}", "d": d})
        for i, t in enumerate(page.tabs):
            d = f"M{_num(t[0, 0])},{_num(t[0, 1])} " + " ".join(f"L{_num(x)},{_num(y)}" for x, y in t[1:]) + " Z"
            ET.SubElement(g, "path", {"id": f"tab-{i}", "class": "tab", "fill": _hex(TAB_RGB), "d": d})

    g = _layer(root, "labels", **{
        "class": "no-cut",
        "fill": _hex(TEXT_RGB),
        "stroke": "none",
        "font-family": "Helvetica, Arial, sans-serif",
        "text-anchor": "middle",
    })
    ET.SubElement(g, "desc").text = "labels: print or draw only, do not cut"
    for t in page.texts:
        bx, by = _baseline(t)
        el = ET.SubElement(g, "text", {"class": t.kind, "x": _num(bx), "y": _num(by), "font-size": _num(t.size)})
        if t.angle:
            # SVG rotate() is clockwise on screen (y down); our angles are counter-clockwise.
            el.set("transform", f"rotate({_num(-t.angle)} {_num(bx)} {_num(by)})")
        el.text = t.text

    width = _num(STROKE_MM)
    groups: dict[str, ET.Element] = {}
    for style in ("valley", "mountain"):
        st = STYLES[style]
        groups[style] = _layer(root, style, **{
            "fill": "none", "stroke": _hex(st["rgb"]), "stroke-width": width,
            "stroke-dasharray": ",".join(_num(v) for v in st["dash"]), "stroke-linecap": "butt",
        })
    for style, cls, segs in _crease_layers(page):
        for (x0, y0), (x1, y1) in segs:
            ET.SubElement(groups[style], "path", {"class": cls, "d": f"M{_num(x0)},{_num(y0)} L{_num(x1)},{_num(y1)}"})

    g = _layer(root, "cut", **{"fill": "none", "stroke": _hex(STYLES["cut"]["rgb"]), "stroke-width": width,
                                "stroke-linejoin": "round"})
    for i, poly in enumerate(page.cut):
        d = f"M{_num(poly[0, 0])},{_num(poly[0, 1])} L" + " ".join(f"{_num(x)},{_num(y)}" for x, y in poly[1:]) + " Z"
        ET.SubElement(g, "path", {"id": f"cut-{i}", "class": "cut", "d": d})
    for i, ((x0, y0), (x1, y1)) in enumerate(page.slits):
        ET.SubElement(g, "path", {"id": f"slit-{i}", "class": "cut slit", "d": f"M{_num(x0)},{_num(y0)} L{_num(x1)},{_num(y1)}"})

    ET.indent(root, space=" ")
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def write_svg_page(page: Page, path: str | os.PathLike) -> None:
    """Write one page as an SVG file (mm units, layers "cut", "mountain", "valley", "labels",
    optional "preview") to `path`, atomically."""
    atomic_write(path, svg_page_string(page))


# ----------------------------------------------------------------------------------------------
# PDF


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


def _draw_pdf_page(c, page: Page) -> None:
    """Draw `page` on the current page of reportlab canvas `c` (page size already set)."""
    c.setFillColorRGB(*(v / 255 for v in TAB_RGB))
    for t in page.tabs:
        _pdf_polygon(c, _pt(page, t), stroke=0, fill=1)
    c.setFillColorRGB(*(v / 255 for v in PREVIEW_RGB))
    for tris in page.faces:
        for tri in _pt(page, tris):
            _pdf_polygon(c, tri, stroke=0, fill=1)

    for style, _cls, segs in _crease_layers(page):
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
        bx, by = _baseline(t)
        c.saveState()
        c.translate(bx * MM_TO_PT, (page.height - by) * MM_TO_PT)
        c.rotate(t.angle)  # PDF rotation is CCW with y up: the same visual sense as ours
        c.setFont("Helvetica", t.size * MM_TO_PT)
        c.drawCentredString(0, 0, t.text)
        c.restoreState()


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
    for page in pages:
        c.setPageSize((page.width * MM_TO_PT, page.height * MM_TO_PT))
        _draw_pdf_page(c, page)
        c.showPage()
    c.save()
    return buf.getvalue()


def write_pdf(pages: Sequence[Page], path: str | os.PathLike, title: str = "polyfold net") -> None:
    """Write all `pages` into one PDF at `path` (atomically); `title` goes into the metadata."""
    atomic_write(path, pdf_bytes(pages, title))


# ----------------------------------------------------------------------------------------------
# DXF

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
    for style, _cls, segs in _crease_layers(page):
        for seg in segs:
            a, b = flip(seg)
            msp.add_line(a, b, dxfattribs={"layer": style.upper()})
    for t in page.texts:
        bx, by = _baseline(t)
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
