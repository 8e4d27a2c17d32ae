"""Forward kinematics of a crease tree (ALGORITHMS.md 6.1).

A configuration q (E,) holds one fold angle per net edge (radians, internal convention rho:
positive = mountain / convex, ALGORITHMS.md 1.2); only the tree creases are read. Piece roots stay
where the flat net puts them (plane z = 0, outer side facing +z); every other face is its parent's
transform followed by a rotation by q[crease] about the crease, directed along the parent's CCW
order (right-hand rule), so a positive angle moves the child below the parent's plane. Folding to
the goal rebuilds the folded shape up to one rigid motion per piece.

The per-configuration kernel `fold_faces` is inlined into its callers (inline="always"): a call
between compiled functions updates the reference count of every array argument atomically
(~5 ns each), which summed to about a third of a small net's collision test.
"""

from __future__ import annotations

import math

from ..jit import njit


@njit(cache=True)
def forward_kinematics(q, order, parent, crease, axis, flat, R, T, out):
    """Fold the net: out[f] = R[f] @ flat[f, k] + T[f] for every face (allocation-free).

    q (E,) fold angles (rho); order (F,) parents first; parent/crease (F,) (-1 at roots);
    axis (F, 2) corners of the parent at the crease ends, a -> b in the parent's CCW order;
    flat (F, 3, 3) flat corners (z = 0). R (F, 3, 3), T (F, 3), out (F, 3, 3) are overwritten.
    """
    fold_faces(q, order, parent, crease, axis, flat, R, T, out, None)
    return out


@njit(cache=True, inline="always")
def fold_faces(q, order, parent, crease, axis, flat, R, T, out, last):
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
