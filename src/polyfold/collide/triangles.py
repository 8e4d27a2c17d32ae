"""The 3D triangle pair test: do two triangles cross, or only touch?

Two faces collide when their relative interiors cross (within the tolerance `tol`); touching is
allowed: sharing a vertex or an edge, a vertex or an edge resting on the other face, coplanar
faces side by side. Coplanar faces whose interiors overlap collide (paper cannot pass through
paper). ALGORITHMS.md 6.2. Separating-axis test on 17 candidate axes (2 normals, 6 in-plane edge
normals, 9 edge x edge); an axis proves "no crossing" by a gap larger than tol or by a touching
witness (see `_no_contact_spans`).

Triangles in these kernels are tuples of corner tuples ((x, y, z) x 3), loaded from the arrays
by scalar reads (`tri_corners`): an array view (tris[i]) costs two atomic reference-count
updates, more than the cheap pair tests themselves. What a pair test needs from one face alone is
its `FaceGeometry`, computed once per face and configuration (`face_geometry`) and kept in a row
of a `geo` array (`store_face` / `load_face`, GEO_SIZE values per row, the face's box from
GEO_LO on) by the broad phase (`sweep.py`).
"""

from __future__ import annotations

import math
from collections import namedtuple

from numba import njit

_AXIS_EPS2 = 1e-24  # a candidate axis is skipped when |axis| < 1e-12 * (product of the lengths crossed)


@njit(cache=True, inline="always")
def tri_corners(tris, f):
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
    <= tol (as `flat.triangles_overlap`); n2 = |n|^2, l2 = squared side lengths."""
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
FaceGeometry = namedtuple("FaceGeometry", ["e", "l", "n", "n2", "uok", "u", "span", "sliver"])


GEO_SIZE = 29  # values per face in a `geo` row: the 23 of a FaceGeometry, then the AABB (lo x y z, hi x y z)


GEO_LO = 23


@njit(cache=True, inline="always")
def face_geometry(t, tol):
    """The FaceGeometry of triangle t."""
    e = (_edge(t, 0), _edge(t, 1), _edge(t, 2))
    l2 = (_dot(e[0], e[0]), _dot(e[1], e[1]), _dot(e[2], e[2]))
    n = _cross(e[0], e[1])
    n2 = _dot(n, n)
    uok, u = _unit(n, l2[0] * l2[1])
    return FaceGeometry(e, l2, n, n2, uok, u, _span(t, u, t[0]), _is_sliver(n2, l2, tol))


@njit(cache=True, inline="always")
def faces_cross(a, b, ga, gb, tol):
    """True if non-degenerate triangles a, b cross (the test of `triangles_collide`); ga, gb their
    FaceGeometry. The verdict does not depend on the order of the axes (any axis proving no contact
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
    """True when one of the 15 edge axes of `faces_cross` proves a, b do not cross. Rarely
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
    ga = face_geometry(ta, tol)
    gb = face_geometry(tb, tol)
    if ga.sliver or gb.sliver:
        return False  # (near) zero-area triangle: no interior
    return faces_cross(ta, tb, ga, gb, tol)


@njit(cache=True, inline="always")
def store_face(geo, f, g):
    """geo[f, :23] = the FaceGeometry g (the layout `load_face` reads)."""
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
def load_face(geo, f):
    """The FaceGeometry stored in geo[f] by `store_face`."""
    e = ((geo[f, 0], geo[f, 1], geo[f, 2]), (geo[f, 3], geo[f, 4], geo[f, 5]), (geo[f, 6], geo[f, 7], geo[f, 8]))
    return FaceGeometry(e, (geo[f, 9], geo[f, 10], geo[f, 11]), (geo[f, 12], geo[f, 13], geo[f, 14]), geo[f, 15],
                 geo[f, 19] > 0.0, (geo[f, 16], geo[f, 17], geo[f, 18]), (geo[f, 20], geo[f, 21]), geo[f, 22] > 0.0)
