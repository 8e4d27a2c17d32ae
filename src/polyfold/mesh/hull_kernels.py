"""numba kernels of a 3D convex hull (incremental) and of the depth of points below it, for the
concavity of a mesh (`geometry.concavity`, `polyfold info`) and of the segmenter's parts and unions
(segment/, ALGORITHMS.md 4.2).

Written for the small sets of the segmenter's merging (tens of points), where qhull's per-call
set-up (about 45 us) costs more than the hull; `geometry.hull_planes` calls it up to a given
number of points and qhull beyond, where this kernel's scan of every facet per point costs more.
`depth_chain` measures the points of a chain of units (see segment/merge_kernels) against a hull
with an early exit once the depth exceeds a limit.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit

NOISE = 1e-12  # depths below NOISE * bbox diagonal are rounding noise of the hull planes: convex
HULL_FLAT_EPS = 1e-12  # relative to the points' extent: thinner sets have no volume (concavity 0)
MAX_HULL_EPS = 1e-6  # relative: the largest tolerance `convex_hull` retries an inconsistent hull at
# convex_hull counts facets per directed edge in an n x n table up to this many points, beyond in a hash
# table: the table's n^2 counts (set to zero per hull) cost more from about 300 points (at 400 points
# 0.4-1.5 ms a hull against 0.4 ms hashed; at 1,000 points 10 ms against 1.2 ms)
DENSE_EDGES = 256
HASH_MUL = 0x9E3779B97F4A7C15  # Fibonacci hashing of the edge keys beyond DENSE_EDGES points (uint64, wrapping)


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
def _compact(F, E, alive, nf):
    """Move the live facets among the first nf to the front, in order: their number."""
    m = 0
    for f in range(nf):
        if alive[f]:
            F[m, 0], F[m, 1], F[m, 2] = F[f, 0], F[f, 1], F[f, 2]
            E[m, 0], E[m, 1], E[m, 2], E[m, 3] = E[f, 0], E[f, 1], E[f, 2], E[f, 3]
            alive[m] = True
            m += 1
    return m


@njit(cache=True)
def _table_size(n):
    """Slots of the hashed edge table for n points: a power of two at least 8 times the 6 n
    directed edges of a hull's 2 n facets, so it stays at most half full between rehashes."""
    size = 1
    while size < 48 * n:
        size *= 2
    return size


@njit(cache=True)
def _slot(keys, fill, key, dense):
    """The slot of directed edge key `key` (a * n + b): the key itself when dense, else its slot in
    the open-addressing table `keys` (length a power of two, -1 empty, linear probing), taken
    (fill[0] counts the keys) if it is not there yet."""
    if dense:
        return key
    mask = keys.shape[0] - 1
    h = np.int64(((np.uint64(key) * np.uint64(HASH_MUL)) >> np.uint64(29)) & np.uint64(mask))
    while keys[h] != key:
        if keys[h] == -1:
            keys[h] = key
            fill[0] += 1
            return h
        h = (h + 1) & mask
    return h


@njit(cache=True)
def _rehash(keys, fill, on, F, alive, nf, n):
    """Empty the hashed edge table and count the live facets' edges again (keys whose facets have
    all gone stay taken otherwise). `seen` is all zero between points, so it needs no rebuild."""
    keys[:] = -1
    on[:] = 0
    fill[0] = 0
    for f in range(nf):
        if alive[f]:
            for k in range(3):
                on[_slot(keys, fill, F[f, k] * n + F[f, (k + 1) % 3], False)] += 1


@njit(cache=True)
def convex_hull(p, rel_eps):
    """3D convex hull of the points p (n, 3): (ids of hull vertices, facet equations (m, 4)); see
    `_hull_at`. A hull that does not close up as a convex polytope (2 V - 4 facets), which nearly
    coplanar points can make at rel_eps (the flat sides of a subdivided mesh: 24 vertices and 129
    facets where qhull has 16 and 28), is made again with a tolerance 100 times larger, up to
    MAX_HULL_EPS."""
    dense = p.shape[0] <= DENSE_EDGES
    v, e = _hull_at(p, rel_eps, dense)
    r = rel_eps
    while e.shape[0] > 0 and e.shape[0] != 2 * v.shape[0] - 4 and r < MAX_HULL_EPS:
        r *= 100.0
        v, e = _hull_at(p, r, dense)
    return v, e


@njit(cache=True)
def _hull_at(p, rel_eps, dense):
    """3D convex hull of the points p (n, 3): (ids of hull vertices, facet equations (m, 4)); the
    edge counts in an n x n table when `dense`, else hashed (the same hull either way).

    Facet planes are unit outward normals with offsets, n.x + d <= 0 inside (qhull's convention).
    Empty equations when the points span no volume (thinner than rel_eps * their extent).
    Incremental: start from a tetrahedron of extreme points; each point above some facets (by more
    than the tolerance) replaces them by a cone over their boundary edges, the horizon. The
    horizon is found as the edges whose reverse lies on a kept facet, so the surface stays closed
    even if rounding makes the visible region odd: a count of the live facets on each directed
    edge answers that per edge.
    Each point is tested against every live facet, so the time grows as n times the hull's size:
    meant for small sets (the merging's tens of points, where qhull's per-call set-up, about
    45 us, is most of its cost) up to a whole mesh's thousands of vertices.
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
    i0 = np.int64(0)  # (int64 from the start: literals compile the helpers they reach twice)
    for i in range(1, n):
        if p[i0, 0] == p[i0, 0] and (p[i, 0] < p[i0, 0] or p[i, 0] != p[i, 0]):
            i0 = i
    i1, best = np.int64(-1), -1.0
    for i in range(n):
        d = (p[i, 0] - p[i0, 0]) ** 2 + (p[i, 1] - p[i0, 1]) ** 2 + (p[i, 2] - p[i0, 2]) ** 2
        if d > best:
            best, i1 = d, i
    d01 = math.sqrt(best)
    i2, best = np.int64(-1), -1.0
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
    nf = np.int64(0)
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
    hor = np.empty((3 * cap, 2), dtype=np.int64)  # every edge of every visible facet at most
    n_live, nf_kept = nf, nf
    # live facets having directed edge a->b (`on`), and the same among the facets visible from the
    # current point (`seen`), at slot a * n + b (dense) or at its slot in the hash table `keys`
    size = n * n if dense else _table_size(n)
    keys = np.full(1 if dense else size, -1, dtype=np.int64)
    on = np.zeros(size, dtype=np.int32)
    seen = np.zeros(size, dtype=np.int32)
    fill = np.zeros(1, dtype=np.int64)  # keys taken (hashed)
    for f in range(nf):
        for k in range(3):
            on[_slot(keys, fill, F[f, k] * n + F[f, (k + 1) % 3], dense)] += 1
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
        # Room for this point's keys (the reverse of each visible edge, 3 per horizon edge): the
        # keys of gone facets dropped, else a table twice as large.
        if not dense and 2 * (fill[0] + 12 * nv) > size:
            _rehash(keys, fill, on, F, alive, nf, n)
            while 2 * (fill[0] + 12 * nv) > size:
                size *= 2
                keys = np.full(size, -1, dtype=np.int64)
                on = np.zeros(size, dtype=np.int32)
                seen = np.zeros(size, dtype=np.int32)
                _rehash(keys, fill, on, F, alive, nf, n)
        # horizon: directed edges of visible faces whose reverse lies on an alive invisible face
        for q in range(nv):
            for k in range(3):
                seen[_slot(keys, fill, F[vl[q], k] * n + F[vl[q], (k + 1) % 3], dense)] += 1
        nh = 0
        for q in range(nv):
            for k in range(3):
                a, b = F[vl[q], k], F[vl[q], (k + 1) % 3]
                r = _slot(keys, fill, b * n + a, dense)
                if on[r] > seen[r]:
                    hor[nh, 0], hor[nh, 1] = a, b
                    nh += 1
        if nf_kept + nh > cap:  # cannot happen for a consistent hull; be safe
            return empty_v, empty_e
        for q in range(nv):
            alive[vl[q]] = False
            n_live -= 1
            for k in range(3):
                e = _slot(keys, fill, F[vl[q], k] * n + F[vl[q], (k + 1) % 3], dense)
                seen[e] -= 1
                on[e] -= 1
        if nf + nh > cap:  # nearly coplanar points can make the visible region odd: room first
            nf = _compact(F, E, alive, nf)
            if nf + nh > cap:
                return empty_v, empty_e
        for h in range(nh):
            a, b = hor[h, 0], hor[h, 1]
            F[nf, 0], F[nf, 1], F[nf, 2] = a, b, i
            nx, ny, nz, d, ln = _plane(p, a, b, i)
            E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
            alive[nf] = ln > 0
            n_live += ln > 0
            if ln > 0:
                on[_slot(keys, fill, a * n + b, dense)] += 1
                on[_slot(keys, fill, b * n + i, dense)] += 1
                on[_slot(keys, fill, i * n + a, dense)] += 1
            nf += 1
        # Compact (keeping the order) once the dead faces are half, so the loops stay short. The
        # safety check above counts the faces as compacting at 2n + 64 kept them (nf_kept), the
        # rule this kernel had, so it decides as before.
        nf_kept += nh
        if nf_kept > 2 * n + 64:
            nf_kept = n_live
        if nf > 2 * n_live:
            nf = _compact(F, E, alive, nf)
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
    `limit`. The loops are written out, not split into calls."""
    n_f = eq.shape[0]
    best, hint, done = 0.0, 0, False
    u, in_b = ua, False
    while u >= 0:
        i = pstart[u]
        while i < pstart[u + 1] and not done:
            x, y, z = pts[i, 0], pts[i, 1], pts[i, 2]
            # The facet that bounded the previous point first: neighbouring points share facets.
            m = -(eq[hint, 0] * x + eq[hint, 1] * y + eq[hint, 2] * z + eq[hint, 3])
            j, start = 1, hint
            while j < n_f and m > best:  # the point's depth, or any value <= best once it is known to be
                f = start + j if start + j < n_f else start + j - n_f  # on from the hint
                d = -(eq[f, 0] * x + eq[f, 1] * y + eq[f, 2] * z + eq[f, 3])
                if d < m:
                    m = d
                    hint = f
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
    return depth_chain(pts, np.array([0, pts.shape[0]]), np.array([-1]), np.int64(0), np.int64(-1), eq, limit)


@njit(cache=True)
def denoise(depth, diag):
    return 0.0 if depth <= NOISE * diag else depth
