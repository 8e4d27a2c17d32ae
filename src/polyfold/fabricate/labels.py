"""Labels printed on the pieces, in mm (y down): the glue label beside each side of a glued edge
and the piece's name, all readable and none overlapping another label or a line.

Size: every glue label has the same font size, `label_font(min_cap_mm)`, whose cap height is the
least asked for (`--min-label-mm`, default paper.MIN_LABEL_MM); never smaller. Where a glue
label goes, in order:
1. inside its face, along the edge (at the middle of the edge, then nearer its ends, then at the
   face's incentre);
2. on the side's glue tab, when this side carries it;
3. just outside the edge (beyond the tab on the side that has one), clear of the piece's faces,
   tabs and labels, else a little further in a free spot with a leader line to the edge, else
   up to FAR_STEPS_MM away in any direction, its leader crossing the piece's lines if it must: an
   off-face label, which the packer keeps clear of other pieces (`SheetPiece.footprint`), never
   further out than the tab room around the piece's convex hull (`tabs.TAB_ROOM_MM`), which
   fitting pieces to the page reserves;
4. when nothing fits: inside the face at the centroid, counted in `LabelStats.unplaced`.
Every box keeps LABEL_PAD_MM from the lines around it and from other labels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .page import TextItem, upright
from .paper import CAP_HEIGHT, CHAR_EM
from .tabs import TAB_CLEAR_MM, TAB_ROOM_MM, CutSide, Room

PIECE_FONT_MAX_MM = 6.0  # a piece's name may be larger, up to this, where its face has room
LABEL_PAD_MM = 0.25  # gap between a label's glyph box and any line or other label
CELL_MM = 10.0  # cell size of the label boxes' spatial hash
LEADER_STEPS_MM = (2.0, 5.0, 9.0, 14.0)  # how far an off-face label with a leader may sit from its edge
LEADER_HALF_MM = 0.1  # half the width of a leader line (clearance it needs)
FAR_STEPS_MM = (8.0, 14.0, 20.0, 28.0)  # the last resort: a label this far away, its leader may cross the piece


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


DIGIT_EM = 0.556  # Helvetica's advance width of every digit, in em


def text_width(text: str, size: float) -> float:
    """Printed width (mm) of `text` at font `size`: DIGIT_EM per digit, CHAR_EM per other character."""
    return size * sum(DIGIT_EM if ch.isdigit() else CHAR_EM for ch in text)


def text_box(center: np.ndarray, u: np.ndarray, text: str, size: float) -> np.ndarray:
    """The 4 corners (4, 2) of the glyph box of `text` at font `size` centred at `center`, its
    reading direction the unit vector u: `text_width` wide, a cap height high."""
    n = np.array([-u[1], u[0]])
    hw, hh = text_width(text, size) / 2, CAP_HEIGHT * size / 2
    return np.array([center - hw * u - hh * n, center + hw * u - hh * n, center + hw * u + hh * n,
                     center - hw * u + hh * n])


def _inside_triangle(tri: np.ndarray, pts: np.ndarray, pad: float) -> bool:
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


@dataclass(eq=False)
class _Boxes:
    """Label boxes placed on one piece, in a spatial hash of CELL_MM cells."""

    cells: dict = field(default_factory=dict)
    count: int = 0  # boxes placed (their ids)

    def _keys(self, box: np.ndarray):
        (x0, y0), (x1, y1) = box.min(axis=0) // CELL_MM, box.max(axis=0) // CELL_MM
        return [(i, j) for i in range(int(x0), int(x1) + 1) for j in range(int(y0), int(y1) + 1)]

    def hits(self, box: np.ndarray) -> bool:
        """True when `box` (4, 2), grown by LABEL_PAD_MM, meets a placed box."""
        from shapely.geometry import Polygon

        return self.hits_bounds(Polygon(box).buffer(LABEL_PAD_MM, quad_segs=1), box)

    def hits_geom(self, geom) -> bool:
        """True when a shapely geometry meets a placed box."""
        x0, y0, x1, y1 = geom.bounds
        return self.hits_bounds(geom, np.array([[x0, y0], [x1, y1]]))

    def hits_bounds(self, geom, corners: np.ndarray) -> bool:
        seen = set()
        for key in self._keys(corners):
            for i, other in self.cells.get(key, ()):
                if i not in seen:
                    seen.add(i)
                    if geom.intersects(other):
                        return True
        return False

    def add(self, box: np.ndarray) -> None:
        from shapely.geometry import Polygon

        item = (self.count, Polygon(box))
        self.count += 1
        for key in self._keys(box):
            self.cells.setdefault(key, []).append(item)


@dataclass
class LabelStats:
    """Where the glue labels went: on a tab, outside their edge, or nowhere readable (`unplaced`:
    at the face's centroid, over lines or labels)."""

    on_tabs: int = 0
    outside: int = 0
    unplaced: int = 0


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


class PieceLabels:
    """The labels of one piece, placed one by one so none overlaps another (see the module
    docstring). `room` is the piece's `tabs.Room`: off-face labels are added to it."""

    def __init__(self, room: Room, size: float) -> None:
        import shapely

        self.room = room
        # off-face labels stay in the room fitting a piece to the page leaves for its tabs
        self.allowed = shapely.convex_hull(shapely.union_all(room.faces)).buffer(TAB_ROOM_MM - TAB_CLEAR_MM)
        self.size = size
        self.boxes = _Boxes()
        self.items: list[TextItem] = []
        self.outside: list = []  # shapely geometries of off-face labels and their leaders
        self.leaders: list[np.ndarray] = []  # (2, 2) leader lines from an edge to its label
        self.stats = LabelStats()

    def _put(self, text: str, center: np.ndarray, u: np.ndarray, size: float, kind: str, box: np.ndarray) -> None:
        self.boxes.add(box)
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
                if _inside_triangle(faces_xy[f], box, LABEL_PAD_MM):
                    self._put(text, center, u, size, "piece-label", box)
                    return
                size *= 0.9
        f = int(np.argmax(r))
        center = faces_xy[f].mean(axis=0)
        self.stats.unplaced += 1
        self._put(text, center, u, self.size, "piece-label", text_box(center, u, text, self.size))

    def edge(self, side: CutSide, text: str, tab_parts: tuple[np.ndarray, ...] = (),
             tab_folds: np.ndarray | None = None) -> None:
        """The glue label of one side of a glued edge (see the module docstring for the order)."""
        s = self.size
        d = side.p1 - side.p0
        length = max(side.length, 1e-12)
        u = _reading(d / length)
        n_out = side.outward()
        h = CAP_HEIGHT * s
        ts = (0.5, 0.35, 0.65, 0.2, 0.8)
        inside = [side.p0 + t * d - n_out * (1.2 * LABEL_PAD_MM + h / 2) for t in ts] + [_incentre(side.tri)]
        for center in inside:  # 1. inside the face
            box = text_box(center, u, text, s)
            if _inside_triangle(side.tri, box, LABEL_PAD_MM) and not self.boxes.hits(box):
                self._put(text, center, u, s, "edge-label", box)
                return
        if self._on_tab(text, u, tab_parts, tab_folds, n_out, h):
            self.stats.on_tabs += 1
            return
        beyond = max((float(np.max((p - side.p0) @ n_out)) for p in tab_parts), default=0.0)
        if self._outside(text, side, u, n_out, beyond, h):
            self.stats.outside += 1
            return
        center = side.tri.mean(axis=0)  # 4. nowhere readable: said in the stats
        self.stats.unplaced += 1
        self._put(text, center, u, s, "edge-label", text_box(center, u, text, s))

    def _outside(self, text: str, side: CutSide, u: np.ndarray, n_out: np.ndarray, beyond: float, h: float) -> bool:
        """3. Outside the edge, `beyond` mm past it (its tab's depth): right beside it, else up to
        LEADER_MAX_MM away in a free spot with a leader line to the middle of the edge (or tab)."""
        from shapely.geometry import LineString, Point, Polygon

        d = side.p1 - side.p0
        start = side.p0 + 0.5 * d + n_out * beyond
        near = beyond + TAB_CLEAR_MM + LABEL_PAD_MM + h / 2
        spots = [(side.p0 + t * d + n_out * near, n_out, False) for t in (0.5, 0.35, 0.65, 0.2, 0.8)]
        for dist in LEADER_STEPS_MM:
            for turn in (0.0, 30.0, -30.0, 60.0, -60.0):
                a = math.radians(turn)
                w = np.array([n_out[0] * math.cos(a) - n_out[1] * math.sin(a), n_out[0] * math.sin(a) + n_out[1] * math.cos(a)])
                spots.append((start + w * (dist + h / 2 + TAB_CLEAR_MM), w, True))
        # last: any direction, further away, the leader crossing the piece's own lines if it must
        far = [(start + np.array([math.cos(a), math.sin(a)]) * dist, None, "across")
               for dist in FAR_STEPS_MM for a in np.radians(np.arange(0.0, 360.0, 30.0))]
        for center, w, leader in spots + far:
            box = text_box(center, u, text, self.size)
            poly = Polygon(box)
            if not self.allowed.contains(poly) or self.boxes.hits(box) or self.room.blocked(poly, None, TAB_CLEAR_MM):
                continue
            extra = [poly]
            if leader:
                end = np.asarray(poly.exterior.interpolate(poly.exterior.project(Point(*start))).coords[0])
                line = LineString([start + (end - start) * min(1.0, TAB_CLEAR_MM / max(np.linalg.norm(end - start), 1e-9)), end])
                if self.boxes.hits_geom(line.buffer(LEADER_HALF_MM)):
                    continue
                if leader != "across" and self.room.blocked(line.buffer(LEADER_HALF_MM), None):
                    continue
                self.leaders.append(np.array([start, end]))
                extra.append(LineString([start, end]).buffer(LEADER_HALF_MM))
            self._put(text, center, u, self.size, "edge-label", box)
            self.room.add(extra)
            self.outside.extend(extra)
            return True
        return False

    def _on_tab(self, text: str, u: np.ndarray, parts, folds, n_out: np.ndarray, h: float) -> bool:
        """2. On a part of the side's tab, along its fold line, inside it with LABEL_PAD_MM."""
        from shapely.geometry import Polygon

        for part, fold in zip(parts, folds if folds is not None else ()):
            poly = Polygon(part).buffer(-LABEL_PAD_MM, quad_segs=1)
            if poly.is_empty:
                continue
            for t in (0.5, 0.35, 0.65, 0.2, 0.8):
                for depth in (LABEL_PAD_MM + h / 2, LABEL_PAD_MM + h):
                    center = fold[0] + t * (fold[1] - fold[0]) + n_out * depth
                    box = text_box(center, u, text, self.size)
                    if poly.contains(Polygon(box)) and not self.boxes.hits(box):
                        self._put(text, center, u, self.size, "edge-label", box)
                        return True
        return False
