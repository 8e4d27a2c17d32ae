"""Closest points on triangle meshes: the one point-triangle primitive (Ericson's) and the two
ways it is used: among given candidate triangles per point (`closest_points`, baking a texture),
and the exact distance from points to a whole surface (`surface_distances`, Hausdorff distances).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..jit import njit

# Candidate triangles of `surface_distances`' last pass held at once: scipy's ball query gives them as
# Python lists (about 36 bytes each: 36 MB), so chunks keep the peak small.
BALL_CANDIDATES = 1_000_000


@njit(cache=True)
def _closest_on_triangle(px, py, pz, t):
    """Barycentric coordinates (u, v, w) of the point of triangle t (3, 3) closest to p (Ericson,
    Real-Time Collision Detection 5.1.5); scalars only (this runs for every texel)."""
    ax, ay, az = t[0, 0], t[0, 1], t[0, 2]
    abx, aby, abz = t[1, 0] - ax, t[1, 1] - ay, t[1, 2] - az
    acx, acy, acz = t[2, 0] - ax, t[2, 1] - ay, t[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    bpx, bpy, bpz = px - t[1, 0], py - t[1, 1], pz - t[1, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3) if d1 != d3 else 0.0  # (equal only on a degenerate triangle)
        return 1.0 - v, v, 0.0
    cpx, cpy, cpz = px - t[2, 0], py - t[2, 1], pz - t[2, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6) if d2 != d6 else 0.0
        return 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6)) if (d4 - d3) + (d5 - d6) > 0.0 else 0.0
        return 0.0, 1.0 - w, w
    den = va + vb + vc
    if den == 0.0:
        return 1.0, 0.0, 0.0
    v, w = vb / den, vc / den
    return 1.0 - v - w, v, w


@njit(cache=True)
def closest_points(points, normals, candidates, tri, tri_normals, penalty, face, bary):
    """For every point (N, 3) the old face (of `candidates` (N, k) into tri (M, 3, 3)) holding its
    closest point and that point's barycentric coordinates, into face (N,) and bary (N, 3).
    Candidates whose normal (tri_normals) points against the point's `normals` (N, 3) get
    `penalty` added to their distance."""
    for i in range(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        best = np.inf
        for j in range(candidates.shape[1]):
            f = candidates[i, j]
            u, v, w = _closest_on_triangle(px, py, pz, tri[f])
            dx = u * tri[f, 0, 0] + v * tri[f, 1, 0] + w * tri[f, 2, 0] - px
            dy = u * tri[f, 0, 1] + v * tri[f, 1, 1] + w * tri[f, 2, 1] - py
            dz = u * tri[f, 0, 2] + v * tri[f, 1, 2] + w * tri[f, 2, 2] - pz
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if tri_normals[f, 0] * normals[i, 0] + tri_normals[f, 1] * normals[i, 1] + tri_normals[f, 2] * normals[i, 2] < 0.0:
                d += penalty
            if d < best:
                best = d
                face[i] = f
                bary[i, 0], bary[i, 1], bary[i, 2] = u, v, w


@njit(cache=True)
def _distances_pruned(points, tri, centre, radius, ptr, candidates, best):
    """Lower best (N,) to the exact distance from each point i to the triangles of tri (M, 3, 3)
    listed in candidates[ptr[i]:ptr[i + 1]] (every triangle when ptr is empty), skipping a
    triangle whose bounding sphere (centre, radius) is farther than best already."""
    every = ptr.shape[0] == 0
    for i in range(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        b = best[i]
        for q in range(0 if every else ptr[i], tri.shape[0] if every else ptr[i + 1]):
            f = q if every else candidates[q]
            cx, cy, cz = centre[f, 0] - px, centre[f, 1] - py, centre[f, 2] - pz
            if math.sqrt(cx * cx + cy * cy + cz * cz) - radius[f] >= b:
                continue
            u, v, w = _closest_on_triangle(px, py, pz, tri[f])
            dx = u * tri[f, 0, 0] + v * tri[f, 1, 0] + w * tri[f, 2, 0] - px
            dy = u * tri[f, 0, 1] + v * tri[f, 1, 1] + w * tri[f, 2, 1] - py
            dz = u * tri[f, 0, 2] + v * tri[f, 1, 2] + w * tri[f, 2, 2] - pz
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if d < b:
                b = d
        best[i] = b


def surface_distances(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, nearest: int = 8) -> np.ndarray:
    """(N,) the exact distance from every point (N, 3) to the surface (vertices, faces): first
    the `nearest` triangles by centroid (scipy's KD-tree); a point for which a farther triangle
    could still be closer (its centroid within that distance plus the largest bounding radius)
    is measured again against every triangle whose centroid is near enough for it to be closer
    (a ball query in the same tree), pruned by bounding spheres."""
    from scipy.spatial import cKDTree

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    tri = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64)[np.asarray(faces)])
    centre = tri.mean(axis=1)
    radius = np.linalg.norm(tri - centre[:, None], axis=2).max(axis=1)
    tree = cKDTree(centre)
    k = min(nearest, len(tri))
    reach, near = tree.query(points, k=k, workers=-1)
    near = np.ascontiguousarray(near.reshape(len(points), k), dtype=np.int64)
    face = np.zeros(len(points), dtype=np.int64)
    bary = np.zeros((len(points), 3))
    closest_points(points, np.zeros((len(points), 3)), near, tri, np.zeros((len(tri), 3)), 0.0, face, bary)
    best = np.linalg.norm(np.einsum("nk,nkc->nc", bary, tri[face]) - points, axis=1)
    if k == len(tri):
        return best
    todo = np.flatnonzero(reach.reshape(len(points), k)[:, -1] - radius.max() < best)
    if not len(todo):
        return best
    # The still unsure: the triangles whose centroid lies within best + the largest bounding
    # radius, found in the KD-tree (a triangle closer than best has its centroid there), not every
    # triangle (every one for 20,000 points on an 82k-face mesh took 5.5 s); in chunks of at most
    # BALL_CANDIDATES, a point whose ball holds a quarter of the mesh against every triangle.
    reach = best[todo] + radius.max()
    counts = np.asarray(tree.query_ball_point(points[todo], reach, return_length=True, workers=-1), dtype=np.int64)
    wide = counts > len(tri) // 4
    if wide.any():
        sub = best[todo[wide]].copy()
        _distances_pruned(points[todo[wide]], tri, centre, radius, np.zeros(0, np.int64), np.zeros(0, np.int64), sub)
        best[todo[wide]] = sub
    todo, reach, counts = todo[~wide], reach[~wide], counts[~wide]
    ends = np.cumsum(counts)
    start = 0
    while start < len(todo):
        stop = max(start + 1, int(np.searchsorted(ends, ends[start] - counts[start] + BALL_CANDIDATES, side="right")))
        balls = tree.query_ball_point(points[todo[start:stop]], reach[start:stop], workers=-1)
        ptr = np.zeros(stop - start + 1, dtype=np.int64)
        np.cumsum(counts[start:stop], out=ptr[1:])
        candidates = np.fromiter(itertools.chain.from_iterable(balls), dtype=np.int64, count=int(ptr[-1]))
        sub = best[todo[start:stop]].copy()
        _distances_pruned(points[todo[start:stop]], tri, centre, radius, ptr, candidates, sub)
        best[todo[start:stop]] = sub
        start = stop
    return best
