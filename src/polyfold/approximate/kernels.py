"""numba kernels of the hull clipping: the volume of a closed convex surface beyond a plane, the
inner loop of the 1-D search for a clipping plane's offset (tens of evaluations per candidate
normal, each over all triangles of two hulls)."""

from __future__ import annotations

import numpy as np

from ..jit import njit


@njit(cache=True)
def _cone(p0, a, b, c):
    """Signed volume of the tetrahedron (p0, a, b, c) (positive when a, b, c run CCW seen from
    the side away from p0)."""
    ax, ay, az = a[0] - p0[0], a[1] - p0[1], a[2] - p0[2]
    bx, by, bz = b[0] - p0[0], b[1] - p0[1], b[2] - p0[2]
    cx, cy, cz = c[0] - p0[0], c[1] - p0[1], c[2] - p0[2]
    return (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / 6.0


@njit(cache=True)
def volume_beyond(tri, normal, offset):
    """Volume of the part {x : normal . x >= offset} of the solid bounded by the closed, outward
    (CCW) triangles tri (T, 3, 3); normal unit (3,).

    Each triangle is clipped to the kept side (Sutherland-Hodgman, at most a quad) and coned to a
    point p0 on the plane: the cap that closes the cut lies in the plane, so its cone is flat and
    adds nothing, and the sum is the cut solid's volume without building the cap."""
    p0 = normal * offset
    poly = np.empty((4, 3))
    total = 0.0
    for t in range(tri.shape[0]):
        d = np.empty(3)
        for k in range(3):
            d[k] = tri[t, k, 0] * normal[0] + tri[t, k, 1] * normal[1] + tri[t, k, 2] * normal[2] - offset
        if d[0] >= 0.0 and d[1] >= 0.0 and d[2] >= 0.0:
            total += _cone(p0, tri[t, 0], tri[t, 1], tri[t, 2])
            continue
        if d[0] < 0.0 and d[1] < 0.0 and d[2] < 0.0:
            continue
        m = 0
        for k in range(3):
            k1 = (k + 1) % 3
            if d[k] >= 0.0:
                poly[m] = tri[t, k]
                m += 1
            if (d[k] >= 0.0) != (d[k1] >= 0.0):
                w = d[k] / (d[k] - d[k1])
                poly[m] = tri[t, k] + w * (tri[t, k1] - tri[t, k])
                m += 1
        for k in range(1, m - 1):
            total += _cone(p0, poly[0], poly[k], poly[k + 1])
    return total


@njit(cache=True)
def volumes_beyond(tri, normal, offsets):
    """`volume_beyond` at every offset (n,) (one call for a grid of offsets)."""
    out = np.empty(offsets.shape[0])
    for k in range(offsets.shape[0]):
        out[k] = volume_beyond(tri, normal, offsets[k])
    return out
