"""Glue tabs: the one routine that gives a glued cut edge its tab, overlapping nothing.

In: the two sides (`CutSide`) of a glued cut edge in mm (y down) and the `Room` of each piece (its
faces, and the tabs and labels already on it). Out: a `Tab` (which side, its polygons, the fold
segment of each, its depth, and why it is smaller than a full tab), or None when no tab with the
minimum glue area fits on either side (the caller then makes a glue strip).

Sizes. A full tab is a trapezoid `full_depth(L)` deep (40 % of the edge length L, between
TAB_MIN_MM and TAB_MAX_MM) with 45-degree sides, steeper on short edges so its top keeps 10 % of
the edge. When it does not fit, in order, on either side: flatter sides (they slip into the
notches of a net), a lower tab (TAB_MIN_MM), then the full tab clipped: everything within
TAB_CLEAR_MM of the piece's other faces, tabs and labels removed (tapered where something comes
close, split in two where it reaches the fold line). A clipped tab keeps at least MIN_GLUE_FRAC of
the full tab's glue area, is hinged along MIN_FOLD_FRAC of its edge and reaches TAB_MIN_DEPTH_MM
from its fold line; less does not hold.

Clearance. Apart from the corners where its fold line meets the neighbouring faces, every tab
stays TAB_CLEAR_MM from everything else on its piece, so a blade never runs two cuts closer.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

TAB_MAX_MM = 6.0  # full tab depth on long edges
TAB_ROOM_MM = TAB_MAX_MM + 1.0  # room left around a piece's convex hull for its tabs and off-face labels
TAB_REL = 0.4  # full tab depth as a fraction of its edge length, between TAB_MIN_MM and TAB_MAX_MM
TAB_MIN_MM = 3.0  # a lowered tab: the least depth that still takes a finger and glue
TAB_MIN_DEPTH_MM = 2.0  # a clipped (tapered) tab must reach this far from its fold line somewhere
MIN_GLUE_FRAC = 0.4  # a clipped tab keeps this fraction of the full tab's area
MIN_FOLD_FRAC = 0.4  # and its fold lines this fraction of the edge: a flap hinged on a stub twists
TAB_CLEAR_MM = 0.5  # gap kept between a tab and the piece's other faces, tabs and labels
OVERLAP_MM2 = 1e-4  # intersections below this area (0.01 x 0.01 mm) are touching, not overlap
MIN_PART_MM2 = 1.0  # parts of a clipped tab smaller than this are dropped
SIMPLIFY_MM = 0.02  # clipped tabs' outlines are simplified this much (fewer cutter nodes)

# (depth: "full" or "min", side angle in degrees, reason) in order of preference
TAB_VARIANTS = (("full", 45.0, "full"), ("full", 30.0, "flatter"), ("full", 15.0, "flatter"),
                ("min", 45.0, "lower"), ("min", 15.0, "lower"))


@dataclass(frozen=True, eq=False)
class CutSide:
    """One side of a cut edge: edge k (corners k, k+1) of face `face` of piece `piece`, its ends
    p0 -> p1 and the face's triangle `tri` (3, 2), all in mm."""

    piece: int
    face: int
    k: int
    p0: np.ndarray
    p1: np.ndarray
    tri: np.ndarray

    @property
    def length(self) -> float:
        return float(math.hypot(*(self.p1 - self.p0)))

    def outward(self) -> np.ndarray:
        """Unit normal of the edge pointing away from its face."""
        u = (self.p1 - self.p0) / max(self.length, 1e-12)
        n = np.array([-u[1], u[0]])
        return -n if np.dot(self.tri.mean(axis=0) - self.p0, n) > 0 else n

    def key(self) -> tuple:
        """All of the side, as a dict key (but its piece's index: the memos key rooms by content)."""
        return self.face, self.k, self.p0.tobytes(), self.p1.tobytes(), self.tri.tobytes()


@dataclass(frozen=True, eq=False)
class Tab:
    """The tab of a glued edge, on `sides[side]`: `polygons` (one, or several parts of a split
    tab), `folds` (k, 2, 2) the stretch of the fold line under each part, `depth` mm (deepest
    point from the fold line) and `reason`: "full", or how it was reduced ("flatter", "lower",
    "tapered": clipped around something, "split": clipped into several parts)."""

    side: int
    polygons: tuple[np.ndarray, ...]
    folds: np.ndarray
    depth: float
    reason: str


def full_depth(length: float) -> float:
    """Depth of a full tab on an edge `length` mm long."""
    return min(TAB_MAX_MM, max(TAB_MIN_MM, TAB_REL * length))


def tab_polygon(side: CutSide, depth: float, side_deg: float) -> np.ndarray | None:
    """Trapezoid (4, 2) = (base start, top, top, base end) outside the face, `depth` mm deep, its
    sides at `side_deg` to the base or steeper, so the top keeps 10 % of the edge."""
    polys = tab_polygons(side, [(depth, side_deg)])
    return None if polys is None else polys[0]


def tab_polygons(side: CutSide, shapes: list[tuple[float, float]]) -> np.ndarray | None:
    """(k, 4, 2) `tab_polygon` of each (depth, side_deg) of shapes at once; None on a side
    shorter than 1e-9 mm."""
    length = side.length
    if length < 1e-9:
        return None
    u = (side.p1 - side.p0) / length
    n = side.outward()
    depth = np.array([d for d, _deg in shapes])[:, None]
    inset = np.array([min(d / math.tan(math.radians(deg)), 0.45 * length) for d, deg in shapes])[:, None]
    out = np.empty((len(shapes), 4, 2))
    out[:, 0], out[:, 1], out[:, 2], out[:, 3] = side.p0, side.p0 + u * inset + n * depth, side.p1 - u * inset + n * depth, side.p1
    return out


def _rings(geom) -> list[tuple[np.ndarray, float]]:
    """The rings (k, 2) of a shapely geometry's polygons, without the repeated last point, each
    with +1 (outer) or -1 (hole); none for lines and points (they cover no area)."""
    import shapely

    out = []
    for part in shapely.get_parts(geom):
        if part.geom_type == "Polygon" and not part.is_empty:
            out.append((np.asarray(part.exterior.coords)[:-1], 1.0))
            out += [(np.asarray(r.coords)[:-1], -1.0) for r in part.interiors]
    return out


class _Obstacles:
    """The rings of a piece's faces and placed extras, as `overlap_kernels` reads them: points,
    ring pointers and signs, and each obstacle's first ring (faces first, then the extras in the
    order added). Arrays grow by doubling."""

    def __init__(self, faces: np.ndarray) -> None:
        import shapely

        self.pts, self.ring_sign = np.zeros((0, 2)), np.zeros(0)
        self.ring_ptr, self.obs_ptr = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64)
        self.n_pts = self.n_rings = self.n_obs = 0
        n = len(faces)
        if n and (shapely.get_type_id(faces) == 3).all() and not shapely.get_num_interior_rings(faces).any() \
                and (shapely.get_num_coordinates(faces) >= 4).all():
            # every face one ring (the usual triangles): all at once, as `add` would put them
            xy, idx = shapely.get_coordinates(shapely.get_exterior_ring(faces), return_index=True)
            counts = np.bincount(idx, minlength=n)
            keep = np.ones(len(xy), dtype=bool)
            keep[np.cumsum(counts) - 1] = False  # the repeated closing point of every ring
            self.pts = np.ascontiguousarray(xy[keep], dtype=float)
            self.ring_ptr = np.concatenate([[0], np.cumsum(counts - 1)]).astype(np.int64)
            self.ring_sign = np.ones(n)
            self.obs_ptr = np.arange(n + 1, dtype=np.int64)
            self.n_pts, self.n_rings, self.n_obs = len(self.pts), n, n
        else:
            for face in faces:
                self.add(face)

    def copy(self) -> _Obstacles:
        out = copy.copy(self)
        out.pts, out.ring_ptr, out.ring_sign, out.obs_ptr = (a.copy() for a in (self.pts, self.ring_ptr,
                                                                              self.ring_sign, self.obs_ptr))
        return out

    @staticmethod
    def _room(a: np.ndarray, need: int) -> np.ndarray:
        if len(a) >= need:
            return a
        grown = np.zeros((max(need, 2 * len(a)), *a.shape[1:]), dtype=a.dtype)
        grown[:len(a)] = a
        return grown

    def add(self, geom) -> None:
        rings = _rings(geom)
        k = sum(len(r) for r, _ in rings)
        self.pts = self._room(self.pts, self.n_pts + k)
        self.ring_ptr = self._room(self.ring_ptr, self.n_rings + len(rings) + 1)
        self.ring_sign = self._room(self.ring_sign, self.n_rings + len(rings))
        self.obs_ptr = self._room(self.obs_ptr, self.n_obs + 2)
        for ring, sign in rings:
            self.pts[self.n_pts:self.n_pts + len(ring)] = ring
            self.n_pts += len(ring)
            self.ring_sign[self.n_rings] = sign
            self.n_rings += 1
            self.ring_ptr[self.n_rings] = self.n_pts
        self.n_obs += 1
        self.obs_ptr[self.n_obs] = self.n_rings


@dataclass(eq=False)
class Room:
    """What is on one piece, for the tabs and labels still to place: its face polygons (shapely,
    in an STRtree) and the tabs and off-face label boxes placed so far (`add`, `extra`). `key`: a
    digest of all of it (the faces' coordinates in order, then every geometry added, in order):
    equal keys, equal rooms (`choose_tab`'s memo)."""

    faces: np.ndarray  # shapely Polygons, one per face
    tree: object = field(init=False)
    face_bounds: np.ndarray = field(init=False)  # (F, 4) x0, y0, x1, y1 of every face
    key: bytes = field(init=False)
    extra: list = field(default_factory=list)
    # (x0, y0, x1, y1) of each extra in the first len(extra) rows (room to grow below them: a
    # piece's rooms take hundreds of tabs and labels one by one, and are asked after each)
    _bounds: np.ndarray = field(default_factory=lambda: np.zeros((16, 4)))
    _table: _Obstacles = field(init=False)  # the faces' and extras' rings (`blocked`)
    _extra_wkb: list = field(default_factory=list)  # each extra's WKB (`near_key`)
    _face_wkb: np.ndarray | None = None  # each face's WKB, made when `near_key` first asks

    def __post_init__(self) -> None:
        import shapely

        self.tree = shapely.STRtree(self.faces)
        self._table = _Obstacles(self.faces)
        self.face_bounds = np.ascontiguousarray(shapely.bounds(self.faces), dtype=float).reshape(-1, 4)
        digest = hashlib.blake2b(np.ascontiguousarray(shapely.get_num_coordinates(self.faces)).tobytes(),
                                 digest_size=16)
        digest.update(np.ascontiguousarray(shapely.get_coordinates(self.faces)).tobytes())
        self.key = digest.digest()

    def copy(self) -> Room:
        """The same room, its placed geometries in lists of their own (the faces and tree shared)."""
        out = copy.copy(self)
        out.extra, out._bounds = list(self.extra), self._bounds.copy()
        out._extra_wkb = list(self._extra_wkb)
        out._table = self._table.copy()
        return out

    def add(self, geoms) -> None:
        """Place shapely geometries (tabs, label boxes, leaders) on the piece."""
        import shapely

        digest = hashlib.blake2b(self.key, digest_size=16)
        for g in geoms:
            wkb = shapely.to_wkb(g)
            if len(self.extra) == len(self._bounds):
                self._bounds = np.concatenate([self._bounds, np.zeros_like(self._bounds)])
            self._bounds[len(self.extra)] = g.bounds
            self.extra.append(g)
            self._extra_wkb.append(wkb)
            self._table.add(g)
            digest.update(wkb)
        self.key = digest.digest()

    def near_key(self, bounds: tuple[float, float, float, float], skip_face: int) -> bytes:
        """A digest of what lies near `bounds` (x0, y0, x1, y1): the faces and extras whose bounds
        meet them, each by its coordinates, the faces in their order, then the extras in theirs,
        and which of those faces is `skip_face`. Equal digests of a region that holds every
        obstacle a test of the room could meet: equal answers, whatever lies elsewhere on the
        piece and however its faces are numbered (`choose_tab`'s memo)."""
        import shapely

        region = shapely.box(*bounds)
        faces = self._faces_near(region)
        extras = self._extras_near(region)
        if self._face_wkb is None:
            self._face_wkb = shapely.to_wkb(self.faces)
        skip = np.flatnonzero(faces == skip_face)
        digest = hashlib.blake2b(np.array([len(faces), len(extras), skip[0] if len(skip) else -1],
                                          dtype=np.int64).tobytes(), digest_size=16)
        for f in faces.tolist():
            digest.update(self._face_wkb[f])
        for e in extras.tolist():
            digest.update(self._extra_wkb[e])
        return digest.digest()

    def obstacle_table(self) -> tuple:
        """What `overlap_kernels.first_clear_box` reads of the room: its obstacles' table (points,
        ring pointers and signs, obstacle pointers), the faces' bounds (F, 4), the extras'
        bounds (E, 4) and E."""
        t = self._table
        return t.pts, t.ring_ptr, t.ring_sign, t.obs_ptr, self.face_bounds, self._extra_bounds(), len(self.extra)

    def _extra_bounds(self) -> np.ndarray:
        """(E, 4) x0, y0, x1, y1 of every extra (a view: later additions leave its rows as they are)."""
        return self._bounds[:len(self.extra)]

    def obstacle_ids(self, region, skip_face: int | None = None) -> np.ndarray:
        """The obstacles whose bounds meet `region`'s, as the table numbers them (faces, but
        `skip_face`, then len(faces) + the extras' indices)."""
        faces = self._faces_near(region, skip_face)
        return np.concatenate([faces, len(self.faces) + self._extras_near(region)]).astype(np.int64)

    def _faces_near(self, region, skip_face: int | None = None) -> np.ndarray:
        """Indices of the faces (but `skip_face`) whose bounds meet `region`'s, in index order (in
        the tree's order they would depend on the whole piece, and so would `blocked`'s sums)."""
        faces = np.sort(self.tree.query(region))
        return faces if skip_face is None else faces[faces != skip_face]

    def geometries(self, ids: np.ndarray) -> list:
        """The faces and extras numbered as the table numbers them (`obstacle_ids`)."""
        n = len(self.faces)
        return [self.faces[i] if i < n else self.extra[i - n] for i in ids.tolist()]

    def obstacles(self, region, skip_face: int | None = None) -> list:
        """Faces (but `skip_face`) and extras whose bounds meet `region`'s."""
        return self.geometries(self.obstacle_ids(region, skip_face))

    def _extras_near(self, region) -> np.ndarray:
        """Indices of the extras whose bounds meet `region`'s."""
        if not self.extra:
            return np.zeros(0, dtype=np.int64)
        x0, y0, x1, y1 = region.bounds
        b = self._extra_bounds()
        return np.flatnonzero((b[:, 0] <= x1) & (x0 <= b[:, 2]) & (b[:, 1] <= y1) & (y0 <= b[:, 3]))

    def extras_near(self, region) -> list:
        """The extras whose bounds meet `region`'s."""
        return [self.extra[i] for i in self._extras_near(region)]

    def blocked(self, poly, skip_face: int | None = None, clear: float = 0.0,
                keep_free: Callable[[], np.ndarray] | None = None) -> bool:
        """True when `poly` (a shapely Polygon) overlaps a face (but `skip_face`) or an extra by
        more than OVERLAP_MM2, or comes within `clear` mm of them (poly grown by shapely's buffer,
        quad_segs=2) by more than that outside `keep_free()`: convex rings (d, m, 2) where near
        contact is expected (made only when asked for).

        A convex poly is measured by a compiled kernel (`overlap_kernels.blocked_by`), and grown
        by shapely only where that decides: the buffer lies between poly's edges moved out and
        joined by chords and the same edges extended to meet, so an area above OVERLAP_MM2 within
        the first, or none within the second, gives the answer (about 9 tests in 10 on a crowded
        piece). Any other poly goes to shapely's overlays."""
        import shapely

        from .overlap_kernels import blocked_by

        x0, y0, x1, y1 = poly.bounds
        region = shapely.box(x0 - clear, y0 - clear, x1 + clear, y1 + clear)  # holds the grown poly
        faces = self._faces_near(region, skip_face)
        extras = self._extras_near(region)
        if not len(faces) and not len(extras):
            return False
        if poly.geom_type == "Polygon" and not poly.interiors:
            t = self._table
            ring = np.asarray(poly.exterior.coords)[:-1]
            discs = keep_free() if (clear and keep_free is not None) else _NO_DISCS
            obstacles = np.concatenate([faces, len(self.faces) + extras]).astype(np.int64)
            answer = blocked_by(ring, float(clear), discs, _NO_RING, OVERLAP_MM2, t.pts, t.ring_ptr, t.ring_sign,
                                t.obs_ptr, obstacles)
            if answer == 2:  # shapely's buffer decides
                exact = np.asarray(poly.buffer(clear, quad_segs=2).exterior.coords)[:-1]
                answer = blocked_by(ring, float(clear), discs, exact, OVERLAP_MM2, t.pts, t.ring_ptr, t.ring_sign,
                                    t.obs_ptr, obstacles)
            if answer >= 0:
                return bool(answer)
        # faces, tabs and labels never overlap one another: areas against each of them add up
        others = np.array([self.faces[i] for i in faces] + [self.extra[i] for i in extras], dtype=object)
        if shapely.area(shapely.intersection(poly, others)).sum() > OVERLAP_MM2:
            return True
        if not clear:
            return False
        hit = shapely.intersection(poly.buffer(clear, quad_segs=2), others)
        if keep_free is not None:
            hit = shapely.difference(hit, shapely.union_all(shapely.polygons(keep_free())))
        return shapely.area(hit).sum() > OVERLAP_MM2


_NO_DISCS = np.zeros((0, 1, 2))
_NO_RING = np.zeros((0, 2))
# a unit circle as shapely's Point.buffer draws it (16 segments a quarter, from angle 0 clockwise)
_CIRCLE = np.stack([np.cos(np.arange(64) * -np.pi / 32), np.sin(np.arange(64) * -np.pi / 32)], axis=1)


def _fold_of(part, side: CutSide) -> np.ndarray | None:
    """The stretch (2, 2) of the side's edge under a tab part: its boundary points on the edge."""
    pts = np.asarray(part.exterior.coords)
    length = side.length
    u = (side.p1 - side.p0) / length
    rel = pts - side.p0
    off = np.abs(rel[:, 0] * u[1] - rel[:, 1] * u[0])
    on = off < 1e-6 * max(1.0, length)
    if on.sum() < 2:
        return None
    t = np.clip(rel[on] @ u, 0.0, length)
    if t.max() - t.min() < 1e-6:
        return None
    return np.array([side.p0 + u * t.min(), side.p0 + u * t.max()])


def _depth(poly: np.ndarray, side: CutSide) -> float:
    return float(np.max((poly - side.p0) @ side.outward()))


def _clipped(s: int, side: CutSide, room: Room) -> Tab | None:
    """The full tab on sides[s] minus everything within TAB_CLEAR_MM of the piece's other faces and
    extras; None when less than the minimum glue area, hinge or depth stays."""
    import shapely
    from shapely.geometry import Polygon

    from .overlap_kernels import overlap_area

    full = tab_polygon(side, full_depth(side.length), 45.0)
    if full is None:
        return None
    whole = Polygon(full)
    ids = room.obstacle_ids(whole.buffer(TAB_CLEAR_MM, quad_segs=2), side.face)
    near = room.geometries(ids)
    rest = whole
    if near:
        # what is left can be no more than the full tab less the obstacles' area within it (they
        # never overlap one another): too little glue area is told without the overlays below
        t = room._table
        covered = overlap_area(full, _NO_DISCS, t.pts, t.ring_ptr, t.ring_sign, t.obs_ptr, ids)
        if covered == covered and whole.area - covered < MIN_GLUE_FRAC * whole.area - 1e-9:
            return None
        # grown so the chords of the buffer's arcs and the simplification below keep TAB_CLEAR_MM
        grow = TAB_CLEAR_MM / math.cos(math.pi / 8) + SIMPLIFY_MM
        rest = shapely.difference(whole, shapely.union_all(near).buffer(grow, quad_segs=2))
        # opening: slivers thinner than a millimetre do not hold glue
        rest = rest.buffer(-0.3, quad_segs=2).buffer(0.3, quad_segs=2).intersection(rest)
    parts, folds = [], []
    for g in getattr(rest, "geoms", [rest]):
        if g.geom_type != "Polygon" or g.area < MIN_PART_MM2:
            continue
        g = g.simplify(SIMPLIFY_MM).intersection(whole)  # back inside the trapezoid: off its own face
        fold = _fold_of(g, side)
        if fold is None or g.geom_type != "Polygon":
            continue
        parts.append(np.asarray(g.exterior.coords)[:-1])
        folds.append(fold)
    if not parts:
        return None
    area = sum(Polygon(p).area for p in parts)
    depth = max(_depth(p, side) for p in parts)
    hinged = float(sum(np.linalg.norm(f[1] - f[0]) for f in folds))
    if (area < MIN_GLUE_FRAC * whole.area or hinged < MIN_FOLD_FRAC * side.length
            or depth < min(TAB_MIN_DEPTH_MM, full_depth(side.length)) - 1e-9):
        return None
    return Tab(s, tuple(parts), np.array(folds), depth, "tapered" if len(parts) == 1 else "split")


def choose_tab(sides: tuple[CutSide, CutSide], rooms: list[Room], memo: dict | None = None,
               key: tuple | None = None) -> Tab | None:
    """The tab of a glued pair: the first of TAB_VARIANTS that fits on either side (the first side
    first), else the larger clipped tab of the two sides; None when nothing fits (see the module
    docstring). A tab may touch the faces beside its fold line at the corners, nothing else.

    It depends on nothing but the two sides and what lies near them on their pieces: every tab
    tried on a side lies within its full depth of the side's ends (trapezoids taper inwards), and
    the tests meet only obstacles whose bounds come within TAB_CLEAR_MM of a tab's. So `memo` (a
    dict kept across drawings of one model's pieces: make draws them again after cutting some)
    keeps it by the sides' coordinates and what lies within NEAR_MM more than that of each side
    (`Room.near_key`): a pair drawn again beside the same faces and tabs gets the tab found
    before, untested, though its piece was cut elsewhere and its faces renumbered. `key`: the
    pair's `tab_key`, when the caller has made it already."""
    if memo is None:
        return _choose_tab(sides, rooms)
    key = tab_key(sides, rooms) if key is None else key
    if key not in memo:
        memo[key] = _choose_tab(sides, rooms)
    return memo[key]


def tab_key(sides: tuple[CutSide, CutSide], rooms: list[Room]) -> tuple:
    """`choose_tab`'s memo key of a glued pair: its sides and what lies near each on its piece."""
    return tuple(_side_key(side, rooms[side.piece]) for side in sides)


NEAR_MM = 0.01  # margin of `choose_tab`'s memo key around the region its tests can reach


def _side_key(side: CutSide, room: Room) -> tuple:
    """A side's coordinates and what lies near it on its piece (`choose_tab`'s memo key)."""
    reach = full_depth(side.length) + TAB_CLEAR_MM + NEAR_MM
    lo, hi = np.minimum(side.p0, side.p1) - reach, np.maximum(side.p0, side.p1) + reach
    return (side.k, side.p0.tobytes(), side.p1.tobytes(), side.tri.tobytes(),
            room.near_key((float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])), side.face))


def _choose_tab(sides: tuple[CutSide, CutSide], rooms: list[Room]) -> Tab | None:
    import shapely

    from .overlap_kernels import first_unblocked

    # where a tab's fold line meets the neighbouring faces: near contact expected there (the discs
    # around a side's ends)
    def corners(s: int) -> np.ndarray:
        return np.stack([sides[s].p0, sides[s].p1])[:, None, :] + 2 * TAB_CLEAR_MM * _CIRCLE

    # every variant on either side, in order (those that make a valid polygon)
    shapes: list[list[tuple[float, float, int, str]]] = [[], []]  # per side: (depth, side angle, variant, reason)
    for v, (depth_kind, side_deg, reason) in enumerate(TAB_VARIANTS):
        for s, side in enumerate(sides):
            full = full_depth(side.length)
            depth = full if depth_kind == "full" else TAB_MIN_MM
            if depth_kind == "min" and depth >= full:
                continue
            shapes[s].append((depth, side_deg, v, reason))
    tries = []
    for s, side in enumerate(sides):
        polys = tab_polygons(side, [(depth, deg) for depth, deg, _v, _r in shapes[s]]) if shapes[s] else None
        if polys is not None:
            tries += [(v, s, poly, depth, reason) for (depth, _deg, v, reason), poly in zip(shapes[s], polys)]
    tries = [t[1:] for t in sorted(tries, key=lambda t: (t[0], t[1]))]
    if tries:
        polys = np.array([poly for _s, poly, _d, _r in tries])
        valid = shapely.is_valid(shapely.polygons(polys))
        tries, polys = [t for t, ok in zip(tries, valid) if ok], polys[valid]
    if tries:
        # the first that nothing blocks: a compiled test of them all (`Room.blocked` asked for a
        # tab it cannot tell)
        side_of = np.array([s for s, _p, _d, _r in tries], dtype=np.int64)
        skip = np.array([sides[0].face, sides[1].face], dtype=np.int64)
        discs = np.stack([corners(0), corners(1)])
        tables = [rooms[side.piece].obstacle_table() for side in sides]
        c = 0
        while c < len(tries):
            k, status = first_unblocked(polys[c:], side_of[c:], skip, discs, TAB_CLEAR_MM, OVERLAP_MM2,
                                        *tables[0], *tables[1])
            c += int(k)
            if status < 0:
                break
            s, poly, depth, reason = tries[c]
            side = sides[s]
            if status == 0 or not rooms[side.piece].blocked(shapely.Polygon(poly), side.face, TAB_CLEAR_MM,
                                                              functools.partial(corners, s)):
                return Tab(s, (poly,), np.array([[side.p0, side.p1]]), depth, reason)
            c += 1
    clipped = [tab for s, side in enumerate(sides) if (tab := _clipped(s, side, rooms[side.piece])) is not None]
    return max(clipped, key=_area, default=None)


def _area(tab: Tab) -> float:
    from shapely.geometry import Polygon

    return sum(Polygon(p).area for p in tab.polygons)
