"""The model's look on the printed pieces: every printed face is its image triangle under the
affine map of its UVs, or its colours; checked against the texture with an independent lookup."""

from __future__ import annotations

import numpy as np
import trimesh

from polyfold.fabricate.paint import page_looks, piece_image
from polyfold.fabricate.sheet import net_sheet
from polyfold.mesh.appearance import Appearance
from polyfold.mesh.mesh import Mesh
from polyfold.unfold.search import unfold


def gradient(h: int = 256, w: int = 256) -> np.ndarray:
    y, x = np.mgrid[0:h, 0:w]
    return np.stack([x * 255 // (w - 1), y * 255 // (h - 1), (x + y) * 255 // (h + w - 2)], axis=2).astype(np.uint8)


def nearest_texel(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    h, w = image.shape[:2]
    x = np.clip(np.floor(uv[..., 0] * w), 0, w - 1).astype(int)
    y = np.clip(np.floor((1 - uv[..., 1]) * h), 0, h - 1).astype(int)
    return image[y, x].astype(int)


def sphere_sheet():
    sphere = trimesh.creation.icosphere(subdivisions=1)
    mesh = Mesh(sphere.vertices, sphere.faces)
    net, _ = unfold(mesh, seed=1, time_limit=20)
    return mesh, net_sheet([net], 120.0)


def pixels_at(image, points: np.ndarray) -> np.ndarray:
    """The PageImage's pixels under page points (n, 2) mm."""
    h, w = image.pixels.shape[:2]
    col = np.floor((points[:, 0] - image.x) / image.width * w).astype(int)
    row = np.floor((points[:, 1] - image.y) / image.height * h).astype(int)
    return image.pixels[row, col].astype(int)


INNER = np.array([[1, 1, 1], [3, 1, 1], [1, 3, 1], [1, 1, 3], [2, 2, 1], [1, 2, 2]], dtype=float)
INNER /= INNER.sum(axis=1, keepdims=True)


def test_every_printed_face_is_its_image_triangle_under_its_uvs():
    mesh, sheet = sphere_sheet()
    rng = np.random.default_rng(3)
    # every face gets a triangle of its own anywhere in the image (the strongest case: no shared UVs)
    uv = 0.15 + 0.7 * rng.random((mesh.n_faces, 3, 2))
    look = Appearance((gradient(),), np.zeros(mesh.n_faces, int), uv, np.full((mesh.n_faces, 3, 3), 255), "texture")
    checked = 0
    for piece in sheet.pieces:
        if not len(piece.face_ids):
            continue
        image = piece_image(piece, look, dpi=300)
        for f, xy in zip(piece.face_ids, piece.faces_xy):
            pts = INNER @ xy  # points well inside the printed face
            want = nearest_texel(look.images[0], INNER @ uv[f])
            got = pixels_at(image, pts)
            # a texel of the 256 px gradient is 1-2 levels; sampling bilinear vs nearest, and the
            # pixel grid, move it by a few
            assert np.abs(got - want).max() <= 8, (f, got, want)
            checked += len(pts)
    assert checked == 6 * mesh.n_faces


def test_vertex_colours_are_interpolated_across_each_face():
    mesh, sheet = sphere_sheet()
    rng = np.random.default_rng(4)
    colors = rng.integers(0, 256, (mesh.n_faces, 3, 3)).astype(np.uint8)
    look = Appearance((), np.full(mesh.n_faces, -1), np.full((mesh.n_faces, 3, 2), np.nan), colors, "vertex")
    piece = max(sheet.pieces, key=lambda p: len(p.face_ids))
    image = piece_image(piece, look, dpi=300)
    for f, xy in zip(piece.face_ids, piece.faces_xy):
        want = INNER @ colors[f].astype(float)
        assert np.abs(pixels_at(image, INNER @ xy) - want).max() <= 6


def test_modes_and_what_gets_a_picture():
    mesh, sheet = sphere_sheet()
    n = mesh.n_faces
    pieces = [p for p in sheet.pieces if len(p.face_ids)]
    flat = np.repeat(np.arange(n)[:, None, None] % 7 * 30, 9).reshape(n, 3, 3).astype(np.uint8)
    one_colour = Appearance((), np.full(n, -1), np.full((n, 3, 2), np.nan), flat, "face")
    fills, images = page_looks(pieces, one_colour, "texture")
    assert not images  # one colour per face: vector fills only
    assert all(np.array_equal(c, flat[p.face_ids, 0]) for c, p in zip(fills, pieces))
    textured = Appearance((gradient(),), np.zeros(n, int), np.random.default_rng(0).random((n, 3, 2)),
                          np.full((n, 3, 3), 255), "texture")
    assert len(page_looks(pieces, textured, "texture")[1]) == len(pieces)
    fills, images = page_looks(pieces, textured, "flat")
    assert not images and len(fills) == len(pieces)
    assert page_looks(pieces, textured, "none") == ((), ())
    assert page_looks(pieces, None, "texture") == ((), ())


def test_the_picture_is_clipped_to_the_faces_and_covers_them():
    mesh, sheet = sphere_sheet()
    n = mesh.n_faces
    look = Appearance((np.zeros((8, 8, 3), np.uint8),), np.zeros(n, int), np.full((n, 3, 2), 0.5),
                      np.full((n, 3, 3), 255), "texture")  # every face black
    piece = max(sheet.pieces, key=lambda p: len(p.face_ids))
    image = piece_image(piece, look, dpi=200)
    import shapely

    clip = shapely.union_all([shapely.Polygon(r) for r in image.clip])
    assert abs(clip.area - piece.body.area) < 1e-6 * piece.body.area
    # every pixel whose centre lies in the body is painted (black), including those on creases
    h, w = image.pixels.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    centres = np.stack([image.x + (xx + 0.5) / w * image.width, image.y + (yy + 0.5) / h * image.height], axis=2)
    inside = shapely.contains_xy(piece.body, centres[..., 0], centres[..., 1])
    assert inside.sum() > 1000
    assert (image.pixels[inside] == 0).all()
