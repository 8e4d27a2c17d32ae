"""polyfold/graphs.py: what scipy.sparse.csgraph gives for the same graphs, exactly (component
numbering, breadth-first predecessors, shortest distances, the heaviest component), on random graphs with isolated nodes,
repeated edges, edges given both ways and self-loops."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, dijkstra

from polyfold import graphs


def _random_graphs(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.integers(1, 60))
        m = int(rng.integers(0, 3 * n))
        u, v = rng.integers(0, n, m), rng.integers(0, n, m)
        if m and rng.random() < 0.5:  # repeats, both ways and the same way
            k = rng.integers(0, m, m // 3)
            u, v = np.concatenate([u, v[k], u[k]]), np.concatenate([v, u[k], v[k]])
        yield n, u.astype(np.int64), v.astype(np.int64), rng


def test_components_are_scipys():
    for n, u, v, _ in _random_graphs(300, 1):
        want_n, want = connected_components(coo_matrix((np.ones(len(u)), (u, v)), shape=(n, n)), directed=False)
        got_n, got = graphs.connected_components(n, u, v)
        assert got_n == want_n and np.array_equal(got, want)
        assert np.array_equal(graphs.union_labels(n, u, v), want)


def test_components_of_meshes_and_long_paths_are_scipys():
    """Graphs of large diameter, where labels spread slowest: the dual graph of a 20,480-face
    sphere with two belts of edges removed (two caps, a band and faces left alone between), and
    paths of 20,000 nodes in order, reversed and shuffled."""
    from polyfold.apps.warmup import bumpy_sphere
    from polyfold.mesh.mesh import Mesh

    mesh = Mesh(*bumpy_sphere(5, 0.02, seed=3))
    ef = mesh.topology.edge_faces
    z = mesh.vertices[mesh.topology.edges].mean(axis=1)[:, 2]
    keep = (np.abs(z - 0.3) > 0.02) & (np.abs(z + 0.3) > 0.02)
    rng = np.random.default_rng(2)
    order = rng.permutation(20_000)
    graphs_ = [(mesh.n_faces, ef[keep, 0], ef[keep, 1])]
    graphs_ += [(20_000, p[:-1], p[1:]) for p in (np.arange(20_000), np.arange(20_000)[::-1], order)]
    for n, u, v in graphs_:
        want_n, want = connected_components(coo_matrix((np.ones(len(u)), (u, v)), shape=(n, n)), directed=False)
        got_n, got = graphs.connected_components(n, u, v)
        assert got_n == want_n and np.array_equal(got, want)
        assert want_n >= 3 if n == mesh.n_faces else want_n == 1


def test_breadth_first_predecessors_are_scipys():
    """On the symmetric weighted graph mesh repair builds (G + G.T, weights >= 1), from every kind
    of head: the tree, and the weight read on each tree edge."""
    for n, u, v, rng in _random_graphs(300, 2):
        w = rng.integers(1, 3, len(u))
        g = coo_matrix((w, (u, v)), shape=(n, n)).tocsr()
        g = (g + g.T).tocsr()
        head = int(rng.integers(0, n))
        _, want = breadth_first_order(g, head, directed=False, return_predecessors=True)
        got = graphs.breadth_first_predecessors(n, u, v, head)
        assert np.array_equal(got, want)
        tree = np.flatnonzero(got >= 0)
        if len(tree):  # (scipy's fancy indexing of none gives a matrix)
            assert np.array_equal(graphs.summed_weights(n, u, v, w, got[tree], tree),
                                  np.asarray(g[got[tree], tree]).reshape(-1))


def test_shortest_distances_are_scipys_bit_for_bit():
    for n, u, v, rng in _random_graphs(300, 3):
        w = rng.random(len(u)) * 10 + 1e-300
        source = int(rng.integers(0, n))
        want = dijkstra(coo_matrix((w, (u, v)), shape=(n, n)).tocsr(), directed=False, indices=source)
        got = graphs.shortest_distances(n, u, v, w, source)
        assert np.array_equal(got, want), np.abs(got - want)[np.isfinite(want)].max()


def test_heaviest_component_is_bincount_of_scipys_components_bit_for_bit():
    for n, u, v, rng in _random_graphs(300, 4):
        w = rng.random(len(u)) * rng.choice([1e-3, 1.0, 1e3], len(u))
        _, label = connected_components(coo_matrix((np.ones(len(u)), (u, v)), shape=(n, n)), directed=False)
        want = np.bincount(label[u], weights=w).max() if len(u) else 0.0
        assert graphs.heaviest_component(n, u, v, w) == want


@pytest.mark.parametrize("n", [0, 1])
def test_tiny_graphs(n):
    none = np.zeros(0, dtype=np.int64)
    count, labels = graphs.connected_components(n, none, none)
    assert count == n and labels.tolist() == list(range(n))
    if n:
        assert graphs.breadth_first_predecessors(n, none, none, 0).tolist() == [graphs.NO_PREDECESSOR]
        assert graphs.shortest_distances(n, none, none, np.zeros(0), 0).tolist() == [0.0]
    assert graphs.heaviest_component(n, none, none, np.zeros(0)) == 0.0
