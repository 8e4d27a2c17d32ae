"""formats/svg.py: the SVG page writer's layers (Inkscape layers, z-order), units, exact
coordinates, crease styles, labels and preview fills, the scale bar and registration marks; the
cut file's plain strokes. (The cut file plotted by Inkscape: tests/pipeline/test_export.py.)"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np

from conftest import PAGE_TOL
from polyfold.fabricate.page import Page, footer, registration_marks
from polyfold.formats.svg import write_cut_svg, write_svg_page


SVG = "{http://www.w3.org/2000/svg}"


INK = "{http://www.inkscape.org/namespaces/inkscape}"


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
        np.testing.assert_allclose(_path_points(d), poly, atol=PAGE_TOL)
    assert layers["cut"].get("fill") == "none" and layers["cut"].get("stroke") == "#000000"
    assert float(layers["cut"].get("stroke-width")) <= 0.3

    mountain = layers["mountain"].findall(f"{SVG}path")
    valley = layers["valley"].findall(f"{SVG}path")
    assert len(mountain) == len(page.mountain)
    assert len(valley) == len(page.valley) + len(page.tab_folds)  # tab folds are scored like valleys
    assert sum(el.get("class") == "tab-fold" for el in valley) == len(page.tab_folds)
    np.testing.assert_allclose(_path_points(mountain[0].get("d")), page.mountain[0], atol=PAGE_TOL)
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


def test_print_svg_draws_scale_bar_and_marks(page: Page, tmp_path) -> None:
    text, bar = footer("test net", 10.0, 110.0, 80.0)
    marked = replace(page, texts=(*page.texts, text), scale_bar=bar, marks=registration_marks(page.width, page.height))
    write_svg_page(marked, tmp_path / "marked.svg")
    root = ET.parse(tmp_path / "marked.svg").getroot()
    layers = _layers(root)
    order = [g.get("id") for g in root.findall(f"{SVG}g")]
    assert order == ["preview", "labels", "scale", "registration", "valley", "mountain", "cut"]
    assert layers["scale"].get("class") == "no-cut" and layers["registration"].get("class") == "no-cut"
    segs = [_path_points(p.get("d")) for p in layers["scale"].findall(f"{SVG}path")]
    np.testing.assert_allclose(segs, bar.segments(), atol=PAGE_TOL)
    assert [t.text for t in layers["scale"].iter(f"{SVG}text")] == [bar.label.text]
    square, *corners = layers["registration"].findall(f"{SVG}path")
    assert square.get("fill") == "#000000" and square.get("d").endswith("Z")
    np.testing.assert_allclose([_path_points(c.get("d")) for c in corners], marked.marks.corners, atol=PAGE_TOL)
    assert all(c.get("stroke") == "#000000" and c.get("fill") is None for c in corners)  # layer: fill none


def test_cut_svg_is_plain_strokes_of_the_print_geometry(page: Page, tmp_path) -> None:
    slit = replace(page, slits=[[[30.0, 30.0], [40.0, 40.0]]], marks=registration_marks(page.width, page.height))
    write_svg_page(slit, tmp_path / "print.svg")
    write_cut_svg(slit, tmp_path / "cut.svg")
    root = ET.parse(tmp_path / "cut.svg").getroot()
    assert root.get("viewBox") == ET.parse(tmp_path / "print.svg").getroot().get("viewBox")
    cut, printed = _layers(root), _layers(ET.parse(tmp_path / "print.svg").getroot())
    assert list(cut) == ["valley", "mountain", "cut"]  # no preview, labels, scale or marks
    assert not list(root.iter(f"{SVG}text")) and not any(el.get("class") == "no-cut" for el in root.iter())
    for name, layer in cut.items():
        assert layer.get("fill") == "none" and layer.get("stroke-dasharray") is None
        assert [p.get("d") for p in layer] == [p.get("d") for p in printed[name].findall(f"{SVG}path")]
    paths = cut["cut"].findall(f"{SVG}path")
    assert [p.get("d").endswith("Z") for p in paths] == [True] * len(page.cut) + [False]  # outlines closed, the slit open
    n_scores = len(cut["mountain"]) + len(cut["valley"])
    assert n_scores == len(page.mountain) + len(page.valley) + len(page.tab_folds)
