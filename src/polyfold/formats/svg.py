"""SVG sheets, one page per file, mm units, Inkscape layers: the print file and the cut file.

`svg_page_string` is the print file (sheet-NN.svg): every layer (preview, labels, scale,
registration, valley, mountain, cut). `cut_svg_string` is the cut file (cut-NN.svg) for cutting
machines: only the layers valley, mountain and cut, drawn by the same code with the same
coordinates, as plain strokes: no fills, no text, no hidden or print-only layers, one closed path
per outline, one open path per slit and per score line.

Score lines in the cut file are solid strokes in their layer's colour (mountain red #ff0000,
valley and tab folds blue #0000ff, cuts black), not dashed. Silhouette Studio ("cut by line
colour" in its Send panel) and Cricut Design Space (an operation per layer, e.g. Score or
Perforate) assign a tool to each colour or layer and run it along the path's geometry: a solid
line gives one score stroke (scoring tool, low-force blade pass or the machine's perforation
setting, as the user chooses), whereas a dashed path, once the dashes are turned into geometry
(stroke to path, DXF/HPGL conversions), becomes dozens of tiny separate cuts that perforate or
tear the paper. The print file keeps the dashes: on paper they tell mountain from valley.
Registration marks are not in the cut file: print-and-cut software (Silhouette Studio) draws its
own at the positions set in its Registration Marks panel; in a cut file they would be cut.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np

from ..fabricate.page import Page, TextItem
from .files import atomic_write
from .sheet_style import (HALO_MM, HALO_RGB, HALO_TEXT, LEADER_MM, PREVIEW_RGB, STROKE_MM, STYLES, TAB_RGB, TEXT_RGB,
                          coloured, crease_layers, text_baseline)


SVG_NS = "http://www.w3.org/2000/svg"


INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"


def _num(v: float) -> str:
    """Millimetre coordinate with 0.1 µm resolution and no trailing zeros (no "-0")."""
    s = f"{v:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _hex(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def _layer(parent: ET.Element, name: str, **attrs: str) -> ET.Element:
    """A top-level <g> that Inkscape, Cricut Design Space and Silhouette Studio show as a layer."""
    return ET.SubElement(parent, "g", {"id": name, "inkscape:groupmode": "layer", "inkscape:label": name, **attrs})


def _polyline_d(points: np.ndarray, closed: bool) -> str:
    """Path data of a polyline (page mm), closed with Z when `closed`. Every point has its own
    command letter (no implicit lineto): the plainest form for cutting software's importers."""
    d = f"M{_num(points[0, 0])},{_num(points[0, 1])} " + " ".join(f"L{_num(x)},{_num(y)}" for x, y in points[1:])
    return d + " Z" if closed else d


def _text(parent: ET.Element, t: TextItem) -> ET.Element:
    """One centred text element (font attributes come from the parent layer)."""
    bx, by = text_baseline(t)
    el = ET.SubElement(parent, "text", {"class": t.kind, "x": _num(bx), "y": _num(by), "font-size": _num(t.size)})
    if t.angle:
        # SVG rotate() is clockwise on screen (y down); our angles are counter-clockwise.
        el.set("transform", f"rotate({_num(-t.angle)} {_num(bx)} {_num(by)})")
    el.text = t.text
    return el


def _svg_root(page: Page) -> ET.Element:
    # Namespace declarations are written as plain attributes: ET.register_namespace would change
    # serialisation globally for every other user of ElementTree in the process.
    return ET.Element("svg", {
        "xmlns": SVG_NS,
        "xmlns:inkscape": INKSCAPE_NS,
        "version": "1.1",
        "width": f"{_num(page.width)}mm",
        "height": f"{_num(page.height)}mm",
        "viewBox": f"0 0 {_num(page.width)} {_num(page.height)}",
    })


def _halo_layer(root: ET.Element, page: Page) -> None:
    """A white stroke under every line of the page (print file of a coloured page only)."""
    g = _layer(root, "halo", **{"class": "no-cut", "fill": "none", "stroke": _hex(HALO_RGB),
                                "stroke-width": _num(STROKE_MM + HALO_MM), "stroke-linejoin": "round",
                                "stroke-linecap": "round", "stroke-opacity": "0.85"})
    ET.SubElement(g, "desc").text = "white halo under the lines on a coloured page: print only, do not cut"
    d = [_polyline_d(seg, closed=False) for _, _, segs in crease_layers(page) for seg in segs]
    d += [_polyline_d(poly, closed=True) for poly in page.cut] + [_polyline_d(seg, closed=False) for seg in page.slits]
    if d:
        ET.SubElement(g, "path", {"d": " ".join(d)})


def _picture_layer(root: ET.Element, page: Page) -> None:
    """The model's texture: one embedded JPEG per piece, clipped to the piece's faces."""
    import base64

    root.set("xmlns:xlink", "http://www.w3.org/1999/xlink")
    defs = ET.SubElement(root, "defs")
    g = _layer(root, "texture", **{"class": "no-cut"})
    ET.SubElement(g, "desc").text = "the model's texture on the pieces: print only, do not cut"
    for i, im in enumerate(page.images):
        clip = ET.SubElement(defs, "clipPath", {"id": f"clip-{i}", "clipPathUnits": "userSpaceOnUse"})
        ET.SubElement(clip, "path", {"clip-rule": "evenodd",
                                     "d": " ".join(_polyline_d(r, closed=True) for r in im.clip)})
        ET.SubElement(g, "image", {"id": f"picture-{i}", "x": _num(im.x), "y": _num(im.y), "width": _num(im.width),
                                   "height": _num(im.height), "preserveAspectRatio": "none",
                                   "clip-path": f"url(#clip-{i})",
                                   # xlink:href (SVG 1.1): what cutting software's importers read
                                   "xlink:href": "data:image/jpeg;base64," + base64.b64encode(im.jpeg).decode("ascii")})


def _line_layers(root: ET.Element, page: Page, dashed: bool) -> None:
    """The layers valley, mountain (one path per score line) and cut (one closed path per
    outline, one path per slit), on top of what `root` holds; dashed creases or solid ones."""
    width = _num(STROKE_MM)
    groups: dict[str, ET.Element] = {}
    for style in ("valley", "mountain"):
        st = STYLES[style]
        attrs = {"fill": "none", "stroke": _hex(st["rgb"]), "stroke-width": width, "stroke-linecap": "butt"}
        if dashed:
            attrs["stroke-dasharray"] = ",".join(_num(v) for v in st["dash"])
        groups[style] = _layer(root, style, **attrs)
    for style, cls, segs in crease_layers(page):
        for seg in segs:
            ET.SubElement(groups[style], "path", {"class": cls, "d": _polyline_d(seg, closed=False)})

    g = _layer(root, "cut", **{"fill": "none", "stroke": _hex(STYLES["cut"]["rgb"]), "stroke-width": width,
                                "stroke-linejoin": "round"})
    for i, poly in enumerate(page.cut):
        ET.SubElement(g, "path", {"id": f"cut-{i}", "class": "cut", "d": _polyline_d(poly, closed=True)})
    for i, seg in enumerate(page.slits):
        ET.SubElement(g, "path", {"id": f"slit-{i}", "class": "cut slit", "d": _polyline_d(seg, closed=False)})


def _document(root: ET.Element) -> str:
    ET.indent(root, space=" ")
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def svg_page_string(page: Page) -> str:
    """The print SVG (str) of one page: layers preview, labels, scale, registration (with marks),
    valley, mountain, cut (bottom to top, so cut lines are drawn over everything)."""
    root = _svg_root(page)
    if page.faces or page.tabs:
        g = _layer(root, "preview", **{"class": "no-cut", "fill": _hex(PREVIEW_RGB), "stroke": "none"})
        ET.SubElement(g, "desc").text = "preview fill: print only, do not cut"
        for i, tris in enumerate(page.faces):
            if page.face_colors:  # the model's colour of every face
                for j, (tri, rgb) in enumerate(zip(tris, page.face_colors[i])):
                    ET.SubElement(g, "path", {"id": f"preview-{i}-{j}", "fill": _hex(tuple(int(v) for v in rgb)),
                                              "d": _polyline_d(tri, closed=True)})
                continue
            d = " ".join(_polyline_d(tri, closed=True) for tri in tris)
            if d:
                ET.SubElement(g, "path", {"id": f"preview-{i}", "d": d})
        for i, t in enumerate(page.tabs):
            ET.SubElement(g, "path", {"id": f"tab-{i}", "class": "tab", "fill": _hex(TAB_RGB),
                                      "d": _polyline_d(t, closed=True)})

    if page.images:
        _picture_layer(root, page)
    halo = coloured(page)
    if halo:
        _halo_layer(root, page)

    text_font = {"font-family": "Helvetica, Arial, sans-serif", "text-anchor": "middle"}
    g = _layer(root, "labels", **{"class": "no-cut", "fill": _hex(TEXT_RGB), "stroke": "none", **text_font})
    ET.SubElement(g, "desc").text = "labels: print or draw only, do not cut"
    for t in page.texts:
        el = _text(g, t)
        if halo:  # a white outline under the glyphs (paint-order: stroke first)
            el.attrib.update({"stroke": _hex(HALO_RGB), "stroke-width": _num(HALO_TEXT * t.size),
                              "stroke-linejoin": "round", "paint-order": "stroke"})
    for seg in page.leaders:  # thin lines from an edge to its label beside the piece
        ET.SubElement(g, "path", {"class": "leader", "fill": "none", "stroke": _hex(TEXT_RGB),
                                  "stroke-width": _num(LEADER_MM), "d": _polyline_d(seg, closed=False)})

    if page.scale_bar is not None:
        bar = page.scale_bar
        g = _layer(root, "scale", **{"class": "no-cut", "fill": "none", "stroke": _hex(TEXT_RGB),
                                     "stroke-width": _num(STROKE_MM), "stroke-linecap": "butt"})
        ET.SubElement(g, "desc").text = f"scale bar: {bar.length:g} mm when printed at 100 %; print only, do not cut"
        for seg in bar.segments():
            ET.SubElement(g, "path", {"class": "scale-bar", "d": _polyline_d(seg, closed=False)})
        label = ET.SubElement(g, "g", {"fill": _hex(TEXT_RGB), "stroke": "none", **text_font})
        _text(label, bar.label)

    if page.marks is not None:
        m = page.marks
        g = _layer(root, "registration", **{"class": "no-cut", "fill": "none", "stroke": "none"})
        ET.SubElement(g, "desc").text = "print-and-cut registration marks (Silhouette Type 1): print only, do not cut"
        ET.SubElement(g, "path", {"class": "mark-square", "fill": _hex(TEXT_RGB),
                                  "d": _polyline_d(m.square, closed=True)})
        for corner in m.corners:
            ET.SubElement(g, "path", {"class": "mark-corner", "stroke": _hex(TEXT_RGB), "stroke-width": _num(m.line),
                                      "stroke-linejoin": "miter", "stroke-linecap": "butt",
                                      "d": _polyline_d(corner, closed=False)})

    _line_layers(root, page, dashed=True)
    return _document(root)


def cut_svg_string(page: Page) -> str:
    """The cut SVG (str) of one page: layers valley, mountain, cut as plain solid strokes, the
    same coordinates as `svg_page_string` (see the module docstring)."""
    root = _svg_root(page)
    _line_layers(root, page, dashed=False)
    return _document(root)


def write_svg_page(page: Page, path: str | os.PathLike) -> None:
    """Write one page as a print SVG file (mm units, layers "cut", "mountain", "valley",
    "labels", optional "preview", "scale", "registration") to `path`, atomically."""
    atomic_write(path, svg_page_string(page))


def write_cut_svg(page: Page, path: str | os.PathLike) -> None:
    """Write one page as a cut SVG file (layers "cut", "mountain", "valley"; see the module
    docstring) to `path`, atomically."""
    atomic_write(path, cut_svg_string(page))
