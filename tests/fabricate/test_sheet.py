"""fabricate/sheet.py: the sheet of `polyfold unfold --svg/--png` (`net_sheet`, written by the
formats/ SVG writer) on hand-made nets: the same tabs, labels and writers as `make`, pieces apart
on one sheet. (The hand-made nets tetra_net / square_net are in conftest: the PNG tests use them.)"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, Polygon, box

from conftest import H3, by_class, make_net, square_net, tetra_net
from polyfold.fabricate.check import check_pages
from polyfold.fabricate.paper import FOOTER_MM, GAP_MM
from polyfold.fabricate.sheet import MARGIN_MM, NetSheet, net_sheet
from polyfold.formats.svg import write_svg_page
from polyfold.unfold.net import Net

SVG = "{http://www.w3.org/2000/svg}"


# ----------------------------------------------------------------------------------------------
# hand-made nets


def grid_net(cells, split_vertex=None) -> Net:
    """Unit grid cells (i, j), each two CCW triangles, flat (z = 0), one piece: a spanning tree of
    the cells in the given order (each cell hangs on the first earlier cell it shares an edge with).
    split_vertex=(x, y, cell): the faces of `cell` get their own mesh vertex at grid point (x, y)."""
    idx: dict = {}
    xy, faces, parent = [], [], []

    def vid(p):
        if p not in idx:
            idx[p] = len(xy)
            xy.append(p[:2])
        return idx[p]

    cell_faces = []
    for n, (i, j) in enumerate(cells):
        def corner(x, y):
            copy = split_vertex and (x, y) == split_vertex[:2] and (i, j) == split_vertex[2]
            return vid((x, y, "copy") if copy else (x, y))

        p00, p10, p11, p01 = corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)
        f0 = len(faces)
        faces += [[p00, p10, p11], [p00, p11, p01]]
        up = next((m for m, (a, b) in enumerate(cells[:n]) if abs(a - i) + abs(b - j) == 1), None)
        if up is None:
            parent += [-1, f0]
        else:  # faces (f0, f1) hold the (bottom, right) and (top, left) sides of their cell
            (a, b) = cells[up]
            side = {(1, 0): 0, (0, 1): 1, (-1, 0): 1, (0, -1): 0}[(i - a, j - b)]  # the earlier cell's face
            mine = {(1, 0): f0 + 1, (0, 1): f0, (-1, 0): f0, (0, -1): f0 + 1}[(i - a, j - b)]
            other = f0 + 1 if mine == f0 else f0
            parent += [0, 0]
            parent[mine] = cell_faces[up][side]
            parent[other] = mine
        cell_faces.append((f0, f0 + 1))
    v3 = [(x, y, 0.0) for x, y in xy]
    return make_net(xy, faces, list(range(len(xy))), v3, parent)


# ----------------------------------------------------------------------------------------------
# helpers


def svg_points(d: str) -> list[tuple[float, float]]:
    return [tuple(float(v) for v in p.split(",")) for p in re.findall(r"-?\d+(?:\.\d+)?,-?\d+(?:\.\d+)?", d)]


def key(p):
    return (round(float(p[0]), 2), round(float(p[1]), 2))


def ring_segments(rings) -> Counter:
    segs = Counter()
    for ring in rings:
        for p, q in zip(ring, np.roll(ring, -1, axis=0)):
            segs[frozenset((key(p), key(q)))] += 1
    return segs


def cut_segments(piece) -> Counter:
    """The sides of the piece's faces that are not shared with another of its faces."""
    segs = Counter(frozenset((key(t[k]), key(t[(k + 1) % 3]))) for t in piece.faces_xy for k in range(3))
    return Counter({s: 1 for s, n in segs.items() if n == 1})


def write(sheet: NetSheet, tmp_path: Path):
    path = tmp_path / "net.svg"
    write_svg_page(sheet.page, path)
    return ET.parse(path).getroot()


def assert_sheet_ok(sheet: NetSheet) -> None:
    """The independent page checks of make: pieces (tabs included) GAP_MM apart, no face or tab
    overlaps, everything inside the margins (the footer strip excluded)."""
    page = sheet.page
    n = len(sheet.pieces)
    box = (MARGIN_MM, MARGIN_MM, page.width - MARGIN_MM, page.height - FOOTER_MM - MARGIN_MM)
    res = check_pages(list(sheet.pieces), [0] * n, 1, box, GAP_MM)
    assert res["problems"] == []


def labels_of(sheet: NetSheet, kind: str = "edge-label") -> Counter:
    return Counter(t.text for t in sheet.page.texts if t.kind == kind)


# ----------------------------------------------------------------------------------------------
# sheet


def test_scale_size_and_margin():
    sheet = net_sheet([tetra_net()], 100.0)
    assert sheet.scale == pytest.approx(100.0)  # the tetrahedron's longest side is 1
    (piece,) = sheet.pieces
    x0, y0, x1, y1 = shapely.bounds(shapely.polygons(piece.faces_xy.reshape(-1, 3, 2))).T
    assert (x1.max() - x0.min(), y1.max() - y0.min()) == pytest.approx((200.0, 200 * H3))  # real mm
    ox0, oy0, ox1, oy1 = piece.outline.bounds
    assert (ox0, oy0) == pytest.approx((MARGIN_MM, MARGIN_MM))
    assert sheet.page.width == pytest.approx(ox1 + MARGIN_MM)
    assert sheet.page.height == pytest.approx(oy1 + MARGIN_MM + FOOTER_MM)
    # seen from the printed side, y down: the apex copy C (net y = 2 H3) is at the top
    apex_c = piece.faces_xy[2, 2]
    assert apex_c[1] == pytest.approx(y0.min())
    assert not sheet.oversize


def test_tetra_svg(tmp_path):
    sheet = net_sheet([tetra_net()], 100.0, title="tetra")
    assert_sheet_ok(sheet)
    root = write(sheet, tmp_path)
    w, h = root.get("width"), root.get("height")
    assert w.endswith("mm") and h.endswith("mm")
    assert float(w[:-2]) == pytest.approx(sheet.page.width, abs=1e-3)
    assert float(h[:-2]) == pytest.approx(sheet.page.height, abs=1e-3)
    assert [float(v) for v in root.get("viewBox").split()] == pytest.approx([0, 0, float(w[:-2]), float(h[:-2])])

    (piece,) = sheet.pieces
    (cut,) = by_class(root, "cut")  # one closed outline: faces and tabs
    assert svg_points(cut.get("d")) == [pytest.approx(p, abs=1e-3) for p in piece.cut_rings()[0]]
    assert cut.get("d").rstrip().endswith("Z")
    assert len(by_class(root, "mountain")) == 3 and not by_class(root, "valley")

    assert labels_of(sheet) == {"1": 2, "2": 2, "3": 2}
    assert Counter(t.text for t in by_class(root, "edge-label")) == {"1": 2, "2": 2, "3": 2}
    body = piece.body
    for t in sheet.page.texts:
        if t.kind == "edge-label":  # inside the net, next to its edge
            pt = Point(t.x, t.y)
            assert body.contains(pt) and body.exterior.distance(pt) < 3

    tabs = [Polygon(t) for t in piece.tabs]
    assert len(tabs) == 3 == len(by_class(root, "tab")) == len(by_class(root, "tab-fold"))
    for i, tab in enumerate(tabs):
        assert tab.is_valid and tab.area > 1
        assert shapely.area(shapely.intersection(tab, body)) < 1e-4  # outside the faces
        assert box(0, 0, sheet.page.width, sheet.page.height).contains(tab)
        for other in tabs[i + 1:]:
            assert shapely.area(shapely.intersection(tab, other)) < 1e-4
    assert piece.outline.area == pytest.approx(body.area + sum(t.area for t in tabs))
    assert [t.text for t in by_class(root, "title")] == ["tetra - 1 piece - 100 mm - polyfold"]


def test_tetra_no_tabs_outline_is_the_cut_edges():
    (piece,) = net_sheet([tetra_net()], 100.0, tabs=False).pieces
    rings = piece.cut_rings()
    assert len(rings) == 1
    segs = ring_segments(rings)
    assert segs == cut_segments(piece) and sum(segs.values()) == 6


def fan_net(wedge_deg: float) -> Net:
    """Six faces around an apex P, unfolded as a fan with a gap of `wedge_deg` between the two
    sides of the cut edge P-Q0 (a cone: the gap is its angle defect). The 3D cone, a hexagonal
    pyramid, only gives the fold signs (all mountains); the net is not scaled to it."""
    n = 6
    step = math.radians((360.0 - wedge_deg) / n)
    xy = [(0.0, 0.0)] + [(math.cos(k * step), math.sin(k * step)) for k in range(n + 1)]
    faces = [[0, k + 1, k + 2] for k in range(n)]
    mesh_vertex = [0] + list(range(1, n + 1)) + [1]  # the last ray is Q0 again
    v3 = [(0.0, 0.0, 0.1)] + [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0.0) for k in range(n)]
    return make_net(xy, faces, mesh_vertex, v3, [-1] + list(range(n - 1)))


def test_a_glue_strip_when_both_sides_are_blocked():
    # a 3-degree gap: no tab, not even a clipped one, fits between the two sides: the seam gets a
    # glue strip, a separate piece labelled like a tab on both halves, folding against its seam
    sheet = net_sheet([fan_net(3.0)], 100.0)
    assert_sheet_ok(sheet)
    (glue,) = sheet.glue
    fan, strip = sheet.pieces
    assert glue.tab_piece == 1 and strip.name == "S" + glue.label and sheet.stats.untabbed == ()
    assert sheet.stats.reduced_tabs == ((glue.label, "glue strip"),)
    assert fan.tabs == () and sheet.page.tabs == ()
    assert labels_of(sheet) == {glue.label: 4}  # both sides and both halves of the strip
    side = np.linalg.norm(np.diff(strip.valley[0], axis=0))  # a convex seam: the strip folds as a valley
    seam = np.linalg.norm(fan.faces_xy[0, 1] - fan.faces_xy[0, 0])  # P-Q0 on the first face
    assert len(strip.mountain) == 0 and math.isclose(side, seam, rel_tol=1e-6)
    # a wide gap: the tab fits on the first side
    wide = net_sheet([fan_net(90.0)], 100.0)
    assert wide.glue[0].tab_piece == 0 and wide.stats.tabs == 1 and wide.stats.tabs_moved == 0


def test_valley_and_open_boundary(tmp_path):
    sheet = net_sheet([square_net(0.3)], 50.0)
    root = write(sheet, tmp_path)
    assert len(by_class(root, "valley")) == 1 and not by_class(root, "mountain")
    assert not by_class(root, "edge-label") and not by_class(root, "tab")  # open boundary: nothing to glue
    assert sheet.stats.open_edges == 4 and sheet.stats.glue_edges == 0
    (cut,) = by_class(root, "cut")
    assert len(svg_points(cut.get("d"))) == 4


def test_mountain_and_valley_styles_differ_and_sit_on_their_creases(tmp_path):
    sheet = net_sheet([square_net(0.3), square_net(-0.3)], 50.0)
    assert_sheet_ok(sheet)
    root = write(sheet, tmp_path)
    layers = {g.get("id"): g for g in root.iter(SVG + "g")}
    m, v = layers["mountain"], layers["valley"]
    assert (m.get("stroke"), m.get("stroke-dasharray")) != (v.get("stroke"), v.get("stroke-dasharray"))
    assert m.get("stroke-dasharray") and v.get("stroke-dasharray")
    (mp,), (vp,) = by_class(m, "mountain"), by_class(v, "valley")
    valley_piece, mountain_piece = sheet.pieces
    for path, piece in ((vp, valley_piece), (mp, mountain_piece)):
        diagonal = {key(p) for p in piece.faces_xy[0]} & {key(p) for p in piece.faces_xy[1]}
        assert {key(p) for p in svg_points(path.get("d"))} == diagonal
    assert len(by_class(root, "cut")) == 2


def test_annulus_is_one_outline_with_a_hole():
    ring = [(0, 0), (1, 0), (2, 0), (2, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    sheet = net_sheet([grid_net(ring)], 60.0, tabs=False)
    (piece,) = sheet.pieces
    assert piece.outline.geom_type == "Polygon" and len(piece.outline.interiors) == 1
    rings = piece.cut_rings()
    assert sorted(len(r) for r in rings) == [4, 12]
    # the ring's spanning tree leaves one crease cut, but the ring is flat, one polygon: its two
    # sides lie on each other, so it is no seam (no slit, no label) and the outline is all the cut
    assert len(piece.slits) == 0 and sheet.stats.glue_edges == 0
    assert ring_segments(rings) == cut_segments(piece)


@pytest.mark.parametrize("split", [False, True])
def test_boundary_touching_itself_is_one_outline(split):
    # a strip of cells that comes back to touch itself at grid point (2, 2) (cells (1,1) and (2,2))
    strip = [(1, 1), (0, 1), (0, 2), (0, 3), (1, 3), (2, 3), (2, 2)]
    sheet = net_sheet([grid_net(strip, split_vertex=(2, 2, (2, 2)) if split else None)], 60.0, tabs=False)
    assert sheet.stats.open_edges == 16 and sheet.stats.glue_edges == 0
    (piece,) = sheet.pieces
    assert piece.outline.geom_type == "Polygon"  # one outline, not two
    segs = ring_segments(piece.cut_rings())
    assert segs == cut_segments(piece) and sum(segs.values()) == 16


def test_no_labels_no_tabs(tmp_path):
    sheet = net_sheet([tetra_net()], 100.0, labels=False, tabs=False)
    root = write(sheet, tmp_path)
    assert not by_class(root, "edge-label") and not by_class(root, "piece-label")
    assert not by_class(root, "tab") and not by_class(root, "tab-fold")
    assert sheet.page.tabs == () and len(sheet.page.tab_folds) == 0
    assert len(by_class(root, "cut")) == 1
    labelled = net_sheet([tetra_net()], 100.0, tabs=False)
    assert labels_of(labelled, "piece-label") == {"A": 1} and len(labels_of(labelled)) == 3


def test_oversize_flag_and_atomic_overwrite(tmp_path):
    path = tmp_path / "net.svg"
    path.write_text("old")
    big = net_sheet([tetra_net()], 150.0)  # a 300 mm wide net, plus tabs and margins
    assert big.oversize and big.page.width > 300
    assert not net_sheet([tetra_net()], 60.0).oversize
    write_svg_page(big.page, path)
    assert ET.parse(path).getroot().tag == SVG + "svg"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["net.svg"]


def test_pieces_of_several_components_stay_apart_and_pair_only_within():
    sheet = net_sheet([tetra_net(), tetra_net(), square_net(0.3)], 80.0)
    assert_sheet_ok(sheet)
    assert [p.part for p in sheet.pieces] == [0, 1, 2]
    assert sheet.stats.glue_edges == 6 and all(g.pieces[0] == g.pieces[1] for g in sheet.glue)
    assert labels_of(sheet) == {str(k): 2 for k in range(1, 7)}


def test_bad_size():
    from polyfold.errors import PolyfoldError

    for size in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(PolyfoldError, match="positive"):
            net_sheet([tetra_net()], size)


def test_outline_specks_merged_without_a_ring_crossing_itself():
    """Merging an outline's corners within OUTLINE_TOL_MM can make its ring cross itself where it
    passes near itself (two faces meeting at a corner): this piece outline of a 1,392-face
    subdivided bunny (mm, as drawn) made `make` stop with a GEOS error before it was mended."""
    import shapely

    from polyfold.fabricate.pieces import OUTLINE_TOL_MM, _without_specks

    ring = [[35.434887, 60.967766], [47.875362, 66.56128], [47.875351, 66.561285], [51.212048, 68.315797],
            [51.671862, 68.101445], [52.473438, 64.417822], [55.810083, 66.17232], [56.269891, 65.95797],
            [57.071435, 62.274323], [57.071404, 62.274338], [40.032944, 58.824287], [57.071425, 62.274321],
            [54.409565, 50.878749], [51.747659, 39.483123], [37.371084, 47.428716], [22.994475, 55.37421]]
    outline = shapely.Polygon(ring)
    assert outline.is_valid
    assert not shapely.Polygon(shapely.remove_repeated_points(outline, OUTLINE_TOL_MM).exterior).is_valid
    out = _without_specks(outline)
    assert out.is_valid and abs(out.area - outline.area) < outline.length * OUTLINE_TOL_MM  # corners moved < tol
    edges = [shapely.LineString(p) for g in shapely.get_parts(out) for p in zip(g.exterior.coords[:-1], g.exterior.coords[1:])]
    assert min(e.length for e in edges) >= OUTLINE_TOL_MM  # no zero-length cuts left
    shapely.union_all([out, shapely.box(0, 0, 1, 1)])  # and it unions (what make did next)
