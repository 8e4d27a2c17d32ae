"""numba kernels of the unfolder's set-up and heuristic edge weights (ALGORITHMS.md 5.3).

Small meshes (segmentation parts of a few dozen faces) are unfolded in well under a millisecond,
so the per-mesh arrays are built in one pass and the weight rules that sort per vertex run here
instead of as chains of small numpy calls. Results are bitwise those of the numpy formulas:
ties and orders follow np.lexsort (stable), sums follow numpy's order, and dot products, matrix
products and atan2 are left to numpy (see `mesh.kernels`).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit


@njit(cache=True, error_model="numpy")  # degenerate input gives nan / inf as numpy does
def problem_arrays(vertices, faces, edges, edge_faces, hyperbolic):
    """Arrays of `unfold.UnfoldProblem` that need no numpy-rounded dot products.

    In: vertices (n, 3), faces (F, 3), edges (E, 2), edge_faces (E, 2) of the mesh topology.
    Out: inner (I,) interior edges ascending; the dual graph as CSR adj_ptr (F+1,), adj_face,
    adj_edge (2I,) (each face's entries: the edges where it is face 0, then those where it is
    face 1, both ascending, as a stable argsort of the concatenation); e1, e2 (F, 3) the sides
    from corner 0; frames (F, 3, 2) local frames with |e1| and |e1 x e2| / |e1| filled (the x of
    corner 2 needs a dot product); edge_vec (E, 3) edges[e, 1] - edges[e, 0] and edge_len (E,);
    box (3,) extent of the vertices used by faces (all vertices when there are no faces);
    the number of interior half-edges at hyperbolic vertices (the random-edge rule's first draw).
    """
    n_f = faces.shape[0]
    n_e = edges.shape[0]
    n_i = 0
    for e in range(n_e):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            n_i += 1
    inner = np.empty(n_i, dtype=np.int64)
    n_i = 0
    for e in range(n_e):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            inner[n_i] = e
            n_i += 1
    adj_ptr = np.zeros(n_f + 1, dtype=np.int64)
    for i in range(n_i):
        adj_ptr[edge_faces[inner[i], 0] + 1] += 1
        adj_ptr[edge_faces[inner[i], 1] + 1] += 1
    for f in range(n_f):
        adj_ptr[f + 1] += adj_ptr[f]
    fill = adj_ptr[:-1].copy()
    adj_face = np.empty(2 * n_i, dtype=np.int64)
    adj_edge = np.empty(2 * n_i, dtype=np.int64)
    for side in range(2):
        for i in range(n_i):
            e = inner[i]
            f = edge_faces[e, side]
            adj_face[fill[f]] = edge_faces[e, 1 - side]
            adj_edge[fill[f]] = e
            fill[f] += 1
    e1, e2, frames = frame_parts(vertices, faces)
    edge_vec = np.empty((n_e, 3))
    edge_len = np.empty(n_e)
    for e in range(n_e):
        for i in range(3):
            edge_vec[e, i] = vertices[edges[e, 1], i] - vertices[edges[e, 0], i]
        edge_len[e] = np.sqrt(edge_vec[e, 0] * edge_vec[e, 0] + edge_vec[e, 1] * edge_vec[e, 1]
                              + edge_vec[e, 2] * edge_vec[e, 2])
    box = _used_extent(vertices, faces)
    return inner, adj_ptr, adj_face, adj_edge, e1, e2, frames, edge_vec, edge_len, box, incident_count(inner, edges, hyperbolic)


@njit(cache=True, error_model="numpy")
def frame_parts(vertices, faces):
    """Sides e1, e2 (F, 3) from corner 0 and the local frames (F, 3, 2) of `unfold.local_frames`
    with all but the x of corner 2 filled (that one is e1 . e2 / |e1|, a numpy dot product)."""
    n_f = faces.shape[0]
    e1 = np.empty((n_f, 3))
    e2 = np.empty((n_f, 3))
    frames = np.zeros((n_f, 3, 2))
    for f in range(n_f):
        a = faces[f, 0]
        for i in range(3):
            e1[f, i] = vertices[faces[f, 1], i] - vertices[a, i]
            e2[f, i] = vertices[faces[f, 2], i] - vertices[a, i]
        l1 = np.sqrt(e1[f, 0] * e1[f, 0] + e1[f, 1] * e1[f, 1] + e1[f, 2] * e1[f, 2])
        # the component formulas of np.cross, then the row norm in numpy's order
        cx = e1[f, 1] * e2[f, 2] - e1[f, 2] * e2[f, 1]
        cy = e1[f, 2] * e2[f, 0] - e1[f, 0] * e2[f, 2]
        cz = e1[f, 0] * e2[f, 1] - e1[f, 1] * e2[f, 0]
        frames[f, 1, 0] = l1
        frames[f, 2, 1] = np.sqrt(cx * cx + cy * cy + cz * cz) / l1
    return e1, e2, frames


@njit(cache=True, error_model="numpy")
def _used_extent(vertices, faces):
    """max - min (3,) over the vertices used by faces (all of them without faces), nan-propagating
    like ndarray.max / min."""
    n_v = vertices.shape[0]
    used = np.zeros(n_v, dtype=np.bool_)
    if faces.shape[0] == 0:
        used[:] = True
    for f in range(faces.shape[0]):
        for k in range(3):
            used[faces[f, k]] = True
    box = np.zeros(3)
    for i in range(3):
        lo = np.inf
        hi = -np.inf
        nan = False
        for v in range(n_v):
            if used[v]:
                x = vertices[v, i]
                if x != x:
                    nan = True
                lo = min(lo, x)
                hi = max(hi, x)
        box[i] = np.nan if nan else hi - lo
    return box


@njit(cache=True)
def incident_count(inner, edges, want):
    """Number of interior half-edges (edge, endpoint) whose endpoint is in `want` (n,) bool."""
    count = 0
    for end in range(2):
        for i in range(inner.shape[0]):
            if want[edges[inner[i], end]]:
                count += 1
    return count


@njit(cache=True)
def pick_random_incident(inner, edges, want, count, keys, weights, hyperbolic):
    """Set weights[e] = 1 for up to `count` random interior edges e at every vertex in `want`.

    The candidates are the interior half-edges at wanted vertices, all first endpoints then all
    second ones (edge order); keys (candidates,) are their random draws. A vertex takes its
    `count` (1 or 2) smallest keys, ties by candidate position: np.lexsort((keys, vertex)) order.
    Returns the next stage's (want, candidates): the vertices (n,) that are neither hyperbolic
    nor an endpoint of an edge with weight >= 1 now, and their number of candidate half-edges.
    """
    n_v = want.shape[0]
    best_key = np.full((n_v, 2), np.inf)
    best_edge = np.full((n_v, 2), -1, dtype=np.int64)
    j = 0
    for end in range(2):
        for i in range(inner.shape[0]):
            e = inner[i]
            v = edges[e, end]
            if not want[v]:
                continue
            r = keys[j]
            j += 1
            if best_edge[v, 0] < 0 or r < best_key[v, 0]:
                best_key[v, 1] = best_key[v, 0]
                best_edge[v, 1] = best_edge[v, 0]
                best_key[v, 0] = r
                best_edge[v, 0] = e
            elif best_edge[v, 1] < 0 or r < best_key[v, 1]:
                best_key[v, 1] = r
                best_edge[v, 1] = e
    for v in range(n_v):
        for s in range(count):
            if best_edge[v, s] >= 0:
                weights[best_edge[v, s]] = 1.0
    uncut = _uncut_elliptic(edges, weights, hyperbolic)
    return uncut, incident_count(inner, edges, uncut)


@njit(cache=True)
def _uncut_elliptic(edges, weights, hyperbolic):
    """Vertices (n,) bool that are not hyperbolic and not an endpoint of an edge with weight >= 1."""
    out = ~hyperbolic
    for e in range(edges.shape[0]):
        if weights[e] >= 1.0:
            out[edges[e, 0]] = False
            out[edges[e, 1]] = False
    return out


@njit(cache=True)
def steepest_cuts(slope, edges, n_vertices, top, un):
    """Weights (E,): 1 on the edge each vertex but `top` cuts, 0 elsewhere.

    Each vertex v takes, among its directed edges v -> w (score slope[e] when v = edges[e, 0],
    -slope[e] when v = edges[e, 1]; with un=True the score is 1 - |score|), the one with the
    highest score; ties go to the first in the order (all edges as run 0 -> 1, then all as run
    1 -> 0), nan scores lose to any number (np.lexsort((-score, v)) order).
    """
    n_e = edges.shape[0]
    best = np.full(n_vertices, np.nan)
    pick = np.full(n_vertices, -1, dtype=np.int64)
    for end in range(2):
        for e in range(n_e):
            v = edges[e, end]
            s = slope[e] if end == 0 else -slope[e]
            if un:
                s = 1.0 - abs(s)
            if pick[v] < 0 or (s > best[v]) or (best[v] != best[v] and s == s):
                best[v] = s
                pick[v] = e
    w = np.zeros(n_e)
    for v in range(n_vertices):
        if pick[v] >= 0 and v != top:
            w[pick[v]] = 1.0
    return w
