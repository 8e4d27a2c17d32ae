"""The assembly guide (issue 22), read back from make folders as a person gets them: every piece
and every glue label in exactly one step, each step gluing only to pieces already in the model,
pictures that show something and change from step to step, guide.pdf with every step, and
--no-guide. On bunny-128 (one part, 12 pieces), horse-302 (long pieces, glue strips), bunny-128
in 3 parts (join steps) and a random convex hull (not a shared model)."""

from __future__ import annotations

import base64
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import guide_problems
from polyfold.mesh.mesh import Mesh
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions


def _hull(n_points: int, seed: int) -> Mesh:
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n_points, 3)) * np.array([1.0, 0.7, 0.5])
    hull = ConvexHull(pts)
    faces = hull.simplices.copy()
    # outward corner order
    c = pts.mean(axis=0)
    n = np.cross(pts[faces[:, 1]] - pts[faces[:, 0]], pts[faces[:, 2]] - pts[faces[:, 0]])
    flip = np.einsum("ij,ij->i", n, pts[faces[:, 0]] - c) < 0
    faces[flip] = faces[flip][:, ::-1]
    used, inverse = np.unique(faces, return_inverse=True)
    return Mesh(pts[used], inverse.reshape(-1, 3))


CASES = {
    "bunny": ("bunny-128.obj", MakeOptions(time_limit=60)),
    "horse": ("horse-302.obj", MakeOptions(time_limit=60)),
    "bunny-parts": ("bunny-128.obj", MakeOptions(parts=3, time_limit=60)),
    "hull": (None, MakeOptions(time_limit=60, size=120)),
    # an open surface (its boundary edges are stored as their faces run them): the guide looked
    # its seams up by sorted vertex pairs in that order and stopped make with a KeyError
    "open-bunny": ("bad/bunny-128-holes.obj", MakeOptions(time_limit=60)),
}


@pytest.fixture(scope="module")
def folders(models_dir: Path, tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("guide")
    out = {}
    for name, (model, opts) in CASES.items():
        src = models_dir / model if model else _hull(90, 7)
        make(src, root / name, opts, name=None if model else "hull-90")
        out[name] = root / name
    return out


def _read(folder: Path) -> tuple[dict, dict]:
    return (json.loads((folder / "assembly.json").read_text()), json.loads((folder / "report.json").read_text()))


def _step_pictures(folder: Path) -> list[np.ndarray]:
    """The picture of every build step in instructions.html (embedded PNGs, in step order)."""
    html = (folder / "instructions.html").read_text()
    out = []
    for section in re.findall(r"<section class='step' id='step-\d+'>(.*?)</section>", html, re.S):
        b64 = re.search(r"<figure class='pic'><img src='data:image/png;base64,([^']+)'", section).group(1)
        out.append(np.asarray(Image.open(io.BytesIO(base64.b64decode(b64))).convert("RGB")))
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_every_piece_and_label_in_exactly_one_step(folders: dict[str, Path], case: str) -> None:
    asm, rep = _read(folders[case])
    assert asm["steps"] and guide_problems(asm) == []
    assert rep["stages"]["guide"]["steps"] == len(asm["steps"])
    if case == "horse":
        assert any(s["strips"] for s in asm["steps"]), "horse-302 has glue strips: each must be used in a step"
    if case == "bunny-parts":
        assert any(s["kind"] == "join" for s in asm["steps"])


@pytest.mark.parametrize("case", list(CASES))
def test_every_piece_after_the_first_is_glued_to_what_is_built(folders: dict[str, Path], case: str) -> None:
    """In its own step or the "more seams" steps right after it; each sheet named is the piece's."""
    asm, _ = _read(folders[case])
    part_of = {p["piece"]: p["part"] for p in asm["pieces"]}
    page_of = {p["piece"]: p["page"] for p in asm["pieces"]}
    placed: list[str] = []
    steps = asm["steps"]
    for i, s in enumerate(steps):
        if s["piece"] is None:
            continue
        assert s["sheets"][0] == page_of[s["piece"]]
        if any(part_of[q] == part_of[s["piece"]] for q in placed):
            more = next((j for j, t in enumerate(steps[i + 1:]) if t["kind"] != "glue"), len(steps) - i - 1)
            run = [s, *steps[i + 1:i + 1 + more]]
            assert any(t["attach_to"] for t in run), f"piece {s['piece']} is glued to nothing built"
        placed.append(s["piece"])


@pytest.mark.parametrize("case", ["bunny", "horse", "bunny-parts"])
def test_the_pictures_show_the_steps(folders: dict[str, Path], case: str) -> None:
    asm, _ = _read(folders[case])
    pics = _step_pictures(folders[case])
    assert len(pics) == len(asm["steps"])
    for k, img in enumerate(pics):
        drawn = (img.astype(int).sum(axis=2) < 3 * 245).mean()
        assert drawn > 0.05, f"step {k + 1}'s picture is nearly blank ({drawn:.1%} drawn)"
        colourful = (img.max(axis=2).astype(int) - img.min(axis=2) > 60).mean()
        assert colourful > 0.002, f"step {k + 1}'s picture has no piece in colour"  # (a one-face piece: ~1 %)
    for k in range(1, len(pics)):
        changed = (np.abs(pics[k].astype(int) - pics[k - 1]).max(axis=2) > 30).mean()
        assert changed > 0.005, f"steps {k} and {k + 1} look the same ({changed:.2%} differs)"


def test_the_overview_names_every_piece(folders: dict[str, Path]) -> None:
    html = (folders["bunny"] / "instructions.html").read_text()
    where = html[html.index("id='where'"):html.index("id='steps'")]
    assert len(re.findall(r"data:image/png;base64", where)) == 6  # six sides
    for side in ("front", "back", "left", "right", "top", "bottom"):
        assert f"the model from the {side}" in where


def test_parts_get_their_own_pictures(folders: dict[str, Path]) -> None:
    html = (folders["bunny-parts"] / "instructions.html").read_text()
    where = html[html.index("id='where'"):html.index("id='steps'")]
    asm, _ = _read(folders["bunny-parts"])
    assert len(re.findall(r"data:image/png;base64", where)) == 6 * (1 + len(asm["parts"]))


@pytest.mark.parametrize("case", ["bunny", "horse"])
def test_guide_pdf_has_every_step(folders: dict[str, Path], case: str) -> None:
    from pypdf import PdfReader

    _, rep = _read(folders[case])
    reader = PdfReader(folders[case] / "guide.pdf")
    assert len(reader.pages) == rep["stages"]["guide"]["pdf_pages"]
    w, h = (float(x) for x in reader.pages[0].mediabox.upper_right)
    assert abs(w - 595.3) < 1 and abs(h - 841.9) < 1  # A4, as --paper
    text = "\n".join(p.extract_text() for p in reader.pages)
    for k in range(1, rep["stages"]["guide"]["steps"] + 1):
        assert f"Step {k}:" in text
    assert "Where each piece goes" in text
    images = sum(len(p.images) for p in reader.pages)
    assert images == rep["stages"]["guide"]["pictures"]


def test_no_guide(models_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "plain"
    make(models_dir / "cube-12.obj", out, MakeOptions(guide=False, paper="letter"))
    asm, rep = _read(out)
    assert asm["steps"] == [] and rep["stages"]["guide"] is None
    assert not (out / "guide.pdf").exists()
    assert "Build steps" not in (out / "instructions.html").read_text()
    make(models_dir / "cube-12.obj", out, MakeOptions(paper="letter"))  # and on again, into the same folder
    from pypdf import PdfReader

    w, h = (float(x) for x in PdfReader(out / "guide.pdf").pages[0].mediabox.upper_right)
    assert abs(w - 612) < 1 and abs(h - 792) < 1  # Letter


def test_non_linear_pieces_show_their_stages(folders: dict[str, Path]) -> None:
    """bunny-128's sequential pieces say so and show each stage; straight ones show four frames."""
    rep = _read(folders["bunny"])[1]
    html = (folders["bunny"] / "instructions.html").read_text()
    for row in rep["pieces"]:
        section = re.search(rf"<h3>Step \d+: piece {row['piece']} \(sheet \d+\)</h3>(.*?)</section>", html, re.S)
        assert section, row["piece"]
        body = section.group(1)
        if row["linear"]:
            assert "Fold all its creases together" in body
            assert len(re.findall(rf"{row['piece']}: \d+ % folded", body)) >= 4
        elif row["path_verified"] and row["faces"] > 1:
            assert "does not fold in one motion" in body and row["planner"] in body
            assert re.search(rf"{row['piece']}: stage 2", body)


def _cube_pose() -> np.ndarray:
    """(12, 3, 3) the triangles of a unit cube, outward."""
    v = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([v[[a, b, c]] for a, b, c, d in quads for a, b, c in ((a, b, c), (a, c, d))])


def test_a_stage_picture_turns_to_show_a_hidden_crease() -> None:
    """A crease the folding pictures' direction cannot see (behind the shape) gets a picture turned
    about the vertical that shows most of it; a crease in sight keeps the usual direction."""
    from polyfold.formats.raster import view_rotation
    from polyfold.guide import pictures as P
    from polyfold.guide.guide import FRAME_PX, FRAME_VIEW, _stage_view

    pose = _cube_pose()
    rotation = view_rotation(*FRAME_VIEW, 2)
    front = np.full((len(pose), 3), 200, dtype=np.uint8)
    back = np.full_like(front, 90)
    cam = P.fit_camera(pose, rotation, *FRAME_PX)
    img, _ids, zbuf = P.draw_faces(cam, pose, front, back)
    edges = np.array([[pose[f, i], pose[f, (i + 1) % 3]] for f in range(len(pose)) for i in range(3)])
    seen = P.draw_lines(img.copy(), cam, zbuf, edges, P.MOUNTAIN_RGB, width=3.0)
    hidden, shown = edges[int(np.argmin(seen))], edges[int(np.argmax(seen))]
    assert seen.min() == 0.0 and seen.max() == 1.0

    cam2, img2, zbuf2, turned = _stage_view(pose, rotation, front, back, [(hidden[None], P.MOUNTAIN_RGB)])
    assert turned
    assert P.draw_lines(img2.copy(), cam2, zbuf2, hidden[None], P.MOUNTAIN_RGB, width=3.0)[0] > 0.75
    *_rest, kept = _stage_view(pose, rotation, front, back, [(shown[None], P.VALLEY_RGB)])
    assert not kept


def test_pictures_drawn_side_by_side_are_the_pictures_drawn_one_by_one(models_dir: Path, tmp_path: Path,
                                                                       monkeypatch) -> None:
    """The guide's pictures (the overview, each part's, each step's and its folding pictures) drawn
    in forked processes, and instructions.html and guide.pdf written side by side: the same
    instructions.html (every picture embedded in it) and assembly.json, and a guide.pdf of as
    many pages, as drawing and writing them one by one."""
    import polyfold.guide.guide as guide
    import polyfold.pipeline.export as export
    import polyfold.processes as processes

    from multiprocessing import RawValue

    spread = RawValue("i", 0)  # (shared: the guide is made in a process forked by the export)
    real = processes.fork_map

    def recorded(fn, items, workers):
        if getattr(fn, "__qualname__", "") == "build_guide.<locals>.draw" and len(items) > 5 and workers == 2:
            spread.value += 1
        return real(fn, items, workers)

    monkeypatch.setattr(processes, "fork_map", recorded)
    monkeypatch.setattr(guide, "PARALLEL_PICTURES", 0)
    monkeypatch.setattr(export, "PARALLEL_GUIDE_PICTURES", 0)
    got = {}
    for cores in (1, 2):
        monkeypatch.setattr(processes, "usable_cores", lambda cores=cores: cores)
        make(models_dir / "bunny-128.obj", tmp_path / str(cores), MakeOptions(parts=3, time_limit=60))
        got[cores] = [(tmp_path / str(cores) / name).read_bytes() for name in ("instructions.html", "assembly.json")]
        got[cores].append(_read(tmp_path / str(cores))[1]["stages"]["guide"])
    assert got[1][:2] == got[2][:2]
    for key in ("steps", "pictures", "pdf_pages", "closing_seams"):
        assert got[1][2][key] == got[2][2][key]
    # with two cores the pictures (the model's and 3 parts' sides, then the steps in runs) were spread
    assert spread.value >= 1


def test_a_picture_pickled_once_encoded_carries_its_files_not_its_pixels() -> None:
    """A guide's pictures drawn in forked processes come back encoded (`Picture.encoded`): the
    pickle holds the PNG and JPEG (what instructions.html and guide.pdf embed) and the shape, the
    same bytes as the picture made them here, and no pixels; one not yet encoded keeps them."""
    import pickle

    from polyfold.guide.guide import Picture

    rng = np.random.default_rng(3)
    image = np.zeros((150, 200, 3), dtype=np.uint8)
    image[40:110, 50:150] = rng.integers(0, 255, size=(70, 100, 3), dtype=np.uint8)
    raw = Picture(image, "a piece")
    assert pickle.loads(pickle.dumps(raw)).image is not None
    encoded = Picture(image.copy(), "a piece").encoded()
    data = pickle.dumps(encoded)
    assert len(data) < image.nbytes
    back = pickle.loads(data)
    assert back.image is None and back.caption == "a piece" and back.shape == (150, 200)
    assert back.png == raw.png and back.jpeg == raw.jpeg
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(back.png)).convert("RGB")), image)
