"""numba kernels of the segmenter: convex hull, depth below a hull, the per-mesh arrays of the
merging, one merging run, and the parts' tables and concavities.

`merge_run` is the whole hierarchical merging of segment.py (ALGORITHMS.md 4.4) in one call:
clusters, their adjacency, the lazy min-heap and the small-part clean-up live in plain arrays, so
a run costs well under a microsecond per heap entry. The union concavities are memoized in a memo
(a tuple of arrays, `new_memo`) that outlives one run, since `parts=K` runs the merging once per
tau it tries and most pairs recur.

Why the code looks the way it does: numba counts array references with atomic operations and
prunes the counts only in simple control flow. A function that takes arrays pays an increment and
a decrement per array per call when it calls a non-trivial numba function (the exception check
after the call splits the paths) or when an array's last use differs between branches; a loop
that reassigns an array variable pays them per iteration. Measured, those were over half of a
run's time. So the kernels run per heap entry (`_heap_pop`, `_heap_push`, `_memo_lookup`,
`_slot`, `_merge`) call only trivial helpers and read their arrays on every path, loops exit
through their conditions, a run sizes its arrays once (the heap and the neighbour lists are
compacted in place when full, pair rows are reused), and a run that finds the memo full stops
and is redone on a regrown memo (`merge_run`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NOISE = 1e-12  # depths below NOISE * bbox diagonal are rounding noise of the hull planes: convex
FLAT_EPS = 1e-12  # relative to the points' extent: thinner sets have no volume (concavity 0)
DENSE_EDGES = 1024  # convex_hull counts facets per directed edge in an n x n table up to this many points


# ----------------------------------------------------------------------------------------------
# Hull and depth


@njit(cache=True)
def _plane(p, a, b, c):
    """Unit normal (right-hand rule a->b->c), offset d (n.x + d = 0 on the plane), and the cross
    product's length (0: degenerate triangle, the normal is then not normalized)."""
    ux, uy, uz = p[b, 0] - p[a, 0], p[b, 1] - p[a, 1], p[b, 2] - p[a, 2]
    vx, vy, vz = p[c, 0] - p[a, 0], p[c, 1] - p[a, 1], p[c, 2] - p[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    ln = math.sqrt(nx * nx + ny * ny + nz * nz)
    if ln > 0:
        nx, ny, nz = nx / ln, ny / ln, nz / ln
    return nx, ny, nz, -(nx * p[a, 0] + ny * p[a, 1] + nz * p[a, 2]), ln


@njit(cache=True)
def _copy_row(dst, i, src, j):
    """dst[i] = src[j] for rows of 3, element by element: a row assignment goes through numpy's
    setitem (a view, a broadcast) and costs ~100 ns, this a few."""
    dst[i, 0], dst[i, 1], dst[i, 2] = src[j, 0], src[j, 1], src[j, 2]


@njit(cache=True)
def convex_hull(p, rel_eps):
    """3D convex hull of the points p (n, 3): (ids of hull vertices, facet equations (m, 4)).

    Facet planes are unit outward normals with offsets, n.x + d <= 0 inside (qhull's convention).
    Empty equations when the points span no volume (thinner than rel_eps * their extent).
    Incremental: start from a tetrahedron of extreme points; each point above some facets (by more
    than the tolerance) replaces them by a cone over their boundary edges, the horizon. The
    horizon is found as the edges whose reverse lies on a kept facet, so the surface stays closed
    even if rounding makes the visible region odd: a count of the live facets on each directed
    edge answers that per edge (up to DENSE_EDGES points; beyond, a scan of the facets does).
    Meant for the small sets of the merging (tens of points), where qhull's per-call set-up
    (about 45 us) is most of its cost.
    """
    n = p.shape[0]
    empty_v = np.empty(0, dtype=np.int64)
    empty_e = np.empty((0, 4))
    if n < 4:
        return empty_v, empty_e
    # (min, max and argmin written out, NaN first as numpy has them: the calls cost more here)
    ext = 0.0
    for k in range(3):
        lo, hi = p[0, k], p[0, k]
        for i in range(1, n):
            v = p[i, k]
            if lo == lo and (v < lo or v != v):
                lo = v
            if hi == hi and (v > hi or v != v):
                hi = v
        ext = max(ext, hi - lo)
    eps = rel_eps * ext
    if ext <= 0:
        return empty_v, empty_e
    # initial tetrahedron: extreme x, farthest from it, farthest from their line, farthest from the plane
    i0 = 0
    for i in range(1, n):
        if p[i0, 0] == p[i0, 0] and (p[i, 0] < p[i0, 0] or p[i, 0] != p[i, 0]):
            i0 = i
    i1, best = -1, -1.0
    for i in range(n):
        d = (p[i, 0] - p[i0, 0]) ** 2 + (p[i, 1] - p[i0, 1]) ** 2 + (p[i, 2] - p[i0, 2]) ** 2
        if d > best:
            best, i1 = d, i
    d01 = math.sqrt(best)
    i2, best = -1, -1.0
    for i in range(n):
        nx, ny, nz, d, ln = _plane(p, i0, i1, i)
        if ln > best:
            best, i2 = ln, i
    nx, ny, nz, d0, ln = _plane(p, i0, i1, i2)
    if ln <= eps * d01:  # all points on the line i0-i1 (ln / d01 is the distance from it)
        return empty_v, empty_e
    i3, best = -1, 0.0
    for i in range(n):
        d = nx * p[i, 0] + ny * p[i, 1] + nz * p[i, 2] + d0
        if abs(d) > abs(best):
            best, i3 = d, i
    if abs(best) <= eps:
        return empty_v, empty_e
    cap = 8 * n + 16
    F = np.empty((cap, 3), dtype=np.int64)
    E = np.empty((cap, 4))
    alive = np.zeros(cap, dtype=np.bool_)
    nf = 0
    if best > 0:  # i3 above the plane (i0, i1, i2): orient that face downwards
        i1, i2 = i2, i1
    for a, b, c in ((i0, i1, i2), (i0, i3, i1), (i1, i3, i2), (i2, i3, i0)):
        F[nf, 0], F[nf, 1], F[nf, 2] = a, b, c
        nx, ny, nz, d, ln = _plane(p, a, b, c)
        E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
        alive[nf] = True
        nf += 1
    vis = np.zeros(cap, dtype=np.bool_)
    vl = np.empty(cap, dtype=np.int64)
    hor = np.empty((cap, 2), dtype=np.int64)
    n_live, nf_kept = nf, nf
    dense = n <= DENSE_EDGES
    on = np.zeros(n * n if dense else 1, dtype=np.int32)  # live facets having directed edge a->b (a * n + b)
    seen = np.zeros(on.shape[0], dtype=np.int32)  # the same among the facets visible from the current point
    if dense:
        for f in range(nf):
            for k in range(3):
                on[F[f, k] * n + F[f, (k + 1) % 3]] += 1
    for i in range(n):
        if i == i0 or i == i1 or i == i2 or i == i3:
            continue
        x, y, z = p[i, 0], p[i, 1], p[i, 2]
        nv = 0  # the visible faces, in face order, are vl[:nv]
        for f in range(nf):
            vis[f] = alive[f] and E[f, 0] * x + E[f, 1] * y + E[f, 2] * z + E[f, 3] > eps
            if vis[f]:
                vl[nv] = f
                nv += 1
        if nv == 0:
            continue
        # horizon: directed edges of visible faces whose reverse lies on an alive invisible face
        if dense:
            for q in range(nv):
                for k in range(3):
                    seen[F[vl[q], k] * n + F[vl[q], (k + 1) % 3]] += 1
        nh = 0
        for q in range(nv):
            for k in range(3):
                a, b = F[vl[q], k], F[vl[q], (k + 1) % 3]
                if dense:
                    found = on[b * n + a] > seen[b * n + a]
                else:
                    found = False
                    for g in range(nf):
                        if not alive[g] or vis[g]:
                            continue
                        if (F[g, 0] == b and F[g, 1] == a) or (F[g, 1] == b and F[g, 2] == a) or (F[g, 2] == b and F[g, 0] == a):
                            found = True
                            break
                if found:
                    hor[nh, 0], hor[nh, 1] = a, b
                    nh += 1
        if nf_kept + nh > cap:  # cannot happen for a consistent hull; be safe
            return empty_v, empty_e
        for q in range(nv):
            alive[vl[q]] = False
            n_live -= 1
            if dense:
                for k in range(3):
                    e = F[vl[q], k] * n + F[vl[q], (k + 1) % 3]
                    seen[e] -= 1
                    on[e] -= 1
        for h in range(nh):
            a, b = hor[h, 0], hor[h, 1]
            F[nf, 0], F[nf, 1], F[nf, 2] = a, b, i
            nx, ny, nz, d, ln = _plane(p, a, b, i)
            E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
            alive[nf] = ln > 0
            n_live += ln > 0
            if dense and ln > 0:
                on[a * n + b] += 1
                on[b * n + i] += 1
                on[i * n + a] += 1
            nf += 1
        # Compact (keeping the order) once the dead faces are half, so the loops stay short. The
        # safety check above counts the faces as compacting at 2n + 64 kept them (nf_kept), the
        # rule this kernel had, so it decides as before.
        nf_kept += nh
        if nf_kept > 2 * n + 64:
            nf_kept = n_live
        if nf > 2 * n_live:
            m = 0
            for f in range(nf):
                if alive[f]:
                    F[m, 0], F[m, 1], F[m, 2] = F[f, 0], F[f, 1], F[f, 2]
                    E[m, 0], E[m, 1], E[m, 2], E[m, 3] = E[f, 0], E[f, 1], E[f, 2], E[f, 3]
                    alive[m] = True
                    m += 1
            nf = m
    used = np.zeros(n, dtype=np.bool_)
    m = 0
    for f in range(nf):
        if alive[f]:
            m += 1
            used[F[f, 0]] = True
            used[F[f, 1]] = True
            used[F[f, 2]] = True
    eq = np.empty((m, 4))
    m = 0
    for f in range(nf):
        if alive[f]:
            eq[m, 0], eq[m, 1], eq[m, 2], eq[m, 3] = E[f, 0], E[f, 1], E[f, 2], E[f, 3]
            m += 1
    nv = 0
    for i in range(n):
        nv += used[i]
    verts = np.empty(nv, dtype=np.int64)
    nv = 0
    for i in range(n):
        if used[i]:
            verts[nv] = i
            nv += 1
    return verts, eq


@njit(cache=True)
def depth_chain(pts, pstart, unxt, ua, ub, eq, limit):
    """max over points of min over facets of -(eq[j, :3] . x + eq[j, 3]) (>= 0) for the points of
    the ranges pts[pstart[u]:pstart[u + 1]] of the units u of the chain from ua, then of the chain
    from ub (-1: none) along unxt, in that order; stops early (a lower bound) once it exceeds
    `limit`. The loops are written out, not split into calls: see the module docstring."""
    n_f = eq.shape[0]
    best, hint, done = 0.0, 0, False
    u, in_b = ua, False
    while u >= 0:
        i = pstart[u]
        while i < pstart[u + 1] and not done:
            x, y, z = pts[i, 0], pts[i, 1], pts[i, 2]
            # The facet that bounded the previous point first: neighbouring points share facets.
            m = -(eq[hint, 0] * x + eq[hint, 1] * y + eq[hint, 2] * z + eq[hint, 3])
            j = 0
            while j < n_f and m > best:  # the point's depth, or any value <= best once it is known to be
                d = -(eq[j, 0] * x + eq[j, 1] * y + eq[j, 2] * z + eq[j, 3])
                if d < m:
                    m = d
                    hint = j
                j += 1
            if m > best:
                best = m
                done = best > limit
            i += 1
        u = unxt[u] if not done else -1
        if u < 0 and not in_b and not done:
            u, in_b = ub, True
    return best


@njit(cache=True)
def max_depth(pts, eq, limit):
    """max_i min_j -(eq[j, :3] . pts[i] + eq[j, 3]) (>= 0); stops early once it exceeds `limit`."""
    return depth_chain(pts, np.array([0, pts.shape[0]]), np.array([-1]), 0, -1, eq, limit)


@njit(cache=True)
def denoise(depth, diag):
    return 0.0 if depth <= NOISE * diag else depth


# ----------------------------------------------------------------------------------------------
# Connected components


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



# ----------------------------------------------------------------------------------------------
# Per-mesh arrays of the merging (one call each per segment(), instead of a dozen numpy calls)


@njit(cache=True)
def face_keys(n):
    """n pseudo-random 64-bit face keys (splitmix64 of the face index). A cluster's key is the sum
    of its faces' keys (see `new_memo`); any fixed random keys do."""
    out = np.empty(n, dtype=np.uint64)
    for f in range(n):
        z = np.uint64(f + 1) * np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        out[f] = z ^ (z >> np.uint64(31))
    return out


@njit(cache=True)
def _norm3(x, y, z):
    """sqrt(x^2 + y^2 + z^2) summed left to right, as np.linalg.norm(axis=1) does for 3 columns."""
    return math.sqrt((x * x + y * y) + z * z)


@njit(cache=True)
def face_lengths(vertices, faces, edges, face_edges):
    """(area (F,), perimeter (F,) over all three edges, edge length (E,)), bitwise as the numpy
    expressions 0.5 * norm(cross(b - a, c - a)), norm(v1 - v0) and edge_len[face_edges].sum(1)."""
    n_f, n_e = faces.shape[0], edges.shape[0]
    area = np.empty(n_f)
    perim = np.empty(n_f)
    length = np.empty(n_e)
    for e in range(n_e):
        a, b = edges[e, 0], edges[e, 1]
        length[e] = _norm3(vertices[b, 0] - vertices[a, 0], vertices[b, 1] - vertices[a, 1], vertices[b, 2] - vertices[a, 2])
    for f in range(n_f):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        ux, uy, uz = vertices[b, 0] - vertices[a, 0], vertices[b, 1] - vertices[a, 1], vertices[b, 2] - vertices[a, 2]
        vx, vy, vz = vertices[c, 0] - vertices[a, 0], vertices[c, 1] - vertices[a, 1], vertices[c, 2] - vertices[a, 2]
        area[f] = 0.5 * _norm3(uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
        perim[f] = (length[face_edges[f, 0]] + length[face_edges[f, 1]]) + length[face_edges[f, 2]]
    return area, perim, length


@njit(cache=True)
def inner_edges(edge_faces, length, fold):
    """The edges with two faces: (face 0, face 1, length, length * concave fold / 90 degrees), the
    last bitwise as length * np.clip(-fold, 0, None) / (pi / 2)."""
    n = 0
    for e in range(edge_faces.shape[0]):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            n += 1
    f0 = np.empty(n, dtype=np.int64)
    f1 = np.empty(n, dtype=np.int64)
    ln = np.empty(n)
    cw = np.empty(n)
    q = 0
    for e in range(edge_faces.shape[0]):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            f0[q], f1[q], ln[q] = edge_faces[e, 0], edge_faces[e, 1], length[e]
            r = -fold[e]
            cw[q] = length[e] * (r if r > 0.0 or r != r else 0.0) / (math.pi / 2)  # clip: -0.0 -> 0.0, NaN kept
            q += 1
    return f0, f1, ln, cw


@njit(cache=True)
def face_groups(edge_faces, face_source, fold, min_fold):
    """Three face labellings by edge-connected components (numbered by smallest face, see
    `union_labels`): seeds, joined across edges with fold >= min_fold or inside one input polygon
    (same face_source); polygons, joined inside one input polygon; components, joined across every
    edge with two faces."""
    n = face_source.shape[0]
    m = edge_faces.shape[0]
    s0, s1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    p0, p1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    c0, c1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    ns = npoly = nc = 0
    for e in range(m):
        a, b = edge_faces[e, 0], edge_faces[e, 1]
        if a >= 0 and b >= 0:
            same = face_source[a] == face_source[b]
            c0[nc], c1[nc] = a, b
            nc += 1
            if same:
                p0[npoly], p1[npoly] = a, b
                npoly += 1
            if same or fold[e] >= min_fold:
                s0[ns], s1[ns] = a, b
                ns += 1
    return (union_labels(n, s0[:ns], s1[:ns]), union_labels(n, p0[:npoly], p1[:npoly]),
            union_labels(n, c0[:nc], c1[:nc]))


@njit(cache=True)
def unit_groups(seeds, polygon):
    """The candidate initial clusters of the merging: each seed (in label order), then the input
    polygons inside it (in label order), faces ascending within each. (seed_unit, sub_lo, sub_hi
    (per seed: its unit and the range of its polygons' units), faces (2F,), start (U + 1,))."""
    n = seeds.shape[0]
    order = np.argsort(seeds, kind="mergesort")
    n_seeds = 0
    for t in range(n):
        if t == 0 or seeds[order[t]] != seeds[order[t - 1]]:
            n_seeds += 1
    seed_unit = np.empty(n_seeds, dtype=np.int64)
    sub_lo = np.empty(n_seeds, dtype=np.int64)
    sub_hi = np.empty(n_seeds, dtype=np.int64)
    faces = np.empty(2 * n, dtype=np.int64)
    start = np.empty(n + n_seeds + 1, dtype=np.int64)
    n_units, w, t, s = 0, 0, 0, 0
    while t < n:
        e = t
        while e < n and seeds[order[e]] == seeds[order[t]]:
            e += 1
        seed_unit[s] = n_units
        start[n_units] = w
        n_units += 1
        for q in range(t, e):
            faces[w] = order[q]
            w += 1
        block = order[t:e]
        sub = block[np.argsort(polygon[block], kind="mergesort")]
        sub_lo[s] = n_units
        for q in range(e - t):
            if q == 0 or polygon[sub[q]] != polygon[sub[q - 1]]:
                start[n_units] = w
                n_units += 1
            faces[w] = sub[q]
            w += 1
        sub_hi[s] = n_units
        s += 1
        t = e
    start[n_units] = w
    return seed_unit, sub_lo, sub_hi, faces, start[:n_units + 1].copy()


@njit(cache=True)
def sample_points(vertices, faces, r):
    """The points of the random pairs r (F, k, 2) on the faces: a + r0 (b - a) + r1 (c - a), with
    pairs beyond the diagonal (r0 + r1 > 1) reflected to 1 - r; bitwise as segment's numpy form."""
    n, k = r.shape[0], r.shape[1]
    out = np.empty((n, k, 3))
    for f in range(n):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        for s in range(k):
            r0, r1 = r[f, s, 0], r[f, s, 1]
            if r0 + r1 > 1:
                r0, r1 = 1 - r0, 1 - r1
            for x in range(3):
                out[f, s, x] = vertices[a, x] + r0 * (vertices[b, x] - vertices[a, x]) + r1 * (vertices[c, x] - vertices[a, x])
    return out


@njit(cache=True)
def first_face_order(label):
    """The labels renumbered 0, 1, ... in order of each part's smallest face: (labels, count)."""
    new = np.full(label.max() + 1, -1, dtype=np.int64)
    out = np.empty(label.shape[0], dtype=np.int64)
    n = 0
    for f in range(label.shape[0]):
        if new[label[f]] < 0:
            new[label[f]] = n
            n += 1
        out[f] = new[label[f]]
    return out, n


@njit(cache=True)
def part_tables(label, n_parts, mesh_faces, n_vertices):
    """Faces and vertices of each part p of the labels (0..n_parts-1): (faces (F,): each part's
    faces, ascending, fstart (P + 1,); verts: each part's vertex ids, ascending, vstart (P + 1,);
    local (F, 3): the corners of `faces` as indices into their part's vertices)."""
    n_f = label.shape[0]
    fstart = np.zeros(n_parts + 1, dtype=np.int64)
    for f in range(n_f):
        fstart[label[f] + 1] += 1
    for p in range(n_parts):
        fstart[p + 1] += fstart[p]
    faces = np.empty(n_f, dtype=np.int64)
    fill = fstart[:-1].copy()
    for f in range(n_f):
        faces[fill[label[f]]] = f
        fill[label[f]] += 1
    pos = np.full(n_vertices, -1, dtype=np.int64)  # a vertex's index in the current part
    verts = np.empty(3 * n_f, dtype=np.int64)
    vstart = np.zeros(n_parts + 1, dtype=np.int64)
    local = np.empty((n_f, 3), dtype=np.int64)
    for p in range(n_parts):
        lo = vstart[p]
        n = lo
        for t in range(fstart[p], fstart[p + 1]):
            for k in range(3):
                v = mesh_faces[faces[t], k]
                if pos[v] != p:
                    pos[v] = p
                    verts[n] = v
                    n += 1
        verts[lo:n].sort()
        vstart[p + 1] = n
        for q in range(lo, n):
            pos[verts[q]] = q - lo
        for t in range(fstart[p], fstart[p + 1]):
            for k in range(3):
                local[t, k] = pos[mesh_faces[faces[t], k]]
        for q in range(lo, n):
            pos[verts[q]] = -1
    return faces, fstart, verts[:vstart[n_parts]].copy(), vstart, local


@njit(cache=True)
def part_concavities(faces, fstart, verts, vstart, vertices, samples, diag, max_verts):
    """segment.part_concavity of each part of `part_tables` (relative to diag): the depth of the
    part's vertices and samples below the hull of its vertices; NaN for parts of more than
    max_verts vertices (whose hull segment.py takes from qhull)."""
    n_parts = fstart.shape[0] - 1
    out = np.zeros(n_parts)
    for p in range(n_parts):
        nv = vstart[p + 1] - vstart[p]
        nf = fstart[p + 1] - fstart[p]
        if nv > max_verts:
            out[p] = np.nan
        elif nv >= 4:
            k = samples.shape[1]
            pts = np.empty((nv + k * nf, 3))
            for q in range(nv):
                _copy_row(pts, q, vertices, verts[vstart[p] + q])
            for t in range(nf):
                for s in range(k):
                    for x in range(3):
                        pts[nv + k * t + s, x] = samples[faces[fstart[p] + t], s, x]
            hv, eq = convex_hull(pts[:nv].copy(), FLAT_EPS)
            if eq.shape[0] > 0 and diag > 0:
                out[p] = denoise(max_depth(pts, eq, np.inf), diag) / diag
    return out


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
def _pow2(n):
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
    return (np.full(_pow2(2 * n), -1, dtype=np.int64), np.zeros((n, 2), dtype=np.uint64), np.zeros(n),
            np.zeros(n, dtype=np.bool_), np.zeros((n, 2), dtype=np.int64), np.empty((32 * n_faces + 256, 3)),
            np.zeros(2, dtype=np.int64))


@njit(cache=True)
def _rows(a, n, keep):
    """A new array of n rows (n >= keep) holding a copy of a's first `keep` rows."""
    out = np.empty((n,) + a.shape[1:], a.dtype)
    out[:keep] = a[:keep]
    return out


@njit(cache=True)
def _memo_grown(memo):
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
        _copy_row(pool, start + q, src, rows[q])
    used[1] = start + rows.shape[0]
    return start, rows.shape[0]


# ----------------------------------------------------------------------------------------------
# Clusters


@njit(cache=True)
def make_cluster(faces, mesh_faces, vertices, samples, diag):
    """(points, hull points, absolute concavity) of the faces (sorted ids): the points are the
    faces' vertices (sorted ids) then their surface samples; the hull is of the vertices."""
    verts = np.unique(mesh_faces[faces].ravel())
    n_v = verts.shape[0]
    pts = np.empty((n_v + 3 * faces.shape[0], 3))
    for k in range(n_v):
        _copy_row(pts, k, vertices, verts[k])
    for k in range(faces.shape[0]):
        for s in range(3):
            for x in range(3):
                pts[n_v + 3 * k + s, x] = samples[faces[k], s, x]
    vpts = pts[:n_v].copy()
    hv, eq = convex_hull(vpts, FLAT_EPS)
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
                _copy_row(pts, w + q, vertices, v)
                _copy_row(pool, used[1] + q, vertices, v)
                for x in range(3):
                    pts[w + 3 + q, x] = samples[f, q, x]
            used[1] += 3
            pstart[u + 1] = w + 6
        else:
            p, h, cu = make_cluster(faces[start[u]:start[u + 1]], mesh_faces, vertices, samples, diag)
            for q in range(p.shape[0]):
                _copy_row(pts, w + q, p, q)
            pstart[u + 1] = w + p.shape[0]
            hull[u, 0], hull[u, 1] = _pool_add(pool, used, h, np.arange(h.shape[0]))
            conc[u] = cu
    return pts[:pstart[n]].copy(), pstart, hull, conc, (table, keys, mconc, exact, mhull, pool, used)


@njit(cache=True)
def _memo_lookup(a, b, limit, key, table, keys, m_conc, m_exact):
    """(memo slot of a u b, its bucket): the slot is -1 when the pair is new or its value is
    inexact but not above the limit (then `_union_eval` fills that bucket). The probing of
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
    hv, eq = convex_hull(both, FLAT_EPS)
    if eq.shape[0] == 0:
        return 0.0, True, keep
    # the kernel stops early (a lower bound) once the depth exceeds the limit; rounding noise must
    # not count as exceeding it
    stop = max(limit, NOISE * diag)
    d = depth_chain(pts, pstart, unxt, ua, ub, eq, stop)
    return denoise(d, diag), d <= stop, hv


@njit(cache=True)
def _union_eval(a, b, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, pts, pstart,
                table, keys, m_conc, m_exact, m_hull, pool, used):
    """Evaluate a u b into memo bucket bk (see `_memo_lookup`): its slot, or -1 when the memo has
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
        _copy_row(both, q, pool, hull[a, 0] + q)
    for q in range(nb):
        _copy_row(both, na + q, pool, hull[b, 0] + q)
    value, exact, keep = _union_value(both, n_faces[a] + n_faces[b] == 2, pts, pstart, unxt, uhead[a], uhead[b],
                                      limit, diag)
    m_conc[slot], m_exact[slot] = value, exact
    start = used[1]
    for q in range(keep.shape[0]):
        _copy_row(pool, start + q, both, keep[q])
    used[1] = start + keep.shape[0]
    m_hull[slot, 0], m_hull[slot, 1] = start, keep.shape[0]
    return slot


@njit(cache=True)
def _cost(a, b, shared, conc_len, c, area, perim, w_compact, w_seam, scale):
    ar = area[a] + area[b]
    pe = perim[a] + perim[b] - 2 * shared
    compact = pe * pe / (4 * math.pi * ar) - 1.0 if ar > 0 else 0.0
    seam = conc_len / shared if shared > 0 else 0.0
    return c + (w_compact * compact + w_seam * seam) * scale


# ----------------------------------------------------------------------------------------------
# The lazy min-heap: parallel arrays (cost, exact?, i, j), ordered lexicographically. The order
# is total (equal entries are interchangeable), so the pop sequence does not depend on the
# arrangement of the arrays: compaction may rebuild it.


@njit(cache=True)
def _less(c1, e1, i1, j1, c2, e2, i2, j2):
    """(c1, e1, i1, j1) < (c2, e2, i2, j2) lexicographically (Python's tuple order)."""
    if c1 != c2:
        return c1 < c2
    if e1 != e2:
        return e1 < e2
    if i1 != i2:
        return i1 < i2
    return j1 < j2


@njit(cache=True)
def _swap(hc, he, hi, hj, a, b):
    hc[a], hc[b] = hc[b], hc[a]
    he[a], he[b] = he[b], he[a]
    hi[a], hi[b] = hi[b], hi[a]
    hj[a], hj[b] = hj[b], hj[a]


@njit(cache=True)
def _heap_push(hc, he, hi, hj, size, c, e, i, j):
    """Add (c, e, i, j) to the heap of `size` entries (room checked by the caller): the new size."""
    k = size
    hc[k], he[k], hi[k], hj[k] = c, e, i, j
    while k > 0 and _less(hc[k], he[k], hi[k], hj[k], hc[(k - 1) >> 1], he[(k - 1) >> 1], hi[(k - 1) >> 1], hj[(k - 1) >> 1]):
        _swap(hc, he, hi, hj, k, (k - 1) >> 1)
        k = (k - 1) >> 1
    return size + 1


@njit(cache=True)
def _sift_down(hc, he, hi, hj, size, k):
    """Restore the heap order below entry k."""
    settled = False
    while not settled:
        c = 2 * k + 1
        if c + 1 < size and _less(hc[c + 1], he[c + 1], hi[c + 1], hj[c + 1], hc[c], he[c], hi[c], hj[c]):
            c += 1
        if c < size and _less(hc[c], he[c], hi[c], hj[c], hc[k], he[k], hi[k], hj[k]):
            _swap(hc, he, hi, hj, c, k)
            k = c
        else:
            settled = True


@njit(cache=True)
def _heap_pop(hc, he, hi, hj, size):
    """Remove the smallest entry (moved to index `size - 1` for the caller to read): the new size.
    (The sift-down is written out here, not called: see the module docstring.)"""
    size -= 1
    _swap(hc, he, hi, hj, 0, size)
    k = 0
    settled = False
    while not settled:
        c = 2 * k + 1
        if c + 1 < size and _less(hc[c + 1], he[c + 1], hi[c + 1], hj[c + 1], hc[c], he[c], hi[c], hj[c]):
            c += 1
        if c < size and _less(hc[c], he[c], hi[c], hj[c], hc[k], he[k], hi[k], hj[k]):
            _swap(hc, he, hi, hj, c, k)
            k = c
        else:
            settled = True
    return size


@njit(cache=True)
def _heap_compact(hc, he, hi, hj, size, alive):
    """Drop the entries of merged clusters and rebuild the heap in place: the new size. Each pair
    of live clusters has at most one entry, so at most as many remain as there are live pairs."""
    n = 0
    for k in range(size):
        if alive[hi[k]] and alive[hj[k]]:
            hc[n], he[n], hi[n], hj[n] = hc[k], he[k], hi[k], hj[k]
            n += 1
    for k in range(n // 2 - 1, -1, -1):
        _sift_down(hc, he, hi, hj, n, k)
    return n


# ----------------------------------------------------------------------------------------------
# Cluster adjacency. Cluster c's neighbours are nb_id[nb_lo[c]:nb_lo[c] + nb_n[c]], with the row
# of their pair (shared length, concave-weighted length) in nb_slot. The lists of new clusters go
# to the end of the pool (nb_lo ascends with the cluster id); the number of live entries only
# decreases as clusters merge, so compacting the pool always makes room.


@njit(cache=True)
def _adjacency(label, n, ef0, ef1, edge_len, conc_w, cap):
    """Adjacency of the n clusters of the face labels: one pair row per adjacent pair, in order of
    its first inner edge, with the shared length and concave-weighted length summed in edge order;
    each cluster lists its neighbours in pair order. (nb_lo, nb_n (cap,), nb_id, nb_slot (room for
    twice the entries), shared, conc_len, number of pairs)."""
    m = ef0.shape[0]
    pair = np.empty((m, 2), dtype=np.uint64)
    shared = np.empty(m + 1)
    conc_len = np.empty(m + 1)
    table = np.full(_pow2(2 * m + 2), -1, dtype=np.int64)
    deg = np.zeros(cap, dtype=np.int64)
    n_pairs = 0
    for e in range(m):
        x, y = label[ef0[e]], label[ef1[e]]
        if x != y:
            k0, k1 = np.uint64(min(x, y)), np.uint64(max(x, y))
            bk = bucket(table, pair, k0, k1)
            ps = table[bk]
            if ps >= 0:
                shared[ps] += edge_len[e]
                conc_len[ps] += conc_w[e]
            else:
                ps = n_pairs
                n_pairs += 1
                table[bk] = ps
                pair[ps, 0], pair[ps, 1] = k0, k1
                shared[ps] = edge_len[e]
                conc_len[ps] = conc_w[e]
                deg[x] += 1
                deg[y] += 1
    nb_lo = np.zeros(cap, dtype=np.int64)
    for c in range(1, n):
        nb_lo[c] = nb_lo[c - 1] + deg[c - 1]
    nb_n = np.zeros(cap, dtype=np.int64)
    nb_id = np.empty(4 * n_pairs + 16, dtype=np.int64)
    nb_slot = np.empty(4 * n_pairs + 16, dtype=np.int64)
    for s in range(n_pairs):
        x, y = np.int64(pair[s, 0]), np.int64(pair[s, 1])
        nb_id[nb_lo[x] + nb_n[x]], nb_slot[nb_lo[x] + nb_n[x]] = y, s
        nb_n[x] += 1
        nb_id[nb_lo[y] + nb_n[y]], nb_slot[nb_lo[y] + nb_n[y]] = x, s
        nb_n[y] += 1
    return nb_lo, nb_n, nb_id, nb_slot, shared, conc_len, n_pairs


@njit(cache=True)
def _nb_compact(nb_lo, nb_n, nb_id, nb_slot, alive, n):
    """Move the lists of the live clusters among 0..n-1 to the front of the pool: its new end."""
    end = 0
    for c in range(n):
        if alive[c]:
            lo = nb_lo[c]
            nb_lo[c] = end
            for t in range(nb_n[c]):
                nb_id[end + t], nb_slot[end + t] = nb_id[lo + t], nb_slot[lo + t]
            end += nb_n[c]
    return end


@njit(cache=True)
def _slot(nb_lo, nb_n, nb_id, nb_slot, i, j):
    """Pair row of the adjacent clusters i and j (-1 when not adjacent)."""
    t, end = nb_lo[i], nb_lo[i] + nb_n[i]
    while t < end and nb_id[t] != j:
        t += 1
    s = nb_slot[min(t, nb_slot.shape[0] - 1)]  # read on every path: see the module docstring
    return s if t < end else -1


@njit(cache=True)
def _merge(i, j, c, u, key, conc, area, perim, n_faces, alive, hull, uhead, utail, unxt,
           nb_lo, nb_n, nb_id, nb_slot, nb_end, shared, conc_len, m_conc, m_hull):
    """Merge clusters i and j (memo slot u holds their exact union) into the new cluster c, whose
    neighbour list goes to nb_end of the pool (the caller made room for deg i + deg j): the new
    end. The pair of c and a neighbour k takes over the row of the first of (i, k), (j, k).
    (The list searches are written out, not called: see the module docstring.)"""
    t = nb_lo[i]
    while nb_id[t] != j:  # the pair row of i and j
        t += 1
    s_ij = nb_slot[t]
    alive[i] = False
    alive[j] = False
    alive[c] = True
    key[c] = key[i] + key[j]
    conc[c] = m_conc[u]
    area[c] = area[i] + area[j]
    perim[c] = perim[i] + perim[j] - 2 * shared[s_ij]
    n_faces[c] = n_faces[i] + n_faces[j]
    hull[c, 0], hull[c, 1] = m_hull[u, 0], m_hull[u, 1]
    uhead[c] = uhead[i]  # the units of c: i's, then j's (the order of the points' concatenation)
    unxt[utail[i]] = uhead[j]
    utail[c] = utail[j]
    lo, n_new = nb_end, 0
    for src in (i, j):
        for t in range(nb_lo[src], nb_lo[src] + nb_n[src]):
            k = nb_id[t]
            if k != i and k != j:
                pos = lo
                while pos < lo + n_new and nb_id[pos] != k:
                    pos += 1
                if pos == lo + n_new:  # first seen: the shared lengths of a u b with k are a's...
                    s2 = nb_slot[t]
                    nb_id[pos], nb_slot[pos] = k, s2
                    n_new += 1
                else:  # ...plus b's
                    s2 = nb_slot[pos]
                    shared[s2] += shared[nb_slot[t]]
                    conc_len[s2] += conc_len[nb_slot[t]]
                # k's list: drop i and j, append c unless it is there already (then it keeps its
                # place, as a dict would); in place, since k lists i or j
                k_lo, k_end = nb_lo[k], nb_lo[k] + nb_n[k]
                q = k_lo
                while q < k_end and nb_id[q] != c:
                    q += 1
                if q == k_end:
                    q = k_lo
                    for r in range(k_lo, k_end):
                        if nb_id[r] != i and nb_id[r] != j:
                            nb_id[q], nb_slot[q] = nb_id[r], nb_slot[r]
                            q += 1
                    nb_id[q], nb_slot[q] = c, s2
                    nb_n[k] = q + 1 - k_lo
    nb_lo[c], nb_n[c] = lo, n_new
    return lo + n_new


@njit(cache=True)
def merge_run(limit, scale, target, w_compact, w_seam, min_faces, diag, units, graph, memo):
    """One merging run of segment._run: (cluster id of every face at the end, number of clusters,
    memo). Ids ascend in creation order, as the parts of the Python version did.

    units: (seed_unit, sub_lo, sub_hi, unit_faces, unit_start, unit_pts, unit_pstart, unit_hull,
    unit_conc, unit_area, unit_perim), the candidate initial clusters with precomputed points, hull
    (start, count in the memo's pool), concavity, area and perimeter; unit u holds the faces
    unit_faces[unit_start[u]:unit_start[u + 1]] and the points unit_pts[unit_pstart[u]:unit_pstart[u + 1]].
    Seed s is unit seed_unit[s]; when its concavity exceeds the limit its polygons, units
    sub_lo[s]:sub_hi[s], start instead. graph: (face_key, ef0, ef1, edge_len, conc_w), the random
    face keys and the inner edges' faces, lengths and concave-weighted lengths. target < 0: merge
    while admissible pairs remain; else stop at `target` clusters. memo: `new_memo`'s tuple, read
    and extended; returned, since a full memo is regrown (and the run redone: its entries so far
    are valid, so the redone run takes the same steps).
    """
    label, n, ok = _merge_pass(limit, scale, target, w_compact, w_seam, min_faces, diag, units, graph, memo)
    while not ok:
        memo = _memo_grown(memo)
        label, n, ok = _merge_pass(limit, scale, target, w_compact, w_seam, min_faces, diag, units, graph, memo)
    return label, n, memo


@njit(cache=True)
def _merge_pass(limit, scale, target, w_compact, w_seam, min_faces, diag, units, graph, memo):
    """`merge_run` on the memo as it is: (labels, number of clusters, False when the memo filled up)."""
    seed_unit, sub_lo, sub_hi, unit_faces, unit_start, unit_pts, unit_pstart, unit_hull, unit_conc, unit_area, unit_perim = units
    face_key, ef0, ef1, edge_len, conc_w = graph
    table, keys, m_conc, m_exact, m_hull, pool, used = memo
    n_fm = face_key.shape[0]
    cap = 2 * n_fm + 1
    key = np.zeros(cap, dtype=np.uint64)
    conc = np.zeros(cap)
    area = np.zeros(cap)
    perim = np.zeros(cap)
    n_faces = np.zeros(cap, dtype=np.int64)
    alive = np.zeros(cap, dtype=np.bool_)
    hull = np.zeros((cap, 2), dtype=np.int64)
    # each cluster's units: a linked list uhead -> unxt -> utail (its points are theirs, in order)
    uhead = np.full(cap, -1, dtype=np.int64)
    utail = np.full(cap, -1, dtype=np.int64)
    unxt = np.full(unit_conc.shape[0], -1, dtype=np.int64)
    label = np.empty(n_fm, dtype=np.int64)
    nid = 0
    for s in range(seed_unit.shape[0]):
        u0 = seed_unit[s]
        lo, hi = (sub_lo[s], sub_hi[s]) if unit_conc[u0] > limit else (u0, u0 + 1)
        for u in range(lo, hi):
            k = np.uint64(0)
            for t in range(unit_start[u], unit_start[u + 1]):
                f = unit_faces[t]
                k += face_key[f]
                label[f] = nid
            key[nid] = k
            conc[nid] = unit_conc[u]
            area[nid] = unit_area[u]
            perim[nid] = unit_perim[u]
            n_faces[nid] = unit_start[u + 1] - unit_start[u]
            alive[nid] = True
            hull[nid, 0], hull[nid, 1] = unit_hull[u, 0], unit_hull[u, 1]
            uhead[nid] = u
            utail[nid] = u
            nid += 1
    nb_lo, nb_n, nb_id, nb_slot, shared, conc_len, n_pairs = _adjacency(label, nid, ef0, ef1, edge_len, conc_w, cap)
    nb_end = 2 * n_pairs

    # the lazy heap: (cost, exact?, i, j); a lazy key is a lower bound of the cost (a u b is at
    # least as concave as a or b); the union's hull is computed when the pair reaches the top.
    # Each live pair has at most one entry, so compacting makes room for any cluster's pushes.
    h_cap = 2 * n_pairs + 64
    hc, he, hi_, hj = np.empty(h_cap), np.empty(h_cap, np.int64), np.empty(h_cap, np.int64), np.empty(h_cap, np.int64)
    size = 0
    for i in range(nid):
        for t in range(nb_lo[i], nb_lo[i] + nb_n[i]):
            j = nb_id[t]
            if i < j and max(conc[i], conc[j]) <= limit:
                s = nb_slot[t]
                cst = _cost(i, j, shared[s], conc_len[s], max(conc[i], conc[j]), area, perim, w_compact, w_seam, scale)
                size = _heap_push(hc, he, hi_, hj, size, cst, 0, i, j)
    stop = 1 if target < 0 else target
    n_alive = nid
    ok = True
    while size > 0 and n_alive > stop and ok:
        size = _heap_pop(hc, he, hi_, hj, size)
        ex, i, j = he[size], hi_[size], hj[size]
        if alive[i] and alive[j]:  # else a merged cluster: its ids are never reused
            u, bk = _memo_lookup(i, j, limit, key, table, keys, m_conc, m_exact)
            if u < 0:
                u = _union_eval(i, j, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, unit_pts, unit_pstart,
                                table, keys, m_conc, m_exact, m_hull, pool, used)
                ok = u >= 0
            if ok and ex == 0:
                if m_exact[u] and m_conc[u] <= limit:  # (the memo may hold exact values from runs with a larger tau)
                    s = _slot(nb_lo, nb_n, nb_id, nb_slot, i, j)
                    cst = _cost(i, j, shared[s], conc_len[s], m_conc[u], area, perim, w_compact, w_seam, scale)
                    if size + 1 > h_cap:
                        size = _heap_compact(hc, he, hi_, hj, size, alive)
                    size = _heap_push(hc, he, hi_, hj, size, cst, 1, i, j)
            elif ok:
                c = nid
                nid += 1
                if nb_end + nb_n[i] + nb_n[j] > nb_id.shape[0]:
                    nb_end = _nb_compact(nb_lo, nb_n, nb_id, nb_slot, alive, c)
                nb_end = _merge(i, j, c, u, key, conc, area, perim, n_faces, alive, hull, uhead, utail, unxt,
                                nb_lo, nb_n, nb_id, nb_slot, nb_end, shared, conc_len, m_conc, m_hull)
                n_alive -= 1
                if size + nb_n[c] > h_cap:
                    size = _heap_compact(hc, he, hi_, hj, size, alive)
                for t in range(nb_lo[c], nb_lo[c] + nb_n[c]):
                    j = nb_id[t]
                    if max(conc[c], conc[j]) <= limit:
                        s = nb_slot[t]
                        cst = _cost(c, j, shared[s], conc_len[s], max(conc[c], conc[j]), area, perim, w_compact, w_seam, scale)
                        size = _heap_push(hc, he, hi_, hj, size, cst, 0, c, j)

    # small parts join the neighbour with the cheapest admissible merge
    changed = True
    while changed and n_alive > stop and ok:
        changed = False
        ids = np.flatnonzero(alive[:nid])
        order = np.argsort(n_faces[ids], kind="mergesort")  # stable: ties in id order
        t = 0
        while t < order.shape[0] and not changed and ok:
            i = ids[order[t]]
            t += 1
            if n_faces[i] < min_faces:
                best_j, best_c, best_u = -1, 0.0, -1
                for q in range(nb_lo[i], nb_lo[i] + nb_n[i]):
                    j = nb_id[q]
                    u, bk = _memo_lookup(i, j, limit, key, table, keys, m_conc, m_exact)
                    if u < 0 and ok:
                        u = _union_eval(i, j, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, unit_pts,
                                        unit_pstart, table, keys, m_conc, m_exact, m_hull, pool, used)
                        ok = u >= 0
                    if ok and m_exact[u] and m_conc[u] <= limit:
                        s = nb_slot[q]
                        cst = _cost(i, j, shared[s], conc_len[s], m_conc[u], area, perim, w_compact, w_seam, scale)
                        if best_j < 0 or cst < best_c:
                            best_j, best_c, best_u = j, cst, u
                if ok and best_j >= 0:
                    if nb_end + nb_n[i] + nb_n[best_j] > nb_id.shape[0]:
                        nb_end = _nb_compact(nb_lo, nb_n, nb_id, nb_slot, alive, nid)
                    nb_end = _merge(i, best_j, nid, best_u, key, conc, area, perim, n_faces, alive, hull, uhead,
                                    utail, unxt, nb_lo, nb_n, nb_id, nb_slot, nb_end, shared, conc_len, m_conc, m_hull)
                    nid += 1
                    n_alive -= 1
                    changed = True
    for c in range(nid):
        if alive[c]:
            u = uhead[c]
            while u >= 0:
                for t in range(unit_start[u], unit_start[u + 1]):
                    label[unit_faces[t]] = c
                u = unxt[u]
    return label, n_alive, ok
