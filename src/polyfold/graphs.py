"""Graph primitives over edge lists: connected components (numpy, and `union_labels` for
kernels), the heaviest component, a breadth-first tree and single-source shortest distances of
undirected graphs on nodes 0..n-1.

They give exactly what scipy.sparse.csgraph gives for the same sparse matrix (tests compare
them): its numbering of components (in the order of each one's lowest node), its breadth-first
predecessors (neighbours in ascending order, -9999 for none), its distances (inf where
unreachable); duplicate edges count as coo_matrix counts them (summed). Own kernels rather than
scipy's because importing scipy.sparse.csgraph took 0.14 s of every command that loads a mesh
(mesh repair and the guide's build order are its only users there): a warm `make` of the bunny
spends 1.0 s in all.
"""

from __future__ import annotations

import numpy as np

from .jit import njit

NO_PREDECESSOR = -9999  # (scipy's)


def _adjacency(n: int, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(indptr (n+1,), neighbours) of the undirected graph with edges u[i]-v[i]: both directions,
    each node's neighbours ascending, once each."""
    a = np.concatenate([u, v]).astype(np.int64)
    b = np.concatenate([v, u]).astype(np.int64)
    key = np.unique(a * n + b)
    src, dst = key // n, key % n
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    return indptr, dst


def connected_components(n: int, u: np.ndarray, v: np.ndarray) -> tuple[int, np.ndarray]:
    """(number of components, label (n,) int64 of each node) of the undirected graph with edges
    u[i]-v[i] (scipy's `connected_components(coo_matrix(...), directed=False)`). numpy only
    (`polyfold info` loads meshes without numba): every node and every label across an edge takes
    the lowest label across that edge, then every node follows labels to their end (pointer
    jumping), until nothing changes; labels end as each component's lowest node, numbered in that
    order."""
    u, v = np.asarray(u, dtype=np.int64), np.asarray(v, dtype=np.int64)
    labels = np.arange(n, dtype=np.int64)
    ends = np.concatenate([u, v])
    while len(u):
        lu, lv = labels[u], labels[v]
        low = np.minimum(lu, lv)
        new = labels.copy()
        # The edge's ends and their labels (roots of the label forest, after the jumping) take the
        # lower label: hooking the roots joins whole trees at once, so a mesh's components take a
        # few rounds, not one per step of their diameter (an 82k-face sphere: 195 rounds).
        np.minimum.at(new, np.concatenate([ends, lu, lv]), np.concatenate([low, low, low, low]))
        jumped = new[new]
        while not np.array_equal(jumped, new):
            new, jumped = jumped, jumped[jumped]
        if np.array_equal(new, labels):
            break
        labels = new
    roots, numbered = np.unique(labels, return_inverse=True)
    return len(roots), numbered.astype(np.int64)


@njit(cache=True)
def union_labels(n, f0, f1):
    """Component label of each of n items joined by the pairs (f0[i], f1[i]); components are
    numbered in the order of their smallest item (as scipy's connected_components numbers them)."""
    root = np.arange(n)
    for k in range(f0.shape[0]):
        a, b = f0[k], f1[k]
        while root[a] != a:
            root[a] = root[root[a]]
            a = root[a]
        while root[b] != b:
            root[b] = root[root[b]]
            b = root[b]
        if a != b:
            if a < b:
                root[b] = a
            else:
                root[a] = b
    label = np.empty(n, dtype=np.int64)
    nxt = 0
    for i in range(n):
        r = i
        while root[r] != r:
            r = root[r]
        if r == i:
            label[i] = nxt
            nxt += 1
        else:
            label[i] = label[r]  # r < i: the root is the smallest item, labelled already
    return label


@njit(cache=True)
def heaviest_component(n, u, v, w):
    """The largest total weight of the edges of one connected component of the undirected graph
    on nodes 0..n-1 with edges u[i]-v[i] of weight w[i] (0.0 with no edges): what
    `np.bincount(connected_components(n, u, v)[1][u], weights=w).max()` gives, to the last bit
    (each component's weights are added in edge order), for callers that ask it per step of a
    growing build (`guide.order.opening_rims`)."""
    label = union_labels(n, u, v)
    total = np.zeros(n)
    for i in range(len(u)):
        total[label[u[i]]] += w[i]
    best = 0.0
    for k in range(n):
        if total[k] > best:
            best = total[k]
    return best


def breadth_first_predecessors(n: int, u: np.ndarray, v: np.ndarray, head: int) -> np.ndarray:
    """(n,) int64 predecessor of each node in the breadth-first tree from `head` of the undirected
    graph with edges u[i]-v[i]; NO_PREDECESSOR at head and where unreached (scipy's
    `breadth_first_order(..., directed=False, return_predecessors=True)[1]`: nodes taken first
    in, first out, each one's neighbours in ascending order). numpy only, a level at a time: a
    level's nodes in the order they were found, each one's neighbours ascending; a node's
    predecessor is the first of them to reach it."""
    indptr, neighbours = _adjacency(n, np.asarray(u), np.asarray(v))
    pred = np.full(n, NO_PREDECESSOR, dtype=np.int64)
    seen = np.zeros(n, dtype=bool)
    seen[head] = True
    level = np.array([head], dtype=np.int64)
    while len(level):
        starts, counts = indptr[level], indptr[level + 1] - indptr[level]
        by = np.repeat(np.arange(len(level)), counts)  # (which node of the level reaches it)
        offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        reached = neighbours[np.repeat(starts, counts) + offset]
        new = ~seen[reached]
        reached, by = reached[new], by[new]
        _, first = np.unique(reached, return_index=True)
        first.sort()  # (the order found)
        pred[reached[first]] = level[by[first]]
        level = reached[first]
        seen[level] = True
    return pred


def summed_weights(n: int, u: np.ndarray, v: np.ndarray, w: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The weight of the undirected edges a[j]-b[j] in the graph whose edges u[i]-v[i] weigh w[i]:
    the sum over its entries in either direction (what (G + G.T)[a, b] reads of G = coo_matrix
    of them); 0 where there is none."""
    key = np.concatenate([np.asarray(u, dtype=np.int64) * n + v, np.asarray(v, dtype=np.int64) * n + u])
    uniq, inverse = np.unique(key, return_inverse=True)
    total = np.bincount(inverse, weights=np.concatenate([w, w]).astype(np.float64), minlength=len(uniq))
    want = np.asarray(a, dtype=np.int64) * n + b
    if not len(uniq):
        return np.zeros(len(want))
    at = np.minimum(np.searchsorted(uniq, want), len(uniq) - 1)
    return np.where(uniq[at] == want, total[at], 0.0)


@njit(cache=True, inline="always")
def heap_push(keys, nodes, size, key, node):
    """Push (key, node) onto the binary min-heap keys[:size], nodes[:size] (room for it is the
    caller's); the new size."""
    i = size
    keys[i], nodes[i] = key, node
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= keys[i]:
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        nodes[parent], nodes[i] = nodes[i], nodes[parent]
        i = parent
    return size + 1


@njit(cache=True, inline="always")
def heap_pop(keys, nodes, size):
    """Pop the least (key, node) of the binary min-heap keys[:size], nodes[:size] (size > 0):
    (key, node, the new size)."""
    key, node = keys[0], nodes[0]
    size -= 1
    keys[0], nodes[0] = keys[size], nodes[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and keys[c + 1] < keys[c]:
            c += 1
        if keys[i] <= keys[c]:
            break
        keys[i], keys[c] = keys[c], keys[i]
        nodes[i], nodes[c] = nodes[c], nodes[i]
        i = c
    return key, node, size


@njit(cache=True)
def _dijkstra(indptr, neighbours, weights, source, n):
    """Shortest distances from source (weights >= 0 per adjacency entry); a binary heap of
    (distance, node), stale entries skipped."""
    dist = np.full(n, np.inf)
    done = np.zeros(n, dtype=np.bool_)
    keys = np.empty(len(neighbours) + 1)
    nodes = np.empty(len(neighbours) + 1, dtype=np.int64)
    dist[source] = 0.0
    size = heap_push(keys, nodes, 0, 0.0, source)
    while size > 0:
        d, node, size = heap_pop(keys, nodes, size)
        if done[node]:
            continue
        done[node] = True
        for k in range(indptr[node], indptr[node + 1]):
            other = neighbours[k]
            nd = d + weights[k]
            if nd < dist[other]:
                dist[other] = nd
                size = heap_push(keys, nodes, size, nd, other)
    return dist


def shortest_distances(n: int, u: np.ndarray, v: np.ndarray, w: np.ndarray, source: int) -> np.ndarray:
    """(n,) distance from `source` to every node of the undirected graph with edges u[i]-v[i] of
    weight w[i] >= 0 (inf where unreachable). As scipy's `dijkstra(coo_matrix((w, (u, v))),
    directed=False, indices=source)`: repeated (u, v) entries add up, and an edge given both ways
    is the lighter of the two."""
    u, v = np.asarray(u, dtype=np.int64), np.asarray(v, dtype=np.int64)
    # the matrix's entries: repeats of one (row, column) summed
    uniq, inverse = np.unique(u * n + v, return_inverse=True)
    summed = np.bincount(inverse, weights=np.asarray(w, dtype=np.float64), minlength=len(uniq))
    rows, cols = uniq // n, uniq % n
    # both directions; where both exist, the lighter (as a traversal either way would take)
    key = np.concatenate([rows * n + cols, cols * n + rows])
    weight = np.concatenate([summed, summed])
    order = np.lexsort((weight, key))
    key, weight = key[order], weight[order]
    first = np.ones(len(key), dtype=bool)
    first[1:] = key[1:] != key[:-1]
    key, weight = key[first], weight[first]
    src, dst = key // n, key % n
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    return _dijkstra(indptr, dst, weight, int(source), n)
