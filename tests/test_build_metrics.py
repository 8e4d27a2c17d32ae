"""tests/sheet_reader.py and tests/build_metrics.py, the independent readers and measures of the
sheets make writes (used by bench/bench_build.py): the three formats read back the same drawing,
the measures agree with what the folder says of itself, and a changed file changes them."""

from __future__ import annotations

import json
import math
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from build_metrics import NOT_LABELS, load_model, measure_folder
from sheet_reader import Label, read_dxf, read_pdf, read_svg

from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

SVG = "{http://www.w3.org/2000/svg}"
SAME_MM = 2e-3  # the writers keep coordinates to 1e-4 mm (SVG) or better


@pytest.fixture(scope="module")
def bunny(models_dir, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("built") / "bunny-128"
    make(models_dir / "bunny-128.obj", out, MakeOptions(time_limit=30))
    return out


def _same_segments(a: np.ndarray, b: np.ndarray) -> bool:
    """Segment sets (k, 2, 2) equal up to SAME_MM and the direction of each segment."""
    if a.shape != b.shape:
        return False
    d = np.minimum(np.abs(a[:, None] - b[None]).max(axis=(2, 3)), np.abs(a[:, None] - b[None, :, ::-1]).max(axis=(2, 3)))
    return bool((d.min(axis=1) < SAME_MM).all() and (d.min(axis=0) < SAME_MM).all())


def test_three_formats_read_the_same_drawing(bunny: Path) -> None:
    pytest.importorskip("pypdf")
    svgs = sorted(bunny.glob("sheet-*.svg"))
    pdf = read_pdf(bunny / "sheets.pdf")
    assert len(pdf) == len(svgs) >= 2
    for k, path in enumerate(svgs):
        svg = read_svg(path)
        dxf = read_dxf(path.with_suffix(".dxf"), svg.height, svg.width)
        assert (svg.width, svg.height) == (210.0, 297.0)
        assert abs(pdf[k].width - 210.0) < 1e-3 and abs(pdf[k].height - 297.0) < 1e-3
        assert len(svg.outlines) >= 1 and len(svg.faces) > 0
        for other in (dxf, pdf[k]):
            assert _same_segments(svg.lines(), other.lines())
            for kind in ("mountain", "valley"):
                assert _same_segments(svg.folds[kind], other.folds[kind])
        # the glue and piece labels: the DXF centres its text on the same baseline point, the PDF
        # starts it there minus half its width (titles, the footer, a scale bar's text: not compared)
        labels = [lb for lb in svg.labels if not any(w in lb.kind.lower() for w in NOT_LABELS)]
        assert len(labels) >= 2
        for s in labels:
            d = min(dxf.labels, key=lambda lb: math.dist(lb.anchor, s.anchor) + 1e3 * (lb.text != s.text))
            assert d.text == s.text and math.dist(d.anchor, s.anchor) < SAME_MM
            assert abs(s.angle - d.angle) < 1e-3 and abs(s.cap - d.cap) < 0.01 * s.cap
            p = min(pdf[k].labels, key=lambda lb: math.dist(lb.anchor, s.anchor) + 1e3 * (lb.text != s.text))
            assert p.text == s.text and abs(p.size - s.size) < 1e-3 and abs((p.angle - s.angle + 180) % 360 - 180) < 1e-3
            assert math.dist(p.anchor, s.anchor) < 0.6 * s.size * len(s.text)


def test_measures_agree_with_the_folder(bunny: Path, models_dir: Path) -> None:
    m = measure_folder(bunny, models_dir / "bunny-128.obj")
    assembly = json.loads((bunny / "assembly.json").read_text())
    layout = json.loads((bunny / "report.json").read_text())["stages"]["layout"]
    assert m.notes == [] or m.notes == ["pypdf not installed: PDF not measured"]
    assert (m.pieces, m.pages, m.glue_edges) == (len(assembly["pieces"]), assembly["pages"], len(assembly["glue"]))
    # every glue edge found twice on the sheets; the ones with a tab are the ones assembly.json says
    assert all(len(m.copies[g["label"]]) == 2 for g in assembly["glue"])
    assert m.untabbed_labels == [g["label"] for g in assembly["glue"] if g["tab_on"] is None]
    assert m.tabs == layout["tabs"] == sum(g["tab_on"] is not None for g in assembly["glue"])
    # the formats agree; every tab fold is drawn in one of them, the ones counted wrong go the other way
    assert len({tuple(v) for v in m.wrong_way_labels.values()}) == 1
    assert 0 <= m.wrong_way["svg"] <= m.tabs
    assert m.smallest_edge_mm == pytest.approx(layout["smallest_edge_mm"], rel=1e-9)
    assert m.smallest_face_mm == pytest.approx(layout["smallest_face_mm"], rel=1e-9)
    assert 0 < m.utilisation < 1 and m.labels >= 2 * m.glue_edges


def _tab_fold_element(root: ET.Element, a: np.ndarray, b: np.ndarray) -> tuple[ET.Element, ET.Element]:
    """(group, path) of the fold line drawn along a-b: the longest single segment on it (both ends
    within SAME_MM of the edge) covering at least 40 % of it (a tab clipped near a corner is hinged
    along part of its edge only)."""
    ab = b - a
    length = float(np.linalg.norm(ab))
    found, best = None, 0.4 * length
    for group in root.iter(f"{SVG}g"):
        for el in group.findall(f"{SVG}path"):
            nums = [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?", el.get("d", ""))]
            if len(nums) == 4:
                ends = np.array(nums).reshape(2, 2)
                t = np.clip((ends - a) @ ab / length**2, 0.0, 1.0)
                if np.linalg.norm(ends - (a + t[:, None] * ab), axis=1).max() < SAME_MM:
                    covered = abs(t[1] - t[0]) * length
                    if covered >= best:
                        found, best = (group, el), covered
    if found is None:
        raise AssertionError("no fold line along the tab's edge")
    return found


def test_changed_files_change_the_measures(bunny: Path, models_dir: Path, tmp_path: Path) -> None:
    """A tab fold moved to the mountain layer, a tab fold line removed, a label shrunk, a label
    moved onto another: each seen, in the SVG only."""
    mesh = models_dir / "bunny-128.obj"
    base = measure_folder(bunny, mesh)
    model = load_model(mesh, 150.0)
    assembly = json.loads((bunny / "assembly.json").read_text())
    # a tab on a convex seam (it should be a mountain)
    row = next(g for g in assembly["glue"] if g["tab_on"] is not None
               and model.fold_deg[tuple(sorted(g["mesh_vertices"]))] > 5.0)
    copy = next(c for c in base.copies[row["label"]] if c.beyond == "tab")
    was_wrong = row["label"] in base.wrong_way_labels["svg"]

    def changed(edit) -> object:
        out = tmp_path / f"case{len(list(tmp_path.iterdir()))}"
        shutil.copytree(bunny, out)
        svg = out / f"sheet-{copy.page + 1:02d}.svg"
        tree = ET.parse(svg)
        edit(tree.getroot())
        tree.write(svg)
        return measure_folder(out, mesh)

    def to_mountain(root):
        group, el = _tab_fold_element(root, copy.a, copy.b)
        group.remove(el)
        next(g for g in root.iter(f"{SVG}g") if g.get("id") == "mountain").append(el)

    m = changed(to_mountain)
    assert m.wrong_way["svg"] == base.wrong_way["svg"] - was_wrong
    assert row["label"] not in m.wrong_way_labels["svg"]
    assert {f: n for f, n in m.wrong_way.items() if f != "svg"} == {f: n for f, n in base.wrong_way.items() if f != "svg"}

    def to_valley(root):
        group, el = _tab_fold_element(root, copy.a, copy.b)
        group.remove(el)
        next(g for g in root.iter(f"{SVG}g") if g.get("id") == "valley").append(el)

    m = changed(to_valley)
    assert row["label"] in m.wrong_way_labels["svg"]

    def unfolded(root):
        group, el = _tab_fold_element(root, copy.a, copy.b)
        group.remove(el)

    m = changed(unfolded)  # paper beyond the edge without a fold line is no tab
    assert m.untabbed == base.untabbed + 1 and row["label"] in m.untabbed_labels and m.tabs == base.tabs - 1

    def texts(root) -> list[ET.Element]:
        """The glue labels of the page that are at least 2 mm tall (font size 2.78 mm)."""
        return [t for t in root.iter(f"{SVG}text") if t.get("class") == "edge-label" and float(t.get("font-size")) > 2.78]

    def shrunk(root):
        texts(root)[0].set("font-size", "2")  # cap height 1.44 mm

    assert changed(shrunk).small_labels == base.small_labels + 1

    def stacked(root):
        a, b = texts(root)[:2]
        b.set("x", a.get("x"))
        b.set("y", a.get("y"))
        b.set("transform", a.get("transform", ""))

    assert changed(stacked).label_pairs >= base.label_pairs + 1


def test_flat_regions_cut_on_the_cube(models_dir: Path, tmp_path: Path) -> None:
    """cube-12: the glue edges counted as flat regions cut are exactly those on a square's
    diagonal (end points differing in two coordinates)."""
    make(models_dir / "cube-12.obj", tmp_path, MakeOptions(time_limit=30))
    m = measure_folder(tmp_path, models_dir / "cube-12.obj")
    model = load_model(models_dir / "cube-12.obj", 150.0)
    assembly = json.loads((tmp_path / "assembly.json").read_text())
    diagonal = [g["label"] for g in assembly["glue"]
                if (np.abs(np.diff(model.vertices[g["mesh_vertices"]], axis=0)) > 1e-9).sum() > 1]
    assert m.flat_cut_labels == diagonal
    for g in assembly["glue"]:
        deg = model.fold_deg[tuple(sorted(g["mesh_vertices"]))]
        assert deg == pytest.approx(0.0 if g["label"] in diagonal else 90.0, abs=1e-9)


def test_model_fold_signs(models_dir: Path) -> None:
    """The L prism has concave (valley) vertical edges; its other edges are convex or flat."""
    model = load_model(models_dir / "l-prism-20.obj", 150.0)
    degs = np.array([d for d in model.fold_deg.values() if d is not None])
    assert (np.isclose(degs, 90.0) | np.isclose(degs, -90.0) | np.isclose(degs, 0.0, atol=1e-9)).all()
    assert (np.isclose(degs, -90.0)).sum() >= 1 and (np.isclose(degs, 90.0)).sum() >= 10
    assert max(np.ptp(model.vertices, axis=0)) * model.scale == pytest.approx(150.0)


def test_label_box() -> None:
    up = Label("12", (10.0, 20.0), 90.0, 2.0, 0.72 * 2.0)  # read bottom to top
    x0, y0, x1, y1 = up.box().bounds
    assert (x0, x1) == pytest.approx((10.0 - 1.44, 10.0))  # the letters' tops point left
    assert (y0, y1) == pytest.approx((20.0 - 1.112, 20.0 + 1.112))  # Helvetica's digits: 0.556 em
    flat = Label("A", (0.0, 0.0), 0.0, 10.0, 7.2, align="start")
    assert flat.box().bounds == pytest.approx((0.0, -7.2, 6.67, 0.0))


def test_pdf_and_dxf_readers_on_hand_made_files(tmp_path: Path) -> None:
    pytest.importorskip("pypdf")
    import ezdxf
    from reportlab.pdfgen.canvas import Canvas

    pt = 72 / 25.4
    c = Canvas(str(tmp_path / "t.pdf"), pagesize=(100 * pt, 50 * pt))
    c.setStrokeColorRGB(1, 0, 0)
    c.setDash([2 * pt, 1 * pt], 0)
    c.line(10 * pt, 40 * pt, 30 * pt, 40 * pt)  # a mountain 10 mm from the top
    c.setStrokeColorRGB(0, 0, 0)
    c.setDash([], 0)
    c.rect(50 * pt, 10 * pt, 20 * pt, 10 * pt, stroke=1, fill=0)  # a cut outline (re)
    c.setStrokeColorRGB(0, 0, 1)
    c.setDash([1 * pt, 1 * pt], 0)
    c.line(0, 0, 5 * pt, 5 * pt)  # a valley in the bottom-left corner
    c.setFillColorRGB(0.5, 0.5, 0.5)
    c.rect(0, 0, 5 * pt, 5 * pt, stroke=0, fill=1)
    c.setFont("Helvetica", 3 * pt)
    c.drawString(20 * pt, 25 * pt, "7")
    c.save()
    (page,) = read_pdf(tmp_path / "t.pdf")
    assert page.width == pytest.approx(100) and page.height == pytest.approx(50)
    np.testing.assert_allclose(page.folds["mountain"], [[[10, 10], [30, 10]]], atol=1e-4)
    np.testing.assert_allclose(page.folds["valley"], [[[0, 50], [5, 45]]], atol=1e-4)
    (ring,) = page.outlines
    assert sorted(map(tuple, np.round(ring, 4).tolist())) == [(50, 30), (50, 40), (70, 30), (70, 40)]
    assert [tuple(np.round(rgb, 3)) for rgb, _ in page.fills] == [(0.5, 0.5, 0.5)]
    (label,) = page.labels
    assert label.text == "7" and label.anchor == pytest.approx((20, 25)) and label.size == pytest.approx(3)

    doc = ezdxf.new("R2010")
    for name in ("CUT", "MOUNTAIN", "VALLEY", "LABELS"):
        doc.layers.add(name)
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 10)], close=True, dxfattribs={"layer": "CUT"})
    msp.add_line((1, 1), (2, 3), dxfattribs={"layer": "VALLEY"})
    msp.add_line((5, 5), (6, 5), dxfattribs={"layer": "MOUNTAIN"})
    msp.add_text("9", height=1.44, rotation=30, dxfattribs={"layer": "LABELS"}).set_placement((4, 4))
    doc.saveas(tmp_path / "t.dxf")
    sheet = read_dxf(tmp_path / "t.dxf", 50.0)
    np.testing.assert_allclose(sheet.outlines[0], [[0, 50], [10, 50], [10, 40]])
    np.testing.assert_allclose(sheet.folds["valley"], [[[1, 49], [2, 47]]])
    np.testing.assert_allclose(sheet.folds["mountain"], [[[5, 45], [6, 45]]])
    (label,) = sheet.labels
    assert label.anchor == pytest.approx((4, 46)) and label.angle == 30 and label.cap == pytest.approx(1.44)
