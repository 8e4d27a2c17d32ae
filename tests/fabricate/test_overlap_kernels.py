"""fabricate/overlap_kernels.py and the `tabs.Room.blocked` built on it: areas of overlap and the
blocked answers are checked against shapely's overlays (GEOS), an independent implementation, on
random scenes: convex windows against non-convex obstacles with holes, near contact included."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from polyfold.fabricate.overlap_kernels import is_convex, offset_bounds, overlap_area
from polyfold.fabricate.tabs import OVERLAP_MM2, TAB_CLEAR_MM, Room, _Obstacles


def _convex(rng: np.random.Generator, centre: np.ndarray, size: float) -> np.ndarray:
    hull = shapely.convex_hull(shapely.multipoints(centre + rng.normal(0.0, size, (rng.integers(3, 9), 2))))
    ring = np.asarray(hull.exterior.coords)[:-1]
    return ring if rng.random() < 0.5 else ring[::-1].copy()


def _obstacle(rng: np.random.Generator, centre: np.ndarray, size: float):
    """A star-shaped (non-convex) polygon, sometimes with a hole, or a triangle."""
    if rng.random() < 0.3:
        return Polygon(centre + rng.normal(0.0, size, (3, 2))).buffer(0)
    k = int(rng.integers(5, 12))
    angle = (np.arange(k) + rng.uniform(0.0, 0.9, k)) * 2 * np.pi / k  # gaps under pi: a simple ring
    radius = size * rng.uniform(0.3, 1.2, k)
    outer = centre + np.stack([np.cos(angle), np.sin(angle)], axis=1) * radius[:, None]
    holes = [centre + 0.15 * size * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]])] if rng.random() < 0.3 else []
    poly = Polygon(outer, holes)
    assert Polygon(outer).is_valid
    return poly if poly.is_valid else Polygon(outer)


def _table(geoms) -> _Obstacles:
    return _Obstacles(np.array(geoms, dtype=object))


def test_overlap_area_matches_shapely_on_random_scenes():
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(300):
        window = _convex(rng, np.zeros(2), 2.0)
        geoms = [_obstacle(rng, rng.normal(0.0, 2.0, 2), 1.5) for _ in range(int(rng.integers(1, 6)))]
        discs = shapely.buffer(shapely.points(window[:2]), 1.0, quad_segs=16)
        disc_rings = shapely.get_coordinates(discs).reshape(2, -1, 2)[:, :-1].copy()
        t = _table(geoms)
        ids = np.arange(len(geoms), dtype=np.int64)
        win = Polygon(window)
        plain = overlap_area(window, np.zeros((0, 1, 2)), t.pts, t.ring_ptr, t.ring_sign, t.obs_ptr, ids)
        expect = sum(shapely.intersection(win, g).area for g in geoms)
        worst = max(worst, abs(plain - expect))
        outside = overlap_area(window, disc_rings, t.pts, t.ring_ptr, t.ring_sign, t.obs_ptr, ids)
        expect = sum(shapely.difference(shapely.intersection(win, g), shapely.union_all(discs)).area for g in geoms)
        worst = max(worst, abs(outside - expect))
    assert worst < 1e-9


def test_the_offset_rings_hold_shapelys_buffer_between_them():
    rng = np.random.default_rng(3)
    for _ in range(200):
        ring = _convex(rng, np.zeros(2), 3.0)
        assert is_convex(ring, 1e-9)
        within, around = offset_bounds(ring, 0.5)
        for quad_segs in (1, 2, 8):
            grown = Polygon(ring).buffer(0.5, quad_segs=quad_segs)
            assert shapely.difference(Polygon(within), grown).area < 1e-9
            assert shapely.difference(grown, Polygon(around)).area < 1e-9
    star = np.array([[0, 0], [4, 0], [1, 1], [0, 4]], dtype=float)
    assert not is_convex(star, 1e-9)


def _blocked_by_shapely(room: Room, poly, skip_face, clear, keep_free) -> bool:
    """Room.blocked as shapely's overlays alone (what it was before the kernels)."""
    grown = poly.buffer(clear, quad_segs=2) if clear else poly
    near = room.obstacles(grown, skip_face)
    if not near:
        return False
    others = np.array(near, dtype=object)
    if shapely.area(shapely.intersection(poly, others)).sum() > OVERLAP_MM2:
        return True
    if not clear:
        return False
    hit = shapely.intersection(grown, others)
    if keep_free is not None:
        hit = shapely.difference(hit, shapely.union_all(shapely.polygons(keep_free())))
    return bool(shapely.area(hit).sum() > OVERLAP_MM2)


@pytest.mark.parametrize("seed", [1, 2])
def test_blocked_gives_shapelys_answers_near_contact(seed):
    # tabs (trapezoids) beside faces and extras that come within 0 to 1 mm of them: most answers
    # are decided by the chord- and mitre-joined rings, the rest by the buffer itself
    rng = np.random.default_rng(seed)
    answers = []
    for _ in range(400):
        edge = rng.uniform(3.0, 15.0)
        depth = min(6.0, 0.4 * edge)
        tab = np.array([[0.0, 0.0], [depth, -depth], [edge - depth, -depth], [edge, 0.0]])
        face = np.array([[0.0, 0.0], [edge, 0.0], [edge / 2, edge]])
        centre = tab.mean(axis=0)
        others = [face]
        for _ in range(int(rng.integers(1, 4))):
            # a thin triangle pointing at the tab from 0.8 mm away to 0.1 mm inside it
            around = Polygon(tab).buffer(rng.uniform(-0.1, 0.8), quad_segs=8).exterior
            tip = np.asarray(around.interpolate(rng.uniform(0.0, around.length)).coords[0])
            away = (tip - centre) / max(np.linalg.norm(tip - centre), 1e-9)
            side = np.array([-away[1], away[0]])
            others.append(np.array([tip, tip + 3.0 * away + side, tip + 3.0 * away - side]))
        room = Room(np.array([Polygon(o) for o in others], dtype=object))
        if rng.random() < 0.5:
            room.add([Polygon(others[-1] + [0.0, -4.0])])
        discs = shapely.get_coordinates(shapely.buffer(shapely.points(tab[[0, 3]]), 2 * TAB_CLEAR_MM,
                                                       quad_segs=16)).reshape(2, -1, 2)[:, :-1].copy()
        poly = Polygon(tab)
        for clear, keep in ((TAB_CLEAR_MM, lambda: discs), (TAB_CLEAR_MM, None), (0.0, None)):
            got = room.blocked(poly, 0, clear, keep)
            assert got == _blocked_by_shapely(room, poly, 0, clear, keep)
            answers.append(got)
    assert 0.2 < np.mean(answers) < 0.8  # both answers are tested


def test_grown_box_meets_gives_shapelys_answers():
    # label boxes against boxes and leader strips placed 0-1 mm from their grown outline
    from polyfold.fabricate.labels import LABEL_PAD_MM, _grown_box_hits, text_box
    from polyfold.fabricate.overlap_kernels import grown_box_apart, grown_box_meets

    rng = np.random.default_rng(5)
    answers, unsure_apart = [], []
    for _ in range(600):
        turn = rng.uniform(0, 2 * np.pi)
        box = text_box(rng.normal(0.0, 20.0, 2), np.array([np.cos(turn), np.sin(turn)]), str(rng.integers(1, 999)), 2.5)
        grown = Polygon(box).buffer(LABEL_PAD_MM, quad_segs=1)
        edge = grown.exterior
        tip = np.asarray(edge.interpolate(rng.uniform(0.0, edge.length)).coords[0])
        away = tip - box.mean(axis=0)
        away /= np.linalg.norm(away)
        gap = rng.choice([0.0, rng.uniform(-0.3, 1.0)])
        if rng.random() < 0.5:  # another label box, a corner towards this one
            spin = rng.uniform(0, 2 * np.pi)
            other = text_box(np.zeros(2), np.array([np.cos(spin), np.sin(spin)]), "88", 2.5)
            corner = other[np.argmin(other @ away)]
            other = other - corner + tip + gap * away
        else:  # a leader strip, bent
            a = tip + gap * away
            other = np.asarray(shapely.LineString([a, a + 4 * away, a + 4 * away + rng.normal(0, 3, 2)])
                               .buffer(0.15).exterior.coords)[:-1]
        near = [(Polygon(other), np.ascontiguousarray(other))]
        expect = bool(shapely.intersects(grown, Polygon(other)))
        assert _grown_box_hits(box, near) == expect
        ptr = np.array([0, len(other)], dtype=np.int64)
        quick = grown_box_meets(box, LABEL_PAD_MM, near[0][1], ptr)
        assert quick in (-1, int(expect))
        apart = grown_box_apart(box, LABEL_PAD_MM, near[0][1], ptr)
        assert apart == (shapely.distance(grown, Polygon(other)) > 1e-9)  # whatever the axis between them
        answers.append(quick)
        unsure_apart.append(quick == -1 and apart)
    answers = np.array(answers)
    assert (answers == 1).mean() > 0.2 and (answers == 0).mean() > 0.2 and (answers == -1).mean() < 0.3
    assert sum(unsure_apart) >= 5  # (the distance test tells boxes the first cannot: 7 here)
    # a ring inside the grown box, and one around it, with no sides near each other: not apart
    box = text_box(np.zeros(2), np.array([1.0, 0.0]), "88", 2.5)
    for ring in (0.2 * box, 10.0 * box, np.array([[0.0, 0.0], [1e-7, 0.0], [0.0, 1e-7]])):
        assert not grown_box_apart(box, LABEL_PAD_MM, ring, np.array([0, len(ring)], dtype=np.int64))


def _crowded_piece(rng: np.random.Generator):
    """PieceLabels on a 6 x 6 grid of jittered 4 mm squares (two triangles each) with a few tabs
    in its room and label boxes and leader strips placed over it (one strip a MultiPolygon: no
    ring for the compiled tests)."""
    from shapely.geometry import LineString

    from polyfold.fabricate.labels import PieceLabels, text_box

    g = np.stack(np.meshgrid(np.arange(7.0), np.arange(7.0), indexing="ij"), axis=-1) * 4.0
    g[1:-1, 1:-1] += rng.uniform(-1.0, 1.0, (5, 5, 2))
    tris = []
    for i in range(6):
        for j in range(6):
            a, b, c, d = g[i, j], g[i + 1, j], g[i + 1, j + 1], g[i, j + 1]
            tris += [np.array([a, b, c]), np.array([a, c, d])]
    room = Room(np.array([Polygon(t) for t in tris], dtype=object))
    room.add([Polygon([[x, -0.5], [x + 1.0, -3.0], [x + 3.0, -3.0], [x + 4.0, -0.5]]) for x in (0.0, 8.0, 16.0)])
    labels = PieceLabels(room, 2.5)
    for _ in range(12):
        turn = rng.uniform(0, np.pi)
        u = np.array([np.cos(turn), np.sin(turn)])
        centre = rng.uniform(-4.0, 28.0, 2)
        labels._put("7", centre, u, 2.5, "edge-label", text_box(centre, u, "77", 2.5))
    for _ in range(4):
        a = rng.uniform(-4.0, 28.0, 2)
        labels.strips.add_geom(LineString([a, a + rng.normal(0.0, 5.0, 2)]).buffer(0.1))
    labels.strips.add_geom(shapely.MultiPolygon([Polygon(t + [40.0, 0.0]) for t in tris[:2]]))
    return labels


def test_first_clear_box_takes_the_spot_that_hits_and_blocked_take():
    # label spots around a crowded piece: the first clear of labels, leaders and the room, found
    # by `PieceLabels._clear_spots` (the compiled test, asking the Python tests only where it says
    # it cannot tell), is the one the Python tests (spatial hash, shapely, `Room.blocked`) find one
    # by one
    from polyfold.fabricate.labels import LABEL_PAD_MM, _box_cells, text_boxes
    from polyfold.fabricate.overlap_kernels import first_clear_box

    rng = np.random.default_rng(11)
    found, asked, tested = 0, 0, 0
    for trial in range(40):
        labels = _crowded_piece(rng)
        a, b = labels.boxes.rings, labels.strips.rings
        for _ in range(10):
            turn = rng.uniform(0, np.pi)
            boxes = text_boxes(rng.uniform(-6.0, 30.0, (8, 2)), np.array([np.cos(turn), np.sin(turn)]), "123", 2.5)
            order = np.flatnonzero(rng.random(8) < 0.8)
            expect = next((int(i) for i in order if not (labels._hits(boxes[i]) or
                                                         labels.room.blocked(Polygon(boxes[i]), None, TAB_CLEAR_MM))),
                          None)
            got = next(labels._clear_spots(boxes, shapely.polygons(boxes), order), None)
            assert got == expect
            found += got is not None
            for i in order:  # the boxes the compiled test leaves to Python, one by one
                asked += first_clear_box(boxes, np.array([i]), 0, _box_cells(boxes), LABEL_PAD_MM, a.pts, a.ring_ptr,
                                         a.cells, a.has_ring, a.n, b.pts, b.ring_ptr, b.cells, b.has_ring, b.n,
                                         TAB_CLEAR_MM, OVERLAP_MM2, *labels.room.obstacle_table())[1] == 1
                tested += 1
    assert 0.2 < found / 400 < 0.95  # spots found and not
    assert 0 < asked < 0.1 * tested  # the MultiPolygon strip (and unsure answers) went to Python, little else


def test_first_box_in_triangle_takes_the_box_inside_triangle_and_hits_take():
    # `PieceLabels._first_in_face` (the compiled test, `_hits` where it cannot tell) takes the box
    # that `inside_triangle` and `_hits` take one by one
    from polyfold.fabricate.labels import LABEL_PAD_MM, inside_triangle, text_boxes

    rng = np.random.default_rng(12)
    found = 0
    for trial in range(40):
        labels = _crowded_piece(rng)
        for _ in range(10):
            tri = rng.uniform(-4.0, 28.0, 2) + rng.normal(0.0, 8.0, (3, 2))
            turn = rng.uniform(0, np.pi)
            boxes = text_boxes(tri.mean(axis=0) + rng.normal(0.0, 1.5, (6, 2)), np.array([np.cos(turn), np.sin(turn)]),
                               "45", 1.5)
            expect = next((i for i in range(6) if inside_triangle(tri, boxes[i], LABEL_PAD_MM)
                           and not labels._hits(boxes[i])), None)
            got = labels._first_in_face(boxes, tri)
            assert got == expect
            found += got is not None
    assert 0.1 < found / 400 < 0.9
