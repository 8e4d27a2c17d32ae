"""Broad phase of the 3D collision test: sort-and-sweep over face boxes.

`sweep_pairs` is the one plain sort-and-sweep: the crossing face pairs of a set of triangles in
sweep order (`triangles.triangles_collide` on the candidates), with the skip rule as data. The
reports of one folded state, `first_collision` / `all_collisions` (for messages and tests: the
colliding pairs in the order this module always reported them), and a mesh's self-intersections
(`self_intersect.py`) both call it.

`sweep_collides` is the planners' hot loop (see `fold/checker.py`), a sweep of its own tuned for
speed: faces in an order kept from one configuration to the next (`sort_by_lo_x`, nearly sorted
between close configurations), their boxes gathered into contiguous rows (`gather_boxes`), and
candidate pairs tested with `triangles.faces_cross` until the first crossing. It gives the same
verdict as `first_collision` (tests/collide/test_sweep.py).

Skipped pairs (never tested) of a folded net: faces of different pieces, a crease pair (parent,
child); in `sweep_collides` also faces of one rigid group (rigid >= 0: their relative pose is
fixed) and degenerate faces (which `triangles_collide` finds never collide).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..sorting import stable_argsort
from .triangles import (GEO_LO, face_geometry, faces_cross, load_face, store_face, thick_collides, tri_corners,
                        triangles_collide)

NO_LIMIT = np.iinfo(np.int64).max  # `sweep_pairs`' stop_after that never stops early


@njit(cache=True)
def face_boxes(tris):
    """(lo, hi), both (F, 3): the axis-aligned box of each triangle of tris (F, 3, 3)."""
    n = tris.shape[0]
    lo = np.empty((n, 3))
    hi = np.empty((n, 3))
    for f in range(n):
        for i in range(3):
            lo[f, i] = min(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
            hi[f, i] = max(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
    return lo, hi


@njit(cache=True, inline="always")
def fill_face_geometry(tris, tol, geo, last):
    """geo[f] = the FaceGeometry of tris[f] (F, 3, 3) and its AABB, for the faces the last forward
    kinematics changed (last: see `fold.kinematics.fold_faces`); the other rows still hold their faces."""
    for f in range(tris.shape[0]):
        if last[f, 1] == 0.0:
            continue
        store_face(geo, f, face_geometry(tri_corners(tris, f), tol))
        for i in range(3):
            geo[f, GEO_LO + i] = min(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
            geo[f, GEO_LO + 3 + i] = max(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])


@njit(cache=True, inline="always")
def sort_by_lo_x(geo, sb, si):
    """Sort the face ids si[0] in place by (lo x, face id); sb[0] = their lo x.

    Consecutive configurations of a planner are close, so si[0] (the previous order) is nearly
    sorted: an insertion sort costs O(F + moves). When the moves pass 8 F (a big jump), a stable
    merge sort of the face ids instead (the same order: ties by face id). The order never depends
    on the guess. (Rows are indexed in place: a row view costs atomic reference counting.)
    """
    n = si.shape[1]
    for p in range(n):
        sb[0, p] = geo[si[0, p], GEO_LO]
    budget = 8 * n
    for p in range(1, n):
        v = sb[0, p]
        f = si[0, p]
        q = p - 1
        while q >= 0 and (sb[0, q] > v or (sb[0, q] == v and si[0, q] > f)):
            sb[0, q + 1] = sb[0, q]
            si[0, q + 1] = si[0, q]
            q -= 1
        sb[0, q + 1] = v
        si[0, q + 1] = f
        budget -= p - 1 - q
        if budget < 0:
            _merge_sort_by_lo_x(geo, sb, si)
            return


@njit(cache=True)
def _merge_sort_by_lo_x(geo, sb, si):
    """si[0] = face ids sorted by (lo x, face id) by a stable merge sort, sb[0] = their lo x (the
    rare fallback of `sort_by_lo_x`: a call, not inlined, keeps compiling fast)."""
    idx = stable_argsort(geo[:, GEO_LO])
    for r in range(si.shape[1]):
        si[0, r] = idx[r]
        sb[0, r] = geo[idx[r], GEO_LO]


@njit(cache=True, inline="always")
def gather_boxes(geo, parent, piece, rigid, sb, si):
    """Fill sb and si[1:5] for the sweep order si[0] (see `collision_work`): contiguous rows for
    the sweep's inner loop, and sb[6] = running maximum of hi x. rigid (F,) groups (-1: none)."""
    top = -np.inf
    for p in range(si.shape[1]):
        f = si[0, p]
        for r in range(6):
            sb[r, p] = geo[f, GEO_LO + (r >> 1) + 3 * (r & 1)]
        top = max(top, sb[1, p])
        sb[6, p] = top
        si[1, p] = parent[f]
        si[2, p] = piece[f]
        si[3, p] = rigid[f]
        si[4, p] = 0 if geo[f, 22] > 0.0 else 1  # FaceGeometry.sliver


@njit(cache=True, inline="always")
def largest_group(rigid, counts):
    """The rigid group holding more than half of the faces, or -1 (also when a label is not a
    face id); counts (F,) int scratch."""
    n = rigid.shape[0]
    counts[:] = 0
    for f in range(n):
        g = rigid[f]
        if g >= n:
            return -1
        if g >= 0:
            counts[g] += 1
            if 2 * counts[g] > n:
                return g
    return -1


@njit(cache=True, inline="always")
def sweep_collides(tris, geo, sb, si, tol, big, ids, thick):
    """Sort-and-sweep on x over the faces' AABBs in the order si[0] (filled by `gather_boxes`).

    A pair is tested (`faces_cross`, the face earlier in the order as a) unless its boxes are
    apart by more than tol on x, y or z, or it is not in one piece, or it is a crease pair, or
    both faces are in the same rigid group (rigid >= 0: their relative pose is fixed, see
    `config_collides_moving`), or a face is degenerate. True at the first pair that crosses.
    big >= 0: a rigid group of most faces, whose own pairs are not tested: only the other faces
    are swept, forward and backward (big = -1: forward from every face).
    sb rows: lo x, hi x, lo y, hi y, lo z, hi z, running max of hi x; si rows: face, parent,
    piece, rigid, non-degenerate, scratch. thick (2,): the paper's thickness and the reach of a
    shared point (`triangles.thick_collides`, which then tests the pairs, with ids (F, 6) the net
    and mesh vertex ids of every corner); thickness 0: `faces_cross`, ids unread.
    Returns the first crossing pair as the key i * F + j (face ids, i the face swept from), or -1.
    """
    n = tris.shape[0]
    h = thick[0]
    if h > tol:
        tol_box = h  # boxes closer than the thickness are candidates
    else:
        tol_box = tol
    for ii in range(n):
        if si[4, ii] == 0 or (big >= 0 and si[3, ii] == big):
            continue  # a degenerate face crosses nothing; big's faces are met from the others
        i = si[0, ii]
        loy = sb[2, ii]
        hiy = sb[3, ii]
        loz = sb[4, ii]
        hiz = sb[5, ii]
        # Branch-free box filters into si[5]: whether boxes overlap in y and z is hard to
        # predict, and a mispredicted branch costs more than all four comparisons.
        end = ii + 1
        while end < n and not (sb[0, end] - sb[1, ii] > tol_box):  # later faces overlapping in x
            end += 1
        k = 0
        for jj in range(ii + 1, end):
            apart = ((sb[2, jj] - hiy > tol_box) | (loy - sb[3, jj] > tol_box)
                     | (sb[4, jj] - hiz > tol_box) | (loz - sb[5, jj] > tol_box))
            si[5, k] = jj
            k += 1 - np.int64(apart)
        later = k
        if big >= 0:
            # earlier faces of big overlapping in x (the others were swept from themselves); no
            # face before jj reaches past the running maximum of hi x
            jj = ii - 1
            while jj >= 0 and not (sb[0, ii] - sb[6, jj] > tol_box):
                apart = ((sb[0, ii] - sb[1, jj] > tol_box) | (sb[2, jj] - hiy > tol_box) | (loy - sb[3, jj] > tol_box)
                         | (sb[4, jj] - hiz > tol_box) | (loz - sb[5, jj] > tol_box) | (si[3, jj] != big))
                si[5, k] = jj
                k += 1 - np.int64(apart)
                jj -= 1
        if k == 0:
            continue
        t = tri_corners(tris, i)
        gt = load_face(geo, i)
        for c in range(k):
            jj = si[5, c]
            j = si[0, jj]
            if (si[4, jj] == 0 or si[2, jj] != si[2, ii] or si[1, jj] == i or si[1, ii] == j
                    or (si[3, ii] >= 0 and si[3, jj] == si[3, ii])):
                continue
            u = tri_corners(tris, j)
            gu = load_face(geo, j)
            # a: the face earlier in the order (i for the forward sweep, j for the backward one)
            a, b, ga, gb = (t, u, gt, gu) if c < later else (u, t, gu, gt)
            if h > 0.0:
                fa, fb = (i, j) if c < later else (j, i)
                if thick_collides(a, b, ga, gb, _ids(ids, fa), _ids(ids, fb), tol, h, thick[1]):
                    return i * n + j
            elif faces_cross(a, b, ga, gb, tol):
                return i * n + j
    return -1


@njit(cache=True, inline="always")
def _ids(ids, f):
    """Row f of ids (F, 6) as a tuple (no array view: no reference counting in the hot loop)."""
    return (ids[f, 0], ids[f, 1], ids[f, 2], ids[f, 3], ids[f, 4], ids[f, 5])


@njit(cache=True)
def sweep_pairs(tris, tol, piece, parent, faces, skip_keys, stop_after, pairs):
    """Crossing face pairs of tris (F, 3, 3) by the plain sort-and-sweep on x: returns their
    number, the first pairs.shape[0] of them written to pairs (i < j, in sweep order).

    Faces in the order of np.argsort of their boxes' lo x; for each face, the later faces whose
    boxes are within tol of its box on x, y and z are the candidates, tested by
    `triangles_collide` (the face earlier in the order as a) unless the skip rule skips them.
    The rule is data, each part off when None (numba then compiles it out): piece (F,) labels:
    faces of different pieces; parent (F,) (f's parent face or -1): crease pairs; faces (F, 3)
    corner ids: faces sharing an edge (two ids); skip_keys, sorted int64 keys i * F + j (i < j):
    those pairs. Stops after stop_after hits. The one sweep of the fold reports
    (`first_collision`, `all_collisions`) and of a mesh's self-intersections
    (`self_intersect.crossing_pairs`): the pairs each reports, and their order, are the ones it
    always reported.
    """
    n = tris.shape[0]
    lo, hi = face_boxes(tris)
    xs = np.argsort(lo[:, 0])
    count = 0
    for ii in range(n):
        i = xs[ii]
        for jj in range(ii + 1, n):
            j = xs[jj]
            if lo[j, 0] - hi[i, 0] > tol:
                break
            if lo[j, 1] - hi[i, 1] > tol or lo[i, 1] - hi[j, 1] > tol:
                continue
            if lo[j, 2] - hi[i, 2] > tol or lo[i, 2] - hi[j, 2] > tol:
                continue
            if piece is not None and piece[i] != piece[j]:
                continue
            if parent is not None and (parent[i] == j or parent[j] == i):
                continue
            if faces is not None and _share_edge(faces, i, j):
                continue
            if skip_keys is not None and _listed(skip_keys, i, j, n):
                continue
            if triangles_collide(tris[i], tris[j], tol):
                if count < pairs.shape[0]:
                    pairs[count, 0] = min(i, j)
                    pairs[count, 1] = max(i, j)
                count += 1
                if count >= stop_after:
                    return count
    return count


@njit(cache=True, inline="always")
def _share_edge(faces, i, j):
    """True when faces i and j (rows of faces (F, 3)) have two corner ids in common."""
    shared = 0
    for a in range(3):
        for b in range(3):
            if faces[i, a] == faces[j, b]:
                shared += 1
    return shared >= 2


@njit(cache=True, inline="always")
def _listed(keys, i, j, n):
    """True when the key min(i, j) * n + max(i, j) is in the sorted keys."""
    key = min(i, j) * n + max(i, j)
    k = np.searchsorted(keys, key)
    return k < keys.shape[0] and keys[k] == key


@njit(cache=True)
def first_collision(tris, parent, piece, tol):
    """First colliding face pair (i, j), i < j, of folded faces tris (F, 3, 3), or (-1, -1):
    the first hit of `sweep_pairs`, skipping pairs of different pieces and crease pairs."""
    pairs = np.empty((1, 2), dtype=np.int64)
    if sweep_pairs(tris, tol, piece, parent, None, None, 1, pairs) > 0:
        return pairs[0, 0], pairs[0, 1]
    return -1, -1


@njit(cache=True)
def all_collisions(tris, parent, piece, tol, max_pairs):
    """(count, pairs): all colliding pairs (count) of `sweep_pairs` with the skip rule of
    `first_collision`, the first min(count, max_pairs) of them."""
    pairs = np.empty((max(max_pairs, 1), 2), dtype=np.int64)
    count = sweep_pairs(tris, tol, piece, parent, None, None, NO_LIMIT, pairs[:max_pairs])
    return count, pairs[: min(count, max_pairs)]
