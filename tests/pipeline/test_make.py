"""pipeline/make.py (`make`, issue 6): every closed model makes clean sheets, parts glued across,
options (segment, paper, tabs), a mesh in memory as well as a file, and the sheet checker itself.

The sheet checks (conftest.read_sheet / check_sheet) read the written SVG files back with their own
parser and test them with shapely: faces (the preview fills) never overlap, glue tabs overlap no
face and no other tab, cut outlines are disjoint (or holes of one another) and everything stays
inside the margins. (`polyfold make` itself, with the piece FOLD files through the independent net
and path checkers: apps/cli/test_make_commands.py.)"""

from __future__ import annotations

import json
import os
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from conftest import check_sheet, closed_meshes, guide_problems, read_sheet
from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions


def run_make(tmp_path: Path, mesh: Path, **kw) -> tuple[Path, dict]:
    out = tmp_path / mesh.stem
    opts = MakeOptions(**{"time_limit": 20.0, **kw})
    result = make(mesh, out, opts)
    return out, result.report.to_dict()


@pytest.mark.parametrize("path", closed_meshes(), ids=lambda p: p.stem)
def test_every_closed_mesh_makes_clean_sheets(path, tmp_path):
    # folding is tested in apps/cli/test_make_commands.py and fold/; here every sheet of every model is checked
    out, report = run_make(tmp_path, path, fold=False, size=120.0)
    assert report["checks"]["problems"] == []
    glue = Counter()
    for svg in sorted(out.glob("sheet-*.svg")):
        sheet = read_sheet(svg)
        assert check_sheet(sheet, 10.0) == [], svg.name
        glue.update(text for kind, text in sheet["labels"] if kind == "edge-label")
    strips = {label for label, why in report["stages"]["layout"]["reduced_tabs"] if why == "glue strip"}
    assert report["stages"]["layout"]["untabbed_edges"] == []
    assert {label: n for label, n in glue.items() if n != 2} == {label: 4 for label in strips}  # both sides (+ a strip)
    assert sum(r["faces"] for r in report["pieces"]) == report["input"]["faces"]
    assert guide_problems(json.loads((out / "assembly.json").read_text())) == []  # the guide's steps (issue 22)


def test_parts_are_glued_across(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "horse-302.obj", parts=7, fold=True, size=200.0, paper="a3")
    assert report["stages"]["segment"]["parts"] == 7
    assert len(list(out.glob("part-*.obj"))) == 7
    assembly = json.loads((out / "assembly.json").read_text())
    between = [g for g in assembly["glue"] if g["between_parts"]]
    assert between and all(len(set(g["pieces"])) == 2 for g in between)
    assert report["checks"]["paths_verified"] == len(report["pieces"])
    html = (out / "instructions.html").read_text()
    seams = html[html.index("id='seams'"):]
    assert "Joining the parts" in seams and seams.count("<h3>Part ") == 7


def test_unsegmented_bunny_is_one_piece_on_large_paper(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "bunny-128.obj", segment="none", paper="600x600mm", fold=False)
    assert len(report["pieces"]) == 1 and report["stages"]["layout"]["splits_for_page"] == 0


@pytest.mark.parametrize("paper, n_pieces", [("a4", 6), ("800x800mm", 1)])
def test_cube_squares_stay_whole(models_dir, tmp_path, paper, n_pieces):
    # issue 18: 6 square pieces at A4 / 150 mm (not 9: no square is cut along its diagonal), one
    # piece of 6 squares on paper large enough; each square's diagonal is a flat crease of its piece
    mesh = load_mesh(models_dir / "cube-12.obj").components[0]
    out, report = run_make(tmp_path, models_dir / "cube-12.obj", paper=paper)
    assert len(report["pieces"]) == n_pieces and report["checks"]["paths_verified"] == n_pieces
    square = {}  # input face -> its square (the direction of its outward normal)
    for f in range(mesh.n_faces):
        square[int(mesh.face_source[f])] = tuple(np.round(mesh.face_normals[f]).astype(int))
    seen = []
    for row in report["pieces"]:
        fold = json.loads((out / row["fold_file"]).read_text())
        faces = fold["polyfold:faces_meshFace"]
        kind = {frozenset(e): a for e, a in zip(fold["edges_vertices"], fold["edges_assignment"])}
        by_square = {}
        for k, f in enumerate(faces):
            by_square.setdefault(square[f], []).append(set(fold["faces_vertices"][k]))
        assert len(faces) == 2 * len(by_square) == 12 // n_pieces
        assert all(kind[frozenset(a & b)] == "F" for a, b in by_square.values())
        seen += list(by_square)
    assert sorted(seen) == sorted(set(square.values()))


def test_no_tabs(models_dir, tmp_path):
    out, report = run_make(tmp_path, models_dir / "cube-12.obj", tabs=False, fold=False, size=60.0)
    assert report["stages"]["layout"]["tabs"] == 0
    for svg in out.glob("sheet-*.svg"):
        assert read_sheet(svg)["tabs"] == []


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


# ----------------------------------------------------------------------------------------------
# make takes a mesh in memory as well as a file: same sheets, no temporary file


def test_mesh_in_memory_makes_the_same_folder(models_dir, tmp_path):
    opts = MakeOptions(time_limit=30)
    from_file = make(models_dir / "bunny-128.obj", tmp_path / "file", opts)
    loaded = load_mesh(models_dir / "bunny-128.obj")
    from_mesh = make(loaded.mesh, tmp_path / "mesh", opts, name="bunny-128.obj")
    from_loaded = make(loaded, tmp_path / "loaded", opts)
    assert from_file.files == from_mesh.files == from_loaded.files
    for name in from_file.files:
        if name in ("report.json", "sheets.pdf") or name.endswith(".dxf"):
            continue  # timings; the PDF and DXF carry no timing but are compared via their pages below
        a = (tmp_path / "file" / name).read_bytes()
        assert a == (tmp_path / "mesh" / name).read_bytes() == (tmp_path / "loaded" / name).read_bytes(), name
    assert from_mesh.report.input.file == "bunny-128.obj" and from_mesh.report.input.components == 1
    # nothing staged left: beside the outputs only the manifest of what make wrote and its lock file
    assert sorted(p.name for p in (tmp_path / "mesh").iterdir() if p.name.startswith(".")) == [
        ".polyfold-manifest.json", ".polyfold.lock"]


@pytest.mark.parametrize("with_writer", [True, False])
def test_a_failed_sheet_check_writes_nothing(models_dir, tmp_path, monkeypatch, with_writer):
    """The sheet check runs in the writer process beside the export's start (or here, before it);
    either way a failed check stops make before any file is written, the folder not even made."""
    import polyfold.pipeline.make as make_module
    from polyfold.errors import PolyfoldError

    real = make_module.check_pages

    def failing(*args):
        counts = real(*args)
        return {**counts, "page_overlaps": 1, "problems": ["page 1: pieces A and B overlap or touch"]}

    monkeypatch.setattr(make_module, "check_pages", failing)
    if not with_writer:
        monkeypatch.setattr(make_module, "_writer_process", lambda: None)
    out = tmp_path / "out"
    with pytest.raises(PolyfoldError, match="sheet check failed, nothing written: page 1: pieces A and B overlap"):
        make(models_dir / "bunny-128.obj", out, MakeOptions(fold=False, time_limit=30))
    assert not out.exists()


def test_the_writer_process_writes_what_this_one_would(models_dir, tmp_path, monkeypatch):
    """The sheets' files and guide.pdf made in make's writer process (`processes.Standby`, where
    it can fork), or the sheets' there and guide.pdf in a process forked when the guide is ready
    (the writer still busy), are byte for byte those made without it (forked at the export, or
    here)."""
    import polyfold.pipeline.make as make_module
    from polyfold.processes import Standby, can_fork, usable_cores

    opts = MakeOptions(time_limit=30)
    with_writer = make(models_dir / "bunny-128.obj", tmp_path / "writer", opts)
    with monkeypatch.context() as busy:
        busy.setattr(Standby, "answered", lambda self, ticket: False)
        writer_busy = make(models_dir / "bunny-128.obj", tmp_path / "busy", opts)
    monkeypatch.setattr(make_module, "_writer_process", lambda: None)
    without = make(models_dir / "bunny-128.obj", tmp_path / "plain", opts)
    assert with_writer.files == writer_busy.files == without.files and "guide.pdf" in without.files
    for name in without.files:
        if name != "report.json":  # (timings)
            plain = (tmp_path / "plain" / name).read_bytes()
            assert (tmp_path / "writer" / name).read_bytes() == plain == (tmp_path / "busy" / name).read_bytes(), name
    if usable_cores() >= 2 and can_fork():
        assert make_module._writer_process() is None  # (patched) and the real one forks:
        monkeypatch.undo()
        writer = make_module._writer_process()
        try:
            assert writer is not None and writer.result(writer.submit(os.getpid)) != os.getpid()
        finally:
            writer.close()


def test_unnamed_mesh_is_called_model(models_dir, tmp_path):
    mesh = load_mesh(models_dir / "octahedron-8.obj").mesh
    result = make(mesh, tmp_path, MakeOptions(time_limit=20))
    assert result.report.input.file == "model"
    assert "model - sheet 1/" in (tmp_path / "sheet-01.svg").read_text()


def test_a_fine_mesh_is_simplified_first_by_default(tmp_path):
    # issue 21: --faces auto (the default) takes a 20,480-face sphere to faces about 12 mm across at
    # --size (60 mm: ~180 faces), says so in the report, and makes clean sheets of that
    import trimesh

    from polyfold.pipeline.report import MakeReport

    sphere = trimesh.creation.icosphere(subdivisions=5)
    sphere.vertices *= 1.0 + 0.01 * np.random.default_rng(1).standard_normal((len(sphere.vertices), 1))
    src = tmp_path / "fine.obj"
    sphere.export(src)
    out, report = run_make(tmp_path, src, size=60.0, fold=False)
    simp = report["stages"]["simplify"]
    assert simp["spec"] == "auto" and simp["faces_before"] == 20480 and 150 <= simp["faces_after"] <= 210
    assert 0.0 < simp["hausdorff"] < 0.05 and simp["min_angle_deg"] > 0.0
    assert report["input"]["faces"] == 20480 and report["checks"]["problems"] == []
    assert sum(p["faces"] for p in report["pieces"]) == simp["faces_after"]
    assert MakeReport.from_dict(report).stages.simplify.faces_after == simp["faces_after"]
    for svg in sorted(out.glob("sheet-*.svg")):
        assert check_sheet(read_sheet(svg), 10.0) == [], svg.name
