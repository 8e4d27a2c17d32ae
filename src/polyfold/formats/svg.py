"""SVG sheets: one page per file, mm units, Inkscape layers (cut, mountain, valley, labels, preview)."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

from ..fabricate.page import Page
from .files import atomic_write
from .sheet_style import PREVIEW_RGB, STROKE_MM, STYLES, TAB_RGB, TEXT_RGB, crease_layers, text_baseline


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
        bx, by = text_baseline(t)
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
    for style, cls, segs in crease_layers(page):
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
