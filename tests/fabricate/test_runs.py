"""fabricate/pieces.py `seam_runs` and labels.py `PieceLabels.run`: where a label per glue edge
does not fit, consecutive glue edges between the same two copies (a chain through mesh vertices
where no other cut edge ends) share one label, ticked at both ends."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from polyfold.fabricate.labels import TICK_MM, PieceLabels, label_font, text_width
from polyfold.fabricate.pieces import seam_runs
from polyfold.fabricate.tabs import CutSide, Room


def _pairs(keys):
    return [((min(a, b), max(a, b)), []) for a, b in keys]


def test_a_chain_through_vertices_of_two_cut_edges_is_one_run_in_order() -> None:
    # cut edges: the path 5-0-1-2-3, then 3 branches to 4 and 6 (3 ends three cut edges)
    keys = [(1, 2), (3, 4), (0, 5), (2, 3), (0, 1), (3, 6)]
    pairs = _pairs(keys)
    runs = seam_runs(pairs, [k for k, _ in pairs])
    assert sorted(len(r) for r in runs) == [1, 1, 4]
    chain = next(r for r in runs if len(r) == 4)
    order = [pairs[i][0] for i in chain]
    assert order in ([(0, 5), (0, 1), (1, 2), (2, 3)], [(2, 3), (1, 2), (0, 1), (0, 5)])
    assert sorted(i for r in runs for i in r) == list(range(len(pairs)))  # every pair once


def test_an_open_edge_or_a_third_cut_edge_at_a_vertex_ends_a_run() -> None:
    pairs = _pairs([(0, 1), (1, 2)])
    assert len(seam_runs(pairs, [(0, 1), (1, 2)])) == 1
    # vertex 1 also ends a cut edge that is glued to nothing (an open boundary)
    assert len(seam_runs(pairs, [(0, 1), (1, 2), (1, 9)])) == 2


def test_a_closed_loop_is_one_run_and_long_chains_are_cut_evenly() -> None:
    loop = _pairs([(0, 1), (1, 2), (2, 0)])
    (run,) = seam_runs(loop, [k for k, _ in loop])
    assert sorted(run) == [0, 1, 2]
    path = _pairs([(i, i + 1) for i in range(10)])
    runs = seam_runs(path, [k for k, _ in path], max_edges=4)
    assert sorted(len(r) for r in runs) == [3, 3, 4]
    # each part still consecutive along the chain
    for r in runs:
        ends = [v for i in r for v in path[i][0]]
        assert len(set(ends)) == len(r) + 1


def test_a_run_gets_one_label_and_a_tick_into_its_face_at_each_end() -> None:
    # three faces along a straight outline y = 0 (faces above it, y > 0 on the page)
    tris = [np.array([[x, 0.0], [x + 4.0, 0.0], [x + 2.0, 3.0]]) for x in (0.0, 4.0, 8.0)]
    room = Room(np.array([Polygon(t) for t in tris], dtype=object))
    labels = PieceLabels(room, label_font(2.0))
    sides = [(CutSide(0, f, 0, t[0], t[1], t), (), None) for f, t in enumerate(tris)]
    labels.run("7", sides)
    assert (labels.stats.runs, labels.stats.unplaced) == (1, 0)
    assert [item.text for item in labels.items] == ["7"]
    ticks = labels.leaders
    assert len(ticks) == 2
    starts = sorted(tuple(np.round(t[0], 9)) for t in ticks)
    assert starts == [(0.0, 0.0), (12.0, 0.0)]  # the run's two ends
    for t in ticks:
        length = float(np.linalg.norm(t[1] - t[0]))
        assert 0.0 < length <= TICK_MM + 1e-9
        assert any(Polygon(tri).buffer(1e-9).contains(Point(*t[1])) for tri in tris)  # into a face
    # the label keeps clear of the ticks
    item = labels.items[0]
    assert all(LineString(t).distance(Point(item.x, item.y)) > 0.5 for t in ticks)


def test_a_single_edge_run_has_no_ticks() -> None:
    tri = np.array([[0.0, 0.0], [20.0, 0.0], [10.0, 15.0]])
    labels = PieceLabels(Room(np.array([Polygon(tri)], dtype=object)), label_font(2.0))
    labels.edge(CutSide(0, 0, 0, tri[0], tri[1], tri), "12")
    assert labels.leaders == [] and labels.stats.runs == 0
    assert [item.text for item in labels.items] == ["12"]
    assert labels.items[0].size == pytest.approx(label_font(2.0))


def test_grid_search_goes_around_a_wall_through_its_gap() -> None:
    from polyfold.fabricate.labels import _grid_bfs

    free = np.ones((20, 20), dtype=bool)
    free[10, :] = False  # a wall across the grid ...
    free[10, 17] = True  # ... with a gap near its right end
    ok = np.zeros((1, 20, 20), dtype=bool)
    ok[0, 15, 2] = True  # the only free spot: beyond the wall, on the left
    dist, found = _grid_bfs(free, 5, 2, 100, ok, 5)
    assert found.tolist() == [[0, 15, 2]]
    assert dist[10, 17] > 0 and dist[10, 5] == -1  # through the gap, never through the wall
    # the straight way would be 10 steps; around through the gap it is longer
    assert dist[15, 2] > 10
    # a step limit stops the search before it gets there
    assert len(_grid_bfs(free, 5, 2, 10, ok, 5)[1]) == 0


def test_a_bent_leader_leaves_a_pocket_of_labels_and_keeps_clear_of_them() -> None:
    from polyfold.fabricate.labels import _Taken, text_box

    face = np.array([[-40.0, -40.0], [40.0, -40.0], [0.0, 40.0]])
    labels = PieceLabels(Room(np.array([Polygon(face)], dtype=object)), label_font(2.0))
    # p in a corridor of labels too narrow for one, closed on the right, its left end facing a
    # column of labels: the way to a free spot turns around a corner
    at = ([(x, y) for x in (-7.0, -2.0, 3.0) for y in (-2.2, 2.2)] + [(6.5, 0.0)]
          + [(-13.0, y) for y in (-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0)])
    boxes = [Polygon(text_box(np.array(q), np.array([1.0, 0.0]), "888", labels.size)) for q in at]
    for b in boxes:
        labels.boxes.add(np.asarray(b.exterior.coords)[:4])
    p = np.zeros(2)
    _k, centre, pts = next(_Taken(labels).routed_near(p, [(text_width("888", labels.size), 2.0)], 10))
    assert np.allclose(pts[0], p) and len(pts) > 2  # bent
    assert any(LineString([p, centre]).intersects(b) for b in boxes)  # the straight way is blocked
    assert min(LineString(pts).distance(b) for b in boxes) > 0.1  # no stretch crosses or grazes a label
    spot = Polygon(text_box(centre, np.array([1.0, 0.0]), "888", labels.size))
    assert not any(spot.intersects(b) for b in boxes)
