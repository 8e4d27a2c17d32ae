"""fabricate/pack.py: packing net pieces onto pages by their real outlines."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
import shapely
from shapely import affinity
from shapely.geometry import LineString, Polygon, box

from polyfold.errors import PolyfoldError
from polyfold.fabricate.pack import (check_packing, fits_page, pack_outlines, Packing, PageFiller, placed_outline,
                                     Placement)

A4 = (210.0, 297.0)


# ----------------------------------------------------------------------------------------------
# helpers


def moved(outline, pl: Placement):
    """The outline on its page, computed independently of Placement.apply (shapely.affinity)."""
    return affinity.translate(affinity.rotate(outline, pl.angle, origin=(0, 0)), *pl.offset)


def brute_force_problems(outlines, packing: Packing, gap: float) -> list[str]:
    """Every pair on every page and every piece against the printable rectangle, no index."""
    W, H = packing.page_size
    m = packing.margin
    placed = [moved(g, pl) for g, pl in zip(outlines, packing.placements)]
    out = []
    for i, q in enumerate(placed):
        x0, y0, x1, y1 = q.bounds
        if min(x0, y0) < m - 1e-9 or x1 > W - m + 1e-9 or y1 > H - m + 1e-9:
            out.append(f"{i} out of the printable area")
        if not 0 <= packing.placements[i].page < packing.n_pages:
            out.append(f"{i} on page {packing.placements[i].page}")
    for i in range(len(placed)):
        for j in range(i + 1, len(placed)):
            if packing.placements[i].page != packing.placements[j].page:
                continue
            if placed[i].intersection(placed[j]).area > 1e-9:
                out.append(f"{i} overlaps {j}")
            elif gap > 0 and placed[i].distance(placed[j]) < gap - 1e-9:
                out.append(f"{i} is {placed[i].distance(placed[j]):.3f} mm from {j}")
    return out


def assert_valid(outlines, packing: Packing, gap: float) -> None:
    assert len(packing.placements) == len(outlines)
    assert check_packing(outlines, packing, gap) == []
    assert brute_force_problems(outlines, packing, gap) == []
    assert {pl.page for pl in packing.placements} == set(range(packing.n_pages))  # no empty page
    pw, ph = packing.page_size[0] - 2 * packing.margin, packing.page_size[1] - 2 * packing.margin
    area = sum(g.area for g in outlines)
    assert packing.utilisation == pytest.approx(area / (packing.n_pages * pw * ph))


def snake(rng: np.random.Generator, steps: int, width: float) -> Polygon:
    """A wandering band (random walk with turns, buffered): long, non-convex, like a triangle strip."""
    heading, p, pts = rng.uniform(0, 2 * np.pi), np.zeros(2), [np.zeros(2)]
    for _ in range(steps):
        heading += rng.uniform(-1.4, 1.4)
        p = p + rng.uniform(8, 16) * np.array([np.cos(heading), np.sin(heading)])
        pts.append(p)
    g = LineString(pts).buffer(width / 2, cap_style="flat", join_style="mitre", mitre_limit=2.0)
    if g.geom_type != "Polygon":
        g = max(shapely.get_parts(g), key=lambda q: q.area)
    return g


def l_shape(a: float, b: float, t: float) -> Polygon:
    return Polygon([(0, 0), (a, 0), (a, t), (t, t), (t, b), (0, b)])


def comb(teeth: int, w: float, gapw: float, depth: float, spine: float) -> Polygon:
    pts, x = [(0.0, 0.0)], 0.0
    for k in range(teeth):
        pts += [(x, spine + depth), (x + w, spine + depth), (x + w, spine)]
        x += w
        if k < teeth - 1:
            pts.append((x + gapw, spine))
            x += gapw
    pts.append((x, 0.0))
    return Polygon(pts)


@pytest.fixture(scope="module")
def snakes() -> list[Polygon]:
    rng = np.random.default_rng(3)
    out = [snake(rng, int(rng.integers(4, 14)), rng.uniform(8, 18)) for _ in range(14)]
    # off-centre and rotated, so that the piece's own origin matters
    return [affinity.translate(affinity.rotate(g, float(rng.uniform(0, 360))), *rng.uniform(-200, 200, 2)) for g in out]


# ----------------------------------------------------------------------------------------------
# placements


def test_placement_apply_rotates_ccw_then_translates():
    pl = Placement(0, 90.0, (10.0, 20.0))
    np.testing.assert_allclose(pl.apply(np.array([[1.0, 0.0], [0.0, 2.0]])), [[10.0, 21.0], [8.0, 20.0]], atol=1e-12)
    assert isinstance(pl.offset[0], float) and isinstance(pl.page, int)


def test_placed_outline_is_the_rotated_translated_input(snakes):
    packing = pack_outlines(snakes, A4, gap=2.0)
    for g, pl in zip(snakes, packing.placements):
        q = placed_outline(g, pl)
        ref = moved(g, pl)
        assert q.area == pytest.approx(g.area, rel=1e-9)
        assert q.symmetric_difference(ref).area < 1e-6 * g.area
        np.testing.assert_allclose(shapely.get_coordinates(q), shapely.get_coordinates(ref), atol=1e-9)
        np.testing.assert_allclose(shapely.get_coordinates(q), pl.apply(shapely.get_coordinates(g)), atol=1e-12)


# ----------------------------------------------------------------------------------------------
# validity


@pytest.mark.parametrize("gap", [0.0, 2.0, 5.0])
def test_snakes_pack_validly(snakes, gap):
    packing = pack_outlines(snakes, A4, margin=10.0, gap=gap)
    assert_valid(snakes, packing, gap)
    assert packing.page_size == A4 and packing.margin == 10.0


def test_gap_is_respected_and_measured(snakes):
    packing = pack_outlines(snakes, (297.0, 210.0), margin=5.0, gap=4.0, seed=2)
    assert_valid(snakes, packing, 4.0)
    placed = [placed_outline(g, pl) for g, pl in zip(snakes, packing.placements)]
    dists = [
        placed[i].distance(placed[j])
        for i in range(len(placed))
        for j in range(i + 1, len(placed))
        if packing.placements[i].page == packing.placements[j].page
    ]
    assert dists and min(dists) >= 4.0 - 1e-9


def test_many_mixed_pieces_on_letter():
    rng = np.random.default_rng(11)
    pieces = [snake(rng, int(rng.integers(3, 10)), rng.uniform(6, 14)) for _ in range(20)]
    pieces += [l_shape(*rng.uniform([40, 30, 8], [90, 80, 20])) for _ in range(8)]
    pieces += [comb(int(rng.integers(3, 6)), 6.0, 16.0, rng.uniform(15, 35), 8.0) for _ in range(6)]
    packing = pack_outlines(pieces, (215.9, 279.4), margin=8.0, gap=1.5, angles=6, seed=5)
    assert_valid(pieces, packing, 1.5)


def test_first_fit_uses_one_page_for_small_pieces():
    pieces = [box(0, 0, 20, 10 + k) for k in range(12)]
    packing = pack_outlines(pieces, A4)
    assert packing.n_pages == 1
    assert_valid(pieces, packing, 2.0)


def test_piece_in_a_hole_and_multipolygons():
    frame = box(0, 0, 100, 100).difference(box(20, 20, 80, 80))  # a 60 mm hole
    two = shapely.MultiPolygon([box(0, 0, 6, 6), box(20, 0, 26, 6)])
    pieces = [frame, box(0, 0, 40, 40), two]
    packing = pack_outlines(pieces, (130.0, 130.0), margin=10.0, gap=2.0)
    # the 110 x 110 printable area has no room for the square beside the frame: it sits in the hole
    assert packing.n_pages == 1
    assert_valid(pieces, packing, 2.0)
    hole = placed_outline(box(20, 20, 80, 80), packing.placements[0])
    assert hole.contains(placed_outline(pieces[1], packing.placements[1]))


def test_piece_that_just_fits_goes_alone_and_others_follow():
    pieces = [box(0, 0, 190, 277), box(0, 0, 30, 30), affinity.rotate(box(0, 0, 277, 190), 90, origin=(0, 0))]
    packing = pack_outlines(pieces, A4, margin=10.0, gap=2.0)
    assert_valid(pieces, packing, 2.0)
    assert packing.n_pages == 3


# ----------------------------------------------------------------------------------------------
# nesting beats bounding boxes


def test_two_l_shapes_nest_on_one_page():
    # printable 100 x 100; each L has a 75 x 75 bounding box: no two such squares fit side by side
    # or stacked in any rotation (that needs 150 mm one way), but the Ls interlock corner to corner
    ls = [l_shape(75, 75, 15), affinity.rotate(l_shape(75, 75, 15), 37, origin=(0, 0))]
    packing = pack_outlines(ls, (120.0, 120.0), margin=10.0, gap=2.0)
    assert packing.n_pages == 1
    assert_valid(ls, packing, 2.0)


def test_two_combs_interlock_on_one_page():
    # bounding box 92 x 50 each on a 120 x 75 printable area: stacked needs 100+ mm of height,
    # side by side 184 mm of width, and a comb on end is 92 mm tall; interlocked they need 106 x ~63
    c = comb(4, 8.0, 20.0, 40.0, 10.0)
    x0, y0, x1, y1 = c.bounds
    assert (x1 - x0, y1 - y0) == (92.0, 50.0)
    combs = [c, affinity.translate(c, 500, -300)]
    packing = pack_outlines(combs, (140.0, 95.0), margin=10.0, gap=2.0)
    assert packing.n_pages == 1
    assert_valid(combs, packing, 2.0)


# ----------------------------------------------------------------------------------------------
# piece orders, and the filler planners use


def test_the_hint_goes_first_and_larger_first_is_kept_when_better(snakes):
    larger_first = pack_outlines(snakes, A4, gap=2.0, seed=4)
    assert larger_first.orders_tried == 1 and not larger_first.ran_out
    areas = [g.area for g in snakes]
    assert all(areas[a] >= areas[b] for a, b in zip(larger_first.order, larger_first.order[1:]))
    smaller_first = sorted(range(len(snakes)), key=lambda i: areas[i])
    alone = pack_outlines(snakes, A4, gap=2.0, seed=4, hint=smaller_first, tries=1)
    assert list(alone.order) == smaller_first and alone.orders_tried == 1
    assert_valid(snakes, alone, 2.0)
    both = pack_outlines(snakes, A4, gap=2.0, seed=4, hint=smaller_first)
    assert both.n_pages == min(alone.n_pages, larger_first.n_pages)
    assert both.orders_tried == (1 if alone.n_pages == math.ceil(sum(areas) / (190 * 277)) else 2)
    assert_valid(snakes, both, 2.0)
    partial = pack_outlines(snakes, A4, gap=2.0, seed=4, hint=[3, 1], tries=1)
    assert list(partial.order[:2]) == [3, 1] and sorted(partial.order) == list(range(len(snakes)))


def test_the_second_order_filled_in_a_forked_process_gives_the_packing_filled_here(snakes, monkeypatch):
    """From PARALLEL_PACK_OUTLINES outlines on, with two cores, the second order is filled in a
    forked process while the first is filled here: the same packing as both filled here, whether
    the first order misses the bound (40 mixed pieces: the forked fill is taken) or meets it (the
    snakes: it is not)."""
    import polyfold.fabricate.pack as pack
    import polyfold.processes as processes

    rng = np.random.default_rng(0)
    mixed = [snake(rng, int(rng.integers(3, 10)), rng.uniform(6, 14)) for _ in range(30)]
    mixed += [l_shape(*rng.uniform([40, 30, 8], [90, 80, 20])) for _ in range(10)]
    monkeypatch.setattr(pack, "PARALLEL_PACK_OUTLINES", 1)
    forked = []

    class Counted(processes.ForkedStream):
        def __init__(self, gen):
            forked.append(1)
            super().__init__(gen)

    monkeypatch.setattr(processes, "ForkedStream", Counted)
    for pieces, tried in ((mixed, 2), (snakes, 1)):
        smaller_first = sorted(range(len(pieces)), key=lambda i: pieces[i].area)
        got = {}
        for cores in (1, 2):
            monkeypatch.setattr(processes, "usable_cores", lambda cores=cores: cores)
            got[cores] = pack_outlines(pieces, A4, gap=2.0, seed=4, hint=smaller_first)
        one, two = got[1], got[2]
        assert one.orders_tried == two.orders_tried == tried
        assert (one.n_pages, one.order, one.placements, one.ran_out) == (two.n_pages, two.order, two.placements,
                                                                         two.ran_out)
        assert_valid(pieces, two, 2.0)
    assert forked == [1, 1]  # (with two cores only)


def test_page_filler_puts_outlines_where_pack_outlines_does(snakes):
    order = list(np.random.default_rng(5).permutation(len(snakes)))
    packing = pack_outlines(snakes, A4, margin=10.0, gap=2.0, seed=3, hint=order, tries=1)
    filler = PageFiller(A4, 10.0, 2.0, len(snakes), seed=3)
    for i in order:
        spot = next(s for pg in range(len(snakes)) if (s := filler.spot(pg, snakes[i], i)) is not None)
        assert filler.put(spot) == packing.placements[i]
    assert filler.free_area(packing.n_pages) == filler.free_area(len(snakes) - 1)  # later pages stay empty


# ----------------------------------------------------------------------------------------------
# errors, determinism, edge cases


def test_too_large_piece_raises_with_the_largest_scale():
    pieces = [box(0, 0, 50, 50), box(0, 0, 300, 100)]
    s = fits_page(pieces[1], A4, 10.0)
    assert s == pytest.approx(277 / 300)
    with pytest.raises(PolyfoldError, match=r"piece 1 .*largest scale that fits is 0\.923") as err:
        pack_outlines(pieces, A4)
    assert "\n" not in str(err.value)


def test_fits_page_scale_above_one_and_rotation():
    assert fits_page(box(0, 0, 19, 27.7), A4, 10.0) == pytest.approx(10.0)
    # a long thin diagonal bar fits only turned onto an axis (minimum-area rectangle rotation)
    bar = affinity.rotate(box(0, 0, 250, 5), 33.0, origin=(0, 0))
    assert fits_page(bar, A4, 10.0, angles=1) == pytest.approx(277 / 250)
    assert fits_page(box(0, 0, 10, 10), (15.0, 15.0), 10.0) == 0.0


def test_deterministic_for_a_seed(snakes):
    a = pack_outlines(snakes, A4, seed=7)
    b = pack_outlines(snakes, A4, seed=7)
    assert a == b
    c = pack_outlines(snakes, A4, seed=8)
    assert_valid(snakes, c, 2.0)


def test_empty_input_gives_no_pages():
    packing = pack_outlines([], A4)
    assert packing.n_pages == 0 and packing.placements == () and packing.utilisation == 0.0
    assert check_packing([], packing) == []


def test_time_limit_falls_back_to_valid_shelves(snakes):
    t = time.perf_counter()
    packing = pack_outlines(snakes, A4, gap=3.0, time_limit=0.0)
    assert time.perf_counter() - t < 5.0
    assert_valid(snakes, packing, 3.0)


def test_check_packing_reports_problems():
    pieces = [box(0, 0, 50, 50), box(0, 0, 50, 50)]
    same = Packing((Placement(0, 0.0, (20, 20)), Placement(0, 0.0, (40, 40))), 1, A4, 10.0, 0.0)
    assert any("overlap" in p for p in check_packing(pieces, same))
    close = Packing((Placement(0, 0.0, (20, 20)), Placement(0, 0.0, (71, 20))), 1, A4, 10.0, 0.0)
    assert check_packing(pieces, close) == []
    assert any("closer than 2" in p for p in check_packing(pieces, close, gap=2.0))
    out = Packing((Placement(0, 0.0, (5, 20)), Placement(1, 0.0, (20, 20))), 1, A4, 10.0, 0.0)
    problems = check_packing(pieces, out)
    assert any("piece 0 leaves" in p for p in problems) and any("piece 1: page 1" in p for p in problems)


def test_final_check_repairs_a_broken_placement(snakes, monkeypatch):
    # a grid that forgets every piece stacks them all in one spot: the exact check must catch it
    # and move the offenders to pages of their own
    from polyfold.fabricate import pack

    monkeypatch.setattr(pack._Page, "stamp", lambda self, mask, y, x: None)
    packing = pack_outlines(snakes[:6], A4, gap=2.0)
    assert_valid(snakes[:6], packing, 2.0)


def test_rejects_bad_input():
    with pytest.raises(PolyfoldError, match="piece 0"):
        pack_outlines([Polygon()], A4)
    with pytest.raises(PolyfoldError, match="gap"):
        pack_outlines([box(0, 0, 1, 1)], A4, gap=-1.0)


def test_twenty_hundred_vertex_pieces_on_a4_fast():
    rng = np.random.default_rng(9)
    pieces = []
    while len(pieces) < 20:
        g = snake(rng, 30, rng.uniform(6, 10)).simplify(0.0)
        s = fits_page(g, A4, 10.0)
        pieces.append(affinity.scale(g, min(1.0, 0.7 * s), min(1.0, 0.7 * s)))
    assert np.mean([len(shapely.get_coordinates(g)) for g in pieces]) > 60
    pack_outlines(pieces[:2], A4)  # numba kernels compiled / loaded outside the timing
    t = time.perf_counter()
    packing = pack_outlines(pieces, A4)
    assert time.perf_counter() - t < 1.0
    assert_valid(pieces, packing, 2.0)


def test_raster_marks_exactly_the_cells_whose_centres_are_inside():
    """The packer's scanline raster against shapely's point-in-polygon at every cell centre, on
    rotated buffered triangles and a ring with a hole (even-odd rule)."""
    import shapely
    from shapely import affinity

    from polyfold.fabricate.pack import _raster

    rng = np.random.default_rng(3)
    shapes = [affinity.rotate(shapely.Polygon(rng.uniform(0, 40, (3, 2))).buffer(rng.uniform(0.5, 3), quad_segs=4),
                              rng.uniform(0, 360)) for _ in range(20)]
    shapes.append(shapely.Point(20, 20).buffer(15).difference(shapely.Point(22, 19).buffer(6)))
    for g in shapes:
        rings = shapely.get_rings(shapely.get_parts(g))
        xy, idx = shapely.get_coordinates(rings, return_index=True)
        same = idx[1:] == idx[:-1]
        lo = xy.min(axis=0) - 1.3
        p0, p1 = xy[:-1][same] - lo, xy[1:][same] - lo
        h, w = (np.ceil(xy.max(axis=0) - lo) + 2).astype(int)[::-1]
        mask = _raster(p0, p1, int(h), int(w))
        r, c = np.mgrid[0:h, 0:w]
        centres = shapely.points(c.ravel() + 0.5 + lo[0], r.ravel() + 0.5 + lo[1])
        inside = shapely.contains_xy(g, c.ravel() + 0.5 + lo[0], r.ravel() + 0.5 + lo[1]).reshape(h, w)
        on_edge = (shapely.distance(g.boundary, centres) < 1e-9).reshape(h, w)
        assert mask.shape == (h, w) and mask.any()
        assert ((mask == inside) | on_edge).all()


def test_page_filler_keeps_a_bounded_raster_cache() -> None:
    """Page planning asks for spots of hundreds of candidate outlines: the filler keeps the rasters
    of at most RASTER_CACHE_PIECES (least recently used dropped; a 1,280-face net's plans reached
    840 MB unbounded), and an outline asked again after it was dropped gets the same spot."""
    from polyfold.fabricate import pack

    filler = PageFiller(A4, 10.0, 2.0, 1, seed=3)
    outlines = [box(0, 0, 10 + (i % 37), 8 + (i % 23)) for i in range(pack.RASTER_CACHE_PIECES + 60)]
    first = [filler.spot(0, g, ("part", i)) for i, g in enumerate(outlines)]
    assert len(filler._pieces) == pack.RASTER_CACHE_PIECES
    assert ("part", 0) not in filler._pieces  # the oldest went first
    again = filler.spot(0, outlines[0], ("part", 0))
    assert (again.y, again.x, again.shape.angle) == (first[0].y, first[0].x, first[0].shape.angle)
    assert len(filler._pieces) == pack.RASTER_CACHE_PIECES


def test_pieces_are_kept_by_their_bytes_and_one_asked_again_is_the_one_kept(monkeypatch) -> None:
    """`_piece` keeps the pieces it made (a make packs its outlines again after every plan) while
    their estimated bytes stay under RASTER_CACHE_BYTES, the least recently used dropped first; an
    outline asked again while kept gets the very piece, after it was dropped an equal one."""
    from polyfold.fabricate import pack

    monkeypatch.setattr(pack, "_pieces_kept", type(pack._pieces_kept)())
    monkeypatch.setattr(pack, "_pieces_held", [0])
    grid = pack._grid(190.0, 277.0, 10.0, 2.0)
    outlines = [box(0, 0, 10 + (i % 37), 8 + (i % 23)) for i in range(200)]
    sizes = [pack._piece_bytes(pack._new_piece(g, 8, 0.0, grid)[0]) for g in outlines]
    monkeypatch.setattr(pack, "RASTER_CACHE_BYTES", sum(sizes[-50:]))  # room for the last 50 or so
    made = [pack._piece(g, 8, 0.0, grid) for g in outlines]
    assert pack._pieces_held[0] == sum(b for _, b in pack._pieces_kept.values()) <= pack.RASTER_CACHE_BYTES
    assert 40 <= len(pack._pieces_kept) < 200
    assert pack._piece(outlines[-1], 8, 0.0, grid) is made[-1]  # (kept)
    again = pack._piece(box(0, 0, 10, 8), 8, 0.0, grid)  # outlines[0] (dropped): made again, equal
    assert again is not made[0]
    assert [again[0].shape(k).runs.tolist() for k in range(len(again[0].degs))] == [
        made[0][0].shape(k).runs.tolist() for k in range(len(made[0][0].degs))]


def test_points_hull_is_shapelys_hull_of_the_points():
    """`points_hull` (the compiled monotone chain, then shapely on its corners only) gives the same
    geometry as shapely's hull of all the points: random clouds, rounded ones (duplicates, several
    points on a hull side), collinear ones, one and two points."""
    import shapely

    from polyfold.fabricate.pack import hull_corners, points_hull

    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 5, 50, 1000):
        for t in range(30):
            xy = rng.random((n, 2)) * 100
            if t % 3 == 0:
                xy = np.round(xy / 25) * 25
            if t % 5 == 0:
                xy[:, 1] = 2 * xy[:, 0] - 3
            want = shapely.convex_hull(shapely.multipoints(xy))
            assert points_hull(xy).equals(want), (n, t)
            if n >= 3 and want.geom_type == "Polygon":
                assert len(hull_corners(xy)) <= len(shapely.get_coordinates(want)) - 1 + 2


def test_hull_corners_of_part_of_a_cloud_from_the_whole_clouds_order():
    """A part's corners from the whole cloud's `sorted_points` with the other points left out
    (`order_among`, the fitting's parts): the corners, point for point, that sorting the part's
    points gives, in any order the part's points come in (equal points stand in for each other);
    on clouds with many equal points (the corners faces share) and collinear ones."""
    from polyfold.fabricate.pack import hull_corners, order_among, sorted_points

    rng = np.random.default_rng(3)
    for n in (3, 12, 300, 3000):
        for t in range(20):
            xy = rng.random((n, 2)) * 100
            if t % 2 == 0:
                xy = np.round(xy / 10) * 10  # (many equal points)
            if t % 5 == 0:
                xy[: n // 2, 1] = 0.5 * xy[: n // 2, 0]
            order = sorted_points(xy)
            ids = np.flatnonzero(rng.random(n) < 0.6)
            if len(ids) < 3:
                continue
            part = xy[ids]
            want = part[hull_corners(part)]
            assert np.array_equal(part[hull_corners(part, order_among(order, ids))], want), (n, t)
            shuffled = xy[rng.permutation(ids)]  # (the same points in another order)
            assert np.array_equal(shuffled[hull_corners(shuffled)], want), (n, t)


def test_shape_runs_are_the_rasters_runs_widest_first_ties_in_row_order():
    """`_shape_runs` finds a rotation's runs from its edges' crossings, without the raster: the
    runs of set cells of `_raster` of the same edges (scanned row by row here), sorted widest
    first with rows in order among equals, and their centroid summed in the same order, to the
    last bit; on rotated buffered triangles, rings with holes, outlines cut by the grid's sides
    (crossings clamped to its first column or past its last), edges along a row's centre line and
    ones that meet at a cell centre, and random grids of cells."""
    import shapely
    from shapely import affinity

    from polyfold.fabricate.pack import _raster, _runs_mask, _shape_runs

    rng = np.random.default_rng(2)
    cases = []
    for _ in range(120):
        g = affinity.rotate(shapely.Polygon(rng.uniform(0, 30, (3, 2))).buffer(rng.uniform(0.3, 4), quad_segs=3),
                            rng.uniform(0, 360))
        if rng.random() < 0.3:
            g = g.difference(shapely.Point(*rng.uniform(5, 25, 2)).buffer(rng.uniform(1, 6)))
        rings = shapely.get_rings(shapely.get_parts(g))
        xy, idx = shapely.get_coordinates(rings, return_index=True)
        same = idx[1:] == idx[:-1]
        lo = xy.min(axis=0) - rng.uniform(-3, 2, 2)  # (some outlines reach past the grid's sides)
        h, w = (np.ceil(xy.max(axis=0) - lo) + rng.integers(-3, 3, 2)).astype(int)[::-1]
        cases.append((xy[:-1][same] - lo, xy[1:][same] - lo, max(int(h), 1), max(int(w), 1)))
    # on cell centre lines and corners: a square, a diamond, a zigzag of cells
    cases.append((np.array([[1.5, 1.5], [6.5, 1.5], [6.5, 5.5], [1.5, 5.5]]),
                  np.array([[6.5, 1.5], [6.5, 5.5], [1.5, 5.5], [1.5, 1.5]]), 8, 9))
    cases.append((np.array([[4.5, 0.5], [8.5, 4.5], [4.5, 8.5], [0.5, 4.5]]),
                  np.array([[8.5, 4.5], [4.5, 8.5], [0.5, 4.5], [4.5, 0.5]]), 10, 10))
    for p0, p1, h, w in cases:
        runs, row, col = _shape_runs(np.ascontiguousarray(p0), np.ascontiguousarray(p1), h, w)
        mask = _raster(np.ascontiguousarray(p0), np.ascontiguousarray(p1), h, w)
        expect, n, sr, sc = [], 0, 0.0, 0.0
        for r in range(h):
            edges = np.flatnonzero(np.diff(np.concatenate([[0], mask[r].astype(int), [0]])))
            for a, c in zip(edges[::2].tolist(), edges[1::2].tolist()):
                expect.append((r, a, c - 1))
                n, sr, sc = n + (c - a), sr + (c - a) * r, sc + (c - a) * (a + c - 1) / 2.0
        expect = np.array(expect, dtype=np.int64).reshape(-1, 3)
        expect = expect[np.argsort(expect[:, 1] - expect[:, 2], kind="stable")]
        assert np.array_equal(runs, expect)
        assert (row, col) == (sr / max(n, 1), sc / max(n, 1))
        assert np.array_equal(_runs_mask(runs, h, w), mask)
    assert sum(len(_shape_runs(np.ascontiguousarray(p0), np.ascontiguousarray(p1), h, w)[0])
               for p0, p1, h, w in cases) > 1000


def test_mark_edges_sets_the_cells_inside_each_geometry_in_its_window_on_its_layer():
    """Several geometries rasterised at once onto two layers of one grid, each over its own window
    (what a label raster marks after placements: label boxes, leader strips, a bent leader's turns
    as discs that may part): on a raster offset from the origin, in cells of 0.2 mm, the cells
    whose centres shapely finds inside each geometry, on its layer, on top of what the layers
    held; the windows are the geometries' bounds in cells, truncated and clipped to the raster
    (geometries reach past it too)."""
    import shapely

    from polyfold.fabricate.pack import mark_edges, ring_edges

    rng = np.random.default_rng(11)
    cell, origin = 0.2, np.array([-3.7, 12.1])
    ny, nx = 70, 90
    centres_x = origin[0] + (np.arange(nx) + 0.5) * cell
    centres_y = origin[1] + (np.arange(ny) + 0.5) * cell
    cx, cy = np.meshgrid(centres_x, centres_y)
    for trial in range(40):
        grid, texts = rng.random((ny, nx)) < 0.05, rng.random((ny, nx)) < 0.05
        before = grid.copy(), texts.copy()
        k = int(rng.integers(1, 7))
        geoms = []
        for _ in range(k):
            pts = origin + rng.uniform(-1, [nx * cell + 1, ny * cell + 1], (4, 2))
            if trial % 4 == 3:  # discs that may part (a MultiPolygon), and a ring with a hole
                g = shapely.MultiPoint(pts[:2]).buffer(rng.uniform(0.3, 1.5), quad_segs=2)
                if rng.random() < 0.5:
                    g = g.difference(shapely.Point(pts[0]).buffer(0.2))
            else:
                g = shapely.Polygon(pts).convex_hull.buffer(rng.uniform(0.1, 0.6), quad_segs=2)
            geoms.append(g)
        geoms = np.array(geoms, dtype=object)
        to_texts = rng.random(k) < 0.5
        bounds = shapely.bounds(geoms)
        p0, p1, owner = ring_edges(geoms)
        start = np.searchsorted(owner, np.arange(k + 1))
        windows = mark_edges(grid, texts, p0, p1, start, bounds, to_texts, origin, 1.0 / cell)
        ij = np.clip(((bounds.reshape(-1, 2) - origin) * (1.0 / cell)).astype(np.int32), 0, [nx - 1, ny - 1])
        ij = ij.reshape(-1, 4)
        assert np.array_equal(windows, np.stack([ij[:, 1], ij[:, 3], ij[:, 0], ij[:, 2]], axis=1))
        want = [before[0].copy(), before[1].copy()]
        for g, layer, (r0, r1, c0, c1) in zip(geoms, to_texts, windows):
            inside = np.zeros((ny, nx), dtype=bool)
            inside[r0:r1 + 1, c0:c1 + 1] = shapely.contains_xy(g, cx[r0:r1 + 1, c0:c1 + 1], cy[r0:r1 + 1, c0:c1 + 1])
            want[int(layer)] |= inside
        assert np.array_equal(grid, want[0]) and np.array_equal(texts, want[1])


def test_ring_edges_of_polygons_without_holes_are_those_of_their_rings():
    """`ring_edges` takes the geometries' own coordinates when every one is a polygon without
    holes: the same edges and owners as going through their parts and rings (a MultiPolygon or a
    hole among them takes that way)."""
    import shapely

    from polyfold.fabricate.pack import ring_edges

    rng = np.random.default_rng(5)
    for _ in range(20):
        polys = [shapely.Polygon(rng.uniform(0, 50, (5, 2))).convex_hull.buffer(rng.uniform(0.1, 2), quad_segs=2)
                 for _ in range(int(rng.integers(1, 6)))]
        geoms = np.array(polys, dtype=object)
        got = ring_edges(geoms)
        parts, part_owner = shapely.get_parts(geoms, return_index=True)
        rings, ring_part = shapely.get_rings(parts, return_index=True)
        xy, idx = shapely.get_coordinates(rings, return_index=True)
        same = idx[1:] == idx[:-1]
        want = (xy[:-1][same], xy[1:][same], part_owner[ring_part[idx[:-1][same]]])
        assert all(np.array_equal(a, b) for a, b in zip(got, want))
        mixed = np.array([*polys, shapely.MultiPoint(rng.uniform(0, 50, (2, 2))).buffer(1.0)], dtype=object)
        p0, _p1, owner = ring_edges(mixed)
        assert np.array_equal(p0[owner < len(polys)], got[0]) and (owner == len(polys)).sum() >= 8
