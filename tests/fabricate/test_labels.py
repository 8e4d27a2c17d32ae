"""fabricate/labels.py: a glue label that fits neither its face, its tab nor the paper just beside
its edge goes to the nearest free spot (here: inside another, larger face) with a leader line from
its edge, at full size and overlapping nothing; text widths are Helvetica's."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from polyfold.fabricate.labels import LABEL_PAD_MM, PieceLabels, label_font, text_box, text_width
from polyfold.fabricate.paper import CAP_HEIGHT
from polyfold.fabricate.tabs import CutSide, Room


def test_a_label_with_no_room_beside_its_edge_goes_elsewhere_with_a_leader() -> None:
    small = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, 2.0]])  # too small for a 2 mm label
    large = np.array([[-30.0, 5.0], [-5.0, 5.0], [-17.0, 25.0]])  # another face of the piece, 5 mm away
    room = Room(np.array([Polygon(small), Polygon(large)], dtype=object))
    # all paper off the faces is taken, as by the tabs of other edges
    taken = Polygon([(-60, -60), (60, -60), (60, 60), (-60, 60)]).difference(
        Polygon(small).union(Polygon(large)).buffer(0.6))
    room.add([taken])
    labels = PieceLabels(room, label_font(2.0))
    side = CutSide(0, 0, 0, small[0], small[1], small)
    labels.edge(side, "123")
    assert (labels.stats.outside, labels.stats.unplaced) == (1, 0)
    (item,) = labels.items
    (leader,) = labels.leaders
    box = text_box(np.array([item.x, item.y]), np.array([math.cos(math.radians(item.angle)),
                                                         -math.sin(math.radians(item.angle))]), "123", item.size)
    assert item.size == pytest.approx(label_font(2.0))  # never shrunk
    # the leader starts on the edge and ends on the box
    assert LineString([side.p0, side.p1]).distance(Point(*leader[0])) < 1e-9
    assert Polygon(box).exterior.distance(Point(*leader[1])) < 1e-6
    # the box lies in the large face, LABEL_PAD_MM from its sides, clear of what is taken
    assert Polygon(large).buffer(-LABEL_PAD_MM + 1e-9).contains(Polygon(box))
    assert not Polygon(box).intersects(taken)


def test_text_widths_are_helveticas() -> None:
    assert text_width("1", 10.0) == pytest.approx(5.56)  # every digit 0.556 em
    assert text_width("W", 10.0) == pytest.approx(9.44)  # wider than a digit
    assert text_width("I", 10.0) == pytest.approx(2.78)
    box = text_box(np.zeros(2), np.array([1.0, 0.0]), "10", 2.0)
    assert np.ptp(box[:, 0]) == pytest.approx(2.224) and np.ptp(box[:, 1]) == pytest.approx(CAP_HEIGHT * 2.0)


def test_text_widths_are_the_pdf_writers_to_the_bit() -> None:
    """ASCII text is measured from reportlab's width table without its metrics module (50 ms to
    import); every string gives the very float reportlab's stringWidth gives, other text
    (accents, dashes, the euro) is measured by stringWidth itself."""
    import random
    import string

    from reportlab.pdfbase.pdfmetrics import stringWidth

    rng = random.Random(7)
    texts = list(string.printable[:95]) + ["glue to AB", "S123", "run 45 (3 edges)", "é", "a–b", "€5", "Ω"]
    texts += ["".join(rng.choice(string.printable[:95]) for _ in range(rng.randint(1, 14))) for _ in range(2000)]
    for k, text in enumerate(texts):
        size = (2.0 / CAP_HEIGHT, 2.5, 3.7, 10.0, 7.123)[k % 5]
        assert text_width(text, size) == float(stringWidth(text, "Helvetica", size)), text


def test_a_label_beside_its_edge_is_nearer_that_edge_than_any_other() -> None:
    # edge A (y = 0) of a face too small for a label, the paper beyond it a 3.4 mm gap up to the cut
    # edge B of another face: a label right beside A would sit nearer B, and a reader would take
    # it for B's; it goes further out with a leader instead (or nearer A)
    small = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, -2.0]])
    big = np.array([[8.0, 3.4], [-5.0, 3.4], [1.5, 20.0]])
    room = Room(np.array([Polygon(small), Polygon(big)], dtype=object))
    a = CutSide(0, 0, 0, small[1], small[0], small)  # outward +y
    sides = np.array([[small[0], small[1]], [small[1], small[2]], [small[2], small[0]],
                      [big[0], big[1]], [big[1], big[2]], [big[2], big[0]]])
    labels = PieceLabels(room, label_font(2.0), sides)
    labels.edge(a, "12")
    assert labels.stats.unplaced == 0
    (item,) = labels.items
    p = np.array([item.x, item.y])
    if not labels.leaders:
        from_a = LineString([a.p0, a.p1]).distance(Point(*p))
        from_b = LineString([big[0], big[1]]).distance(Point(*p))
        assert from_a < from_b
    else:  # a leader from A's middle to the label
        assert LineString([a.p0, a.p1]).distance(Point(*labels.leaders[0][0])) < 1e-9


@pytest.mark.parametrize("name,size,paper", [("bunny-128", 150.0, "a4"), ("fish-472", 60.0, "80x80mm")])
def test_pieces_placed_in_parallel_get_the_same_labels(models_dir, monkeypatch, name, size, paper) -> None:
    """`pieces._labels` places each piece on its own, in forked processes from PARALLEL_LABELS
    labels on, with its outline (made there, after its labels): the sheets, outlines and footprints
    included, are the same as in one process, when every edge gets its label (the
    bunny) and when that fails and seam runs are labelled instead (the fish at 60 mm, cut to fit
    80 mm pages: 11 pieces). Asked to label by seam run at once (`by_run`, a redraw of such
    pieces), the fish's sheets are the same again, without the failed try."""
    import shapely

    from polyfold.deadline import Deadline
    from polyfold.fabricate import pieces as P
    from polyfold.fabricate.fit import model_scale
    from polyfold.formats.meshes import load_mesh
    from polyfold.pipeline.options import MakeOptions, paper_size
    from polyfold.pipeline.parts import make_parts
    from polyfold.pipeline.sheets import fit_parts, pack_box, part_piece_inputs

    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    opts = MakeOptions(size=size, paper=paper)
    parts, _, _ = make_parts(mesh, opts, Deadline.after(60), lambda *a: None)
    scale = model_scale([mesh], opts.size)
    fitted, _ = fit_parts(parts, scale, opts, pack_box(*paper_size(opts.paper), opts), name)
    inputs = part_piece_inputs(mesh, fitted)

    def sheet(workers: int, by_run: bool = False):
        monkeypatch.setattr(P, "PARALLEL_LABELS", 0)
        monkeypatch.setattr("polyfold.processes.usable_cores", lambda: workers)
        pieces, glue, stats = P.build_sheet_pieces(inputs, scale, by_run=by_run)
        for i, piece in enumerate(pieces[:len(inputs)]):  # every piece got its own labels
            assert [t.text for t in piece.texts if t.kind == "piece-label"] == [P.piece_name(i)]
        return ([(p.texts, p.leaders.tobytes(), shapely.to_wkb(p.outline), shapely.to_wkb(p.footprint)) for p in pieces],
                [(g.label, g.printed) for g in glue], stats)

    one, many = sheet(1), sheet(3)
    assert len(inputs) >= 3 and sum(len(p[0]) for p in one[0]) > len(inputs)  # names and glue labels
    assert one == many
    assert (one[2].seam_runs > 0) == (name == "fish-472") == one[2].labels_by_run
    if name == "fish-472":
        assert sheet(1, by_run=True) == one


def test_the_screen_of_far_spots_skips_only_what_the_exact_test_turns_down(models_dir, monkeypatch) -> None:
    """`PieceLabels._leader_spots` (the compiled screen of the spots `_elsewhere` finds for a label
    that fits nowhere near its edge) skips spots off the faces that the room blocks and spots whose
    leader would cross a label: each one it skips, `_leader_spot` turns down, and the crowded fish
    (60 mm, 80 mm pages, labelled by seam run) gets the same sheets with the screen as with every
    spot asked of `_leader_spot`, which is asked far less often."""
    import shapely

    from polyfold.deadline import Deadline
    from polyfold.fabricate import labels as L
    from polyfold.fabricate import pieces as P
    from polyfold.fabricate.fit import model_scale
    from polyfold.formats.meshes import load_mesh
    from polyfold.pipeline.options import MakeOptions, paper_size
    from polyfold.pipeline.parts import make_parts
    from polyfold.pipeline.sheets import fit_parts, pack_box, part_piece_inputs

    mesh = load_mesh(models_dir / "fish-472.obj").mesh
    opts = MakeOptions(size=60.0, paper="80x80mm")
    parts, _, _ = make_parts(mesh, opts, Deadline.after(60), lambda *a: None)
    scale = model_scale([mesh], opts.size)
    fitted, _ = fit_parts(parts, scale, opts, pack_box(*paper_size(opts.paper), opts), "fish-472")
    inputs = part_piece_inputs(mesh, fitted)
    monkeypatch.setattr("polyfold.processes.usable_cores", lambda: 1)
    screened, exact, elsewhere = L.PieceLabels._leader_spots, L.PieceLabels._leader_spot, L.PieceLabels._elsewhere
    counts = {"asked": 0, "skipped": 0, "skipped but taken": 0}

    def with_text(self, text, sides):
        self._text = text  # (for `checked`)
        return elsewhere(self, text, sides)

    def checked(self, boxes, p):
        """The screen's spots, after every spot it skips is asked of the exact test (which turns
        it down, placing nothing: it may not take it)."""
        kept = list(screened(self, boxes, p))
        for i in sorted(set(range(len(boxes))) - set(kept)):
            center = boxes[i].mean(axis=0)
            u = (boxes[i][1] - boxes[i][0]) / np.linalg.norm(boxes[i][1] - boxes[i][0])
            counts["skipped"] += 1
            counts["skipped but taken"] += exact(self, self._text, u, center, np.array([p, center]), bent=False)
        yield from kept

    def counted(self, *args, **kwargs):
        counts["asked"] += 1
        return exact(self, *args, **kwargs)

    def sheet():
        counts["asked"] = 0
        pieces, glue, stats = P.build_sheet_pieces(inputs, scale)
        return ([(p.texts, p.leaders.tobytes(), shapely.to_wkb(p.outline), shapely.to_wkb(p.footprint)) for p in pieces],
                [(g.label, g.printed) for g in glue], stats)

    monkeypatch.setattr(L.PieceLabels, "_elsewhere", with_text)
    monkeypatch.setattr(L.PieceLabels, "_leader_spots", checked)
    checked_sheet = sheet()
    assert checked_sheet[2].labels_by_run and checked_sheet[2].labels_outside > 0
    assert counts["skipped"] > 200 and counts["skipped but taken"] == 0, counts
    monkeypatch.setattr(L.PieceLabels, "_leader_spots", screened)
    monkeypatch.setattr(L.PieceLabels, "_leader_spot", counted)
    assert sheet() == checked_sheet
    with_screen = counts["asked"]
    monkeypatch.setattr(L.PieceLabels, "_leader_spots", lambda self, boxes, p: iter(range(len(boxes))))
    assert sheet() == checked_sheet
    assert with_screen < 0.7 * counts["asked"], (with_screen, counts["asked"])


def test_the_room_for_off_face_labels_is_around_the_hull_of_the_faces_union() -> None:
    """`PieceLabels.allowed` is taken from the hull of the faces' corners: the same polygon, to
    the bit, as the hull of their union grown alike, on grids of triangles (straight outlines,
    many corners on the hull's sides) and on jittered ones."""
    import shapely

    from polyfold.fabricate.labels import TAB_CLEAR_MM
    from polyfold.fabricate.tabs import TAB_ROOM_MM

    rng = np.random.default_rng(3)
    for jitter in (0.0, 0.0, 0.2, 0.3):
        nx, ny = (int(v) for v in rng.integers(2, 9, 2))
        xy = np.stack(np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0)), axis=-1) * 3.0
        xy += rng.uniform(-jitter, jitter, xy.shape)
        tris = [t for i in range(nx) for j in range(ny)
                for t in ((xy[j, i], xy[j, i + 1], xy[j + 1, i + 1]), (xy[j, i], xy[j + 1, i + 1], xy[j + 1, i]))]
        room = Room(np.array([Polygon(t) for t in tris], dtype=object))
        want = shapely.convex_hull(shapely.union_all(room.faces)).buffer(TAB_ROOM_MM - TAB_CLEAR_MM)
        assert shapely.to_wkb(PieceLabels(room, 2.0).allowed) == shapely.to_wkb(want)


def _distances_by_numpy(p: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(k,) distances from p (2,) to the segments (k, 2, 2) as numpy writes them."""
    a, ab = segments[:, 0], segments[:, 1] - segments[:, 0]
    t = np.clip(((p - a) * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * ab - p, axis=1)


def _nearer_by_numpy(p: np.ndarray, segments: np.ndarray, own: np.ndarray, pad: float) -> bool:
    """The test of a spot beside its own edge in numpy (the other segments' distances; `own`
    left out either way round)."""
    d, mine = _distances_by_numpy(p, segments), float(_distances_by_numpy(p, own[None])[0])
    same = (np.abs(segments - own).max(axis=(1, 2)) < 1e-9) | (np.abs(segments - own[::-1]).max(axis=(1, 2)) < 1e-9)
    return bool(np.all(d[~same] > mine + pad))


def test_spots_beside_an_edge_are_told_as_numpy_tells_them():
    """`PieceLabels._nearest_to`'s compiled test agrees with numpy's distances on every point, own
    side given either way round, zero-length sides among the others, and pads that put a point's
    nearest other side right at the limit (the last bit decides)."""
    from polyfold.fabricate.labels import _nearer_than_others

    rng = np.random.default_rng(5)
    for trial in range(300):
        segments = rng.uniform(-10, 10, (int(rng.integers(2, 30)), 2, 2))
        zero = rng.random(len(segments)) < 0.1
        segments[zero, 1] = segments[zero, 0]
        k = int(rng.integers(0, len(segments)))
        own = segments[k].copy() if trial % 2 else segments[k][::-1].copy()
        pts = rng.uniform(-12, 12, (20, 2))
        pads = [LABEL_PAD_MM]
        for p in pts[:3]:  # the pad at which p's nearest other side is as far as its own plus the pad
            d = _distances_by_numpy(p, segments)
            d[k] = np.inf
            pads.append(float(d.min() - _distances_by_numpy(p, own[None])[0]))
        for pad in pads:
            got = _nearer_than_others(pts, np.ascontiguousarray(segments), own, pad)
            assert got.tolist() == [_nearer_by_numpy(p, segments, own, pad) for p in pts]
        assert _nearer_than_others(pts, np.zeros((0, 2, 2)), own, LABEL_PAD_MM).all()


def test_text_boxes_are_their_corners_at_each_centre():
    """A box's corners: centre -+ half its width along u -+ half a cap height across (in that
    order, as `text_box` always made them), for many centres at once as for one."""
    from polyfold.fabricate.labels import text_boxes

    rng = np.random.default_rng(6)
    for text in ("7", "128", "AB"):
        angle = rng.uniform(0, 2 * math.pi)
        u = np.array([math.cos(angle), math.sin(angle)])
        n = np.array([-u[1], u[0]])
        hw, hh = text_width(text, 2.5) / 2, CAP_HEIGHT * 2.5 / 2
        centres = rng.uniform(-100, 100, (25, 2))
        want = np.stack([np.array([c - hw * u - hh * n, c + hw * u - hh * n, c + hw * u + hh * n,
                                   c - hw * u + hh * n]) for c in centres])
        assert np.array_equal(text_boxes(centres, u, text, 2.5), want)
        assert np.array_equal(np.stack([text_box(c, u, text, 2.5) for c in centres]), want)


def test_free_spot_kernels_give_numpys_cells_to_the_last_bit():
    """The raster search of `PieceLabels._elsewhere`: the summed-area test of free boxes
    (`_box_free`) against numpy's cumulative sums, and the free cells near a point with a clear
    leader (`_clear_near`, ring by ring) against numpy: nonzero of the window, distances, a
    stable argsort, the first LEADER_TRIES, the leader looked up at every point, the first
    `want` clear; on random rasters, windows, points and limits."""
    from polyfold.fabricate.labels import _RINGS2, FREE_CELL_MM, _box_free, _clear_near, _half_cells

    rng = np.random.default_rng(7)
    for _ in range(60):
        ny, nx = (int(v) for v in rng.integers(1, 90, 2))
        taken = rng.random((ny, nx)) < rng.uniform(0.0, 0.3)
        w, h = rng.uniform(0.1, 8.0, 2)
        hw, hh = _half_cells(w), _half_cells(h)
        want = np.zeros((ny, nx), dtype=bool)
        kh, kw = 2 * hh + 1, 2 * hw + 1
        if ny >= kh and nx >= kw:
            s = np.pad(np.cumsum(np.cumsum(taken, axis=0, dtype=np.int32), axis=1), ((1, 0), (1, 0)))
            count = s[kh:, kw:] - s[:-kh, kw:] - s[kh:, :-kw] + s[:-kh, :-kw]
            want[hh:hh + count.shape[0], hw:hw + count.shape[1]] = count == 0
        assert np.array_equal(_box_free(taken, hw, hh), want)

    t = np.linspace(0.0, 1.0, 9)
    for trial in range(120):
        # up to 300 x 300 cells (60 mm): rings cut across the window and beyond it
        ny, nx = (int(v) for v in rng.integers(1, 300, 2))
        free_a, free_b = (rng.random((ny, nx)) < rng.uniform(0.05, 0.9) for _ in range(2))
        in_faces = rng.random((ny, nx)) < 0.5
        texts = rng.random((ny, nx)) < rng.uniform(0.0, 0.02)
        origin = rng.uniform(-50, 50, 2)
        p = origin + rng.uniform(-0.2, 1.2, 2) * [nx, ny] * FREE_CELL_MM  # (over the raster, or off it)
        r0, r1 = sorted(int(v) for v in rng.integers(0, ny, 2))
        c0, c1 = sorted(int(v) for v in rng.integers(0, nx, 2))
        tries, k = int(rng.choice([3, 40, 1000])), int(rng.choice([1, 5, 40]))
        found = np.empty((4, (r1 - r0 + 1) * (c1 - c0 + 1), 3))
        counts, ring_end = np.zeros(4, dtype=np.int64), np.zeros((4, len(_RINGS2)), dtype=np.int64)
        scanned = np.zeros(1, dtype=np.int64)
        for q in rng.permutation(4) if trial % 2 else range(4):  # (the rings are scanned once, for all four)
            layer, inside = (free_a, free_b)[q % 2], q < 2
            rows, cols = np.nonzero(layer[r0:r1 + 1, c0:c1 + 1] & (in_faces[r0:r1 + 1, c0:c1 + 1] == inside))
            centres = origin + (np.stack([cols + c0, rows + r0], axis=1) + 0.5) * FREE_CELL_MM
            d2 = ((centres - p) ** 2).sum(axis=1)
            near = np.flatnonzero(d2 <= _RINGS2[-1])
            looked = centres[near[np.argsort(d2[near], kind="stable")]][:tries]
            pts = p + t[None, :, None] * (looked - p)[:, None, :]
            cell = np.clip(((pts - origin) * (1.0 / FREE_CELL_MM)).astype(np.int32), 0, [nx - 1, ny - 1])
            expected = looked[~texts[cell[..., 1], cell[..., 0]].any(axis=1)][:k]
            state, got = np.zeros(3, dtype=np.int64), []
            while len(batch := _clear_near(free_a, free_b, in_faces, r0, r1, c0, c1, origin, p, FREE_CELL_MM, _RINGS2,
                                           int(q), state, scanned, found, counts, ring_end, tries, texts, t, k)):
                got.append(batch)
            got = np.concatenate(got) if got else np.zeros((0, 2))
            assert np.array_equal(got, expected)


def test_bent_leader_kernels_give_the_python_rules_paths():
    """A bent leader's way back from a found cell (`_path_back`: one step nearer each time, the
    first of right, down, left, up, then the diagonals) and its turns (`_path_turns`: from each
    kept point the farthest later one whose stretch, looked up at linspace points, crosses no
    label cell) against the rules written out in Python, on random rasters."""
    from polyfold.fabricate.labels import FREE_CELL_MM, LEADER_STEP_MM, _grid_bfs, _path_back, _path_turns

    def back(dist, r, c):
        path = [(r, c)]
        while dist[path[-1]] > 0:
            r, c = path[-1]
            d = dist[r, c]
            path.append([(r + dr, c + dc) for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))
                         if 0 <= r + dr < dist.shape[0] and 0 <= c + dc < dist.shape[1] and dist[r + dr, c + dc] == d - 1][0])
        return np.array(path)

    def turns(pts, texts, origin):
        last = np.array([texts.shape[1] - 1, texts.shape[0] - 1])
        keep = [0]
        while keep[-1] < len(pts) - 1:
            i, j = keep[-1], len(pts) - 1
            while j > i + 1:
                t = np.linspace(0.0, 1.0, int(math.ceil(np.linalg.norm(pts[j] - pts[i]) / LEADER_STEP_MM)) + 1)
                ij = np.clip(((pts[i] + t[:, None] * (pts[j] - pts[i]) - origin) * (1.0 / FREE_CELL_MM)).astype(np.int32),
                             0, last)
                if not texts[ij[:, 1], ij[:, 0]].any():
                    break
                j -= 1
            keep.append(j)
        return np.array(keep)

    rng = np.random.default_rng(21)
    bent = 0
    for _ in range(60):
        ny, nx = (int(v) for v in rng.integers(20, 120, 2))
        texts = rng.random((ny, nx)) < rng.uniform(0.05, 0.35)
        sr, sc = int(rng.integers(ny)), int(rng.integers(nx))
        free = ~texts
        free[sr, sc] = True
        dist, found = _grid_bfs(free, sr, sc, 150, (rng.random((1, ny, nx)) < 0.01), 10)
        origin = rng.uniform(-50, 50, 2)
        for _k, r, c in found.tolist():
            path = _path_back(dist, r, c)
            assert np.array_equal(path, back(dist, r, c))
            pts = origin + (path[::-1][:, ::-1] + 0.5) * FREE_CELL_MM
            pts[0] += rng.uniform(-0.1, 0.1, 2)
            got = _path_turns(np.ascontiguousarray(pts), texts, origin, 1.0 / FREE_CELL_MM, LEADER_STEP_MM)
            assert np.array_equal(got, turns(pts, texts, origin))
            bent += len(got) > 2
    assert bent > 20  # paths with turns, not only straight ones


def test_a_free_map_refreshed_in_windows_is_the_free_map_made_anew():
    """`_Taken`'s maps of free box centres, refreshed only around the windows where cells were
    taken (`_refresh_free`), equal `_box_free` of the whole raster made again."""
    from polyfold.fabricate.labels import _box_free, _refresh_free

    rng = np.random.default_rng(8)
    for _ in range(40):
        ny, nx = (int(v) for v in rng.integers(10, 90, 2))
        taken = rng.random((ny, nx)) < 0.05
        hw, hh = (int(v) for v in rng.integers(0, 6, 2))
        free = _box_free(taken, hw, hh)
        windows = []
        for _ in range(int(rng.integers(1, 5))):
            r0, r1 = sorted(int(v) for v in rng.integers(0, ny, 2))
            c0, c1 = sorted(int(v) for v in rng.integers(0, nx, 2))
            r1, c1 = min(r1, r0 + 6), min(c1, c0 + 6)
            taken[r0:r1 + 1, c0:c1 + 1] |= rng.random((r1 - r0 + 1, c1 - c0 + 1)) < 0.5
            windows.append([r0, r1, c0, c1])
        _refresh_free(free, taken, np.array(windows, dtype=np.int64), hw, hh)
        assert np.array_equal(free, _box_free(taken, hw, hh))


def test_the_free_spot_rasters_dilation_and_enclosed_cells_are_scipys():
    # `_Taken` grows the face sides by a disc and finds the cells they enclose with two compiled
    # kernels (make imports no scipy for them): on random rasters of sparse and dense walls, discs of
    # radius 0-3, they give scipy.ndimage's binary_dilation and the components of its `label`
    # (4 neighbours) that touch no border
    from scipy import ndimage

    from polyfold.fabricate.labels import _dilated, _enclosed

    rng = np.random.default_rng(11)
    enclosed_seen = 0
    for trial in range(60):
        ny, nx = rng.integers(1, 40, 2)
        cells = rng.random((ny, nx)) < rng.choice([0.05, 0.2, 0.5])
        r = int(rng.integers(0, 4))
        disc = np.hypot(*np.mgrid[-r:r + 1, -r:r + 1]) <= r
        grown = _dilated(cells, disc)
        assert np.array_equal(grown, ndimage.binary_dilation(cells, structure=disc))
        parts, n = ndimage.label(~grown)
        outer = np.zeros(n + 1, dtype=bool)
        outer[np.concatenate([parts[0], parts[-1], parts[:, 0], parts[:, -1]])] = True
        want = ~grown & ~outer[parts]
        assert np.array_equal(_enclosed(grown), want)
        enclosed_seen += int(want.any())
    assert enclosed_seen >= 10
