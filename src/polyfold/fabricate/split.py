"""Splitting pieces along creases so that they fill fewer pages.

A piece that `fit.split_to_fit` left as large as a page is usually a sprawling net whose arms
enclose space that no other piece fits into, so most of its page stays empty. `plan_pages` packs
the pieces onto a given number of pages, larger first, each onto the first page with room (the
bottom-left fill of `pack.PageFiller`). A piece that fits on no page is split along one crease:
the largest of its two sides that fits on some page (the emptiest first, or the first) goes there
and the other side goes back into the queue; when nothing of it fits anywhere, the plan fails
(None). With a `cap`, a part whose convex hull is larger than that is split first, whether or not
it fits whole: the largest side with a hull within the cap that fits goes onto a page (when no
such side fits, the part is placed or split as without a cap). A sprawling part encloses gaps that
the bottom-left fill cannot use, so compact parts fill a page denser (periscope2-44 and star-24
on one page instead of two). A side is a subtree of the piece's tree or what is left of the piece
without one, so only creases are cut and no face moves: the parts stay overlap-free. Only creases
the net allows to be cut are cut (`Net.cuttable`: never inside a flat polygon).

What is packed is a piece's footprint (outline and labels printed off its faces). The footprint of
a part is estimated before anything is redrawn: its faces with the tabs and labels the whole piece
has on them, plus room for a full-size tab on both sides of every crease cut (the tab goes on one
of them, `tabs.choose_tab`). The caller redraws the split pieces and packs their real footprints
(`pipeline.sheets.split_for_pages`): the plan only says where to cut. Glue strips (pieces without
a net) are placed whole.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely import MultiPolygon, Polygon

from ..deadline import clock
from ..unfold.net import Net, subtree_areas
from .pack import ANGLES, PageFiller, Spot, points_hull
from .pieces import SheetPiece
from .tabs import CutSide, full_depth, tab_polygon

# smallest part split off (either side), as a fraction of the printable area of a page (245 mm^2 on
# A4, a triangle of 22 mm sides): 0.01 gave 2 pages more and 29 pieces fewer over 45 benchmark meshes
MIN_PART = 0.005
MIN_PART_FACES = 2  # nor a single face (more glue per paper, and make's FOLD file of one has no path)
SPLIT_TRIES = 8  # candidate parts weighed per page before a finer look between the last two


@dataclass(frozen=True)
class PagePlan:
    """Where `plan_pages` cuts. cuts[i]: faces of piece i (ids into its net) whose crease to their
    parent is cut; order: (piece, root face) of every part in the order the plan placed them (a
    part is named by the face that is its root once the cuts are made); pages: how many pages."""

    cuts: tuple[np.ndarray, ...]
    order: tuple[tuple[int, int], ...]
    pages: int


class _Tree:
    """One piece as a tree of faces on paper (mm, the sheet piece's frame): per face the polygon of
    the face with what the piece has beside it (its tabs, its labels printed off the faces) and its
    area, the Euler-tour intervals (subtrees), and tab room on the creases cut. A piece without a
    net (a glue strip) is one part that is never split."""

    def __init__(self, piece: SheetPiece, net: Net | None) -> None:
        self.piece = piece
        self._room: dict[tuple[int, int], Polygon | None] = {}
        self._corners: tuple[np.ndarray, np.ndarray] | None = None  # `hull`'s, made on its first call
        if net is None:
            self.polys = np.array([piece.footprint], dtype=object)
            self.area = shapely.area(self.polys)
            self.parent = np.array([-1])
            self.tin, self.tout, self.by_tin = np.array([0]), np.array([1]), np.array([0])
            self.cuttable = np.array([False])
            return
        xy = np.asarray(piece.faces_xy, dtype=float)
        self.xy = xy
        self.parent = np.asarray(net.parent)
        self.parent_edge = np.asarray(net.parent_edge)
        self.face_edges = net.mesh.topology.face_edges
        faces = shapely.polygons(xy)
        extra, owner = [], []  # what the piece has beside its faces, and the face it goes with
        # each tab (or part of a split tab) to the face side under its fold line
        folds = np.asarray(piece.tab_folds, dtype=float).reshape(-1, 2, 2)
        if len(folds):
            sides = shapely.linestrings(np.stack([xy, np.roll(xy, -1, axis=1)], axis=2).reshape(-1, 2, 2))
            _, side = shapely.STRtree(sides).query_nearest(shapely.points(folds.mean(axis=1)), all_matches=False)
            extra += [Polygon(t) for t in piece.tabs]
            owner += (side // 3).tolist()
        # labels printed off the faces (the footprint beyond the outline) to the nearest face
        off = [g for g in shapely.get_parts(shapely.difference(piece.footprint, piece.outline)) if g.area > 0]
        if off:
            extra += off
            owner += shapely.STRtree(faces).query_nearest(off, all_matches=False)[1].tolist()
        beside: dict[int, list] = {}
        for g, f in zip(extra, owner):
            beside.setdefault(f, []).append(g)
        self.polys = faces.copy()
        for f, gs in beside.items():
            self.polys[f] = shapely.union_all([faces[f], *gs])
        self.area = shapely.area(self.polys)
        _, self.tin, self.tout = subtree_areas(net)
        self.by_tin = np.argsort(self.tin)
        self.cuttable = net.cuttable

    def root(self, mask: np.ndarray) -> int:
        """The face of a part (a connected set of the tree's faces) whose parent is not in it."""
        f = np.flatnonzero(mask & ((self.parent < 0) | ~mask[np.maximum(self.parent, 0)]))
        return int(f[0])

    def hull(self, mask: np.ndarray) -> float:
        """Area of the convex hull of the part (its faces with their tabs and labels; without tab
        room on the creases cut): the hull of the corners of its faces' hulls, which are made once,
        on the first call (plans without a cap never ask: a plan's time is the page split's budget)."""
        if self._corners is None:
            hulls = shapely.convex_hull(self.polys)
            self._corners = (shapely.get_coordinates(hulls), shapely.get_num_coordinates(hulls))
        corners, counts = self._corners
        return float(points_hull(corners[np.repeat(mask, counts)]).area)

    def room(self, f: int, side: int) -> Polygon | None:
        """Room for a full-size tab on the crease of face f to its parent, on f (side 0) or on the
        parent (side 1); None when the side is too short for a tab."""
        key = (f, side)
        if key not in self._room:
            g = f if side == 0 else int(self.parent[f])
            k = int(np.argmax(self.face_edges[g] == self.parent_edge[f]))
            xy = self.xy
            cut = CutSide(0, g, k, xy[g, k], xy[g, (k + 1) % 3], xy[g])
            poly = tab_polygon(cut, full_depth(cut.length), 45.0)
            self._room[key] = None if poly is None else Polygon(poly)
        return self._room[key]

    def outline(self, mask: np.ndarray) -> Polygon | MultiPolygon:
        """The whole piece's footprint, or the estimated one of a part: its faces with their tabs
        and labels, tab room on every cut crease."""
        if mask.all():
            return self.piece.footprint
        par = np.maximum(self.parent, 0)
        cut_here = np.flatnonzero(mask & (self.parent >= 0) & ~mask[par])  # crease to a parent outside
        cut_below = np.flatnonzero(~mask & (self.parent >= 0) & mask[par])  # crease to a child outside
        rooms = [self.room(int(f), 0) for f in cut_here] + [self.room(int(f), 1) for f in cut_below]
        return shapely.union_all([*self.polys[mask], *(r for r in rooms if r is not None)])

    def sides(self, mask: np.ndarray, lo: float, hi: float) -> list[tuple[float, int, bool]]:
        """The parts one cut of a crease inside the part `mask` makes, as (area, face, below): the
        subtree below the face (below=True) or the rest, with area in [lo, hi], the other side at
        least lo, and MIN_PART_FACES faces or more on both sides; largest first."""
        pre = np.zeros((2, len(mask) + 1))
        pre[:, 1:] = np.cumsum(np.stack([np.where(mask, self.area, 0.0), mask])[:, self.by_tin], axis=1)
        total, n_total = pre[0, -1], pre[1, -1]
        fs = np.flatnonzero(mask & self.cuttable & mask[np.maximum(self.parent, 0)])
        sub, n_sub = pre[:, self.tout[fs]] - pre[:, self.tin[fs]]
        area = np.concatenate([sub, total - sub])
        n = np.concatenate([n_sub, n_total - n_sub])
        face = np.concatenate([fs, fs])
        below = np.repeat([True, False], len(fs))
        keep = ((area >= lo) & (area <= hi) & (total - area >= lo)
                & (n >= MIN_PART_FACES) & (n_total - n >= MIN_PART_FACES))
        o = np.argsort(-area[keep], kind="stable")
        return list(zip(area[keep][o].tolist(), face[keep][o].tolist(), below[keep][o].tolist()))

    def split(self, mask: np.ndarray, face: int, below: bool) -> tuple[np.ndarray, np.ndarray]:
        """(the side named by (face, below), the other side) of cutting the crease of `face`."""
        sub = np.zeros_like(mask)
        sub[self.by_tin[self.tin[face]:self.tout[face]]] = True
        side = mask & sub if below else mask & ~sub
        return side, mask & ~side


def _split_onto(filler: PageFiller, page: int, tree: _Tree, t: int, mask: np.ndarray, lo: float,
                tries: int, cap: float = math.inf) -> tuple[Spot, np.ndarray, np.ndarray, int] | None:
    """The largest side of one cut of part (t, mask) that fits on `page` and whose convex hull is
    at most `cap` mm^2: a spread of `tries` candidates (largest first) finds the largest of them
    that fits, then the candidates between it and the last one that did not are tried in turn.
    (spot, side, rest, the face whose crease to its parent is cut) or None."""
    cands = tree.sides(mask, lo, min(cap, 0.95 * filler.free_area(page)))
    if not cands:
        return None

    def attempt(i: int):
        _, face, below = cands[i]
        side, rest = tree.split(mask, face, below)
        if cap < math.inf and tree.hull(side) > cap:  # like a side that does not fit: hull >= area
            return None
        spot = filler.spot(page, tree.outline(side), (t, side.tobytes()))
        return None if spot is None else (spot, side, rest, face)

    n = len(cands)
    picks = sorted({round(j * (n - 1) / max(tries - 1, 1)) for j in range(min(tries, n))})
    prev = -1
    for i in picks:
        found = attempt(i)
        if found is not None:
            for j in range(prev + 1, min(i, prev + 1 + tries)):  # larger ones skipped by the spread
                better = attempt(j)
                if better is not None:
                    return better
            return found
        prev = i
    return None


def plan_pages(pieces: Sequence[SheetPiece], nets: Sequence[Net], page_size: tuple[float, float], margin: float,
               gap: float, n_pages: int, deadline: float, angles: int = ANGLES, seed: int = 0,
               emptiest_first: bool = True, min_part: float = MIN_PART, tries: int = SPLIT_TRIES,
               rasters: dict | None = None, cap: float | None = None) -> PagePlan | None:
    """Cut creases so that the pieces fit on `n_pages` pages (see the module docstring). pieces[i]
    is drawn from the single-piece net nets[i] (same faces, same order); pieces after the last net
    (glue strips) are placed whole. Packed: the pieces' footprints. page_size (width, height mm),
    margin, gap, angles and seed as `pack.pack_outlines`. A part split off goes onto the page with
    the most room that takes one (`emptiest_first`), else the first. A side split off, and the rest,
    cover at least `min_part` of a page's printable area. None when the plan finds no way, or at
    `deadline` (a `deadline.clock()` time). A plan without cuts is pack_outlines' first fit in
    the plan's order: given that order as its hint, pack_outlines puts the pieces on `n_pages` pages.
    `rasters`: a dict kept across plans of these very pieces (same page, gap, angles, seed), so that
    a part tried by one is not rasterised again by the next. `cap`: the largest convex hull of a part
    placed whole (a fraction of the printable area), when given."""
    filler = PageFiller(page_size, margin, gap, n_pages, angles, seed, rasters)
    lo = min_part * filler.printable_area
    cap_area = math.inf if cap is None else cap * filler.printable_area
    trees = [_Tree(p, nets[i] if i < len(nets) else None) for i, p in enumerate(pieces)]
    # the queue: (-area, sequence number, piece, faces); larger first, ties in input order
    queue = sorted((-float(tr.area.sum()), t, t, np.ones(len(tr.area), dtype=bool)) for t, tr in enumerate(trees))
    seq = len(queue)
    placed: list[tuple[int, int]] = []
    cuts: list[list[int]] = [[] for _ in trees]
    while queue:
        if clock() > deadline:
            return None
        _, _, t, mask = queue.pop(0)
        tree = trees[t]
        outline, key = tree.outline(mask), (t, mask.tobytes())
        pages = sorted(range(n_pages), key=lambda p: -filler.free_area(p)) if emptiest_first else range(n_pages)
        hit = None
        if cap_area < math.inf and tree.hull(mask) > cap_area:  # not compact: a compact side first
            hit = next((h for pg in pages if (h := _split_onto(filler, pg, tree, t, mask, lo, tries, cap_area))), None)
        if hit is None:
            spot = next((s for pg in range(n_pages) if (s := filler.spot(pg, outline, key)) is not None), None)
            if spot is not None:
                filler.put(spot)
                placed.append((t, tree.root(mask)))
                continue
            for pg in pages:
                hit = _split_onto(filler, pg, tree, t, mask, lo, tries)
                if hit is not None:
                    break
            else:
                return None
        spot, side, rest, face = hit
        filler.put(spot)
        cuts[t].append(face)
        placed.append((t, tree.root(side)))
        bisect.insort(queue, (-float(tree.area[rest].sum()), seq, t, rest), key=lambda q: q[:2])
        seq += 1
    return PagePlan(tuple(np.array(sorted(c), dtype=np.int64) for c in cuts[:len(nets)]), tuple(placed), n_pages)


# the smaller side of a cut for labels keeps at least this fraction of the piece's area: an even cut
# opens the most outline to paper, a sliver would only add a seam
LABEL_SPLIT_LEAST = 0.2


def plan_label_cuts(pieces: Sequence[SheetPiece], nets: Sequence[Net | None],
                    crowded: Sequence[tuple[int, float, float]]) -> tuple[np.ndarray, ...]:
    """Where to cut the pieces some of whose labels found no readable place (`crowded`: piece, x,
    y mm in its frame, as `pieces.LayoutStats.crowded`): per such piece one crease, the one
    nearest to those places (in whole mm) among those whose two sides each keep at least
    LABEL_SPLIT_LEAST of its area, the evener first. Those places are where the piece's edges are
    densest, usually the hub of a fan of thin faces; a cut through it puts half the fan's edges on
    an outline with open paper beside them. cuts[i]: faces of nets[i] whose crease to their parent
    is cut (none for the other pieces)."""
    where: dict[int, list[tuple[float, float]]] = {}
    for i, x, y in crowded:
        where.setdefault(i, []).append((x, y))
    cuts = [np.zeros(0, dtype=np.int64) for _ in pieces]
    for i, pts in where.items():
        if i >= len(nets) or nets[i] is None:
            continue
        tree = _Tree(pieces[i], nets[i])
        total = float(tree.area.sum())
        options = [(area, f) for area, f, below in tree.sides(np.ones(len(tree.parent), dtype=bool),
                                                              LABEL_SPLIT_LEAST * total, total) if below]
        if not options:
            continue
        area, faces = np.array([a for a, _ in options]), np.array([f for _, f in options])
        k = np.argmax(tree.face_edges[faces] == tree.parent_edge[faces][:, None], axis=1)
        creases = shapely.linestrings(np.stack([tree.xy[faces, k], tree.xy[faces, (k + 1) % 3]], axis=1))
        near = np.round(shapely.distance(creases, shapely.multipoints(np.array(pts))))
        best = np.lexsort((np.abs(area / total - 0.5), near))[0]
        cuts[i] = np.array([faces[best]], dtype=np.int64)
    return tuple(cuts)
