"""Labels printed on the pieces, in mm (y down): the glue label beside each side of a glued edge
and the piece's name, all readable and none overlapping another label or a line.

Size: every glue label has the same font size, `label_font(min_cap_mm)`, whose cap height is the
least asked for (`--min-label-mm`, default paper.MIN_LABEL_MM); never smaller. Where a glue
label goes, in order:
1. inside its face, along the edge (at the middle of the edge, then nearer its ends, then at the
   face's incentre);
2. on the side's glue tab, when this side carries it;
3. just outside the edge (beyond the tab on the side that has one), clear of the piece's faces,
   tabs and labels and nearer the edge than any other cut side of the piece (`cut_sides`), else
   a little further in a free spot with a leader line from the edge: an
   off-face label, which the packer keeps clear of other pieces (`SheetPiece.footprint`), never
   further out than the tab room around the piece's convex hull (`tabs.TAB_ROOM_MM`), which
   fitting pieces to the page reserves;
4. else the free spot nearest the edge, up to ELSEWHERE_MM away: off the faces as in 3, or inside
   any face of the piece, its leader line crossing the piece's lines if it must (never a label);
   where no straight leader gets out between the labels around, a bent one (straight stretches
   through the gaps, found breadth first on the piece's raster: `_Taken.routed_near`);
5. when nothing fits: inside the face at the centroid, counted in `LabelStats.unplaced` and
   listed in `crowded` (make cuts such a piece there and draws it again:
   `pipeline.sheets._split_for_labels`).
Every box keeps LABEL_PAD_MM from the lines around it and from other labels.

One label may stand for a seam run (`PieceLabels.run`, chosen by `pieces.build_sheet_pieces`
when a label per edge does not fit): consecutive sides of one copy, the label beside any of them
(stages 1-3 from the middle side out, then 4), a tick (TICK_MM) into the face at both ends.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from ..jit import njit
from .overlap_kernels import first_box_in_triangle, first_clear_box, first_leader_spot, point_segment_distance
from .page import TextItem, upright
from .paper import CAP_HEIGHT
from .tabs import OVERLAP_MM2, TAB_CLEAR_MM, TAB_ROOM_MM, CutSide, Room

PIECE_FONT_MAX_MM = 6.0  # a piece's name may be larger, up to this, where its face has room
LABEL_PAD_MM = 0.25  # gap between a label's glyph box and any line or other label
CELL_MM = 10.0  # cell size of the label boxes' spatial hash
LEADER_STEPS_MM = (2.0, 5.0, 9.0, 14.0)  # how far an off-face label with a leader may sit from its edge
LEADER_HALF_MM = 0.1  # half the width of a leader line (clearance it needs)
ELSEWHERE_MM = 30.0  # the last resort: a label this far from its edge, its leader crossing the piece
FREE_CELL_MM = 0.2  # cell of the raster of what is taken on a piece, which finds those spots
ELSEWHERE_TRIES = 40  # most spots checked exactly per label (nearest first)
LEADER_STEP_MM = 0.4  # a leader is looked up in the raster at points this far apart
LEADER_TRIES = 1000  # most spots whose leader is checked against the raster (nearest first)
ELSEWHERE_GIVE_UP = 20  # a piece where this many labels found no spot is too crowded to look further
TICK_MM = 1.5  # a seam run's end mark, from the outline into the face
# `PieceLabels._outside`'s spots: along the edge (t of its length), and the turns of a leader's
# direction from the edge's outward normal (cos, sin of 0, 30, -30, 60, -60 degrees, as math has them)
_ALONG = np.array([0.5, 0.35, 0.65, 0.2, 0.8])
# where a leader of ELSEWHERE_MM at most is looked up in the raster (fractions of its length)
_LEADER_T = np.linspace(0.0, 1.0, int(math.ceil(ELSEWHERE_MM / LEADER_STEP_MM)) + 1)
_TURNS = np.array([(math.cos(math.radians(t)), math.sin(math.radians(t))) for t in (0.0, 30.0, -30.0, 60.0, -60.0)])
SCREEN_MARGIN_MM = 1e-6  # what a compiled screen of spots leaves undecided on either side of a test's bound
# a leader's strip (shapely's buffer of it, LEADER_HALF_MM, 8 segments a quarter circle) holds every
# point this near its line: a label box this near is surely hit
_LEADER_STRIP_MM = LEADER_HALF_MM * math.cos(math.pi / 32) - SCREEN_MARGIN_MM


def label_font(min_cap_mm: float) -> float:
    """Font size (em, mm) of every glue label: the one whose cap height is `min_cap_mm` (larger
    labels would take room that smaller faces need)."""
    return min_cap_mm / CAP_HEIGHT


def piece_name(i: int) -> str:
    """A, B, ..., Z, AA, AB, ... (short ids printed on the pieces) for piece index i."""
    s = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        s = chr(65 + r) + s
    return s


@functools.lru_cache(maxsize=4096)  # (a label's spots all ask for its width)
def text_width(text: str, size: float) -> float:
    """Printed width (mm) of `text` at font `size` (mm) in Helvetica, the font of the PDF and the
    first of the SVG's (Arial, the usual stand-in, has the same widths): the advance widths of
    the font's metrics as reportlab, which draws the PDF, has them (its stringWidth: the same
    float; ASCII text from its width table, `_ascii_widths`: `width_key`)."""
    summed = width_key(text)
    if isinstance(summed, int):
        return summed * 0.001 * size  # (as stringWidth sums and scales)
    from reportlab.pdfbase.pdfmetrics import stringWidth

    return float(stringWidth(text, "Helvetica", size))


def width_key(text: str) -> int | str:
    """All that a label's place depends on of its text, as a dict key: every test of a spot sees
    the text only as a `text_width` box, so the sum of its glyphs' advance widths (1/1000 em)
    where `text_width` sums them (ASCII; glue numbers are digits, all as wide in Helvetica), else
    the text itself."""
    widths = _ascii_widths()
    return sum(map(widths.__getitem__, text)) if all(c in widths for c in text) else text


@functools.lru_cache(maxsize=1)
def _ascii_widths() -> dict[str, int]:
    """Helvetica's advance widths (1/1000 em) of the printable ASCII characters, from reportlab's
    font data: {character: width}; {} where reportlab keeps them elsewhere. Importing its metrics
    module (stringWidth) takes a layout 50 ms, these two 5 ms; the PDF's encoding (WinAnsi) puts
    printable ASCII at its own code points."""
    try:
        from reportlab.pdfbase._fontdata_enc_winansi import WinAnsiEncoding
        from reportlab.pdfbase._fontdata_widths_helvetica import widths
    except ImportError:
        return {}
    return {chr(i): widths[WinAnsiEncoding[i]] for i in range(32, 127)
            if WinAnsiEncoding[i] in widths}


def text_box(center: np.ndarray, u: np.ndarray, text: str, size: float) -> np.ndarray:
    """The 4 corners (4, 2) of the glyph box of `text` at font `size` centred at `center`, its
    reading direction the unit vector u: `text_width` wide, a cap height high."""
    return text_boxes(np.asarray(center, dtype=float)[None], u, text, size)[0]


def text_boxes(centers: np.ndarray, u: np.ndarray, text: str, size: float) -> np.ndarray:
    """(k, 4, 2) `text_box` at each of the centres (k, 2)."""
    n = np.array([-u[1], u[0]])
    hw, hh = text_width(text, size) / 2, CAP_HEIGHT * size / 2
    a, b = hw * u, hh * n
    return np.stack([centers - a - b, centers + a - b, centers + a + b, centers - a + b], axis=1)


def inside_triangle(tri: np.ndarray, pts: np.ndarray, pad: float) -> bool:
    """All points inside triangle `tri` (either orientation), at least `pad` from its sides."""
    a, b, c = tri
    area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    sgn = 1.0 if area2 > 0 else -1.0
    for p, q in ((a, b), (b, c), (c, a)):
        e = q - p
        ln = math.hypot(e[0], e[1])
        if ln == 0:
            return False
        d = sgn * (e[0] * (pts[:, 1] - p[1]) - e[1] * (pts[:, 0] - p[0])) / ln
        if (d < pad).any():
            return False
    return True


def _box_cells(boxes: np.ndarray) -> np.ndarray:
    """(k, 4) `_cell_range` of each box (k, m, 2)'s corners, as `_Boxes._keys` finds them."""
    lo, hi = np.floor_divide(boxes.min(axis=1), CELL_MM), np.floor_divide(boxes.max(axis=1), CELL_MM)
    return np.stack([lo[:, 0], hi[:, 0], lo[:, 1], hi[:, 1]], axis=1).astype(np.int64)


class _Rings:
    """Every geometry placed in a `_Boxes`, as `overlap_kernels.first_clear_box` reads them: the
    points of each one's ring (`pts`, `ring_ptr`; none and has_ring False for a geometry that is
    not one simple polygon) and the range of hash cells it was put in (`cells`: first and last
    column, first and last row). Arrays grow by doubling; the first n rows are the items."""

    def __init__(self) -> None:
        self.pts, self.ring_ptr = np.zeros((16, 2)), np.zeros(9, dtype=np.int64)
        self.cells, self.has_ring = np.zeros((8, 4), dtype=np.int64), np.zeros(8, dtype=bool)
        self.n = self.n_pts = 0

    def add(self, ring: np.ndarray | None, cells: tuple[int, int, int, int]) -> None:
        k = 0 if ring is None else len(ring)
        if self.n_pts + k > len(self.pts):
            self.pts = np.concatenate([self.pts, np.zeros((max(self.n_pts + k, 2 * len(self.pts)) - len(self.pts), 2))])
        if self.n + 1 >= len(self.cells):
            more = len(self.cells)
            self.cells = np.concatenate([self.cells, np.zeros((more, 4), dtype=np.int64)])
            self.has_ring = np.concatenate([self.has_ring, np.zeros(more, dtype=bool)])
            self.ring_ptr = np.concatenate([self.ring_ptr, np.zeros(more, dtype=np.int64)])
        if k:
            self.pts[self.n_pts:self.n_pts + k] = ring
        self.n_pts += k
        self.cells[self.n] = cells
        self.has_ring[self.n] = ring is not None
        self.n += 1
        self.ring_ptr[self.n] = self.n_pts


def _cell_range(x0: float, y0: float, x1: float, y1: float) -> tuple[int, int, int, int]:
    """First and last column, first and last row of the CELL_MM hash cells a box with these
    bounds lies in."""
    return int(x0 // CELL_MM), int(x1 // CELL_MM), int(y0 // CELL_MM), int(y1 // CELL_MM)


@dataclass(eq=False)
class _Boxes:
    """Label boxes placed on one piece, in a spatial hash of CELL_MM cells (and in `rings`, for
    compiled tests)."""

    cells: dict = field(default_factory=dict)
    count: int = 0  # boxes placed (their ids)
    rings: _Rings = field(default_factory=_Rings)

    def _keys(self, box: np.ndarray):
        xs, ys = box[:, 0].tolist(), box[:, 1].tolist()  # (Python's min of a few floats: no numpy call)
        x0, x1, y0, y1 = _cell_range(min(xs), min(ys), max(xs), max(ys))
        return [(i, j) for i in range(x0, x1 + 1) for j in range(y0, y1 + 1)]

    def at(self, corners: np.ndarray) -> list:
        """The placed geometries in the cells of the points `corners` (k, 2)' bounding box, each
        once, in the order they were placed per cell (what `hits` tests against)."""
        return [geom for geom, _ring in self._items_at(corners)]

    def _items_at(self, corners: np.ndarray) -> list:
        seen: set[int] = set()
        out = []
        for key in self._keys(corners):
            for i, other, ring in self.cells.get(key, ()):
                if i not in seen:
                    seen.add(i)
                    out.append((other, ring))
        return out

    def hits(self, box: np.ndarray) -> bool:
        """True when `box` (4, 2), grown by LABEL_PAD_MM, meets a placed box."""
        return _grown_box_hits(box, self._items_at(box))

    def hits_geom(self, geom) -> bool:
        """True when a shapely geometry meets a placed box."""
        import shapely

        x0, y0, x1, y1 = geom.bounds
        near = self.at(np.array([[x0, y0], [x1, y1]]))
        return bool(near) and bool(shapely.intersects(geom, np.array(near, dtype=object)).any())

    def add(self, box: np.ndarray) -> None:
        from shapely.geometry import Polygon

        self.add_geom(Polygon(box), np.array(box, dtype=float))

    def add_geom(self, geom, ring: np.ndarray | None = None) -> None:
        """Place a shapely geometry (a label box, a leader line's strip); `ring`: its outline
        (k, 2) when it is one simple polygon (a strip's is read from it)."""
        if ring is None and geom.geom_type == "Polygon" and not geom.interiors:
            ring = np.asarray(geom.exterior.coords)[:-1]
        x0, y0, x1, y1 = geom.bounds
        item = (self.count, geom, ring)
        self.count += 1
        for key in self._keys(np.array([[x0, y0], [x1, y1]])):
            self.cells.setdefault(key, []).append(item)
        self.rings.add(ring, _cell_range(x0, y0, x1, y1))


def _grown_box_hits(box: np.ndarray, near: list) -> bool:
    """Whether the label box (4, 2) grown by LABEL_PAD_MM meets any of the geometries `near`
    ((shapely geometry, its ring or None) pairs; grown only when there are any: most candidate
    spots have none around). Told by compiled tests (`overlap_kernels.grown_box_meets`, then
    `grown_box_apart`) where they can, else by shapely's buffer (quad_segs=1) and intersects."""
    if not near:
        return False
    import shapely

    if all(ring is not None for _geom, ring in near):
        from .overlap_kernels import grown_box_apart, grown_box_meets

        rings = [ring for _geom, ring in near]
        ptr = np.array([0, *itertools.accumulate(len(r) for r in rings)], dtype=np.int64)
        box, pts = np.ascontiguousarray(box, dtype=float), np.concatenate(rings)
        answer = grown_box_meets(box, LABEL_PAD_MM, pts, ptr)
        if answer >= 0:
            return bool(answer)
        if grown_box_apart(box, LABEL_PAD_MM, pts, ptr):  # (a strip or box near a corner, not touching)
            return False
    grown = shapely.Polygon(box).buffer(LABEL_PAD_MM, quad_segs=1)
    return bool(shapely.intersects(grown, np.array([geom for geom, _ring in near], dtype=object)).any())


@dataclass
class LabelStats:
    """Where the glue labels went: on a tab, outside their edge, or nowhere readable (`unplaced`:
    at the face's centroid, over lines or labels)."""

    on_tabs: int = 0
    outside: int = 0
    unplaced: int = 0
    runs: int = 0  # labels that stand for a seam run of several edges (`PieceLabels.run`)


def _nearest_on(poly, p: np.ndarray) -> np.ndarray:
    """The point of a label box's outline nearest p (where a leader from p ends)."""
    from shapely.geometry import Point

    ring = poly.exterior
    return np.asarray(ring.interpolate(ring.project(Point(*p))).coords[0])


@njit(cache=True)
def _nearer_than_others(pts, segments, own, pad):
    """(k,) bool: per point of pts (k, 2), whether every segment of `segments` (m, 2, 2) other
    than `own` (2, 2) (either way round, to 1e-9) is farther from it than `own` by more than pad.
    Each distance is numpy's of the nearest point on the segment, to the last bit: t = ((p - a) .
    ab) / max(ab . ab, 1e-300) clipped to [0, 1], then the norm of a + t ab - p."""
    other = np.empty(len(segments), dtype=np.bool_)
    for k in range(len(segments)):
        a0, a1, b0, b1 = segments[k, 0, 0], segments[k, 0, 1], segments[k, 1, 0], segments[k, 1, 1]
        same = max(abs(a0 - own[0, 0]), abs(a1 - own[0, 1]), abs(b0 - own[1, 0]), abs(b1 - own[1, 1])) < 1e-9
        swapped = max(abs(a0 - own[1, 0]), abs(a1 - own[1, 1]), abs(b0 - own[0, 0]), abs(b1 - own[0, 1])) < 1e-9
        other[k] = not (same or swapped)
    out = np.ones(len(pts), dtype=np.bool_)
    for i in range(len(pts)):
        limit = point_segment_distance(pts[i, 0], pts[i, 1], own[0, 0], own[0, 1], own[1, 0], own[1, 1]) + pad
        for k in range(len(segments)):
            if other[k] and not point_segment_distance(pts[i, 0], pts[i, 1], segments[k, 0, 0], segments[k, 0, 1],
                                                  segments[k, 1, 0], segments[k, 1, 1]) > limit:
                out[i] = False
                break
    return out


def _end_away(side: CutSide, neighbour: CutSide) -> np.ndarray:
    """The end of `side` away from `neighbour`, the next side along the same run (they share
    the other end)."""
    ends = np.array([neighbour.p0, neighbour.p1])
    d0, d1 = (float(np.min(np.linalg.norm(ends - p, axis=1))) for p in (side.p0, side.p1))
    return side.p0 if d0 > d1 else side.p1


def _incentre(tri: np.ndarray) -> np.ndarray:
    a, b, c = tri
    la, lb, lc = np.linalg.norm(b - c), np.linalg.norm(c - a), np.linalg.norm(a - b)
    return (la * a + lb * b + lc * c) / max(la + lb + lc, 1e-300)


def _angle(u: np.ndarray) -> float:
    """Reading angle (degrees CCW as seen on a y-down page) of direction u, never upside down."""
    return upright(math.degrees(math.atan2(-u[1], u[0])))


def _reading(u: np.ndarray) -> np.ndarray:
    """The direction u or -u that the text reads along (the upright one)."""
    a = math.radians(_angle(u))
    return np.array([math.cos(a), -math.sin(a)])


def _half_cells(size: float) -> int:
    """Cells a box reaches on each side of its centre cell along a side `size` mm long."""
    return int(math.ceil(size / 2 / FREE_CELL_MM - 1e-9))


@njit(cache=True)
def _box_free(taken, hw, hh):
    """(ny, nx) bool: the cells of `taken` (ny, nx) that centre a box of 2 hh + 1 rows by 2 hw + 1
    columns (`_half_cells` of a box's height and width) that lies inside the raster and holds no
    True cell, counted by a summed-area table (int32, as numpy's cumulative sums would make it)."""
    ny, nx = taken.shape
    out = np.zeros((ny, nx), dtype=np.bool_)
    kh, kw = 2 * hh + 1, 2 * hw + 1
    if ny < kh or nx < kw:
        return out
    table = np.zeros((ny + 1, nx + 1), dtype=np.int32)
    for r in range(ny):
        row = 0
        for c in range(nx):
            row += taken[r, c]
            table[r + 1, c + 1] = table[r, c + 1] + row
    for r in range(ny - kh + 1):
        for c in range(nx - kw + 1):
            count = table[r + kh, c + kw] - table[r, c + kw] - table[r + kh, c] + table[r, c]
            out[r + hh, c + hw] = count == 0
    return out


@njit(cache=True)
def _refresh_free(free, taken, windows, hw, hh):
    """`_box_free` (taken, hw, hh) written into free (ny, nx) again where cells in windows (k, 4:
    first and last row, first and last column) may have been taken: at the centres whose boxes
    reach them, each window's from the cells those boxes cover."""
    ny, nx = taken.shape
    for k in range(windows.shape[0]):
        r0, r1, c0, c1 = windows[k, 0], windows[k, 1], windows[k, 2], windows[k, 3]
        t0, t1, u0, u1 = max(0, r0 - hh), min(ny - 1, r1 + hh), max(0, c0 - hw), min(nx - 1, c1 + hw)
        s0, s1, v0, v1 = max(0, t0 - hh), min(ny - 1, t1 + hh), max(0, u0 - hw), min(nx - 1, u1 + hw)
        part = _box_free(np.ascontiguousarray(taken[s0:s1 + 1, v0:v1 + 1]), hw, hh)
        for r in range(t0, t1 + 1):  # (a loop, not a slice assignment: see polyfold.arrays)
            for c in range(u0, u1 + 1):
                free[r, c] = part[r - s0, c - v0]


@njit(cache=True)
def _grid_bfs(free, sr, sc, max_steps, ok, want):
    """Breadth-first search over the True cells of `free` (ny, nx) from cell (sr, sc), 8
    neighbours, at most max_steps steps: (steps to each cell, -1 unreached; (n, 3) the first
    `want` cells reached, in the order reached, that are True in a layer k of ok (K, ny, nx), as
    (k, row, col))."""
    ny, nx = free.shape
    dist = np.full((ny, nx), -1, dtype=np.int32)
    queue = np.empty((ny * nx, 2), dtype=np.int64)
    found = np.empty((want, 3), dtype=np.int64)
    n_found = 0
    dist[sr, sc] = 0
    queue[0, 0], queue[0, 1] = sr, sc
    head, tail = 0, 1
    while head < tail and n_found < want:
        r, c = queue[head, 0], queue[head, 1]
        head += 1
        d = dist[r, c]
        if d >= max_steps:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if 0 <= rr < ny and 0 <= cc < nx and dist[rr, cc] < 0 and free[rr, cc]:
                    dist[rr, cc] = d + 1
                    queue[tail, 0], queue[tail, 1] = rr, cc
                    tail += 1
                    for k in range(ok.shape[0]):
                        if ok[k, rr, cc] and n_found < want:
                            found[n_found, 0], found[n_found, 1], found[n_found, 2] = k, rr, cc
                            n_found += 1
    return dist, found[:n_found]


@njit(cache=True)
def _path_back(dist, r, c):
    """(n, 2) the cells (row, column) from (r, c) back to the cell at distance 0 of `dist` (ny, nx:
    `_grid_bfs`'s steps, -1 unreached), each step to the first neighbour one step nearer in the
    order right, down, left, up, then the diagonals (down-right, down-left, up-right, up-left)."""
    ny, nx = dist.shape
    steps = ((0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))
    out = np.empty((dist[r, c] + 1, 2), dtype=np.int64)
    out[0, 0], out[0, 1] = r, c
    k = 0
    while dist[r, c] > 0:
        d = dist[r, c]
        for dr, dc in steps:
            rr, cc = r + dr, c + dc
            if 0 <= rr < ny and 0 <= cc < nx and dist[rr, cc] == d - 1:
                r, c = rr, cc
                break
        k += 1
        out[k, 0], out[k, 1] = r, c
    return out


@njit(cache=True)
def _path_turns(pts, texts, origin, inv_cell, step):
    """Indices of the points of a path pts (n, 2) kept at its turns: from each kept point the
    farthest later one whose straight stretch crosses no True cell of `texts` (ny, nx), looked up
    at ceil(length / step) + 1 points spaced as numpy's linspace spaces t from 0 to 1, each in
    the cell (column, row) = int((point - origin) inv_cell), clipped to the raster (as
    `_Taken._cells`, `_taken_at`); the next point when none is."""
    n = pts.shape[0]
    keep = np.empty(n, dtype=np.int64)
    keep[0] = 0
    m = 1
    while keep[m - 1] < n - 1:
        i = keep[m - 1]
        j = n - 1
        while j > i + 1:
            dx, dy = pts[j, 0] - pts[i, 0], pts[j, 1] - pts[i, 1]
            count = int(math.ceil(math.sqrt(dx * dx + dy * dy) / step)) + 1
            delta = 1.0 / (count - 1) if count > 1 else 0.0
            clear = True
            for q in range(count):
                t = 1.0 if (q == count - 1 and count > 1) else q * delta
                if _taken_at(texts, pts[i, 0] + t * dx, pts[i, 1] + t * dy, origin, inv_cell):
                    clear = False
                    break
            if clear:
                break
            j -= 1
        keep[m] = j
        m += 1
    return keep[:m]


@njit(cache=True)
def _dilated(cells, disc):
    """(ny, nx) bool: `cells` (ny, nx) bool grown by the symmetric structure `disc` (2r + 1, 2r + 1)
    bool centred on each True cell, nothing beyond the raster (scipy.ndimage's binary_dilation)."""
    ny, nx = cells.shape
    r = disc.shape[0] // 2
    out = np.zeros((ny, nx), dtype=np.bool_)
    for y in range(ny):
        for x in range(nx):
            if cells[y, x]:
                for dy in range(-r, r + 1):
                    for dx in range(-r, r + 1):
                        yy, xx = y + dy, x + dx
                        if disc[dy + r, dx + r] and 0 <= yy < ny and 0 <= xx < nx:
                            out[yy, xx] = True
    return out


@njit(cache=True)
def _enclosed(walls):
    """(ny, nx) bool: the cells not in `walls` (ny, nx) bool that no path of such cells, from each
    to one of its 4 side neighbours, joins to the raster's border (the components of scipy.ndimage's
    `label` that touch no border)."""
    ny, nx = walls.shape
    outer = np.zeros((ny, nx), dtype=np.bool_)
    stack = np.empty((ny * nx, 2), dtype=np.int32)
    n = 0
    for y in range(ny):
        for x in range(nx):
            if (y == 0 or y == ny - 1 or x == 0 or x == nx - 1) and not walls[y, x] and not outer[y, x]:
                outer[y, x] = True
                stack[n, 0], stack[n, 1] = y, x
                n += 1
    while n:
        n -= 1
        y, x = stack[n, 0], stack[n, 1]
        for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            yy, xx = y + dy, x + dx
            if 0 <= yy < ny and 0 <= xx < nx and not walls[yy, xx] and not outer[yy, xx]:
                outer[yy, xx] = True
                stack[n, 0], stack[n, 1] = yy, xx
                n += 1
    out = np.zeros((ny, nx), dtype=np.bool_)
    for y in range(ny):
        for x in range(nx):
            out[y, x] = not walls[y, x] and not outer[y, x]
    return out


@njit(cache=True, inline="always")
def _taken_at(texts, x, y, origin, inv_cell):
    """Whether the cell (column, row) = int((x, y) - origin) inv_cell of texts (ny, nx), clipped to
    the raster (as `_Taken._cells`), is True."""
    ny, nx = texts.shape
    c = min(max(np.int32((x - origin[0]) * inv_cell), 0), nx - 1)
    r = min(max(np.int32((y - origin[1]) * inv_cell), 0), ny - 1)
    return texts[r, c]


@njit(cache=True, inline="always")
def _leader_clear(texts, origin, inv_cell, p, x, y, t):
    """Whether the leader from p to (x, y) crosses no True cell of `texts` (ny, nx): looked up at
    the points p + t ((x, y) - p), each in the cell (column, row) = int((point - origin) inv_cell),
    clipped to the raster (as `_Taken._cells`), and given up at its first taken point."""
    for j in range(len(t)):
        if _taken_at(texts, p[0] + t[j] * (x - p[0]), p[1] + t[j] * (y - p[1]), origin, inv_cell):
            return False
    return True


# `_clear_near`'s rings around a point, their outer radii (mm, squared; the last ELSEWHERE_MM's):
# a search that finds a spot near its point scans only the rings out to it
_RINGS2 = np.array([6.0, 12.0, 20.0, ELSEWHERE_MM]) ** 2


@njit(cache=True)
def _scan_ring(free_a, free_b, in_faces, r0, r1, c0, c1, origin, p, cell, lo2, hi2, found, counts):
    """Append to four lists the cells of rows r0..r1 and columns c0..c1 (inclusive) whose squared
    distance dd from p (their centres origin + (column or row + 0.5) cell) has lo2 < dd <= hi2
    and that are True in free_a, free_b (ny, nx), in `in_faces` or not: (a, in a face), (b, in a
    face), (a, off the faces), (b, off the faces), found[q, counts[q]:] (4, n, 3: x, y, dd),
    counts (4,) advanced; in row order (numpy's nonzero). Rows and columns that cannot reach the
    ring are not read, nor the columns of a row well inside its inner circle."""
    inv_cell = 1.0 / cell
    radius = math.sqrt(hi2)
    # rows and columns whose centres may lie within the outer radius (a cell wider)
    ra = max(r0, int(math.floor((p[1] - radius - origin[1]) * inv_cell - 0.5)) - 1)
    rb = min(r1, int(math.ceil((p[1] + radius - origin[1]) * inv_cell - 0.5)) + 1)
    ca = max(c0, int(math.floor((p[0] - radius - origin[0]) * inv_cell - 0.5)) - 1)
    cb = min(c1, int(math.ceil((p[0] + radius - origin[0]) * inv_cell - 0.5)) + 1)
    for r in range(ra, rb + 1):
        y = origin[1] + (r + 0.5) * cell
        dy = y - p[1]
        # the columns inside the inner circle, a cell narrower on each side, are skipped
        skip0, skip1 = 1, 0
        if lo2 > dy * dy:
            half = math.sqrt(lo2 - dy * dy)
            skip0 = int(math.ceil((p[0] - half - origin[0]) * inv_cell - 0.5)) + 1
            skip1 = int(math.floor((p[0] + half - origin[0]) * inv_cell - 0.5)) - 1
        c = ca
        while c <= cb:
            if skip0 <= c <= skip1:
                c = skip1 + 1
                continue
            a, b = free_a[r, c], free_b[r, c]
            if a or b:
                x = origin[0] + (c + 0.5) * cell
                dx = x - p[0]
                dd = dx * dx + dy * dy
                if lo2 < dd <= hi2:
                    off = 0 if in_faces[r, c] else 2
                    for k in range(2):
                        if (a, b)[k]:
                            q = off + k
                            i = counts[q]
                            found[q, i, 0], found[q, i, 1], found[q, i, 2] = x, y, dd
                            counts[q] = i + 1
            c += 1


@njit(cache=True)
def _clear_near(free_a, free_b, in_faces, r0, r1, c0, c1, origin, p, cell, rings2, q, state, scanned, found, counts,
                ring_end, tries, texts, t, want):
    """The next batch of free cells of list q (`_scan_ring`'s: 0, 1 free_a, free_b in a face; 2,
    3 off the faces) whose leader from p crosses no label (`_leader_clear`, cells of 1 / cell),
    looked at nearest first (the order of numpy's stable argsort of the distances of numpy's
    nonzero, found bucket by bucket: what a search that ends early did not read is not sorted) up
    to squared distance rings2[-1], at most `tries` of them, until `want` are found clear. Ring
    by ring (rings2: their squared outer radii): list q from ring state[0], state[1]
    cells looked at and state[2] found so far (updated here); the rings are scanned once for
    all four lists when first needed (scanned[0] of them so far: found, counts as `_scan_ring`
    fills them; ring_end (4, rings): the lists' lengths after each ring). Returns the centres
    (m, 2) of those found clear in the first ring that has any, in order; none (0, 2) when the
    search of list q is over."""
    inv_cell = 1.0 / cell
    while state[0] < rings2.shape[0]:
        k = state[0]
        state[0] = k + 1
        while scanned[0] <= k:
            j = scanned[0]
            _scan_ring(free_a, free_b, in_faces, r0, r1, c0, c1, origin, p, cell, rings2[j - 1] if j > 0 else -1.0,
                       rings2[j], found, counts)
            for g in range(4):
                ring_end[g, j] = counts[g]
            scanned[0] = j + 1
        lo, hi = ring_end[q, k - 1] if k > 0 else 0, ring_end[q, k]
        n = hi - lo
        out = np.empty((min(n, want), 2))
        m = 0
        if n == 0:
            continue
        # nearest first: the ring's cells counted into buckets of squared distance (row order kept
        # within each), each bucket sorted by insertion (stable) when reached
        base = max(rings2[k - 1], 0.0) if k > 0 else 0.0
        n_buckets = max(1, n // 4)
        scale = n_buckets / max(rings2[k] - base, 1e-300)
        start = np.zeros(n_buckets + 1, dtype=np.int64)
        bucket = np.empty(n, dtype=np.int64)
        for i in range(n):
            b = min(max(int((found[q, lo + i, 2] - base) * scale), 0), n_buckets - 1)
            bucket[i] = b
            start[b + 1] += 1
        for b in range(n_buckets):
            start[b + 1] += start[b]
        fill = start[:n_buckets].copy()
        perm = np.empty(n, dtype=np.int64)
        for i in range(n):
            perm[fill[bucket[i]]] = lo + i
            fill[bucket[i]] += 1
        done = False
        for b in range(n_buckets):
            s, e = start[b], start[b + 1]
            for j in range(s + 1, e):
                i = perm[j]
                v = found[q, i, 2]
                h = j - 1
                while h >= s and found[q, perm[h], 2] > v:
                    perm[h + 1] = perm[h]
                    h -= 1
                perm[h + 1] = i
            for j in range(s, e):
                if state[1] >= tries or state[2] >= want:
                    done = True
                    break
                state[1] += 1
                i = perm[j]
                if _leader_clear(texts, origin, inv_cell, p, found[q, i, 0], found[q, i, 1], t):
                    out[m, 0], out[m, 1] = found[q, i, 0], found[q, i, 1]
                    m += 1
                    state[2] += 1
            if done:
                break
        if state[1] >= tries or state[2] >= want:
            state[0] = rings2.shape[0]
        if m:
            return out[:m]
    return np.empty((0, 2))


class _Taken:
    """A raster (FREE_CELL_MM cells) of what a label may not touch on one piece, for finding free
    spots fast: every face side (outline, creases and the sides inside flat polygons alike),
    labels and leaders grown by LABEL_PAD_MM, the piece's tabs and off-face labels grown by
    TAB_CLEAR_MM, and everything outside `PieceLabels.allowed`. Cells are taken by their
    centres, so a box clear of them all is only likely to fit: the caller checks it exactly
    (inside one face, or off the faces by TAB_CLEAR_MM)."""

    def __init__(self, labels: "PieceLabels") -> None:
        import shapely

        x0, y0, x1, y1 = labels.allowed.bounds
        self.origin = np.array([x0, y0])
        nx, ny = int(math.ceil((x1 - x0) / FREE_CELL_MM)) + 1, int(math.ceil((y1 - y0) / FREE_CELL_MM)) + 1
        cx = x0 + (np.arange(nx) + 0.5) * FREE_CELL_MM
        cy = y0 + (np.arange(ny) + 0.5) * FREE_CELL_MM
        # outside `allowed` (convex): per row of cell centres, left and right of where it crosses
        ring = np.asarray(labels.allowed.exterior.coords)
        a, b = ring[:-1], ring[1:]
        span = (np.minimum(a[:, 1], b[:, 1])[None, :] <= cy[:, None]) & (cy[:, None] <= np.maximum(a[:, 1], b[:, 1])[None, :])
        t = (cy[:, None] - a[None, :, 1]) / np.where(b[:, 1] == a[:, 1], 1.0, b[:, 1] - a[:, 1])[None, :]
        x = a[None, :, 0] + np.clip(t, 0.0, 1.0) * (b - a)[None, :, 0]
        lo, hi = np.where(span, x, np.inf).min(axis=1), np.where(span, x, -np.inf).max(axis=1)
        self.grid = (cx[None, :] < lo[:, None]) | (cx[None, :] > hi[:, None])  # (ny, nx), True = taken
        self.texts = np.zeros_like(self.grid)  # the labels alone (a leader may not cross them)
        self._last = np.array([nx - 1, ny - 1], dtype=np.int32)
        self._free: dict[tuple[int, int], np.ndarray] = {}  # `free`'s maps by half box size in cells
        self._pending: list[tuple[object, float, bool]] = []  # (geometry, grow, into texts) to mark: `_flush`
        # face sides: points every half cell along them, then grown by a disc
        tri = shapely.get_coordinates(np.asarray(labels.room.faces, dtype=object)).reshape(-1, 4, 2)[:, :3]
        self.tris = np.ascontiguousarray(tri)  # (the faces' triangles, for `PieceLabels._leader_spots`)
        a, b = tri.reshape(-1, 2), np.roll(tri, -1, axis=1).reshape(-1, 2)
        steps = np.maximum(np.ceil(np.linalg.norm(b - a, axis=1) / (0.5 * FREE_CELL_MM)).astype(int), 1)
        # np.linspace(0, 1, k + 1) of each side, at once: i (1 / k), the last 1
        which = np.repeat(np.arange(len(a)), steps + 1)
        first = np.cumsum(steps + 1) - (steps + 1)
        t = (np.arange(len(which)) - first[which]) * (1.0 / steps)[which]
        t[first + steps] = 1.0
        pts = a[which] + t[:, None] * (b - a)[which]
        lines = np.zeros_like(self.grid)
        ij = self._cells(pts)
        lines[ij[:, 1], ij[:, 0]] = True
        r = int(round(LABEL_PAD_MM / FREE_CELL_MM))
        disc = np.hypot(*np.mgrid[-r:r + 1, -r:r + 1]) <= r
        lines = _dilated(lines, disc)
        self.grid |= lines
        # inside the faces: the cells the face sides enclose (not joined to the raster's border)
        self.in_faces = _enclosed(lines)
        for g in labels.room.extra:
            self.mark(g, TAB_CLEAR_MM)
        everywhere = np.array([[x0, y0], [x1, y1]])
        for g in labels.boxes.at(everywhere):
            self.mark(g, LABEL_PAD_MM, text=True)
        for g in labels.strips.at(everywhere):
            self.mark(g, LABEL_PAD_MM)

    def _cells(self, pts: np.ndarray) -> np.ndarray:
        """(k, 2) column, row of the cells holding points (clipped to the raster)."""
        ij = ((pts - self.origin) * (1.0 / FREE_CELL_MM)).astype(np.int32)  # truncation: points sit right of origin
        return np.clip(ij, 0, self._last, out=ij)

    def mark(self, geom, grow: float, text: bool = False) -> None:
        """Mark the cells whose centres lie in `geom` grown by `grow` mm; a label's box (`text`)
        also in `texts`, grown by half the step between a leader's points and half a cell's
        diagonal beyond LEADER_HALF_MM, as a leader is looked up at the cells of its points.
        (Marked when the raster is next read: `_flush`.)"""
        self._pending.append((geom, grow, False))
        if text:
            self._pending.append((geom, LEADER_HALF_MM + 0.5 * LEADER_STEP_MM + 0.71 * FREE_CELL_MM, True))

    def close(self, geom) -> None:
        """No later leader path through the cells at `geom` (a bent leader's turns: `routed_near`
        paths go around them; labels may still sit beside them)."""
        self._pending.append((geom, 0.5 * FREE_CELL_MM, True))

    def _flush(self) -> None:
        """Mark what `mark` and `close` were given since the last flush, all at once (a piece places
        a hundred labels beside their edges between two searches of the raster): each geometry
        grown (shapely's buffer, quad_segs=2) and rasterised by its cells' centres over its bounds,
        both layers in one compiled pass (`pack.mark_edges`, over the packer's `_raster`); then
        `free`'s maps again where cells were taken."""
        if not self._pending:
            return
        import shapely

        from .pack import mark_edges, ring_edges

        geoms, grows, to_texts = (np.array(v, dtype=t) for v, t in zip(zip(*self._pending), (object, float, bool)))
        self._pending = []
        grown = shapely.buffer(geoms, grows, quad_segs=2)
        p0, p1, owner = ring_edges(grown)
        start = np.searchsorted(owner, np.arange(len(grown) + 1))
        windows = mark_edges(self.grid, self.texts, p0, p1, start, shapely.bounds(grown), to_texts, self.origin,
                             1.0 / FREE_CELL_MM)
        if (~to_texts).any():
            self._refresh(windows[~to_texts])

    def free(self, w: float, h: float) -> np.ndarray:
        """(ny, nx) `_box_free` of the whole raster for w x h mm boxes, kept up to date as
        cells are taken (`_refresh`): a label is looked for a dozen times between two placements."""
        self._flush()
        key = (_half_cells(w), _half_cells(h))
        if key not in self._free:
            self._free[key] = _box_free(self.grid, *key)
        return self._free[key]

    def _refresh(self, windows: np.ndarray) -> None:
        """`free` again where the cells of `windows` (k, 4: first and last row, first and last
        column) may have been taken: at the centres whose boxes reach them, from the cells those
        boxes cover; the whole map at once when that is less work."""
        ny, nx = self.grid.shape
        for (hw, hh), free in self._free.items():
            near = (windows[:, 1] - windows[:, 0] + 1 + 4 * hh) * (windows[:, 3] - windows[:, 2] + 1 + 4 * hw)
            if near.sum() > ny * nx:
                free[:] = _box_free(self.grid, hw, hh)
                continue
            _refresh_free(free, self.grid, windows, hw, hh)

    def free_near(self, p: np.ndarray, sizes: list[tuple[float, float]], want: int) -> Iterator[tuple[int, np.ndarray]]:
        """Centres of level boxes of each of the two sizes (w, h mm) that touch no taken cell and whose
        leader from p crosses no label, within ELSEWHERE_MM of p: up to `want` per size and place,
        nearest first, centred in a face (each size in turn), then off the faces (the same), as
        (index into sizes, centres (m, 2)) in batches, each made when asked for: a ring around p at a
        time (`_clear_near`), the raster scanned once for all four, so a spot found near p costs a
        scan of the rings out to it; nothing may be placed between two asks."""
        self._flush()
        (c0, r0), (c1, r1) = self._cells(np.array([p - ELSEWHERE_MM, p + ELSEWHERE_MM]))
        if self.grid[r0:r1 + 1, c0:c1 + 1].all():
            return
        p = np.asarray(p, dtype=np.float64)
        free_a, free_b = self.free(*sizes[0]), self.free(*sizes[1])
        found = np.empty((4, int((r1 - r0 + 1) * (c1 - c0 + 1)), 3))  # (`_scan_ring`'s lists: filled as needed)
        counts, ring_end = np.zeros(4, dtype=np.int64), np.zeros((4, len(_RINGS2)), dtype=np.int64)
        scanned = np.zeros(1, dtype=np.int64)
        for q in range(4):  # in a face first (each size), then off the faces
            # a leader from p to the centre crosses no label: its points (LEADER_STEP_MM apart at
            # most) are free; nearest first among the LEADER_TRIES nearest, until `want` are found
            state = np.zeros(3, dtype=np.int64)
            while len(clear := _clear_near(free_a, free_b, self.in_faces, int(r0), int(r1), int(c0), int(c1),
                                           self.origin, p, FREE_CELL_MM, _RINGS2, q, state, scanned, found, counts,
                                           ring_end, LEADER_TRIES, self.texts, _LEADER_T, want)):
                yield q % 2, clear

    def routed_near(self, p: np.ndarray, sizes: list[tuple[float, float]], want: int
                    ) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """Free boxes (as `free_near`, one of `sizes` (w, h) each, centred in a face or off the
        faces) that a bent leader reaches from p: a path of cells no label takes, breadth first
        over 8 neighbours up to ELSEWHERE_MM long. Up to `want`, nearest along the path first:
        (index into sizes, centre, the leader's points from p to the centre, kept at its turns:
        each stretch is clear of labels), each path made when asked for."""
        self._flush()
        (c0, r0), (c1, r1) = self._cells(np.array([p - ELSEWHERE_MM, p + ELSEWHERE_MM]))
        free = ~self.texts[r0:r1 + 1, c0:c1 + 1]
        sc, sr = self._cells(p[None])[0] - (c0, r0)
        free[sr, sc] = True
        centres = np.stack([self.free(w, h)[r0:r1 + 1, c0:c1 + 1] for w, h in sizes])
        dist, found = _grid_bfs(free, int(sr), int(sc), int(ELSEWHERE_MM / FREE_CELL_MM), centres, want)
        for k, r, c in found.tolist():
            path = _path_back(dist, r, c)  # back to p, one step nearer each time (straightest first)
            pts = self.origin + (path[::-1][:, ::-1] + np.array([c0, r0]) + 0.5) * FREE_CELL_MM
            pts[0] = p
            yield k, pts[-1].copy(), self._turns(pts)

    def _turns(self, pts: np.ndarray) -> np.ndarray:
        """A path of cell centres cut to its turns: from each kept point the farthest later one a
        straight stretch reaches without crossing a label (`_path_turns`)."""
        self._flush()
        return pts[_path_turns(np.ascontiguousarray(pts), self.texts, self.origin, 1.0 / FREE_CELL_MM, LEADER_STEP_MM)]


class PieceLabels:
    """The labels of one piece, placed one by one so none overlaps another (see the module
    docstring). `room` is the piece's `tabs.Room`: off-face labels are added to it."""

    def __init__(self, room: Room, size: float, cut_sides: np.ndarray | None = None) -> None:
        import shapely

        self.room = room
        # (k, 2, 2) ends of every cut side of the piece: a label without a leader off the faces is
        # placed nearer its own side than any other, or a reader takes it for that one's
        self.cut_sides = np.zeros((0, 2, 2)) if cut_sides is None else np.ascontiguousarray(cut_sides, dtype=float)
        # off-face labels stay in the room fitting a piece to the page leaves for its tabs: around
        # the hull of the faces' corners (the hull of their union, without the union: 3 ms a piece)
        corners = shapely.multipoints(shapely.get_coordinates(room.faces))
        self.allowed = shapely.convex_hull(corners).buffer(TAB_ROOM_MM - TAB_CLEAR_MM)
        shapely.prepare(self.allowed)  # asked whether it contains a label box for every spot tried
        self.size = size
        self.boxes = _Boxes()
        self.strips = _Boxes()  # leader lines drawn across the piece (`_elsewhere`)
        self.items: list[TextItem] = []
        self.outside: list = []  # shapely geometries of off-face labels and their leaders
        self.leaders: list[np.ndarray] = []  # (2, 2) leader lines from an edge to its label
        self.stats = LabelStats()
        self._taken = None  # `_Taken` raster of the piece, made at the first `_elsewhere`
        self._no_spot = 0  # labels `_elsewhere` found no spot for
        self.crowded: list[np.ndarray] = []  # where labels with no readable place went (their face's centroid)

    def _first_in_face(self, boxes: np.ndarray, tri: np.ndarray) -> int | None:
        """The first of the label boxes (k, 4, 2) inside triangle tri (3, 2) by LABEL_PAD_MM
        (`inside_triangle`) and clear of the placed labels and leaders (`_hits`), or None: a
        compiled test of them all (`overlap_kernels.first_box_in_triangle`); `_hits` decides a
        box it cannot tell."""
        cells = _box_cells(boxes)
        lengths = np.array([math.hypot(*(tri[(k + 1) % 3] - tri[k])) for k in range(3)])
        a, b = self.boxes.rings, self.strips.rings
        i = 0
        while i < len(boxes):
            k, status = first_box_in_triangle(boxes[i:], tri, lengths, LABEL_PAD_MM, cells[i:], LABEL_PAD_MM,
                                              a.pts, a.ring_ptr, a.cells, a.has_ring, a.n,
                                              b.pts, b.ring_ptr, b.cells, b.has_ring, b.n)
            i += int(k)
            if status < 0:
                return None
            if status == 0 or not self._hits(boxes[i]):
                return i
            i += 1
        return None

    def _clear_spots(self, boxes: np.ndarray, polys: np.ndarray, order: np.ndarray) -> Iterator[int]:
        """The label boxes (k, 4, 2; their shapely polygons) of `order` (indices) clear of the
        placed labels and leaders (`_hits`) and not blocked off the faces in the room
        (`Room.blocked`, TAB_CLEAR_MM), in that order: a compiled test of them all
        (`overlap_kernels.first_clear_box`), the Python tests deciding a box it cannot tell.
        Nothing may be placed while it is iterated."""
        cells = _box_cells(boxes)
        a, b = self.boxes.rings, self.strips.rings
        table = self.room.obstacle_table()
        j = 0
        while j < len(order):
            j, status = first_clear_box(boxes, order, j, cells, LABEL_PAD_MM, a.pts, a.ring_ptr, a.cells, a.has_ring,
                                        a.n, b.pts, b.ring_ptr, b.cells, b.has_ring, b.n, TAB_CLEAR_MM, OVERLAP_MM2,
                                        *table)
            if status < 0:
                return
            i = int(order[j])
            j += 1
            if status == 0 or not (self._hits(boxes[i]) or self.room.blocked(polys[i], None, TAB_CLEAR_MM)):
                yield i

    def _hits(self, box: np.ndarray) -> bool:
        """True when a label box (4, 2) comes within LABEL_PAD_MM of a placed label or leader."""
        return _grown_box_hits(box, self.boxes._items_at(box) + self.strips._items_at(box))

    def _off_faces(self, geoms: list) -> None:
        """Record what an off-face label puts on the paper (its box, its leader's stretch beyond
        the tab): in the piece's room (tabs keep clear of it), its footprint and the raster."""
        self.room.add(geoms)
        self.outside.extend(geoms)
        if self._taken is not None:
            for g in geoms:
                self._taken.mark(g, TAB_CLEAR_MM)

    def _put(self, text: str, center: np.ndarray, u: np.ndarray, size: float, kind: str, box: np.ndarray) -> None:
        self.boxes.add(box)
        if self._taken is not None:
            from shapely.geometry import Polygon

            self._taken.mark(Polygon(box), LABEL_PAD_MM, text=True)
        self.items.append(TextItem(text, float(center[0]), float(center[1]), _angle(u), size, kind))

    def piece(self, faces_xy: np.ndarray, text: str) -> None:
        """The piece's name in the face with the largest incircle that holds it, as large as fits up
        to PIECE_FONT_MAX_MM (never below the label size)."""
        a, b, c = faces_xy[:, 0], faces_xy[:, 1], faces_xy[:, 2]
        la, lb, lc = (np.linalg.norm(b - c, axis=1), np.linalg.norm(c - a, axis=1), np.linalg.norm(a - b, axis=1))
        area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
        per = np.maximum(la + lb + lc, 1e-300)
        r = 2 * area / per
        u = np.array([1.0, 0.0])
        for f in np.argsort(-r, kind="stable")[:20]:
            center = (la[f] * a[f] + lb[f] * b[f] + lc[f] * c[f]) / per[f]
            size = min(PIECE_FONT_MAX_MM, max(self.size, 1.2 * r[f] / max(text_width(text, 1.0), CAP_HEIGHT)))
            while size >= self.size - 1e-9:
                box = text_box(center, u, text, size)
                if inside_triangle(faces_xy[f], box, LABEL_PAD_MM):
                    self._put(text, center, u, size, "piece-label", box)
                    return
                size *= 0.9
        f = int(np.argmax(r))
        center = faces_xy[f].mean(axis=0)
        self.stats.unplaced += 1
        self.crowded.append(center)
        self._put(text, center, u, self.size, "piece-label", text_box(center, u, text, self.size))

    def edge(self, side: CutSide, text: str, tab_parts: tuple[np.ndarray, ...] = (),
             tab_folds: np.ndarray | None = None) -> None:
        """The glue label of one side of a glued edge (see the module docstring for the order)."""
        self.run(text, [(side, tab_parts, tab_folds)])

    def run(self, text: str, sides: list[tuple[CutSide, tuple, np.ndarray | None]]) -> None:
        """One label for a seam run: consecutive sides along the outline (`edge`'s arguments per
        side, in order) glued to the run's other copy. Stages 1-3 beside each side, middle side
        first, then stage 4 from the sides in that order; a run of several sides gets a tick
        across its outline at both ends (`tick`), placed first so no label covers them."""
        if len(sides) > 1:
            self.tick(sides[0][0], _end_away(sides[0][0], sides[1][0]))
            self.tick(sides[-1][0], _end_away(sides[-1][0], sides[-2][0]))
            self.stats.runs += 1
        mid = len(sides) // 2
        order = sorted(range(len(sides)), key=lambda i: (abs(i - mid), i))
        for i in order:
            side, tab_parts, tab_folds = sides[i]
            if self._near(side, text, tab_parts, tab_folds):
                return
        side = sides[mid][0]
        if self._elsewhere(text, [sides[i][0] for i in order]):
            self.stats.outside += 1
            return
        s = self.size
        u = _reading((side.p1 - side.p0) / max(side.length, 1e-12))
        center = side.tri.mean(axis=0)  # 5. nowhere readable: said in the stats
        self.stats.unplaced += 1
        self.crowded.append(center)
        self._put(text, center, u, s, "edge-label", text_box(center, u, text, s))

    def tick(self, side: CutSide, p: np.ndarray) -> None:
        """A run's end mark: a short line from outline point p (an end of `side`) into its face,
        along the bisector of the face's corner there (TICK_MM, or less in a small face), drawn
        with the leaders and kept clear of labels."""
        from shapely.geometry import LineString

        tri = side.tri
        k = int(np.argmin(np.linalg.norm(tri - p, axis=1)))
        a, b = tri[(k + 1) % 3] - tri[k], tri[(k + 2) % 3] - tri[k]
        la, lb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
        if la == 0.0 or lb == 0.0:
            return
        w = a / la + b / lb
        lw = float(np.linalg.norm(w))
        if lw == 0.0:
            return
        end = tri[k] + w / lw * min(TICK_MM, 0.4 * min(la, lb))
        self.leaders.append(np.array([tri[k], end]))
        strip = LineString([tri[k], end]).buffer(LEADER_HALF_MM)
        self.strips.add_geom(strip)
        if self._taken is not None:
            self._taken.mark(strip, LABEL_PAD_MM)

    def _near(self, side: CutSide, text: str, tab_parts: tuple[np.ndarray, ...], tab_folds: np.ndarray | None) -> bool:
        """Stages 1-3 for one side: inside its face, on its tab, just outside it."""
        s = self.size
        d = side.p1 - side.p0
        length = max(side.length, 1e-12)
        u = _reading(d / length)
        n_out = side.outward()
        h = CAP_HEIGHT * s
        # 1. inside the face: the first of these spots whose box fits (a compiled test; a box
        # whose labels around it that cannot tell is asked here)
        inside = np.concatenate([side.p0 + _ALONG[:, None] * d - n_out * (1.2 * LABEL_PAD_MM + h / 2),
                                 _incentre(side.tri)[None]])
        boxes = text_boxes(inside, u, text, s)
        i = self._first_in_face(boxes, side.tri)
        if i is not None:
            self._put(text, inside[i], u, s, "edge-label", boxes[i])
            return True
        if self._on_tab(text, u, tab_parts, tab_folds, n_out, h):
            self.stats.on_tabs += 1
            return True
        beyond = max((float(np.max((p - side.p0) @ n_out)) for p in tab_parts), default=0.0)
        if self._outside(text, side, u, n_out, beyond, h):
            self.stats.outside += 1
            return True
        return False

    def _outside(self, text: str, side: CutSide, u: np.ndarray, n_out: np.ndarray, beyond: float, h: float) -> bool:
        """3. Outside the edge, `beyond` mm past it (its tab's depth): right beside it (nearer it
        than any other cut side), else up to LEADER_STEPS_MM away in a free spot with a leader line
        from the middle of the edge. The spots' boxes, their shapes and whether they lie in the
        allowed room are made for all spots at once; the rest is asked spot by spot, in order."""
        import shapely
        from shapely.geometry import LineString

        d = side.p1 - side.p0
        mid = side.p0 + 0.5 * d
        start = mid + n_out * beyond
        near = beyond + TAB_CLEAR_MM + LABEL_PAD_MM + h / 2
        turns = np.stack([n_out[0] * _TURNS[:, 0] - n_out[1] * _TURNS[:, 1],
                          n_out[0] * _TURNS[:, 1] + n_out[1] * _TURNS[:, 0]], axis=1)
        reach = np.array([dist + h / 2 + TAB_CLEAR_MM for dist in LEADER_STEPS_MM])
        # beside the edge (no leader), then for each distance every turn (a leader)
        centers = np.concatenate([side.p0 + _ALONG[:, None] * d + n_out * near,
                                  (start + turns[None] * reach[:, None, None]).reshape(-1, 2)])
        leader = np.arange(len(centers)) >= len(_ALONG)
        ok = leader.copy()  # (a spot with a leader names its edge by the leader)
        ok[:len(_ALONG)] = self._nearest_to(centers[:len(_ALONG)], side)
        boxes = text_boxes(centers, u, text, self.size)
        polys = shapely.polygons(boxes)
        ok &= shapely.contains(self.allowed, polys)
        # spot by spot, in order, those clear of labels and leaders and not blocked in the room
        for i in self._clear_spots(boxes, polys, np.flatnonzero(ok)):
            center, box, poly = centers[i], boxes[i], polys[i]
            extra = [poly]
            if leader[i]:
                end = _nearest_on(poly, start)
                line = LineString([start + (end - start) * min(1.0, TAB_CLEAR_MM / max(np.linalg.norm(end - start), 1e-9)), end])
                # drawn from the edge itself, over its own tab: a leader ending at the tab's tip
                # points at whatever edge lies beyond it (the partner's, in a notch)
                drawn = LineString([mid, end])
                if self.boxes.hits_geom(drawn.buffer(LEADER_HALF_MM)):
                    continue
                if self.room.blocked(line.buffer(LEADER_HALF_MM), None):
                    continue
                self.leaders.append(np.array([mid, end]))
                extra.append(line.buffer(LEADER_HALF_MM))
            self._put(text, center, u, self.size, "edge-label", box)
            self._off_faces(extra)
            return True
        return False

    def _nearest_to(self, pts: np.ndarray, side: CutSide) -> np.ndarray:
        """(k,) bool per point of pts (k, 2): whether it is nearer `side` than every other cut side
        of the piece, by LABEL_PAD_MM (a label beside an edge names the edge a reader sees nearest
        to it)."""
        return _nearer_than_others(np.ascontiguousarray(pts, dtype=float), self.cut_sides,
                                   np.array([side.p0, side.p1], dtype=float), LABEL_PAD_MM)

    def _elsewhere(self, text: str, sides: list[CutSide]) -> bool:
        """4. The free spot nearest the middle of an edge of `sides` (a run's, middle one first;
        failing that, a quarter of the way along it from either end), up to ELSEWHERE_MM away,
        the label level (failing that, upright): inside a face of the piece (LABEL_PAD_MM from its
        sides) or off the faces (as in 3), with a leader line from there on the edge that may
        cross the piece's lines but no label; failing a straight leader, a bent one from the
        middle side (`_Taken.routed_near`). Candidates come from the piece's `_Taken` raster,
        nearest first; each is checked exactly (`_leader_spot`). After ELSEWHERE_GIVE_UP labels
        without a spot the piece is not searched again (a mesh that dense needs a larger --size)."""
        if self._no_spot >= ELSEWHERE_GIVE_UP:
            return False
        if self._taken is None:
            self._taken = _Taken(self)
        w, h = text_width(text, self.size), CAP_HEIGHT * self.size
        level, upward = np.array([1.0, 0.0]), _reading(np.array([0.0, 1.0]))

        def tries():
            for side in sides:
                for t in (0.5, 0.25, 0.75):
                    mid = side.p0 + t * (side.p1 - side.p0)
                    # in a face first (off them a label takes paper), level, then upright
                    for k, centres in self._taken.free_near(mid, [(w, h), (h, w)], ELSEWHERE_TRIES):
                        u = (level, upward)[k]
                        for i in self._leader_spots(text_boxes(centres, u, text, self.size), mid):
                            yield mid, u, centres[i]

        for mid, u, center in tries():
            if self._leader_spot(text, u, center, np.array([mid, center]), bent=False):
                return True
        # no straight leader gets out between the labels around: a bent one from the middle side
        mid = sides[0].p0 + 0.5 * (sides[0].p1 - sides[0].p0)
        for k, center, pts in self._taken.routed_near(mid, [(w, h), (h, w)], ELSEWHERE_TRIES):
            if self._leader_spot(text, (level, upward)[k], center, pts, bent=True):
                return True
        self._no_spot += 1
        return False

    def _leader_spots(self, boxes: np.ndarray, p: np.ndarray) -> Iterator[int]:
        """The label boxes (k, 4, 2) that `_leader_spot` may take with a straight leader from p, in
        order: the others, those it surely turns down (off the faces and blocked in the room, or
        their leader over a label: `overlap_kernels.first_leader_spot`), are skipped. Nothing may
        be placed while it is iterated."""
        a = self.boxes.rings
        pts, ring_ptr, ring_sign, obs_ptr, face_bounds, extra_bounds, n_extras = self.room.obstacle_table()
        i = 0
        while True:
            i = first_leader_spot(boxes, i, p, self._taken.tris, face_bounds, LABEL_PAD_MM, SCREEN_MARGIN_MM,
                                  _LEADER_STRIP_MM, CELL_MM, a.pts, a.ring_ptr, a.cells, a.has_ring, a.n, TAB_CLEAR_MM,
                                  OVERLAP_MM2, pts, ring_ptr, ring_sign, obs_ptr, extra_bounds, n_extras)
            if i >= len(boxes):
                return
            yield i
            i += 1

    def _leader_spot(self, text: str, u: np.ndarray, center: np.ndarray, path: np.ndarray, bent: bool) -> bool:
        """Stage 4's exact check and placement: the label at `center` (reading along u) with a
        leader along `path` (points from the edge into the box; cut where it meets the box), when
        the box keeps clear of labels, leaders and lines (in a face) or of the piece (off the
        faces, in its room) and the leader crosses no label. No later bent leader runs through
        a bent leader's turns (it reads as one line, joined end to end; crossing is allowed)."""
        from shapely.geometry import LineString, MultiPoint, Point, Polygon

        box = text_box(center, u, text, self.size)
        if self._hits(box):
            return False
        poly = Polygon(box)
        in_face = any(inside_triangle(np.asarray(self.room.faces[f].exterior.coords)[:3], box, LABEL_PAD_MM)
                      for f in self.room.tree.query(poly))
        if not in_face and (not self.allowed.contains(poly) or self.room.blocked(poly, None, TAB_CLEAR_MM)):
            return False
        grown = poly.buffer(LABEL_PAD_MM)
        outside = [q for q in path[:-1] if not grown.contains(Point(*q))]
        if not outside:
            return False
        line = np.array([*outside, _nearest_on(poly, outside[-1])])
        strip = LineString(line).buffer(LEADER_HALF_MM)
        if self.boxes.hits_geom(strip):
            return False
        self.leaders.extend(np.array([a, b]) for a, b in zip(line[:-1], line[1:]))
        self._put(text, center, u, self.size, "edge-label", box)
        self.strips.add_geom(strip)  # later labels keep off it (straight leaders may cross)
        self._taken.mark(strip, LABEL_PAD_MM)
        if bent and len(line) > 2:
            self._taken.close(MultiPoint(line[1:-1]))
        if not in_face:
            self._off_faces([poly])
        return True

    def _on_tab(self, text: str, u: np.ndarray, parts, folds, n_out: np.ndarray, h: float) -> bool:
        """2. On a part of the side's tab, along its fold line, inside it with LABEL_PAD_MM."""
        import shapely
        from shapely.geometry import Polygon

        depth = np.tile([LABEL_PAD_MM + h / 2, LABEL_PAD_MM + h], len(_ALONG))  # per spot along, both depths
        along = np.repeat(_ALONG, 2)
        for part, fold in zip(parts, folds if folds is not None else ()):
            poly = Polygon(part).buffer(-LABEL_PAD_MM, quad_segs=1)
            if poly.is_empty:
                continue
            centers = fold[0] + along[:, None] * (fold[1] - fold[0]) + n_out * depth[:, None]
            boxes = text_boxes(centers, u, text, self.size)
            for i in np.flatnonzero(shapely.contains(poly, shapely.polygons(boxes))):
                if not self._hits(boxes[i]):
                    self._put(text, centers[i], u, self.size, "edge-label", boxes[i])
                    return True
        return False
