"""pipeline/approximate.py, `make --approximate hulls` (issue 24): the model built from convex
polyhedra, one per part, none overlapping, each one net with a folding path, errors reported.

What make writes is read back and checked with code of the test's own: the parts' OBJ files for
closedness, convexity and overlaps (manifold3d's booleans, not the LP make runs), the folding
paths of the FOLD files by tests/path_checker.py, the sheets by the SVG reader, and the glued
faces from the part files' geometry."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from conftest import assert_valid_component, check_sheet, guide_problems, read_sheet, signed_volume
from path_checker import check_path
from polyfold.approximate.error import overlap_volumes
from polyfold.errors import PolyfoldError
from polyfold.formats.meshes import load_mesh, read_mesh_as_is
from polyfold.pipeline.approximate import contact_areas, joined
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.report import MakeReport


@pytest.fixture(scope="module")
def hull_folders(models_dir: Path, tmp_path_factory) -> dict[str, tuple[Path, dict]]:
    out = {}
    for name in ("bunny-128", "horse-302"):
        folder = tmp_path_factory.mktemp("hulls") / name
        rep = make(models_dir / f"{name}.obj", folder, MakeOptions(approximate="hulls", time_limit=60.0)).report
        out[name] = (folder, rep.to_dict())
    return out


@pytest.mark.parametrize("name", ["bunny-128", "horse-302"])
def test_every_part_is_a_convex_polyhedron_apart_from_the_others(hull_folders, models_dir, name):
    folder, report = hull_folders[name]
    approx = report["stages"]["approximate"]
    original = read_mesh_as_is(folder / "original.obj")
    model = load_mesh(models_dir / f"{name}.obj").mesh
    np.testing.assert_allclose(original.vertices[original.faces], model.vertices[model.faces], atol=1e-6)
    parts = [read_mesh_as_is(folder / f"part-{k}.obj") for k in range(approx["parts"])]
    assert report["stages"]["segment"]["parts"] == approx["parts"] == len(parts) > 1
    diag = model.bbox_diagonal
    for k, part in enumerate(parts):
        assert_valid_component(part)
        assert not part.topology.boundary.any(), f"part {k} is open"
        tri = part.vertices[part.faces]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        outside = ((part.vertices[None] - tri[:, None, 0]) @ n[:, :, None]).max()
        assert outside <= 1e-6 * diag, f"part {k} is not convex"  # (OBJ files round to 6 decimals)
    vol = overlap_volumes(parts)
    np.fill_diagonal(vol, 0.0)
    assert vol.max() <= 1e-9 * signed_volume(model), "two parts overlap (manifold3d)"
    assert approx["overlapping_pairs"] == 0 and approx["clip_planes"] >= 1
    assert 0.0 < approx["hausdorff_max"] < 0.3 and 0.8 < approx["volume_ratio"] < 1.5
    assert approx["hausdorff_max"] == pytest.approx(max(max(approx["hausdorff_out"]), max(approx["hausdorff_in"])),
                                                    abs=1e-6)
    assert sum(approx["faces_after"]) == sum(p.n_faces for p in parts) == sum(r["faces"] for r in report["pieces"])


@pytest.mark.parametrize("name", ["bunny-128", "horse-302"])
def test_every_part_unfolds_whole_folds_and_glues(hull_folders, name):
    folder, report = hull_folders[name]
    assert [n["pieces"] for n in report["stages"]["unfold"]["nets"]] == [1] * report["stages"]["approximate"]["parts"]
    assert report["checks"]["problems"] == [] and report["checks"]["paths_verified"] == len(report["pieces"])
    for row in report["pieces"]:
        if row["faces"] == 1:
            continue  # a lone face (cut off to fill the pages) has nothing to fold
        path = check_path(folder / row["fold_file"])
        assert path.ok, f"{row['piece']}:\n{path}"
    for svg in sorted(folder.glob("sheet-*.svg")):
        assert check_sheet(read_sheet(svg), 10.0) == [], svg.name
    assert report["stages"]["layout"]["smallest_edge_mm"] >= 2.0  # no edge a builder cannot fold
    assert guide_problems(json.loads((folder / "assembly.json").read_text())) == []
    # where two parts touch, the guide says to glue them, by the pieces they are made of
    contacts = report["stages"]["approximate"]["contacts"]
    assert contacts and all(area > 0 for _, _, area in contacts)
    intro = (folder / "instructions.html").read_text()
    i, j, _ = contacts[0]
    assert f"Glue part {i + 1} (piece" in intro and f"to part {j + 1} (piece" in intro
    # every glued side is marked with the piece it goes onto, both ways (but those too small)
    notes = {}
    for svg in folder.glob("sheet-*.svg"):
        for kind, text in read_sheet(svg)["labels"]:
            note = re.fullmatch(r"(?:glue )?to ([A-Z]+)", text or "")  # ("to X" where the long one has no room)
            if note:
                notes[note.group(1)] = notes.get(note.group(1), 0) + 1
    part_of = {row["piece"]: row["part"] for row in report["pieces"]}
    assert notes and all(name in part_of for name in notes)
    assert sum(notes.values()) == 2 * len(contacts) - report["stages"]["approximate"]["unmarked_sides"]
    scale = report["stages"]["layout"]["scale_mm_per_unit"]
    big = sum(area * scale ** 2 >= 100.0 for _, _, area in contacts)  # 1 cm2 or more on paper
    assert big >= 1 and sum(notes.values()) >= 2 * big


def test_glued_faces_are_measured_from_the_part_files(hull_folders, models_dir):
    """The contacts of the report are where the parts' files have faces on one plane, facing each
    other: the same pairs, about the same areas (the files round to 6 decimals)."""
    folder, report = hull_folders["horse-302"]
    parts = [read_mesh_as_is(folder / f"part-{k}.obj") for k in range(report["stages"]["approximate"]["parts"])]
    diag = load_mesh(models_dir / "horse-302.obj").mesh.bbox_diagonal
    # the files' faces regrouped into flat sides (face_source is lost in OBJ): one side per plane
    sides = []
    for part in parts:
        n = part.face_normals
        key = np.round(np.c_[n, np.einsum("ij,ij->i", n, part.vertices[part.faces[:, 0]]) / diag], 4)
        _, src = np.unique(key, axis=0, return_inverse=True)
        sides.append(type(part)(part.vertices, part.faces, src.reshape(-1)))
    found = {(i, j): a for i, j, a in contact_areas(sides, diag * 1e3)}
    reported = {(i, j): a for i, j, a in report["stages"]["approximate"]["contacts"]}
    assert set(found) == set(reported)
    for key, area in reported.items():
        assert found[key] == pytest.approx(area, rel=1e-3)


def test_report_round_trips_and_cli_says_it(hull_folders, models_dir, tmp_path):
    folder, report = hull_folders["bunny-128"]
    again = MakeReport.from_dict(json.loads((folder / "report.json").read_text()))
    assert again.to_dict() == report and again.options.approximate == "hulls"
    from conftest import run_cli

    proc = run_cli("make", str(models_dir / "bunny-128.obj"), "-o", str(tmp_path / "cli"), "--approximate", "hulls")
    assert proc.returncode == 0, proc.stderr
    assert "convex approximation: 5 polyhedra" in proc.stderr and "none overlapping (independent check)" in proc.stderr
    bad = run_cli("make", str(models_dir / "bunny-128.obj"), "-o", str(tmp_path / "bad"), "--approximate", "boxes")
    assert bad.returncode != 0 and "--approximate must be none or hulls" in bad.stderr
    assert "Traceback" not in bad.stderr and not (tmp_path / "bad").exists()


def test_joined_keeps_the_parts_apart():
    from polyfold.mesh.mesh import Mesh

    a = Mesh(np.eye(3), np.array([[0, 1, 2]]), np.array([4]))
    b = Mesh(np.eye(3) + 5, np.array([[0, 2, 1]]), np.array([0]))
    j = joined([a, b])
    assert j.faces.tolist() == [[0, 1, 2], [3, 5, 4]] and j.face_source.tolist() == [4, 5]
    with pytest.raises(PolyfoldError, match="--approximate"):
        from polyfold.pipeline.options import check_options

        check_options(MakeOptions(approximate="spheres"))


def test_a_star_of_needle_points_folds(models_dir, tmp_path):
    """star-24's convex parts had sides coming to a 4-degree point: the sides beside it met only
    at the point and came within the 0.2 mm paper's thickness along it, so two pieces found no
    folding path. Needle points go (`hulls._without_needles`): every piece folds."""
    rep = make(models_dir / "star-24.obj", tmp_path / "star", MakeOptions(approximate="hulls", time_limit=60.0)).report
    assert rep.checks.paths_verified == len(rep.pieces) and all(p.path_verified for p in rep.pieces)
    for row in rep.pieces:
        if row.faces > 1:
            assert check_path(tmp_path / "star" / row.fold_file).ok


def test_every_flat_side_is_one_polygon_of_its_net(hull_folders):
    """A side of a convex part (several triangles in one plane) is never cut through in its net:
    it is one polygon on paper, scored nowhere inside (issue 11's flat regions)."""
    from conftest import assert_flat_regions_whole
    from polyfold.mesh.geometry import merged_edges
    from polyfold.unfold.search import unfold

    folder, report = hull_folders["horse-302"]
    polygons = 0
    for k in range(report["stages"]["approximate"]["parts"]):
        part = read_mesh_as_is(folder / f"part-{k}.obj")
        net, _ = unfold(part, seed=1, time_limit=10.0, max_pieces=1)
        assert_flat_regions_whole(net)
        polygons += int(merged_edges(part).sum())
    assert polygons > 0  # (sides of more than one triangle exist: the check had work to do)
