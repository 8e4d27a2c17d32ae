"""numba kernels of the segmenter's concavity: the depth of points below a hull (ALGORITHMS.md 4.2;
the hull itself is mesh/hull_kernels.py's).

`depth_chain` measures the points of a chain of units (see merge_kernels) against a hull with an
early exit once the depth exceeds a limit.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit

NOISE = 1e-12  # depths below NOISE * bbox diagonal are rounding noise of the hull planes: convex


@njit(cache=True)
def copy_row(dst, i, src, j):
    """dst[i] = src[j] for rows of 3, element by element: a row assignment goes through numpy's
    setitem (a view, a broadcast) and costs ~100 ns, this a few."""
    dst[i, 0], dst[i, 1], dst[i, 2] = src[j, 0], src[j, 1], src[j, 2]


@njit(cache=True)
def depth_chain(pts, pstart, unxt, ua, ub, eq, limit):
    """max over points of min over facets of -(eq[j, :3] . x + eq[j, 3]) (>= 0) for the points of
    the ranges pts[pstart[u]:pstart[u + 1]] of the units u of the chain from ua, then of the chain
    from ub (-1: none) along unxt, in that order; stops early (a lower bound) once it exceeds
    `limit`. The loops are written out, not split into calls: see the module docstring."""
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
