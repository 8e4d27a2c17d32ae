"""numba kernels of the segmenter's merging run: the cost of a merge, the lazy min-heap, the
clusters' adjacency lists and `merge_run`.

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
run's time. So the kernels run per heap entry (`_heap_pop`, `_heap_push`, `memo_lookup`,
`_slot`, `_merge`) call only trivial helpers and read their arrays on every path, loops exit
through their conditions, a run sizes its arrays once (the heap and the neighbour lists are
compacted in place when full, pair rows are reused), and a run that finds the memo full stops
and is redone on a regrown memo (`merge_run`).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from ..sorting import stable_argsort
from .memo_kernels import bucket, memo_grown, memo_lookup, pow2, union_eval


# ----------------------------------------------------------------------------------------------
# Merge cost


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
    _swap(hc, he, hi, hj, np.int64(0), size)
    k = np.int64(0)
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
    n = np.int64(0)
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
    table = np.full(pow2(2 * m + 2), -1, dtype=np.int64)
    deg = np.zeros(cap, dtype=np.int64)
    n_pairs = np.int64(0)
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
    end = np.int64(0)
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
        memo = memo_grown(memo)
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
    nid = np.int64(0)
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
    size = np.int64(0)
    for i in range(nid):
        for t in range(nb_lo[i], nb_lo[i] + nb_n[i]):
            j = nb_id[t]
            if i < j and max(conc[i], conc[j]) <= limit:
                s = nb_slot[t]
                cst = _cost(i, j, shared[s], conc_len[s], max(conc[i], conc[j]), area, perim, w_compact, w_seam, scale)
                size = _heap_push(hc, he, hi_, hj, size, cst, np.int64(0), i, j)
    stop = 1 if target < 0 else target
    n_alive = nid
    ok = True
    while size > 0 and n_alive > stop and ok:
        size = _heap_pop(hc, he, hi_, hj, size)
        ex, i, j = he[size], hi_[size], hj[size]
        if alive[i] and alive[j]:  # else a merged cluster: its ids are never reused
            u, bk = memo_lookup(i, j, limit, key, table, keys, m_conc, m_exact)
            if u < 0:
                u = union_eval(i, j, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, unit_pts, unit_pstart,
                                table, keys, m_conc, m_exact, m_hull, pool, used)
                ok = u >= 0
            if ok and ex == 0:
                if m_exact[u] and m_conc[u] <= limit:  # (the memo may hold exact values from runs with a larger tau)
                    s = _slot(nb_lo, nb_n, nb_id, nb_slot, i, j)
                    cst = _cost(i, j, shared[s], conc_len[s], m_conc[u], area, perim, w_compact, w_seam, scale)
                    if size + 1 > h_cap:
                        size = _heap_compact(hc, he, hi_, hj, size, alive)
                    size = _heap_push(hc, he, hi_, hj, size, cst, np.int64(1), i, j)
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
                        size = _heap_push(hc, he, hi_, hj, size, cst, np.int64(0), c, j)

    # small parts join the neighbour with the cheapest admissible merge
    changed = True
    while changed and n_alive > stop and ok:
        changed = False
        ids = np.flatnonzero(alive[:nid])
        order = stable_argsort(n_faces[ids])  # ties in id order
        t = np.int64(0)
        while t < order.shape[0] and not changed and ok:
            i = ids[order[t]]
            t += 1
            if n_faces[i] < min_faces:
                best_j, best_c, best_u = np.int64(-1), 0.0, np.int64(-1)
                for q in range(nb_lo[i], nb_lo[i] + nb_n[i]):
                    j = nb_id[q]
                    u, bk = memo_lookup(i, j, limit, key, table, keys, m_conc, m_exact)
                    if u < 0 and ok:
                        u = union_eval(i, j, bk, limit, diag, key, conc, n_faces, hull, uhead, unxt, unit_pts,
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
