"""numba kernels of `tree.build_tree`: a FOLD net's edge table, crease tree and crease axes.

`net_tree` checks what fold_tree's one-line errors name, in the order fold_tree names them, and
returns an error code with the indices the message needs (OK = 0, info -1 elsewhere); fold_tree
turns the code into the message. Outputs are arguments (returning arrays from numba costs more
than the work on a small net); after an error code they are not meaningful.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..mesh.kernels import fold_deg_to_rho
from ..sorting import stable_argsort

OK = 0
# faces
FACE_OUT_OF_RANGE = 21  # (f): a vertex outside 0..V-1
FACE_REPEAT = 22  # (f): a vertex twice
# edge table
BAD_EDGE = 1  # (e): an endpoint outside 0..V-1, or both endpoints equal
DUPLICATE_EDGE = 2  # (first, second, u, v): two edges join u < v
MISSING_SIDE = 3  # (u, v, f): side u-v of face f is no edge
THIRD_FACE = 4  # (e): edge e borders a third face
CLOCKWISE = 5  # (f)
# crease tree
INVALID_PARENT = 11  # (f, p)
NO_COMMON_EDGE = 12  # (f, p)
CUT_PARENT_EDGE = 13  # (f, p, e)
PIECE_CREASE = 14  # (e, f, g): a crease joins faces of two pieces (BFS tree)
CYCLE = 15  # (f): not below any root
PARENT_PIECE = 16  # (f): the parent is in another piece
PIECE_ROOTS = 17  # (piece, r0, r1): a piece with two roots


@njit(cache=True)
def net_tree(faces, n_v, edges, kind, n_cut, xy, min_area2, parent_in, piece_in, min_len2, mountain, valley, deg,
             stage, info, face_edges, edge_faces, flat, parent, crease, order, piece, axis, short, creases, goal):
    """Everything fold_tree derives from a net's arrays; returns (code, len(short), len(creases),
    first bad fold angle edge or -1, whether it is out of range).

    In: faces (F, 3) (F >= 1), n_v vertices, edges (E, 2), kind (E,) assignment kinds (cuts below
    n_cut), xy (V, 2); parent_in / piece_in (F,) or empty when not given; deg (E,) fold angles in
    degrees or empty. stage: how far the inputs are usable: 1 faces only, 2 + edge table (edges and
    kinds), 3 + crease tree (parents, pieces), 4 + fold angles. Checks, in order: faces (vertex
    range, then repeats, first face each), the edge table and clockwise faces (`_side_table`), the
    crease tree (`_crease_tree`), and the fold angles (`_fold_angle_errors`, reported separately:
    fold_tree checks zero-length creases before them). Fills info (4,), face_edges (F, 3),
    edge_faces (E, 2), flat (F, 3, 3), parent, crease, order, piece, short, creases (F,), axis
    (F, 2) and, at stage 4, goal (E,) (-radians(deg), 0 on the cuts).
    """
    info[:] = -1
    for f in range(faces.shape[0]):
        a = faces[f, 0]
        b = faces[f, 1]
        c = faces[f, 2]
        if min(a, b, c) < 0 or max(a, b, c) >= n_v:
            info[0] = f
            return FACE_OUT_OF_RANGE, 0, 0, -1, False
    for f in range(faces.shape[0]):
        if faces[f, 0] == faces[f, 1] or faces[f, 1] == faces[f, 2] or faces[f, 2] == faces[f, 0]:
            info[0] = f
            return FACE_REPEAT, 0, 0, -1, False
    if stage < 2:
        return OK, 0, 0, -1, False
    code = _side_table(faces, edges, n_v, xy, min_area2, info, face_edges, edge_faces, flat)
    if code != OK or stage < 3:
        return code, 0, 0, -1, False
    code, n_short, n_creases = _crease_tree(faces, edges, face_edges, edge_faces, kind, n_cut, parent_in,
                                            parent_in.shape[0] > 0, piece_in, piece_in.shape[0] > 0, xy, min_len2,
                                            info, parent, crease, order, piece, axis, short, creases)
    if code != OK or stage < 4:
        return code, n_short, n_creases, -1, False
    bad, out_of_range = _fold_angle_errors(deg, kind, n_cut, mountain, valley, goal)
    return OK, n_short, n_creases, bad, out_of_range


@njit(cache=True)
def _side_table(faces, edges, n_v, xy, min_area2, info, face_edges, edge_faces, flat):
    """Edge table of a net; returns the error code, fills info (4,), face_edges (F, 3), edge_faces
    (E, 2) and flat (F, 3, 3).

    faces (F, 3) with vertices in range; edges (E, 2); xy (V, 2) flat coordinates. face_edges[f, k]
    is the edge of side corner k -> k+1; edge_faces[e] the faces of edge e in face order (-1 when
    missing); flat the corners at z = 0. Checks, in this order: edge endpoints, duplicate edges
    (the first repeat in edge order), sides that are no edge and third faces (in face / side
    order), then clockwise faces (twice the signed area < min_area2, numpy's formula).
    """
    n_f = faces.shape[0]
    n_e = edges.shape[0]
    face_edges[:] = -1
    edge_faces[:] = -1
    for e in range(n_e):
        u = edges[e, 0]
        v = edges[e, 1]
        if min(u, v) < 0 or max(u, v) >= n_v or u == v:
            info[0] = e
            return BAD_EDGE
    # edges in buckets by their lower vertex (CSR, edge order within a bucket): the sides' lookup
    start = np.zeros(n_v + 1, dtype=np.int64)
    for e in range(n_e):
        start[min(edges[e, 0], edges[e, 1]) + 1] += 1
    for v in range(n_v):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    bucket = np.empty(n_e, dtype=np.int64)
    for e in range(n_e):
        lo = min(edges[e, 0], edges[e, 1])
        hi = max(edges[e, 0], edges[e, 1])
        for r in range(start[lo], fill[lo]):  # the earlier edges at lo: the first repeat is named
            g = bucket[r]
            if max(edges[g, 0], edges[g, 1]) == hi:
                info[0] = g
                info[1] = e
                info[2] = lo
                info[3] = hi
                return DUPLICATE_EDGE
        bucket[fill[lo]] = e
        fill[lo] += 1
    for f in range(n_f):
        for k in range(3):
            u = faces[f, k]
            v = faces[f, (k + 1) % 3]
            lo = min(u, v)
            hi = max(u, v)
            e = -1
            for r in range(start[lo], start[lo + 1]):
                if max(edges[bucket[r], 0], edges[bucket[r], 1]) == hi:
                    e = bucket[r]
                    break
            if e < 0:
                info[0] = u
                info[1] = v
                info[2] = f
                return MISSING_SIDE
            face_edges[f, k] = e
            if edge_faces[e, 0] < 0:
                edge_faces[e, 0] = f
            elif edge_faces[e, 1] < 0:
                edge_faces[e, 1] = f
            else:
                info[0] = e
                return THIRD_FACE
    for f in range(n_f):
        for k in range(3):
            flat[f, k, 0] = xy[faces[f, k], 0]
            flat[f, k, 1] = xy[faces[f, k], 1]
            flat[f, k, 2] = 0.0
    for f in range(n_f):
        area2 = ((flat[f, 1, 0] - flat[f, 0, 0]) * (flat[f, 2, 1] - flat[f, 0, 1])
                 - (flat[f, 1, 1] - flat[f, 0, 1]) * (flat[f, 2, 0] - flat[f, 0, 0]))
        if area2 < min_area2:
            info[0] = f
            return CLOCKWISE
    return OK


@njit(cache=True)
def _parent_creases(parent, face_edges, cut, crease, info):
    """Crease of every face to its given parent (first side of f that is a side of p)."""
    n_f = parent.shape[0]
    for f in range(n_f):
        p = parent[f]
        if p < -1 or p >= n_f or p == f:
            info[0] = f
            info[1] = p
            return INVALID_PARENT
        if p < 0:
            continue
        common = -1
        for k in range(3):
            e = face_edges[f, k]
            if e == face_edges[p, 0] or e == face_edges[p, 1] or e == face_edges[p, 2]:
                common = e
                break
        if common < 0:
            info[0] = f
            info[1] = p
            return NO_COMMON_EDGE
        if cut[common]:
            info[0] = f
            info[1] = p
            info[2] = common
            return CUT_PARENT_EDGE
        crease[f] = common
    return OK


@njit(cache=True)
def _bfs_creases(edge_faces, cut, piece_in, has_piece, parent, crease, info):
    """BFS over the creases from the lowest unvisited face; neighbours in edge order."""
    n_f = parent.shape[0]
    n_e = edge_faces.shape[0]
    ptr = np.zeros(n_f + 1, dtype=np.int64)
    for e in range(n_e):
        if edge_faces[e, 1] >= 0 and not cut[e]:
            ptr[edge_faces[e, 0] + 1] += 1
            ptr[edge_faces[e, 1] + 1] += 1
    for f in range(n_f):
        ptr[f + 1] += ptr[f]
    fill = ptr[:-1].copy()
    nb_face = np.empty(ptr[n_f], dtype=np.int64)
    nb_edge = np.empty(ptr[n_f], dtype=np.int64)
    for e in range(n_e):
        if edge_faces[e, 1] >= 0 and not cut[e]:
            for s in range(2):
                f = edge_faces[e, s]
                nb_face[fill[f]] = edge_faces[e, 1 - s]
                nb_edge[fill[f]] = e
                fill[f] += 1
    seen = np.zeros(n_f, dtype=np.bool_)
    queue = np.empty(n_f, dtype=np.int64)
    for root in range(n_f):
        if seen[root]:
            continue
        seen[root] = True
        queue[0] = root
        head = 0
        tail = 1
        while head < tail:
            f = queue[head]
            head += 1
            for r in range(ptr[f], ptr[f + 1]):
                g = nb_face[r]
                if seen[g]:
                    continue
                if has_piece and piece_in[g] != piece_in[f]:
                    info[0] = nb_edge[r]
                    info[1] = f
                    info[2] = g
                    return PIECE_CREASE
                seen[g] = True
                parent[g] = f
                crease[g] = nb_edge[r]
                queue[tail] = g
                tail += 1
    return OK


@njit(cache=True)
def _crease_tree(faces, edges, face_edges, edge_faces, kind, n_cut, parent_in, has_parent, piece_in, has_piece, xy,
                min_len2, info, parent, crease, order, piece, axis, short, creases):
    """The crease tree of a net; returns (error code, len(short), len(creases)) and fills info (3,),
    parent, crease, order, piece (F,), axis (F, 2), short and creases (F,, the first entries).

    kind (E,): assignment kind of every edge, cuts below n_cut. parent_in (F,) the given parents (has_parent), else a BFS over the non-cut edges; piece_in
    (F,) the given pieces (has_piece), else one per tree. order (F,) BFS from the roots (ascending),
    children in face order; axis (F, 2) the parent's corners at the crease ends, a -> b in its CCW
    order (-1 at roots); short: the faces (ascending) whose crease may be shorter than fold_tree's
    limit (squared xy length not above min_len2), for an exact check by the caller; creases: the
    tree's creases ascending. Checks, in this
    order: the given parents (range, common edge, cut edge) or the BFS's pieces, cycles, then the
    given pieces (parent in another piece, two roots in one piece).
    """
    n_f = faces.shape[0]
    n_e = edges.shape[0]
    cut = np.empty(n_e, dtype=np.bool_)
    for e in range(n_e):
        cut[e] = kind[e] < n_cut
    crease[:] = -1
    piece[:] = -1
    axis[:] = -1
    if has_parent:
        for f in range(n_f):  # (element by element: an array assignment compiles numba's shape-mismatch
            parent[f] = parent_in[f]  # error, 2-3 s of a first run)
        code = _parent_creases(parent, face_edges, cut, crease, info)
    else:
        parent[:] = -1
        code = _bfs_creases(edge_faces, cut, piece_in, has_piece, parent, crease, info)
    if code != OK:
        return code, 0, 0
    # children lists (CSR, face order) and the BFS order from the roots
    ptr = np.zeros(n_f + 1, dtype=np.int64)
    for f in range(n_f):
        if parent[f] >= 0:
            ptr[parent[f] + 1] += 1
    for f in range(n_f):
        ptr[f + 1] += ptr[f]
    fill = ptr[:-1].copy()
    children = np.empty(ptr[n_f], dtype=np.int64)
    for f in range(n_f):
        if parent[f] >= 0:
            children[fill[parent[f]]] = f
            fill[parent[f]] += 1
    tree_of = np.full(n_f, -1, dtype=np.int64)
    n_roots = 0
    tail = 0
    for root in range(n_f):
        if parent[root] >= 0:
            continue
        tree_of[root] = root
        piece[root] = n_roots
        n_roots += 1
        head = tail
        order[tail] = root
        tail += 1
        while head < tail:
            f = order[head]
            head += 1
            for r in range(ptr[f], ptr[f + 1]):
                g = children[r]
                tree_of[g] = root
                piece[g] = piece[root]
                order[tail] = g
                tail += 1
    if tail != n_f:
        for f in range(n_f):
            if tree_of[f] < 0:
                info[0] = f
                break
        return CYCLE, 0, 0
    if has_piece:
        for f in range(n_f):
            piece[f] = piece_in[f]
        for f in range(n_f):
            if parent[f] >= 0 and piece[f] != piece[parent[f]]:
                info[0] = f
                return PARENT_PIECE, 0, 0
        roots = np.flatnonzero(parent < 0)
        by_piece = stable_argsort(piece[roots])  # a piece's roots stay ascending
        for r in range(1, roots.shape[0]):
            a = roots[by_piece[r - 1]]
            b = roots[by_piece[r]]
            if piece[a] == piece[b]:  # the first such pair: the lowest piece, its two lowest roots
                info[0] = piece[a]
                info[1] = a
                info[2] = b
                return PIECE_ROOTS, 0, 0
    n_short = 0
    is_crease = np.zeros(n_e, dtype=np.bool_)
    for f in range(n_f):
        p = parent[f]
        if p < 0:
            continue
        is_crease[crease[f]] = True
        u = edges[crease[f], 0]
        v = edges[crease[f], 1]
        k = 0
        while faces[p, k] != u:
            k += 1
        kv = 0
        while faces[p, kv] != v:
            kv += 1
        if (k + 1) % 3 == kv:
            axis[f, 0] = k
            axis[f, 1] = kv
        else:
            axis[f, 0] = kv
            axis[f, 1] = k
        dx = xy[u, 0] - xy[v, 0]
        dy = xy[u, 1] - xy[v, 1]
        d2 = dx * dx + dy * dy
        if not (d2 > min_len2 and d2 > 1e-280):  # tiny squares lose precision: leave them to the exact check
            short[n_short] = f
            n_short += 1
    n_creases = 0
    for e in range(n_e):  # (a crease joins one child to its parent: no repeats)
        if is_crease[e]:
            creases[n_creases] = e
            n_creases += 1
    return OK, n_short, n_creases


@njit(cache=True)
def extent(pts):
    """max - min (D,) of finite points (V, D), V >= 1."""
    lo = pts[0].copy()
    hi = pts[0].copy()
    for v in range(1, pts.shape[0]):
        for i in range(pts.shape[1]):
            lo[i] = min(lo[i], pts[v, i])
            hi[i] = max(hi[i], pts[v, i])
    return hi - lo


@njit(cache=True)
def _fold_angle_errors(deg, kind, n_cut, mountain, valley, goal):
    """First non-cut edge (kind >= n_cut) whose fold angle deg (E,) is not within [-180, 180] (nan
    and inf included) or has the wrong sign for a mountain (<= 0) / valley (>= 0): (edge, out of
    range), (-1, False) for none. Fills goal (E,): `fold_deg_to_rho(deg)`, 0 on the cut edges."""
    first = -1
    out_of_range = False
    for e in range(deg.shape[0]):
        if kind[e] < n_cut:
            goal[e] = 0.0
            continue
        goal[e] = fold_deg_to_rho(deg[e])
        if first >= 0:
            continue
        d = deg[e]
        if not (abs(d) <= 180.0):
            first = e
            out_of_range = True
        elif (kind[e] == mountain and d > 0) or (kind[e] == valley and d < 0):
            first = e
    return first, out_of_range
