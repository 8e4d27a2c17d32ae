"""Cut sheet (SVG) and PNG preview of hand-made FOLD nets."""

from __future__ import annotations

import logging
import math
import re
import struct
import xml.etree.ElementTree as ET
import zlib
from collections import Counter

import numpy as np
import pytest
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from polyfold.formats import sheet

SVG = "{http://www.w3.org/2000/svg}"
H3 = math.sqrt(3) / 2
TETRA_FOLD = -(180 - math.degrees(math.acos(1 / 3)))  # mountain: negative


# ----------------------------------------------------------------------------------------------
# helpers


def make_fold(coords2, faces, pieces, assign=None, mesh_edge=None, coords3=None, fold_angle=-90.0):
    """FOLD dict from triangles; edges derived from the faces (one entry per vertex pair).

    assign: {(u, v): "M"/"V"/"F"} for creases (others: shared by two faces -> "F", else "B");
    mesh_edge: {(u, v): int} (missing edges get fresh unique numbers).
    """
    assign = {tuple(sorted(k)): v for k, v in (assign or {}).items()}
    mesh_edge = {tuple(sorted(k)): v for k, v in (mesh_edge or {}).items()}
    count = Counter()
    order = []
    for f in faces:
        for i in range(3):
            key = tuple(sorted((f[i], f[(i + 1) % 3])))
            if key not in count:
                order.append(key)
            count[key] += 1
    fresh = max(mesh_edge.values(), default=-1) + 1
    ev, ea, fa, me = [], [], [], []
    for key in order:
        a = assign.get(key, "F" if count[key] == 2 else "B")
        ev.append(list(key))
        ea.append(a)
        fa.append({"M": fold_angle, "V": -fold_angle}.get(a, 0.0))
        if key not in mesh_edge:
            mesh_edge[key] = fresh
            fresh += 1
        me.append(mesh_edge[key])
    if coords3 is None:
        coords3 = [[x, y, 0.0] for x, y in coords2]
    return {
        "file_spec": 1.1,
        "vertices_coords": [list(map(float, p)) for p in coords2],
        "faces_vertices": [list(map(int, f)) for f in faces],
        "edges_vertices": ev,
        "edges_assignment": ea,
        "edges_foldAngle": fa,
        "file_frames": [{"frame_classes": ["foldedForm"], "frame_inherit": True, "frame_parent": 0,
                         "frame_attributes": ["3D"], "vertices_coords": coords3}],
        "polyfold:faces_piece": list(pieces),
        "polyfold:edges_meshEdge": me,
    }


APEX = [1.0, H3 / 3, -math.sqrt(2 / 3)]


def tetra_fold():
    """Regular tetrahedron (edge 1) unfolded into one big triangle: A B C corners, D E F midpoints."""
    A, D, B, E, F, C = range(6)
    coords = [(0, 0), (1, 0), (2, 0), (1.5, H3), (0.5, H3), (1, 2 * H3)]
    c3 = [APEX, [1, 0, 0], APEX, [1.5, H3, 0], [0.5, H3, 0], APEX]
    faces = [[A, D, F], [D, B, E], [F, E, C], [D, E, F]]
    assign = {(D, E): "M", (E, F): "M", (F, D): "M"}
    me = {(D, E): 0, (E, F): 1, (F, D): 2, (A, D): 3, (A, F): 3, (D, B): 4, (B, E): 4, (E, C): 5, (C, F): 5}
    return make_fold(coords, faces, [0] * 4, assign, me, c3, TETRA_FOLD)


def tetra_two_pieces(gap=0.02):
    """Tetrahedron net in two pieces; piece 1 (triangle F'E'C', turned over 180 degrees in the plane)
    points its tip into the room above piece 0's edge FE, so a tab there is blocked."""
    A, D, B, E, F = range(5)
    F1, E1, C1 = 5, 6, 7
    coords = [(0, 0), (1, 0), (2, 0), (1.5, H3), (0.5, H3), (1.5, 2 * H3 + gap), (0.5, 2 * H3 + gap), (1, H3 + gap)]
    c3 = [APEX, [1, 0, 0], APEX, [1.5, H3, 0], [0.5, H3, 0], [0.5, H3, 0], [1.5, H3, 0], APEX]
    faces = [[A, D, F], [D, B, E], [D, E, F], [F1, E1, C1]]
    assign = {(D, E): "M", (F, D): "M"}
    me = {(D, E): 0, (E, F): 1, (F1, E1): 1, (F, D): 2, (A, D): 3, (A, F): 3, (D, B): 4, (B, E): 4,
          (E1, C1): 5, (C1, F1): 5}
    return make_fold(coords, faces, [0, 0, 0, 1], assign, me, c3, TETRA_FOLD)


def grid_fold(cells, split_vertex=None):
    """Unit grid cells (i, j), each split in two CCW triangles; one piece, flat (z = 0).

    split_vertex=(x, y, cell): give the faces of `cell` their own copy of grid point (x, y)."""
    idx: dict = {}
    coords = []

    def vid(p):
        if p not in idx:
            idx[p] = len(coords)
            coords.append(p[:2])
        return idx[p]

    faces = []
    for (i, j) in cells:
        def corner(x, y):
            if split_vertex and (x, y) == split_vertex[:2] and (i, j) == split_vertex[2]:
                return vid((x, y, "copy"))
            return vid((x, y))
        p00, p10, p11, p01 = corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)
        faces += [[p00, p10, p11], [p00, p11, p01]]
    return make_fold(coords, faces, [0] * len(faces))


def square_valley():
    return make_fold([(0, 0), (1, 0), (1, 1), (0, 1)], [[0, 1, 2], [0, 2, 3]], [0, 0], {(0, 2): "V"})


def render(fold, tmp_path, **kw):
    path = tmp_path / "net.svg"
    sheet.write_svg(fold, path, **kw)
    return ET.parse(path).getroot()


def by_class(root, cls):
    return [el for el in root.iter() if el.get("class") == cls]


def subpaths(d):
    """[(points, closed)] of a path made of M/L/Z commands."""
    out = []
    for tok in re.findall(r"[MLZ]|-?\d+(?:\.\d+)?,-?\d+(?:\.\d+)?", d):
        if tok == "M":
            out.append([[], False])
        elif tok == "Z":
            out[-1][1] = True
        elif tok != "L":
            out[-1][0].append(tuple(float(v) for v in tok.split(",")))
    return [(pts, closed) for pts, closed in out]


def key(p):
    return (round(p[0], 2), round(p[1], 2))


def segments(d):
    segs = Counter()
    for pts, closed in subpaths(d):
        ring = pts + [pts[0]] if closed else pts
        for p, q in zip(ring, ring[1:]):
            segs[frozenset((key(p), key(q)))] += 1
    return segs


def cut_edges_mm(fold, lay, piece):
    segs = Counter()
    fp = fold["polyfold:faces_piece"]
    for (u, v), a in zip(fold["edges_vertices"], fold["edges_assignment"]):
        if a == "B" and any(fp[f] == piece and u in fv and v in fv for f, fv in enumerate(fold["faces_vertices"])):
            segs[frozenset((key(lay.coords[u]), key(lay.coords[v])))] += 1
    return segs


def net_polygon(fold, lay):
    return unary_union([Polygon(lay.coords[f]) for f in fold["faces_vertices"]])


def overlaps(a, b):
    """True if the polygons overlap by more than the SVG's 0.001 mm coordinate rounding."""
    return a.buffer(-0.01).intersects(b)


def tab_polygons(root):
    return {el.get("id"): Polygon(subpaths(el.get("d"))[0][0]) for el in by_class(root, "tab")}


# ----------------------------------------------------------------------------------------------
# SVG


def test_layout_scale_and_size():
    fold = tetra_fold()
    lay = sheet.sheet_layout(fold, 100.0)
    assert lay.longest == pytest.approx(1.0)
    assert lay.scale == pytest.approx(100.0)
    assert lay.width == pytest.approx(2 * 100 + 20)
    assert lay.height == pytest.approx(2 * H3 * 100 + 20)
    assert lay.coords[:, 0].min() == pytest.approx(10) and lay.coords[:, 1].min() == pytest.approx(10)
    # y flipped: A (y = 0) at the bottom of the sheet, C (top) at the margin
    assert lay.coords[0, 1] == pytest.approx(lay.height - 10) and lay.coords[5, 1] == pytest.approx(10)
    assert not lay.oversize


def test_tetra_svg(tmp_path):
    fold = tetra_fold()
    root = render(fold, tmp_path, size_mm=100)
    lay = sheet.sheet_layout(fold, 100)
    w, h = root.get("width"), root.get("height")
    assert w.endswith("mm") and h.endswith("mm")
    assert float(w[:-2]) == pytest.approx(220, abs=1e-3)
    assert float(h[:-2]) == pytest.approx(2 * H3 * 100 + 20, abs=1e-3)
    assert [float(v) for v in root.get("viewBox").split()] == pytest.approx([0, 0, float(w[:-2]), float(h[:-2])])

    cuts = by_class(root, "cut")
    assert [c.get("id") for c in cuts] == ["cut-0"]
    sp = subpaths(cuts[0].get("d"))
    assert len(sp) == 1 and sp[0][1]
    assert segments(cuts[0].get("d")) == cut_edges_mm(fold, lay, 0)

    assert len(by_class(root, "mountain")) == fold["edges_assignment"].count("M") == 3
    assert len(by_class(root, "valley")) == 0

    labels = Counter(t.text for t in by_class(root, "label"))
    assert labels == {"3": 2, "4": 2, "5": 2}
    net = net_polygon(fold, lay)
    for t in by_class(root, "label"):  # just inside the net, next to the edge
        pt = Point(float(t.get("x")), float(t.get("y")))
        assert net.contains(pt) and net.exterior.distance(pt) < 3

    tabs = tab_polygons(root)
    assert sorted(tabs) == ["tab-3", "tab-4", "tab-5"]
    assert len(by_class(root, "tab-fold")) == 3
    net = net_polygon(fold, lay)
    for poly in tabs.values():
        assert poly.is_valid and poly.area > 1
        assert not overlaps(poly, net)
        assert 0 <= poly.bounds[0] and poly.bounds[2] <= lay.width and 0 <= poly.bounds[1] and poly.bounds[3] <= lay.height
    polys = list(tabs.values())
    for i in range(len(polys)):
        for j in range(i + 1, len(polys)):
            assert not overlaps(polys[i], polys[j])
    assert by_class(root, "title") and "1 piece" in by_class(root, "title")[0].text


def test_tab_falls_back_to_other_twin(tmp_path):
    fold = tetra_two_pieces()
    root = render(fold, tmp_path, size_mm=100)
    lay = sheet.sheet_layout(fold, 100)
    assert sorted(c.get("id") for c in by_class(root, "cut")) == ["cut-0", "cut-1"]
    for piece in (0, 1):
        d = root.find(f".//{SVG}path[@id='cut-{piece}']").get("d")
        assert len(subpaths(d)) == 1
        assert segments(d) == cut_edges_mm(fold, lay, piece)
    assert len(by_class(root, "mountain")) == 2
    assert Counter(t.text for t in by_class(root, "label")) == {"1": 2, "3": 2, "4": 2, "5": 2}

    tabs = tab_polygons(root)
    # edge FE of piece 0 comes first but is blocked by piece 1's tip: the tab goes on F'E'
    base = {key(p) for p in tabs["tab-1"].exterior.coords}
    assert key(lay.coords[5]) in base and key(lay.coords[6]) in base
    assert tabs["tab-1"].centroid.y < lay.coords[5, 1]  # above piece 1 on the sheet
    net = net_polygon(fold, lay)
    polys = list(tabs.values())
    for i, poly in enumerate(polys):
        assert not overlaps(poly, net)
        for other in polys[i + 1:]:
            assert not overlaps(poly, other)


def test_tab_omitted_when_both_twins_blocked(tmp_path):
    fold = tetra_two_pieces()
    # turn piece 1 back (tip up) and put it right above FE: both twins of edge 1 face each other
    fold["vertices_coords"][5:8] = [[0.5, H3 + 0.02], [1.5, H3 + 0.02], [1.0, 2 * H3 + 0.02]]
    root = render(fold, tmp_path, size_mm=100)
    tabs = tab_polygons(root)
    assert "tab-1" not in tabs
    assert Counter(t.text for t in by_class(root, "label"))["1"] == 2  # labels still tell what to glue


def test_valley_and_open_boundary(tmp_path):
    fold = square_valley()
    root = render(fold, tmp_path, size_mm=50)
    assert len(by_class(root, "valley")) == 1 and len(by_class(root, "mountain")) == 0
    assert not by_class(root, "label") and not by_class(root, "tab")  # open boundary: nothing to glue
    v = by_class(root, "valley")[0]
    assert v.get("stroke-dasharray") and v.get("stroke") != "#000000"
    cut = by_class(root, "cut")[0]
    assert len(segments(cut.get("d"))) == 4


def test_mountain_valley_styles_differ(tmp_path):
    fold = square_valley()
    fold["vertices_coords"] += [[3, 0], [4, 0], [4, 1], [3, 1]]
    fold["faces_vertices"] += [[4, 5, 6], [4, 6, 7]]
    fold["polyfold:faces_piece"] += [1, 1]
    fold["file_frames"][0]["vertices_coords"] += [[3, 0, 0], [4, 0, 0], [4, 1, 0], [3, 1, 0]]
    for e in ([4, 5], [5, 6], [6, 7], [4, 7]):
        fold["edges_vertices"].append(e)
        fold["edges_assignment"].append("B")
        fold["edges_foldAngle"].append(0)
        fold["polyfold:edges_meshEdge"].append(100 + len(fold["edges_vertices"]))
    fold["edges_vertices"].append([4, 6])
    fold["edges_assignment"].append("M")
    fold["edges_foldAngle"].append(-90)
    fold["polyfold:edges_meshEdge"].append(200)
    root = render(fold, tmp_path, size_mm=50)
    (m,), (v,) = by_class(root, "mountain"), by_class(root, "valley")
    assert (m.get("stroke"), m.get("stroke-dasharray")) != (v.get("stroke"), v.get("stroke-dasharray"))
    assert len(by_class(root, "cut")) == 2


def test_annulus_one_path_two_loops(tmp_path):
    ring = [(i, j) for i in range(3) for j in range(3) if (i, j) != (1, 1)]
    fold = grid_fold(ring)
    root = render(fold, tmp_path, size_mm=60)
    lay = sheet.sheet_layout(fold, 60)
    (cut,) = by_class(root, "cut")
    sp = subpaths(cut.get("d"))
    assert len(sp) == 2 and all(c for _, c in sp)
    assert sorted(len(p) for p, _ in sp) == [4, 12]
    assert segments(cut.get("d")) == cut_edges_mm(fold, lay, 0)


@pytest.mark.parametrize("split", [False, True])
def test_boundary_touching_itself_is_one_loop(tmp_path, split):
    # a strip of cells that comes back to touch itself at grid point (2, 2) (cells (1,1) and (2,2))
    strip = [(1, 1), (0, 1), (0, 2), (0, 3), (1, 3), (2, 3), (2, 2)]
    fold = grid_fold(strip, split_vertex=(2, 2, (2, 2)) if split else None)
    n_b = fold["edges_assignment"].count("B")
    assert n_b == 16
    root = render(fold, tmp_path, size_mm=60)
    lay = sheet.sheet_layout(fold, 60)
    (cut,) = by_class(root, "cut")
    sp = subpaths(cut.get("d"))
    assert len(sp) == 1 and sp[0][1] and len(sp[0][0]) == 16
    segs = segments(cut.get("d"))
    assert segs == cut_edges_mm(fold, lay, 0) and sum(segs.values()) == 16


def test_no_labels_no_tabs(tmp_path):
    root = render(tetra_fold(), tmp_path, size_mm=100, labels=False, tabs=False)
    assert not by_class(root, "label") and not by_class(root, "tab") and not by_class(root, "tab-fold")
    assert len(by_class(root, "cut")) == 1


def test_oversize_flag_and_atomic_overwrite(tmp_path):
    path = tmp_path / "net.svg"
    path.write_text("old")
    sheet.write_svg(tetra_fold(), path)  # 150 mm model -> 320 mm wide sheet
    assert sheet.sheet_layout(tetra_fold(), 150).oversize
    assert not sheet.sheet_layout(tetra_fold(), 60).oversize
    assert ET.parse(path).getroot().tag == SVG + "svg"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["net.svg"]


# ----------------------------------------------------------------------------------------------
# PNG


def read_png(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, []
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        tag, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        (crc,) = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        assert crc == zlib.crc32(tag + body) & 0xFFFFFFFF
        chunks.append((tag, body))
        pos += 12 + n
    assert chunks[0][0] == b"IHDR" and chunks[-1][0] == b"IEND"
    w, h, depth, ctype, comp, filt, inter = struct.unpack(">IIBBBBB", chunks[0][1])
    assert (depth, ctype, comp, filt, inter) == (8, 2, 0, 0, 0)
    raw = zlib.decompress(b"".join(body for tag, body in chunks if tag == b"IDAT"))
    assert len(raw) == h * (1 + 3 * w)
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(h, 1 + 3 * w)
    assert (rows[:, 0] == 0).all()
    return rows[:, 1:].reshape(h, w, 3)


def test_png_preview(tmp_path):
    fold = tetra_two_pieces(gap=0.3)
    path = tmp_path / "net.png"
    sheet.write_png(fold, path, width_px=400)
    img = read_png(path)
    net = sheet._parse(fold)
    r = sheet._raster_layout(net, 400)
    assert img.shape == (r.height, 400, 3)
    # aspect kept: net is 2 x (2*H3 + 0.3) model units
    assert r.height == pytest.approx(400 * (2 * H3 + 0.3) / 2, rel=0.1)
    coords = np.asarray(fold["vertices_coords"])
    for f, piece in zip(fold["faces_vertices"], fold["polyfold:faces_piece"]):
        x, y = r.to_px(coords[f].mean(axis=0))
        assert tuple(img[int(y), int(x)]) == sheet._piece_color(piece)
    assert sheet._piece_color(0) != sheet._piece_color(1)
    assert tuple(img[0, 0]) == (255, 255, 255) and tuple(img[-1, -1]) == (255, 255, 255)
    # cut edge A-D (bottom side) is black at its middle; mountains show up red
    x, y = r.to_px([0.5, 0.0])
    assert tuple(img[int(y), int(x)]) == (0, 0, 0)
    red = (img[:, :, 0] > 200) & (img[:, :, 1] < 60) & (img[:, :, 2] < 60)
    assert red.sum() > 50


def test_png_valley_blue(tmp_path):
    path = tmp_path / "sq.png"
    sheet.write_png(square_valley(), path, width_px=100)
    img = read_png(path)
    assert img.shape[0] == img.shape[1] == 100
    blue = (img[:, :, 2] > 200) & (img[:, :, 0] < 60)
    assert blue.sum() > 20
