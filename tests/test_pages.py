"""Page model and its SVG / PDF / DXF writers: layers, styles, exact coordinates, atomic writes."""

from __future__ import annotations

import base64
import math
import os
import re
import xml.etree.ElementTree as ET
import zlib

import ezdxf
import numpy as np
import pytest

from polyfold.formats import pdf as pdf_writer
from polyfold.formats import sheet_style
from polyfold.fabricate.page import Page, TextItem
from polyfold.formats.dxf import write_dxf_page
from polyfold.formats.pdf import write_pdf
from polyfold.formats.sheet_style import MM_TO_PT
from polyfold.formats.svg import write_svg_page

SVG = "{http://www.w3.org/2000/svg}"
INK = "{http://www.inkscape.org/namespaces/inkscape}"
TOL = 1e-3  # mm


def _square_piece(x0: float, y0: float, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A square (outline, its diagonal, its two triangles) with top-left corner (x0, y0)."""
    a, b, c, d = (x0, y0), (x0 + s, y0), (x0 + s, y0 + s), (x0, y0 + s)
    return np.array([a, b, c, d], float), np.array([a, c], float), np.array([[a, b, c], [a, c, d]], float)


@pytest.fixture
def page() -> Page:
    """Two 30 mm squares split into triangles (one mountain, one valley diagonal); the first has a
    glue tab on its top edge (in its outline, fold along the edge); edge, piece and title labels."""
    sq1, diag1, tris1 = _square_piece(20.0, 25.0, 30.0)
    sq2, diag2, tris2 = _square_piece(70.5, 40.25, 30.0)
    # Tab on the top edge (20,25)-(50,25) of piece 1: outline goes a -> tab -> b -> c -> d.
    outline1 = np.array([sq1[0], (25.0, 19.0), (45.0, 19.0), sq1[1], sq1[2], sq1[3]])
    return Page(
        width=120.0,
        height=90.0,
        cut=(outline1, sq2),
        mountain=diag1[None],
        valley=diag2[None],
        tab_folds=np.array([[sq1[0], sq1[1]]]),
        texts=(
            TextItem("7", 35.0, 22.0, 0.0, 2.5, "edge-label"),
            TextItem("7", 85.5, 41.5, 90.0, 2.5, "edge-label"),
            TextItem("P1", 38.0, 45.0, 30.0, 4.0, "piece-label"),
            TextItem("test net", 60.0, 5.0, 0.0, 3.0, "title"),
        ),
        faces=(tris1, tris2),
    )


# ----------------------------------------------------------------------------------------------
# model


def test_page_coerces_and_validates() -> None:
    p = Page(50, 40, cut=([[0, 0], [10, 0], [10, 10], [0, 0]],), mountain=[], valley=np.zeros((0, 2, 2)),
             tab_folds=[[[0, 0], [1, 1]]], texts=())
    assert p.cut[0].shape == (3, 2) and p.cut[0].dtype == np.float64  # repeated closing point dropped
    assert p.mountain.shape == (0, 2, 2) and p.tab_folds.shape == (1, 2, 2)
    with pytest.raises(ValueError):
        Page(50, 40, cut=([[0, 0], [1, 1]],), mountain=[], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        Page(50, 40, cut=(), mountain=[[[0, 0], [np.nan, 1]]], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        Page(0, 40, cut=(), mountain=[], valley=[], tab_folds=[], texts=())
    with pytest.raises(ValueError):
        TextItem("x", 0, 0, 0, 2, "caption")


def test_baseline_centres_text_for_any_angle() -> None:
    for angle in (0.0, 30.0, 90.0, -135.0):
        t = TextItem("A", 10.0, 20.0, angle, 4.0, "edge-label")
        bx, by = sheet_style.text_baseline(t)
        a = math.radians(angle)
        reading = np.array([math.cos(a), -math.sin(a)])  # CCW on a y-down page
        off = np.array([bx - 10.0, by - 20.0])
        assert abs(off @ reading) < 1e-12  # shifted across the reading direction only
        assert math.isclose(np.hypot(*off), 0.5 * sheet_style.CAP_HEIGHT * 4.0)
        # Towards the glyphs' bottom: clockwise of the reading direction as seen on screen.
        assert reading[0] * off[1] - reading[1] * off[0] > 0


# ----------------------------------------------------------------------------------------------
# SVG


def _layers(root: ET.Element) -> dict[str, ET.Element]:
    return {g.get("id"): g for g in root.findall(f"{SVG}g")}


def _path_points(d: str) -> np.ndarray:
    return np.array([float(v) for v in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", d)]).reshape(-1, 2)


def test_svg_layers_units_and_coordinates(page: Page, tmp_path) -> None:
    path = tmp_path / "page.svg"
    write_svg_page(page, path)
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG}svg"
    assert root.get("width") == "120mm" and root.get("height") == "90mm"
    assert [float(v) for v in root.get("viewBox").split()] == [0, 0, 120, 90]

    layers = _layers(root)
    assert {"cut", "mountain", "valley", "labels", "preview"} <= set(layers)
    for name in ("cut", "mountain", "valley", "labels", "preview"):
        assert layers[name].get(f"{INK}groupmode") == "layer"
        assert layers[name].get(f"{INK}label") == name
    # Document order is z-order: preview fills at the bottom, cut lines on top.
    order = [g.get("id") for g in root.findall(f"{SVG}g")]
    assert order[0] == "preview" and order[-1] == "cut"
    assert layers["labels"].get("class") == "no-cut" and layers["preview"].get("class") == "no-cut"

    cut_paths = layers["cut"].findall(f"{SVG}path")
    assert len(cut_paths) == len(page.cut)
    for el, poly in zip(cut_paths, page.cut):
        d = el.get("d")
        assert d.rstrip().endswith("Z")  # closed by the writer
        np.testing.assert_allclose(_path_points(d), poly, atol=TOL)
    assert layers["cut"].get("fill") == "none" and layers["cut"].get("stroke") == "#000000"
    assert float(layers["cut"].get("stroke-width")) <= 0.3

    mountain = layers["mountain"].findall(f"{SVG}path")
    valley = layers["valley"].findall(f"{SVG}path")
    assert len(mountain) == len(page.mountain)
    assert len(valley) == len(page.valley) + len(page.tab_folds)  # tab folds are scored like valleys
    assert sum(el.get("class") == "tab-fold" for el in valley) == len(page.tab_folds)
    np.testing.assert_allclose(_path_points(mountain[0].get("d")), page.mountain[0], atol=TOL)
    dm, dv = layers["mountain"].get("stroke-dasharray"), layers["valley"].get("stroke-dasharray")
    assert dm and dv and dm != dv
    assert len(dm.split(",")) == 4 and len(dv.split(",")) == 2  # dash-dot vs dashed
    assert layers["mountain"].get("stroke") != layers["valley"].get("stroke")

    texts = layers["labels"].findall(f"{SVG}text")
    assert [t.text for t in texts] == [t.text for t in page.texts]
    assert texts[0].get("transform") is None  # angle 0
    assert texts[1].get("transform").startswith("rotate(-90 ")  # CCW on the page = negative SVG rotate
    assert len(layers["preview"].findall(f"{SVG}path")) == len(page.faces)


def test_svg_without_faces_has_no_preview(page: Page, tmp_path) -> None:
    bare = Page(page.width, page.height, page.cut, page.mountain, page.valley, page.tab_folds, page.texts)
    write_svg_page(bare, tmp_path / "bare.svg")
    assert "preview" not in _layers(ET.parse(tmp_path / "bare.svg").getroot())


# ----------------------------------------------------------------------------------------------
# PDF


def _pdf_content_streams(data: bytes) -> list[bytes]:
    """Decoded content streams of a reportlab PDF (ASCII85 + Flate, or unfiltered)."""
    out = []
    for m in re.finditer(rb"<<(.*?)>>\s*stream\r?\n(.*?)endstream", data, re.S):
        head, body = m.group(1), m.group(2)
        if b"/ASCII85Decode" in head:
            body = base64.a85decode(body.strip().removesuffix(b"~>"))
        if b"/FlateDecode" in head:
            body = zlib.decompress(body)
        out.append(body)
    return out


def test_pdf_pages_mediabox_and_geometry(page: Page, tmp_path) -> None:
    small = Page(50.0, 30.0, cut=([[5, 5], [20, 5], [20, 20]],), mountain=[], valley=[], tab_folds=[], texts=())
    path = tmp_path / "net.pdf"
    write_pdf([page, small, page], path, title="my net")
    data = path.read_bytes()
    assert data.startswith(b"%PDF")
    assert len(re.findall(rb"/Type\s*/Page(?![s\w])", data)) == 3
    boxes = [[float(v) for v in m.split()] for m in re.findall(rb"/MediaBox\s*\[([^\]]*)\]", data)]
    expected = [(p.width * MM_TO_PT, p.height * MM_TO_PT) for p in (page, small, page)]
    assert len(boxes) == 3
    for box, (w, h) in zip(boxes, expected):
        np.testing.assert_allclose(box, [0, 0, w, h], atol=1e-3)
    assert b"(my net)" in data  # title in the document info

    # Geometry: the small page's triangle, in points with y flipped (origin bottom-left).
    content = [s for s in _pdf_content_streams(data) if b" m" in s]
    assert len(content) == 3
    pts = np.array([[float(x), float(y)] for x, y in re.findall(rb"(-?[\d.]+) (-?[\d.]+) [ml]\b", content[1])])
    expect = np.array([[5, 30 - 5], [20, 30 - 5], [20, 30 - 20]]) * MM_TO_PT
    np.testing.assert_allclose(pts, expect, atol=TOL * MM_TO_PT)
    # Colours and dashes of the big page: red and blue strokes, two distinct dash arrays.
    big = content[0].decode("latin-1")
    assert re.search(r"\b1 0 0 RG\b", big) and re.search(r"\b0 0 1 RG\b", big)
    dashes = set(re.findall(r"\[([^\]]*)\] 0 d", big))
    assert len({d for d in dashes if d.strip()}) == 2
    # Text is drawn in Helvetica, rotated about its flipped baseline anchor: 90 deg -> (0 1 -1 0).
    assert "/F1 " in big and "(P1) Tj" in big
    m = re.search(r"(?m)^0 1 -1 0 (-?[\d.]+) (-?[\d.]+) cm$", big)
    assert m, "no text rotated by 90 degrees"
    bx, by = sheet_style.text_baseline(page.texts[1])
    np.testing.assert_allclose([float(m.group(1)), float(m.group(2))],
                               [bx * MM_TO_PT, (page.height - by) * MM_TO_PT], atol=TOL * MM_TO_PT)


def test_pdf_rejects_no_pages(tmp_path) -> None:
    with pytest.raises(ValueError):
        write_pdf([], tmp_path / "empty.pdf")
    assert not any(tmp_path.iterdir())


# ----------------------------------------------------------------------------------------------
# DXF


def test_dxf_layers_units_entities_and_flip(page: Page, tmp_path) -> None:
    path = tmp_path / "page.dxf"
    write_dxf_page(page, path)
    doc = ezdxf.readfile(path)
    assert doc.header["$INSUNITS"] == 4
    for name, color, linetype in (("CUT", 7, "CONTINUOUS"), ("MOUNTAIN", 1, "DASHDOT"),
                                  ("VALLEY", 5, "DASHED"), ("LABELS", None, None)):
        layer = doc.layers.get(name)
        assert layer is not None
        if color is not None:
            assert layer.color == color and layer.dxf.linetype.upper() == linetype

    msp = doc.modelspace()
    by_layer: dict[tuple[str, str], int] = {}
    for e in msp:
        key = (e.dxf.layer, e.dxftype())
        by_layer[key] = by_layer.get(key, 0) + 1
    assert by_layer == {
        ("CUT", "LWPOLYLINE"): len(page.cut),
        ("MOUNTAIN", "LINE"): len(page.mountain),
        ("VALLEY", "LINE"): len(page.valley) + len(page.tab_folds),
        ("LABELS", "TEXT"): len(page.texts),
    }

    flip = np.array([1.0, -1.0])
    shift = np.array([0.0, page.height])
    polys = msp.query('LWPOLYLINE[layer=="CUT"]')
    for e, poly in zip(polys, page.cut):
        assert e.closed
        got = np.array([(x, y) for x, y, *_ in e.get_points()])
        np.testing.assert_allclose(got, poly * flip + shift, atol=TOL)
    line = msp.query('LINE[layer=="MOUNTAIN"]')[0]
    ends = [(line.dxf.start.x, line.dxf.start.y), (line.dxf.end.x, line.dxf.end.y)]
    np.testing.assert_allclose(ends, page.mountain[0] * flip + shift, atol=TOL)
    texts = msp.query("TEXT")
    assert [t.dxf.text for t in texts] == [t.text for t in page.texts]
    assert [t.dxf.rotation for t in texts] == [t.angle for t in page.texts]  # flip keeps CCW sense
    anchor = np.array([texts[0].dxf.align_point.x, texts[0].dxf.align_point.y])
    bx, by = sheet_style.text_baseline(page.texts[0])
    np.testing.assert_allclose(anchor, [bx, page.height - by], atol=TOL)


# ----------------------------------------------------------------------------------------------
# atomic writes


WRITERS = {
    "svg": lambda p, path: write_svg_page(p, path),
    "pdf": lambda p, path: write_pdf([p], path),
    "dxf": lambda p, path: write_dxf_page(p, path),
}


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_failed_write_leaves_no_file(page: Page, tmp_path, monkeypatch, fmt: str) -> None:
    def boom(*_args, **_kwargs):
        raise OSError("disk full")

    # Fails after the bytes went into the temp file, before it replaces the target.
    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(OSError, match="disk full"):
        WRITERS[fmt](page, tmp_path / f"out.{fmt}")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_failed_write_keeps_old_file(page: Page, tmp_path, monkeypatch, fmt: str) -> None:
    target = tmp_path / f"out.{fmt}"
    target.write_bytes(b"old")

    def boom(*_args, **_kwargs):
        raise RuntimeError("interrupted")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(RuntimeError):
        WRITERS[fmt](page, target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


def test_failure_while_drawing_writes_nothing(page: Page, tmp_path, monkeypatch) -> None:
    def boom(*_args, **_kwargs):
        raise RuntimeError("renderer crashed")

    monkeypatch.setattr(pdf_writer, "_draw_pdf_page", boom)
    with pytest.raises(RuntimeError):
        write_pdf([page], tmp_path / "x.pdf")
    assert list(tmp_path.iterdir()) == []
