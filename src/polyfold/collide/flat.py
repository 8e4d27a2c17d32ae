"""Exact 2D overlap test for the triangles of a net (numba, sort-and-sweep broad phase).

Two triangles overlap when their interiors intersect: every one of the six separating-axis
candidates (the edge normals of both triangles) shows a penetration depth larger than `tol`.
Touching along an edge or at a vertex gives depth ~0 on some axis and is therefore not an overlap;
`tol` only absorbs floating-point noise (callers pass ~1e-9 of the model size).
"""

from __future__ import annotations

import numpy as np

from ..arrays import copy_flat
from ..jit import njit


@njit(cache=True, inline="always")
def _separated_on_axes_of(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """True if some edge normal of triangle `a` (3, 2) separates it from `b` by more than -tol."""
    for k in range(3):
        p = a[k]
        q = a[(k + 1) % 3]
        nx = q[1] - p[1]
        ny = p[0] - q[0]
        norm = np.sqrt(nx * nx + ny * ny)
        if norm == 0.0:
            return True  # degenerate triangle: no interior, cannot overlap
        amin = np.inf
        amax = -np.inf
        bmin = np.inf
        bmax = -np.inf
        for m in range(3):
            s = nx * a[m, 0] + ny * a[m, 1]
            t = nx * b[m, 0] + ny * b[m, 1]
            amin = min(amin, s)
            amax = max(amax, s)
            bmin = min(bmin, t)
            bmax = max(bmax, t)
        depth = min(amax - bmin, bmax - amin) / norm
        if depth <= tol:
            return True
    return False


@njit(cache=True, inline="always")
def _is_sliver(t: np.ndarray, tol: float) -> bool:
    ux = t[1, 0] - t[0, 0]
    uy = t[1, 1] - t[0, 1]
    vx = t[2, 0] - t[0, 0]
    vy = t[2, 1] - t[0, 1]
    wx = t[2, 0] - t[1, 0]
    wy = t[2, 1] - t[1, 1]
    longest = np.sqrt(max(ux * ux + uy * uy, vx * vx + vy * vy, wx * wx + wy * wy))
    return abs(ux * vy - uy * vx) <= tol * longest  # height over the longest side <= tol


@njit(cache=True)
def triangles_overlap(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Exact interior-overlap test of two 2D triangles (3, 2) with noise tolerance `tol`."""
    if _is_sliver(a, tol) or _is_sliver(b, tol):
        return False  # no interior (all corners within tol of one line)
    if _separated_on_axes_of(a, b, tol):
        return False
    if _separated_on_axes_of(b, a, tol):
        return False
    return True


@njit(cache=True)
def overlapping_pairs(tris: np.ndarray, parent: np.ndarray, tol: float, max_pairs: int) -> tuple:
    """All overlapping pairs among `tris` (F, 3, 2), skipping crease pairs (f, parent[f]).

    Sort-and-sweep on x, then y-interval rejection, then the exact test. Returns (count, pairs)
    where pairs (min(count, max_pairs), 2) lists the first pairs found (max_pairs=0: count only;
    max_pairs < 0: every pair, in a buffer that doubles as it fills).
    """
    n = tris.shape[0]
    xmin = np.empty(n)
    xmax = np.empty(n)
    ymin = np.empty(n)
    ymax = np.empty(n)
    for i in range(n):
        xmin[i] = min(tris[i, 0, 0], tris[i, 1, 0], tris[i, 2, 0])
        xmax[i] = max(tris[i, 0, 0], tris[i, 1, 0], tris[i, 2, 0])
        ymin[i] = min(tris[i, 0, 1], tris[i, 1, 1], tris[i, 2, 1])
        ymax[i] = max(tris[i, 0, 1], tris[i, 1, 1], tris[i, 2, 1])
    order = np.argsort(xmin)
    every = max_pairs < 0
    pairs = np.empty((64 if every else max(max_pairs, 1), 2), dtype=np.int64)
    count = 0
    for ii in range(n):
        i = order[ii]
        for jj in range(ii + 1, n):
            j = order[jj]
            if xmin[j] >= xmax[i] - tol:
                break
            if ymin[j] >= ymax[i] - tol or ymin[i] >= ymax[j] - tol:
                continue
            if parent[i] == j or parent[j] == i:
                continue
            if triangles_overlap(tris[i], tris[j], tol):
                if every and count == pairs.shape[0]:
                    grown = np.empty((2 * count, 2), dtype=np.int64)
                    copy_flat(grown, pairs, 2 * count)
                    pairs = grown
                if every or count < max_pairs:
                    pairs[count, 0] = min(i, j)
                    pairs[count, 1] = max(i, j)
                count += 1
    return count, pairs[: count if every else min(count, max_pairs)]


@njit(cache=True)
def all_overlapping_pairs(tris: np.ndarray, parent: np.ndarray, tol: float) -> np.ndarray:
    """Every overlapping pair (k, 2) of `overlapping_pairs`, in one sweep (a second sweep that
    only counted first cost the local search of 5,000 faces a third of each call's start)."""
    return overlapping_pairs(tris, parent, tol, np.int64(-1))[1]  # (a literal -1 would compile it twice)


def find_overlaps(tris: np.ndarray, parent: np.ndarray | None = None, tol: float = 0.0) -> np.ndarray:
    """All overlapping face pairs (k, 2) of a 2D net `tris` (F, 3, 2); crease pairs skipped."""
    tris = np.ascontiguousarray(tris, dtype=np.float64)
    if parent is None:
        parent = np.full(len(tris), -1, dtype=np.int64)
    return all_overlapping_pairs(tris, np.asarray(parent, np.int64), float(tol))


@njit(cache=True)
def face_bounds(tris: np.ndarray, faces: np.ndarray, xmin: np.ndarray, xmax: np.ndarray, ymin: np.ndarray,
                ymax: np.ndarray) -> None:
    """Write the axis-aligned bounds of tris[f] (F, 3, 2) to xmin[f], ... for each f in `faces`."""
    for f in faces:
        xmin[f] = min(tris[f, 0, 0], tris[f, 1, 0], tris[f, 2, 0])
        xmax[f] = max(tris[f, 0, 0], tris[f, 1, 0], tris[f, 2, 0])
        ymin[f] = min(tris[f, 0, 1], tris[f, 1, 1], tris[f, 2, 1])
        ymax[f] = max(tris[f, 0, 1], tris[f, 1, 1], tris[f, 2, 1])


@njit(cache=True)
def overlapping_pairs_between(tris: np.ndarray, parent: np.ndarray, a: np.ndarray, b: np.ndarray, xmin: np.ndarray,
                              xmax: np.ndarray, ymin: np.ndarray, ymax: np.ndarray, tol: float,
                              limit: int) -> np.ndarray:
    """The overlapping pairs (k, 2) (smaller index first) of one face of `a` and one of `b`, or
    the first `limit` found (k == limit: there may be more; a caller that only needs to know
    whether there are that many stops paying for the rest).

    a, b: disjoint face indices; xmin..ymax (F,): the faces' bounds (`face_bounds`); crease pairs
    (f, parent[f]) skipped. The same test as `overlapping_pairs` restricted to pairs across the two
    sets: the smaller set is binned in a uniform grid over its bounds, and each face of the other
    set looks only in the cells its bounds cover, so the cost is one pass over the larger set plus
    the pairs that are near each other.
    """
    if a.shape[0] > b.shape[0]:
        a, b = b, a
    out = np.empty((16, 2), dtype=np.int64)
    count = 0
    if a.shape[0] == 0:
        return out[:0]
    x0 = np.inf
    x1 = -np.inf
    y0 = np.inf
    y1 = -np.inf
    size = 0.0
    for f in a:
        x0 = min(x0, xmin[f])
        x1 = max(x1, xmax[f])
        y0 = min(y0, ymin[f])
        y1 = max(y1, ymax[f])
        size += max(xmax[f] - xmin[f], ymax[f] - ymin[f])
    # cells about one face across, at most ~4 per face of `a`
    cell = max(size / a.shape[0], np.sqrt((x1 - x0) * (y1 - y0) / (4.0 * a.shape[0])), 1e-300)
    nx = int((x1 - x0) / cell) + 1
    ny = int((y1 - y0) / cell) + 1
    start = np.zeros(nx * ny + 1, dtype=np.int64)
    for f in a:
        for i in range(int((xmin[f] - x0) / cell), int((xmax[f] - x0) / cell) + 1):
            for j in range(int((ymin[f] - y0) / cell), int((ymax[f] - y0) / cell) + 1):
                start[i * ny + j + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    binned = np.empty(start[-1], dtype=np.int64)
    for f in a:
        for i in range(int((xmin[f] - x0) / cell), int((xmax[f] - x0) / cell) + 1):
            for j in range(int((ymin[f] - y0) / cell), int((ymax[f] - y0) / cell) + 1):
                binned[fill[i * ny + j]] = f
                fill[i * ny + j] += 1
    for g in b:
        if xmin[g] >= x1 - tol or xmax[g] <= x0 + tol or ymin[g] >= y1 - tol or ymax[g] <= y0 + tol:
            continue
        i0 = max(int((xmin[g] - x0) / cell), 0)
        i1 = min(int((xmax[g] - x0) / cell), nx - 1)
        j0 = max(int((ymin[g] - y0) / cell), 0)
        j1 = min(int((ymax[g] - y0) / cell), ny - 1)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for q in range(start[i * ny + j], start[i * ny + j + 1]):
                    f = binned[q]
                    if xmin[f] >= xmax[g] - tol or xmin[g] >= xmax[f] - tol:
                        continue
                    if ymin[f] >= ymax[g] - tol or ymin[g] >= ymax[f] - tol:
                        continue
                    # each pair once: in the cell holding the lower-left corner of the bounds' overlap
                    if (min(max(int((max(xmin[f], xmin[g]) - x0) / cell), 0), nx - 1) != i
                            or min(max(int((max(ymin[f], ymin[g]) - y0) / cell), 0), ny - 1) != j):
                        continue
                    if parent[f] == g or parent[g] == f:
                        continue
                    if triangles_overlap(tris[f], tris[g], tol):
                        if count == out.shape[0]:
                            grown = np.empty((2 * count, 2), dtype=np.int64)
                            for q2 in range(count):  # (not grown[:count] = out: see local_search)
                                grown[q2, 0], grown[q2, 1] = out[q2, 0], out[q2, 1]
                            out = grown
                        out[count, 0] = min(f, g)
                        out[count, 1] = max(f, g)
                        count += 1
                        if count >= limit:
                            return out[:count]
    return out[:count]
