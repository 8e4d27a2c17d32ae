"""numba kernels of the unfolder: edge weights -> spanning tree (Prim) -> 2D layout -> fitness.

All arrays are plain numpy; nothing here allocates Python objects, so a whole GA generation is
evaluated in one call.
"""

from __future__ import annotations

import numpy as np

from ..collide.flat import all_overlapping_pairs, face_bounds, overlapping_pairs, overlapping_pairs_between
from ..arrays import copy_flat
from ..jit import njit
from ..sorting import sort_in_place


# Prim's heap: parallel arrays (weight, push counter, face, parent, edge) ordered by (weight,
# counter); the counter breaks ties in push order. The order test is written out at each use: as
# a helper (even inlined) it made prim_tree twice as slow.


@njit(cache=True, inline="always")
def _swap(hw, hc, hf, hp, he, a, b):
    hw[a], hw[b] = hw[b], hw[a]
    hc[a], hc[b] = hc[b], hc[a]
    hf[a], hf[b] = hf[b], hf[a]
    hp[a], hp[b] = hp[b], hp[a]
    he[a], he[b] = he[b], he[a]


@njit(cache=True)
def _heap_push(hw, hc, hf, hp, he, size, w, c, f, p, e):
    """Add the entry (w, c, f, p, e) to the heap of `size` entries: the new size."""
    i = size
    hw[i] = w
    hc[i] = c
    hf[i] = f
    hp[i] = p
    he[i] = e
    while i > 0:
        par = (i - 1) >> 1
        if hw[par] < hw[i] or (hw[par] == hw[i] and hc[par] < hc[i]):
            break
        _swap(hw, hc, hf, hp, he, par, i)
        i = par
    return size + 1


@njit(cache=True)
def _heap_pop(hw, hc, hf, hp, he, size):
    """Remove the first entry: its (face, parent, edge) and the new size."""
    f, p, e = hf[0], hp[0], he[0]
    size -= 1
    hw[0], hc[0], hf[0], hp[0], he[0] = hw[size], hc[size], hf[size], hp[size], he[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        m = left
        right = left + 1
        if right < size and (hw[right] < hw[left] or (hw[right] == hw[left] and hc[right] < hc[left])):
            m = right
        if hw[i] < hw[m] or (hw[i] == hw[m] and hc[i] < hc[m]):
            break
        _swap(hw, hc, hf, hp, he, m, i)
        i = m
    return f, p, e, size


@njit(cache=True)
def prim_tree(weights, base, adj_ptr, adj_face, adj_edge, parent, parent_edge, order):
    """Minimum spanning tree of the dual graph from face `base` (Prim, binary heap).

    weights (E,) per mesh edge (low = keep as crease). Fills parent (F,), parent_edge (F,) and
    order (F,) (parents before children). Returns the number of faces reached.
    """
    n = parent.shape[0]
    cap = adj_face.shape[0] + 1
    hw = np.empty(cap)
    hc = np.empty(cap, dtype=np.int64)
    hf = np.empty(cap, dtype=np.int64)
    hp = np.empty(cap, dtype=np.int64)
    he = np.empty(cap, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    size = np.int64(0)  # (int64 from the start: a literal 0 compiled the heap's helpers twice)
    counter = np.int64(0)
    parent[base] = -1
    parent_edge[base] = -1
    done[base] = True
    order[0] = base
    reached = 1
    for k in range(adj_ptr[base], adj_ptr[base + 1]):
        size = _heap_push(hw, hc, hf, hp, he, size, weights[adj_edge[k]], counter, adj_face[k], base, adj_edge[k])
        counter += 1
    while size > 0 and reached < n:
        f, p, e, size = _heap_pop(hw, hc, hf, hp, he, size)
        if done[f]:
            continue
        done[f] = True
        parent[f] = p
        parent_edge[f] = e
        order[reached] = f
        reached += 1
        for k in range(adj_ptr[f], adj_ptr[f + 1]):
            g = adj_face[k]
            if not done[g]:
                size = _heap_push(hw, hc, hf, hp, he, size, weights[adj_edge[k]], counter, g, f, adj_edge[k])
                counter += 1
    return reached


@njit(cache=True)
def layout_tree(order, parent, parent_edge, faces, face_edges, local, out):
    """Lay out every face of the tree in the plane: out (F, 3, 2).

    local (F, 3, 2) is each triangle in its own frame (CCW). The base face keeps its local frame;
    each child is rotated and translated so that its crease corners land exactly on the parent's.
    """
    base = order[0]
    for c in range(3):
        out[base, c, 0] = local[base, c, 0]
        out[base, c, 1] = local[base, c, 1]
    place_children(order[1:], parent, parent_edge, faces, face_edges, local, out)


@njit(cache=True)
def place_children(order, parent, parent_edge, faces, face_edges, local, out):
    """Lay out the faces of `order` (F',) in turn, each from its parent's corners in out (F, 3, 2):
    the parent of each must be placed already (earlier in `order`, or before the call)."""
    for idx in range(order.shape[0]):
        f = order[idx]
        p = parent[f]
        e = parent_edge[f]
        k = 0
        for m in range(3):
            if face_edges[f, m] == e:
                k = m
        i = k
        j = (k + 1) % 3
        vi = faces[f, i]
        vj = faces[f, j]
        pi_x = 0.0
        pi_y = 0.0
        pj_x = 0.0
        pj_y = 0.0
        for m in range(3):
            if faces[p, m] == vi:
                pi_x = out[p, m, 0]
                pi_y = out[p, m, 1]
            elif faces[p, m] == vj:
                pj_x = out[p, m, 0]
                pj_y = out[p, m, 1]
        # rotation r = (P_j - P_i) / (L_j - L_i) as a unit complex number
        dlx = local[f, j, 0] - local[f, i, 0]
        dly = local[f, j, 1] - local[f, i, 1]
        dwx = pj_x - pi_x
        dwy = pj_y - pi_y
        rx = dwx * dlx + dwy * dly
        ry = dwy * dlx - dwx * dly
        rn = np.sqrt(rx * rx + ry * ry)
        rx /= rn
        ry /= rn
        for c in range(3):
            if c == i:
                out[f, c, 0] = pi_x
                out[f, c, 1] = pi_y
            elif c == j:
                out[f, c, 0] = pj_x
                out[f, c, 1] = pj_y
            else:
                lx = local[f, c, 0] - local[f, i, 0]
                ly = local[f, c, 1] - local[f, i, 1]
                out[f, c, 0] = pi_x + rx * lx - ry * ly
                out[f, c, 1] = pi_y + ry * lx + rx * ly


@njit(cache=True)
def local_overlaps(pairs, face_edges, edges, hyperbolic):
    """Paper's local overlap count L: overlapping pairs that share a (cut) edge, counted once per
    hyperbolic endpoint of that edge."""
    total = 0
    for r in range(pairs.shape[0]):
        f = pairs[r, 0]
        g = pairs[r, 1]
        for a in range(3):
            ea = face_edges[f, a]
            for b in range(3):
                if face_edges[g, b] == ea:
                    if hyperbolic[edges[ea, 0]]:
                        total += 1
                    if hyperbolic[edges[ea, 1]]:
                        total += 1
    return total


@njit(cache=True)
def tree_arrays(n):
    """Room for one spanning tree of n faces and its layout: (parent, parent_edge, order (n,),
    coords (n, 3, 2)), uninitialised."""
    return np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64), np.empty((n, 3, 2))


@njit(cache=True)
def evaluate_batch(weights, base, adj_ptr, adj_face, adj_edge, faces, face_edges, edges, hyperbolic, local, tol, max_pairs):
    """Decode and score a batch of genomes (B, E): returns global overlaps G (B,) and local L (B,)."""
    nb = weights.shape[0]
    nf = faces.shape[0]
    G = np.zeros(nb, dtype=np.int64)
    L = np.zeros(nb, dtype=np.int64)
    parent, parent_edge, order, tris = tree_arrays(nf)
    for b in range(nb):
        prim_tree(weights[b], base, adj_ptr, adj_face, adj_edge, parent, parent_edge, order)
        layout_tree(order, parent, parent_edge, faces, face_edges, local, tris)
        count, pairs = overlapping_pairs(tris, parent, tol, max_pairs)
        G[b] = count
        L[b] = local_overlaps(pairs, face_edges, edges, hyperbolic)
    return G, L


@njit(cache=True)
def tree_from_creases(crease, base, adj_ptr, adj_face, adj_edge, parent, parent_edge, order):
    """BFS over crease edges from `base`: fills parent, parent_edge, order (faces not reached:
    parent -2); returns faces reached."""
    n = parent.shape[0]
    for f in range(n):
        parent[f] = -2
    parent[base] = -1
    parent_edge[base] = -1
    order[0] = base
    reached = np.zeros(n, dtype=np.int64)
    reached[base] = 1
    return crease_bfs(crease, np.ones(n, dtype=np.bool_), reached, np.int64(1), adj_ptr, adj_face, adj_edge, parent,
                      parent_edge, order, np.int64(0))


@njit(cache=True)
def crease_bfs(crease, inside, mark, stamp, adj_ptr, adj_face, adj_edge, parent, parent_edge, order, head):
    """BFS over crease edges from order[head] (marked: mark[f] == stamp) through the faces with
    `inside` not yet marked: each one's parent and parent_edge set, appended to order. Returns the
    end of order."""
    tail = head + 1
    while head < tail:
        f = order[head]
        head += 1
        for k in range(adj_ptr[f], adj_ptr[f + 1]):
            g = adj_face[k]
            if crease[adj_edge[k]] and inside[g] and mark[g] != stamp:
                mark[g] = stamp
                parent[g] = f
                parent_edge[g] = adj_edge[k]
                order[tail] = g
                tail += 1
    return tail


@njit(cache=True)
def _score(pairs, count, face_edges, edges, hyperbolic):
    return count + 100 * local_overlaps(pairs, face_edges, edges, hyperbolic)


# Share of moves that glue back a cut edge at an end of the crease just cut, when there is one:
# the subtree turns about that vertex by a few faces' angles, a small step, where a cut edge
# anywhere on the boundary swings it far. Seeds 1-8 at 20 s, median / max seconds to a single net:
# subdivided horse (1,208 faces) 1.05 / 4.4 s with none, 0.25 / 1.45 with half, 0.31 / 0.93 with
# 0.8, 3.8 / 8.6 with all; noisy sphere sigma 0.12 1.8 / 7.6, 1.45 / 5.2, 1.7 / 6.7, no net on 7 of 8.
NEAR_MOVES = 0.5


# New overlapping pairs across a move, past those it removes, at which `local_search` stops testing
# and judges the move on that lower bound of its score: at temperature 0.5 such a move is taken with
# probability at most exp(-10) (then every pair is tested after all). 5,120 faces: 206 -> 97 us an
# iteration from steepest-edge trees (the moves that swing a subtree far meet hundreds of faces).
SURE_REJECT = 5


@njit(cache=True)
def _accepts(delta, u, temperature):
    """The local search's Metropolis test of a move that changes the score by delta, with the
    uniform draw u in [0, 1): a move that does not make the score grow always, else with
    probability exp(-delta / temperature)."""
    return delta <= 0 or (temperature > 0 and u < np.exp(-delta / temperature))


@njit(cache=True)
def local_search(crease, merged, base, adj_ptr, adj_face, adj_edge, edge_faces, faces, face_edges, edges, hyperbolic,
                 local, tol, iterations, seed, temperature, sure_reject):
    """Edge-swap local search on the spanning tree (in place on `crease`, a bool mask per edge).

    A move picks an overlapping pair, a crease on the tree path between the two faces that is not
    merged (merged (E,): edges inside flat regions, never cut), and a cut edge that is not merged
    and reconnects the two halves (half the time, when there is one, a cut edge at an end of the
    cut crease: `NEAR_MOVES`); it is kept when the score (G + 100 L) does not grow, or with
    probability exp(-delta / temperature). Returns (best score, iterations done); `crease` holds
    the best tree seen.

    A move turns the subtree it detaches as one rigid body, so only pairs across the subtree's
    boundary can change: those are re-tested (`overlapping_pairs_between`) and the pairs on either
    side carried over. A score of 0 is confirmed by testing every pair. A move that finds
    sure_reject (>= 1) more new pairs than it removes is judged on that lower bound of its score,
    unless the Metropolis draw would take it even so (`SURE_REJECT`): the same result as testing
    every pair of every move.
    """
    np.random.seed(seed)
    n = faces.shape[0]
    n_e = edges.shape[0]
    parent, parent_edge, order, tris = tree_arrays(n)
    depth = np.empty(n, dtype=np.int64)
    in_sub = np.empty(n, dtype=np.bool_)
    sub = np.empty(n, dtype=np.int64)
    saved = np.empty((n, 3, 2))
    saved_parent = np.empty(n, dtype=np.int64)
    saved_edge = np.empty(n, dtype=np.int64)
    new_order = np.empty(n, dtype=np.int64)
    hung = np.full(n, -1, dtype=np.int64)
    xmin = np.empty(n)
    xmax = np.empty(n)
    ymin = np.empty(n)
    ymax = np.empty(n)
    best_crease = crease.copy()
    tree_from_creases(crease, base, adj_ptr, adj_face, adj_edge, parent, parent_edge, order)
    layout_tree(order, parent, parent_edge, faces, face_edges, local, tris)
    face_bounds(tris, order, xmin, xmax, ymin, ymax)
    pairs = all_overlapping_pairs(tris, parent, tol)
    score = _score(pairs, pairs.shape[0], face_edges, edges, hyperbolic)
    best = score
    it = 0
    path = np.empty(n, dtype=np.int64)
    saved_depth = np.empty(n, dtype=np.int64)
    # only the faces a move turns change depth: theirs are updated with them (restored when the
    # move is turned down), not every face's recomputed at every move
    tree_depths(parent, order, depth)
    pos = np.empty(n, dtype=np.int64)  # each face's place in `order`
    for idx in range(n):
        pos[order[idx]] = idx
    candidates = np.empty(n_e, dtype=np.int64)
    while it < iterations and best > 0:
        it += 1
        npairs = pairs.shape[0]
        if npairs == 0:
            break
        r = np.random.randint(npairs)
        f = pairs[r, 0]
        g = pairs[r, 1]
        plen = tree_path(f, g, parent, depth, path, 0)
        free = 0  # the path's creases that may be cut, moved to its front
        for k in range(plen):
            if not merged[parent_edge[path[k]]]:
                path[free] = path[k]
                free += 1
        if free == 0:  # the two faces are in one flat region: no move separates them
            continue
        x = path[np.random.randint(free)]
        c = parent_edge[x]
        # faces of the subtree under x
        in_sub[:] = False
        in_sub[x] = True
        n_sub = 0
        px = pos[x]
        for idx in range(px, n):  # (no face of the subtree comes before x in `order`)
            y = order[idx]
            if y == x or (parent[y] >= 0 and in_sub[parent[y]]):
                in_sub[y] = True
                sub[n_sub] = y
                n_sub += 1
        # reservoir-sample a reconnecting cut edge, and one at an end of c (NEAR_MOVES), in edge
        # order: from the edges of the subtree's faces, sorted (each edge that reconnects has one
        # face in the subtree), when their 3 n_sub, sort included, cost less than a pass over
        # every edge (12 n_sub < E), else from every edge
        n_cand = np.int64(0)
        from_sub = 12 * n_sub < n_e
        if from_sub:
            for idx in range(n_sub):
                for k in range(3):
                    e = face_edges[sub[idx], k]
                    f0 = edge_faces[e, 0]
                    f1 = edge_faces[e, 1]
                    if f0 >= 0 and f1 >= 0 and in_sub[f0] != in_sub[f1]:
                        candidates[n_cand] = e
                        n_cand += 1
            sort_in_place(candidates[:n_cand])
        pick = np.int64(-1)  # (not a literal: see prim_tree's size)
        seen = 0
        near_pick = np.int64(-1)
        near_seen = 0
        for ci in range(n_cand if from_sub else n_e):
            e = candidates[ci] if from_sub else ci
            if crease[e] or e == c or merged[e]:
                continue
            f0 = edge_faces[e, 0]
            f1 = edge_faces[e, 1]
            if f0 < 0 or f1 < 0:
                continue
            if in_sub[f0] != in_sub[f1]:
                seen += 1
                if np.random.randint(seen) == 0:
                    pick = e
                if (edges[e, 0] == edges[c, 0] or edges[e, 0] == edges[c, 1] or edges[e, 1] == edges[c, 0]
                        or edges[e, 1] == edges[c, 1]):
                    near_seen += 1
                    if np.random.randint(near_seen) == 0:
                        near_pick = e
        if near_pick >= 0 and np.random.random() < NEAR_MOVES:
            pick = near_pick
        if pick < 0:
            continue
        crease[c] = False
        crease[pick] = True
        # Re-hang the subtree from the new crease (a BFS from its end of `pick`, placed after the
        # other faces, whose parents and exact coordinates do not change) and lay out only it.
        moved = sub[:n_sub]
        for f in moved:
            for k in range(3):
                saved[f, k, 0] = tris[f, k, 0]
                saved[f, k, 1] = tris[f, k, 1]
            saved_parent[f] = parent[f]
            saved_edge[f] = parent_edge[f]
            saved_depth[f] = depth[f]
        n_rest = _rehang(pick, in_sub, order, new_order, parent, parent_edge, crease, edge_faces, adj_ptr, adj_face,
                         adj_edge, hung, it, px)
        tree_depths(parent, new_order[n_rest:], depth)  # (the subtree hangs from a face outside it)
        place_children(new_order[n_rest:], parent, parent_edge, faces, face_edges, local, tris)
        face_bounds(tris, moved, xmin, xmax, ymin, ymax)
        keep = np.empty(npairs, dtype=np.bool_)
        for q in range(npairs):
            keep[q] = in_sub[pairs[q, 0]] == in_sub[pairs[q, 1]]
        gone = pairs[~keep]
        gone_score = _score(gone, gone.shape[0], face_edges, edges, hyperbolic)
        # A move that swings a subtree far meets hundreds of faces, and testing them all was most
        # of an iteration's time: the pairs across are found up to a number (each adds at least 1
        # to the score) past which the move is almost surely turned down. Only then is the
        # Metropolis number drawn (delta > 0 for certain: where the old search drew it too), and
        # only if it would still take the move are the rest found; so the same moves, the same
        # random stream and the same trees as testing every pair.
        limit = np.int64(gone_score + sure_reject)
        across = overlapping_pairs_between(tris, parent, moved, new_order[:n_rest], xmin, xmax, ymin, ymax, tol,
                                           limit)
        drawn = across.shape[0] >= limit  # delta >= sure_reject > 0: the draw is due now
        u = np.random.random() if drawn and temperature > 0 else 1.0
        turned_down = drawn and not _accepts(limit - gone_score, u, temperature)
        if turned_down:
            new_score = score + limit - gone_score  # (a lower bound of its score)
            new_pairs = pairs
        else:
            if drawn:  # taken even so (about 1 in 20,000 of them): every pair after all
                across = overlapping_pairs_between(tris, parent, moved, new_order[:n_rest], xmin, xmax, ymin, ymax,
                                                   tol, np.int64(2**62))
            new_pairs = np.concatenate((pairs[keep], across))
            new_score = score - gone_score + _score(across, across.shape[0], face_edges, edges, hyperbolic)
            if new_score == 0:  # confirmed on every pair before the search stops on it
                new_pairs = all_overlapping_pairs(tris, parent, tol)
                new_score = _score(new_pairs, new_pairs.shape[0], face_edges, edges, hyperbolic)
        delta = new_score - score
        if delta > 0 and not drawn and temperature > 0:
            u = np.random.random()
        if _accepts(delta, u, temperature):
            score = new_score
            pairs = new_pairs
            order, new_order = new_order, order
            for idx in range(px, n):  # (the faces before x keep their places)
                pos[order[idx]] = idx
            if score < best:
                best = score
                for e in range(crease.shape[0]):  # (element by element: an array assignment compiles
                    best_crease[e] = crease[e]    # numba's shape-mismatch error, 3 s of a first run)
        else:
            crease[c] = True
            crease[pick] = False
            for f in moved:
                for k in range(3):
                    tris[f, k, 0] = saved[f, k, 0]
                    tris[f, k, 1] = saved[f, k, 1]
                parent[f] = saved_parent[f]
                parent_edge[f] = saved_edge[f]
                depth[f] = saved_depth[f]
            face_bounds(tris, moved, xmin, xmax, ymin, ymax)
    for e in range(crease.shape[0]):
        crease[e] = best_crease[e]
    return best, it


@njit(cache=True)
def _rehang(pick, in_sub, order, new_order, parent, parent_edge, crease, edge_faces, adj_ptr, adj_face, adj_edge,
            hung, stamp, first):
    """Hang the subtree (in_sub) from the crease `pick` that now joins it to the other faces: its
    faces' parents by a BFS over creases from its end of `pick` (hung[f] = stamp marks those
    reached). new_order: the other faces in `order`'s order, then the subtree's in BFS order (parents
    first). first: no face of the subtree comes before order[first] (its top's place). Returns the
    number of other faces."""
    hang = edge_faces[pick, 0] if in_sub[edge_faces[pick, 0]] else edge_faces[pick, 1]
    copy_flat(new_order, order, first)
    n_rest = np.int64(first)  # (not a literal: see prim_tree's size)
    for idx in range(first, order.shape[0]):
        if not in_sub[order[idx]]:
            new_order[n_rest] = order[idx]
            n_rest += 1
    parent[hang] = edge_faces[pick, 0] + edge_faces[pick, 1] - hang
    parent_edge[hang] = pick
    hung[hang] = stamp
    new_order[n_rest] = hang
    crease_bfs(crease, in_sub, hung, stamp, adj_ptr, adj_face, adj_edge, parent, parent_edge, new_order, n_rest)
    return n_rest


@njit(cache=True)
def tree_depths(parent, order, depth):
    """Fill depth (F,) for the faces of `order`: each one's number of creases below its root (roots
    0). A face's parent must precede it in `order`, or lie outside it with its depth set."""
    for idx in range(order.shape[0]):
        f = order[idx]
        depth[f] = depth[parent[f]] + 1 if parent[f] >= 0 else 0


@njit(cache=True)
def tree_path(a, b, parent, depth, out, k):
    """Write the creases of the tree path between faces a and b (same tree) to out[k:], each
    named by its child face, climbing from the deeper end: the index after the last one written."""
    while a != b:
        if depth[a] >= depth[b]:
            out[k] = a
            a = parent[a]
        else:
            out[k] = b
            b = parent[b]
        k += 1
    return k


@njit(cache=True)
def tree_path_ptr(parent, order, pairs, limit):
    """The CSR ptr (P+1,) of `tree_paths` (ptr[-1]: the creases on all paths) without the paths;
    once more than `limit` creases are counted, the ptr so far (its last entry over `limit`)."""
    depth = np.empty(parent.shape[0], dtype=np.int64)
    tree_depths(parent, order, depth)
    return _path_ptr(parent, depth, pairs, limit)


@njit(cache=True)
def _path_ptr(parent, depth, pairs, limit):
    """`tree_path_ptr` with the faces' depths given."""
    scratch = np.empty(parent.shape[0], dtype=np.int64)  # a path has fewer creases than the tree has faces
    ptr = np.zeros(pairs.shape[0] + 1, dtype=np.int64)
    for r in range(pairs.shape[0]):
        ptr[r + 1] = ptr[r] + tree_path(pairs[r, 0], pairs[r, 1], parent, depth, scratch, 0)
        if ptr[r + 1] > limit:
            return ptr[:r + 2]
    return ptr


@njit(cache=True)
def size_cuts(parent, order, cuttable, block):
    """(F,) bool: creases (named by their child face) that cut a forest into pieces of about
    `block` faces: bottom up, the crease above a face whose uncut subtree has reached `block`
    faces (when `cuttable` allows; a face has at most 3 children, so a piece stays under
    about 3 `block` faces where creases may be cut). Parents must precede children in `order`."""
    n = parent.shape[0]
    size = np.ones(n, dtype=np.int64)
    cut = np.zeros(n, dtype=np.bool_)
    for idx in range(n - 1, -1, -1):
        f = order[idx]
        p = parent[f]
        if p < 0:
            continue
        if size[f] >= block and cuttable[f]:
            cut[f] = True
        else:
            size[p] += size[f]
    return cut


@njit(cache=True)
def tree_paths(parent, order, pairs):
    """Tree paths between the faces of each pair, as CSR (ptr, members); a crease is named by its
    child face. Parents must precede children in `order`."""
    n = parent.shape[0]
    depth = np.empty(n, dtype=np.int64)
    tree_depths(parent, order, depth)
    ptr = _path_ptr(parent, depth, pairs, np.iinfo(np.int64).max)
    members = np.empty(ptr[-1], dtype=np.int64)
    for r in range(pairs.shape[0]):
        tree_path(pairs[r, 0], pairs[r, 1], parent, depth, members, ptr[r])
    return ptr, members


@njit(cache=True)
def greedy_cover(ptr, members, n):
    """Greedy set cover: repeatedly cut the crease on the most uncovered paths. Returns (n,) bool."""
    n_rows = ptr.shape[0] - 1
    count = np.zeros(n, dtype=np.int64)
    for k in range(members.shape[0]):
        count[members[k]] += 1
    # crease -> rows (CSR)
    cptr = np.zeros(n + 1, dtype=np.int64)
    for k in range(members.shape[0]):
        cptr[members[k] + 1] += 1
    for c in range(n):
        cptr[c + 1] += cptr[c]
    fill = cptr[:-1].copy()
    rows_of = np.empty(members.shape[0], dtype=np.int64)
    for r in range(n_rows):
        for k in range(ptr[r], ptr[r + 1]):
            c = members[k]
            rows_of[fill[c]] = r
            fill[c] += 1
    covered = np.zeros(n_rows, dtype=np.bool_)
    chosen = np.zeros(n, dtype=np.bool_)
    left = n_rows
    while left > 0:
        best = np.argmax(count)
        if count[best] <= 0:
            break
        chosen[best] = True
        for k in range(cptr[best], cptr[best + 1]):
            r = rows_of[k]
            if covered[r]:
                continue
            covered[r] = True
            left -= 1
            for m in range(ptr[r], ptr[r + 1]):
                count[members[m]] -= 1
    return chosen


@njit(cache=True)
def decode_tree(weights, base, adj_ptr, adj_face, adj_edge, faces, face_edges, local):
    """Genome (E,) -> (reached, parent, parent_edge, order, coords (F, 3, 2)): Prim's tree and its
    layout. coords is only laid out when every face is reached (reached == F)."""
    n = faces.shape[0]
    parent, parent_edge, order, coords = tree_arrays(n)
    reached = prim_tree(weights, base, adj_ptr, adj_face, adj_edge, parent, parent_edge, order)
    if reached == n:
        layout_tree(order, parent, parent_edge, faces, face_edges, local, coords)
    return reached, parent, parent_edge, order, coords


@njit(cache=True)
def piece_labels(order, parent):
    """Piece (F,) of every face: roots numbered 0, 1, ... in `order` (parents first), every other
    face in its parent's piece."""
    piece = np.full(parent.shape[0], -1, dtype=np.int64)
    count = 0
    for f in order:
        if parent[f] < 0:
            piece[f] = count
            count += 1
        else:
            piece[f] = piece[parent[f]]
    return piece


@njit(cache=True)
def dfs_intervals(parent):
    """Euler-tour (tin, tout) (F,) per face of the forest `parent` (F,) (-1 at roots): roots in
    face order, each face's children in face order; g is in the subtree of f iff
    tin[f] <= tin[g] < tout[f]."""
    n = parent.shape[0]
    first = np.zeros(n + 1, dtype=np.int64)  # children of f: kids[first[f]:first[f + 1]], ascending
    for f in range(n):
        if parent[f] >= 0:
            first[parent[f] + 1] += 1
    for f in range(n):
        first[f + 1] += first[f]
    kids = np.empty(first[n], dtype=np.int64)
    fill = first[:n].copy()
    for f in range(n):
        p = parent[f]
        if p >= 0:
            kids[fill[p]] = f
            fill[p] += 1
    tin = np.zeros(n, dtype=np.int64)
    tout = np.zeros(n, dtype=np.int64)
    stack = np.empty(n, dtype=np.int64)  # faces whose subtree is open; next child to visit in `nxt`
    nxt = np.zeros(n, dtype=np.int64)
    t = 0
    for root in range(n):
        if parent[root] >= 0:
            continue
        top = 0
        stack[0] = root
        tin[root] = t
        t += 1
        nxt[root] = first[root]
        while top >= 0:
            f = stack[top]
            if nxt[f] < first[f + 1]:
                g = kids[nxt[f]]
                nxt[f] += 1
                tin[g] = t
                t += 1
                nxt[g] = first[g]
                top += 1
                stack[top] = g
            else:
                tout[f] = t
                top -= 1
    return tin, tout
