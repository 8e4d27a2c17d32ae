"""Folding a net in 3D: forward kinematics of the crease tree and the self-intersection test.

A configuration q (E,) holds one fold angle per net edge (radians, internal convention rho:
positive = mountain / convex, ALGORITHMS.md 1.2); only the tree creases are read. Forward
kinematics (ALGORITHMS.md 6.1): piece roots stay where the flat net puts them (plane z = 0, outer
side facing +z); every other face is its parent's transform followed by a rotation by
q[crease] about the crease, directed along the parent's CCW order (right-hand rule), so a positive
angle moves the child below the parent's plane. Folding to `goal` rebuilds the foldedForm up to one
rigid motion per piece.

Self-intersection (ALGORITHMS.md 6.2): two faces collide when their relative interiors cross
(within the tolerance `tol`); touching is allowed: sharing a vertex or an edge, a vertex or an
edge resting on the other face, coplanar faces side by side. Coplanar faces whose interiors overlap
collide (paper cannot pass through paper). Every pair of faces of one piece is tested except the
crease pairs (parent, child), including faces that share a net vertex and twins of a cut edge.

The numba kernels take plain arrays so a planner can call them inside its own @njit loops:
`forward_kinematics`, `triangles_collide`, `first_collision`, `config_collides`, and for planners
`collision_work` + `segment_collides` (all the samples of a segment in one call, reusing what did
not change from one configuration to the next).
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import _tree_kernels as TK
from .errors import PolyfoldError
from .mesh import vector_norm

CONTACT_TOL = 1e-7  # contact tolerance, as a fraction of the model's bounding-box diagonal
_AXIS_EPS2 = 1e-24  # a candidate axis is skipped when |axis| < 1e-12 * (product of the lengths crossed)
_CUT = ("B", "C")  # assignments that do not join faces (FOLD 1.2 adds C = cut)
_CREASE = ("M", "V", "F", "U", "J")


# --------------------------------------------------------------------------------------------------
# numba kernels
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def forward_kinematics(q, order, parent, crease, axis, flat, R, T, out):
    """Fold the net: out[f] = R[f] @ flat[f, k] + T[f] for every face (allocation-free).

    q (E,) fold angles (rho); order (F,) parents first; parent/crease (F,) (-1 at roots);
    axis (F, 2) corners of the parent at the crease ends, a -> b in the parent's CCW order;
    flat (F, 3, 3) flat corners (z = 0). R (F, 3, 3), T (F, 3), out (F, 3, 3) are overwritten.
    """
    _fold(q, order, parent, crease, axis, flat, R, T, out, None)
    return out


# The per-configuration kernels below are inlined into their callers (inline="always"): a call
# between compiled functions updates the reference count of every array argument atomically
# (~5 ns each), which summed to about a third of a small net's collision test.


@njit(cache=True, inline="always")
def _fold(q, order, parent, crease, axis, flat, R, T, out, last):
    """`forward_kinematics`, inlined. last: None, or (F, 2) per face the crease angle R, T, out
    of the face were last computed with (NaN: never; roots 0.0) and whether this call changed
    them (1.0) or not (0.0). A face whose parent did not change and whose angle is the same, bit
    for bit, would be recomputed to the same values, so it is skipped: a planner's segment often
    moves only a few creases. (R, T, out must then hold the result of the previous call.)"""
    for ii in range(order.shape[0]):
        f = order[ii]
        p = parent[f]
        if last is not None:
            angle = 0.0 if p < 0 else q[crease[f]]
            if ((p < 0 or last[p, 1] == 0.0) and angle == last[f, 0]
                    and math.copysign(1.0, angle) == math.copysign(1.0, last[f, 0])):  # sin(-0.0) = -0.0
                last[f, 1] = 0.0
                continue
            last[f, 0] = angle
            last[f, 1] = 1.0
        if p < 0:
            for i in range(3):
                for j in range(3):
                    R[f, i, j] = 1.0 if i == j else 0.0
                T[f, i] = 0.0
                for k in range(3):
                    out[f, k, i] = flat[f, k, i]
            continue
        ax = out[p, axis[f, 0], 0]
        ay = out[p, axis[f, 0], 1]
        az = out[p, axis[f, 0], 2]
        ux = out[p, axis[f, 1], 0] - ax
        uy = out[p, axis[f, 1], 1] - ay
        uz = out[p, axis[f, 1], 2] - az
        norm = math.sqrt(ux * ux + uy * uy + uz * uz)
        angle = q[crease[f]]
        if norm > 0.0:
            ux /= norm
            uy /= norm
            uz /= norm
        else:
            angle = 0.0  # zero-length crease (rejected by fold_tree): no rotation
        c = math.cos(angle)
        s = math.sin(angle)
        t = 1.0 - c
        # Rodrigues: rotation by `angle` about unit u (right-hand rule)
        r00 = c + t * ux * ux
        r01 = t * ux * uy - s * uz
        r02 = t * ux * uz + s * uy
        r10 = t * uy * ux + s * uz
        r11 = c + t * uy * uy
        r12 = t * uy * uz - s * ux
        r20 = t * uz * ux - s * uy
        r21 = t * uz * uy + s * ux
        r22 = c + t * uz * uz
        # M_f = Rot(A, u, angle) o M_p:  R_f = Rr R_p,  T_f = Rr (T_p - A) + A
        for j in range(3):
            p0 = R[p, 0, j]
            p1 = R[p, 1, j]
            p2 = R[p, 2, j]
            R[f, 0, j] = r00 * p0 + r01 * p1 + r02 * p2
            R[f, 1, j] = r10 * p0 + r11 * p1 + r12 * p2
            R[f, 2, j] = r20 * p0 + r21 * p1 + r22 * p2
        dx = T[p, 0] - ax
        dy = T[p, 1] - ay
        dz = T[p, 2] - az
        T[f, 0] = r00 * dx + r01 * dy + r02 * dz + ax
        T[f, 1] = r10 * dx + r11 * dy + r12 * dz + ay
        T[f, 2] = r20 * dx + r21 * dy + r22 * dz + az
        for k in range(3):
            x = flat[f, k, 0]
            y = flat[f, k, 1]
            z = flat[f, k, 2]
            for i in range(3):
                out[f, k, i] = R[f, i, 0] * x + R[f, i, 1] * y + R[f, i, 2] * z + T[f, i]


# Triangles in the collision kernels are tuples of corner tuples ((x, y, z) x 3), loaded from the
# arrays by scalar reads: an array view (tris[i]) costs two atomic reference-count updates, more
# than the cheap pair tests themselves.


@njit(cache=True, inline="always")
def _corners(tris, f):
    """Triangle f of tris (F, 3, 3) as a tuple of corner tuples."""
    return ((tris[f, 0, 0], tris[f, 0, 1], tris[f, 0, 2]),
            (tris[f, 1, 0], tris[f, 1, 1], tris[f, 1, 2]),
            (tris[f, 2, 0], tris[f, 2, 1], tris[f, 2, 2]))


@njit(cache=True)
def _edge(t, k):
    k1 = (k + 1) % 3
    return (t[k1][0] - t[k][0], t[k1][1] - t[k][1], t[k1][2] - t[k][2])


@njit(cache=True)
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@njit(cache=True)
def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


@njit(cache=True)
def _is_sliver(n2, l2, tol):
    """Degenerate triangle: |n| = 2 area ~ 0 relative to its sides, or height over the longest side
    <= tol (as `overlap.triangles_overlap`); n2 = |n|^2, l2 = squared side lengths."""
    longest2 = max(l2[0], l2[1], l2[2])
    return not (n2 > _AXIS_EPS2 * longest2 * longest2) or n2 <= tol * tol * longest2


@njit(cache=True, inline="always")
def _span(t, n, o):
    """(min, max) of the corners of triangle t projected on axis n (unit), origin o."""
    s0 = n[0] * (t[0][0] - o[0]) + n[1] * (t[0][1] - o[1]) + n[2] * (t[0][2] - o[2])
    s1 = n[0] * (t[1][0] - o[0]) + n[1] * (t[1][1] - o[1]) + n[2] * (t[1][2] - o[2])
    s2 = n[0] * (t[2][0] - o[0]) + n[1] * (t[2][1] - o[1]) + n[2] * (t[2][2] - o[2])
    return min(min(s0, s1), s2), max(max(s0, s1), s2)


@njit(cache=True, inline="always")
def _no_contact_spans(amin, amax, bmin, bmax, tol):
    """True when the projections [amin, amax], [bmin, bmax] on one axis prove the triangles do not
    cross: a gap > tol, or a touching witness (depth <= tol, unless both are thinner than tol)."""
    depth = min(amax - bmin, bmax - amin)
    if depth < -tol:
        return True  # strictly apart
    if depth <= tol and (amax - amin > tol or bmax - bmin > tol):
        return True  # touching witness (a common normal of coplanar faces is no witness)
    return False


@njit(cache=True)
def _unit(n, ref2):
    """(usable, n / |n|): an axis is usable when |n|^2 > _AXIS_EPS2 * ref2 (ref2: the product of
    the squared lengths crossed); near-zero axes prove nothing."""
    l2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2]
    if not (l2 > _AXIS_EPS2 * ref2):
        return False, (0.0, 0.0, 0.0)
    inv = 1.0 / math.sqrt(l2)
    return True, (n[0] * inv, n[1] * inv, n[2] * inv)


@njit(cache=True)
def _no_contact_on(a, b, n, ref2, tol):
    """True when axis n (any length) proves triangles a, b do not cross (`_no_contact_spans`;
    origin a's first corner)."""
    ok, u = _unit(n, ref2)
    if not ok:
        return False
    amin, amax = _span(a, u, a[0])
    bmin, bmax = _span(b, u, a[0])
    return _no_contact_spans(amin, amax, bmin, bmax, tol)


# What every pair test of a face needs from that face alone (one configuration), so a face in k
# candidate pairs computes it once, not k times: e = edge vectors e_k = v_{k+1} - v_k, l = their
# squared lengths, n = e_0 x e_1, n2 = |n|^2, (uok, u) = `_unit(n, l_0 l_1)`, span = (min, max)
# of the face's own corners on u (origin: its first corner), sliver = degenerate (never collides).
_Face = namedtuple("_Face", ["e", "l", "n", "n2", "uok", "u", "span", "sliver"])
_G_SIZE = 29  # values per face in a `geo` row: the 23 of a _Face, then the AABB (lo x y z, hi x y z)
_G_LO = 23


@njit(cache=True, inline="always")
def _face_geometry(t, tol):
    """The _Face of triangle t."""
    e = (_edge(t, 0), _edge(t, 1), _edge(t, 2))
    l2 = (_dot(e[0], e[0]), _dot(e[1], e[1]), _dot(e[2], e[2]))
    n = _cross(e[0], e[1])
    n2 = _dot(n, n)
    uok, u = _unit(n, l2[0] * l2[1])
    return _Face(e, l2, n, n2, uok, u, _span(t, u, t[0]), _is_sliver(n2, l2, tol))


@njit(cache=True, inline="always")
def _faces_cross(a, b, ga, gb, tol):
    """True if non-degenerate triangles a, b cross (the test of `triangles_collide`); ga, gb their
    _Face. The verdict does not depend on the order of the axes (any axis proving no contact
    decides): the normals go first, they tell most pairs apart (a pair sharing a vertex by one)."""
    o = a[0]
    if ga.uok:
        bmin, bmax = _span(b, ga.u, o)
        if _no_contact_spans(ga.span[0], ga.span[1], bmin, bmax, tol):
            return False
    if gb.uok:
        amin, amax = _span(a, gb.u, o)
        bmin, bmax = _span(b, gb.u, o)
        if _no_contact_spans(amin, amax, bmin, bmax, tol):
            return False
    return not _edge_axes_prove_no_contact(a, b, ga, gb, tol)


@njit(cache=True)
def _edge_axes_prove_no_contact(a, b, ga, gb, tol):
    """True when one of the 15 edge axes of `_faces_cross` proves a, b do not cross. Rarely
    reached, so a call (of tuples: no reference counting), not inlined (keeps compiling fast)."""
    for k in range(3):
        # in-plane edge normals n_A x e_A and n_B x e_B
        if _no_contact_on(a, b, _cross(ga.n, ga.e[k]), ga.n2 * ga.l[k], tol):
            return True
        if _no_contact_on(a, b, _cross(gb.n, gb.e[k]), gb.n2 * gb.l[k], tol):
            return True
    for i in range(3):
        for j in range(3):
            if _no_contact_on(a, b, _cross(ga.e[i], gb.e[j]), ga.l[i] * gb.l[j], tol):
                return True
    return False


@njit(cache=True)
def triangles_collide(a, b, tol):
    """True if 3D triangles a, b (3, 3) cross each other (relative interiors meet, beyond tol).

    Separating-axis test on the 17 candidate axes (2 normals, 6 in-plane edge normals, 9 edge x
    edge). Touching (shared vertex or edge, contact without crossing) is not a collision; coplanar
    overlapping interiors are. Degenerate triangles (zero area, or every corner within tol of the
    line of the longest side) never collide.
    """
    ta = ((a[0, 0], a[0, 1], a[0, 2]), (a[1, 0], a[1, 1], a[1, 2]), (a[2, 0], a[2, 1], a[2, 2]))
    tb = ((b[0, 0], b[0, 1], b[0, 2]), (b[1, 0], b[1, 1], b[1, 2]), (b[2, 0], b[2, 1], b[2, 2]))
    ga = _face_geometry(ta, tol)
    gb = _face_geometry(tb, tol)
    if ga.sliver or gb.sliver:
        return False  # (near) zero-area triangle: no interior
    return _faces_cross(ta, tb, ga, gb, tol)


@njit(cache=True, inline="always")
def _store_face(geo, f, g):
    """geo[f, :23] = the _Face g (the layout `_load_face` reads)."""
    for k in range(3):
        for c in range(3):
            geo[f, 3 * k + c] = g.e[k][c]
        geo[f, 9 + k] = g.l[k]
        geo[f, 12 + k] = g.n[k]
        geo[f, 16 + k] = g.u[k]
    geo[f, 15] = g.n2
    geo[f, 19] = 1.0 if g.uok else 0.0
    geo[f, 20] = g.span[0]
    geo[f, 21] = g.span[1]
    geo[f, 22] = 1.0 if g.sliver else 0.0


@njit(cache=True, inline="always")
def _load_face(geo, f):
    """The _Face stored in geo[f] by `_store_face`."""
    e = ((geo[f, 0], geo[f, 1], geo[f, 2]), (geo[f, 3], geo[f, 4], geo[f, 5]), (geo[f, 6], geo[f, 7], geo[f, 8]))
    return _Face(e, (geo[f, 9], geo[f, 10], geo[f, 11]), (geo[f, 12], geo[f, 13], geo[f, 14]), geo[f, 15],
                 geo[f, 19] > 0.0, (geo[f, 16], geo[f, 17], geo[f, 18]), (geo[f, 20], geo[f, 21]), geo[f, 22] > 0.0)


@njit(cache=True)
def _boxes(tris):
    n = tris.shape[0]
    lo = np.empty((n, 3))
    hi = np.empty((n, 3))
    for f in range(n):
        for i in range(3):
            lo[f, i] = min(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
            hi[f, i] = max(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
    return lo, hi


@njit(cache=True)
def collision_work(n_faces):
    """Work arrays of `segment_collides` for one tree of n_faces faces, reused across calls:
    (geo, sb, si, last, R, T, out, meta).

    geo (F, _G_SIZE): per-face geometry and AABB; sb (7, F): the AABBs (lo x, hi x, lo y, hi y,
    lo z, hi z) in sweep order and the running maximum of hi x; si (6, F) int: si[0] the sweep
    order (face ids by lo x; kept from call to call, it is the next call's starting guess), then
    per position parent, piece, rigid group, non-degenerate flag, and scratch for the candidates
    of one face; last (F, 2), R, T,
    out: the folded state of the previous call (see `_fold`); meta (1,): the tol geo was filled
    with (NaN: geo not of out). The state changes only the cost, never a verdict.
    """
    si = np.empty((6, n_faces), dtype=np.int64)
    last = np.empty((n_faces, 2))
    meta = np.empty(1)
    for f in range(n_faces):  # (loops, not np.full: that takes seconds to compile)
        si[0, f] = f
        last[f, 0] = np.nan
    meta[0] = np.nan
    return (np.empty((n_faces, _G_SIZE)), np.empty((7, n_faces)), si, last,
            np.empty((n_faces, 3, 3)), np.empty((n_faces, 3)), np.empty((n_faces, 3, 3)), meta)


@njit(cache=True, inline="always")
def _fill_faces(tris, tol, geo, last):
    """geo[f] = the _Face of tris[f] (F, 3, 3) and its AABB, for the faces the last forward
    kinematics changed (last: see `_fold`); the other rows still hold their faces."""
    for f in range(tris.shape[0]):
        if last[f, 1] == 0.0:
            continue
        _store_face(geo, f, _face_geometry(_corners(tris, f), tol))
        for i in range(3):
            geo[f, _G_LO + i] = min(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])
            geo[f, _G_LO + 3 + i] = max(tris[f, 0, i], tris[f, 1, i], tris[f, 2, i])


@njit(cache=True, inline="always")
def _sort_by_lo_x(geo, sb, si):
    """Sort the face ids si[0] in place by (lo x, face id); sb[0] = their lo x.

    Consecutive configurations of a planner are close, so si[0] (the previous order) is nearly
    sorted: an insertion sort costs O(F + moves). When the moves pass 8 F (a big jump), a stable
    merge sort of the face ids instead (the same order: ties by face id). The order never depends
    on the guess. (Rows are indexed in place: a row view costs atomic reference counting.)
    """
    n = si.shape[1]
    for p in range(n):
        sb[0, p] = geo[si[0, p], _G_LO]
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
    rare fallback of `_sort_by_lo_x`: a call, not inlined, keeps compiling fast)."""
    si[0, :] = np.argsort(geo[:, _G_LO], kind="mergesort")
    for r in range(si.shape[1]):
        sb[0, r] = geo[si[0, r], _G_LO]


@njit(cache=True, inline="always")
def _gather(geo, parent, piece, rigid, sb, si):
    """Fill sb and si[1:5] for the sweep order si[0] (see `collision_work`): contiguous rows for
    the sweep's inner loop, and sb[6] = running maximum of hi x. rigid (F,) groups (-1: none)."""
    top = -np.inf
    for p in range(si.shape[1]):
        f = si[0, p]
        for r in range(6):
            sb[r, p] = geo[f, _G_LO + (r >> 1) + 3 * (r & 1)]
        top = max(top, sb[1, p])
        sb[6, p] = top
        si[1, p] = parent[f]
        si[2, p] = piece[f]
        si[3, p] = rigid[f]
        si[4, p] = 0 if geo[f, 22] > 0.0 else 1  # _Face.sliver


@njit(cache=True, inline="always")
def _largest_group(rigid, counts):
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
def _sweep(tris, geo, sb, si, tol, big):
    """Sort-and-sweep on x over the faces' AABBs in the order si[0] (filled by `_gather`).

    A pair is tested (`_faces_cross`, the face earlier in the order as a) unless its boxes are
    apart by more than tol on x, y or z, or it is not in one piece, or it is a crease pair, or
    both faces are in the same rigid group (rigid >= 0: their relative pose is fixed, see
    `config_collides_moving`), or a face is degenerate. True at the first pair that crosses.
    big >= 0: a rigid group of most faces, whose own pairs are not tested: only the other faces
    are swept, forward and backward (big = -1: forward from every face).
    sb rows: lo x, hi x, lo y, hi y, lo z, hi z, running max of hi x; si rows: face, parent,
    piece, rigid, non-degenerate, scratch.
    """
    n = tris.shape[0]
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
        while end < n and not (sb[0, end] - sb[1, ii] > tol):  # later faces overlapping in x
            end += 1
        k = 0
        for jj in range(ii + 1, end):
            apart = ((sb[2, jj] - hiy > tol) | (loy - sb[3, jj] > tol)
                     | (sb[4, jj] - hiz > tol) | (loz - sb[5, jj] > tol))
            si[5, k] = jj
            k += 1 - np.int64(apart)
        later = k
        if big >= 0:
            # earlier faces of big overlapping in x (the others were swept from themselves); no
            # face before jj reaches past the running maximum of hi x
            jj = ii - 1
            while jj >= 0 and not (sb[0, ii] - sb[6, jj] > tol):
                apart = ((sb[0, ii] - sb[1, jj] > tol) | (sb[2, jj] - hiy > tol) | (loy - sb[3, jj] > tol)
                         | (sb[4, jj] - hiz > tol) | (loz - sb[5, jj] > tol) | (si[3, jj] != big))
                si[5, k] = jj
                k += 1 - np.int64(apart)
                jj -= 1
        if k == 0:
            continue
        t = _corners(tris, i)
        gt = _load_face(geo, i)
        for c in range(k):
            jj = si[5, c]
            j = si[0, jj]
            if (si[4, jj] == 0 or si[2, jj] != si[2, ii] or si[1, jj] == i or si[1, ii] == j
                    or (si[3, ii] >= 0 and si[3, jj] == si[3, ii])):
                continue
            u = _corners(tris, j)
            gu = _load_face(geo, j)
            # a: the face earlier in the order (i for the forward sweep, j for the backward one)
            a, b, ga, gb = (t, u, gt, gu) if c < later else (u, t, gu, gt)
            if _faces_cross(a, b, ga, gb, tol):
                return True
    return False


@njit(cache=True)
def _collisions(tris, parent, piece, tol, max_pairs, pairs):
    """Colliding pairs for reports (first_collision, all_collisions): sort-and-sweep on x in the
    order of np.argsort of the boxes' lo x, `triangles_collide` on each candidate (the face
    earlier in the order as a), as this module always did, so the pairs reported and their order
    are the ones it always reported (the planners' test is `segment_collides`). Stops after
    max_pairs hits, the first ones (i < j) written to pairs; returns the number of hits."""
    n = tris.shape[0]
    lo, hi = _boxes(tris)
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
            if piece[i] != piece[j] or parent[i] == j or parent[j] == i:
                continue
            if triangles_collide(tris[i], tris[j], tol):
                if count < pairs.shape[0]:
                    pairs[count, 0] = min(i, j)
                    pairs[count, 1] = max(i, j)
                count += 1
                if count >= max_pairs:
                    return count
    return count


@njit(cache=True)
def first_collision(tris, parent, piece, tol):
    """First colliding face pair (i, j), i < j, of folded faces tris (F, 3, 3), or (-1, -1)."""
    pairs = np.empty((1, 2), dtype=np.int64)
    if _collisions(tris, parent, piece, tol, np.int64(1), pairs) > 0:
        return pairs[0, 0], pairs[0, 1]
    return -1, -1


@njit(cache=True)
def all_collisions(tris, parent, piece, tol, max_pairs):
    """(count, pairs): all colliding pairs (count), the first min(count, max_pairs) of them."""
    pairs = np.empty((max(max_pairs, 1), 2), dtype=np.int64)
    count = _collisions(tris, parent, piece, tol, np.iinfo(np.int64).max, pairs[:max_pairs])
    return count, pairs[: min(count, max_pairs)]


@njit(cache=True)
def segment_collides(qa, qb, ks, m, order, parent, crease, axis, flat, piece, rigid, tol, work, q):
    """The planners' collision test, at the configurations q = qa + (k / m) (qb - qa) for k in ks,
    in that order (m = 0: q = qa), up to the first that self-intersects: (collides, checked).

    Pairs with rigid[i] == rigid[j] >= 0 are not tested (see `config_collides_moving`; -1 for
    none). work: `collision_work(F)` of this tree, reused across calls: the faces and sweep order
    of the previous configuration are the starting point (work's out holds the last configuration
    folded). q (E,) scratch. All the samples of a segment in one call: a call between compiled
    functions updates the reference count of every array argument, which per configuration
    would cost a tenth of a small net's test.
    """
    geo, sb, si, last, R, T, out, meta = work
    if not (meta[0] == tol):
        last[:, 0] = np.nan  # geo rows of another tol: recompute every face
        meta[0] = tol
    big = _largest_group(rigid, si[5])
    checked = 0
    for k in ks:
        if m == 0:
            q[:] = qa
        else:
            t = k / m
            for i in range(qa.shape[0]):
                q[i] = qa[i] + t * (qb[i] - qa[i])
        checked += 1
        _fold(q, order, parent, crease, axis, flat, R, T, out, last)
        _fill_faces(out, tol, geo, last)
        _sort_by_lo_x(geo, sb, si)
        _gather(geo, parent, piece, rigid, sb, si)
        if _sweep(out, geo, sb, si, tol, big):
            return True, checked
    return False, checked


@njit(cache=True)
def config_collides_cached(q, order, parent, crease, axis, flat, piece, rigid, tol, work):
    """`config_collides_moving` with the work arrays of `segment_collides` (rigid -1: no group)."""
    # np.int64(0), not 0: a literal would compile another specialization of segment_collides
    return segment_collides(q, q, np.zeros(1, dtype=np.int64), np.int64(0), order, parent, crease, axis, flat,
                            piece, rigid, tol, work, np.empty(q.shape[0]))[0]


@njit(cache=True)
def config_collides_moving(q, order, parent, crease, axis, flat, piece, rigid, tol, R, T, out):
    """Like `config_collides`, but pairs with rigid[i] == rigid[j] >= 0 are not tested.

    Along a segment on which only some creases move, faces joined by non-moving creases keep
    their relative pose; if both endpoints are collision-free such pairs never collide, so a
    planner can label those rigid groups once per segment and skip them.
    """
    work = collision_work(order.shape[0])
    hit = config_collides_cached(q, order, parent, crease, axis, flat, piece, rigid, tol, work)
    R[:] = work[4]
    T[:] = work[5]
    out[:] = work[6]
    return hit


@njit(cache=True)
def config_collides(q, order, parent, crease, axis, flat, piece, tol, R, T, out):
    """forward_kinematics into (R, T, out), then the collision test: True if q self-intersects."""
    no_groups = np.empty(order.shape[0], dtype=np.int64)
    no_groups[:] = -1
    return config_collides_moving(q, order, parent, crease, axis, flat, piece, no_groups, tol, R, T, out)


# --------------------------------------------------------------------------------------------------
# the tree of a FOLD net
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FoldTree:
    """Arrays of a FOLD net for the kernels (see the module docstring for the conventions).

    flat (F, 3, 3) flat corners (x, y, 0) in faces_vertices order; faces (F, 3) net vertex ids;
    order (F,) parents first; parent / crease (F,) parent face and crease edge index, -1 at roots;
    axis (F, 2) the parent's corners at the crease ends, a -> b in the parent's CCW order;
    piece (F,); goal (E,) goal angle per edge (rho, radians; 0 for cuts); creases (n,) the tree
    creases (the DOF), ascending; scale = bounding-box diagonal (foldedForm, else flat net);
    tol = contact tolerance (CONTACT_TOL * scale); folded (V, 3) foldedForm coords or None.
    """

    flat: np.ndarray
    faces: np.ndarray
    order: np.ndarray
    parent: np.ndarray
    crease: np.ndarray
    axis: np.ndarray
    piece: np.ndarray
    goal: np.ndarray
    creases: np.ndarray
    scale: float
    tol: float
    folded: np.ndarray | None

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @property
    def n_edges(self) -> int:
        return len(self.goal)

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fresh (R, T, out) work arrays for forward_kinematics / config_collides."""
        n = self.n_faces
        return np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3, 3))


def _fail(message: str) -> PolyfoldError:
    return PolyfoldError(f"malformed net: {message}")


def _int_array(fold: dict, key: str, shape_tail: tuple[int, ...], what: str) -> np.ndarray:
    try:
        arr = np.asarray(fold[key])
        if arr.size == 0:
            arr = arr.reshape((0,) + shape_tail)
        if arr.dtype == object or arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
            raise ValueError
        if arr.dtype != np.int64 and not np.issubdtype(arr.dtype, np.integer):  # (JSON ints: int64)
            if not np.issubdtype(arr.dtype, np.floating) or not np.all(arr == np.round(arr)):
                raise ValueError
        return arr.astype(np.int64)
    except (ValueError, TypeError):
        raise _fail(f"{key!r} is not a list of {what}") from None


def _float_array(value, key: str, n_cols: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (ValueError, TypeError):
        raise _fail(f"{key!r} is not a list of coordinates") from None
    if arr.ndim != 2 or arr.shape[1] not in n_cols:
        raise _fail(f"{key!r} must hold {' or '.join(map(str, n_cols))} coordinates per vertex")
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.flatnonzero(~finite.all(axis=1))
        raise _fail(f"{key!r}: vertex {bad[0]} has a non-finite coordinate")
    return arr


def _bbox_diagonal(pts: np.ndarray) -> float:
    """Bounding-box diagonal of finite points (V, 2 or 3)."""
    return vector_norm(TK.extent(pts)) if len(pts) else 0.0


def _folded_coords(fold: dict, n_v: int) -> np.ndarray | None:
    frames = fold.get("file_frames")
    if not frames:
        return None
    frame = next((fr for fr in frames if isinstance(fr, dict) and "foldedForm" in (fr.get("frame_classes") or [])), frames[0])
    if not isinstance(frame, dict) or "vertices_coords" not in frame:
        return None
    coords = _float_array(frame["vertices_coords"], "file_frames[0].vertices_coords", (3,))
    if len(coords) != n_v:
        raise _fail(f"the foldedForm frame has {len(coords)} vertices, the net has {n_v}")
    return coords


def _check_triangles(rows) -> None:
    """Every face is a sequence of 3 corners (before the corners themselves are parsed)."""
    # the usual case (lists of 3-lists, as JSON gives) without a Python loop over the faces
    if type(rows) is list and set(map(type, rows)) <= {list} and set(map(len, rows)) <= {3}:
        return
    for f, corners in enumerate(rows):
        if not isinstance(corners, (list, tuple, np.ndarray)) or len(corners) != 3:
            raise _fail(f"face {f} is not a triangle (only triangulated nets can be folded)")


_KNOWN = frozenset(_CUT + _CREASE)
_KIND = {a: i for i, a in enumerate(_CUT + _CREASE)}  # kind < len(_CUT): a cut
_MOUNTAIN, _VALLEY = _KIND["M"], _KIND["V"]


def _assignments(assign, n_e: int) -> tuple[list[str], np.ndarray]:
    """Upper-cased assignments and their kinds (E,) int8 (index into _CUT + _CREASE)."""
    if not isinstance(assign, (list, tuple)) or len(assign) != n_e:
        raise _fail(f"'edges_assignment' must have one entry per edge ({n_e})")
    if set(map(type, assign)) <= {str}:
        try:  # the usual case: all upper-case and known already
            return assign, np.fromiter(map(_KIND.__getitem__, assign), dtype=np.int8, count=n_e)
        except KeyError:
            pass
    assign = [str(a).upper() for a in assign]
    for e, a in enumerate(assign):
        if a not in _KNOWN:
            raise _fail(f"edge {e} has unknown assignment {a!r}")
    return assign, np.fromiter(map(_KIND.__getitem__, assign), dtype=np.int8, count=n_e)


def _fold_angles(fold: dict, n_e: int) -> np.ndarray:
    """'edges_foldAngle' as (E,) float64 degrees (values are checked by the kernel)."""
    try:
        deg = np.asarray(fold["edges_foldAngle"], dtype=np.float64)
    except (ValueError, TypeError):
        raise _fail("'edges_foldAngle' is not a list of numbers") from None
    if deg.shape != (n_e,):
        raise _fail(f"'edges_foldAngle' has {deg.size} entries for {n_e} edges")
    return deg


def _goal_from_folded(assign, kind: np.ndarray, edges: np.ndarray, edge_faces: np.ndarray, faces: np.ndarray,
                      folded: np.ndarray | None) -> np.ndarray:
    """Goal angles (E,) of a file without fold angles: from the foldedForm frame, else +-pi by the
    assignment (0 on cuts)."""
    n_e = len(edges)
    goal = np.zeros(n_e)
    is_cut = kind < len(_CUT)
    for e in range(n_e):  # files without fold angles only (net_to_fold always writes them)
        if is_cut[e]:
            continue
        if folded is not None and edge_faces[e, 1] >= 0:
            f0, f1 = edge_faces[e]
            u, v = edges[e]
            k = int(np.flatnonzero(faces[f0] == u)[0])
            a, b = (u, v) if faces[f0][(k + 1) % 3] == v else (v, u)
            n0 = np.cross(*(folded[faces[f0][1:]] - folded[faces[f0][0]]))
            n1 = np.cross(*(folded[faces[f1][1:]] - folded[faces[f1][0]]))
            n0 /= max(np.linalg.norm(n0), 1e-300)
            n1 /= max(np.linalg.norm(n1), 1e-300)
            goal[e] = math.atan2(float(np.cross(n0, n1) @ (folded[b] - folded[a])) / max(np.linalg.norm(folded[b] - folded[a]), 1e-300),
                                 float(n0 @ n1))
        elif assign[e] in ("M", "V"):
            goal[e] = math.pi if assign[e] == "M" else -math.pi
    return goal


_SIDE_ERRORS = {  # messages of the edge-table codes of _tree_kernels (info, then the edge's vertex pair)
    TK.BAD_EDGE: "edge {0} has invalid vertices {pair}",
    TK.DUPLICATE_EDGE: "edges {0} and {1} join the same vertices {uv}",
    TK.MISSING_SIDE: "side {0}-{1} of face {2} is not in 'edges_vertices'",
    TK.THIRD_FACE: "edge {0} borders more than two faces",
    TK.CLOCKWISE: "face {0} is clockwise seen from +z (faces must be CCW, outer side up)",
}


def _tree_error(code: int, info: np.ndarray, parent: np.ndarray, piece: np.ndarray, assign: list[str]) -> PolyfoldError:
    """The one-line message of a `_tree_kernels.crease_tree` error code."""
    a, b, c = info[:3].tolist()
    if code == TK.INVALID_PARENT:
        return _fail(f"face {a} has invalid parent {b}")
    if code == TK.NO_COMMON_EDGE:
        return _fail(f"face {a} shares no edge with its parent face {b}")
    if code == TK.CUT_PARENT_EDGE:
        return _fail(f"face {a} is joined to its parent face {b} by cut edge {c} (assignment {assign[c]})")
    if code == TK.PIECE_CREASE:
        return _fail(f"crease edge {a} joins face {b} (piece {piece[b]}) to face {c} (piece {piece[c]})")
    if code == TK.CYCLE:
        return _fail(f"face {a} is on a cycle of 'polyfold:faces_parent' (no path to a root)")
    if code == TK.PARENT_PIECE:
        return _fail(f"face {a} (piece {piece[a]}) has its parent face {parent[a]} in piece {piece[parent[a]]}")
    return _fail(f"piece {a} is not connected by creases (faces {b} and {c} are both roots)")


def fold_tree(fold: dict, contact_tol: float = CONTACT_TOL) -> FoldTree:
    """The FoldTree of a FOLD net (as written by `foldfile.net_to_fold`).

    Uses `polyfold:faces_parent` when present, else a BFS over the crease (non-B) edges from the
    lowest-index face of each piece. Raises PolyfoldError (one line naming the face / edge) when the
    net cannot be folded: non-triangular faces, bad indices, clockwise faces, a parent that is not
    joined by a crease, cycles, pieces inconsistent with the tree, zero-length creases, ...
    The per-face work is one numba kernel (`_tree_kernels.net_tree`); so that it runs once, the
    later inputs are parsed first and a parse error is raised where its check comes in this order.
    """
    if not isinstance(fold, dict):
        raise _fail("not a FOLD dict")
    for key in ("vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment"):
        if key not in fold:
            raise _fail(f"no {key!r}")
    xy = _float_array(fold["vertices_coords"], "vertices_coords", (2, 3))
    n_v = len(xy)
    folded = _folded_coords(fold, n_v)
    scale = _bbox_diagonal(folded if folded is not None else xy)
    if not scale > 0:
        raise _fail("the net has zero size")
    if xy.shape[1] == 3:
        bad = np.flatnonzero(np.abs(xy[:, 2]) > 1e-9 * scale)
        if len(bad):
            raise _fail(f"vertex {bad[0]} of the crease pattern is not in the plane z = 0")
        xy = np.ascontiguousarray(xy[:, :2])
    _check_triangles(fold["faces_vertices"])
    faces = _int_array(fold, "faces_vertices", (3,), "vertex triples")
    n_f = len(faces)
    if n_f == 0:
        raise _fail("no faces")

    # parsed ahead of their checks (errors kept for later): edges, then the tree, then fold angles
    none = np.empty(0, dtype=np.int64)
    edges, kind, assign, parent_in, piece_in, deg = none.reshape(0, 2), none, [], none, none, np.empty(0)
    stage, late = 1, None
    try:
        edges = _int_array(fold, "edges_vertices", (2,), "vertex pairs")
        assign, kind = _assignments(fold["edges_assignment"], len(edges))
        stage = 2
        if "polyfold:faces_piece" in fold:
            piece_in = _int_array(fold, "polyfold:faces_piece", (), "integers")
            if len(piece_in) != n_f:
                raise _fail(f"'polyfold:faces_piece' has {len(piece_in)} entries for {n_f} faces")
        if "polyfold:faces_parent" in fold:
            parent_in = _int_array(fold, "polyfold:faces_parent", (), "integers")
            if len(parent_in) != n_f:
                raise _fail(f"'polyfold:faces_parent' has {len(parent_in)} entries for {n_f} faces")
        stage = 3
        if "edges_foldAngle" in fold:
            deg = _fold_angles(fold, len(edges))
            stage = 4
    except Exception as exc:  # noqa: BLE001 (raised below, after the checks that come first)
        late = exc
    n_e = len(edges)
    info = np.empty(4, dtype=np.int64)
    face_edges, edge_faces, flat = np.empty((n_f, 3), dtype=np.int64), np.empty((n_e, 2), dtype=np.int64), np.empty((n_f, 3, 3))
    parent, crease, order = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    piece, short, creases = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    axis = np.empty((n_f, 2), dtype=np.int64)
    goal = np.empty(n_e)
    code, n_short, n_creases, bad_angle, out_of_range = TK.net_tree(
        faces, n_v, edges, kind, len(_CUT), xy, -1e-12 * scale * scale, parent_in, piece_in, (2e-12 * scale) ** 2,
        _MOUNTAIN, _VALLEY, deg, stage, info, face_edges, edge_faces, flat, parent, crease, order, piece, axis, short,
        creases, goal)
    i = info.tolist()
    if code in (TK.FACE_OUT_OF_RANGE, TK.FACE_REPEAT):
        raise _fail(f"face {i[0]} refers to a vertex outside 0..{n_v - 1}" if code == TK.FACE_OUT_OF_RANGE
                    else f"face {i[0]} repeats a vertex")
    if stage < 2:
        raise late
    if code in _SIDE_ERRORS:
        raise _fail(_SIDE_ERRORS[code].format(*i, pair=edges[i[0]].tolist() if code == TK.BAD_EDGE else None, uv=i[2:]))
    if stage < 3:
        raise late
    if code != TK.OK:
        raise _tree_error(code, info, parent, piece_in if len(piece_in) else piece, assign)
    for f in short[:n_short].tolist():  # the exact test (as always) of the creases the kernel could not clear
        p, e = int(parent[f]), int(crease[f])
        u, v = edges[e]
        if not np.linalg.norm(xy[u] - xy[v]) > 1e-12 * scale:
            raise _fail(f"crease edge {e} (between faces {p} and {f}) has zero length")
    if late is not None:
        raise late
    if bad_angle >= 0:
        d = deg[bad_angle]
        if out_of_range:
            raise _fail(f"edge {bad_angle} has fold angle {d} (must be within [-180, 180] degrees)")
        raise _fail(f"edge {bad_angle} is a {'mountain' if assign[bad_angle] == 'M' else 'valley'} with fold angle {d} "
                    "(FOLD: valley positive, mountain negative)")
    if stage < 4:  # no fold angles in the file: from the foldedForm, else +-180 degrees
        goal = _goal_from_folded(assign, kind, edges, edge_faces, faces, folded)
    return FoldTree(
        flat=flat, faces=faces, order=order, parent=parent, crease=crease, axis=axis,
        piece=piece, goal=goal, creases=creases[:n_creases], scale=scale,
        tol=contact_tol * scale, folded=folded,
    )


# --------------------------------------------------------------------------------------------------
# wrappers
# --------------------------------------------------------------------------------------------------


def _config(tree: FoldTree, q) -> np.ndarray:
    q = np.ascontiguousarray(q, dtype=np.float64)
    if q.shape != (tree.n_edges,):
        raise ValueError(f"q must have one angle per net edge: shape ({tree.n_edges},), got {q.shape}")
    return q


def fold_positions(tree: FoldTree, q: np.ndarray) -> np.ndarray:
    """Folded face corners (F, 3, 3) at configuration q (E,) (radians, rho convention)."""
    R, T, out = tree.buffers()
    return forward_kinematics(_config(tree, q), tree.order, tree.parent, tree.crease, tree.axis, tree.flat, R, T, out)


def collides(tree: FoldTree, q: np.ndarray) -> bool:
    """True if the net folded to q self-intersects."""
    R, T, out = tree.buffers()
    return bool(config_collides(_config(tree, q), tree.order, tree.parent, tree.crease, tree.axis, tree.flat,
                                tree.piece, tree.tol, R, T, out))


def colliding_pairs(tree: FoldTree, q: np.ndarray) -> np.ndarray:
    """All colliding face pairs (k, 2), i < j, sorted, of the net folded to q."""
    tris = fold_positions(tree, q)
    count, _ = all_collisions(tris, tree.parent, tree.piece, tree.tol, 0)
    _, pairs = all_collisions(tris, tree.parent, tree.piece, tree.tol, int(count))
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
