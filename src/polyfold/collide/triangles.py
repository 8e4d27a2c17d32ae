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

The small helpers (`_span`, `_no_contact_spans`, `face_geometry`, `tri_corners`, ...) are plain
compiled calls: LLVM inlines them all the same (the collision test's time per configuration is
unchanged, `bench/bench_fold.py --collision`), while numba's own inline="always" typed each
again at every call site, 6-7 s of a first run's compiling (the fold stage's 34 -> 27 s here).
Only the per-face pair tests with array reads (`load_face`, `store_face`, `faces_cross`,
`thick_collides`) stay inlined: as calls they cost 10-15% of the test.

With the paper's thickness (README "Paper thickness") the planners ask `thick_collides` instead:
crossing, or closer than the thickness with overlapping projections (`faces_near`, the same
separating-axis machinery with a margin), where faces sharing a vertex may touch near it (quick
answers `_wedge_clear`, `_straddle_clear`, `_beside` for most such pairs; corners cut off and a
shared mesh edge's strip removed for the rest). The independent re-check of written paths is
`verify.paths`, which shares none of this.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..jit import njit

_AXIS_EPS2 = 1e-24  # a candidate axis is skipped when |axis| < 1e-12 * (product of the lengths crossed)


@njit(cache=True)
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


@njit(cache=True)
def _span(t, n, o):
    """(min, max) of the corners of triangle t projected on axis n (unit), origin o."""
    s0 = n[0] * (t[0][0] - o[0]) + n[1] * (t[0][1] - o[1]) + n[2] * (t[0][2] - o[2])
    s1 = n[0] * (t[1][0] - o[0]) + n[1] * (t[1][1] - o[1]) + n[2] * (t[1][2] - o[2])
    s2 = n[0] * (t[2][0] - o[0]) + n[1] * (t[2][1] - o[1]) + n[2] * (t[2][2] - o[2])
    return min(min(s0, s1), s2), max(max(s0, s1), s2)


@njit(cache=True)
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


@njit(cache=True)
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


# ----------------------------------------------------------------------------------------------
# Thickness: faces closer than the paper's thickness with overlapping projections collide


@njit(cache=True)
def _apart_on(a, b, n, ref2, gap):
    """True when axis n (any length) separates triangles a, b by more than gap (unusable axis: False)."""
    ok, u = _unit(n, ref2)
    if not ok:
        return False
    amin, amax = _span(a, u, a[0])
    bmin, bmax = _span(b, u, a[0])
    return bmin - amax > gap or amin - bmax > gap


@njit(cache=True)
def _shallow_on(a, b, n, ref2, gap):
    """True when on in-plane axis n the projections of a and b overlap by at most gap (they do not
    reach more than the thickness into each other: side by side, or one resting on the other's edge)."""
    ok, u = _unit(n, ref2)
    if not ok:
        return False
    amin, amax = _span(a, u, a[0])
    bmin, bmax = _span(b, u, a[0])
    return min(amax - bmin, bmax - amin) <= gap


@njit(cache=True)
def faces_apart(a, b, ga, gb, gap):
    """True when a normal or edge x edge axis separates triangles a, b by more than gap (then
    they, and any parts of them, are farther apart than gap)."""
    if ga.uok and _apart_on(a, b, ga.u, 1.0, gap):
        return True
    if gb.uok and _apart_on(a, b, gb.u, 1.0, gap):
        return True
    for i in range(3):
        for j in range(3):
            if _apart_on(a, b, _cross(ga.e[i], gb.e[j]), ga.l[i] * gb.l[j], gap):
                return True
    return False


@njit(cache=True)
def faces_near(a, b, ga, gb, gap):
    """True when triangles a, b come closer than gap with projections overlapping by more than gap:
    no normal or edge x edge axis separates them by more than gap, and one reaches more than gap
    into the other seen along the other's normal (on every axis in that plane normal to a side of
    either, their projections overlap by more than gap). Conservative (a separating-axis bound of the
    distance), so it may call near what the independent check (`verify.paths`) lets touch."""
    return not faces_apart(a, b, ga, gb, gap) and _reaches_into(a, b, ga, gb, gap)


@njit(cache=True)
def _reaches_into(a, b, ga, gb, gap):
    """The second half of `faces_near`: b reaches more than gap into a seen along a's normal (the
    2D separating-axis test in a's plane, a's sides and b's sides projected, every axis overlapping
    by more than gap), or a into b."""
    into_a, into_b = True, True
    for k in range(3):
        if into_a and (_shallow_on(a, b, _cross(ga.n, ga.e[k]), ga.n2 * ga.l[k], gap)
                       or _shallow_on(a, b, _cross(ga.n, gb.e[k]), ga.n2 * gb.l[k], gap)):
            into_a = False
        if into_b and (_shallow_on(a, b, _cross(gb.n, gb.e[k]), gb.n2 * gb.l[k], gap)
                       or _shallow_on(a, b, _cross(gb.n, ga.e[k]), gb.n2 * ga.l[k], gap)):
            into_b = False
    return into_a or into_b


@njit(cache=True)
def _beyond_side(t, mask, reach):
    """(triangle, scale): the part of triangle t farther than reach from its side whose two corners
    are in mask (the triangle shrunk towards the third corner by `scale`; scale <= 0: nothing left)."""
    o = 0 if not mask & 1 else (1 if not mask & 2 else 2)
    p, q = t[(o + 1) % 3], t[(o + 2) % 3]
    e = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
    w = (t[o][0] - p[0], t[o][1] - p[1], t[o][2] - p[2])
    c = _cross(e, w)
    le = math.sqrt(_dot(e, e))
    height = 0.0 if le == 0.0 else math.sqrt(_dot(c, c)) / le
    s = 0.0 if height == 0.0 else 1.0 - reach / height
    if s <= 0.0:
        return t, s
    v = t[o]
    return (v, (v[0] + s * (p[0] - v[0]), v[1] + s * (p[1] - v[1]), v[2] + s * (p[2] - v[2])),
            (v[0] + s * (q[0] - v[0]), v[1] + s * (q[1] - v[1]), v[2] + s * (q[2] - v[2]))), s


@njit(cache=True)
def _corner_at(a, p, tol):
    """The corner of a within tol of point p, or -1."""
    for m in range(3):
        e = (a[m][0] - p[0], a[m][1] - p[1], a[m][2] - p[2])
        if _dot(e, e) <= tol * tol:
            return m
    return -1


@njit(cache=True)
def _turn_ok(det, ll, scale2):
    """det >= -1e-9 |x| |y|, det being n . (x cross y) scaled by sqrt(scale2) (ll = |x|^2 |y|^2)."""
    return det >= 0.0 or det * det <= 1e-18 * ll * scale2


@njit(cache=True)
def _beside(a, ga, b, mb, d, tol):
    """`_wedge_clear` when b (one shared corner s, on a's plane) lies within the thickness of a's
    plane: True when, seen along a's normal, b's corner at s and a's corner there are apart (no
    side of one inside the other's corner, within a relative 1e-9), so b's projection meets a only
    at s. Directions are compared in a's plane: every n . (x cross y) is the 2D determinant of x
    and y in the basis (e1, n cross e1), scaled by |e1|^2 (six of them; no square root)."""
    if not (mb == 1 or mb == 2 or mb == 4):
        return False
    k = _corner_of(mb)
    if abs(d[k]) > tol:
        return False
    j = _corner_at(a, b[k], tol)
    if j < 0:
        return False
    s = a[j]
    e1 = (a[(j + 1) % 3][0] - s[0], a[(j + 1) % 3][1] - s[1], a[(j + 1) % 3][2] - s[2])
    e2 = (a[(j + 2) % 3][0] - s[0], a[(j + 2) % 3][1] - s[1], a[(j + 2) % 3][2] - s[2])
    u1 = (b[(k + 1) % 3][0] - s[0], b[(k + 1) % 3][1] - s[1], b[(k + 1) % 3][2] - s[2])
    u2 = (b[(k + 2) % 3][0] - s[0], b[(k + 2) % 3][1] - s[1], b[(k + 2) % 3][2] - s[2])
    r = _cross(ga.u, e1)
    l_e1, l_e2, l_u1, l_u2 = _dot(e1, e1), _dot(e2, e2), _dot(u1, u1), _dot(u2, u2)
    scale2 = l_e1 * l_e1
    # 2D coordinates (x . e1, x . r); e1 itself is (|e1|^2, 0)
    x2, y2 = _dot(e2, e1), _dot(e2, r)
    xu1, yu1 = _dot(u1, e1), _dot(u1, r)
    xu2, yu2 = _dot(u2, e1), _dot(u2, r)
    d_e = l_e1 * y2  # e1 x e2
    d_u = xu1 * yu2 - yu1 * xu2  # u1 x u2
    d_e1u1 = l_e1 * yu1
    d_e1u2 = l_e1 * yu2
    d_u1e2 = xu1 * y2 - yu1 * x2
    d_u2e2 = xu2 * y2 - yu2 * x2
    # u in a's corner (e1, e2): n . (e1 x u) >= 0 and n . (u x e2) >= 0 (both flipped for a
    # clockwise corner), and u not opposite the corner
    fe = -1.0 if d_e < 0.0 else 1.0
    if (_turn_ok(fe * d_e1u1, l_e1 * l_u1, scale2) and _turn_ok(fe * d_u1e2, l_u1 * l_e2, scale2)
            and (_dot(e1, u1) > 0.0 or _dot(e2, u1) > 0.0)):
        return False
    if (_turn_ok(fe * d_e1u2, l_e1 * l_u2, scale2) and _turn_ok(fe * d_u2e2, l_u2 * l_e2, scale2)
            and (_dot(e1, u2) > 0.0 or _dot(e2, u2) > 0.0)):
        return False
    # a's sides in b's corner (u1, u2)
    fu = -1.0 if d_u < 0.0 else 1.0
    if (_turn_ok(-fu * d_e1u1, l_u1 * l_e1, scale2) and _turn_ok(fu * d_e1u2, l_e1 * l_u2, scale2)
            and (_dot(u1, e1) > 0.0 or _dot(u2, e1) > 0.0)):
        return False
    return not (_turn_ok(fu * d_u1e2, l_u1 * l_e2, scale2) and _turn_ok(-fu * d_u2e2, l_e2 * l_u2, scale2)
                and (_dot(u1, e2) > 0.0 or _dot(u2, e2) > 0.0))


@njit(cache=True)
def _straddle_clear(a, ga, b, mb, d, gap, reach, tol):
    """`_wedge_clear` when b (one shared corner s, on a's plane) crosses a's plane, or has a second
    corner x within gap of it: b meets that plane along the segment from s to a point x of its
    opposite side (or to that corner). True when that segment
    leaves s outside a's corner (no crossing), so far from a's sides that the band of b within gap
    of the plane reaches into a only within reach of s."""
    if not (mb == 1 or mb == 2 or mb == 4):
        return False
    k = _corner_of(mb)
    if abs(d[k]) > tol:
        return False
    c1, c2 = b[(k + 1) % 3], b[(k + 2) % 3]
    d1, d2 = d[(k + 1) % 3], d[(k + 2) % 3]
    if abs(d1) <= gap or abs(d2) <= gap:  # one corner within gap of the plane: the side to it
        t = 0.0 if abs(d1) <= abs(d2) else 1.0
    else:
        t = d1 / (d1 - d2)
    sb = b[k]
    u = (c1[0] + t * (c2[0] - c1[0]) - sb[0], c1[1] + t * (c2[1] - c1[1]) - sb[1], c1[2] + t * (c2[2] - c1[2]) - sb[2])
    lu = math.sqrt(_dot(u, u))
    # a's corner at s: the corner of a nearest to b's shared corner
    j, best = 0, math.inf
    for m in range(3):
        e = (a[m][0] - sb[0], a[m][1] - sb[1], a[m][2] - sb[2])
        if _dot(e, e) < best:
            j, best = m, _dot(e, e)
    if best > tol * tol or lu == 0.0:
        return False
    e1 = (a[(j + 1) % 3][0] - a[j][0], a[(j + 1) % 3][1] - a[j][1], a[(j + 1) % 3][2] - a[j][2])
    e2 = (a[(j + 2) % 3][0] - a[j][0], a[(j + 2) % 3][1] - a[j][1], a[(j + 2) % 3][2] - a[j][2])
    n = ga.u
    # sines of u's angles from a's two sides at s, signed so that inside the corner both are >= 0
    l1, l2 = math.sqrt(_dot(e1, e1)), math.sqrt(_dot(e2, e2))
    s1 = _dot(n, _cross(e1, u)) / (l1 * lu)
    s2 = _dot(n, _cross(u, e2)) / (l2 * lu)
    if _dot(n, _cross(e1, e2)) < 0.0:
        s1, s2 = -s1, -s2
    eps = 1e-9
    if s1 > eps and s2 > eps:
        return False  # the segment runs into a: they may cross
    nb = _cross(_edge(b, 0), _edge(b, 1))
    lb = math.sqrt(_dot(nb, nb))
    if lb == 0.0:
        return False
    cos_t = abs(_dot(n, nb)) / lb
    sin_t = math.sqrt(max(0.0, 1.0 - cos_t * cos_t))
    if sin_t <= 1e-3:
        return False
    band = 2.0 * gap * cos_t / sin_t  # b's band within gap of the plane, seen along a's normal
    if band <= gap:
        return True  # the segment runs outside a or along its side: the band stays in a's rim
    # the segment at distance r from s stays at least r sin(phi) from a (phi: its angle from the
    # nearest side, or r itself beyond 90 degrees)
    sin_phi = 1.0
    if s1 < 0.0 and _dot(e1, u) > 0.0:
        sin_phi = min(sin_phi, -s1)
    if s2 < 0.0 and _dot(e2, u) > 0.0:
        sin_phi = min(sin_phi, -s2)
    if sin_phi > 0.0 and (band + 2.0 * gap) / sin_phi + gap <= reach:  # plus a's inset
        return True
    return _beside(a, ga, b, mb, d, tol)  # b's corner beside a's, seen along a's normal


@njit(cache=True)
def _wedge_clear(a, ga, b, mb, gap, reach, tol):
    """True when b neither crosses a's plane nor comes within gap of it farther than reach from
    its shared corners (mb): b's other corners lie beyond gap on one side, its shared corners not
    beyond tol on the other, and the wedge the slab leaves at the shared corners is short. (The
    quick answer for faces around a common vertex, most of the pairs a thick test meets.)"""
    if not ga.uok:
        return False
    o = a[0]
    d = (_dot(ga.u, (b[0][0] - o[0], b[0][1] - o[1], b[0][2] - o[2])),
         _dot(ga.u, (b[1][0] - o[0], b[1][1] - o[1], b[1][2] - o[2])),
         _dot(ga.u, (b[2][0] - o[0], b[2][1] - o[1], b[2][2] - o[2])))  # a tuple: a list would allocate
    sides, flat = 0, 0
    for c in range(3):
        if not mb & (1 << c):
            if abs(d[c]) <= gap:
                flat += 1
            sides |= 1 if d[c] > 0 else 2
    if flat == 2:
        return _beside(a, ga, b, mb, d, tol)
    if flat or sides == 3:  # b meets a's plane along a segment from the shared corner
        return _straddle_clear(a, ga, b, mb, d, gap, reach, tol)
    up = sides == 1
    short = True  # the wedge |e| gap / |d| (e: shared -> free corner) plus gap within reach, squared: no sqrt
    room = (reach - gap) * (reach - gap)
    for k in range(3):
        if mb & (1 << k):
            if (d[k] < -tol) if up else (d[k] > tol):
                return False  # the shared corner is across the plane: b may cross a there
            for c in range(3):
                if not mb & (1 << c):
                    e = (b[c][0] - b[k][0], b[c][1] - b[k][1], b[c][2] - b[k][2])
                    short &= _dot(e, e) * gap * gap <= room * d[c] * d[c]
    # a short wedge; or, seen along a's normal, b's corner beside a's (nearly flat neighbours)
    return (short and reach >= gap) or _beside(a, ga, b, mb, d, tol)


@njit(cache=True, inline="always")
def thick_collides(a, b, ga, gb, ids_a, ids_b, tol, thick, reach):
    """The planners' pair test with the paper's thickness (ALGORITHMS.md 6.2, README "Paper
    thickness"): a, b cross (`faces_cross`), or come closer than thick with overlapping
    projections (`faces_near`). ids_a, ids_b: per corner (net vertex id x 3, mesh vertex id x 3;
    -1 unknown). Where they share a point they may touch: corners at a shared net or mesh vertex
    are cut off at reach first (the rest tested in triangles); faces sharing a mesh edge (a glued
    seam, closing) lose the strip within reach of it, and once both its copies meet (closed) are
    only tested for crossing. (The goal itself is tested without thickness: `fold.plan`.)"""
    # typed int64 from the start: literal zeros here compiled every helper below twice (1.5 s)
    ma, mb, met, edge = np.int64(0), np.int64(0), np.int64(0), np.int64(0)
    for i in range(3):
        for j in range(3):
            shared = ids_a[i] == ids_b[j]
            if ids_a[3 + i] >= 0 and ids_a[3 + i] == ids_b[3 + j]:
                shared = True
                edge += 1
                d = (a[i][0] - b[j][0], a[i][1] - b[j][1], a[i][2] - b[j][2])
                met += 1 if _dot(d, d) <= thick * thick else 0
            if shared:
                ma |= 1 << i
                mb |= 1 << j
    if met >= 2:
        return faces_cross(a, b, ga, gb, tol)  # a closed seam: the faces meet along it
    if (ma and _wedge_clear(a, ga, b, mb, thick, reach, tol)
            and _wedge_clear(b, gb, a, ma, thick, reach, tol)):
        return False
    return _thick_rest(a, b, ga, gb, ma, mb, edge, tol, thick, reach)


@njit(cache=True)
def _thick_rest(a, b, ga, gb, ma, mb, edge, tol, thick, reach):
    """`thick_collides` past its quick answers (a call: rarely reached, keeps compiling fast)."""
    if ma == 0:
        # whole faces farther apart than the thickness on some axis neither cross nor come near
        if faces_apart(a, b, ga, gb, thick):
            return False
        return faces_cross(a, b, ga, gb, tol) or _reaches_into(a, b, ga, gb, thick)
    one_corner = _one_bit(ma) and _one_bit(mb) and edge < 2
    if one_corner:
        # each face is cut to a quad away from the shared corner; while the corner's two copies are
        # apart (a mesh vertex not yet closed) the whole faces are often farther apart than the
        # thickness, and then so are their quads (and they do not cross)
        ka, kb = _corner_of(ma), _corner_of(mb)
        dk = (a[ka][0] - b[kb][0], a[ka][1] - b[kb][1], a[ka][2] - b[kb][2])
        if _dot(dk, dk) > thick * thick and faces_apart(a, b, ga, gb, thick):
            return False
    if faces_cross(a, b, ga, gb, tol):
        return True
    if edge >= 2:  # a mesh edge they share (a seam): what is left beyond reach of it
        sa, sb = _beyond_side(a, ma, reach), _beyond_side(b, mb, reach)
        if sa[1] <= 0.0 or sb[1] <= 0.0:
            return False
        return faces_near(sa[0], sb[0], face_geometry(sa[0], tol), face_geometry(sb[0], tol), thick)
    if not one_corner:
        return faces_near(a, b, ga, gb, thick)  # (no such pair in a net: two shared net vertices are a crease)
    qa, qb = _corner_cut(a, ma, reach), _corner_cut(b, mb, reach)
    for ta in qa:
        sa = face_geometry(ta, tol)
        if sa.sliver:
            continue
        for tb in qb:
            sb = face_geometry(tb, tol)
            if not sb.sliver and faces_near(ta, tb, sa, sb, thick):
                return True
    return False


@njit(cache=True)
def _one_bit(m):
    return m == 1 or m == 2 or m == 4


@njit(cache=True)
def _corner_of(m):
    """The corner (0, 1, 2) of a one-bit corner mask m (`_one_bit`)."""
    return 0 if m == 1 else (1 if m == 2 else 2)


@njit(cache=True)
def _corner_cut(t, mask, reach):
    """Triangle t with its corner in mask (one bit) cut off at reach along its two sides (at most
    half of each): what is left away from the point it shares, as the two triangles of a quad."""
    k = _corner_of(mask)
    c, p, n = t[k], t[(k + 2) % 3], t[(k + 1) % 3]
    dp = (p[0] - c[0], p[1] - c[1], p[2] - c[2])
    dn = (n[0] - c[0], n[1] - c[1], n[2] - c[2])
    lp, ln = math.sqrt(_dot(dp, dp)), math.sqrt(_dot(dn, dn))
    sp = 0.0 if lp == 0.0 else min(reach, 0.5 * lp) / lp
    sn = 0.0 if ln == 0.0 else min(reach, 0.5 * ln) / ln
    cp = (c[0] + sp * dp[0], c[1] + sp * dp[1], c[2] + sp * dp[2])
    cn = (c[0] + sn * dn[0], c[1] + sn * dn[1], c[2] + sn * dn[2])
    return ((cp, cn, n), (cp, n, p))
