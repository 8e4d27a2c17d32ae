"""Independent readers of the sheets `polyfold make` writes: the print SVG, the DXF and the PDF.

Stands alone on purpose (numpy, shapely, xml.etree, ezdxf's reader, pypdf; never polyfold): the
tests and bench/bench_build.py measure what was written, not what polyfold meant to write.

Every reader gives `Sheet`s in page millimetres, origin at the page's top-left corner, y down (the
SVG's frame; DXF and PDF have y up and are flipped here):

- outlines: closed cut paths (rings (n, 2), first point not repeated);
- cut_lines (k, 2, 2): open cut strokes (slits) on the pieces, as segments; open cut-coloured
  strokes off the pieces (a scale bar, registration corners: a PDF tells them by colour only) are
  printed marks, in `marks`;
- folds: {"mountain": (k, 2, 2), "valley": (k, 2, 2)} scored lines, as segments; fold_classes
  gives the SVG class of each segment (e.g. "valley" or "tab-fold"; "" in DXF and PDF);
- faces / tabs: the SVG preview's face and tab polygons (empty for DXF; the PDF's fills are in
  `fills` as (rgb, ring) without telling faces from tabs);
- labels: `Label`s (text, anchor, angle, size) with an estimated box.

What counts as what, so that new layers and classes are read without changes here: an element's
kind is the first of "mountain", "valley", "cut" found in its own class, then in the id, label and
class of its groups, nearest first (SVG), or in its layer name (DXF); failing that, its stroke
colour: pure red mountain, pure blue valley, black undashed cut (SVG, PDF). Anything marked
"no-cut", or named for a scale bar or registration marks ("scale", "mark", "legend"), is not a
cut or fold line; strokes of other colours are ignored.

Label boxes are estimates (the writers' fonts are not embedded): width the advance widths of
Helvetica (the font the SVG names first and the PDF uses; Arial's are the same) from the font
metrics reportlab ships, height the cap height 0.72 em above the baseline, placed by the text's
anchor (SVG text-anchor; DXF alignment; PDF: the drawn string's start) and turned by its rotation.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

MM_PER_PT = 25.4 / 72.0
CAP = 0.72  # cap height, in em
FOLD_KINDS = ("mountain", "valley")
_KINDS = ("mountain", "valley", "cut")
_NOT_LINES = ("no-cut", "scale", "mark", "legend")  # names of things that are never cut or scored
_SVG = "{http://www.w3.org/2000/svg}"
_INK_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"


# ----------------------------------------------------------------------------------------------
# What a sheet holds


@dataclass(frozen=True)
class Label:
    """A text on a sheet: anchor (x, y) the point it is placed from, on its baseline (page mm, y
    down); align "middle" (centred on the anchor) or "start"; angle its reading direction in
    degrees counter-clockwise as seen on the page; size its font size (em) in mm; cap its cap
    height in mm; kind its SVG class or DXF layer ("" when unknown)."""

    text: str
    anchor: tuple[float, float]
    angle: float
    size: float
    cap: float
    align: str = "middle"
    kind: str = ""

    @property
    def width(self) -> float:
        from reportlab.pdfbase.pdfmetrics import stringWidth

        return float(stringWidth(self.text, "Helvetica", self.size))

    def box(self) -> shapely.Polygon:
        """The estimated box of the text on the page (see the module docstring)."""
        x0 = -self.width / 2 if self.align == "middle" else -self.width if self.align == "end" else 0.0
        corners = np.array([[x0, 0.0], [x0 + self.width, 0.0], [x0 + self.width, -self.cap], [x0, -self.cap]])
        a = math.radians(self.angle)  # CCW on the page = clockwise in the y-down frame
        rot = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
        return shapely.Polygon(corners @ rot.T + np.asarray(self.anchor))


@dataclass
class Sheet:
    """One page, read back (see the module docstring)."""

    width: float
    height: float
    outlines: list[np.ndarray] = field(default_factory=list)
    cut_lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))
    folds: dict[str, np.ndarray] = field(default_factory=lambda: {k: np.zeros((0, 2, 2)) for k in FOLD_KINDS})
    fold_classes: dict[str, list[str]] = field(default_factory=lambda: {k: [] for k in FOLD_KINDS})
    faces: list[np.ndarray] = field(default_factory=list)
    tabs: list[np.ndarray] = field(default_factory=list)
    fills: list[tuple[tuple[float, float, float], np.ndarray]] = field(default_factory=list)
    labels: list[Label] = field(default_factory=list)
    marks: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))
    leaders: list[np.ndarray] = field(default_factory=list)  # printed open lines of class "leader" (SVG)

    def lines(self) -> np.ndarray:
        """Every cut and fold stroke as segments (k, 2, 2): outline sides, slits, folds."""
        parts = [np.stack([r, np.roll(r, -1, axis=0)], axis=1) for r in self.outlines if len(r) >= 2]
        parts += [self.cut_lines] + [self.folds[k] for k in FOLD_KINDS]
        return np.concatenate([p.reshape(-1, 2, 2) for p in parts]) if parts else np.zeros((0, 2, 2))

    def pieces(self) -> list[shapely.Polygon]:
        """The paper pieces: outlines inside an even number of other outlines (none: the outer
        ring of a piece; two: a piece placed in another's hole), each with the outlines directly
        inside it as holes."""
        polys = [shapely.make_valid(shapely.Polygon(r)) for r in self.outlines if len(r) >= 3]
        polys = [p for p in polys if p.area > 0]
        inside = [[j for j in range(len(polys)) if j != i and polys[j].area > polys[i].area
                   and polys[j].contains(polys[i].representative_point())] for i in range(len(polys))]
        depth = [len(c) for c in inside]
        holes: dict[int, list] = {i: [] for i in range(len(polys)) if depth[i] % 2 == 0}
        for i in range(len(polys)):
            if depth[i] % 2:
                host = min((j for j in inside[i] if depth[j] == depth[i] - 1), key=lambda j: polys[j].area)
                holes[host].append(polys[i])
        return [shapely.difference(polys[o], shapely.union_all(h)) if h else polys[o] for o, h in holes.items()]


def _kind_of(names: list[str]) -> str | None:
    """'mountain' / 'valley' / 'cut' from names (nearest first), 'none' when something marks it
    as never cut or scored, None when the names say nothing."""
    for name in names:
        low = name.lower()
        if any(word in low for word in _NOT_LINES):
            return "none"
        for kind in _KINDS:
            if kind in low:
                return kind
    return None


def _kind_of_colour(rgb: tuple[float, float, float] | None, dashed: bool) -> str | None:
    """The kind a cutter reads from a stroke colour (components 0..1)."""
    if rgb is None:
        return None
    r, g, b = (round(v * 255) for v in rgb)
    if (r, g, b) == (255, 0, 0):
        return "mountain"
    if (r, g, b) == (0, 0, 255):
        return "valley"
    if (r, g, b) == (0, 0, 0) and not dashed:
        return "cut"
    return None


def _segments(polylines: list[np.ndarray]) -> np.ndarray:
    segs = [np.stack([p[:-1], p[1:]], axis=1) for p in polylines if len(p) >= 2]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 2))


def _finish(sheet: Sheet, strokes: list[tuple[str, str, list[np.ndarray], list[np.ndarray]]]) -> Sheet:
    """Sort strokes (kind, class, closed rings, open polylines) into the sheet's lists."""
    cut_open, folds, classes = [], {k: [] for k in FOLD_KINDS}, {k: [] for k in FOLD_KINDS}
    for kind, cls, rings, opens in strokes:
        if kind == "cut":
            sheet.outlines.extend(rings)
            cut_open.extend(opens)
        elif kind in FOLD_KINDS:
            segs = _segments(opens + [np.vstack([r, r[:1]]) for r in rings])
            folds[kind].append(segs)
            classes[kind].extend([cls] * len(segs))
    cuts = _segments(cut_open)
    paper = shapely.union_all([shapely.make_valid(shapely.Polygon(r)) for r in sheet.outlines if len(r) >= 3]).buffer(0.01)
    on = np.array([paper.covers(shapely.LineString(seg)) for seg in cuts], dtype=bool).reshape(-1)
    sheet.cut_lines, sheet.marks = cuts[on].reshape(-1, 2, 2), cuts[~on].reshape(-1, 2, 2)
    sheet.folds = {k: np.concatenate(v) if v else np.zeros((0, 2, 2)) for k, v in folds.items()}
    sheet.fold_classes = classes
    return sheet


# ----------------------------------------------------------------------------------------------
# SVG


def _affine(transform: str | None) -> np.ndarray:
    """The 3x3 matrix of an SVG transform attribute (matrix, translate, scale, rotate)."""
    m = np.eye(3)
    for name, args in re.findall(r"(matrix|translate|scale|rotate|skewX|skewY)\s*\(([^)]*)\)", transform or ""):
        v = [float(x) for x in re.split(r"[\s,]+", args.strip()) if x]
        if name == "matrix":
            t = np.array([[v[0], v[2], v[4]], [v[1], v[3], v[5]], [0, 0, 1]])
        elif name == "translate":
            t = np.array([[1, 0, v[0]], [0, 1, v[1] if len(v) > 1 else 0.0], [0, 0, 1]])
        elif name == "scale":
            t = np.diag([v[0], v[1] if len(v) > 1 else v[0], 1.0])
        elif name == "rotate":
            a = math.radians(v[0])
            r = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
            if len(v) == 3:
                c = np.array([[1, 0, v[1]], [0, 1, v[2]], [0, 0, 1]])
                r = c @ r @ np.linalg.inv(c)
            t = r
        else:
            a = math.tan(math.radians(v[0]))
            t = np.array([[1, a, 0], [0, 1, 0], [0, 0, 1]]) if name == "skewX" else np.array([[1, 0, 0], [a, 1, 0], [0, 0, 1]])
        m = m @ t
    return m


def _path_d(d: str) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Closed rings and open polylines of an SVG path made of straight commands (M L H V Z, either
    case); curves are read as straight lines to their end points."""
    tokens = re.findall(r"[A-Za-z]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", d)
    rings, opens, cur, pos, start, cmd, i = [], [], [], np.zeros(2), np.zeros(2), "M", 0
    arity = {"M": 2, "L": 2, "T": 2, "H": 1, "V": 1, "C": 6, "S": 4, "Q": 4, "A": 7, "Z": 0}

    def flush(closed: bool) -> None:
        nonlocal cur
        if len(cur) >= 2:
            pts = np.array(cur)
            if closed:
                if np.allclose(pts[0], pts[-1]):
                    pts = pts[:-1]
                rings.append(pts)
            else:
                opens.append(pts)
        cur = []

    while i < len(tokens):
        if tokens[i].isalpha():
            cmd = tokens[i]
            i += 1
            if cmd in "Zz":
                flush(True)
                pos = start.copy()
                continue
        up, rel = cmd.upper(), cmd.islower()
        n = arity[up]
        vals = [float(t) for t in tokens[i:i + n]]
        i += n
        if len(vals) < n:
            break
        if up == "H":
            pos = np.array([vals[0] + (pos[0] if rel else 0.0), pos[1]])
        elif up == "V":
            pos = np.array([pos[0], vals[0] + (pos[1] if rel else 0.0)])
        else:
            end = np.array(vals[-2:])
            pos = end + pos if rel else end
        if up == "M":
            flush(False)
            start = pos.copy()
            cmd = "l" if rel else "L"  # further pairs after M are lines
        cur.append(pos.copy())
    flush(False)
    return rings, opens


def _style(el: ET.Element) -> dict[str, str]:
    """Presentation attributes of an element, its style="" included."""
    out = {k: v for k, v in el.attrib.items()}
    for item in (el.get("style") or "").split(";"):
        if ":" in item:
            k, v = item.split(":", 1)
            out[k.strip()] = v.strip()
    return out


_NAMED = {"black": (0, 0, 0), "red": (1, 0, 0), "blue": (0, 0, 1)}


def _colour(value: str | None) -> tuple[float, float, float] | None:
    if not value or value == "none":
        return None
    value = value.strip().lower()
    if value in _NAMED:
        return _NAMED[value]
    m = re.fullmatch(r"#([0-9a-f]{6})", value)
    if m:
        h = m.group(1)
        return tuple(int(h[k:k + 2], 16) / 255 for k in (0, 2, 4))
    m = re.fullmatch(r"#([0-9a-f]{3})", value)
    if m:
        return tuple(int(c * 2, 16) / 255 for c in m.group(1))
    m = re.fullmatch(r"rgb\(\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*\)", value)
    if m:
        return tuple(int(c) / 255 for c in m.groups())
    return None


def read_svg(path: str | Path) -> Sheet:
    """A print SVG (sheet-NN.svg) read back (see the module docstring)."""
    root = ET.parse(path).getroot()
    vb = [float(v) for v in re.split(r"[\s,]+", (root.get("viewBox") or "").strip()) if v]

    def mm(attr: str) -> float:
        value = root.get(attr) or ""
        num = float(re.match(r"[-+]?[\d.]+", value).group(0)) if value else 0.0
        return num * (25.4 if value.endswith("in") else 1.0)

    width, height = mm("width") or (vb[2] if vb else 0.0), mm("height") or (vb[3] if vb else 0.0)
    base = np.eye(3)
    if len(vb) == 4 and vb[2] > 0 and vb[3] > 0:
        base = np.array([[width / vb[2], 0, -vb[0] * width / vb[2]], [0, height / vb[3], -vb[1] * height / vb[3]], [0, 0, 1]])
    sheet = Sheet(width=width, height=height)
    strokes = []

    def walk(el: ET.Element, m: np.ndarray, inherited: dict[str, str], names: list[str]) -> None:
        st = {**inherited, **{k: v for k, v in _style(el).items() if k not in ("id", "class", "transform", "d")}}
        m = m @ _affine(el.get("transform"))
        tag = el.tag.removeprefix(_SVG)
        own = [n for n in (el.get("class"), el.get("id"), el.get(_INK_LABEL)) if n]
        names = own + names if tag == "g" else names
        if tag == "g" or tag == "svg":
            for child in el:
                walk(child, m, st, names)
            return
        if tag == "path" or tag in ("line", "polyline", "polygon", "rect"):
            rings, opens = _shape(el, tag)
            rings = [_apply(m, r) for r in rings]
            opens = [_apply(m, p) for p in opens]
            cls = el.get("class") or ""
            stroke = _colour(st.get("stroke"))
            if stroke is None:  # a fill: the preview's faces and tabs
                if any("preview" in n.lower() for n in names + [cls]):
                    (sheet.tabs if "tab" in cls.split() else sheet.faces).extend(rings)
                return
            if "leader" in cls.split():  # a printed line from an edge to its label: neither cut nor score
                sheet.leaders.extend(opens)
                return
            kind = _kind_of([cls] + names)
            if kind is None:
                kind = _kind_of_colour(stroke, st.get("stroke-dasharray", "none") not in ("none", ""))
            if kind and kind != "none":
                strokes.append((kind, cls, rings, opens))
        elif tag == "text":
            text = "".join(el.itertext()).strip()
            if not text:
                return
            x, y = float(el.get("x", 0)), float(el.get("y", 0))
            size = float(re.match(r"[\d.]+", st.get("font-size", "0")).group(0))
            p = m @ np.array([x, y, 1.0])
            ex = m[:2, :2] @ np.array([1.0, 0.0])  # the text's reading direction on the page
            scale = float(np.hypot(*ex))
            angle = math.degrees(math.atan2(-ex[1], ex[0]))  # CCW as seen on a y-down page
            align = {"middle": "middle", "end": "end"}.get(st.get("text-anchor", "start"), "start")
            sheet.labels.append(Label(text=text, anchor=(float(p[0]), float(p[1])), angle=angle, size=size * scale,
                                      cap=CAP * size * scale, align=align, kind=el.get("class") or ""))

    walk(root, base, {}, [])
    return _finish(sheet, strokes)


def _shape(el: ET.Element, tag: str) -> tuple[list[np.ndarray], list[np.ndarray]]:
    if tag == "path":
        return _path_d(el.get("d") or "")
    if tag == "line":
        return [], [np.array([[float(el.get("x1", 0)), float(el.get("y1", 0))], [float(el.get("x2", 0)), float(el.get("y2", 0))]])]
    if tag == "rect":
        x, y, w, h = (float(el.get(k, 0)) for k in ("x", "y", "width", "height"))
        return [np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])], []
    pts = np.array([float(v) for v in re.split(r"[\s,]+", (el.get("points") or "").strip()) if v]).reshape(-1, 2)
    return ([pts], []) if tag == "polygon" else ([], [pts])


def _apply(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    return pts @ m[:2, :2].T + m[:2, 2]


# ----------------------------------------------------------------------------------------------
# DXF


def read_dxf(path: str | Path, page_height: float, page_width: float = 0.0) -> Sheet:
    """A DXF sheet read with ezdxf's reader; y flipped with the page height (mm) given (the
    header's limits are not trusted). Kinds by layer name (CUT, MOUNTAIN, VALLEY, ...); TEXT
    height is the cap height."""
    import ezdxf

    doc = ezdxf.readfile(str(path))
    sheet = Sheet(width=page_width, height=page_height)
    strokes = []

    def page(points) -> np.ndarray:
        pts = np.array([(float(p[0]), float(p[1])) for p in points], dtype=float).reshape(-1, 2)
        pts[:, 1] = page_height - pts[:, 1]
        return pts

    for e in doc.modelspace():
        layer = e.dxf.layer
        kind = _kind_of([layer])
        t = e.dxftype()
        if t in ("TEXT", "MTEXT"):
            if t == "TEXT":
                text, cap = e.dxf.text, float(e.dxf.height)
                aligned = e.dxf.halign != 0 or e.dxf.valign != 0
                point = e.dxf.align_point if aligned and e.dxf.hasattr("align_point") else e.dxf.insert
                align = {1: "middle", 2: "end", 4: "middle"}.get(e.dxf.halign, "start")
                rotation = float(e.dxf.rotation)
            else:
                text, cap, point, align, rotation = e.plain_text(), float(e.dxf.char_height), e.dxf.insert, "start", float(e.dxf.rotation)
            (x, y), = page([point]).tolist()
            sheet.labels.append(Label(text=text, anchor=(x, y), angle=rotation, size=cap / CAP, cap=cap, align=align,
                                      kind=layer))
            continue
        if kind in (None, "none"):
            continue
        if t == "LINE":
            strokes.append((kind, "", [], [page([e.dxf.start, e.dxf.end])]))
        elif t == "LWPOLYLINE":
            pts = page(e.get_points("xy"))
            strokes.append((kind, "", [pts], []) if e.closed else (kind, "", [], [pts]))
        elif t == "POLYLINE":
            pts = page([v.dxf.location for v in e.vertices])
            strokes.append((kind, "", [pts], []) if e.is_closed else (kind, "", [], [pts]))
    return _finish(sheet, strokes)


# ----------------------------------------------------------------------------------------------
# PDF


def read_pdf(path: str | Path) -> list[Sheet]:
    """Every page of a PDF read with pypdf: the content stream's path operators (m l re h, S s f
    f* B b n), stroke and fill colours (RG rg G g), the dash state (d), the transformation (cm,
    q/Q) and text (Tf, Tm, Td, TD, T*, Tj, TJ). Strokes by colour (module docstring)."""
    from pypdf import PdfReader
    from pypdf.generic import ContentStream

    reader = PdfReader(str(path))
    sheets = []
    for pg in reader.pages:
        box = [float(v) for v in pg.mediabox]
        w_pt, h_pt = box[2] - box[0], box[3] - box[1]
        sheet = Sheet(width=w_pt * MM_PER_PT, height=h_pt * MM_PER_PT)
        strokes = []
        contents = pg.get_contents()
        ops = ContentStream(contents, reader).operations if contents is not None else []

        def to_mm(pts: np.ndarray) -> np.ndarray:
            out = (pts - np.array([box[0], box[1]])) * MM_PER_PT
            out[:, 1] = sheet.height - out[:, 1]
            return out

        state = {"ctm": np.eye(3), "stroke": (0.0, 0.0, 0.0), "fill": (0.0, 0.0, 0.0), "dash": False, "font": 0.0}
        stack = []
        subpaths: list[tuple[list, bool]] = []  # (points in device space, closed)
        tm = tlm = np.eye(3)
        leading = 0.0

        def point(x, y) -> np.ndarray:
            return (state["ctm"] @ np.array([float(x), float(y), 1.0]))[:2]

        def paint(stroke: bool, fill: bool) -> None:
            for pts, closed in subpaths:
                if len(pts) < 2:
                    continue
                arr = to_mm(np.array(pts))
                if closed and len(arr) > 2 and np.allclose(arr[0], arr[-1]):
                    arr = arr[:-1]
                if fill and closed:
                    sheet.fills.append((state["fill"], arr))
                if stroke:
                    kind = _kind_of_colour(state["stroke"], state["dash"])
                    if kind:
                        strokes.append((kind, "", [arr], []) if closed else (kind, "", [], [arr]))

        for operands, op in ops:
            op = op.decode() if isinstance(op, bytes) else op
            if op == "q":
                stack.append(dict(state))
            elif op == "Q":
                state = stack.pop() if stack else state
            elif op == "cm":
                a, b, c, d, e, f = (float(v) for v in operands)
                state["ctm"] = state["ctm"] @ np.array([[a, c, e], [b, d, f], [0, 0, 1]])
            elif op == "RG":
                state["stroke"] = tuple(float(v) for v in operands)
            elif op == "rg":
                state["fill"] = tuple(float(v) for v in operands)
            elif op == "G":
                state["stroke"] = (float(operands[0]),) * 3
            elif op == "g":
                state["fill"] = (float(operands[0]),) * 3
            elif op == "d":
                state["dash"] = len(operands[0]) > 0
            elif op == "m":
                subpaths.append(([point(*operands)], False))
            elif op == "l" and subpaths:
                subpaths[-1][0].append(point(*operands))
            elif op == "h" and subpaths:
                pts = subpaths[-1][0]
                subpaths[-1] = (pts + [pts[0]], True)
            elif op == "re":
                x, y, w, h = (float(v) for v in operands)
                pts = [point(x, y), point(x + w, y), point(x + w, y + h), point(x, y + h)]
                subpaths.append((pts + [pts[0]], True))
            elif op in ("S", "s", "f", "F", "f*", "B", "B*", "b", "b*", "n"):
                if op in ("s", "b", "b*") and subpaths:
                    pts = subpaths[-1][0]
                    subpaths[-1] = (pts + [pts[0]], True)
                paint(op in ("S", "s", "B", "B*", "b", "b*"), op in ("f", "F", "f*", "B", "B*", "b", "b*"))
                subpaths = []
            elif op == "BT":
                tm = tlm = np.eye(3)
            elif op == "Tf":
                state["font"] = float(operands[1])
            elif op == "TL":
                leading = float(operands[0])
            elif op == "Tm":
                a, b, c, d, e, f = (float(v) for v in operands)
                tm = tlm = np.array([[a, c, e], [b, d, f], [0, 0, 1]])
            elif op in ("Td", "TD"):
                tx, ty = float(operands[0]), float(operands[1])
                if op == "TD":
                    leading = -ty
                tm = tlm = tlm @ np.array([[1, 0, tx], [0, 1, ty], [0, 0, 1]])
            elif op == "T*":
                tm = tlm = tlm @ np.array([[1, 0, 0], [0, 1, -leading], [0, 0, 1]])
            elif op in ("Tj", "TJ", "'", '"'):
                raw = operands[-1]
                text = "".join(str(s) for s in raw if not isinstance(s, (int, float))) if op == "TJ" else str(raw)
                if text.strip():
                    m = state["ctm"] @ tm
                    origin = to_mm(m[:2, 2][None])[0]
                    ex = m[:2, :2] @ np.array([1.0, 0.0])
                    size = state["font"] * float(np.hypot(*ex)) * MM_PER_PT
                    angle = math.degrees(math.atan2(ex[1], ex[0]))  # PDF y up: CCW as seen
                    sheet.labels.append(Label(text=text, anchor=(float(origin[0]), float(origin[1])), angle=angle,
                                              size=size, cap=CAP * size, align="start"))
        sheets.append(_finish(sheet, strokes))
    return sheets
