"""Reading a mesh's look: OBJ + MTL + image, GLB textures, PLY / OBJ / GLB colours, and bad
looks that must only warn."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from PIL import Image

from polyfold.formats.meshes import load_mesh


def gradient(h: int = 64, w: int = 64) -> np.ndarray:
    """A texture whose colour says where it is: red grows to the right, green downwards."""
    y, x = np.mgrid[0:h, 0:w]
    return np.stack([x * 255 // (w - 1), y * 255 // (h - 1), np.full_like(x, 90)], axis=2).astype(np.uint8)


def expected(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The texel under texture coordinates (u right, v up), nearest texel: independent of the
    bilinear sampler under test."""
    h, w = image.shape[:2]
    x = np.clip(np.floor(uv[..., 0] * w), 0, w - 1).astype(int)
    y = np.clip(np.floor((1 - uv[..., 1]) * h), 0, h - 1).astype(int)
    return image[y, x].astype(int)


QUAD_OBJ = """mtllib look.mtl
usemtl skin
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 0.5 -1
vt 0.1 0.1
vt 0.9 0.1
vt 0.9 0.9
vt 0.1 0.9
vt 0.5 0.5
f 1/1 4/4 3/3 2/2
f 1/1 2/2 5/5
f 2/2 3/3 5/5
f 3/3 4/4 5/5
f 4/4 1/1 5/5
"""


def write_textured(tmp_path, obj: str = QUAD_OBJ, mtl: str = "newmtl skin\nKd 1 1 1\nmap_Kd look.png\n",
                   image: np.ndarray | None = None):
    (tmp_path / "look.mtl").write_text(mtl)
    Image.fromarray(gradient() if image is None else image).save(tmp_path / "look.png")
    path = tmp_path / "pyramid.obj"
    path.write_text(obj)
    return path


def test_an_obj_texture_is_read_with_the_uvs_of_every_corner(tmp_path):
    loaded = load_mesh(write_textured(tmp_path))
    look = loaded.appearance
    assert look is not None and look.kind == "texture"
    assert look.textured.all() and look.images[0].shape == (64, 64, 3)
    # every corner's UV is the vt its file corner named; in this file vt = 0.1 + 0.8 * (x, y) of
    # the base corners and (0.5, 0.5) at the apex, so the check is geometric (repair renumbers)
    xy = loaded.mesh.vertices[loaded.mesh.faces][..., :2]
    apex = loaded.mesh.vertices[loaded.mesh.faces][..., 2] < -0.5
    want = np.where(apex[..., None], [0.5, 0.5], 0.1 + 0.8 * xy)
    assert np.allclose(look.uv, want)
    # the colour sampled at a face's centre is the texel under its mean UV
    rgb = look.sample(np.arange(look.n_faces), np.full((look.n_faces, 3), 1 / 3))
    assert np.abs(rgb.astype(int) - expected(look.images[0], look.uv.mean(axis=1))).max() <= 6


def test_flipped_faces_keep_their_corners_uvs(tmp_path):
    # the last face is wound the wrong way: repair flips it, and its UVs must follow its corners
    obj = QUAD_OBJ.replace("f 4/4 1/1 5/5", "f 1/1 4/4 5/5")
    loaded = load_mesh(write_textured(tmp_path, obj))
    assert any("flipped" in w for w in loaded.warnings)
    tri = loaded.mesh.vertices[loaded.mesh.faces]
    apex = tri[..., 2] < -0.5
    want = np.where(apex[..., None], [0.5, 0.5], 0.1 + 0.8 * tri[..., :2])
    assert np.allclose(loaded.appearance.uv, want)


@pytest.mark.parametrize("mtl, image, words", [
    ("newmtl skin\nmap_Kd missing.png\n", None, "'missing.png' not found"),
    ("newmtl skin\nmap_Kd broken.png\n", "broken", "'broken.png' cannot be read"),
    ("newmtl skin\nKd 1 x 1\nmap_Kd look.png\n", None, "Kd colour that is not 3 numbers"),
])
def test_a_bad_look_is_one_warning_and_the_model_still_loads(tmp_path, mtl, image, words):
    path = write_textured(tmp_path, mtl=mtl)
    if image == "broken":
        (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n not really")
    loaded = load_mesh(path)
    assert loaded.mesh.n_faces == 6
    hits = [w for w in loaded.warnings if words in w]
    assert len(hits) == 1 and "\n" not in hits[0]


def test_a_missing_mtl_file_warns(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(QUAD_OBJ)  # names look.mtl, which is not there
    loaded = load_mesh(path)
    assert loaded.appearance is None or not loaded.appearance.textured.any()
    assert any("look.mtl" in w and "cannot be read" in w for w in loaded.warnings)


def test_broken_and_repeating_uvs_warn(tmp_path):
    obj = QUAD_OBJ.replace("vt 0.5 0.5", "vt 2.5 0.5").replace("vt 0.1 0.9", "vt nan 0.9")
    loaded = load_mesh(write_textured(tmp_path, obj))
    look = loaded.appearance
    assert any("broken texture coordinates" in w for w in loaded.warnings)
    assert any("outside 0..1: the texture repeats" in w for w in loaded.warnings)
    assert not look.textured.all() and look.textured.any()  # faces on vertex 4 (NaN) lost the texture only
    assert np.isnan(look.uv[~look.textured]).all()


def test_textured_glb_with_a_base_colour_factor(tmp_path):
    box = trimesh.creation.box()
    uv = np.random.default_rng(0).random((len(box.vertices), 2))
    material = trimesh.visual.material.PBRMaterial(baseColorTexture=Image.fromarray(gradient()),
                                                   baseColorFactor=[255, 128, 255, 255])
    box.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    path = tmp_path / "box.glb"
    path.write_bytes(box.export(file_type="glb"))
    look = load_mesh(path).appearance
    assert look.kind == "texture" and look.textured.all()
    # the factor tints the texture: green halved
    assert np.abs(look.images[0][..., 1].astype(int) - gradient()[..., 1] // 2).max() <= 1
    assert np.abs(look.images[0][..., 0].astype(int) - gradient()[..., 0]).max() <= 1


def test_vertex_and_face_colours(tmp_path):
    box = trimesh.creation.box()
    vc = np.random.default_rng(1).integers(0, 255, (len(box.vertices), 4)).astype(np.uint8)
    vc[:, 3] = 255
    box.visual = trimesh.visual.ColorVisuals(box, vertex_colors=vc)
    (tmp_path / "v.ply").write_bytes(box.export(file_type="ply"))
    loaded = load_mesh(tmp_path / "v.ply")
    look = loaded.appearance
    assert look.kind == "vertex"
    # each corner carries the colour of its vertex (found by position: repair may renumber)
    near = np.argmin(np.linalg.norm(loaded.mesh.vertices[:, None] - box.vertices[None], axis=2), axis=1)
    assert np.array_equal(look.colors, vc[near[loaded.mesh.faces]][..., :3])

    box = trimesh.creation.box()
    fc = np.random.default_rng(2).integers(0, 255, (len(box.faces), 4)).astype(np.uint8)
    box.visual = trimesh.visual.ColorVisuals(box, face_colors=fc)
    (tmp_path / "f.ply").write_bytes(box.export(file_type="ply"))
    look = load_mesh(tmp_path / "f.ply").appearance
    assert look.kind == "face" and not look.shaded.any()


def test_obj_vertex_colours(tmp_path):
    text = "".join(f"v {x} {y} {z} {x} {y} 0.5\n" for x, y, z in trimesh.creation.box().vertices + 0.5)
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in trimesh.creation.box().faces)
    (tmp_path / "c.obj").write_text(text)
    loaded = load_mesh(tmp_path / "c.obj")
    look = loaded.appearance
    assert look.kind == "vertex"
    corners = loaded.mesh.vertices[loaded.mesh.faces]
    assert np.abs(look.colors[..., 0].astype(float) - corners[..., 0] * 255).max() <= 1
    assert np.abs(look.colors[..., 2].astype(float) - 128).max() <= 1


def test_the_spot_control_mesh_reads_its_texture(models_dir):
    loaded = load_mesh(models_dir / "textured" / "spot" / "spot_control_mesh.obj")
    look = loaded.appearance
    assert look.kind == "texture" and look.textured.all() and look.images[0].shape == (1024, 1024, 3)
    assert np.nanmin(look.uv) > -0.1 and np.nanmax(look.uv) < 1.1
    assert not [w for w in loaded.warnings if "texture" in w]  # a good model loads without a word about it
