"""`polyfold make` (issue 6): the outputs, and an independent check of every sheet.

The sheet checks here read the written SVG files back with their own parser and test them with
shapely: faces (the preview fills) never overlap, glue tabs overlap no face and no other tab, cut
outlines are disjoint (or holes of one another) and everything stays inside the margins. Piece
FOLD files go through the independent net and path checkers."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from conftest import closed_meshes
from fold_checker import check_fold, read_mesh
from path_checker import check_path
from test_cli import one_line, run_cli

from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions, paper_size

NS = {"svg": "http://www.w3.org/2000/svg"}
AREA_EPS = 1e-3  # mm^2; the SVG stores coordinates to 1e-4 mm, so touching shapes may show slivers
REPORT_KEYS = {"polyfold_report", "input", "options", "stages", "pieces", "checks", "outputs", "seconds"}
STAGES = {"load", "inflate", "segment", "unfold", "fold", "layout", "export"}


def _rings(d: str) -> list[np.ndarray]:
    """Closed subpaths of an SVG path made of M / L / Z commands with absolute coordinates."""
    out = []
    for sub in re.findall(r"M([^MZ]*)Z", d):
        nums = [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", sub)]
        out.append(np.array(nums).reshape(-1, 2))
    return out


def read_sheet(path: Path) -> dict:
    root = ET.parse(path).getroot()
    w, h = (float(root.get(k).removesuffix("mm")) for k in ("width", "height"))
    layers = {g.get("id"): g for g in root.findall("svg:g", NS)}
    faces, tabs, cuts, labels = [], [], [], []
    for el in layers["preview"].findall("svg:path", NS):
        (tabs if el.get("class") == "tab" else faces).extend(_rings(el.get("d")))
    for el in layers["cut"].findall("svg:path", NS):
        if "slit" not in (el.get("class") or ""):
            cuts.extend(_rings(el.get("d")))
    for el in layers["labels"].findall("svg:text", NS):
        labels.append((el.get("class"), el.text))
    return {"width": w, "height": h, "faces": faces, "tabs": tabs, "cuts": cuts, "labels": labels,
            "layers": set(layers)}


def check_sheet(sheet: dict, margin: float) -> list[str]:
    """Problems of one sheet (empty = fine), from its SVG content alone."""
    problems = []
    faces = shapely.polygons([f for f in sheet["faces"]])
    tabs = shapely.polygons([t for t in sheet["tabs"]]) if sheet["tabs"] else np.array([], dtype=object)
    shapes = np.concatenate([faces, tabs])
    kind = np.array(["face"] * len(faces) + ["tab"] * len(tabs))
    i, j = shapely.STRtree(shapes).query(shapes, predicate="intersects")
    keep = i < j
    i, j = i[keep], j[keep]
    area = shapely.area(shapely.intersection(shapes[i], shapes[j]))
    for a, b, ar in zip(i, j, area):
        if ar > AREA_EPS:
            problems.append(f"{kind[a]} {a} overlaps {kind[b]} {b} by {ar:.4f} mm^2")
    # cut outlines: disjoint or nested (holes), inside the margins
    cut_polys = [shapely.make_valid(Polygon(c)) for c in sheet["cuts"]]  # (rounded to 1e-4 mm in the file)
    inner = shapely.box(margin, margin, sheet["width"] - margin, sheet["height"] - margin).buffer(1e-3)
    for k, c in enumerate(cut_polys):
        if not inner.contains(c):
            problems.append(f"cut outline {k} crosses the margin")
        for m in range(k + 1, len(cut_polys)):
            d = cut_polys[m]
            if c.intersects(d) and not (c.contains(d) or d.contains(c)):
                if shapely.area(shapely.intersection(c, d)) > AREA_EPS:
                    problems.append(f"cut outlines {k} and {m} overlap")
    # everything printed is inside some cut outline (nothing floats outside a piece)
    union = shapely.union_all(cut_polys).buffer(1e-3)
    for name, group in (("face", faces), ("tab", tabs)):
        for k, g in enumerate(group):
            if not union.contains(g):
                problems.append(f"{name} {k} lies outside every cut outline")
    return problems


def piece_files(fold_path: Path, mesh_path: Path, tmp_path: Path) -> tuple[str, str]:
    """A piece covers some of the mesh's faces: write those faces as their own OBJ (file order
    kept) and the FOLD with faces_meshFace renumbered into it, for the whole-net checker."""
    verts, polys = read_mesh(str(mesh_path))
    fold = json.loads(fold_path.read_text())
    src = sorted(set(fold["polyfold:faces_meshFace"]))
    new = {f: k for k, f in enumerate(src)}
    obj = tmp_path / f"{fold_path.stem}.obj"
    obj.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in verts.tolist())
                   + "".join("f " + " ".join(str(v + 1) for v in polys[f]) + "\n" for f in src))
    fold["polyfold:faces_meshFace"] = [new[f] for f in fold["polyfold:faces_meshFace"]]
    out = tmp_path / fold_path.name
    out.write_text(json.dumps(fold))
    return str(out), str(obj)


def run_make(tmp_path: Path, mesh: Path, **kw) -> tuple[Path, dict]:
    out = tmp_path / mesh.stem
    opts = MakeOptions(**{"time_limit": 20.0, **kw})
    result = make(mesh, out, opts)
    return out, result.report.to_dict()


# ----------------------------------------------------------------------------------------------


def test_paper_sizes():
    assert paper_size("A4") == (210.0, 297.0)
    assert paper_size("12x12in") == pytest.approx((304.8, 304.8))
    assert paper_size("200x300mm") == (200.0, 300.0)
    assert paper_size("8.5x11in") == pytest.approx((215.9, 279.4))
    with pytest.raises(Exception, match="unknown paper"):
        paper_size("b5")


def test_make_bunny_default_cli(models_dir, tmp_path):
    src = models_dir / "bunny-128.obj"
    out = tmp_path / "bunny"
    (out).mkdir()
    (out / "sheet-09.svg").write_text("stale")
    proc = run_cli("make", src, "-o", out)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = json.loads((out / "report.json").read_text())
    assert REPORT_KEYS <= set(report) and STAGES <= set(report["stages"])
    n_pages = report["stages"]["layout"]["pages"]
    pieces = report["pieces"]
    assert set(report["outputs"]) == {p.name for p in out.iterdir()}
    assert not (out / "sheet-09.svg").exists()
    assert not list(out.glob(".polyfold-*"))
    # sheets in every format, one per page
    svgs = sorted(out.glob("sheet-*.svg"))
    assert len(svgs) == n_pages == len(list(out.glob("sheet-*.dxf")))
    pdf = (out / "sheets.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type /Page\b", pdf)) == n_pages
    labels = Counter()
    for svg in svgs:
        sheet = read_sheet(svg)
        assert {"cut", "mountain", "valley", "labels"} <= sheet["layers"]
        assert (sheet["width"], sheet["height"]) == (210.0, 297.0)
        assert check_sheet(sheet, 10.0) == []
        labels.update(text for kind, text in sheet["labels"] if kind == "edge-label")
    # every glue label printed exactly twice; every glue pair of the assembly is labelled
    assembly = json.loads((out / "assembly.json").read_text())
    assert set(labels.values()) == {2}
    assert set(labels) == {g["label"] for g in assembly["glue"]}
    assert sum(g["tab_on"] is None for g in assembly["glue"]) == len(report["stages"]["layout"]["untabbed_edges"])
    # every piece: a verified net and a verified folding path, checked independently
    assert report["checks"]["paths_verified"] == len(pieces)
    for row in pieces:
        fold = out / row["fold_file"]
        net = check_fold(*piece_files(fold, src, tmp_path))
        assert net.ok and net.pieces == 1, f"{row['piece']}:\n{net}"
        path = check_path(fold)
        assert path.ok, f"{row['piece']}:\n{path}"
    assert sum(r["faces"] for r in pieces) == 128
    html = (out / "instructions.html").read_text()
    assert all(f"<b>{r['piece']}</b>" in html for r in pieces) and "data:image/png;base64," in html
    assert all(f"src='{s.name}'" in html for s in svgs)


@pytest.mark.parametrize("path", closed_meshes(), ids=lambda p: p.stem)
def test_every_closed_mesh_makes_clean_sheets(path, tmp_path):
    # folding is tested above and in test_fold; here every sheet of every model is checked
    out, report = run_make(tmp_path, path, fold=False, size=120.0)
    assert report["checks"]["problems"] == []
    glue = Counter()
    for svg in sorted(out.glob("sheet-*.svg")):
        sheet = read_sheet(svg)
        assert check_sheet(sheet, 10.0) == [], svg.name
        glue.update(text for kind, text in sheet["labels"] if kind == "edge-label")
    assert set(glue.values()) <= {2}
    assert sum(r["faces"] for r in report["pieces"]) == report["input"]["faces"]


def test_parts_are_glued_across(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "horse-302.obj", parts=7, fold=True, size=200.0, paper="a3")
    assert report["stages"]["segment"]["parts"] == 7
    assert len(list(out.glob("part-*.obj"))) == 7
    assembly = json.loads((out / "assembly.json").read_text())
    between = [g for g in assembly["glue"] if g["between_parts"]]
    assert between and all(len(set(g["pieces"])) == 2 for g in between)
    assert report["checks"]["paths_verified"] == len(report["pieces"])
    html = (out / "instructions.html").read_text()
    assert "Joining the parts" in html and html.count("<h2>Part ") == 7


def test_unsegmented_bunny_is_one_piece_on_large_paper(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "bunny-128.obj", segment="none", paper="600x600mm", fold=False)
    assert len(report["pieces"]) == 1 and report["stages"]["layout"]["splits_for_page"] == 0


def test_no_tabs(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "cube-12.obj", tabs=False, fold=False, size=60.0)
    assert report["stages"]["layout"]["tabs"] == 0
    for svg in out.glob("sheet-*.svg"):
        assert read_sheet(svg)["tabs"] == []


def test_too_large_and_bad_options(models_dir, tmp_path):
    out = tmp_path / "t"
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--size", 150)
    assert proc.returncode == 2
    line = one_line(proc.stderr.strip().splitlines()[-1] + "\n")
    assert "largest size that fits is 144.4 mm" in line
    assert not out.exists() or not any(out.iterdir())
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--paper", "b5", "-q")
    assert proc.returncode == 2 and "unknown paper" in one_line(proc.stderr)
    proc = run_cli("make", models_dir / "tetrahedron-4.obj", "-o", out, "--tau", 0.1, "--parts", 2, "-q")
    assert proc.returncode == 2 and "--tau or --parts" in one_line(proc.stderr)


def test_sheet_checker_sees_overlaps(models_dir, tmp_path):
    out, _ = run_make(tmp_path, models_dir / "cube-12.obj", fold=False, size=60.0)
    sheet = read_sheet(sorted(out.glob("sheet-*.svg"))[0])
    assert check_sheet(sheet, 10.0) == []
    moved = dict(sheet, faces=sheet["faces"] + [sheet["faces"][0] + 0.5])  # a face slid over another
    assert any("overlaps" in p for p in check_sheet(moved, 10.0))
    tab_on_face = dict(sheet, tabs=sheet["tabs"] + [sheet["faces"][1][[0, 1, 2, 0]] * 1.0])
    assert any("tab" in p and "face" in p for p in check_sheet(tab_on_face, 10.0))
    off = dict(sheet, cuts=sheet["cuts"] + [np.array([[1.0, 1.0], [5.0, 1.0], [5.0, 5.0]])])
    assert any("margin" in p for p in check_sheet(off, 10.0))
