"""numba kernels of the segmenter's memo of union concavities: hash buckets, the memo (a tuple of
arrays that outlives one merging run) and its regrowth, the candidate initial clusters' points and
hulls, and the evaluation of a union (its hull and depth) into the memo.

The lookups run per heap entry of the merging and are written for numba's reference counting:
see merge_kernels' docstring.
"""

from __future__ import annotations

import numpy as np

from ..arrays import copy_flat, copy_row
from ..jit import njit
from ..mesh.hull_kernels import HULL_FLAT_EPS, NOISE, convex_hull, denoise, depth_chain, max_depth
from ..sorting import sorted_unique


# ----------------------------------------------------------------------------------------------
# Hash buckets and the memo of union concavities


@njit(cache=True)
def _hash(k0, k1):
    """Bucket hash (int64 >= 0) of the uint64 pair (k0, k1)."""
    h = k0 * np.uint64(0x9E3779B97F4A7C15) ^ k1 * np.uint64(0xC2B2AE3D27D4EB4F)
    h ^= h >> np.uint64(29)
    return np.int64(h >> np.uint64(1))


@njit(cache=True)
def bucket(table, keys, k0, k1):
    """Open addressing: the bucket of `table` (power-of-two size, -1 = empty) that holds the row
    of `keys` equal to (k0, k1) (uint64), else the empty bucket where that row goes."""
    mask = table.shape[0] - 1
    b = _hash(k0, k1) & mask
    s = table[b]
    while s >= 0 and not (keys[s, 0] == k0 and keys[s, 1] == k1):  # linear probing
        b = (b + 1) & mask
        s = table[b]
    return b


@njit(cache=True)
def pow2(n):
    """The smallest power of two >= n."""
    t = 1
    while t < n:
        t *= 2
    return t


@njit(cache=True)
def new_memo(n_faces):
    """Empty memo of union concavities for a mesh of n_faces faces, kept across the runs of one
    segment() call. A tuple of arrays (it crosses the numba border in about a microsecond, where
    typed containers cost tens): table (T,) hash buckets of slot ids (-1 empty); keys (S, 2)
    uint64, the pair of cluster keys of each slot, smaller first; conc (S,); exact (S,) bool; hull
    (S, 2) start and count of the slot's hull points in pool (P, 3), which also holds the units'
    hulls; used (2,): slots and pool rows in use.

    Cluster keys are sums of random 64-bit face keys: the key of a union is the sum of its parts'
    keys, and two distinct face sets collide with probability ~2^-64."""
    n = 8 * n_faces + 64
    return (np.full(pow2(2 * n), -1, dtype=np.int64), np.zeros((n, 2), dtype=np.uint64), np.zeros(n),
            np.zeros(n, dtype=np.bool_), np.zeros((n, 2), dtype=np.int64), np.empty((32 * n_faces + 256, 3)),
            np.zeros(2, dtype=np.int64))


@njit(cache=True)
def _rows(a, n, keep):
    """A new array of n rows (n >= keep) holding a copy of a's first `keep` rows."""
    out = np.empty((n,) + a.shape[1:], a.dtype)
    copy_flat(out, a, keep * (a.size // max(a.shape[0], 1)))  # (keep rows of a.size / a.shape[0] each)
    return out


@njit(cache=True)
def memo_grown(memo):
    """The memo with twice the room in each of its parts (slots, buckets, pool rows) that is more
    than half full, entries kept. A run stops for want of a slot, of buckets under half load, or
    of pool rows for a union's hull (fewer than the rows in use), so something always grows."""
    table, keys, conc, exact, hull, pool, used = memo
    n, p = used[0], used[1]
    if 2 * (n + 1) > keys.shape[0]:
        s = 2 * keys.shape[0]
        keys, conc, exact, hull = _rows(keys, s, n), _rows(conc, s, n), _rows(exact, s, n), _rows(hull, s, n)
    if 4 * (n + 1) > table.shape[0]:
        table = np.full(2 * table.shape[0], -1, dtype=np.int64)
        for q in range(n):
            table[bucket(table, keys, keys[q, 0], keys[q, 1])] = q
    if 2 * p > pool.shape[0]:
        pool = _rows(pool, 2 * pool.shape[0], p)
    return table, keys, conc, exact, hull, pool, used


@njit(cache=True)
def _pool_add(pool, used, src, rows):
    """Append the rows `rows` of src (n, 3) to the pool (the caller checked the room): their
    (start, count) in the pool."""
    start = used[1]
    for q in range(rows.shape[0]):
        copy_row(pool, start + q, src, rows[q])
    used[1] = start + rows.shape[0]
    return start, rows.shape[0]


# ----------------------------------------------------------------------------------------------
# Clusters


@njit(cache=True)
def make_cluster(faces, mesh_faces, vertices, samples, diag):
    """(points, hull points, absolute concavity) of the faces (sorted ids): the points are the
    faces' vertices (sorted ids) then their surface samples; the hull is of the vertices."""
    verts = sorted_unique(mesh_faces[faces].ravel())
    n_v = verts.shape[0]
    pts = np.empty((n_v + 3 * faces.shape[0], 3))
    for k in range(n_v):
        copy_row(pts, k, vertices, verts[k])
    for k in range(faces.shape[0]):
        for s in range(3):
            for x in range(3):
                pts[n_v + 3 * k + s, x] = samples[faces[k], s, x]
    vpts = pts[:n_v].copy()
    hv, eq = convex_hull(vpts, HULL_FLAT_EPS)
    if eq.shape[0] == 0:
        return pts, vpts, 0.0
    return pts, vpts[hv], denoise(max_depth(pts, eq, np.inf), diag)


@njit(cache=True)
def make_units(faces, start, mesh_faces, vertices, samples, diag, memo):
    """`make_cluster` of each face list faces[start[u]:start[u + 1]]: (points (N, 3) of all units,
    point start of each unit (U + 1,), hull (U, 2): start and count in the memo's pool,
    concavity (U,), memo). The units' hull points are appended to the memo's pool."""
    n = start.shape[0] - 1
    n_in = start[n] - start[0]
    pts = np.empty((6 * n_in, 3))  # at most 3 vertices and 3 samples per face
    pstart = np.zeros(n + 1, dtype=np.int64)
    hull = np.empty((n, 2), dtype=np.int64)
    conc = np.zeros(n)
    table, keys, mconc, exact, mhull, pool, used = memo
    if used[1] + 3 * n_in > pool.shape[0]:
        pool = _rows(pool, 2 * (used[1] + 3 * n_in), used[1])
    for u in range(n):
        w = pstart[u]
        f = faces[start[u]]
        a, b, c = mesh_faces[f, 0], mesh_faces[f, 1], mesh_faces[f, 2]
        if start[u + 1] - start[u] == 1 and a != b and b != c and a != c:
            # one triangle (the usual fallback unit): its sorted corners and samples, no volume
            a, b, c = min(a, b, c), a + b + c - min(a, b, c) - max(a, b, c), max(a, b, c)
            hull[u, 0], hull[u, 1] = used[1], 3
            for q, v in enumerate((a, b, c)):
                copy_row(pts, w + q, vertices, v)
                copy_row(pool, used[1] + q, vertices, v)
                for x in range(3):
                    pts[w + 3 + q, x] = samples[f, q, x]
            used[1] += 3
            pstart[u + 1] = w + 6
        else:
            p, h, cu = make_cluster(faces[start[u]:start[u + 1]], mesh_faces, vertices, samples, diag)
            for q in range(p.shape[0]):
                copy_row(pts, w + q, p, q)
            pstart[u + 1] = w + p.shape[0]
            hull[u, 0], hull[u, 1] = _pool_add(pool, used, h, np.arange(h.shape[0]))
            conc[u] = cu
    return pts[:pstart[n]].copy(), pstart, hull, conc, (table, keys, mconc, exact, mhull, pool, used)


@njit(cache=True)
def memo_lookup(a, b, limit, key, table, keys, m_conc, m_exact):
    """(memo slot of a u b, its bucket): the slot is -1 when the pair is new or its value is
    inexact but not above the limit (then `union_eval` fills that bucket). The probing of
    `bucket` is written out and the slot's values are read unconditionally: see the module
    docstring."""
    ka, kb = key[a], key[b]
    k0, k1 = (ka, kb) if ka < kb else (kb, ka)
    mask = table.shape[0] - 1
    bk = _hash(k0, k1) & mask
    slot = table[bk]
    while slot >= 0 and not (keys[slot, 0] == k0 and keys[slot, 1] == k1):
        bk = (bk + 1) & mask
        slot = table[bk]
    q = max(slot, 0)
    decided = m_exact[q] or m_conc[q] > limit
    return (slot if decided else -1), bk


@njit(cache=True)
def _union_value(both, two_triangles, pts, pstart, unxt, ua, ub, limit, diag):
    """(absolute concavity, exact?, rows of `both` on the hull) of a union whose hull is the hull
    of the points `both` and whose points are the unit chains from ua then ub (see depth_chain);
    inexact values exceed the limit (the depth kernel stopped early)."""
    keep = np.arange(both.shape[0])
    if two_triangles:  # two triangles sharing an edge are two faces of their tetrahedron: concavity 0
        return 0.0, True, keep
    hv, eq = convex_hull(both, HULL_FLAT_EPS)
    if eq.shape[0] == 0:
        return 0.0, True, keep
    # the kernel stops early (a lower bound) once the depth exceeds the limit; rounding noise must
    # not count as exceeding it
    stop = max(limit, NOISE * diag)
    d = depth_chain(pts, pstart, unxt, ua, ub, eq, stop)
    return denoise(d, diag), d <= stop, hv


@njit(cache=True)
def union_eval(a, b, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, pts, pstart,
                table, keys, m_conc, m_exact, m_hull, pool, used):
    """Evaluate a u b into memo bucket bk (see `memo_lookup`): its slot, or -1 when the memo has
    no room left. Sets (absolute concavity of a u b, exact?, hull points of a u b); inexact values
    exceed the limit (the depth kernel stopped early, or a part alone exceeds it) and are
    recomputed when a later run has a larger limit."""
    slot = table[bk]
    na, nb = hull[a, 1], hull[b, 1]
    if slot < 0 and (used[0] + 1 > keys.shape[0] or 2 * (used[0] + 1) > table.shape[0]):
        return -1
    if used[1] + na + nb > pool.shape[0]:
        return -1
    if slot < 0:
        slot = used[0]
        used[0] += 1
        table[bk] = slot
        ka, kb = key[a], key[b]
        keys[slot, 0], keys[slot, 1] = (ka, kb) if ka < kb else (kb, ka)
    floor = max(conc[a], conc[b])
    if floor > limit:  # decided without a hull (most candidate pairs once clusters grow)
        m_conc[slot], m_exact[slot] = floor, False
        m_hull[slot, 0], m_hull[slot, 1] = used[1], 0
        return slot
    both = np.empty((na + nb, 3))  # the hull of a u b is the hull of the two hulls' points
    for q in range(na):
        copy_row(both, q, pool, hull[a, 0] + q)
    for q in range(nb):
        copy_row(both, na + q, pool, hull[b, 0] + q)
    value, exact, keep = _union_value(both, n_faces[a] + n_faces[b] == 2, pts, pstart, unxt, uhead[a], uhead[b],
                                      limit, diag)
    m_conc[slot], m_exact[slot] = value, exact
    start = used[1]
    for q in range(keep.shape[0]):
        copy_row(pool, start + q, both, keep[q])
    used[1] = start + keep.shape[0]
    m_hull[slot, 0], m_hull[slot, 1] = start, keep.shape[0]
    return slot
