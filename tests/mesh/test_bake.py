"""Simplification keeps the look: the new faces show what the old surface showed there."""

from __future__ import annotations

import numpy as np
import trimesh

from polyfold.mesh.appearance import Appearance
from polyfold.mesh.mesh import Mesh
from polyfold.mesh.repair import LoadedMesh
from polyfold.mesh.simplify import simplify


def gradient(n: int = 256) -> np.ndarray:
    y, x = np.mgrid[0:n, 0:n]
    return np.stack([x * 255 // (n - 1), y * 255 // (n - 1), np.full_like(x, 60)], axis=2).astype(np.uint8)


def projected_uv(points: np.ndarray) -> np.ndarray:
    """UVs that project the unit sphere along z: colour is then a function of (x, y)."""
    return np.stack([0.5 + 0.45 * points[..., 0], 0.5 + 0.45 * points[..., 1]], axis=-1)


def expected(points: np.ndarray) -> np.ndarray:
    """The gradient's colour (nearest texel) at the projection of surface points."""
    uv = projected_uv(points)
    x = np.clip(np.floor(uv[..., 0] * 256), 0, 255)
    y = np.clip(np.floor((1 - uv[..., 1]) * 256), 0, 255)
    return np.stack([x, y, np.full_like(x, 60)], axis=-1)


def sphere(subdivisions: int = 4) -> Mesh:
    s = trimesh.creation.icosphere(subdivisions=subdivisions)
    return Mesh(s.vertices, s.faces)


def random_points(mesh: Mesh, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    faces = rng.integers(0, mesh.n_faces, n)
    bary = rng.dirichlet([2, 2, 2], n)
    points = np.einsum("nk,nkc->nc", bary, mesh.vertices[mesh.faces[faces]])
    return faces, bary, points


def test_a_baked_texture_shows_the_old_surface():
    old = sphere()
    look = Appearance((gradient(),), np.zeros(old.n_faces, int), projected_uv(old.vertices[old.faces]),
                      np.full((old.n_faces, 3, 3), 255), "texture")
    done = simplify(LoadedMesh("sphere", old, (old,), (), appearance=look), 400)
    new, baked = done.loaded.mesh, done.loaded.appearance
    assert new.n_faces <= 420 and baked.kind == "texture" and baked.textured.all()
    faces, bary, points = random_points(new, 4000, 1)
    got = baked.sample(faces, bary).astype(float)
    # the new surface lies within ~1 % of the old: the closest old point's colour moves a few levels
    err = np.abs(got - expected(points)).max(axis=1)
    assert np.median(err) <= 4 and np.percentile(err, 99) <= 12, (np.median(err), np.percentile(err, 99))


def test_vertex_colours_follow_the_corners():
    old = sphere()
    corners = old.vertices[old.faces]
    colors = ((corners * 0.5 + 0.5) * 255).round().astype(np.uint8)  # colour = position
    look = Appearance((), np.full(old.n_faces, -1), np.full((old.n_faces, 3, 2), np.nan), colors, "vertex")
    done = simplify(LoadedMesh("sphere", old, (old,), (), appearance=look), 300)
    new, baked = done.loaded.mesh, done.loaded.appearance
    assert baked.kind == "vertex" and not baked.textured.any()
    want = (new.vertices[new.faces] * 0.5 + 0.5) * 255
    assert np.abs(baked.colors.astype(float) - want).max() <= 8


def test_face_colours_stay_one_per_face():
    old = sphere(3)
    rgb = np.where(old.vertices[old.faces].mean(axis=1)[:, :1] > 0, [200, 30, 30], [30, 30, 200]).astype(np.uint8)
    look = Appearance((), np.full(old.n_faces, -1), np.full((old.n_faces, 3, 2), np.nan),
                      np.repeat(rgb[:, None], 3, axis=1), "face")
    done = simplify(LoadedMesh("sphere", old, (old,), (), appearance=look), 200)
    new, baked = done.loaded.mesh, done.loaded.appearance
    assert baked.kind == "face" and not baked.shaded.any()
    side = new.vertices[new.faces].mean(axis=1)[:, 0]
    clear = np.abs(side) > 0.2  # faces away from the colour boundary x = 0
    assert (baked.colors[clear, 0, 0] == np.where(side[clear] > 0, 200, 30)).all()
