"""Packing of paper-net pieces onto pages by their real outlines (not their bounding boxes).

Every piece is tried in a few rotations (``angles`` evenly over 360 degrees plus the rotation that
aligns its minimum-area bounding rectangle with the page axes) and dropped where its centroid is
lowest, then leftmost, among the free positions of a page (bottom-left fill with "gravity" towards
y = 0), so a piece slides into the concavities and holes of pieces already placed. Larger pieces
go first; each piece goes onto the first open page that takes it, and a new page is opened only
when none does (first-fit decreasing). Pieces are never mirrored: the printed side must stay up.
First fit depends on the order of the pieces: a caller may give an order to fill first (a plan's,
`split.plan_pages`); larger first is filled too unless that order reached the area bound (no fewer
pages can hold the outlines' area), and the one with fewer pages is kept. (Seeded shuffles of
near-equal sizes, 8 orders in all, found no page fewer on the benchmark models or bench_pack's
sets, so they are not tried.)

Free positions are found on an occupancy grid (about 600 cells along the page's long side): every
piece is grown by half the gap plus half a cell diagonal and rasterised by cell centres, which
over-approximates the cells the half-gap-grown piece touches. Two pieces whose grids do not share a
cell are therefore at least ``gap`` apart, exactly; the result is nevertheless re-checked with
shapely (`check_packing`) before it is returned. The scan over positions is a numba kernel that
checks a piece row by row as runs of cells against a "last occupied column" table and jumps past
the obstacle it hits, so no loop visits every cell.

`shelves.shelf_offsets` puts bounding boxes on plain shelves: the fallback when the time budget runs out,
and the layout of the one sheet of `polyfold unfold --svg` (`sheet.py`).

`PageFiller` is the same bottom-left fill one outline at a time, for planners that try many
candidate outlines before they commit to one (`split.plan_pages` splits pieces to fill pages).
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import shapely
from shapely import MultiPolygon, Polygon

from ..deadline import clock
from ..errors import PolyfoldError
from ..jit import njit
from ..shelves import shelf_offsets

_CELLS = 600  # grid cells along the long printable side: ~0.46 mm on A4
_QUAD_SEGS = 4  # arcs of the grown outline: 4 segments per quarter circle
_TOL = 1e-9  # mm: float noise allowed by check_packing
ANGLES = 16  # rotations tried per piece (every 22.5 degrees), plus its minimum-rectangle ones
ORDER_TRIES = 2  # piece orders pack_outlines fills: a caller's hint, then larger first
# from this many outlines on, pack_outlines fills its second order in a forked process while this
# one fills the first (a 1,500-face model's 190-270 outlines: 0.18-0.35 s a fill, on a core its
# layout leaves idle here); a few dozen take milliseconds, less than the fork
PARALLEL_PACK_OUTLINES = 100
# outlines whose rasters a PageFiller keeps (least recently used dropped): page planning tries
# hundreds of candidate parts, each up to ANGLES rasters (about 1 MB a part on a 1,280-face net,
# where an unbounded cache reached 840 MB)
RASTER_CACHE_PIECES = 128


@dataclass(frozen=True)
class Placement:
    """Where one piece goes: rotate by `angle` degrees CCW about the origin of its own
    coordinates, then translate by `offset` (mm), onto page `page` (0-based)."""

    page: int
    angle: float
    offset: tuple[float, float]

    def __post_init__(self) -> None:
        # plain Python numbers whatever the caller computed them with (numpy scalars print badly)
        object.__setattr__(self, "page", int(self.page))
        object.__setattr__(self, "angle", float(self.angle))
        object.__setattr__(self, "offset", (float(self.offset[0]), float(self.offset[1])))

    def apply(self, xy: np.ndarray) -> np.ndarray:
        """(n, 2) piece coordinates -> (n, 2) page coordinates."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        return xy @ _rot(self.angle).T + np.asarray(self.offset, dtype=float)


@dataclass(frozen=True)
class Packing:
    """The result of `pack_outlines`: one placement per input outline, in input order."""

    placements: tuple[Placement, ...]
    n_pages: int
    page_size: tuple[float, float]  # (width, height) mm
    margin: float
    # the outlines' area over the printable area of the pages used: total outline area / (n_pages *
    # (width - 2 margin) * (height - 2 margin)); make packs footprints (labels beside pieces too) and
    # reports the cut-out area instead (pipeline.make)
    utilisation: float
    order: tuple[int, ...] = ()  # the piece order whose first fit gave these placements
    orders_tried: int = 0
    ran_out: bool = False  # the time limit stopped the fill (shelves for the rest) or the orders


def placed_outline(outline: Polygon | MultiPolygon, placement: Placement) -> Polygon | MultiPolygon:
    """The outline moved onto its page (page coordinates, mm)."""
    return shapely.transform(outline, placement.apply)


# ----------------------------------------------------------------------------------------------
# geometry helpers


def _rot(deg: float) -> np.ndarray:
    """(2, 2) CCW rotation matrix."""
    return _rots(np.array([deg]))[0]


def _rots(degs: np.ndarray) -> np.ndarray:
    """(k, 2, 2) CCW rotation matrices; quarter turns are exact (cos 90 is 6e-17 in floats,
    which would make a piece that exactly fits the page miss by a hair)."""
    t = np.radians(np.asarray(degs, dtype=float))
    c, s = np.cos(t), np.sin(t)
    c, s = np.where(np.abs(c) < 1e-15, 0.0, c), np.where(np.abs(s) < 1e-15, 0.0, s)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def _polygonal(outline, i: int) -> Polygon | MultiPolygon:
    """The outline as a valid, non-empty (Multi)Polygon, or a PolyfoldError naming piece `i`."""
    if not isinstance(outline, (Polygon, MultiPolygon)):
        raise PolyfoldError(f"piece {i}: outline is a {type(outline).__name__}, not a polygon")
    if not outline.is_valid:
        # unions of triangles can come out self-touching; repair rather than refuse
        outline = shapely.make_valid(outline)
        outline = shapely.unary_union([g for g in shapely.get_parts(outline) if isinstance(g, (Polygon, MultiPolygon))])
    if outline.is_empty or outline.area <= 0.0 or not np.isfinite(shapely.get_coordinates(outline)).all():
        raise PolyfoldError(f"piece {i}: outline is empty or not finite")
    return outline


def _angles(outline: Polygon | MultiPolygon, angles: int, phase: float) -> np.ndarray:
    """Rotations to try (degrees in [0, 360)): `angles` evenly spaced ones starting at `phase`, and
    the two that put the sides of the minimum-area bounding rectangle along the page axes."""
    out = [phase + k * 360.0 / max(angles, 1) for k in range(max(angles, 1))]
    rect = shapely.get_coordinates(shapely.minimum_rotated_rectangle(outline))
    if len(rect) >= 2:
        d = rect[1] - rect[0]
        if np.hypot(*d) > 0:
            a = -math.degrees(math.atan2(d[1], d[0]))
            out += [a, a + 90.0]
    out = np.mod(np.asarray(out), 360.0)
    d = np.abs(out[:, None] - out[None, :])
    near = np.minimum(d, 360.0 - d) <= 1e-6  # (a handful of values: drop near-duplicates of those kept before)
    keep = np.ones(len(out), dtype=bool)
    for i in range(1, len(out)):
        keep[i] = not (near[i, :i] & keep[:i]).any()
    return out[keep]


def hull_corners(xy: np.ndarray, order: np.ndarray | None = None) -> np.ndarray:
    """Indices of the corners of the convex hull of the points xy (n, 2), counter-clockwise from
    the lowest-x (then lowest-y) point; points on a hull side are left out (Andrew's monotone
    chain). Collinear points: the two ends; fewer than three points: all of them. The points are
    ordered by numpy (a stable sort compiled by numba took 2.5 s of a first run), or by `order`
    when the caller has it (`sorted_points`)."""
    xy = np.ascontiguousarray(xy, dtype=np.float64)
    if len(xy) < 3:
        return np.arange(len(xy))
    return _monotone_chain(xy, sorted_points(xy) if order is None else order)


def sorted_points(xy: np.ndarray) -> np.ndarray:
    """The points xy (n, 2) in `hull_corners`' order: by x, then y, then index. The order of some
    of them (ids, increasing) is this order with the others left out (`order_among`)."""
    return np.lexsort((xy[:, 1], xy[:, 0]))


def order_among(order: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """`sorted_points` of xy[ids] from that of xy (`order`), for increasing `ids`: positions in ids."""
    rank = np.full(len(order), -1, dtype=np.int64)
    rank[ids] = np.arange(len(ids))
    ranked = rank[order]
    return ranked[ranked >= 0]


@njit(cache=True)
def _monotone_chain(xy, order):
    """`hull_corners` of the points xy (n >= 3, 2) in `order` (by x, then y)."""
    n = xy.shape[0]
    out = np.empty(2 * n + 1, dtype=np.int64)
    k = 0
    for half in range(2):
        start = k
        for m in range(n):
            i = order[m] if half == 0 else order[n - 1 - m]
            while k >= start + 2:
                a = out[k - 2]
                b = out[k - 1]
                cross = ((xy[b, 0] - xy[a, 0]) * (xy[i, 1] - xy[a, 1])
                         - (xy[b, 1] - xy[a, 1]) * (xy[i, 0] - xy[a, 0]))
                if cross > 0:
                    break
                k -= 1
            out[k] = i
            k += 1
        k -= 1  # each chain's last point starts the other
    return out[:k]


def points_hull(xy: np.ndarray):
    """The convex hull of the points xy (n, 2) as a shapely geometry (Polygon; LineString or Point
    when they are collinear or one), from `hull_corners`: quicker than shapely's own on thousands
    of points, which builds a geometry for each."""
    xy = np.ascontiguousarray(xy, dtype=np.float64)
    if len(xy) == 0:
        return shapely.Polygon()
    return shapely.convex_hull(shapely.multipoints(xy[hull_corners(xy)]))


def _hull_xy(outline) -> np.ndarray:
    """(n, 2) corners of the outline's convex hull: the same extents in every rotation as all its
    points (they are some of them), from far fewer points."""
    return shapely.get_coordinates(shapely.convex_hull(outline))


def _extents(xy: np.ndarray, degs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounding boxes of the points `xy` rotated by each angle: mins (k, 2), maxs (k, 2)."""
    r = np.einsum("kij,nj->kni", _rots(degs), xy)
    return r.min(axis=1), r.max(axis=1)


def _best_fit(xy: np.ndarray, degs: np.ndarray, pw: float, ph: float) -> tuple[float, float]:
    """(largest scale, its angle) at which the points fit a pw x ph rectangle."""
    lo, hi = _extents(xy, degs)
    ext = hi - lo
    with np.errstate(divide="ignore"):
        s = np.minimum(np.where(ext[:, 0] > 0, pw / ext[:, 0], np.inf), np.where(ext[:, 1] > 0, ph / ext[:, 1], np.inf))
    k = int(np.argmax(s))
    return float(s[k]), float(degs[k])


def fits_page(outline: Polygon | MultiPolygon, page_size: tuple[float, float], margin: float,
              angles: int = ANGLES) -> float:
    """The largest uniform scale s (may be > 1) such that `outline` * s fits the printable area
    (page minus margins) in one of the rotations `pack_outlines` tries with the same `angles`."""
    pw, ph = page_size[0] - 2 * margin, page_size[1] - 2 * margin
    if pw <= 0 or ph <= 0:
        return 0.0
    xy = _hull_xy(outline)
    if len(xy) == 0:
        return math.inf
    return _best_fit(xy, _angles(outline, angles, 0.0), pw, ph)[0]


# ----------------------------------------------------------------------------------------------
# rasters


def ring_edges(geoms) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start and end points (e, 2) of every edge of every ring of (Multi)Polygons `geoms` (a
    geometry or an array of them), and the index (e,) of each edge's geometry, in order."""
    if (shapely.get_type_id(geoms) == 3).all() and not shapely.get_num_interior_rings(geoms).any():
        # polygons without holes (grown outlines, label boxes, leader strips): one ring each, so
        # the geometries' own coordinates are their rings' (one shapely call instead of three)
        xy, owner = shapely.get_coordinates(geoms, return_index=True)
        same = owner[1:] == owner[:-1]
        return xy[:-1][same], xy[1:][same], owner[:-1][same]
    parts, part_owner = shapely.get_parts(geoms, return_index=True)
    rings, ring_part = shapely.get_rings(parts, return_index=True)
    xy, idx = shapely.get_coordinates(rings, return_index=True)
    same = idx[1:] == idx[:-1]  # consecutive points of one ring (rings are closed)
    return xy[:-1][same], xy[1:][same], part_owner[ring_part[idx[:-1][same]]]


@njit(cache=True)
def _rows_crossed(a: np.ndarray, b: np.ndarray, h: int) -> tuple[int, int]:
    """(r0, r1): the rows r0 <= r < r1 of a raster h rows high whose centre line r + 0.5 the edge
    a -> b (points (2,) in cell units) crosses, lo <= r + 0.5 < hi (none for a level edge)."""
    return (min(max(math.ceil(min(a[1], b[1]) - 0.5), 0), h), min(max(math.ceil(max(a[1], b[1]) - 0.5), 0), h))


@njit(cache=True)
def _toggled_column(a: np.ndarray, b: np.ndarray, r: int, w: int) -> int:
    """The first cell of row r (of w) whose centre lies right of where the edge a -> b crosses the
    row's centre line (one of `_rows_crossed`); w when none does."""
    u = a[0] + (r + 0.5 - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
    return min(max(math.ceil(u - 0.5), 0), w)


@njit(cache=True)
def _raster(p0: np.ndarray, p1: np.ndarray, h: int, w: int) -> np.ndarray:
    """(h, w) bool: cells whose centre (c + 0.5, r + 0.5) is inside the rings p0 -> p1 (e, 2) given
    in cell units (even-odd rule, so holes work). Scanline: each edge toggles, in every row whose
    centre line it crosses, the first cell whose centre lies right of the crossing; a running
    parity along the row then says inside. (The labels' rasters, `mark_edges`; a piece's rotations
    are rasterised as their runs, `_shape_runs`, which reads the same crossings.)"""
    toggles = np.zeros((h, w + 1), dtype=np.uint8)
    for e in range(p0.shape[0]):
        r0, r1 = _rows_crossed(p0[e], p1[e], h)
        for r in range(r0, r1):
            toggles[r, _toggled_column(p0[e], p1[e], r, w)] ^= 1
    inside = np.empty((h, w), dtype=np.bool_)
    for r in range(h):
        parity = 0
        for c in range(w):
            parity ^= toggles[r, c]
            inside[r, c] = parity == 1
    return inside


@njit(cache=True)
def mark_edges(grid, texts, p0, p1, start, bounds, to_texts, origin, inv_cell):
    """Mark geometries on two rasters of one grid (the labels' `_Taken`: what labels may not touch,
    and the labels alone): the cells of grid (ny, nx), or of texts where to_texts[g], whose
    centres lie inside geometry g, its rings' edges p0[start[g]:start[g + 1]] -> p1[...] (e, 2 mm:
    `ring_edges`), even-odd (holes work), within its window: its bounds (k, 4: x0, y0, x1, y1) in
    cells of 1 / inv_cell mm from origin, truncated and clipped to the raster. Cell (c, r) has its
    centre at origin + (c + 0.5, r + 0.5) / inv_cell. Returns the windows (k, 4: first and last
    row, first and last column)."""
    k = bounds.shape[0]
    ny, nx = grid.shape
    windows = np.empty((k, 4), dtype=np.int64)
    for g in range(k):
        c0 = min(max(np.int32((bounds[g, 0] - origin[0]) * inv_cell), 0), nx - 1)
        r0 = min(max(np.int32((bounds[g, 1] - origin[1]) * inv_cell), 0), ny - 1)
        c1 = min(max(np.int32((bounds[g, 2] - origin[0]) * inv_cell), 0), nx - 1)
        r1 = min(max(np.int32((bounds[g, 3] - origin[1]) * inv_cell), 0), ny - 1)
        windows[g, 0], windows[g, 1], windows[g, 2], windows[g, 3] = r0, r1, c0, c1
        a, e = start[g], start[g + 1] - start[g]
        q0 = np.empty((e, 2))  # the edges in cells of the window
        q1 = np.empty((e, 2))
        for i in range(e):
            q0[i, 0] = (p0[a + i, 0] - origin[0]) * inv_cell - float(c0)
            q0[i, 1] = (p0[a + i, 1] - origin[1]) * inv_cell - float(r0)
            q1[i, 0] = (p1[a + i, 0] - origin[0]) * inv_cell - float(c0)
            q1[i, 1] = (p1[a + i, 1] - origin[1]) * inv_cell - float(r0)
        inside = _raster(q0, q1, r1 - r0 + 1, c1 - c0 + 1)
        target = texts if to_texts[g] else grid
        for r in range(r1 - r0 + 1):
            for c in range(c1 - c0 + 1):
                if inside[r, c]:
                    target[r0 + r, c0 + c] = True
    return windows


@dataclass
class _Shape:
    """One piece in one rotation, rasterised on a grid aligned with its rotated bounding box."""

    angle: float
    lo: np.ndarray  # (2,) min corner of the rotated outline (mm)
    h: int  # rows and columns of the grown piece's raster; cell (0, 0) starts at lo - pad cells
    w: int
    runs: np.ndarray  # (k, 3) int64: row, first column, last column of each run of set cells
    xmax: int  # largest column offset at which the piece stays inside the printable area
    ymax: int
    cy: float  # centroid of the cells (rows, columns): pieces go where it is lowest ("gravity")
    cx: float

    @property
    def mask(self) -> np.ndarray:
        """(h, w) bool: the cells of the runs (made for the shapes placed, not the thousands tried)."""
        return _runs_mask(self.runs, self.h, self.w)


@njit(cache=True)
def _runs_mask(runs: np.ndarray, h: int, w: int) -> np.ndarray:
    """(h, w) bool with the cells of runs (k, 3: row, first column, last column) set."""
    mask = np.zeros((h, w), dtype=np.bool_)
    for i in range(runs.shape[0]):
        mask[runs[i, 0], runs[i, 1]:runs[i, 2] + 1] = True
    return mask


@njit(cache=True)
def _shape_runs(p0: np.ndarray, p1: np.ndarray, h: int, w: int) -> tuple[np.ndarray, float, float]:
    """The runs of set cells of `_raster`(p0, p1, h, w), (k, 3) int64 rows of (row, first column,
    last column), and their centroid (row, column), without the raster: per row, the columns
    where `_raster`'s edges toggle (`_rows_crossed`, `_toggled_column`), sorted, a column toggled
    twice dropped; a run from each odd toggle to the cell before the next (or to the row's end). Runs widest
    first, rows in order among equals: a stable counting sort by width (numba's
    argsort(kind="mergesort") compiled for 1.5 s). The same runs and centroid, to the last bit, as
    scanning the raster's rows; work by edges and rows, not cells (a piece's rotation is 50,000
    cells or more, tried thousands of times by page planning)."""
    # the toggled columns, by row (counted, then filled)
    count = np.zeros(h + 1, dtype=np.int64)
    for e in range(p0.shape[0]):
        r0, r1 = _rows_crossed(p0[e], p1[e], h)
        for r in range(r0, r1):
            count[r + 1] += 1
    for r in range(h):
        count[r + 1] += count[r]
    cols = np.empty(count[h], dtype=np.int64)
    fill = count[:h].copy()
    for e in range(p0.shape[0]):
        r0, r1 = _rows_crossed(p0[e], p1[e], h)
        for r in range(r0, r1):
            cols[fill[r]] = _toggled_column(p0[e], p1[e], r, w)
            fill[r] += 1
    runs = np.empty((count[h] // 2 + h, 3), dtype=np.int64)
    n = 0
    sr = 0.0
    sc = 0.0
    cnt = 0
    for r in range(h):
        lo, hi = count[r], count[r + 1]
        for i in range(lo + 1, hi):  # insertion sort: a row crosses a few edges
            v = cols[i]
            j = i - 1
            while j >= lo and cols[j] > v:
                cols[j + 1] = cols[j]
                j -= 1
            cols[j + 1] = v
        start = -1  # the column where the current run began (-1: outside)
        i = lo
        while i <= hi:
            if i < hi:
                v = cols[i]
                k = i
                while k < hi and cols[k] == v:
                    k += 1
                odd = (k - i) % 2 == 1 and v < w  # toggled an odd number of times, at a cell of the row
            else:  # the row's end closes a run still open
                v, k, odd = w, hi + 1, start >= 0
            if odd:
                if start < 0:
                    start = v
                else:
                    runs[n, 0], runs[n, 1], runs[n, 2] = r, start, v - 1
                    n += 1
                    m = v - start
                    cnt += m
                    sr += m * r
                    sc += m * (start + v - 1) / 2.0
                    start = -1
            i = k
    per_width = np.zeros(w + 2, dtype=np.int64)
    for i in range(n):
        per_width[w - (runs[i, 2] - runs[i, 1])] += 1  # (widest: bucket 1)
    for k in range(1, w + 2):
        per_width[k] += per_width[k - 1]
    out = np.empty((n, 3), dtype=np.int64)
    for i in range(n):
        b = w - (runs[i, 2] - runs[i, 1]) - 1
        slot = per_width[b]
        per_width[b] += 1
        out[slot, 0], out[slot, 1], out[slot, 2] = runs[i, 0], runs[i, 1], runs[i, 2]
    return out, sr / max(cnt, 1), sc / max(cnt, 1)


class _Piece:
    def __init__(self, geom, degs: np.ndarray, grow: float, res: float, pad: int, pw: float, ph: float):
        self.xy = _hull_xy(geom)
        self.area = float(geom.area)
        self.degs = degs
        self.p0, self.p1, _ = ring_edges(geom.buffer(grow, quad_segs=_QUAD_SEGS))
        self.res, self.pad, self.pw, self.ph = res, pad, pw, ph
        self.rots = _rots(degs)
        self.lo, self.hi = _extents(self.xy, degs)
        self._shapes: dict[int, _Shape | None] = {}

    def shape(self, k: int) -> _Shape | None:
        """Rotation k rasterised (cached: a piece is tried on several pages), None if it cannot
        fit the printable area in that rotation."""
        if k not in self._shapes:
            self._shapes[k] = self._make_shape(k)
        return self._shapes[k]

    def _make_shape(self, k: int) -> _Shape | None:
        res, pad = self.res, self.pad
        lo, ext = self.lo[k], self.hi[k] - self.lo[k]
        xmax, ymax = math.floor((self.pw - ext[0]) / res), math.floor((self.ph - ext[1]) / res)
        if xmax < 0 or ymax < 0:
            return None
        w, h = (np.ceil(ext / res).astype(int) + 2 * pad + 1).tolist()
        rot = self.rots[k].T
        origin = lo - pad * res
        runs, cy, cx = _shape_runs((self.p0 @ rot - origin) / res, (self.p1 @ rot - origin) / res, h, w)
        return _Shape(float(self.degs[k]), lo, h, w, runs, xmax, ymax, cy, cx)


# ----------------------------------------------------------------------------------------------
# the position scan


@njit(cache=True)
def _scan(last: np.ndarray, rowmax: np.ndarray, runs: np.ndarray, ymax: int, xmax: int) -> tuple[int, int]:
    """Lowest row y <= ymax, then lowest column x <= xmax, at which no run of the piece covers an
    occupied cell; (-1, -1) if none. last[r, c] is the last occupied column <= c of row r (-1 if
    none), so a run [a, b] placed at x is free iff last[y + row, x + b] < x + a; when it is not,
    no x' <= last - a can work either, and the scan jumps there. rowmax[r] is the longest free
    run of row r: rows where one of the widest runs (listed first) cannot fit are skipped whole."""
    n = runs.shape[0]
    k0 = 0  # the run that blocked last is tried first: neighbouring positions share obstacles
    for y in range(ymax + 1):
        skip = False
        for k in range(min(n, 4)):
            if rowmax[y + runs[k, 0]] < runs[k, 2] - runs[k, 1] + 1:
                skip = True
                break
        if skip:
            continue
        x = 0
        while x <= xmax:
            ok = True
            for t in range(n):
                k = k0 + t
                if k >= n:
                    k -= n
                c = last[y + runs[k, 0], x + runs[k, 2]]
                if c >= x + runs[k, 1]:
                    x = c - runs[k, 1] + 1
                    k0 = k
                    ok = False
                    break
            if ok:
                return y, x
    return -1, -1


class _Page:
    def __init__(self, h: int, w: int):
        self.occ = np.zeros((h, w), dtype=bool)
        self.last = np.full((h, w), -1, dtype=np.int32)
        self.free = h * w
        self.rowmax = np.full(h, w, dtype=np.int32)  # longest run of free cells in each row
        self._cols = np.arange(w, dtype=np.int32)

    def stamp(self, mask: np.ndarray, y: int, x: int) -> None:
        h, w = mask.shape
        block = self.occ[y : y + h, x : x + w]
        self.free -= int(np.count_nonzero(mask & ~block))
        block |= mask
        rows = self.occ[y : y + h]
        self.last[y : y + h] = np.maximum.accumulate(np.where(rows, self._cols, -1), axis=1)
        # a free cell c ends a free run of c - last[c] cells; occupied cells give 0
        self.rowmax[y : y + h] = (self._cols - self.last[y : y + h]).max(axis=1)


def _best_on_page(page: _Page, piece: _Piece, res: float) -> tuple[_Shape, int, int] | None:
    """The position and rotation of the piece on the page with the lowest centroid (then the
    leftmost): like gravity, this drops pieces into the gaps left by others rather than merely
    keeping their bounding boxes low, which would always prefer the flattest rotation."""
    if piece.area / res**2 > page.free:
        return None
    widest_free = int(page.rowmax.max())
    best, best_key = None, None
    for k in range(len(piece.degs)):
        s = piece.shape(k)
        if s is None or s.runs[0, 2] - s.runs[0, 1] + 1 > widest_free:
            continue
        ylim = s.ymax if best_key is None else min(s.ymax, math.floor(best_key[0] - s.cy))
        if ylim < 0:
            continue  # branch and bound: cannot beat the best rotation so far
        y, x = _scan(page.last, page.rowmax, s.runs, ylim, s.xmax)
        if y < 0:
            continue
        key = (y + s.cy, x + s.cx)
        if best_key is None or key < best_key:
            best, best_key = (s, y, x), key
    return best


# ----------------------------------------------------------------------------------------------
# shelves (the fallback, and sheets that grow to fit)


def _shelf(items: list[tuple[int, _Piece]], pw: float, ph: float, margin: float, gap: float, first_page: int) -> dict[int, Placement]:
    """Bounding-box shelf packing onto new pages from `first_page` on: quick and always valid,
    used for what is left when the time budget runs out. Each piece takes its flattest rotation."""
    items = sorted(items, key=lambda item: item[0])  # ties between equal heights go by piece index
    rots, sizes = [], []
    for _, p in items:
        ext = p.hi - p.lo
        with np.errstate(divide="ignore"):
            scale = np.minimum(pw / ext[:, 0], ph / ext[:, 1])
        ok = np.flatnonzero(scale >= 1.0 - 1e-12)  # as in pack_outlines: some rotation fits
        k = int(ok[np.argmin(ext[ok, 1])])
        rots.append(k)
        sizes.append((float(ext[k, 0]), float(ext[k, 1])))
    out: dict[int, Placement] = {}
    for (i, p), k, (page, x, y) in zip(items, rots, shelf_offsets(sizes, pw, ph, gap)):
        lo = p.lo[k]
        out[i] = Placement(first_page + page, float(p.degs[k]), (margin + x - lo[0], margin + y - lo[1]))
    return out


# ----------------------------------------------------------------------------------------------
# the bottom-left fill


@dataclass(frozen=True)
class _Grid:
    """The occupancy grid of a page: cells of `res` mm, pieces grown by `grow` mm (`pad` cells),
    gh x gw cells; the printable area pw x ph mm inside `margin`."""

    res: float
    grow: float
    pad: int
    gh: int
    gw: int
    pw: float
    ph: float
    margin: float


def _grid(pw: float, ph: float, margin: float, gap: float) -> _Grid:
    res = max(pw, ph) / _CELLS
    # grow each piece by half the gap plus half a cell diagonal, and by 1/cos(half an arc segment)
    # because shapely's arcs are chords inside the true circle: the grown polygon then contains
    # every cell that the half-gap-grown piece touches (see the module docstring)
    grow = (gap / 2 + res * math.sqrt(0.5)) / math.cos(math.pi / (4 * _QUAD_SEGS)) + 1e-6
    pad = math.ceil(grow / res)
    return _Grid(res, grow, pad, math.ceil(ph / res) + 2 * pad + 2, math.ceil(pw / res) + 2 * pad + 2, pw, ph, margin)


def _phase(seed: int, angles: int, rng: np.random.Generator | None = None) -> float:
    """The turn (degrees) of the rotations tried: 0 for seed 0, else a random phase drawn first
    from the seed's generator (`rng`, when the caller draws more from it)."""
    if seed == 0:
        return 0.0
    rng = np.random.default_rng(seed) if rng is None else rng
    return float(rng.uniform(0.0, 360.0 / max(angles, 1)))


# the pieces `_piece` keeps (least recently used dropped) while their estimated bytes (`_piece_bytes`)
# stay under this. A make packs its 190-270 outlines (1,500 faces) again after every plan and in each
# packing: a cache of 128 pieces, less than one pass over them, missed 777 of 1,111 asks (cube-12
# decimated), the outlines all kept hit all but the 241 first (make 6.45 -> 5.86 s, 12 MB). The
# estimate is 2-3 times the bytes the rasters take; a 1,280-face net's candidate parts run to 1 MB each.
RASTER_CACHE_BYTES = 128_000_000
_pieces_kept: OrderedDict = OrderedDict()  # (outline, angles, phase, grid) -> ((piece, scale), bytes)
_pieces_held = [0]  # their bytes
_pieces_lock = threading.Lock()


def _piece(g, angles: int, phase: float, grid: _Grid) -> tuple[_Piece, float]:
    """A `_Piece` for the outline with the rotations to try, and the largest scale at which it fits
    the printable area in one of them. The same outline (shapely's equality: exactly the same
    coordinates) on the same grid gives the same piece, its rasters included: page planning packs
    one set of outlines many times (every split tried), so pieces are kept (RASTER_CACHE_BYTES)."""
    key = (g, angles, phase, grid)
    with _pieces_lock:
        kept = _pieces_kept.get(key)
        if kept is not None:
            _pieces_kept.move_to_end(key)
            return kept[0]
    made = _new_piece(g, angles, phase, grid)
    size = _piece_bytes(made[0])
    with _pieces_lock:
        if key not in _pieces_kept:  # (another thread may have made it meanwhile)
            _pieces_kept[key] = (made, size)
            _pieces_held[0] += size
        while _pieces_held[0] > RASTER_CACHE_BYTES and len(_pieces_kept) > 1:
            _pieces_held[0] -= _pieces_kept.popitem(last=False)[1][1]
    return made


def _piece_bytes(piece: _Piece) -> int:
    """An upper estimate of the bytes a piece holds once its rotations are rasterised: its grown
    outline's edges and, per rotation, three runs of 24 bytes a row."""
    rows = ((piece.hi - piece.lo)[:, 1] / piece.res + 2 * piece.pad + 1).sum()
    return int(piece.p0.nbytes + piece.p1.nbytes + 72 * rows)


def _new_piece(g, angles: int, phase: float, grid: _Grid) -> tuple[_Piece, float]:
    xy = _hull_xy(g)
    degs = _angles(g, angles, phase)
    if phase != 0.0:  # keep fits_page's best rotation, so its "fits" always holds here too
        degs = np.append(degs, _best_fit(xy, _angles(g, angles, 0.0), grid.pw, grid.ph)[1])
    scale, _ = _best_fit(xy, degs, grid.pw, grid.ph)
    return _Piece(g, degs, grid.grow, grid.res, grid.pad, grid.pw, grid.ph), scale


def _pieces(geoms: list, angles: int, phase: float, grid: _Grid, W: float, H: float) -> list[_Piece]:
    """A `_Piece` per outline with the rotations to try; PolyfoldError if one fits in none."""
    pieces = []
    for i, g in enumerate(geoms):
        piece, scale = _piece(g, angles, phase, grid)
        if scale < 1.0 - 1e-12:  # float noise of the rotation; check_packing allows 1e-9 mm
            raise PolyfoldError(
                f"piece {i} does not fit a {W:g} x {H:g} mm page with {grid.margin:g} mm margins; "
                f"the largest scale that fits is {math.floor(scale * 1000) / 1000:.3f}"
            )
        pieces.append(piece)
    return pieces


def _place_alone(p: _Piece, page: _Page, pg: int, grid: _Grid) -> Placement:
    """A piece that fits exactly but not on the conservative grid: alone in the middle of its new
    page, with its grown raster stamped so later pieces can still use the rest of the page."""
    res, pad, margin = grid.res, grid.pad, grid.margin
    _, a = _best_fit(p.xy, p.degs, grid.pw, grid.ph)
    lo, hi = _extents(p.xy, np.array([a]))
    off = np.array([margin, margin]) + (np.array([grid.pw, grid.ph]) - (hi[0] - lo[0])) / 2 - lo[0]
    origin = margin - pad * res
    rot = _rot(a).T
    runs, _, _ = _shape_runs((p.p0 @ rot + off - origin) / res, (p.p1 @ rot + off - origin) / res, grid.gh, grid.gw)
    page.stamp(_runs_mask(runs, grid.gh, grid.gw), 0, 0)
    return Placement(pg, a, (off[0], off[1]))


def _fill_pages(pieces: list[_Piece], order: list[int], grid: _Grid, gap: float,
                deadline: float) -> tuple[dict[int, Placement], bool]:
    """First fit over pages in `order`; shelves for the rest once `deadline` passed. Returns the
    placements and whether the deadline cut the fill short."""
    res, margin = grid.res, grid.margin
    pages: list[_Page] = []
    place: dict[int, Placement] = {}
    ran_out = False
    for n_done, i in enumerate(order):
        p, hit, pg = pieces[i], None, len(pages)
        for pg, page in enumerate(pages):  # first fit: the first open page that takes the piece
            if clock() > deadline:
                break
            hit = _best_on_page(page, p, res)
            if hit is not None:
                break
        if hit is None and clock() > deadline:
            # out of time: shelves on new pages for this piece and the rest (valid, quick)
            rest = [(int(j), pieces[j]) for j in order[n_done:]]
            place.update(_shelf(rest, grid.pw, grid.ph, margin, gap, len(pages)))
            ran_out = True
            break
        if hit is None:
            pg, page = len(pages), _Page(grid.gh, grid.gw)
            pages.append(page)
            hit = _best_on_page(page, p, res)
        if hit is None:
            place[i] = _place_alone(p, page, pg, grid)
            continue
        s, y, x = hit
        page.stamp(s.mask, y, x)
        place[i] = Placement(pg, s.angle, _offset(s, y, x, grid))
    return place, ran_out


class PageFiller:
    """`n_pages` pages of `page_size` (width, height mm) inside `margin`, filled one outline at a
    time by the bottom-left fill of `pack_outlines` with the same gap, angles and seed (the same
    rotations): for planners that try many candidate outlines before committing to one. Whole
    outlines put in the order pack_outlines is given as its hint land where it puts them. An
    outline is a valid (Multi)Polygon in mm in its own coordinates; `key` names it so that its
    rasters are made once (a candidate is often tried on several pages)."""

    def __init__(self, page_size: tuple[float, float], margin: float, gap: float, n_pages: int,
                 angles: int = ANGLES, seed: int = 0, rasters: dict | None = None) -> None:
        pw, ph = page_size[0] - 2 * margin, page_size[1] - 2 * margin
        if pw <= 0 or ph <= 0:
            raise PolyfoldError(f"page {page_size[0]:g} x {page_size[1]:g} mm has no printable area inside {margin:g} mm margins")
        self.grid = _grid(pw, ph, margin, gap)
        self.pages = [_Page(self.grid.gh, self.grid.gw) for _ in range(n_pages)]
        self.angles = angles
        self.phase = _phase(seed, angles)
        self.printable_area = pw * ph
        # key -> rasters of the outline (at most RASTER_CACHE_PIECES); a dict shared by fillers with
        # the same page, gap, angles and seed keeps them across fillers (each key naming one outline)
        self._pieces: dict[object, _Piece] = {} if rasters is None else rasters

    def free_area(self, page: int) -> float:
        """mm^2 of the page's grid not yet covered by placed outlines grown by half the gap (an
        upper bound of what still fits)."""
        return self.pages[page].free * self.grid.res**2

    def spot(self, page: int, outline: Polygon | MultiPolygon, key: object) -> Spot | None:
        """Where the fill would put the outline on `page` (nothing is placed yet), or None when it
        fits nowhere there."""
        g = self.grid
        cache = self._pieces
        piece = cache.pop(key, None)
        if piece is None:
            piece = _piece(outline, self.angles, self.phase, g)[0]
            while len(cache) >= RASTER_CACHE_PIECES:  # the least recently used out first
                del cache[next(iter(cache))]
        cache[key] = piece  # (re)inserted last: dicts keep insertion order
        hit = _best_on_page(self.pages[page], piece, g.res)
        return None if hit is None else Spot(page, *hit)

    def put(self, spot: Spot) -> Placement:
        """Place an outline at a spot found on the pages as they are now."""
        self.pages[spot.page].stamp(spot.shape.mask, spot.y, spot.x)
        return Placement(spot.page, spot.shape.angle, _offset(spot.shape, spot.y, spot.x, self.grid))


@dataclass(frozen=True, eq=False)
class Spot:
    """A free position found by `PageFiller.spot`: grid cell (y, x) of `page`, the outline in the
    rotation `shape`."""

    page: int
    shape: _Shape
    y: int
    x: int


def _offset(s: _Shape, y: int, x: int, grid: _Grid) -> tuple[float, float]:
    """The translation (mm) that puts shape `s` at grid cell (y, x) of a page."""
    return grid.margin + x * grid.res - s.lo[0], grid.margin + y * grid.res - s.lo[1]


def _orders(areas: np.ndarray, rng: np.random.Generator, hint: list[int] | None) -> list[list[int]]:
    """The piece orders to fill: the hint (a caller's order, e.g. a plan's; pieces it leaves out
    follow, larger first), then larger first (ties in a seeded random order)."""
    n = len(areas)
    out = []
    if hint is not None:
        head = [int(i) for i in dict.fromkeys(hint) if 0 <= int(i) < n]
        out.append(head + sorted(set(range(n)) - set(head), key=lambda i: (-areas[i], i)))
    larger_first = np.lexsort((rng.random(n), -areas)).tolist()
    if larger_first not in out:
        out.append(larger_first)
    return out


def _fill_ahead(pieces: list[_Piece], orders: list[list[int]], grid: _Grid, gap: float, deadline: float):
    """A `processes.ForkedStream` of `_fill_pages` of the second of `orders`, begun now, while
    `pack_outlines` fills the first (the same fill, from the same pieces, as the one made here
    after it; killed unused when the first meets the bound); None where it would not pay
    (PARALLEL_PACK_OUTLINES) or there is one order, one core or no fork."""
    from ..processes import ForkedStream, can_fork, usable_cores

    if len(orders) < 2 or len(pieces) < PARALLEL_PACK_OUTLINES or usable_cores() < 2 or not can_fork():
        return None
    return ForkedStream(lambda: iter([_fill_pages(pieces, orders[1], grid, gap, deadline)]))


def pack_outlines(
    outlines: list[Polygon | MultiPolygon],
    page_size: tuple[float, float],
    margin: float = 10.0,
    gap: float = 2.0,
    angles: int = ANGLES,
    seed: int = 0,
    time_limit: float = 5.0,
    hint: list[int] | None = None,
    tries: int = ORDER_TRIES,
) -> Packing:
    """Place the outlines (mm, each in its own coordinates) on as few pages of `page_size` (width,
    height mm) as the bottom-left fill finds, inside `margin` and at least `gap` apart. Raises
    PolyfoldError naming a piece (and the largest scale that fits) if one cannot fit an empty page.
    The order `hint` (piece indices) is filled first, then larger first (`_orders`; `tries` = 1:
    only the first of them; the second is filled in a forked process meanwhile, `_fill_ahead`);
    the first with the fewest pages is kept. The same seed gives the same
    packing; a seed other than 0 turns the tried rotations by a random phase. After `time_limit`
    seconds no further order is tried and the remaining pieces of the one being filled are
    shelf-packed onto new pages (`Packing.ran_out`)."""
    W, H = float(page_size[0]), float(page_size[1])
    pw, ph = W - 2 * margin, H - 2 * margin
    geoms = [_polygonal(g, i) for i, g in enumerate(outlines)]
    if not geoms:
        return Packing((), 0, (W, H), float(margin), 0.0)
    if gap < 0 or not math.isfinite(gap):
        raise PolyfoldError(f"gap between pieces must be >= 0 mm, got {gap:g}")
    if pw <= 0 or ph <= 0:
        raise PolyfoldError(f"page {W:g} x {H:g} mm has no printable area inside {margin:g} mm margins")
    rng = np.random.default_rng(seed)
    phase = _phase(seed, angles, rng)
    grid = _grid(pw, ph, margin, gap)
    pieces = _pieces(geoms, angles, phase, grid, W, H)
    areas = np.array([p.area for p in pieces])
    bound = math.ceil(areas.sum() / (pw * ph) - 1e-9)  # no fewer pages can hold the area
    deadline = clock() + time_limit  # (the Deadline clock: compiling is not packing)
    best, best_pages, best_order, tried, ran_out = None, math.inf, [], 0, False
    orders = _orders(areas, rng, hint)[:max(1, tries)]
    ahead = _fill_ahead(pieces, orders, grid, gap, deadline)
    try:
        for k, order in enumerate(orders):
            if tried and clock() > deadline:
                ran_out = True
                break
            got, filled = ahead.next() if ahead is not None and k == 1 else (False, None)
            place, cut_short = filled if got else _fill_pages(pieces, order, grid, gap, deadline)
            tried += 1
            ran_out |= cut_short
            n_pages = max(pl.page for pl in place.values()) + 1
            if n_pages < best_pages:
                best, best_pages, best_order = place, n_pages, order
            if best_pages <= bound:
                break
    finally:
        if ahead is not None:
            ahead.close()

    placements = [best[i] for i in range(len(geoms))]
    # the grid argument is exact, but never hand out a packing that fails the independent check
    bad = sorted({j for pair in _conflicts(geoms, placements, W, H, margin, gap) for j in pair[1:]})
    if bad:
        n_pages = max(pl.page for pl in placements) + 1
        for i, pl in _shelf([(i, pieces[i]) for i in bad], pw, ph, margin, gap, n_pages).items():
            placements[i] = pl
    used = sorted({pl.page for pl in placements})  # renumber in case a page was emptied above
    remap = {old: new for new, old in enumerate(used)}
    placements = [Placement(remap[pl.page], pl.angle, pl.offset) for pl in placements]
    util = float(areas.sum()) / (len(used) * pw * ph)
    return Packing(tuple(placements), len(used), (W, H), float(margin), util, tuple(best_order), tried, ran_out)


def _conflicts(outlines, placements, W, H, margin, gap) -> list[tuple[str, int, ...]]:
    """("page" | "bounds" | "gap" | "overlap", piece indices...) for every problem found."""
    out: list[tuple] = []
    if not outlines:
        return out
    placed = []
    for i, (g, pl) in enumerate(zip(outlines, placements)):
        q = placed_outline(g, pl)
        placed.append(q)
        x0, y0, x1, y1 = q.bounds
        if x0 < margin - _TOL or y0 < margin - _TOL or x1 > W - margin + _TOL or y1 > H - margin + _TOL:
            out.append(("bounds", i))
    pages = np.array([pl.page for pl in placements])
    for page in np.unique(pages):  # one tree per page: pieces on other pages never conflict
        idx = np.flatnonzero(pages == page)
        geoms = [placed[j] for j in idx]
        tree = shapely.STRtree(geoms)
        if gap > 0:
            left, right = tree.query(geoms, predicate="dwithin", distance=gap)
        else:
            left, right = tree.query(geoms, predicate="intersects")
        for a, b in zip(idx[left].tolist(), idx[right].tolist()):
            if a >= b:
                continue
            if gap > 0:
                if placed[a].distance(placed[b]) < gap - _TOL:
                    out.append(("gap", a, b))
            elif placed[a].relate_pattern(placed[b], "T********"):
                out.append(("overlap", a, b))
    return sorted(out, key=lambda p: p[1:])


def check_packing(outlines: list[Polygon | MultiPolygon], packing: Packing, gap: float = 0.0) -> list[str]:
    """Independent exact check of a packing: one human-readable line per problem (empty = OK):
    a wrong number of placements or a page index out of range, an outline leaving the printable
    rectangle, or two outlines on one page whose interiors intersect (gap = 0) or that are closer
    than `gap`."""
    if len(outlines) != len(packing.placements):
        return [f"{len(packing.placements)} placements for {len(outlines)} outlines"]
    problems = [
        f"piece {i}: page {pl.page} is not in 0..{packing.n_pages - 1}"
        for i, pl in enumerate(packing.placements)
        if not 0 <= pl.page < packing.n_pages
    ]
    W, H = packing.page_size
    m = packing.margin
    # GEOS predicates can fail on invalid input; measure what pack_outlines measured (its repair)
    geoms = [g if g.is_valid else _polygonal(g, i) for i, g in enumerate(outlines)]
    for kind, *idx in _conflicts(geoms, list(packing.placements), W, H, m, gap):
        if kind == "bounds":
            problems.append(f"piece {idx[0]} leaves the printable area [{m:g}, {W - m:g}] x [{m:g}, {H - m:g}]")
        elif kind == "gap":
            problems.append(f"pieces {idx[0]} and {idx[1]} on page {packing.placements[idx[0]].page} are closer than {gap:g} mm")
        else:
            problems.append(f"pieces {idx[0]} and {idx[1]} on page {packing.placements[idx[0]].page} overlap")
    return problems
