"""mesh/mesh.py: the edge table of `edge_topology` (one lexsort) against np.unique and a
lexsort loop on random face lists (non-manifold, unoriented, degenerate), and on a known mesh."""

import numpy as np
import pytest

from conftest import single_component
from polyfold.mesh.mesh import edge_topology


def _reference_topology(faces):
    """Edge table by np.unique of the sorted sides and a loop over the sides (lexsort order)."""
    m = len(faces)
    directed = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)
    key = np.sort(directed, axis=1)
    edges, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    edge_faces = np.full((len(edges), 2), -1, dtype=np.int64)
    forward = directed[:, 0] == key[:, 0]
    for idx in np.lexsort((~forward, inverse)):
        e, slot = inverse[idx], 0 if forward[idx] else 1
        if edge_faces[e, slot] >= 0:
            slot = 1 - slot
            if edge_faces[e, slot] >= 0:
                continue
        edge_faces[e, slot] = idx // 3
    swap = (edge_faces[:, 0] < 0) & (edge_faces[:, 1] >= 0)
    edge_faces[swap] = edge_faces[swap][:, ::-1]
    edges = edges.copy()
    edges[swap] = edges[swap][:, ::-1]
    return edges, edge_faces, inverse.reshape(m, 3), counts


@pytest.mark.parametrize("seed", range(40))
def test_edge_table_matches_unique_and_lexsort(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    faces = rng.integers(0, n, size=(int(rng.integers(0, 25)), 3))  # non-manifold, unoriented, degenerate
    topo = edge_topology(faces)
    for got, want in zip((topo.edges, topo.edge_faces, topo.face_edges, topo.face_count), _reference_topology(faces)):
        assert got.dtype == np.int64 and np.array_equal(got, want)


def test_topology_of_known_mesh(models_dir):
    mesh = single_component(models_dir, "cube-12")
    topo = edge_topology(mesh.faces)
    assert topo.n_edges == 18 and topo.interior.all()
    assert np.count_nonzero(mesh.fold_angles > 1.0) == 12  # the cube's 90 degree edges
    assert np.count_nonzero(np.abs(mesh.fold_angles) < 1e-9) == 6  # face diagonals
