"""numba kernels of `pattern.crease_pattern`: net vertices, piece boxes and net edges of one Net.

Exact operations only (gathers, sums of two numbers, min / max, and `rho_to_fold_deg`, which
rounds as np.degrees), so the pattern is bitwise the one numpy's formulas gave.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..mesh.kernels import rho_to_fold_deg


@njit(cache=True)
def corner_labels(faces, parent, parent_edge, edges):
    """Net vertex (F*3,) of every face corner, numbered in order of first corner (row-major).

    A child's corners at the ends of its crease are joined to its parent's corners there; each
    child corner points to at most one parent corner, so the joins form a forest over the corners
    and a net vertex is one of its trees (found by walking up to the tree's root).
    """
    n = faces.shape[0]
    link = np.arange(3 * n)
    for f in range(n):
        p = parent[f]
        if p < 0:
            continue
        for end in range(2):
            v = edges[parent_edge[f], end]
            kc = 0
            while kc < 2 and faces[f, kc] != v:
                kc += 1
            kp = 0
            while kp < 2 and faces[p, kp] != v:
                kp += 1
            link[3 * f + kc] = 3 * p + kp
    label = np.full(3 * n, -1)
    count = 0
    for c in range(3 * n):
        r = c
        while link[r] != r:
            r = link[r]
        if label[r] < 0:
            label[r] = count
            count += 1
        label[c] = label[r]
    return label


@njit(cache=True, inline="always")
def _extend(lo, hi, i, j, x):
    # min / max that propagate nan, as ndarray.min / max and ufunc.reduceat do
    if x != x or lo[i, j] != lo[i, j]:
        lo[i, j] = np.nan
        hi[i, j] = np.nan
    else:
        lo[i, j] = min(lo[i, j], x)
        hi[i, j] = max(hi[i, j], x)


@njit(cache=True)
def net_vertices(faces, parent, parent_edge, edges, vertices, coords, piece, mv_off):
    """Net vertices of one Net and the boxes the packing needs.

    Out: corner_v (F, 3) net vertex of every corner; mesh_vertex (V,) the mesh vertex of each net
    vertex plus mv_off (its number in the FOLD file); folded (V, 3) its 3D point; extent (3,) max - min of folded; lo, hi (P, 2) the box of
    every piece's flat corners coords (F, 3, 2), pieces 0..max(piece).
    """
    n_f = faces.shape[0]
    label = corner_labels(faces, parent, parent_edge, edges)
    n_v = 0
    for c in range(3 * n_f):
        n_v = max(n_v, label[c] + 1)
    mesh_vertex = np.zeros(n_v, dtype=np.int64)
    for c in range(3 * n_f):
        mesh_vertex[label[c]] = faces[c // 3, c % 3]
    folded = np.empty((n_v, 3))
    box = np.empty((1, 3))
    box_hi = np.empty((1, 3))
    box[0, :] = np.inf
    box_hi[0, :] = -np.inf
    for v in range(n_v):
        for i in range(3):
            folded[v, i] = vertices[mesh_vertex[v], i]
            _extend(box, box_hi, 0, i, folded[v, i])
    extent = np.empty(3)
    for i in range(3):
        extent[i] = box_hi[0, i] - box[0, i]
    n_pieces = 0
    for f in range(n_f):
        n_pieces = max(n_pieces, piece[f] + 1)
    lo = np.full((n_pieces, 2), np.inf)
    hi = np.full((n_pieces, 2), -np.inf)
    for f in range(n_f):
        for k in range(3):
            for i in range(2):
                _extend(lo, hi, piece[f], i, coords[f, k, i])
    return label.reshape(n_f, 3), mesh_vertex + mv_off, folded, extent, lo, hi


@njit(cache=True)
def net_edges(corner_v, n_v, coords, offsets, piece, face_edges, parent, parent_edge, fold_angles, flat_eps,
              v_off, f_off, p_off, e_off):
    """Placed flat coordinates, faces and net edges of one Net, numbered as in the FOLD file.

    In: corner_v (F, 3), n_v net vertices, coords (F, 3, 2), offsets (P, 2) per piece, the mesh's
    face_edges (F, 3) and fold_angles (E,), parent / parent_edge (F,); the numbers of the net's
    first vertex, face, piece and mesh edge in the file. Out: xy (V, 2) net vertex positions;
    faces (F, 3), piece (F,), parent (F,) (-1 at roots); for every net edge (the first face side,
    in side order f*3 + k, of each net vertex pair; a cut mesh edge gives two): its net vertices
    (S, 2), mesh edge (S,), FOLD fold angle (S,) (degrees, valley positive: -degrees(rho) on
    mountains and valleys, 0 elsewhere) and kind (S,) 0 cut, 1 flat (|rho| < flat_eps), 2 mountain
    (rho > 0), 3 valley.
    """
    n_f = corner_v.shape[0]
    xy = np.zeros((n_v, 2))
    faces = np.empty((n_f, 3), dtype=np.int64)
    piece_out = np.empty(n_f, dtype=np.int64)
    parent_out = np.empty(n_f, dtype=np.int64)
    for f in range(n_f):
        piece_out[f] = piece[f] + p_off
        parent_out[f] = parent[f] + f_off if parent[f] >= 0 else -1
        for k in range(3):
            faces[f, k] = corner_v[f, k] + v_off
            for i in range(2):
                xy[corner_v[f, k], i] = coords[f, k, i] + offsets[piece[f], i]
    # the first side of each net vertex pair: sides in buckets by their lower net vertex
    n_s = 3 * n_f
    start = np.zeros(n_v + 1, dtype=np.int64)
    for s in range(n_s):
        start[min(corner_v[s // 3, s % 3], corner_v[s // 3, (s % 3 + 1) % 3]) + 1] += 1
    for v in range(n_v):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    bucket_hi = np.empty(n_s, dtype=np.int64)
    first = np.zeros(n_s, dtype=np.bool_)
    count = 0
    for s in range(n_s):
        u = corner_v[s // 3, s % 3]
        v = corner_v[s // 3, (s % 3 + 1) % 3]
        lo = min(u, v)
        hi = max(u, v)
        seen = False
        for r in range(start[lo], fill[lo]):
            if bucket_hi[r] == hi:
                seen = True
                break
        if not seen:
            bucket_hi[fill[lo]] = hi
            fill[lo] += 1
            first[s] = True
            count += 1
    crease = np.zeros(fold_angles.shape[0], dtype=np.bool_)
    for f in range(n_f):
        if parent_edge[f] >= 0:
            crease[parent_edge[f]] = True
    ev = np.empty((count, 2), dtype=np.int64)
    em = np.empty(count, dtype=np.int64)
    angle = np.zeros(count)
    kind = np.zeros(count, dtype=np.int64)
    j = 0
    for s in range(n_s):
        if not first[s]:
            continue
        f = s // 3
        k = s % 3
        ev[j, 0] = corner_v[f, k] + v_off
        ev[j, 1] = corner_v[f, (k + 1) % 3] + v_off
        e = face_edges[f, k]
        em[j] = e + e_off
        rho = fold_angles[e]  # (not r, the bucket loop's index: compiled ahead of time, numba types them as one)
        if crease[e]:
            kind[j] = 1 if abs(rho) < flat_eps else (2 if rho > 0 else 3)
        if kind[j] >= 2:
            angle[j] = rho_to_fold_deg(rho)
        j += 1
    return xy, faces, piece_out, parent_out, ev, em, angle, kind
