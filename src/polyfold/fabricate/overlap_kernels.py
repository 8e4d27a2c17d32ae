"""Compiled areas of overlap between one convex polygon and a piece's obstacles (`tabs.Room`).

Polygons are rings of points (k, 2), not closed (the first point is not repeated), either
orientation. An obstacle is one or more rings in a shared table: `pts` (P, 2) the points of every
ring, ring r being pts[ring_ptr[r]:ring_ptr[r + 1]] with `ring_sign[r]` +1 (an outer ring) or -1
(a hole), obstacle o being rings obs_ptr[o] to obs_ptr[o + 1] - 1. Its area within a convex
polygon C is the sum over its rings of sign * area(ring clipped to C): Sutherland-Hodgman clipping
by a convex window gives a ring (degenerate where the subject is not convex) whose shoelace area
is the area of the subject within the window, for any simple subject ring.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit


@njit(cache=True)
def _orientation(ring: np.ndarray) -> float:
    """Twice the signed area of a ring (k, 2): positive counter-clockwise (y up)."""
    s = 0.0
    n = ring.shape[0]
    for i in range(n):
        j = (i + 1) % n
        s += ring[i, 0] * ring[j, 1] - ring[j, 0] * ring[i, 1]
    return s


@njit(cache=True)
def _area(bufs: np.ndarray, b: int, n: int) -> float:
    """Area (positive) of the ring bufs[b, :n]; 0 under 3 points."""
    if n < 3:
        return 0.0
    s = 0.0
    for i in range(n):
        j = (i + 1) % n
        s += bufs[b, i, 0] * bufs[b, j, 1] - bufs[b, j, 0] * bufs[b, i, 1]
    return abs(s) / 2.0


@njit(cache=True)
def is_convex(ring: np.ndarray, tol: float) -> bool:
    """Whether a ring (k, 2) turns one way only at every corner (turns below `tol` x the two
    sides' lengths are straight: a buffer's arcs)."""
    n = ring.shape[0]
    pos, neg = False, False
    for i in range(n):
        a, b, c = ring[i], ring[(i + 1) % n], ring[(i + 2) % n]
        ux, uy, vx, vy = b[0] - a[0], b[1] - a[1], c[0] - b[0], c[1] - b[1]
        cross = ux * vy - uy * vx
        scale = np.hypot(ux, uy) * np.hypot(vx, vy)
        if cross > tol * scale:
            pos = True
        elif cross < -tol * scale:
            neg = True
    return not (pos and neg)


@njit(cache=True)
def _clip(bufs: np.ndarray, src: int, n: int, window: np.ndarray, sign: float) -> tuple[int, int]:
    """The ring bufs[src, :n] clipped to the convex `window` (k, 2), whose orientation is `sign`
    (+1 counter-clockwise), clipping back and forth between bufs[src] and bufs[1 - src]:
    (the buffer holding the result, its length; -1 when the buffers are too small)."""
    cur, m = src, n
    k = window.shape[0]
    size = bufs.shape[1]
    for e in range(k):
        if m == 0:
            break
        if 2 * m > size:  # (a half-plane at most doubles a ring: no room, no answer)
            return cur, -1
        ax, ay = window[e, 0], window[e, 1]
        ex, ey = window[(e + 1) % k, 0] - ax, window[(e + 1) % k, 1] - ay
        if ex == 0.0 and ey == 0.0:
            continue
        out = 1 - cur
        cnt = 0
        for i in range(m):
            j = (i + 1) % m
            px, py = bufs[cur, i, 0], bufs[cur, i, 1]
            qx, qy = bufs[cur, j, 0], bufs[cur, j, 1]
            dp = sign * (ex * (py - ay) - ey * (px - ax))
            dq = sign * (ex * (qy - ay) - ey * (qx - ax))
            if dp >= 0.0:
                bufs[out, cnt, 0], bufs[out, cnt, 1] = px, py
                cnt += 1
            if (dp >= 0.0) != (dq >= 0.0):
                t = dp / (dp - dq)
                bufs[out, cnt, 0], bufs[out, cnt, 1] = px + t * (qx - px), py + t * (qy - py)
                cnt += 1
        cur, m = out, cnt
    return cur, m


@njit(cache=True)
def overlap_area(window: np.ndarray, discs: np.ndarray, pts: np.ndarray, ring_ptr: np.ndarray,
                 ring_sign: np.ndarray, obs_ptr: np.ndarray, obstacles: np.ndarray) -> float:
    """Area of the obstacles (indices into the table: see the module docstring) within the convex
    ring `window` (k, 2) and outside every one of `discs` (d, m, 2: convex rings, at most two);
    nan when a clipped ring outgrows the work arrays."""
    longest = 0
    for o in obstacles:
        for r in range(obs_ptr[o], obs_ptr[o + 1]):
            longest = max(longest, ring_ptr[r + 1] - ring_ptr[r])
    size = 4 * (longest + window.shape[0] + discs.shape[1]) + 16
    hit = np.empty((2, size, 2))  # the ring within the window
    part = np.empty((2, size, 2))  # that within a disc, or both
    s_window = 1.0 if _orientation(window) >= 0 else -1.0
    s_disc = np.empty(discs.shape[0])
    for k in range(discs.shape[0]):
        s_disc[k] = 1.0 if _orientation(discs[k]) >= 0 else -1.0
    total = 0.0
    for o in obstacles:
        for r in range(obs_ptr[o], obs_ptr[o + 1]):
            n = ring_ptr[r + 1] - ring_ptr[r]
            for i in range(n):
                hit[0, i, 0], hit[0, i, 1] = pts[ring_ptr[r] + i, 0], pts[ring_ptr[r] + i, 1]
            h, m = _clip(hit, 0, n, window, s_window)
            if m < 0:
                return np.nan
            if m < 3:
                continue
            area = _area(hit, h, m)
            for k in range(discs.shape[0]):  # minus the discs (inclusion-exclusion over the two)
                for i in range(m):
                    part[0, i, 0], part[0, i, 1] = hit[h, i, 0], hit[h, i, 1]
                p, m1 = _clip(part, 0, m, discs[k], s_disc[k])
                if m1 < 0:
                    return np.nan
                area -= _area(part, p, m1)
                for k2 in range(k + 1, discs.shape[0]):
                    if m1 >= 3:
                        p2, m2 = _clip(part, p, m1, discs[k2], s_disc[k2])
                        if m2 < 0:
                            return np.nan
                        area += _area(part, p2, m2)
            total += ring_sign[r] * area
    return total


@njit(cache=True)
def offset_bounds(ring: np.ndarray, dist: float) -> tuple[np.ndarray, np.ndarray]:
    """Two convex rings between which every round-joined buffer of the convex `ring` by `dist`
    lies whose arcs are polylines with their corners on the circle (GEOS's, any quad_segs): the
    bevelled one (each edge moved out by dist, consecutive ones joined by a chord: inside it) and
    the mitred one (consecutive moved edges extended to meet: around it). Same orientation as ring."""
    n = ring.shape[0]
    sign = 1.0 if _orientation(ring) >= 0 else -1.0
    normals = np.zeros((n, 2))
    edges = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        j = (i + 1) % n
        ex, ey = ring[j, 0] - ring[i, 0], ring[j, 1] - ring[i, 1]
        length = np.sqrt(ex * ex + ey * ey)
        if length > 1e-12:  # outward: to the right of a counter-clockwise edge
            normals[i, 0], normals[i, 1] = sign * ey / length, -sign * ex / length
            edges[m] = i
            m += 1
    bevel = np.empty((2 * m, 2))
    mitre = np.empty((m, 2))
    for q in range(m):
        i, h = edges[q], edges[(q + m - 1) % m]  # edge i starts at ring[i]; edge h ends there
        hx, hy, ix, iy = normals[h, 0], normals[h, 1], normals[i, 0], normals[i, 1]
        vx, vy = ring[i, 0], ring[i, 1]
        bevel[2 * q, 0], bevel[2 * q, 1] = vx + dist * hx, vy + dist * hy
        bevel[2 * q + 1, 0], bevel[2 * q + 1, 1] = vx + dist * ix, vy + dist * iy
        f = dist / max(1.0 + hx * ix + hy * iy, 1e-12)
        mitre[q, 0], mitre[q, 1] = vx + f * (hx + ix), vy + f * (hy + iy)
    return bevel, mitre


@njit(cache=True)
def blocked_by(poly: np.ndarray, clear: float, discs: np.ndarray, exact: np.ndarray, least: float, pts: np.ndarray,
               ring_ptr: np.ndarray, ring_sign: np.ndarray, obs_ptr: np.ndarray, obstacles: np.ndarray) -> int:
    """Whether the obstacles (see the module docstring) cover more than `least` of the convex
    ring `poly`, or of poly grown by `clear` outside the `discs` (d, m, 2): 1 yes, 0 no; 2 when
    the grown poly's shape decides and is not given (`exact` with no points; see
    `offset_bounds`), to be asked again with it (then only the grown poly is measured: poly
    itself was); -1 when this cannot say (poly not convex, or a clipped ring outgrew the work
    arrays)."""
    if exact.shape[0] >= 3:
        near = overlap_area(exact, discs, pts, ring_ptr, ring_sign, obs_ptr, obstacles)
        return -1 if np.isnan(near) else int(near > least)
    if not is_convex(poly, 1e-9):
        return -1
    none = np.zeros((0, 1, 2))
    inside = overlap_area(poly, none, pts, ring_ptr, ring_sign, obs_ptr, obstacles)
    if np.isnan(inside):
        return -1
    if inside > least:
        return 1
    if clear <= 0.0:
        return 0
    within, around = offset_bounds(poly, clear)
    low = overlap_area(within, discs, pts, ring_ptr, ring_sign, obs_ptr, obstacles)
    if np.isnan(low):
        return -1
    if low > least:
        return 1
    high = overlap_area(around, discs, pts, ring_ptr, ring_sign, obs_ptr, obstacles)
    if np.isnan(high):
        return -1
    return 0 if high <= least else 2


@njit(cache=True)
def grown_box_meets(box: np.ndarray, pad: float, pts: np.ndarray, ring_ptr: np.ndarray) -> int:
    """Whether the ring `box` (k, 2), convex, grown by `pad` with its corners cut by chords
    (shapely's buffer with quad_segs=1), meets any of the rings pts[ring_ptr[r]:ring_ptr[r + 1]]:
    1 when one overlaps it by more than 1e-12 mm², 0 when each lies more than 1e-9 mm beyond
    one of its sides; -1 when neither tells for some ring and none overlaps (a ring touching it,
    or near it across a corner: `grown_box_apart` tells the latter)."""
    return _grown_box_meets(box, pad, pts, ring_ptr, np.arange(ring_ptr.shape[0] - 1))


@njit(cache=True)
def _grown_box_meets(box, pad, pts, ring_ptr, rings):
    """`grown_box_meets` for the rings whose indices are `rings` (the answer does not depend on
    their order: 1 as soon as one overlaps, else -1 when one was unsure)."""
    window = offset_bounds(box, pad)[0]
    k = window.shape[0]
    sign = 1.0 if _orientation(window) >= 0 else -1.0
    longest = 0
    for r in rings:
        longest = max(longest, ring_ptr[r + 1] - ring_ptr[r])
    bufs = np.empty((2, 4 * (longest + k) + 16, 2))
    unsure = False
    for r in rings:
        lo, hi = ring_ptr[r], ring_ptr[r + 1]
        apart = False
        for e in range(k):
            ax, ay = window[e, 0], window[e, 1]
            ex, ey = window[(e + 1) % k, 0] - ax, window[(e + 1) % k, 1] - ay
            length = np.sqrt(ex * ex + ey * ey)
            if length == 0.0:
                continue
            beyond = True
            for i in range(lo, hi):
                if sign * (ex * (pts[i, 1] - ay) - ey * (pts[i, 0] - ax)) / length > -1e-9:
                    beyond = False
                    break
            if beyond:
                apart = True
                break
        if apart:
            continue
        for i in range(hi - lo):
            bufs[0, i, 0], bufs[0, i, 1] = pts[lo + i, 0], pts[lo + i, 1]
        b, m = _clip(bufs, 0, hi - lo, window, sign)
        if m >= 0 and _area(bufs, b, m) > 1e-12:
            return 1
        unsure = True
    return -1 if unsure else 0


@njit(cache=True, inline="always")
def point_segment_distance(px, py, a0, a1, b0, b1):
    """Distance from (px, py) to the segment (a0, a1)-(b0, b1): numpy's of the nearest point on
    it, to the last bit: t = ((p - a) . ab) / max(ab . ab, 1e-300) clipped to [0, 1], then the
    norm of a + t ab - p (`labels._nearer_than_others` compares such distances)."""
    ab0, ab1 = b0 - a0, b1 - a1
    t = ((px - a0) * ab0 + (py - a1) * ab1) / max(ab0 * ab0 + ab1 * ab1, 1e-300)
    t = min(max(t, 0.0), 1.0)
    d0, d1 = a0 + t * ab0 - px, a1 + t * ab1 - py
    return math.sqrt(d0 * d0 + d1 * d1)


@njit(cache=True)
def _segments_distance(ax, ay, bx, by, cx, cy, dx, dy):
    """Distance between the segments a-b and c-d: 0 when they cross, else the least of their
    ends' distances to the other segment (where the least distance of two segments that do not
    cross lies)."""
    o1 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    o2 = (bx - ax) * (dy - ay) - (by - ay) * (dx - ax)
    o3 = (dx - cx) * (ay - cy) - (dy - cy) * (ax - cx)
    o4 = (dx - cx) * (by - cy) - (dy - cy) * (bx - cx)
    if ((o1 > 0.0 and o2 < 0.0) or (o1 < 0.0 and o2 > 0.0)) and ((o3 > 0.0 and o4 < 0.0) or (o3 < 0.0 and o4 > 0.0)):
        return 0.0
    return min(point_segment_distance(ax, ay, cx, cy, dx, dy), point_segment_distance(bx, by, cx, cy, dx, dy),
               point_segment_distance(cx, cy, ax, ay, bx, by), point_segment_distance(dx, dy, ax, ay, bx, by))


@njit(cache=True)
def _rings_apart(window, pts, lo, hi, eps):
    """True when the convex ring `window` (k, 2) and the ring pts[lo:hi] (any simple ring) are
    more than eps apart: every side of one farther than eps from every side of the other, and
    neither has a corner inside the other (so neither holds the other). False says nothing."""
    k = window.shape[0]
    for e in range(k):
        ax, ay = window[e, 0], window[e, 1]
        bx, by = window[(e + 1) % k, 0], window[(e + 1) % k, 1]
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            if _segments_distance(ax, ay, bx, by, pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1]) <= eps:
                return False
    # a corner of the ring inside the convex window: on the inner side of all its sides
    sign = 1.0 if _orientation(window) >= 0 else -1.0
    px, py = pts[lo, 0], pts[lo, 1]
    inside = True
    for e in range(k):
        ax, ay = window[e, 0], window[e, 1]
        ex, ey = window[(e + 1) % k, 0] - ax, window[(e + 1) % k, 1] - ay
        if sign * (ex * (py - ay) - ey * (px - ax)) <= 0.0:
            inside = False
            break
    if inside:
        return False
    # a corner of the window inside the ring (crossings of a ray to +x)
    qx, qy = window[0, 0], window[0, 1]
    crossings = 0
    for i in range(lo, hi):
        j = i + 1 if i + 1 < hi else lo
        yi, yj = pts[i, 1], pts[j, 1]
        if (yi > qy) != (yj > qy):
            x = pts[i, 0] + (qy - yi) / (yj - yi) * (pts[j, 0] - pts[i, 0])
            if x > qx:
                crossings += 1
    return crossings % 2 == 0


@njit(cache=True)
def _near_cells(cells, has_ring, n, cx0, cx1, cy0, cy1, out):
    """How many of the first n items (cells (n, 4): first and last column, first and last row of
    the hash cells they lie in) share a cell with the range cx0..cx1, cy0..cy1, their indices
    written to out; -1 when one of them has no ring (`has_ring` False)."""
    m = 0
    for t in range(n):
        if cells[t, 0] <= cx1 and cx0 <= cells[t, 1] and cells[t, 2] <= cy1 and cy0 <= cells[t, 3]:
            if not has_ring[t]:
                return -1
            out[m] = t
            m += 1
    return m


@njit(cache=True)
def _meets_labels(box, cx0, cx1, cy0, cy1, pad, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n,
                  b_pts, b_ring_ptr, b_cells, b_has_ring, b_n, near_a, near_b):
    """Whether the box (4, 2) in hash cells cx0..cx1, cy0..cy1, grown by `pad`, meets a label
    shape of set a or b sharing a cell with it (see `first_clear_box`): 1 yes, 0 no, -1 when this
    cannot tell (an item near it without a ring, or `grown_box_meets` unsure)."""
    na = _near_cells(a_cells, a_has_ring, a_n, cx0, cx1, cy0, cy1, near_a)
    nb = _near_cells(b_cells, b_has_ring, b_n, cx0, cx1, cy0, cy1, near_b)
    if na < 0 or nb < 0:
        return -1
    unsure = False
    if na > 0:
        hit = _grown_box_meets(box, pad, a_pts, a_ring_ptr, near_a[:na])
        if hit == 1:
            return 1
        unsure = hit < 0
    if nb > 0:
        hit = _grown_box_meets(box, pad, b_pts, b_ring_ptr, near_b[:nb])
        if hit == 1:
            return 1
        unsure = unsure or hit < 0
    return -1 if unsure else 0


APART_MM = 1e-9  # a label shape farther than this from a grown box does not meet it (shapely would agree)


@njit(cache=True)
def _all_apart(window, pts, ring_ptr, rings):
    """Whether every ring pts[ring_ptr[r]:ring_ptr[r + 1]], r in `rings`, lies more than APART_MM
    from the convex ring `window` (`_rings_apart`)."""
    for r in rings:
        if not _rings_apart(window, pts, ring_ptr[r], ring_ptr[r + 1], APART_MM):
            return False
    return True


@njit(cache=True)
def grown_box_apart(box: np.ndarray, pad: float, pts: np.ndarray, ring_ptr: np.ndarray) -> bool:
    """Whether every ring pts[ring_ptr[r]:ring_ptr[r + 1]] lies more than APART_MM from the box
    (k, 2) grown by `pad` as `grown_box_meets` grows it (`_all_apart`): what an unsure answer of
    that kernel turns out to be for a box near a bent leader strip or across a box's corner."""
    return _all_apart(offset_bounds(box, pad)[0], pts, ring_ptr, np.arange(ring_ptr.shape[0] - 1))


@njit(cache=True)
def _set_apart(window, pts, ring_ptr, cells, has_ring, n, cx0, cx1, cy0, cy1, near):
    """Whether every item of one hashed set sharing a cell with cx0..cx1, cy0..cy1 has a ring
    more than APART_MM from the convex ring `window` (`_all_apart`)."""
    m = _near_cells(cells, has_ring, n, cx0, cx1, cy0, cy1, near)
    return m >= 0 and _all_apart(window, pts, ring_ptr, near[:m])


@njit(cache=True)
def _labels_apart(box, cx0, cx1, cy0, cy1, pad, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n,
                  b_pts, b_ring_ptr, b_cells, b_has_ring, b_n, near_a, near_b):
    """Whether the box (4, 2) grown by `pad` (`grown_box_meets`' outline) lies more than APART_MM
    from every label shape near it (`_meets_labels`' sets): what an unsure answer of
    `_meets_labels` turns out to be for a box near a bent leader strip or across a box's corner
    (4,484 times on the Loop-subdivided fish). False when an item near it has no ring, or one is
    that close. (Only `first_clear_box` asks: a first run compiles it when a make needs it.)"""
    window = offset_bounds(box, pad)[0]
    return (_set_apart(window, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n, cx0, cx1, cy0, cy1, near_a)
            and _set_apart(window, b_pts, b_ring_ptr, b_cells, b_has_ring, b_n, cx0, cx1, cy0, cy1, near_b))


@njit(cache=True)
def first_clear_box(boxes, order, start, box_cells, pad, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n,
                    b_pts, b_ring_ptr, b_cells, b_has_ring, b_n, clear, least, pts, ring_ptr, ring_sign, obs_ptr,
                    face_bounds, extra_bounds, n_extras):
    """The first position j >= start of `order` whose box boxes[order[j]] (4, 2 corners, convex)
    neither meets, grown by `pad` (`grown_box_meets`), a ring of two hashed sets of label shapes
    near it (a: rings a_pts[a_ring_ptr[t]:a_ring_ptr[t + 1]] of the first a_n items, each in the
    hash cells a_cells[t] (first, last column; first, last row); b alike), nor is `blocked_by` the
    obstacles of a piece's table (pts .. obs_ptr: the module docstring) whose bounds (x0, y0,
    x1, y1) meet its own grown by `clear`: the faces (face_bounds (F, 4), obstacles 0..F-1),
    then the first n_extras extras (extra_bounds, obstacles F..). The labels near a box are those
    sharing a hash cell with it (box_cells[i], as the items'); where `grown_box_meets` is unsure,
    they are told by distance (`_labels_apart`). As (j, 0); (j, 1) when that box is one these
    tests cannot tell (an item without a ring near it, one touching it, or an unsure answer: the
    caller decides it); (len(order), -1) when none is clear."""
    no_discs = np.zeros((0, 1, 2))
    near_a = np.empty(a_n, dtype=np.int64)
    near_b = np.empty(b_n, dtype=np.int64)
    obstacles = np.empty(face_bounds.shape[0] + n_extras, dtype=np.int64)
    for j in range(start, order.shape[0]):
        i = order[j]
        box = np.ascontiguousarray(boxes[i])
        hit = _meets_labels(box, box_cells[i, 0], box_cells[i, 1], box_cells[i, 2], box_cells[i, 3], pad,
                            a_pts, a_ring_ptr, a_cells, a_has_ring, a_n, b_pts, b_ring_ptr, b_cells, b_has_ring, b_n,
                            near_a, near_b)
        if hit == 1:
            continue
        if hit < 0 and not _labels_apart(box, box_cells[i, 0], box_cells[i, 1], box_cells[i, 2], box_cells[i, 3],
                                         pad, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n, b_pts, b_ring_ptr,
                                         b_cells, b_has_ring, b_n, near_a, near_b):
            return j, 1
        answer = _room_blocks(box, clear, no_discs, least, -1, pts, ring_ptr, ring_sign, obs_ptr, face_bounds,
                              extra_bounds, n_extras, obstacles)
        if answer == 1:
            continue
        if answer == 0:
            return j, 0
        return j, 1
    return order.shape[0], -1


@njit(cache=True)
def first_box_in_triangle(boxes, tri, side_lengths, inset, box_cells, pad, a_pts, a_ring_ptr, a_cells, a_has_ring, a_n,
                          b_pts, b_ring_ptr, b_cells, b_has_ring, b_n):
    """The first index i of boxes (k, 4, 2) whose corners all lie inside the triangle `tri`
    (3, 2), either orientation, at least `inset` from its sides (as `labels.inside_triangle`
    computes it; side_lengths (3,): Python's math.hypot of sides ab, bc, ca, which numba's may
    differ from in the last bit), and which meets no label shape near it grown by `pad` (`first_clear_box`'s a
    and b): (i, 0); (i, 1) when the labels' test cannot tell for that box (the caller decides);
    (k, -1) when none."""
    near_a = np.empty(a_n, dtype=np.int64)
    near_b = np.empty(b_n, dtype=np.int64)
    for i in range(boxes.shape[0]):
        box = np.ascontiguousarray(boxes[i])
        if not _triangle_clearance(box, tri, side_lengths) >= inset:
            continue
        hit = _meets_labels(box, box_cells[i, 0], box_cells[i, 1], box_cells[i, 2], box_cells[i, 3], pad,
                            a_pts, a_ring_ptr, a_cells, a_has_ring, a_n, b_pts, b_ring_ptr, b_cells, b_has_ring, b_n,
                            near_a, near_b)
        if hit == 0:
            return i, 0
        if hit < 0:
            return i, 1
    return boxes.shape[0], -1


@njit(cache=True)
def _room_obstacles(x0, y0, x1, y1, skip_face, face_bounds, extra_bounds, n_extras, out):
    """How many obstacles of a room (faces but skip_face, then extras: numbered as `blocked_by`'s
    table) have bounds (x0, y0, x1, y1) meeting the box x0..x1, y0..y1 (edges included), written
    to out in that order."""
    m = 0
    n_faces = face_bounds.shape[0]
    for f in range(n_faces):
        if f != skip_face and face_bounds[f, 0] <= x1 and x0 <= face_bounds[f, 2] and face_bounds[f, 1] <= y1 \
                and y0 <= face_bounds[f, 3]:
            out[m] = f
            m += 1
    for e in range(n_extras):
        if extra_bounds[e, 0] <= x1 and x0 <= extra_bounds[e, 2] and extra_bounds[e, 1] <= y1 and y0 <= extra_bounds[e, 3]:
            out[m] = n_faces + e
            m += 1
    return m


@njit(cache=True)
def _room_blocks(ring, clear, discs, least, skip_face, pts, ring_ptr, ring_sign, obs_ptr, face_bounds, extra_bounds,
                 n_extras, out):
    """`blocked_by` of the convex ring (k, 2) by a room's obstacles whose bounds meet its own grown
    by `clear` (`_room_obstacles`, but face skip_face; `out` their work array): 0 when there are
    none."""
    x0, y0, x1, y1 = ring[0, 0], ring[0, 1], ring[0, 0], ring[0, 1]
    for i in range(1, ring.shape[0]):
        x0, y0 = min(x0, ring[i, 0]), min(y0, ring[i, 1])
        x1, y1 = max(x1, ring[i, 0]), max(y1, ring[i, 1])
    m = _room_obstacles(x0 - clear, y0 - clear, x1 + clear, y1 + clear, skip_face, face_bounds, extra_bounds, n_extras,
                        out)
    if m == 0:
        return 0
    return blocked_by(ring, clear, discs, np.zeros((0, 2)), least, pts, ring_ptr, ring_sign, obs_ptr, out[:m])


@njit(cache=True)
def first_unblocked(polys, side_of, skip_faces, discs, clear, least,
                    pts0, ring_ptr0, ring_sign0, obs_ptr0, face_bounds0, extra_bounds0, n_extras0,
                    pts1, ring_ptr1, ring_sign1, obs_ptr1, face_bounds1, extra_bounds1, n_extras1):
    """The first of the convex polygons polys (k, m, 2) not `blocked_by` the room of its side
    (side_of[c], 0 or 1: a glued pair's two sides, each with its room's table, faces' and
    extras' bounds as `first_clear_box` takes them): the room's obstacles whose bounds meet the
    polygon's grown by `clear`, but face skip_faces[side], measured outside the side's discs
    (discs[side]: (d, n, 2) convex rings). As (c, 0); (c, 1) when `blocked_by` cannot tell for
    it (the caller asks `tabs.Room.blocked`); (k, -1) when every one is blocked."""
    out0 = np.empty(face_bounds0.shape[0] + n_extras0, dtype=np.int64)
    out1 = np.empty(face_bounds1.shape[0] + n_extras1, dtype=np.int64)
    for c in range(polys.shape[0]):
        ring = np.ascontiguousarray(polys[c])
        if side_of[c] == 0:
            answer = _room_blocks(ring, clear, discs[0], least, skip_faces[0], pts0, ring_ptr0, ring_sign0, obs_ptr0,
                                  face_bounds0, extra_bounds0, n_extras0, out0)
        else:
            answer = _room_blocks(ring, clear, discs[1], least, skip_faces[1], pts1, ring_ptr1, ring_sign1, obs_ptr1,
                                  face_bounds1, extra_bounds1, n_extras1, out1)
        if answer == 1:
            continue
        if answer == 0:
            return c, 0
        return c, 1
    return polys.shape[0], -1


@njit(cache=True)
def _triangle_clearance(box, tri, side_lengths):
    """How far inside triangle `tri` (3, 2), either orientation, the box's corners (k, 2) lie: the
    least of their distances from its sides as `labels.inside_triangle` computes them
    (side_lengths (3,): of sides ab, bc, ca), negative outside; -inf when a side has no length."""
    ax, ay, bx, by, cx, cy = tri[0, 0], tri[0, 1], tri[1, 0], tri[1, 1], tri[2, 0], tri[2, 1]
    area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    sgn = 1.0 if area2 > 0 else -1.0
    least = np.inf
    for s in range(3):
        px, py = tri[s, 0], tri[s, 1]
        ex, ey = tri[(s + 1) % 3, 0] - px, tri[(s + 1) % 3, 1] - py
        ln = side_lengths[s]
        if ln == 0:
            return -np.inf
        for c in range(box.shape[0]):
            d = sgn * (ex * (box[c, 1] - py) - ey * (box[c, 0] - px)) / ln
            if d < least:
                least = d
    return least


@njit(cache=True)
def first_leader_spot(boxes, start, p, tris, face_bounds, inset, margin, strip, cell, a_pts, a_ring_ptr, a_cells,
                      a_has_ring, a_n, clear, least, pts, ring_ptr, ring_sign, obs_ptr, extra_bounds, n_extras):
    """The first index i >= start of the label boxes (k, 4, 2 corners) that `labels.PieceLabels.
    _leader_spot` may take with a straight leader from p (2,); k when none may. It surely turns a
    box down
    - when the box lies in no face (each face triangle of tris (F, 3, 2) whose bounds face_bounds
      (F, 4) meet the box's holds it less than `inset` from its sides, by more than `margin`:
      `_triangle_clearance`, numba's hypot, which may differ from Python's in the last bit)
      and the room blocks it (`_room_blocks`, `clear` and `least` as `tabs.Room.blocked`; the room's
      table pts .. obs_ptr, its faces then its first n_extras extras, extra_bounds (E, 4)); or
    - when its leader, p to the nearest point of the box's outline, comes within `strip` of a placed
      label box (the rings a_pts[a_ring_ptr[t]:a_ring_ptr[t + 1]] of the first a_n, each in the
      `cell` mm hash cells a_cells[t], as `first_clear_box`'s): `strip` less than the leader's half
      width by what shapely's buffer of it cuts off its round ends, and by a margin for where that
      nearest point may differ in the last bits.
    (The screen of `_elsewhere`'s candidates: most are turned down by one of these, each in a
    tenth of a millisecond of shapely; the caller decides the others exactly.)"""
    no_discs = np.zeros((0, 1, 2))
    obstacles = np.empty(face_bounds.shape[0] + n_extras, dtype=np.int64)
    near = np.empty(a_n, dtype=np.int64)
    lengths = np.empty(3)
    for i in range(start, boxes.shape[0]):
        box = np.ascontiguousarray(boxes[i])
        x0, y0, x1, y1 = box[0, 0], box[0, 1], box[0, 0], box[0, 1]
        for c in range(1, 4):
            x0, y0 = min(x0, box[c, 0]), min(y0, box[c, 1])
            x1, y1 = max(x1, box[c, 0]), max(y1, box[c, 1])
        in_face = False
        for f in range(tris.shape[0]):
            if face_bounds[f, 0] <= x1 and x0 <= face_bounds[f, 2] and face_bounds[f, 1] <= y1 \
                    and y0 <= face_bounds[f, 3]:
                t0, t1, t2 = tris[f, 0], tris[f, 1], tris[f, 2]
                lengths[0] = math.hypot(t1[0] - t0[0], t1[1] - t0[1])
                lengths[1] = math.hypot(t2[0] - t1[0], t2[1] - t1[1])
                lengths[2] = math.hypot(t0[0] - t2[0], t0[1] - t2[1])
                if not _triangle_clearance(box, tris[f], lengths) < inset - margin:
                    in_face = True
                    break
        if not in_face and _room_blocks(box, clear, no_discs, least, -1, pts, ring_ptr, ring_sign, obs_ptr,
                                        face_bounds, extra_bounds, n_extras, obstacles) == 1:
            continue
        # the leader's end: the nearest point of the box's outline (its first side on a tie)
        best, ex, ey = np.inf, 0.0, 0.0
        for c in range(4):
            a0, a1 = box[c, 0], box[c, 1]
            b0, b1 = box[(c + 1) % 4, 0], box[(c + 1) % 4, 1]
            ab0, ab1 = b0 - a0, b1 - a1
            t = ((p[0] - a0) * ab0 + (p[1] - a1) * ab1) / max(ab0 * ab0 + ab1 * ab1, 1e-300)
            t = min(max(t, 0.0), 1.0)
            qx, qy = a0 + t * ab0, a1 + t * ab1
            d = math.hypot(qx - p[0], qy - p[1])
            if d < best:
                best, ex, ey = d, qx, qy
        # the labels sharing a hash cell with the leader's bounds (a cell wider: `_Boxes` hashes by
        # Python's floor division), as `_Boxes.hits_geom` finds them
        m = _near_cells(a_cells, a_has_ring, a_n, int(math.floor((min(p[0], ex) - strip) / cell)) - 1,
                        int(math.floor((max(p[0], ex) + strip) / cell)) + 1,
                        int(math.floor((min(p[1], ey) - strip) / cell)) - 1,
                        int(math.floor((max(p[1], ey) + strip) / cell)) + 1, near)
        hit = False
        for q in range(max(m, 0)):
            lo, hi = a_ring_ptr[near[q]], a_ring_ptr[near[q] + 1]
            for k in range(lo, hi):
                e = k + 1 if k + 1 < hi else lo
                if _segments_distance(p[0], p[1], ex, ey, a_pts[k, 0], a_pts[k, 1], a_pts[e, 0], a_pts[e, 1]) < strip:
                    hit = True
                    break
            if hit:
                break
        if not hit:
            return i
    return boxes.shape[0]
