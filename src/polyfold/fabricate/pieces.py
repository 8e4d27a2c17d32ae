"""Paper geometry of net pieces, in millimetres: cut outline, scored creases, glue tabs, labels.

In: single-piece nets (`unfold.piece_net`) with maps to the whole mesh's vertices (`PieceInput`,
`piece_input`), and a scale (mm per model unit). Out (`build_sheet_pieces`): `SheetPiece`s in
their own frame (y down, as on the page, outer side of the surface facing the reader) and the
`GlueEdge`s: which two cut edges glue together, the short label printed beside both, and which
side carries the glue tab (`tabs.choose_tab`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..deadline import Deadline
from ..mesh.geometry import FLAT_EPS, merged_edges  # flat creases are not scored, as in the FOLD files
from ..mesh.mesh import Mesh
from ..unfold.net import Net
from .labels import LABEL_PAD_MM, LabelStats, PieceLabels, label_font, piece_name, text_box, text_width, width_key
from .page import TextItem, upright
from .paper import MIN_LABEL_MM
from .tabs import CutSide, Room, Tab, choose_tab, full_depth, tab_key

OUTLINE_TOL_MM = 1e-3  # outline corners closer than this are one corner
RUN_MAX_EDGES = 8  # a seam run printed with one label spans at most this many edges


def _without_specks(outline):
    """The outline without what the union of faces and grown tabs leaves at nm scale, which files
    written to 1e-4 mm would turn into zero-length cuts: corners within OUTLINE_TOL_MM merged,
    then holes (and parts) that shrank to nothing dropped. Where merging corners makes the ring
    cross itself (it passes near itself: two faces meeting at a corner; a 1,392-face subdivided
    bunny), the corners are snapped to an OUTLINE_TOL_MM grid instead, which GEOS keeps valid."""
    import shapely

    def dropped(merged):
        parts = []
        for poly in getattr(merged, "geoms", [merged]):
            if poly.geom_type != "Polygon" or poly.area <= OUTLINE_TOL_MM ** 2:
                continue
            holes = [r for r in poly.interiors if len(r.coords) >= 4 and shapely.Polygon(r).area > OUTLINE_TOL_MM ** 2]
            parts.append(shapely.Polygon(poly.exterior, holes))
        return parts[0] if len(parts) == 1 else shapely.MultiPolygon(parts)

    out = dropped(shapely.remove_repeated_points(outline, OUTLINE_TOL_MM))
    if not out.is_valid:
        out = dropped(shapely.set_precision(outline, OUTLINE_TOL_MM))
    return out


@dataclass(frozen=True, eq=False)
class PieceInput:
    """One piece to draw: a single-piece net, its part, and its maps into the whole mesh."""

    net: Net
    part: int
    vertex_ids: np.ndarray  # piece-mesh vertex -> whole-mesh vertex
    face_ids: np.ndarray  # piece-mesh face -> whole-mesh face


def piece_input(net: Net, part: int, mesh_faces: np.ndarray, face_ids: np.ndarray) -> PieceInput:
    """A single-piece net (from `unfold.piece_net`) as a PieceInput. mesh_faces (F, 3): its faces
    in whole-mesh vertex ids, in the order of net.mesh.faces; face_ids (F,): their whole-mesh ids.
    (`Mesh.submesh` numbers a piece's vertices in the order of their whole-mesh ids.)"""
    return PieceInput(net=net, part=part, vertex_ids=np.unique(mesh_faces), face_ids=np.asarray(face_ids))


@dataclass(frozen=True, eq=False)
class SheetPiece:
    """A piece on paper, in mm (y down). outline = body (the faces) plus its tabs."""

    name: str
    part: int
    face_ids: np.ndarray
    faces_xy: np.ndarray  # (n, 3, 2)
    body: object  # shapely geometry: union of the faces
    outline: object  # shapely geometry: body + tabs (what is cut out)
    mountain: np.ndarray  # (m, 2, 2)
    valley: np.ndarray  # (v, 2, 2)
    slits: np.ndarray  # (s, 2, 2) cut edges inside the outline
    tabs: tuple[np.ndarray, ...]  # (k, 2) tab polygons (trapezoids, or clipped)
    tab_folds: np.ndarray  # (t, 2, 2) the fold line under each tab polygon
    texts: tuple[TextItem, ...]
    tab_mountain: np.ndarray  # (t,) bool: tab t folds as a mountain seen from the printed side (convex seam)
    footprint: object  # shapely geometry: outline + off-face labels (what packing keeps apart)
    leaders: np.ndarray  # (l, 2, 2) printed lines from an edge to its off-face label

    def cut_rings(self) -> list[np.ndarray]:
        """The outline's boundary rings (exterior and holes), without the repeated last point."""
        geoms = getattr(self.outline, "geoms", [self.outline])
        rings = []
        for g in geoms:
            for ring in [g.exterior, *g.interiors]:
                rings.append(np.asarray(ring.coords)[:-1])
        return rings


@dataclass(frozen=True)
class GlueEdge:
    """Two cut edges that are one mesh edge: glued together, labelled `label` on both sides."""

    label: str
    mesh_edge: tuple[int, int]  # whole-mesh vertex ids
    pieces: tuple[int, int]  # piece index of each side
    tab_piece: int | None  # the piece whose side carries the tab; None: no tab fits either side
    tab_height_mm: float  # the tab's depth from its fold line
    fold_angle: float = 0.0  # the seam's signed fold angle rho (radians, + convex) in the model
    printed: str = ""  # the label printed beside it: its own, or its seam run's (the run's lowest label)

    def __post_init__(self) -> None:
        if not self.printed:
            object.__setattr__(self, "printed", self.label)


@dataclass(frozen=True)
class LayoutStats:
    glue_edges: int
    tabs: int
    tabs_shrunk: int  # tabs smaller than full (reduced_tabs says which and why)
    tabs_moved: int  # put on the second side because the first had no room
    untabbed: tuple[str, ...]  # labels of the edges without a tab
    small_labels: int  # labels with no readable place (at their face's centroid, over lines or labels)
    open_edges: int  # boundary edges of the input mesh (cut, nothing to glue to)
    reduced_tabs: tuple[tuple[str, str], ...] = ()  # (edge label, reason: tabs.Tab.reason) of reduced tabs
    labels_on_tabs: int = 0  # glue labels printed on their tab (no room in the face)
    labels_outside: int = 0  # glue labels printed just outside their edge
    seam_runs: int = 0  # runs of several glue edges printed with one label (too dense for one per edge)
    crowded: tuple[tuple[int, float, float], ...] = ()  # (piece, x, y mm in its frame) of every small label
    labels_by_run: bool = False  # one glue label per seam run (one beside every edge found no room, or `by_run`)


@dataclass(frozen=True, eq=False)
class _Drawn:
    """One piece in mm before gluing: faces, their union, scored creases, its cut sides."""

    faces_xy: np.ndarray
    body: object
    mountain: np.ndarray
    valley: np.ndarray
    sides: list[tuple[tuple[int, int], CutSide]]  # (whole-mesh edge key, side)


def _draw(inp: PieceInput, i: int, scale: float) -> _Drawn:
    """Piece `i` in mm, y down (seen from the outer side): faces, creases by fold sign, cut sides."""
    import shapely

    net = inp.net
    mesh = net.mesh
    topo = mesh.topology
    xy = net.coords * scale
    xy[..., 1] *= -1.0  # y down, seen from the outer side
    body = shapely.union_all(shapely.polygons(xy))
    child = np.flatnonzero(net.parent >= 0)
    e = net.parent_edge[child]
    ends = topo.edges[e]
    k0 = np.argmax(mesh.faces[child] == ends[:, :1], axis=1)
    k1 = np.argmax(mesh.faces[child] == ends[:, 1:], axis=1)
    seg = np.stack([xy[child, k0], xy[child, k1]], axis=1)
    rho = mesh.fold_angles[e]
    # cut sides: face sides that are not creases of this piece
    E = topo.n_edges
    crease_keys = np.concatenate([child * E + e, net.parent[child] * E + e])
    occ_key = np.arange(len(mesh.faces))[:, None] * E + topo.face_edges
    is_cut = ~np.isin(occ_key, crease_keys)
    sides = []
    for f, k in zip(*np.nonzero(is_cut)):
        a, b = inp.vertex_ids[mesh.faces[f, k]], inp.vertex_ids[mesh.faces[f, (k + 1) % 3]]
        key = (int(min(a, b)), int(max(a, b)))
        sides.append((key, CutSide(i, int(f), int(k), xy[f, k], xy[f, (k + 1) % 3], xy[f])))
    drawn = ~merged_edges(mesh)[e]  # no line inside a flat polygon (coplanar faces, one input polygon)
    return _Drawn(xy, body, seg[drawn & (rho > FLAT_EPS)], seg[drawn & (rho < -FLAT_EPS)], sides)


def _pair_sides(drawn: list[_Drawn]) -> tuple[list[tuple[tuple[int, int], list[CutSide]]], int]:
    """Cut sides grouped by mesh edge: the glued pairs (ordered by their first piece, then mesh
    edge) and the number of open edges (one side only: a boundary of the input mesh)."""
    groups: dict[tuple[int, int], list[CutSide]] = {}
    for d in drawn:
        for key, side in d.sides:
            groups.setdefault(key, []).append(side)
    pairs = [(key, v) for key, v in groups.items() if len(v) == 2]
    open_edges = sum(1 for v in groups.values() if len(v) == 1)
    pairs.sort(key=lambda kv: (min(s.piece for s in kv[1]), kv[0]))
    return pairs, open_edges


def seam_runs(pairs, cut_keys: list[tuple[int, int]], max_edges: int = RUN_MAX_EDGES) -> list[list[int]]:
    """The glued pairs (indices into `pairs`) as seam runs, every pair in one run, runs in the
    order of their first pair: a run is a chain of glued edges that follow each other along both
    copies' outlines (consecutive edges meet at a mesh vertex where no other cut edge ends, so
    the faces around it are two fans, one per copy), in chain order, cut into near-equal stretches
    of at most `max_edges`. cut_keys: every cut mesh edge (glued, open or not), low/high ids."""
    from collections import Counter

    degree = Counter(v for key in set(cut_keys) for v in key)
    at: dict[int, list[int]] = {}
    for i, (key, _sides) in enumerate(pairs):
        for v in key:
            if degree[v] == 2:
                at.setdefault(v, []).append(i)
    links: dict[int, list[int]] = {}
    for ids in at.values():
        if len(ids) == 2:
            links.setdefault(ids[0], []).append(ids[1])
            links.setdefault(ids[1], []).append(ids[0])
    seen: set[int] = set()
    runs = []
    for i in range(len(pairs)):
        if i in seen:
            continue
        start, prev = i, -1  # to one end of the chain (around a closed loop: back at i)
        while True:
            step = [j for j in links.get(start, ()) if j != prev]
            if not step or step[0] == i:
                break
            prev, start = start, step[0]
        chain, prev = [start], -1
        seen.add(start)
        while True:
            step = [j for j in links.get(chain[-1], ()) if j != prev and j not in seen]
            if not step:
                break
            prev = chain[-1]
            chain.append(step[0])
            seen.add(step[0])
        k = -(-len(chain) // max_edges)
        runs += [list(part) for part in np.array_split(np.array(chain), k)]
    return runs


def seam_fold_angles(inputs: list[PieceInput]) -> tuple[dict[tuple[int, int], float], set[tuple[int, int]]]:
    """Signed fold angle rho (radians, + convex) of every edge of the model the pieces make, keyed
    by its whole-mesh vertex ids (low, high), and the edges inside a flat polygon of it
    (`merged_edges`): the pieces' faces put back together in 3D, so a seam between two pieces gets
    the angle of its two faces in the model."""
    n = max(int(inp.vertex_ids.max()) for inp in inputs) + 1
    vertices = np.zeros((n, 3))
    for inp in inputs:
        vertices[inp.vertex_ids] = inp.net.mesh.vertices
    whole = Mesh(vertices, np.concatenate([inp.vertex_ids[inp.net.mesh.faces] for inp in inputs]),
                 np.concatenate([inp.net.mesh.face_source for inp in inputs]))
    keys = [(int(a), int(b)) for a, b in np.sort(whole.topology.edges, axis=1)]
    merged = merged_edges(whole)
    return dict(zip(keys, whole.fold_angles.tolist())), {k for k, m in zip(keys, merged) if m}


@dataclass
class _Glued:
    """What gluing adds to each piece (lists per piece index) and the counts of LayoutStats."""

    n: int
    tabs: list = field(init=False)  # per piece: tab polygons (k, 2)
    tab_folds: list = field(init=False)  # per piece: fold segment (2, 2) of each tab polygon
    tab_mountain: list = field(init=False)  # per piece: per tab polygon, its seam is convex
    slits: list = field(init=False)
    glue: list = field(default_factory=list)
    untabbed: list = field(default_factory=list)
    reduced: list = field(default_factory=list)  # (label, reason) of every tab smaller than full
    n_tabs: int = 0
    moved: int = 0
    new_tabs: int = 0  # tabs not found in `_glue`'s memo
    ahead_tabs: int = 0  # of those, tabs its forked process chose

    def __post_init__(self) -> None:
        self.tabs, self.tab_folds, self.tab_mountain, self.slits = ([[] for _ in range(self.n)] for _ in range(4))


def _glue(pairs, drawn: list[_Drawn], rooms: list[Room], tabs: bool,
          rho: dict[tuple[int, int], float], deadline: Deadline, memo: dict | None = None,
          expected_new: int | None = None) -> tuple[_Glued, list[Tab | None]]:
    """Note slits (two sides of one piece that touch in the plane) and give each glued pair (label
    = its 1-based rank) its tab (`choose_tab`, with its `memo`); every tab joins its piece's `Room`.

    Where AHEAD_PAIRS tabs or more are to be chosen anew (`expected_new`, not found in the memo;
    None: every pair's) and there is a second core, the tabs of the later pairs (from AHEAD_SHARE
    of them on) are chosen ahead in a process forked from this one (`_tabs_ahead`), as if the
    pairs before them were not there, while this one chooses the earlier ones; each comes back
    with its memo key, and is taken where the pair's key here is the same: a tab depends on
    nothing but the pair's sides and what lies near them (`choose_tab`), and most tabs of the
    earlier pairs lie far from the later pairs. The same tabs whatever the process. The tabs
    chosen anew this time are counted in `_Glued.new_tabs`."""
    from ..processes import ForkedStream, can_fork, usable_cores

    out = _Glued(len(drawn))
    chosen: list[Tab | None] = []
    start, ahead = len(pairs), None
    if (tabs and (len(pairs) if expected_new is None else expected_new) >= AHEAD_PAIRS and usable_cores() > 1
            and can_fork()):
        memo = {} if memo is None else memo  # (the same tabs with or without one: `choose_tab`)
        start = int(AHEAD_SHARE * len(pairs))
        ahead = ForkedStream(lambda: _tabs_ahead(pairs, rooms, memo, start))
    try:
        for idx, (key, (o1, o2)) in enumerate(pairs):
            deadline.check(f"placing the tabs of {len(pairs):,} glued edges")
            label = str(idx + 1)
            if o1.piece == o2.piece and np.allclose(o1.p0, o2.p1, atol=1e-6) and np.allclose(o1.p1, o2.p0, atol=1e-6):
                out.slits[o1.piece].append(np.array([o1.p0, o1.p1]))  # the two sides touch in the plane
            tab = None
            if tabs and memo is None:
                tab = choose_tab((o1, o2), rooms)
            elif tabs:
                sides = (o1, o2)
                tab_id = tab_key(sides, rooms)
                out.new_tabs += tab_id not in memo
                if ahead is not None and idx >= start:  # (the values come in the pairs' order, one each)
                    got, value = ahead.next()
                    if got and value[0] not in memo:
                        memo[value[0]] = value[1]
                        out.ahead_tabs += value[0] == tab_id
                tab = choose_tab(sides, rooms, memo, tab_id)
            chosen.append(tab)
            if tab is None:
                if tabs:
                    out.untabbed.append(label)
                out.glue.append(GlueEdge(label, key, (o1.piece, o2.piece), None, 0.0, rho[key]))
                continue
            piece = _join_room(tab, (o1, o2), rooms)
            for poly, fold in zip(tab.polygons, tab.folds):
                out.tabs[piece].append(poly)
                out.tab_folds[piece].append(fold)
                out.tab_mountain[piece].append(rho[key] > 0)
            out.n_tabs += 1
            out.moved += tab.side == 1
            if tab.reason != "full":
                out.reduced.append((label, tab.reason))
            out.glue.append(GlueEdge(label, key, (o1.piece, o2.piece), piece, tab.depth, rho[key]))
    finally:
        if ahead is not None:
            ahead.close()
    return out, chosen


# `_glue` has the later pairs' tabs chosen ahead in a second process where this many are new (a
# 1,500-face model has about 750 pairs, the bunny 190): the first drawing of torus-50 decimated to
# 1,500 faces, 756 pairs, took 0.91 s in one process; with the tabs from half of the pairs on
# chosen ahead (0.43 s there; 58 of those 378 had to be chosen here again: a pair before them had
# put a tab near them), 0.58 s. From 0.4 of them on: 0.48 s (horse-302 decimated 0.61 -> 0.56 s,
# periscope2-44 0.60 -> 0.53 s; from 0.3, 0.35, 0.45, 0.55 or 0.6 on, slower on one of the three)
AHEAD_PAIRS = 300
AHEAD_SHARE = 0.4


def _join_room(tab: Tab, sides: tuple[CutSide, CutSide], rooms: list[Room]) -> int:
    """Add the tab's polygons to the room of the piece it goes on (one at a time: a room's key
    depends on how they are added); returns that piece."""
    from shapely.geometry import Polygon

    piece = sides[tab.side].piece
    for poly in tab.polygons:
        rooms[piece].add([Polygon(poly)])
    return piece


def _tabs_ahead(pairs, rooms: list[Room], memo: dict, start: int):
    """(`choose_tab`'s memo key, tab) of each of pairs[start:] in turn, chosen as `_glue` chooses
    them but in these rooms as they are (each tab joins them): for `_glue`'s forked process."""
    for _key, sides in pairs[start:]:
        key = tab_key(sides, rooms)
        tab = choose_tab(sides, rooms, memo, key)
        if tab is not None:
            _join_room(tab, sides, rooms)
        yield key, tab


# glue labels to place from which `_labels` places pieces in parallel (forked processes, one piece
# at a time each): horse-302 (308) gains 0.69 -> 0.58 s, fish-472 (478) 1.78 -> 1.15 s here; the
# bunny (136) loses, with a pool (15-20 ms: 0.128 s in one process, 0.141 s in two) and with
# `fork_map`'s plain forks since (6-8 ms: its make's two drawings 25 ms slower)
PARALLEL_LABELS = 250


@dataclass(frozen=True, eq=False)
class _Placed:
    """What `labels.PieceLabels` placed on one piece: its texts, the shapely geometries of its
    off-face labels and their leaders, its leader lines (2, 2), where labels with no readable
    place went, and the counts; and what `_labels`' shape gave for them (the piece's outline)."""

    items: list
    outside: list
    leaders: list
    crowded: list
    stats: LabelStats
    shape: tuple | None = None  # (memo key or None, outline, footprint): `build_sheet_pieces`' shape


def _labels(pairs, drawn: list[_Drawn], rooms: list[Room], chosen: list[Tab | None],
            min_label_mm: float, runs: list[list[int]], deadline: Deadline, all_or_none: bool = False,
            memo: dict | None = None, shape: Callable[[int, list], tuple] | None = None
            ) -> tuple[list[_Placed], LabelStats] | None:
    """Every piece's name, then one glue label per copy of every run of glued pairs (a run of
    one: the edge's own label on both sides; of several: its lowest label, `PieceLabels.run`).
    all_or_none: None when a glue label finds no readable place.

    A piece's labels look only at that piece (its faces, tabs, room and labels), so each piece is
    placed on its own, in the order of the runs; with PARALLEL_LABELS or more labels, pieces are
    placed in processes forked from this one (`processes.fork_map`, the most labels first): the
    same labels in the same places whatever the number of processes. `memo` keeps every piece's
    labels by all they depend on (its room's key, cut sides, font size, and its labels' sides
    with their tabs, in order; of its name and labels' texts, only their widths, `width_key`): a
    piece met again is not placed again, its texts renamed where they differ (a cut elsewhere
    renumbers the glue edges after it and renames the pieces after it).
    shape(i, off-face geometries), when given, is asked of every piece placed, where it was placed
    (the piece's outline, which waits for its labels: made beside the other pieces' labels), and
    kept with them; it may depend on nothing but the piece's room and those geometries."""
    from multiprocessing import RawValue

    from ..processes import fork_map, usable_cores

    size = label_font(min_label_mm)
    jobs: list[list[tuple[str, list]]] = [[] for _ in drawn]
    for run in runs:
        for copy in _run_copies(run, pairs, chosen):
            jobs[copy[0][0].piece].append((str(min(run) + 1), copy))
    failed = RawValue("b", 0)  # (shared with forked workers: the others stop at the next label)

    def place(i: int) -> _Placed | None:
        d = drawn[i]
        labels = PieceLabels(rooms[i], size, np.array([[side.p0, side.p1] for _key, side in d.sides]).reshape(-1, 2, 2))
        labels.piece(d.faces_xy, piece_name(i))
        for text, copy in jobs[i]:
            deadline.check(f"placing the glue labels of {len(pairs):,} glued edges")
            if failed.value:
                return None
            before = labels.stats.unplaced
            labels.run(text, copy)
            if all_or_none and labels.stats.unplaced > before:
                failed.value = 1
                return None
        return _Placed(labels.items, labels.outside, labels.leaders, labels.crowded, labels.stats,
                       None if shape is None else shape(i, labels.outside))

    texts = [(piece_name(i), *(text for text, _copy in jobs[i])) for i in range(len(drawn))]
    keys = [None if memo is None else _labels_key(drawn[i], rooms[i], size, all_or_none, texts[i], jobs[i])
            for i in range(len(drawn))]
    placed: list[_Placed | None] = [None if memo is None or k not in memo else _renamed(*memo[k], texts[i])
                                    for i, k in enumerate(keys)]
    order = sorted((i for i in range(len(drawn)) if placed[i] is None), key=lambda i: -len(jobs[i]))
    n_labels = sum(len(jobs[i]) for i in order)
    done = fork_map(place, order, usable_cores() if n_labels >= PARALLEL_LABELS else 1)
    if failed.value or any(p is None for p in done):
        return None
    for i, p in zip(order, done):
        placed[i] = p
        if memo is not None:
            memo[keys[i]] = (texts[i], p)
    stats = LabelStats()
    for p in placed:
        stats.on_tabs += p.stats.on_tabs
        stats.outside += p.stats.outside
        stats.unplaced += p.stats.unplaced
        stats.runs += p.stats.runs
    return placed, stats


def _labels_key(d: _Drawn, room: Room, size: float, all_or_none: bool, texts: tuple[str, ...],
                jobs: list[tuple[str, list]]) -> tuple:
    """All that `_labels` places a piece's labels from (see there), as a dict key; texts: its
    name, then its labels' texts (jobs' order)."""
    copies = tuple(tuple((side.key(), tuple(np.asarray(p).tobytes() for p in polys),
                          None if folds is None else np.asarray(folds).tobytes())
                         for side, polys, folds in copy) for _text, copy in jobs)
    return (room.key, size, all_or_none, tuple(side.key() for _key, side in d.sides), tuple(map(width_key, texts)),
            copies)


def _renamed(texts_then: tuple[str, ...], placed: _Placed, texts: tuple[str, ...]) -> _Placed | None:
    """A piece's labels placed with texts_then (`_labels_key`'s texts), their texts now `texts`
    (as wide: the same places); None where the two do not pair off one to one (to be placed
    anew)."""
    if texts == texts_then:
        return placed
    new = dict(zip(texts_then, texts))
    if (len(new) != len(set(new.values())) or any(new[a] != b for a, b in zip(texts_then, texts))
            or any(t.text not in new for t in placed.items)):
        return None
    return replace(placed, items=[replace(t, text=new[t.text]) for t in placed.items])


def _run_copies(run: list[int], pairs, chosen: list[Tab | None]) -> list[list[tuple]]:
    """The two copies of a run of glued pairs, each a list of `PieceLabels.run` entries (side, its
    tab parts, their folds) in run order: the sides of the next pair that continue a copy share an
    end with its last side."""
    copies: list[list[tuple]] = [[], []]
    for n, idx in enumerate(run):
        sides, tab = pairs[idx][1], chosen[idx]
        order = (0, 1)
        if n and _gap(copies[0][-1][0], sides[1]) < _gap(copies[0][-1][0], sides[0]):
            order = (1, 0)
        for c, s in enumerate(order):
            mine = tab is not None and tab.side == s
            copies[c].append((sides[s], tab.polygons if mine else (), tab.folds if mine else None))
    return copies


def _gap(last: CutSide, side: CutSide) -> float:
    """How far `side` is from continuing `last` along an outline: the distance between their
    nearest ends (infinite on another piece)."""
    if side.piece != last.piece:
        return math.inf
    ends = np.array([last.p0, last.p1])
    return min(float(np.min(np.linalg.norm(ends - p, axis=1))) for p in (side.p0, side.p1))


def _split_at(runs: list[list[int]], breaks: set[int]) -> list[list[int]]:
    """Runs cut so that every pair in `breaks` is a run of its own."""
    out = []
    for run in runs:
        part: list[int] = []
        for i in run:
            if i in breaks:
                out += [part] if part else []
                out.append([i])
                part = []
            else:
                part.append(i)
        out += [part] if part else []
    return out


def glue_strip(label: str, length: float, rho: float, part: int, size: float) -> SheetPiece:
    """A glue strip for a seam `length` mm long that has no room for a tab: a separate rectangle
    as long as the seam (or its label), 2 x `tabs.full_depth` wide, glued behind both sides of the seam, scored along its middle and
    labelled like a tab on both halves. Its printed side faces the model's inside, so it folds the
    other way from its seam: a valley on a convex seam. Named "S" + the seam's label."""
    import shapely

    depth = full_depth(length)
    long = max(length, text_width(label, size) + 2.0)  # never shorter than its label (trim after gluing)
    rect = np.array([[0.0, -depth], [long, -depth], [long, depth], [0.0, depth]])
    body = shapely.Polygon(rect)
    line = np.array([[[0.0, 0.0], [long, 0.0]]])
    none = np.zeros((0, 2, 2))
    texts = tuple(TextItem(label, long / 2, y, 0.0, size, "edge-label") for y in (-depth / 2, depth / 2))
    return SheetPiece(name=f"S{label}", part=part, face_ids=np.zeros(0, dtype=np.int64), faces_xy=np.zeros((0, 3, 2)),
                      body=body, outline=body, mountain=line if rho < 0 else none, valley=line if rho >= 0 else none,
                      slits=none, tabs=(), tab_folds=none, texts=texts, tab_mountain=np.zeros(0, dtype=bool),
                      footprint=body, leaders=none)


def with_side_notes(pieces: list[SheetPiece], glued_to: np.ndarray, min_label_mm: float = MIN_LABEL_MM
                    ) -> tuple[list[SheetPiece], int]:
    """(the pieces with "glue to X" printed on every face that is glued flat onto another piece's
    face, how many sides found no place for it): glued_to (F,) whole-mesh face -> a face of the side
    it is glued onto, -1 for none (`make --approximate hulls`: the sides where two convex parts
    touch). A note goes at the point of its side farthest from the side's edges (shapely's
    polylabel), along the side's long axis or across the page, as "glue to X" or "to X", at 1.5 x the
    glue labels' size down to their size, clear of the piece's other texts."""
    from shapely import Polygon, union_all

    piece_of = {int(f): k for k, p in enumerate(pieces) for f in p.face_ids}
    size = 1.5 * label_font(min_label_mm)
    out, missed = [], 0
    for p in pieces:
        sides: dict[str, list[int]] = {}
        for local, f in enumerate(p.face_ids):
            other = int(glued_to[f]) if 0 <= f < len(glued_to) else -1
            if other >= 0 and other in piece_of:
                sides.setdefault(pieces[piece_of[other]].name, []).append(local)
        texts = list(p.texts)
        for name, local in sides.items():
            taken = [Polygon(text_box(np.array([t.x, t.y]), np.array([math.cos(math.radians(t.angle)),
                                                                       -math.sin(math.radians(t.angle))]),
                                      t.text, t.size)) for t in texts]
            side = union_all([Polygon(t) for t in p.faces_xy[local]], grid_size=1e-6)
            spot = _note_spot(side, name, size, label_font(min_label_mm), taken)
            if spot is None:
                missed += 1
                continue
            texts.append(spot)
        out.append(replace(p, texts=tuple(texts)) if len(texts) > len(p.texts) else p)
    return out, missed


def _note_spot(side, name: str, size: float, smallest: float, taken: list) -> TextItem | None:
    """The note of a glued side (a shapely polygon, mm) naming piece `name`: see `with_side_notes`;
    None when it fits nowhere."""
    from shapely import Polygon
    from shapely.ops import polylabel

    if side.geom_type != "Polygon" or side.area <= 0:
        return None
    inner = side.buffer(-LABEL_PAD_MM)
    centre = np.asarray(polylabel(side, tolerance=0.05).coords[0])
    box = np.asarray(side.minimum_rotated_rectangle.exterior.coords)[:4]
    edges = np.diff(np.vstack([box, box[:1]]), axis=0)
    long = edges[np.argmax(np.linalg.norm(edges, axis=1))]
    along = long / max(float(np.linalg.norm(long)), 1e-12)
    for text in (f"glue to {name}", f"to {name}"):
        for u in (along, np.array([1.0, 0.0])):
            s = size
            while s >= smallest - 1e-9:
                glyphs = Polygon(text_box(centre, u, text, s))
                if inner.contains(glyphs) and not any(glyphs.intersects(t) for t in taken):
                    angle = upright(math.degrees(math.atan2(-u[1], u[0])))  # (the box is the same either way)
                    return TextItem(text, float(centre[0]), float(centre[1]), angle, s, "edge-label")
                s *= 0.9
    return None


def _outline(body, tabs: list[np.ndarray], outside: list):
    """A piece's outline (its faces' union `body` with its tabs) and footprint (with its labels
    printed off the faces, `outside`)."""
    import shapely

    tab_polys = [shapely.Polygon(t) for t in tabs]
    # a clipped tab meets its face mid-edge, where float noise would leave a hair-thin gap:
    # each tab is grown by 10 nm (invisible) so it overlaps its face, then all is unioned on a grid
    grown = [t.buffer(1e-5, join_style="mitre") for t in tab_polys]
    outline = shapely.union_all([body, *grown], grid_size=1e-6) if tab_polys else body
    outline = _without_specks(outline)
    return outline, (shapely.union_all([outline, *outside]) if outside else outline)


def build_sheet_pieces(inputs: list[PieceInput], scale: float, tabs: bool = True,
                       min_label_mm: float = MIN_LABEL_MM, deadline: Deadline = Deadline.never(),
                       by_run: bool = False, memo: dict | None = None
                       ) -> tuple[list[SheetPiece], list[GlueEdge], LayoutStats]:
    """Draw every piece in mm and pair up their cut edges (see the module docstring). Tabs:
    `tabs.choose_tab` per glued pair; pairs without one are listed in LayoutStats.untabbed.
    Labels: `labels.PieceLabels`, cap height at least `min_label_mm`: one beside every glued edge,
    or, when one of those finds no readable place, one per seam run (`LayoutStats.labels_by_run`);
    by_run: per seam run at once (a redraw of pieces whose drawing needed them: the failed try
    took a third of a dense model's drawing). OutOfTime past `deadline` (checked between pieces,
    tabs and labels). memo: one dict for all drawings of one model's pieces at one scale (make
    draws them again after cutting some): a glued pair's tab (`choose_tab`), a piece's labels
    (`_labels`) and its outline and footprint (`_outline`) found before are taken again where all
    they depend on is the same; the same drawings with or without it."""
    import shapely

    drawn = []
    for i, inp in enumerate(inputs):
        deadline.check(f"drawing {len(inputs):,} pieces")
        drawn.append(_draw(inp, i, scale))
    pairs, open_edges = _pair_sides(drawn)
    rooms = [Room(shapely.polygons(d.faces_xy)) for d in drawn]
    faces_keys = [room.key for room in rooms]  # (the faces' coordinates: before tabs join the rooms)
    rho, flat = seam_fold_angles(inputs)
    # a flat polygon whose faces close a cycle keeps one edge out of its tree: both sides lie on
    # each other in the plane, one polygon on paper, not a seam (no slit, label or tab)
    pairs = [(key, sides) for key, sides in pairs if not (key in flat and sides[0].piece == sides[1].piece)]
    tab_memo = None if memo is None else memo.setdefault("tabs", {})
    label_memo = None if memo is None else memo.setdefault("labels", {})
    g, chosen = _glue(pairs, drawn, rooms, tabs, rho, deadline, tab_memo,
                      None if memo is None else memo.get("new_tabs"))
    if memo is not None:
        memo["new_tabs"] = g.new_tabs  # (as many are likely new in the next drawing: `_glue` goes by it)
    shapes = None if memo is None else memo.setdefault("outlines", {})

    def shape(i: int, outside: list) -> tuple:
        """(memo key or None, outline, footprint) of piece i with its tabs and these off-face labels
        (`_outline`; a piece drawn again with the same faces, tabs and off-face labels: found
        before, by those as a key)."""
        key = None if shapes is None else (
            faces_keys[i], tuple(np.asarray(t).tobytes() for t in g.tabs[i]),
            tuple(shapely.to_wkb(outside).tolist()) if outside else ())
        if key is not None and key in shapes:
            return (key, *shapes[key])
        return (key, *_outline(drawn[i].body, g.tabs[i], outside))

    bare = [room.copy() for room in rooms]
    per_edge = None if by_run else _labels(pairs, drawn, rooms, chosen, min_label_mm,
                                           [[i] for i in range(len(pairs))], deadline, all_or_none=True,
                                           memo=label_memo, shape=shape)
    if per_edge is not None:
        placed, label_stats = per_edge
    else:
        # too dense for a readable label beside every edge: one per seam run (a glue strip's
        # edge stays on its own, the strip carries its label)
        runs = seam_runs(pairs, [key for d in drawn for key, _side in d.sides])
        runs = _split_at(runs, {int(label) - 1 for label in g.untabbed})
        # the shortest runs first: they sit where the mesh is densest and have the fewest places
        runs.sort(key=lambda run: sum(pairs[i][1][0].length for i in run))
        placed, label_stats = _labels(pairs, drawn, bare, chosen, min_label_mm, runs, deadline, memo=label_memo,
                                      shape=shape)
        for run in runs:
            for i in run:
                g.glue[i] = replace(g.glue[i], printed=str(min(run) + 1))
    pieces = []
    for i, (inp, d) in enumerate(zip(inputs, drawn)):
        key, outline, footprint = placed[i].shape
        if key is not None:
            shapes[key] = outline, footprint
        pieces.append(SheetPiece(
            name=piece_name(i), part=inp.part, face_ids=np.asarray(inp.face_ids), faces_xy=d.faces_xy, body=d.body,
            outline=outline, mountain=d.mountain.reshape(-1, 2, 2), valley=d.valley.reshape(-1, 2, 2),
            slits=np.array(g.slits[i]).reshape(-1, 2, 2), tabs=tuple(g.tabs[i]),
            tab_folds=np.array(g.tab_folds[i]).reshape(-1, 2, 2), texts=tuple(placed[i].items),
            tab_mountain=np.array(g.tab_mountain[i], dtype=bool), footprint=footprint,
            leaders=np.array(placed[i].leaders).reshape(-1, 2, 2)))
    size = label_font(min_label_mm)
    for label in g.untabbed:  # the last resort: a separate glue strip behind the seam
        idx = int(label) - 1
        key, (o1, _o2) = pairs[idx]
        pieces.append(glue_strip(label, o1.length, rho[key], inputs[o1.piece].part, size))
        g.glue[idx] = replace(g.glue[idx], tab_piece=len(pieces) - 1, tab_height_mm=full_depth(o1.length))
        g.reduced.append((label, "glue strip"))
    stats = LayoutStats(glue_edges=len(pairs), tabs=g.n_tabs, tabs_shrunk=len(g.reduced), tabs_moved=g.moved,
                        untabbed=(), small_labels=label_stats.unplaced, open_edges=open_edges,
                        reduced_tabs=tuple(g.reduced), labels_on_tabs=label_stats.on_tabs,
                        labels_outside=label_stats.outside, seam_runs=label_stats.runs // 2,
                        crowded=tuple((i, float(x), float(y)) for i, p in enumerate(placed) for x, y in p.crowded),
                        labels_by_run=per_edge is None)
    return pieces, g.glue, stats
