"""Cut sheets (SVG, real millimetres) and PNG previews of a paper net given as a FOLD 1.1 dict.

Input conventions (the project's canonical net format, see `foldfile`):

* ``vertices_coords``: 2D net coordinates (model units), outer side of the surface towards +z;
* ``faces_vertices``: triangles, CCW seen from +z;
* ``edges_vertices`` / ``edges_assignment``: "B" cut or open boundary, "M" mountain, "V" valley,
  "F" flat (not scored);
* ``file_frames[...]`` with class "foldedForm": the same vertices folded in 3D (gives the model's
  longest dimension, which `size_mm` refers to);
* ``polyfold:faces_piece``: piece index per face; ``polyfold:edges_meshEdge``: mesh edge per edge
  (the two twins of a cut edge share it: it is the glue label printed on both).

The sheet is drawn as seen from +z (SVG y points down, so y is flipped).
"""

from __future__ import annotations

import colorsys
import logging
import math
import os
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import PolyfoldError
from .files import atomic_write
from .raster import fill_triangles, png_bytes

log = logging.getLogger(__name__)

MARGIN_MM = 10.0
MAX_SHEET_MM = 300.0
TAB_MAX_MM = 6.0
TAB_REL = 0.35

_CUT = frozenset({"B", "C"})
_STYLE = {
    "cut": dict(stroke="#000000", stroke_width=0.25, fill="none", stroke_linejoin="round"),
    "mountain": dict(stroke="#e00000", stroke_width=0.2, fill="none", stroke_dasharray="3,1,0.5,1"),
    "valley": dict(stroke="#0040ff", stroke_width=0.2, fill="none", stroke_dasharray="1.5,1"),
    "crease": dict(stroke="#999999", stroke_width=0.15, fill="none", stroke_dasharray="1,1"),
    "tab": dict(stroke="#000000", stroke_width=0.25, fill="none", stroke_linejoin="round"),
    "tab-fold": dict(stroke="#808080", stroke_width=0.15, fill="none", stroke_dasharray="1,1"),
}
_PNG_COLORS = {"cut": (0, 0, 0), "mountain": (220, 30, 30), "valley": (30, 70, 230), "crease": (150, 150, 150)}


# ----------------------------------------------------------------------------------------------
# input


@dataclass(frozen=True)
class _Net:
    coords: np.ndarray  # (n, 2) model units
    faces: np.ndarray  # (m, 3)
    edges: np.ndarray  # (k, 2)
    kind: list  # per edge: "cut", "mountain", "valley", "flat", "crease"
    mesh_edge: np.ndarray  # (k,) ; -1 - index when the file has none (never paired)
    pieces: np.ndarray  # (m,)
    edge_face: np.ndarray  # (k,) face incident to the edge (first one), -1 if none
    edge_dir: np.ndarray  # (k, 2) the edge oriented as in edge_face (a -> b), CCW order
    coords3: np.ndarray | None  # (n, 3) folded form, if any

    @property
    def piece_ids(self) -> np.ndarray:
        return np.unique(self.pieces)

    def twins(self) -> list[tuple[int, int]]:
        """Pairs (e1 < e2) of cut edges sharing a mesh edge that appears exactly twice among cuts."""
        by: dict[int, list[int]] = defaultdict(list)
        for e, k in enumerate(self.kind):
            if k == "cut" and self.mesh_edge[e] >= 0 and self.edge_face[e] >= 0:
                by[int(self.mesh_edge[e])].append(e)
        return sorted((min(v), max(v)) for v in by.values() if len(v) == 2)


def _kind(assignment: str) -> str:
    a = str(assignment).upper()
    if a in _CUT:
        return "cut"
    return {"M": "mountain", "V": "valley", "F": "flat"}.get(a, "crease")


def _folded_coords(fold: dict) -> np.ndarray | None:
    for fr in fold.get("file_frames") or []:
        if not isinstance(fr, dict):
            continue
        classes = fr.get("frame_classes") or []
        coords = fr.get("vertices_coords")
        if "foldedForm" in classes and coords:
            arr = np.asarray(coords, dtype=np.float64)
            if arr.ndim == 2 and arr.shape[1] >= 2:
                return arr[:, :3] if arr.shape[1] >= 3 else np.pad(arr, ((0, 0), (0, 1)))
    return None


def _parse(fold: dict) -> _Net:
    try:
        coords = np.asarray(fold["vertices_coords"], dtype=np.float64)
        faces = np.asarray(fold["faces_vertices"], dtype=np.int64)
    except KeyError as exc:
        raise PolyfoldError(f"FOLD net lacks {exc.args[0]!r}") from None
    except (ValueError, TypeError):
        raise PolyfoldError("FOLD net: vertices_coords/faces_vertices are not numeric arrays (triangles only)") from None
    if coords.ndim != 2 or coords.shape[1] < 2 or len(coords) == 0:
        raise PolyfoldError("FOLD net: vertices_coords must be a non-empty list of [x, y]")
    coords = coords[:, :2]
    if not np.isfinite(coords).all():
        raise PolyfoldError("FOLD net: vertices_coords contains non-finite values")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise PolyfoldError("FOLD net: faces_vertices must be a non-empty list of triangles")
    if faces.min() < 0 or faces.max() >= len(coords):
        raise PolyfoldError("FOLD net: faces_vertices refers to a missing vertex")
    edges = np.asarray(fold.get("edges_vertices", []), dtype=np.int64).reshape(-1, 2)
    if len(edges) and (edges.min() < 0 or edges.max() >= len(coords)):
        raise PolyfoldError("FOLD net: edges_vertices refers to a missing vertex")
    assign = list(fold.get("edges_assignment") or [])
    if len(assign) != len(edges):
        raise PolyfoldError(f"FOLD net: {len(assign)} edges_assignment for {len(edges)} edges")
    kind = [_kind(a) for a in assign]
    me = fold.get("polyfold:edges_meshEdge")
    if me is not None and len(me) == len(edges):
        mesh_edge = np.asarray(me, dtype=np.int64)
    else:
        mesh_edge = -1 - np.arange(len(edges), dtype=np.int64)

    # half-edges of the faces, by undirected key
    inc: dict[tuple[int, int], list[tuple[int, int, int]]] = defaultdict(list)
    for f, (a, b, c) in enumerate(faces.tolist()):
        for u, v in ((a, b), (b, c), (c, a)):
            inc[(u, v) if u < v else (v, u)].append((f, u, v))
    edge_face = np.full(len(edges), -1, dtype=np.int64)
    edge_dir = edges.copy()
    for e, (u, v) in enumerate(edges.tolist()):
        hs = inc.get((u, v) if u < v else (v, u))
        if hs:
            edge_face[e] = hs[0][0]
            edge_dir[e] = hs[0][1:]

    fp = fold.get("polyfold:faces_piece")
    if fp is not None and len(fp) == len(faces):
        pieces = np.asarray(fp, dtype=np.int64)
    else:  # connected components of faces across non-cut edges
        parent = list(range(len(faces)))

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        cut_keys = {(min(u, v), max(u, v)) for (u, v), k in zip(edges.tolist(), kind) if k == "cut"}
        for key, hs in inc.items():
            if key in cut_keys:
                continue
            for h in hs[1:]:
                parent[find(h[0])] = find(hs[0][0])
        pieces = np.unique([find(i) for i in range(len(faces))], return_inverse=True)[1].astype(np.int64)
    return _Net(coords, faces, edges, kind, mesh_edge, pieces, edge_face, edge_dir, _folded_coords(fold))


# ----------------------------------------------------------------------------------------------
# layout


@dataclass(frozen=True)
class SheetLayout:
    """Placement of the net on the sheet. `coords` are the vertices in SVG millimetres (y down)."""

    scale: float  # mm per model unit
    margin: float  # mm
    width: float  # sheet width, mm
    height: float  # sheet height, mm
    coords: np.ndarray  # (n, 2) mm, SVG frame
    longest: float  # longest dimension of the folded model (model units)

    @property
    def oversize(self) -> bool:
        """True when the sheet exceeds 300 x 300 mm (does not fit common printers/cutters)."""
        return self.width > MAX_SHEET_MM or self.height > MAX_SHEET_MM


def _used_bbox(net: _Net) -> tuple[float, float, float, float]:
    pts = net.coords[np.unique(net.faces)]
    (xmin, ymin), (xmax, ymax) = pts.min(axis=0), pts.max(axis=0)
    return float(xmin), float(ymin), float(xmax), float(ymax)


def _layout(net: _Net, size_mm: float) -> SheetLayout:
    if not (size_mm > 0 and math.isfinite(size_mm)):
        raise PolyfoldError(f"sheet size must be a positive number of mm, got {size_mm}")
    xmin, ymin, xmax, ymax = _used_bbox(net)
    if net.coords3 is not None and len(net.coords3) == len(net.coords):
        p3 = net.coords3[np.unique(net.faces)]
        longest = float((p3.max(axis=0) - p3.min(axis=0)).max())
    else:
        log.warning("FOLD net has no foldedForm frame: sizing by the flat net instead of the model")
        longest = max(xmax - xmin, ymax - ymin)
    if not (longest > 0 and math.isfinite(longest)):
        raise PolyfoldError("FOLD net: the model has zero size, cannot scale the sheet")
    s = size_mm / longest
    m = MARGIN_MM
    xy = np.empty_like(net.coords)
    xy[:, 0] = (net.coords[:, 0] - xmin) * s + m
    xy[:, 1] = (ymax - net.coords[:, 1]) * s + m
    return SheetLayout(s, m, (xmax - xmin) * s + 2 * m, (ymax - ymin) * s + 2 * m, xy, longest)


def sheet_layout(fold: dict, size_mm: float) -> SheetLayout:
    """Scale (mm per model unit) = size_mm / longest 3D dimension; net in mm with a 10 mm margin."""
    return _layout(_parse(fold), size_mm)


# ----------------------------------------------------------------------------------------------
# cut outlines


def _boundary_loops(net: _Net, piece: int) -> list[tuple[list[int], bool]]:
    """Boundary loops of one piece as lists of vertex ids (closed flag per loop).

    Walks the piece's cut edges oriented like their face (interior on the left for CCW faces). Where
    several unused edges leave a vertex (the outline touches itself there), the walk keeps to the
    face sector it came from: it takes the first outgoing edge met rotating from the incoming edge
    towards the interior, i.e. the topological boundary of the piece, so a crease-connected piece
    that touches itself at a vertex still gives one loop; holes give further loops.
    """
    hes: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()
    for e, k in enumerate(net.kind):
        f = net.edge_face[e]
        if k != "cut" or f < 0 or net.pieces[f] != piece:
            continue
        a, b = (int(x) for x in net.edge_dir[e])
        if a == b or (a, b) in seen:
            continue
        seen.add((a, b))
        hes.append((a, b))
    if not hes:
        return []
    fs = net.faces[net.pieces == piece]
    p = net.coords
    area = _cross2(p[fs[:, 1]] - p[fs[:, 0]], p[fs[:, 2]] - p[fs[:, 0]]).sum()
    sign = 1.0 if area >= 0 else -1.0

    out: dict[int, list[int]] = defaultdict(list)
    for i, (a, _) in enumerate(hes):
        out[a].append(i)

    def turn(i_in: int, i_out: int) -> float:
        a, b = hes[i_in]
        r = p[a] - p[b]
        d = p[hes[i_out][1]] - p[b]
        ang = (-sign * math.atan2(r[0] * d[1] - r[1] * d[0], r[0] * d[0] + r[1] * d[1])) % (2 * math.pi)
        return ang if ang > 1e-12 else 2 * math.pi

    used = [False] * len(hes)
    loops = []
    for start in range(len(hes)):
        if used[start]:
            continue
        used[start] = True
        loop, cur, closed = [start], start, False
        for _ in range(len(hes)):
            cands = out.get(hes[cur][1], [])
            if not cands:
                break
            best = min(cands, key=lambda j: turn(cur, j))
            if best == start:
                closed = True
                break
            if used[best]:
                free = [j for j in cands if not used[j]]
                if not free:
                    closed = hes[cur][1] == hes[start][0]
                    break
                best = min(free, key=lambda j: turn(cur, j))
            used[best] = True
            loop.append(best)
            cur = best
        verts = [hes[i][0] for i in loop]
        if not closed:
            verts.append(hes[loop[-1]][1])
        loops.append((verts, closed))
    return loops


def _cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _fmt(x: float) -> str:
    s = f"{x:.3f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _pt(q) -> str:
    return f"{_fmt(q[0])},{_fmt(q[1])}"


# ----------------------------------------------------------------------------------------------
# tabs


def _tab_polygon(xy: np.ndarray, net: _Net, e: int) -> np.ndarray | None:
    """Trapezoid (p0, q0, q1, p1) on the outer side of cut edge e, in sheet mm; None if degenerate."""
    a, b = net.edge_dir[e]
    p0, p1 = xy[a], xy[b]
    d = p1 - p0
    length = float(np.hypot(*d))
    if length < 1e-9:
        return None
    d = d / length
    n = np.array([-d[1], d[0]])
    centroid = xy[net.faces[net.edge_face[e]]].mean(axis=0)
    if np.dot(centroid - (p0 + p1) / 2, n) > 0:
        n = -n
    h = min(TAB_REL * length, TAB_MAX_MM)
    inset = min(h, 0.25 * length)
    return np.array([p0, p0 + d * inset + n * h, p1 - d * inset + n * h, p1])


class _Grid:
    """Uniform-grid bucket of placed tab polygons (for quick overlap checks)."""

    def __init__(self, cell: float) -> None:
        self.cell = cell
        self.buckets: dict[tuple[int, int], list] = defaultdict(list)

    def _cells(self, geom):
        x0, y0, x1, y1 = geom.bounds
        c = self.cell
        for i in range(int(x0 // c), int(x1 // c) + 1):
            for j in range(int(y0 // c), int(y1 // c) + 1):
                yield (i, j)

    def hits(self, geom) -> bool:
        return any(geom.intersects(g) for key in self._cells(geom) for g in self.buckets.get(key, ()))

    def add(self, geom) -> None:
        for key in self._cells(geom):
            self.buckets[key].append(geom)


def _place_tabs(net: _Net, xy: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """(edge, trapezoid) for each twin pair that has room for a tab on one of its twins."""
    import shapely
    from shapely.geometry import Polygon

    pairs = net.twins()
    if not pairs:
        return []
    tris = shapely.polygons(xy[net.faces])
    tree = shapely.STRtree(tris)
    grid = _Grid(2 * TAB_MAX_MM)
    placed = []
    for e1, e2 in pairs:
        for e in (e1, e2):
            poly = _tab_polygon(xy, net, e)
            if poly is None:
                continue
            # push the candidate off its base by a hair so that touching its own edge is no hit
            n = (poly[1] + poly[2] - poly[0] - poly[3]) / 2
            h = float(np.hypot(*n))
            if h <= 0:
                continue
            probe = Polygon(poly + n / h * min(1e-3, 0.01 * h))
            if not probe.is_valid or len(tree.query(probe, predicate="intersects")) or grid.hits(probe):
                continue
            grid.add(Polygon(poly))
            placed.append((e, poly))
            break
    return placed


# ----------------------------------------------------------------------------------------------
# SVG


def _label_geometry(xy: np.ndarray, net: _Net, e: int) -> tuple[float, float, float, float] | None:
    """(x, y, angle_deg, font_size) of the glue label of cut edge e, just inside its face."""
    a, b = net.edge_dir[e]
    p0, p1 = xy[a], xy[b]
    d = p1 - p0
    length = float(np.hypot(*d))
    if length < 1e-9:
        return None
    fs = min(2.5, max(0.8, 0.2 * length))
    n = np.array([-d[1], d[0]]) / length
    tri = xy[net.faces[net.edge_face[e]]]
    mid = (p0 + p1) / 2
    if np.dot(tri.mean(axis=0) - mid, n) < 0:
        n = -n
    v = tri - tri[0]
    face_h = abs(v[1, 0] * v[2, 1] - v[1, 1] * v[2, 0]) / length  # height over edge e
    off = min(0.3 + 0.6 * fs, face_h / 3)
    x, y = mid + n * off
    ang = math.degrees(math.atan2(d[1], d[0]))
    if ang > 90:
        ang -= 180
    elif ang <= -90:
        ang += 180
    return float(x), float(y), ang, fs


def write_svg(fold: dict, path, *, size_mm: float = 150.0, labels: bool = True, tabs: bool = True) -> None:
    """Write the cut sheet of the net: real millimetres, the model's longest dimension = size_mm.

    One closed cut path per piece (class "cut", id "cut-{piece}", subpaths for holes), one path per
    mountain/valley crease (classes "mountain"/"valley"; flat creases are omitted), glue labels
    (class "label", the mesh-edge number, on both twins of each cut edge), glue tabs (class "tab",
    base class "tab-fold") and a title. `sheet_layout(fold, size_mm).oversize` tells whether it exceeds 300 x 300 mm.
    """
    import svgwrite

    net = _parse(fold)
    lay = _layout(net, size_mm)
    xy = lay.coords
    W, H = lay.width, lay.height
    dwg = svgwrite.Drawing(size=(f"{_fmt(W)}mm", f"{_fmt(H)}mm"), viewBox=f"0 0 {_fmt(W)} {_fmt(H)}", profile="full", debug=False)
    pieces = net.piece_ids

    if tabs:
        g_tabs = dwg.g(id="tabs")
        for e, poly in _place_tabs(net, xy):
            me = int(net.mesh_edge[e])
            g_tabs.add(dwg.path(d=f"M{_pt(poly[0])} L{_pt(poly[1])} L{_pt(poly[2])} L{_pt(poly[3])}",
                                class_="tab", id=f"tab-{me}", **_STYLE["tab"]))
            g_tabs.add(dwg.path(d=f"M{_pt(poly[0])} L{_pt(poly[3])}", class_="tab-fold", **_STYLE["tab-fold"]))
        dwg.add(g_tabs)

    g_creases = dwg.g(id="creases")
    for e, k in enumerate(net.kind):
        if k in ("mountain", "valley", "crease"):
            u, v = net.edges[e]
            g_creases.add(dwg.path(d=f"M{_pt(xy[u])} L{_pt(xy[v])}", class_=k, **_STYLE[k]))
    dwg.add(g_creases)

    g_cuts = dwg.g(id="cuts")
    for piece in pieces:
        parts = []
        for verts, closed in _boundary_loops(net, int(piece)):
            d = f"M{_pt(xy[verts[0]])} " + " ".join(f"L{_pt(xy[v])}" for v in verts[1:])
            parts.append(d + (" Z" if closed else ""))
        if parts:
            g_cuts.add(dwg.path(d=" ".join(parts), class_="cut", id=f"cut-{int(piece)}", **_STYLE["cut"]))
    dwg.add(g_cuts)

    if labels:
        g_labels = dwg.g(id="labels", font_family="sans-serif", fill="#000000")
        for pair in net.twins():
            for e in pair:
                geo = _label_geometry(xy, net, e)
                if geo is None:
                    continue
                x, y, ang, fs = geo
                g_labels.add(dwg.text(str(int(net.mesh_edge[e])), insert=(_fmt(x), _fmt(y)), class_="label",
                                      font_size=_fmt(fs), text_anchor="middle", dominant_baseline="central",
                                      transform=f"rotate({_fmt(ang)},{_fmt(x)},{_fmt(y)})"))
        p = xy
        areas = np.abs(_cross2(p[net.faces[:, 1]] - p[net.faces[:, 0]], p[net.faces[:, 2]] - p[net.faces[:, 0]])) / 2
        for piece in pieces:
            fids = np.flatnonzero(net.pieces == piece)
            f = fids[np.argmax(areas[fids])]
            c = p[net.faces[f]].mean(axis=0)
            fs = min(5.0, max(1.5, 0.25 * math.sqrt(areas[f])))
            g_labels.add(dwg.text(f"P{int(piece)}", insert=(_fmt(c[0]), _fmt(c[1])), class_="piece-label",
                                  font_size=_fmt(fs), text_anchor="middle", dominant_baseline="central",
                                  fill="#b0b0b0"))
        dwg.add(g_labels)

    n = len(pieces)
    title = (f"polyfold net: {n} piece{'s' if n != 1 else ''}, model {_fmt(size_mm)} mm long, "
             f"sheet {W:.0f} x {H:.0f} mm")
    dwg.add(dwg.text(title, insert=(2, 3.5), class_="title", font_size=3, font_family="sans-serif", fill="#404040"))

    # Oversize sheets are the caller's to report (see `sheet_layout(...).oversize`).
    atomic_write(path, dwg.tostring())


# ----------------------------------------------------------------------------------------------
# PNG


@dataclass(frozen=True)
class _Raster:
    scale: float  # px per model unit
    width: int
    height: int
    ox: float
    oy: float
    xmin: float
    ymax: float

    def to_px(self, pts) -> np.ndarray:
        """Model 2D -> pixel coordinates (x right, y down; pixel (i, j) covers [j, j+1) x [i, i+1))."""
        pts = np.asarray(pts, dtype=np.float64)
        return np.stack([(pts[..., 0] - self.xmin) * self.scale + self.ox,
                         (self.ymax - pts[..., 1]) * self.scale + self.oy], axis=-1)


def _raster_layout(net: _Net, width_px: int) -> _Raster:
    if int(width_px) < 16:
        raise PolyfoldError(f"PNG width must be at least 16 px, got {width_px}")
    width_px = int(width_px)
    xmin, ymin, xmax, ymax = _used_bbox(net)
    w, h = xmax - xmin, ymax - ymin
    if not (max(w, h) > 0):
        raise PolyfoldError("FOLD net has zero size, cannot draw it")
    m = max(4, round(0.03 * width_px))
    avail = width_px - 2 * m
    s = avail / w if w > 0 else avail / h
    max_h = 4 * width_px
    if h * s + 2 * m > max_h:
        s = (max_h - 2 * m) / h
    height = int(math.ceil(h * s + 2 * m))
    return _Raster(s, width_px, height, (width_px - w * s) / 2, (height - h * s) / 2, xmin, ymax)


def _piece_color(piece: int) -> tuple[int, int, int]:
    """Light fill colour of a piece in the PNG preview (hue by golden-ratio steps)."""
    r, g, b = colorsys.hsv_to_rgb((0.08 + 0.618033988749895 * int(piece)) % 1.0, 0.28, 0.98)
    return int(round(r * 255)), int(round(g * 255)), int(round(b * 255))


def _draw_segments(img: np.ndarray, seg: np.ndarray, color, thick: int) -> None:
    if len(seg) == 0:
        return
    H, W = img.shape[:2]
    a, b = seg[:, 0], seg[:, 1]
    length = np.hypot(*(b - a).T)
    counts = np.ceil(length / 0.5).astype(np.int64) + 1
    idx = np.repeat(np.arange(len(seg)), counts)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    t = (np.arange(counts.sum()) - starts) / np.repeat(np.maximum(counts - 1, 1), counts)
    pts = a[idx] + t[:, None] * (b - a)[idx]
    offs = [0.0] if thick <= 1 else [-0.5, 0.5]
    for dx in offs:
        for dy in offs:
            ix = np.floor(pts[:, 0] + dx).astype(np.int64)
            iy = np.floor(pts[:, 1] + dy).astype(np.int64)
            ok = (ix >= 0) & (ix < W) & (iy >= 0) & (iy < H)
            img[iy[ok], ix[ok]] = color


def write_png(fold: dict, path, *, width_px: int = 1200) -> None:
    """Write a PNG preview: faces filled (one light hue per piece), cuts black, mountains red, valleys blue."""
    net = _parse(fold)
    r = _raster_layout(net, width_px)
    img = np.full((r.height, r.width, 3), 255, dtype=np.uint8)
    xy = r.to_px(net.coords)
    cols = np.array([_piece_color(p) for p in range(int(net.pieces.max()) + 1)], dtype=np.uint8)
    fill_triangles(img, xy[net.faces], cols[net.pieces])
    for k, thick in (("crease", 1), ("valley", 1), ("mountain", 1), ("cut", 2)):
        sel = [e for e, kk in enumerate(net.kind) if kk == k]
        if sel:
            _draw_segments(img, xy[net.edges[sel]], _PNG_COLORS[k], thick)
    atomic_write(path, png_bytes(img))
