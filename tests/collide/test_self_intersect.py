"""collide/self_intersect.py: the mesh self-intersection built on `sweep_pairs` (`crossing_pairs`,
`self_intersections`, `face_triangles`), against an O(n^2) reference on real meshes."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MESHES, reference
from polyfold.collide.self_intersect import crossing_pairs, face_triangles, self_intersections


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


def test_face_triangles(meshes: dict) -> None:
    mesh = meshes["fish-472.obj"]
    assert np.array_equal(face_triangles(mesh.vertices, mesh.faces), mesh.vertices[mesh.faces])
