"""fabricate/tabs.py: a glue tab goes on the other side of the edge when the first is blocked (by
a face or a tab already placed), is clipped around what is in the way when neither side has room
for a whole one, and is None only when not even the minimum glue area fits."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

from polyfold.fabricate.tabs import (MIN_FOLD_FRAC, MIN_GLUE_FRAC, TAB_CLEAR_MM, TAB_VARIANTS, CutSide, Room, choose_tab,
                                     full_depth)


def _rooms(*faces_per_piece):
    return [Room(np.array([Polygon(f) for f in faces], dtype=object)) for faces in faces_per_piece]


TRI0 = np.array([[0.0, 0.0], [20.0, 0.0], [10.0, 15.0]])
TRI1 = TRI0 + [40.0, 0.0]
SIDE0 = CutSide(0, 0, 0, TRI0[0], TRI0[1], TRI0)
SIDE1 = CutSide(1, 0, 0, TRI1[0], TRI1[1], TRI1)


def test_tab_moves_to_the_other_side_when_the_first_is_blocked():
    # in front of side 0's edge (y = 0, tab downwards) lies another face of its piece, 0.5 mm away
    blocker = np.array([(-5, -0.5), (25, -0.5), (10, -20)])
    tab = choose_tab((SIDE0, SIDE1), _rooms([TRI0, blocker], [TRI1]))
    assert tab is not None and tab.side == 1 and tab.reason == "full"
    (poly,) = tab.polygons
    assert poly[:, 1].max() <= 1e-9  # below the edge, away from its face
    assert np.allclose(poly[[0, 3]], TRI1[:2]) and np.allclose(tab.folds[0], TRI1[:2])
    assert np.isclose(tab.depth, full_depth(20.0))
    # nothing in the way: the first side
    assert choose_tab((SIDE0, SIDE1), _rooms([TRI0], [TRI1])).side == 0
    # a tab already there blocks as a face does
    rooms = _rooms([TRI0], [TRI1])
    rooms[0].add([Polygon([(0, 0), (20, 0), (20, -3), (0, -3)])])
    assert choose_tab((SIDE0, SIDE1), rooms).side == 1
    # both sides blocked right at the edge: no tab
    blocker1 = blocker + [40.0, 0.0]
    assert choose_tab((SIDE0, SIDE1), _rooms([TRI0, blocker], [TRI1, blocker1])) is None
    assert TAB_VARIANTS[0] == ("full", 45.0, "full")


def test_a_tab_is_clipped_around_a_face_in_its_way_and_keeps_its_distance():
    # a narrow face reaching down to 1 mm below the middle of both edges: no whole tab fits, a
    # tab split in two around it does
    spike = np.array([(9.0, -1.0), (11.0, -1.0), (10.0, -30.0)])
    rooms = _rooms([TRI0, spike], [TRI1, spike + [40.0, 0.0]])
    tab = choose_tab((SIDE0, SIDE1), rooms)
    assert tab is not None and tab.reason == "split" and len(tab.polygons) == 2
    whole = Polygon([(0, 0), (20, 0), (20 - full_depth(20), -full_depth(20)), (full_depth(20), -full_depth(20))])
    parts = [Polygon(p) for p in tab.polygons]
    assert sum(p.area for p in parts) >= MIN_GLUE_FRAC * whole.area
    for p in parts:
        assert p.distance(Polygon(spike)) >= TAB_CLEAR_MM - 1e-6
        assert shapely.area(shapely.intersection(p, Polygon(TRI0))) < 1e-6
    # every part sits on the edge: its fold is a stretch of the edge
    for fold in tab.folds:
        assert np.allclose(fold[:, 1], 0.0) and fold[:, 0].min() >= -1e-9 and fold[:, 0].max() <= 20 + 1e-9


def test_a_clipped_tab_hinged_on_a_stub_is_no_tab():
    # a thin face along most of the edge, just beyond it: the tab's body below it keeps plenty of
    # glue area, but it would hang on the last 5 mm of a 20 mm edge (a flap that twists)
    bar = np.array([(0.5, -0.6), (14.0, -0.6), (14.0, -0.8), (0.5, -0.8)])
    rooms = _rooms([TRI0, bar], [TRI1, bar + [40.0, 0.0]])
    assert choose_tab((SIDE0, SIDE1), rooms) is None
    # shorter, the bar leaves half the edge free: a tapered tab, hinged along that half
    short = np.array([(0.5, -0.6), (8.0, -0.6), (8.0, -0.8), (0.5, -0.8)])
    tab = choose_tab((SIDE0, SIDE1), _rooms([TRI0, short], [TRI1, short + [40.0, 0.0]]))
    assert tab is not None and tab.reason == "tapered"
    hinged = sum(float(np.linalg.norm(f[1] - f[0])) for f in tab.folds)
    assert MIN_FOLD_FRAC * 20.0 <= hinged < 20.0 - 8.0


def test_a_rooms_key_says_what_is_on_it_in_order() -> None:
    """Equal faces and additions in the same order: equal keys (choose_tab's memo takes a tab
    found before for them); another addition, another order or other faces: other keys."""
    faces = np.array([Polygon([(0, 0), (10, 0), (0, 10)]), Polygon([(10, 0), (10, 10), (0, 10)])])
    tab_a, tab_b = Polygon([(0, 0), (10, 0), (8, -3), (2, -3)]), Polygon([(10, 0), (10, 10), (13, 8), (13, 2)])
    one, two = Room(faces.copy()), Room(faces.copy())
    assert one.key == two.key
    one.add([tab_a])
    assert one.key != two.key
    two.add([tab_a])
    assert one.key == two.key
    copied = one.copy()
    assert copied.key == one.key
    copied.add([tab_b])
    assert copied.key != one.key  # (the copy's additions are its own)
    a_then_b, b_then_a = Room(faces.copy()), Room(faces.copy())
    a_then_b.add([tab_a, tab_b])
    b_then_a.add([tab_b])
    b_then_a.add([tab_a])
    assert a_then_b.key != b_then_a.key
    moved = Room(np.array([shapely.affinity.translate(f, 1e-9, 0) for f in faces]))
    assert moved.key != Room(faces.copy()).key


def test_a_memo_gives_the_tab_choose_tab_gives() -> None:
    """With a memo, a pair met again beside the same room gets the very tab found before; beside
    a room with more on it, the tab is chosen again (and may differ)."""
    faces = np.array([Polygon([(0, 0), (20, 0), (0, 20)])])
    tri = np.array([[0.0, 0.0], [20.0, 0.0], [0.0, 20.0]])
    side = CutSide(0, 0, 0, tri[0], tri[1], tri)
    other = Room(np.array([Polygon([(0, -40), (20, -40), (20, -60)])]))
    memo: dict = {}
    rooms = [Room(faces.copy()), other]
    first = choose_tab((side, side), rooms, memo)
    assert first is not None and len(memo) == 1
    again = choose_tab((side, side), [Room(faces.copy()), other], memo)
    assert again is first and len(memo) == 1
    crowded = Room(faces.copy())
    crowded.add([Polygon([(-5, -1), (25, -1), (25, -30), (-5, -30)])])  # the tab's place is taken
    blocked = choose_tab((side, side), [crowded, other], memo)
    assert len(memo) == 2
    assert blocked is None and choose_tab((side, side), [crowded, other]) is None


def _grid_room(rng: np.random.Generator, shift: float, n: int = 5, cell: float = 4.0):
    """A jittered n x n grid of cell-mm squares (two triangles each) at x + shift, as a Room,
    with its triangles and the sides of its outline (CutSides of piece `shift > 0`)."""
    g = np.stack(np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij"), axis=-1) * cell
    g[1:-1, 1:-1] += rng.uniform(-1.0, 1.0, (n - 1, n - 1, 2))
    g[..., 0] += shift
    tris = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = g[i, j], g[i + 1, j], g[i + 1, j + 1], g[i, j + 1]
            tris += [np.array([a, b, c]), np.array([a, c, d])]
    piece = int(shift > 0)
    sides = []
    for f, tri in enumerate(tris):
        for k in range(3):
            p0, p1 = tri[k], tri[(k + 1) % 3]
            mid = (p0 + p1) / 2 - [shift, 0.0]
            if min(mid.min(), n * cell - mid.max()) < 1e-9:  # on the grid's outline
                sides.append(CutSide(piece, f, k, p0, p1, tri))
    return Room(np.array([Polygon(t) for t in tris], dtype=object)), sides


def test_choose_tab_takes_the_tab_the_one_by_one_rule_takes(monkeypatch):
    # random crowded rooms (tabs already placed along the outline): the variants tried on both
    # sides at once by a compiled test, and clipped tabs skipped when the obstacles' area alone
    # leaves too little glue, give the tab of trying each variant with Room.blocked, in order,
    # then clipping both sides in full
    import polyfold.fabricate.overlap_kernels as kernels
    from polyfold.fabricate.tabs import _CIRCLE, TAB_MIN_MM, _clipped, _choose_tab, _area, tab_polygon

    def one_by_one(sides, rooms):
        for depth_kind, side_deg, reason in TAB_VARIANTS:
            for s, side in enumerate(sides):
                depth = full_depth(side.length) if depth_kind == "full" else TAB_MIN_MM
                if depth_kind == "min" and depth >= full_depth(side.length):
                    continue
                poly = tab_polygon(side, depth, side_deg)
                ends = np.stack([side.p0, side.p1])[:, None, :] + 2 * TAB_CLEAR_MM * _CIRCLE
                if poly is not None and Polygon(poly).is_valid and not rooms[side.piece].blocked(
                        Polygon(poly), side.face, TAB_CLEAR_MM, lambda ends=ends: ends):
                    return ("whole", s, reason, poly)
        with monkeypatch.context() as m:
            m.setattr(kernels, "overlap_area", lambda *args: np.nan)  # (no shortcut)
            clipped = [t for s, side in enumerate(sides) if (t := _clipped(s, side, rooms[side.piece])) is not None]
        best = max(clipped, key=_area, default=None)
        return None if best is None else ("clipped", best.side, best.reason, np.concatenate(best.polygons))

    rng = np.random.default_rng(3)
    kinds = []
    for trial in range(30):
        (room0, sides0), (room1, sides1) = _grid_room(rng, 0.0), _grid_room(rng, 100.0)
        rooms = [room0, room1]
        for room, sides in ((room0, sides0), (room1, sides1)):
            for side in sides:
                if rng.random() < 0.4:  # a tab (or label) already beside some of the outline
                    n = side.outward()
                    off = rng.uniform(0.2, 4.0)
                    w = rng.uniform(0.5, 3.0)
                    at = side.p0 + rng.uniform(0.0, 1.0) * (side.p1 - side.p0) + n * off
                    u = (side.p1 - side.p0) / side.length
                    room.add([Polygon([at - u * w, at + u * w, at + u * w + n * w, at - u * w + n * w])])
        for _ in range(15):
            pair = (sides0[rng.integers(len(sides0))], sides1[rng.integers(len(sides1))])
            got = _choose_tab(pair, rooms)
            expect = one_by_one(pair, rooms)
            if expect is None:
                assert got is None
            else:
                kind, s, reason, poly = expect
                assert got is not None and (got.side, got.reason) == (s, reason)
                assert np.array_equal(np.concatenate(got.polygons), poly)
            kinds.append("none" if expect is None else expect[0])
    assert {"none", "whole", "clipped"} <= set(kinds)


def _crowded_rooms(rng: np.random.Generator):
    """Two random grid rooms (`_grid_room`) with tabs (or labels) already beside some of their
    outlines, and their outline sides."""
    (room0, sides0), (room1, sides1) = _grid_room(rng, 0.0), _grid_room(rng, 100.0)
    for room, sides in ((room0, sides0), (room1, sides1)):
        for side in sides:
            if rng.random() < 0.4:
                n, u = side.outward(), (side.p1 - side.p0) / side.length
                w = rng.uniform(0.5, 3.0)
                at = side.p0 + rng.uniform(0.0, 1.0) * (side.p1 - side.p0) + n * rng.uniform(0.2, 4.0)
                room.add([Polygon([at - u * w, at + u * w, at + u * w + n * w, at - u * w + n * w])])
    return [room0, room1], sides0, sides1


def test_the_memo_takes_a_tab_again_beside_the_same_things_on_a_cut_piece():
    # choose_tab's memo keys a pair by what lies near its sides: the same pair on pieces that lost
    # their faces and tabs far from it (faces renumbered, their order kept, as a cut piece's are)
    # gets the tab found before, and choosing it afresh there gives the very same tab; a tab
    # added beside a side makes it look again
    from polyfold.fabricate.tabs import NEAR_MM, _choose_tab

    rng = np.random.default_rng(5)
    hits = misses = 0
    for trial in range(20):
        rooms, sides0, sides1 = _crowded_rooms(rng)
        memo: dict = {}
        pair = (sides0[rng.integers(len(sides0))], sides1[rng.integers(len(sides1))])
        first = choose_tab(pair, rooms, memo)
        cut_rooms, cut_pair = [], []
        for side, room in zip(pair, rooms):
            reach = full_depth(side.length) + TAB_CLEAR_MM + NEAR_MM + 0.5
            lo, hi = np.minimum(side.p0, side.p1) - reach, np.maximum(side.p0, side.p1) + reach
            near = np.array([b[0] <= hi[0] and lo[0] <= b[2] and b[1] <= hi[1] and lo[1] <= b[3]
                             for b in shapely.bounds(room.faces)])
            kept = np.flatnonzero(near | (rng.random(len(near)) < 0.3))  # and some far ones
            cut = Room(room.faces[kept])
            cut.add([g for g in room.extra if (lambda b: b[0] <= hi[0] and lo[0] <= b[2] and b[1] <= hi[1]
                                                and lo[1] <= b[3])(g.bounds)])
            cut.add([Polygon([(500.0, 500.0), (510.0, 500.0), (505.0, 509.0)])])  # far away
            cut_rooms.append(cut)
            cut_pair.append(CutSide(side.piece, int(np.searchsorted(kept, side.face)), side.k, side.p0, side.p1,
                                    side.tri))
        again = choose_tab(tuple(cut_pair), cut_rooms, memo)
        fresh = _choose_tab(tuple(cut_pair), cut_rooms)
        assert again is first and len(memo) == 1
        if first is None:
            assert fresh is None
        else:
            assert (fresh.side, fresh.reason, fresh.depth) == (first.side, first.reason, first.depth)
            assert all(np.array_equal(a, b) for a, b in zip(fresh.polygons, first.polygons))
            assert np.array_equal(fresh.folds, first.folds)
        hits += 1
        # something new right beside the first side: looked at again
        side = cut_pair[0]
        n = side.outward()
        mid = (side.p0 + side.p1) / 2
        cut_rooms[0].add([Polygon([mid + n * 0.6, mid + n * 0.6 + [0.3, 0.0], mid + n * 0.9])])
        choose_tab(tuple(cut_pair), cut_rooms, memo)
        misses += len(memo) == 2
    assert hits == 20 and misses == 20
