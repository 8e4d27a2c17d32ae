"""numba kernels of the segmenter: convex hull, depth below a hull, and one merging run.

`merge_run` is the whole hierarchical merging of segment.py (ALGORITHMS.md 4.4) in one call:
clusters, their adjacency, the lazy min-heap and the small-part clean-up live in plain arrays and
typed containers, so a run costs microseconds per merge instead of a Python object's overhead.
The union concavities are memoized in a `Memo` that outlives one run, since `parts=K` runs the
merging once per tau it tries and most pairs recur.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.typed import Dict, List

NOISE = 1e-12  # depths below NOISE * bbox diagonal are rounding noise of the hull planes: convex
FLAT_EPS = 1e-12  # relative to the points' extent: thinner sets have no volume (concavity 0)


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
def convex_hull(p, rel_eps):
    """3D convex hull of the points p (n, 3): (ids of hull vertices, facet equations (m, 4)).

    Facet planes are unit outward normals with offsets, n.x + d <= 0 inside (qhull's convention).
    Empty equations when the points span no volume (thinner than rel_eps * their extent).
    Incremental: start from a tetrahedron of extreme points; each point above some facets (by more
    than the tolerance) replaces them by a cone over their boundary edges, the horizon. The
    horizon is found as the edges whose reverse lies on a kept facet, so the surface stays closed
    even if rounding makes the visible region odd. O(n * facets^2): meant for the small sets of
    the merging (tens of points), where qhull's per-call set-up (about 45 us) is most of its cost.
    """
    n = p.shape[0]
    empty_v = np.empty(0, dtype=np.int64)
    empty_e = np.empty((0, 4))
    if n < 4:
        return empty_v, empty_e
    ext = 0.0
    for k in range(3):
        ext = max(ext, p[:, k].max() - p[:, k].min())
    eps = rel_eps * ext
    if ext <= 0:
        return empty_v, empty_e
    # initial tetrahedron: extreme x, farthest from it, farthest from their line, farthest from the plane
    i0 = np.argmin(p[:, 0])
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
    hor = np.empty((cap, 2), dtype=np.int64)
    for i in range(n):
        if i == i0 or i == i1 or i == i2 or i == i3:
            continue
        x, y, z = p[i, 0], p[i, 1], p[i, 2]
        any_vis = False
        for f in range(nf):
            vis[f] = False
            if alive[f] and E[f, 0] * x + E[f, 1] * y + E[f, 2] * z + E[f, 3] > eps:
                vis[f] = True
                any_vis = True
        if not any_vis:
            continue
        # horizon: directed edges of visible faces whose reverse lies on an alive invisible face
        nh = 0
        for f in range(nf):
            if not vis[f]:
                continue
            for k in range(3):
                a, b = F[f, k], F[f, (k + 1) % 3]
                for g in range(nf):
                    if not alive[g] or vis[g]:
                        continue
                    if (F[g, 0] == b and F[g, 1] == a) or (F[g, 1] == b and F[g, 2] == a) or (F[g, 2] == b and F[g, 0] == a):
                        hor[nh, 0], hor[nh, 1] = a, b
                        nh += 1
                        break
        if nf + nh > cap:  # cannot happen for a consistent hull; be safe
            return empty_v, empty_e
        for f in range(nf):
            if vis[f]:
                alive[f] = False
        for h in range(nh):
            a, b = hor[h, 0], hor[h, 1]
            F[nf, 0], F[nf, 1], F[nf, 2] = a, b, i
            nx, ny, nz, d, ln = _plane(p, a, b, i)
            E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
            alive[nf] = ln > 0
            nf += 1
        # compact when the dead faces dominate, so the loops stay short
        if nf > 2 * n + 64:
            m = 0
            for f in range(nf):
                if alive[f]:
                    F[m] = F[f]
                    E[m] = E[f]
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
            eq[m] = E[f]
            m += 1
    return np.flatnonzero(used), eq


@njit(cache=True)
def max_depth(pts, eq, limit):
    """max_i min_j -(eq[j, :3] . pts[i] + eq[j, 3]) (>= 0); stops early once it exceeds `limit`."""
    best = 0.0
    n_f = eq.shape[0]
    hint = 0
    for i in range(pts.shape[0]):
        x, y, z = pts[i, 0], pts[i, 1], pts[i, 2]
        # The facet that bounded the previous point first: neighbouring points share facets.
        m = -(eq[hint, 0] * x + eq[hint, 1] * y + eq[hint, 2] * z + eq[hint, 3])
        if m <= best:
            continue
        for j in range(n_f):
            d = -(eq[j, 0] * x + eq[j, 1] * y + eq[j, 2] * z + eq[j, 3])
            if d < m:
                m = d
                hint = j
                if m <= best:
                    break
        if m > best:
            best = m
            if best > limit:
                return best
    return best


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
# Clusters


@njit(cache=True)
def make_cluster(faces, mesh_faces, vertices, samples, diag):
    """(points, hull points, absolute concavity) of the faces (sorted ids): the points are the
    faces' vertices (sorted ids) then their surface samples; the hull is of the vertices."""
    verts = np.unique(mesh_faces[faces].ravel())
    n_v = verts.shape[0]
    pts = np.empty((n_v + 3 * faces.shape[0], 3))
    for k in range(n_v):
        pts[k] = vertices[verts[k]]
    for k in range(faces.shape[0]):
        for s in range(3):
            pts[n_v + 3 * k + s] = samples[faces[k], s]
    vpts = pts[:n_v].copy()
    hv, eq = convex_hull(vpts, FLAT_EPS)
    if eq.shape[0] == 0:
        return pts, vpts, 0.0
    return pts, vpts[hv], denoise(max_depth(pts, eq, np.inf), diag)


POINTS = types.float64[:, ::1]  # element type of the typed lists of point arrays
IDS = types.int64[::1]
PAIR = types.UniTuple(types.int64, 2)
KEYPAIR = types.UniTuple(types.uint64, 2)


@njit(cache=True)
def new_memo():
    """Empty memo of union concavities, kept across the runs of one segment() call: slot index
    by the pair of cluster keys, then concavity, exact?, hull points per slot.

    Cluster keys are sums of random 64-bit face keys: the key of a union is the sum of its parts'
    keys, and two distinct face sets collide with probability ~2^-64. (Made here, not in Python:
    numba builds typed containers faster.)"""
    return (Dict.empty(key_type=KEYPAIR, value_type=types.int64), List.empty_list(types.float64),
            List.empty_list(types.boolean), List.empty_list(POINTS))


@njit(cache=True)
def make_units(faces, start, mesh_faces, vertices, samples, diag):
    """`make_cluster` of each face list faces[start[u]:start[u + 1]]: (points, hulls, concavities)."""
    n = start.shape[0] - 1
    pts = List.empty_list(POINTS)
    hulls = List.empty_list(POINTS)
    conc = np.empty(n)
    for u in range(n):
        p, h, c = make_cluster(faces[start[u]:start[u + 1]], mesh_faces, vertices, samples, diag)
        pts.append(p)
        hulls.append(h)
        conc[u] = c
    return pts, hulls, conc


@njit(cache=True)
def _union_conc(a, b, limit, key, conc, n_faces, hulls, pts, diag, m_index, m_conc, m_exact, m_hull):
    """Memo slot of (absolute concavity of a u b, exact?, hull points of a u b); inexact values
    exceed the limit (the depth kernel stopped early, or a part alone exceeds it)."""
    ka, kb = key[a], key[b]
    mk = (ka, kb) if ka < kb else (kb, ka)
    slot = -1
    if mk in m_index:
        slot = m_index[mk]
        if m_exact[slot] or m_conc[slot] > limit:
            return slot
    floor = max(conc[a], conc[b])
    ha, hb = hulls[a], hulls[b]
    if floor > limit:  # decided without a hull (most candidate pairs once clusters grow)
        value, exact, hull = floor, False, np.empty((0, 3))
    elif n_faces[a] + n_faces[b] == 2:
        # two triangles sharing an edge are two faces of their tetrahedron: concavity 0
        value, exact, hull = 0.0, True, np.concatenate((ha, hb))
    else:
        both = np.concatenate((ha, hb))
        hv, eq = convex_hull(both, FLAT_EPS)
        if eq.shape[0] == 0:
            value, exact, hull = 0.0, True, both
        else:
            # the kernel stops early (a lower bound) once the depth exceeds the limit; rounding
            # noise must not count as exceeding it
            stop = max(limit, NOISE * diag)
            d = max_depth(np.concatenate((pts[a], pts[b])), eq, stop)
            value, exact, hull = denoise(d, diag), d <= stop, both[hv]
    if slot < 0:
        slot = len(m_conc)
        m_index[mk] = slot
        m_conc.append(value)
        m_exact.append(exact)
        m_hull.append(hull)
    else:
        m_conc[slot] = value
        m_exact[slot] = exact
        m_hull[slot] = hull
    return slot


@njit(cache=True)
def _cost(a, b, shared, conc_len, c, area, perim, w_compact, w_seam, scale):
    ar = area[a] + area[b]
    pe = perim[a] + perim[b] - 2 * shared
    compact = pe * pe / (4 * math.pi * ar) - 1.0 if ar > 0 else 0.0
    seam = conc_len / shared if shared > 0 else 0.0
    return c + (w_compact * compact + w_seam * seam) * scale


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
def _heap_push(hc, he, hi, hj, size, c, e, i, j):
    k = size
    hc[k], he[k], hi[k], hj[k] = c, e, i, j
    while k > 0:
        p = (k - 1) >> 1
        if not _less(hc[k], he[k], hi[k], hj[k], hc[p], he[p], hi[p], hj[p]):
            break
        hc[p], hc[k] = hc[k], hc[p]
        he[p], he[k] = he[k], he[p]
        hi[p], hi[k] = hi[k], hi[p]
        hj[p], hj[k] = hj[k], hj[p]
        k = p
    return size + 1


@njit(cache=True)
def _heap_pop(hc, he, hi, hj, size):
    """Remove the smallest entry (moved to index `size - 1` for the caller to read)."""
    size -= 1
    hc[0], hc[size] = hc[size], hc[0]
    he[0], he[size] = he[size], he[0]
    hi[0], hi[size] = hi[size], hi[0]
    hj[0], hj[size] = hj[size], hj[0]
    k = 0
    while True:
        c = 2 * k + 1
        if c >= size:
            break
        if c + 1 < size and _less(hc[c + 1], he[c + 1], hi[c + 1], hj[c + 1], hc[c], he[c], hi[c], hj[c]):
            c += 1
        if not _less(hc[c], he[c], hi[c], hj[c], hc[k], he[k], hi[k], hj[k]):
            break
        hc[c], hc[k] = hc[k], hc[c]
        he[c], he[k] = he[k], he[c]
        hi[c], hi[k] = hi[k], hi[c]
        hj[c], hj[k] = hj[k], hj[c]
        k = c
    return size


@njit(cache=True)
def _reserve(hc, he, hi, hj, need):
    """The heap arrays with room for `need` entries (doubled when short)."""
    if need <= hc.shape[0]:
        return hc, he, hi, hj
    n = max(need, 2 * hc.shape[0])
    c2, e2, i2, j2 = np.empty(n), np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    m = hc.shape[0]
    c2[:m], e2[:m], i2[:m], j2[:m] = hc, he, hi, hj
    return c2, e2, i2, j2


@njit(cache=True)
def _slot(nb_id, nb_slot, i, j):
    ids = nb_id[i]
    for t in range(ids.shape[0]):
        if ids[t] == j:
            return nb_slot[i][t]
    return -1


@njit(cache=True)
def _relink(nb_id, nb_slot, k, i, j, c, s):
    """Neighbour k of the clusters i, j now merged into c: drop i and j from k's neighbours and
    append c (slot s) unless it is there already (then it keeps its place, as a dict would)."""
    ids, sl = nb_id[k], nb_slot[k]
    for t in range(ids.shape[0]):
        if ids[t] == c:
            return
    n = 1
    for t in range(ids.shape[0]):
        if ids[t] != i and ids[t] != j:
            n += 1
    new_ids = np.empty(n, np.int64)
    new_sl = np.empty(n, np.int64)
    q = 0
    for t in range(ids.shape[0]):
        if ids[t] != i and ids[t] != j:
            new_ids[q], new_sl[q] = ids[t], sl[t]
            q += 1
    new_ids[q], new_sl[q] = c, s
    nb_id[k] = new_ids
    nb_slot[k] = new_sl


@njit(cache=True)
def _merge(i, j, c, u, key, conc, area, perim, n_faces, alive, head, tail, nxt, pts, hulls,
           nb_id, nb_slot, shared, conc_len, m_conc, m_hull):
    """Merge clusters i and j (memo slot u holds their exact union) into the new cluster c."""
    s_ij = _slot(nb_id, nb_slot, i, j)
    alive[i] = False
    alive[j] = False
    alive[c] = True
    key[c] = key[i] + key[j]
    conc[c] = m_conc[u]
    area[c] = area[i] + area[j]
    perim[c] = perim[i] + perim[j] - 2 * shared[s_ij]
    n_faces[c] = n_faces[i] + n_faces[j]
    head[c] = head[i]
    nxt[tail[i]] = head[j]
    tail[c] = tail[j]
    pts.append(np.concatenate((pts[i], pts[j])))
    hulls.append(m_hull[u])
    new_ids = np.empty(nb_id[i].shape[0] + nb_id[j].shape[0], np.int64)
    new_sl = np.empty_like(new_ids)
    n_new = 0
    for src in (i, j):
        ids, sl = nb_id[src], nb_slot[src]
        for t in range(ids.shape[0]):
            k = ids[t]
            if k == i or k == j:
                continue
            pos = -1
            for q in range(n_new):
                if new_ids[q] == k:
                    pos = q
                    break
            if pos < 0:  # the shared lengths of a u b with k: a's, plus b's below
                s2 = len(shared)
                shared.append(shared[sl[t]])
                conc_len.append(conc_len[sl[t]])
                new_ids[n_new], new_sl[n_new] = k, s2
                n_new += 1
            else:
                s2 = new_sl[pos]
                shared[s2] += shared[sl[t]]
                conc_len[s2] += conc_len[sl[t]]
            _relink(nb_id, nb_slot, k, i, j, c, s2)
    nb_id.append(new_ids[:n_new].copy())
    nb_slot.append(new_sl[:n_new].copy())


@njit(cache=True)
def merge_run(limit, scale, target, w_compact, w_seam, min_faces, diag,
              seed_unit, sub_lo, sub_hi, unit_faces, unit_start, unit_pts, unit_hull, unit_conc,
              unit_area, unit_perim, face_key, ef0, ef1, edge_len, conc_w,
              m_index, m_conc, m_exact, m_hull):
    """One merging run of segment._run: the cluster id of every face at the end (ids ascend in
    creation order, as the parts of the Python version did).

    Units are candidate initial clusters with precomputed points, hull, concavity, area and
    perimeter; unit u holds faces unit_faces[unit_start[u]:unit_start[u + 1]]. Seed s is unit
    seed_unit[s]; when its concavity exceeds the limit its polygons, units sub_lo[s]:sub_hi[s],
    start instead. ef0, ef1, edge_len, conc_w: the inner edges' faces, lengths and concave-weighted
    lengths. target < 0: merge while admissible pairs remain; else stop at `target` clusters.
    m_*: the Memo's containers (read and extended).
    """
    n_fm = face_key.shape[0]
    cap = 2 * n_fm + 1
    key = np.zeros(cap, dtype=np.uint64)
    conc = np.zeros(cap)
    area = np.zeros(cap)
    perim = np.zeros(cap)
    n_faces = np.zeros(cap, dtype=np.int64)
    alive = np.zeros(cap, dtype=np.bool_)
    head = np.full(cap, -1, dtype=np.int64)  # each cluster's faces: a linked list head -> nxt -> tail
    tail = np.full(cap, -1, dtype=np.int64)
    nxt = np.full(n_fm, -1, dtype=np.int64)
    label = np.empty(n_fm, dtype=np.int64)
    pts = List.empty_list(POINTS)
    hulls = List.empty_list(POINTS)
    nid = 0
    for s in range(seed_unit.shape[0]):
        u0 = seed_unit[s]
        lo, hi = (sub_lo[s], sub_hi[s]) if unit_conc[u0] > limit else (u0, u0 + 1)
        for u in range(lo, hi):
            k = np.uint64(0)
            prev = -1
            for t in range(unit_start[u], unit_start[u + 1]):
                f = unit_faces[t]
                k += face_key[f]
                label[f] = nid
                if prev < 0:
                    head[nid] = f
                else:
                    nxt[prev] = f
                prev = f
            tail[nid] = prev
            key[nid] = k
            conc[nid] = unit_conc[u]
            area[nid] = unit_area[u]
            perim[nid] = unit_perim[u]
            n_faces[nid] = unit_start[u + 1] - unit_start[u]
            alive[nid] = True
            pts.append(unit_pts[u])
            hulls.append(unit_hull[u])
            nid += 1
    # adjacency: one slot of (shared length, concave-weighted length) per adjacent pair, summed
    # over the shared edges in edge order; each cluster lists its neighbours in first-seen order
    pair_slot = Dict.empty(key_type=PAIR, value_type=types.int64)
    shared = List.empty_list(types.float64)
    conc_len = List.empty_list(types.float64)
    first = np.empty((ef0.shape[0], 2), dtype=np.int64)
    deg = np.zeros(nid, dtype=np.int64)
    for e in range(ef0.shape[0]):
        x, y = label[ef0[e]], label[ef1[e]]
        if x == y:
            continue
        pk = (x, y) if x < y else (y, x)
        if pk in pair_slot:
            ps = pair_slot[pk]
            shared[ps] += edge_len[e]
            conc_len[ps] += conc_w[e]
        else:
            ps = len(shared)
            pair_slot[pk] = ps
            shared.append(edge_len[e])
            conc_len.append(conc_w[e])
            first[ps, 0], first[ps, 1] = x, y
            deg[x] += 1
            deg[y] += 1
    nb_id = List.empty_list(IDS)
    nb_slot = List.empty_list(IDS)
    for c in range(nid):
        nb_id.append(np.empty(deg[c], np.int64))
        nb_slot.append(np.empty(deg[c], np.int64))
    fill = np.zeros(nid, dtype=np.int64)
    for s in range(len(shared)):
        for x, y in ((first[s, 0], first[s, 1]), (first[s, 1], first[s, 0])):
            nb_id[x][fill[x]] = y
            nb_slot[x][fill[x]] = s
            fill[x] += 1

    # the lazy heap: (cost, exact?, i, j); a lazy key is a lower bound of the cost (a u b is at
    # least as concave as a or b); the union's hull is computed when the pair reaches the top
    size = 0
    hc, he, hi_, hj = np.empty(64), np.empty(64, np.int64), np.empty(64, np.int64), np.empty(64, np.int64)
    for i in range(nid):
        hc, he, hi_, hj = _reserve(hc, he, hi_, hj, size + nb_id[i].shape[0])
        for t in range(nb_id[i].shape[0]):
            j = nb_id[i][t]
            if i < j:
                floor = max(conc[i], conc[j])
                if floor <= limit:
                    s = nb_slot[i][t]
                    cst = _cost(i, j, shared[s], conc_len[s], floor, area, perim, w_compact, w_seam, scale)
                    size = _heap_push(hc, he, hi_, hj, size, cst, 0, i, j)
    stop = 1 if target < 0 else target
    n_alive = nid
    while size > 0 and n_alive > stop:
        size = _heap_pop(hc, he, hi_, hj, size)
        ex, i, j = he[size], hi_[size], hj[size]
        if not alive[i] or not alive[j]:  # a merged cluster: its ids are never reused
            continue
        if ex == 0:
            u = _union_conc(i, j, limit, key, conc, n_faces, hulls, pts, diag, m_index, m_conc, m_exact, m_hull)
            if m_exact[u] and m_conc[u] <= limit:  # (the memo may hold exact values from runs with a larger tau)
                s = _slot(nb_id, nb_slot, i, j)
                cst = _cost(i, j, shared[s], conc_len[s], m_conc[u], area, perim, w_compact, w_seam, scale)
                hc, he, hi_, hj = _reserve(hc, he, hi_, hj, size + 1)
                size = _heap_push(hc, he, hi_, hj, size, cst, 1, i, j)
            continue
        u = _union_conc(i, j, limit, key, conc, n_faces, hulls, pts, diag, m_index, m_conc, m_exact, m_hull)
        c = nid
        nid += 1
        _merge(i, j, c, u, key, conc, area, perim, n_faces, alive, head, tail, nxt, pts, hulls,
               nb_id, nb_slot, shared, conc_len, m_conc, m_hull)
        n_alive -= 1
        hc, he, hi_, hj = _reserve(hc, he, hi_, hj, size + nb_id[c].shape[0])
        for t in range(nb_id[c].shape[0]):
            j = nb_id[c][t]
            floor = max(conc[c], conc[j])
            if floor <= limit:
                s = nb_slot[c][t]
                cst = _cost(c, j, shared[s], conc_len[s], floor, area, perim, w_compact, w_seam, scale)
                size = _heap_push(hc, he, hi_, hj, size, cst, 0, c, j)

    # small parts join the neighbour with the cheapest admissible merge
    changed = True
    while changed and n_alive > stop:
        changed = False
        ids = np.flatnonzero(alive[:nid])
        for t in np.argsort(n_faces[ids], kind="mergesort"):  # stable: ties in id order
            i = ids[t]
            if n_faces[i] >= min_faces:
                continue
            best_j, best_c = -1, 0.0
            for q in range(nb_id[i].shape[0]):
                j = nb_id[i][q]
                u = _union_conc(i, j, limit, key, conc, n_faces, hulls, pts, diag, m_index, m_conc, m_exact, m_hull)
                if m_exact[u] and m_conc[u] <= limit:
                    s = nb_slot[i][q]
                    cst = _cost(i, j, shared[s], conc_len[s], m_conc[u], area, perim, w_compact, w_seam, scale)
                    if best_j < 0 or cst < best_c:
                        best_j, best_c = j, cst
            if best_j >= 0:
                u = _union_conc(i, best_j, limit, key, conc, n_faces, hulls, pts, diag, m_index, m_conc, m_exact, m_hull)
                _merge(i, best_j, nid, u, key, conc, area, perim, n_faces, alive, head, tail, nxt, pts, hulls,
                       nb_id, nb_slot, shared, conc_len, m_conc, m_hull)
                nid += 1
                n_alive -= 1
                changed = True
                break
    for c in range(nid):
        if alive[c]:
            f = head[c]
            while f >= 0:
                label[f] = c
                f = nxt[f]
    return label
