"""The one plain sort-and-sweep of collide/ (`sweep_pairs`) and the mesh self-intersection built on
it (`crossing_pairs`, `self_intersections`), against an O(n^2) reference on real meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numba import njit

from polyfold.collide.self_intersect import crossing_pairs, face_triangles, self_intersections
from polyfold.collide.sweep import NO_LIMIT, all_collisions, first_collision, sweep_pairs
from polyfold.collide.triangles import triangles_collide
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh

# self-crossing inputs, and closed / open ones that do not cross themselves
MESHES = ["fish-472.obj", "bad/intersecting-cubes.obj", "bad/two-cubes.obj", "bunny-348.obj", "torus-12x6-144.obj",
          "spiky-icosahedron-60.obj", "open/tube-132.obj"]


@njit(cache=True)
def _reference(tris, tol, piece, parent, faces, keys):
    """Every pair i < j the skip rule keeps (empty array: that part off), tested by
    triangles_collide: no broad phase at all. Hits as rows (i, j), in (i, j) order."""
    n = tris.shape[0]
    hits = []
    for i in range(n):
        for j in range(i + 1, n):
            if piece.shape[0] and piece[i] != piece[j]:
                continue
            if parent.shape[0] and (parent[i] == j or parent[j] == i):
                continue
            if faces.shape[0]:
                shared = 0
                for a in range(3):
                    for b in range(3):
                        if faces[i, a] == faces[j, b]:
                            shared += 1
                if shared >= 2:
                    continue
            if keys.shape[0] and (keys == i * n + j).any():
                continue
            if triangles_collide(tris[i], tris[j], tol):
                hits.append((i, j))
    out = np.empty((len(hits), 2), dtype=np.int64)
    for k in range(len(hits)):
        out[k, 0] = hits[k][0]
        out[k, 1] = hits[k][1]
    return out


NONE_I = np.empty(0, dtype=np.int64)
NONE_F = np.empty((0, 3), dtype=np.int64)


def reference(tris, tol, piece=None, parent=None, faces=None, keys=None) -> list[tuple[int, int]]:
    return [tuple(p) for p in _reference(tris, tol, NONE_I if piece is None else piece,
                                         NONE_I if parent is None else parent, NONE_F if faces is None else faces,
                                         NONE_I if keys is None else keys).tolist()]


def swept(tris, tol, piece=None, parent=None, faces=None, keys=None, stop_after=NO_LIMIT, room=None):
    """(count, pairs in sweep order) of sweep_pairs, room rows for the pairs (default: all)."""
    if room is None:
        room = sweep_pairs(tris, tol, piece, parent, faces, keys, NO_LIMIT, np.empty((0, 2), np.int64))
    pairs = np.empty((room, 2), dtype=np.int64)
    count = sweep_pairs(tris, tol, piece, parent, faces, keys, stop_after, pairs)
    return count, [tuple(p) for p in pairs[: min(count, room)].tolist()]


@pytest.fixture(scope="module")
def meshes(models_dir: Path) -> dict[str, Mesh]:
    return {name: load_mesh(models_dir / name).mesh for name in MESHES}


def doubled(mesh: Mesh) -> np.ndarray:
    """The faces' triangles and a shrunk, shifted copy of them: many crossing pairs."""
    tris = face_triangles(mesh.vertices, mesh.faces)
    shift = 0.013 * mesh.bbox_diagonal
    return np.ascontiguousarray(np.concatenate([tris, tris * 0.97 + shift]))


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("rel_tol", [1e-7, 1e-3])
def test_self_intersections_match_the_reference(meshes: dict, name: str, rel_tol: float) -> None:
    mesh = meshes[name]
    X = mesh.vertices
    tol = rel_tol * float(np.linalg.norm(X.max(0) - X.min(0)))  # as self_intersections scales it
    tris = face_triangles(X, mesh.faces)
    expected = reference(tris, tol, faces=mesh.faces)
    count, _ = crossing_pairs(X, mesh.faces, tol, 0)
    assert count == len(expected)
    count, pairs = crossing_pairs(X, mesh.faces, tol, count)
    assert len(pairs) == count
    assert sorted(map(tuple, pairs.tolist())) == expected
    assert sorted(map(tuple, self_intersections(mesh, rel_tol).tolist())) == expected
    if rel_tol == 1e-7 and name in ("fish-472.obj", "bad/intersecting-cubes.obj"):
        assert expected  # the crossing inputs do cross


def test_crossing_pairs_skips_the_listed_keys(meshes: dict) -> None:
    mesh = meshes["bad/intersecting-cubes.obj"]
    tol = 1e-7 * mesh.bbox_diagonal
    count, pairs = crossing_pairs(mesh.vertices, mesh.faces, tol, 100)
    assert count >= 4
    m = len(mesh.faces)
    keys = np.sort(pairs[::2, 0] * m + pairs[::2, 1])
    left, rest = crossing_pairs(mesh.vertices, mesh.faces, tol, 100, keys)
    assert left == count - len(keys)
    assert rest.tolist() == pairs[1::2].tolist()  # the others, still in sweep order
    tris = face_triangles(mesh.vertices, mesh.faces)
    assert sorted(map(tuple, rest.tolist())) == reference(tris, tol, faces=mesh.faces, keys=keys)
    first, one = crossing_pairs(mesh.vertices, mesh.faces, tol, 1)
    assert first == count and one.tolist() == pairs[:1].tolist()  # counts all, keeps the first


@pytest.mark.parametrize("name", MESHES)
def test_fold_rule_matches_the_reference(meshes: dict, name: str) -> None:
    tris = doubled(meshes[name])
    n = len(tris)
    rng = np.random.default_rng(n)
    for piece, parent in [(np.zeros(n, np.int64), np.full(n, -1)),
                          (rng.integers(0, 2, n), rng.integers(-1, n, n))]:
        for tol in (1e-9, 1e-3 * meshes[name].bbox_diagonal):
            expected = reference(tris, tol, piece=piece, parent=parent)
            count, pairs = swept(tris, tol, piece=piece, parent=parent)
            assert count == len(expected) > 0
            assert sorted(pairs) == expected
            # the reports: the same pairs in the same (sweep) order, the first one first
            total, reported = all_collisions(tris, parent, piece, tol, count)
            assert total == count and [tuple(p) for p in reported.tolist()] == pairs
            assert tuple(first_collision(tris, parent, piece, tol)) == pairs[0]


def test_stopping_and_room(meshes: dict) -> None:
    tris = doubled(meshes["bunny-348.obj"])
    count, pairs = swept(tris, 1e-9)
    assert count > 10
    for stop in (1, 2, 7, count, count + 5):
        got, head = swept(tris, 1e-9, stop_after=stop)
        assert got == min(stop, count) and head == pairs[:got]  # the first hits, then stop
    got, head = swept(tris, 1e-9, room=3)
    assert got == count and head == pairs[:3]  # counts them all, writes what fits
    assert swept(tris, 1e-9, room=0) == (count, [])


def test_no_faces() -> None:
    tris = np.empty((0, 3, 3))
    assert swept(tris, 1e-9) == (0, [])
    assert self_intersections(Mesh(np.empty((0, 3)), np.empty((0, 3), np.int64))).shape == (0, 2)


def test_face_triangles(meshes: dict) -> None:
    mesh = meshes["fish-472.obj"]
    assert np.array_equal(face_triangles(mesh.vertices, mesh.faces), mesh.vertices[mesh.faces])
