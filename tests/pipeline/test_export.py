"""pipeline/export.py on a real make folder (bunny-128, A4, 150 mm), read back by other programs:
the cut files plotted by Inkscape's HPGL export (one pen-down stroke per outline and per score
line), the scale bar measured in the print SVG (xml.etree) and in the PDF (rasterised by
poppler's pdftoppm, its label found by pdftotext -bbox), and --marks: registration marks on the
printed pages, none in the cut files, pieces clear of the marked corners.

Tools missing on the machine skip their test with the reason (.ci/run installs them)."""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

from conftest import read_sheet
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

SVG = "{http://www.w3.org/2000/svg}"
HPGL_UNITS_PER_MM = 1016 / 25.4  # Inkscape's HPGL export at its default resolution (1016 dpi)
PDF_DPI = 600


def _make(models_dir: Path, tmp_path_factory, name: str, **kw) -> Path:
    out = tmp_path_factory.mktemp(name) / "bunny-128"
    make(models_dir / "bunny-128.obj", out, MakeOptions(fold=False, time_limit=20.0, guide=False, **kw))
    return out


@pytest.fixture(scope="module")
def folder(models_dir, tmp_path_factory) -> Path:
    return _make(models_dir, tmp_path_factory, "plain")


@pytest.fixture(scope="module")
def marked(models_dir, tmp_path_factory) -> Path:
    return _make(models_dir, tmp_path_factory, "marks", marks=True)


def _layers(path: Path) -> dict[str, ET.Element]:
    return {g.get("id"): g for g in ET.parse(path).getroot().findall(f"{SVG}g")}


def _numbers(s: str) -> np.ndarray:
    return np.array([float(v) for v in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", s)])


def _svg_paths(path: Path) -> tuple[int, int]:
    """(closed, open) paths of an SVG file, counted with xml.etree: a closed path's data ends in Z."""
    paths = ET.parse(path).getroot().iter(f"{SVG}path")
    ds = [p.get("d").strip() for p in paths]
    assert all(d.count("M") == 1 for d in ds)  # one subpath each: one stroke each
    closed = sum(d.endswith("Z") for d in ds)
    return closed, len(ds) - closed


def _hpgl_strokes(hpgl: str) -> list[np.ndarray]:
    """Pen-down strokes of an HPGL program: each the pen-up point it starts from, then its
    pen-down points, (k, 2) in plotter units."""
    strokes, pos = [], None
    for cmd in hpgl.replace("\n", "").split(";"):
        if cmd[:2] not in ("PU", "PD"):
            continue  # IN, SP (pen select), VS, FS: no coordinates
        nums = _numbers(cmd[2:]).reshape(-1, 2)
        if cmd.startswith("PU") and len(nums):
            pos = nums[-1]
        elif cmd.startswith("PD") and len(nums):
            strokes.append(np.vstack([pos, nums]))
            pos = nums[-1]
    return strokes


def _inkscape_hpgl(svg: Path, out: Path) -> str:
    if shutil.which("inkscape") is None:
        pytest.skip("inkscape is not installed (apt-get install inkscape)")
    # a fresh profile: the HPGL export's defaults (pen 1, 1016 dpi, precut, 0.25 mm tool offset,
    # 1 mm overcut), not whatever a user saved
    env = {**os.environ, "XDG_CONFIG_HOME": str(out.parent / "inkscape-config"), "HOME": str(out.parent)}
    proc = subprocess.run(["inkscape", "--export-type=hpgl", f"--export-filename={out}", str(svg)],
                          capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 0 and out.exists(), proc.stderr
    return out.read_text()


def test_cut_file_plots_one_stroke_per_outline_and_score_line(folder, tmp_path):
    cut = folder / "cut-01.svg"
    layers = _layers(cut)
    assert set(layers) == {"cut", "mountain", "valley"}
    root = ET.parse(cut).getroot()
    assert not list(root.iter(f"{SVG}text"))
    for el in root.iter():
        assert el.get("fill") in (None, "none"), el.attrib
        assert el.get("stroke-dasharray") is None and "display" not in el.attrib and el.get("style") is None
    assert layers["cut"].get("stroke") == "#000000"
    assert layers["mountain"].get("stroke") == "#ff0000" and layers["valley"].get("stroke") == "#0000ff"

    closed, open_ = _svg_paths(cut)
    n_cut = len(layers["cut"].findall(f"{SVG}path"))
    n_score = len(layers["mountain"].findall(f"{SVG}path")) + len(layers["valley"].findall(f"{SVG}path"))
    assert closed >= 1 and n_score > 0 and closed + open_ == n_cut + n_score

    strokes = _hpgl_strokes(_inkscape_hpgl(cut, tmp_path / "cut-01.hpgl"))
    # the export's precut: a short line at the plotter origin to turn the blade, before the drawing
    if len(strokes[0]) == 2 and not strokes[0][0].any():
        strokes = strokes[1:]
    assert len(strokes) == closed + open_
    # a closed outline comes back to where it started (within the tool offset) after going away
    # from it, a score line does not
    back = []
    for s in strokes:
        dist = np.hypot(*(s - s[0]).T) / HPGL_UNITS_PER_MM
        away = int(np.argmax(dist > 2.0))
        back.append(bool(away > 0 and (dist[away:] < 0.6).any()))
    assert sum(back) == closed and len(back) - sum(back) == open_


def test_cut_file_matches_the_print_file(folder):
    """Same geometry in both files: the cut layer's and the score layers' path data are equal."""
    for cut in sorted(folder.glob("cut-*.svg")):
        printed = _layers(folder / cut.name.replace("cut-", "sheet-"))
        for name, layer in _layers(cut).items():
            assert [p.get("d") for p in layer.findall(f"{SVG}path")] == \
                   [p.get("d") for p in printed[name].findall(f"{SVG}path")]
        assert printed["valley"].get("stroke-dasharray")  # the print file keeps its dashes
    assert len(list(folder.glob("cut-*.svg"))) == len(list(folder.glob("sheet-*.svg")))


def _scale_bar(svg: Path) -> tuple[np.ndarray, str]:
    """The scale layer of a print SVG: its (3, 2, 2) segments and its label."""
    layer = _layers(svg)["scale"]
    segs = np.array([_numbers(p.get("d")).reshape(2, 2) for p in layer.findall(f"{SVG}path")])
    (text,) = layer.iter(f"{SVG}text")
    return segs, text.text


def test_scale_bar_in_the_svg(folder):
    for svg in sorted(folder.glob("sheet-*.svg")):
        segs, label = _scale_bar(svg)
        bar = max(segs, key=lambda s: abs(s[1, 0] - s[0, 0]))
        assert label == "50 mm" and abs(bar[1, 0] - bar[0, 0]) == pytest.approx(50.0, abs=1e-4)
        assert bar[0, 1] == bar[1, 1]  # horizontal
        ticks = [s for s in segs if s is not bar and s[0, 0] == s[1, 0]]
        assert sorted(t[0, 0] for t in ticks) == pytest.approx(sorted(bar[:, 0]))
        # in the footer strip: below every piece, inside the page's margins
        sheet = read_sheet(svg)
        assert 297 - 10 - 6 <= segs[..., 1].min() and segs[..., 1].max() <= 297 - 10
        assert 10 <= segs[..., 0].min() and segs[..., 0].max() <= 210 - 10
        pieces = shapely.union_all([shapely.make_valid(Polygon(c)) for c in sheet["cuts"]])
        assert shapely.union_all([LineString(s) for s in segs]).distance(pieces) > 1.0


def _pdf_page_gray(pdf: Path, page: int, tmp_path: Path) -> np.ndarray:
    """Page `page` (1-based) of a PDF rasterised by poppler at PDF_DPI, (H, W) uint8 grey."""
    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm is not installed (apt-get install poppler-utils)")
    stem = tmp_path / f"page{page}"
    subprocess.run(["pdftoppm", "-gray", "-r", str(PDF_DPI), "-f", str(page), "-l", str(page), "-singlefile",
                    str(pdf), str(stem)], check=True, timeout=120)
    data = Path(f"{stem}.pgm").read_bytes()
    m = re.match(rb"P5\s+(\d+)\s+(\d+)\s+(\d+)\s", data)
    w, h = int(m.group(1)), int(m.group(2))
    return np.frombuffer(data[m.end():m.end() + w * h], dtype=np.uint8).reshape(h, w)


def _longest_dark_run(img: np.ndarray) -> tuple[int, int, int]:
    """(length, row, first column) of the longest horizontal run of dark pixels."""
    best = (0, 0, 0)
    for r in np.flatnonzero((img < 128).any(axis=1)):
        dark = np.concatenate([[False], img[r] < 128, [False]])
        edges = np.flatnonzero(np.diff(dark.astype(np.int8)))
        starts, ends = edges[::2], edges[1::2]
        k = int(np.argmax(ends - starts))
        best = max(best, (int(ends[k] - starts[k]), int(r), int(starts[k])))
    return best


def test_scale_bar_in_the_pdf(folder, tmp_path):
    px_per_mm = PDF_DPI / 25.4
    n_pages = len(list(folder.glob("sheet-*.svg")))
    for page in range(1, n_pages + 1):
        img = _pdf_page_gray(folder / "sheets.pdf", page, tmp_path)
        assert img.shape[1] / px_per_mm == pytest.approx(210.0, abs=0.1)
        strip = img[int((297 - 16) * px_per_mm):int((297 - 10) * px_per_mm)]  # the footer strip
        length, row, col = _longest_dark_run(strip)
        # the printed bar: 50 mm (+ up to half a 0.25 mm tick stroke at each end), at its place
        assert length / px_per_mm == pytest.approx(50.0, abs=0.3)
        assert col / px_per_mm == pytest.approx(150.0, abs=0.3)
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext is not installed (apt-get install poppler-utils)")
    html = subprocess.run(["pdftotext", "-bbox", "-f", "1", "-l", "1", str(folder / "sheets.pdf"), "-"],
                          capture_output=True, text=True, check=True, timeout=60).stdout
    words = [(float(a), float(b), float(c), float(d), t) for a, b, c, d, t in re.findall(
        r'<word xMin="([\d.]+)" yMin="([\d.]+)" xMax="([\d.]+)" yMax="([\d.]+)">([^<]*)</word>', html)]
    pt = 72 / 25.4
    at = [i for i in range(len(words) - 1) if words[i][4] == "50" and words[i + 1][4] == "mm"]
    assert len(at) == 1
    x0, y0, x1, y1 = words[at[0]][0], words[at[0]][1], words[at[0] + 1][2], words[at[0] + 1][3]
    assert (x0 + x1) / 2 / pt == pytest.approx(175.0, abs=1.0)  # centred over the bar
    assert 297 - 16 <= y0 / pt < y1 / pt <= 297 - 10 - 2  # in the strip, above the ticks


def test_marks_on_print_pages_not_in_cut_files(marked, folder, tmp_path):
    svgs = sorted(marked.glob("sheet-*.svg"))
    for svg in svgs:
        reg = _layers(svg)["registration"]
        (square,) = [p for p in reg.findall(f"{SVG}path") if p.get("class") == "mark-square"]
        corners = [p for p in reg.findall(f"{SVG}path") if p.get("class") == "mark-corner"]
        sq = _numbers(square.get("d")).reshape(-1, 2)
        assert square.get("fill") == "#000000"
        np.testing.assert_allclose([sq.min(axis=0), sq.max(axis=0)], [[10, 10], [15, 15]])
        ls = sorted(_numbers(c.get("d")).reshape(3, 2)[1].tolist() for c in corners)  # the corner points
        assert ls == [[10.0, 287.0], [200.0, 10.0]]
        assert all(float(c.get("stroke-width")) == 0.5 for c in corners)
        # pieces clear of the three marked corners (30 mm squares; a piece may touch one's side, the
        # margin line), and of the marks themselves
        pieces = shapely.union_all([shapely.make_valid(Polygon(c)) for c in read_sheet(svg)["cuts"]])
        for x0, y0 in ((0, 0), (180, 0), (0, 267)):
            assert not pieces.relate_pattern(shapely.box(x0, y0, x0 + 30, y0 + 30), "T********")  # interiors
    for cut in marked.glob("cut-*.svg"):
        assert set(_layers(cut)) == {"cut", "mountain", "valley"}
    assert "registration" not in _layers(folder / "sheet-01.svg")
    # in the PDF: the square printed solid black at 10..15 mm
    img = _pdf_page_gray(marked / "sheets.pdf", 1, tmp_path)
    px = PDF_DPI / 25.4
    inner = img[int(10.3 * px):int(14.7 * px), int(10.3 * px):int(14.7 * px)]
    around = img[int(5 * px):int(9.5 * px), int(5 * px):int(30 * px)]
    assert inner.max() < 64 and around.min() > 192
    assert math.isclose(_longest_dark_run(img[int(9.5 * px):int(10.5 * px)])[0] / px, 20.0, abs_tol=0.5)  # top-right leg
