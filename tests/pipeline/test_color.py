"""make prints the model's look: Spot's texture on its pieces, read back from the printed PDF
through the FOLD files (independent of the painter), the simplified Spot textured too, and the
--color modes."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from polyfold.errors import PolyfoldError
from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

DPI = 100  # the PDF is rendered at this to read the printed colours back


@pytest.fixture(scope="module")
def spot(models_dir):
    return models_dir / "textured" / "spot"


@pytest.fixture(scope="module")
def control(spot, tmp_path_factory):
    out = tmp_path_factory.mktemp("spot-control")
    return make(spot / "spot_control_mesh.obj", out, MakeOptions(fold=False, guide=False)), out


def printed_triangles(out, loaded):
    """Every printed face (page, its 3 corners in page mm, its UVs (3, 2)) from the FOLD files: the
    pattern's corners are matched to the mesh face's corners by the folded form (the model in mm)."""
    look, mesh = loaded.appearance, loaded.mesh
    for fold_file in sorted(out.glob("piece-*.fold")):
        doc = json.loads(fold_file.read_text())
        xy = np.array(doc["vertices_coords"]) * [1, -1]  # FOLD mm (y up) -> page mm (y down)
        folded = np.array(doc["file_frames"][0]["vertices_coords"]) / doc["polyfold:mmPerModelUnit"]
        for corners, f in zip(doc["faces_vertices"], doc["polyfold:faces_wholeMeshFace"]):
            model = mesh.vertices[mesh.faces[f]]
            k = [int(np.argmin(np.linalg.norm(model - folded[c], axis=1))) for c in corners]
            assert sorted(k) == [0, 1, 2]
            yield doc["polyfold:page"], xy[corners], look.uv[f, k]


def test_spot_prints_its_texture_on_every_face(control, spot, tmp_path):
    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm is not installed (apt-get install poppler-utils)")
    result, out = control
    color = result.report.stages.color
    assert (color.source, color.printed, color.faces_textured) == ("texture", "texture", 372)
    assert color.pictures == sum(1 for r in result.report.pieces if r.faces)
    loaded = load_mesh(spot / "spot_control_mesh.obj")
    texture = loaded.appearance.images[0].astype(int)
    subprocess.run(["pdftoppm", "-png", "-r", str(DPI), str(out / "sheets.pdf"), str(tmp_path / "p")], check=True)
    pages = {int(p.stem.split("-")[-1]): np.asarray(Image.open(p).convert("RGB"), dtype=int)
             for p in tmp_path.glob("p-*.png")}
    inner = np.array([[1, 1, 1], [2, 1, 1], [1, 2, 1], [1, 1, 2]], float)
    inner /= inner.sum(axis=1, keepdims=True)
    errors = []
    for page, xy, uv in printed_triangles(out, loaded):
        pts, at = inner @ xy, inner @ uv
        px = pages[page][(pts[:, 1] / 25.4 * DPI).astype(int), (pts[:, 0] / 25.4 * DPI).astype(int)]
        h, w = texture.shape[:2]
        want = texture[np.clip(((1 - at[:, 1]) % 1 * h).astype(int), 0, h - 1),
                       np.clip((at[:, 0] % 1 * w).astype(int), 0, w - 1)]
        errors += list(np.abs(px - want).max(axis=1))
    errors = np.array(errors)
    assert len(errors) == 4 * 372
    # labels, halos and crease lines print over some points, and the texture's patch edges are
    # sharp: nearly all points match closely, none of the faces is printed from the wrong place
    assert np.median(errors) <= 6 and (errors <= 40).mean() >= 0.9, (np.median(errors), (errors <= 40).mean())


def test_the_sheets_embed_one_picture_per_piece(control):
    from pypdf import PdfReader

    result, out = control
    reader = PdfReader(out / "sheets.pdf")
    on_page = [sum(1 for r in result.report.pieces if r.page == k + 1 and r.faces) for k in range(len(reader.pages))]
    assert [len(p.images) for p in reader.pages] == on_page
    svg = (out / "sheet-01.svg").read_text()
    assert svg.count("<image ") == on_page[0] and "clipPath" in svg
    assert "<image" not in (out / "cut-01.svg").read_text()
    assert (out / "model.glb").exists() and "model.glb" in result.files


def test_the_fine_spot_is_simplified_with_its_texture(spot, tmp_path):
    result = make(spot / "spot_triangulated.obj", tmp_path, MakeOptions(fold=False, guide=False))
    report = result.report
    simp, color = report.stages.simplify, report.stages.color
    assert simp.faces_before == 5856 and simp.faces_after < 1000  # --faces auto
    assert color.printed == "texture" and color.faces_textured == simp.faces_after
    assert report.stages.export.pdf_bytes < 20e6
    assert report.stages.layout.smallest_face_mm > 0.5


def test_flat_and_none(spot, tmp_path):
    flat = make(spot / "spot_control_mesh.obj", tmp_path / "flat", MakeOptions(fold=False, color="flat", guide=False))
    assert flat.report.stages.color.printed == "flat" and flat.report.stages.color.pictures == 0
    assert "<image" not in (tmp_path / "flat" / "sheet-01.svg").read_text()
    none = make(spot / "spot_control_mesh.obj", tmp_path / "none", MakeOptions(fold=False, color="none", guide=False))
    assert none.report.stages.color.printed == "none"
    assert not (tmp_path / "none" / "model.glb").exists()
    assert b"/DCTDecode" not in (tmp_path / "none" / "sheets.pdf").read_bytes()


@pytest.mark.parametrize("opts, words", [(MakeOptions(color="photo"), "--color must be one of"),
                                         (MakeOptions(dpi=5000), "--dpi must be between")])
def test_bad_color_options_are_one_line(spot, tmp_path, opts, words):
    with pytest.raises(PolyfoldError, match=words):
        make(spot / "spot_control_mesh.obj", tmp_path, opts)
