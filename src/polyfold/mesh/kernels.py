"""numba kernels behind `mesh.py`: the edge table and the per-corner / per-edge vectors of the
geometric quantities.

The floating-point results must stay bitwise equal to the numpy formulas they replace, so the
kernels only do what rounds the same way in both (differences, products, sums in numpy's order,
sqrt); dot products (einsum) and atan2 stay in numpy, whose SIMD loops round differently.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def edge_table(faces):
    """Edges of a triangle mesh, as `mesh.edge_topology` documents them.

    faces (m, 3) int64 -> (edges (E, 2), edge_faces (E, 2), face_edges (m, 3), face_count (E,)).
    Edges are numbered in lexicographic order of their sorted vertex pair (as np.unique of the
    rows); slot 0 of an edge takes the first face (in face order) that runs it low -> high, slot 1
    the first that runs it high -> low; a second face running the same way takes a free slot and
    further faces are only counted (non-manifold input). Boundary edges keep their face in slot 0
    and are flipped so that face runs edges[e, 0] -> edges[e, 1].
    """
    m = faces.shape[0]
    n_d = 3 * m
    lo = np.empty(n_d, dtype=np.int64)
    hi = np.empty(n_d, dtype=np.int64)
    forward = np.empty(n_d, dtype=np.bool_)
    for f in range(m):
        for k in range(3):
            a = faces[f, k]
            b = faces[f, (k + 1) % 3]
            i = 3 * f + k
            forward[i] = a <= b
            lo[i] = min(a, b)
            hi[i] = max(a, b)
    # lexicographic (lo, hi) order, stable: hi first, then lo (both merge sorts)
    by_hi = np.argsort(hi, kind="mergesort")
    by_lo = np.argsort(lo[by_hi], kind="mergesort")
    order = by_hi[by_lo]
    inverse = np.empty(n_d, dtype=np.int64)
    n_e = 0
    for r in range(n_d):
        i = order[r]
        if r > 0:
            j = order[r - 1]
            if lo[i] != lo[j] or hi[i] != hi[j]:
                n_e += 1
        inverse[i] = n_e
    if n_d > 0:
        n_e += 1
    edges = np.empty((n_e, 2), dtype=np.int64)
    counts = np.zeros(n_e, dtype=np.int64)
    edge_faces = np.full((n_e, 2), -1, dtype=np.int64)
    start = 0
    while start < n_d:
        e = inverse[order[start]]
        stop = start
        while stop < n_d and inverse[order[stop]] == e:
            stop += 1
        edges[e, 0] = lo[order[start]]
        edges[e, 1] = hi[order[start]]
        counts[e] = stop - start
        # faces running the edge low -> high first, each group in face order
        for want in (True, False):
            for r in range(start, stop):
                i = order[r]
                if forward[i] != want:
                    continue
                slot = 0 if want else 1
                if edge_faces[e, slot] >= 0:
                    slot = 1 - slot
                    if edge_faces[e, slot] >= 0:
                        continue
                edge_faces[e, slot] = i // 3
        start = stop
    for e in range(n_e):
        if edge_faces[e, 0] < 0 and edge_faces[e, 1] >= 0:
            edge_faces[e, 0] = edge_faces[e, 1]
            edge_faces[e, 1] = -1
            a = edges[e, 0]
            edges[e, 0] = edges[e, 1]
            edges[e, 1] = a
    return edges, edge_faces, inverse.reshape(m, 3), counts


@njit(cache=True, inline="always")
def _cross_into(ax, ay, az, bx, by, bz, out, i):
    # the component formulas of np.cross (a1 b2 - a2 b1, ...), so the rounding is the same
    out[i, 0] = ay * bz - az * by
    out[i, 1] = az * bx - ax * bz
    out[i, 2] = ax * by - ay * bx


@njit(cache=True)
def corner_vectors(vertices, faces):
    """Side vectors at every corner: a[k, f] = v[f, k+1] - v[f, k], b[k, f] = v[f, k+2] - v[f, k]
    (k mod 3), both (3, m, 3), and y (3, m) = |a x b| (as np.linalg.norm(np.cross(a, b), axis=1))."""
    m = faces.shape[0]
    a = np.empty((3, m, 3))
    b = np.empty((3, m, 3))
    y = np.empty((3, m))
    c = np.empty((1, 3))
    for k in range(3):
        for f in range(m):
            p = faces[f, k]
            q = faces[f, (k + 1) % 3]
            r = faces[f, (k + 2) % 3]
            for i in range(3):
                a[k, f, i] = vertices[q, i] - vertices[p, i]
                b[k, f, i] = vertices[r, i] - vertices[p, i]
            _cross_into(a[k, f, 0], a[k, f, 1], a[k, f, 2], b[k, f, 0], b[k, f, 1], b[k, f, 2], c, 0)
            y[k, f] = np.sqrt(c[0, 0] * c[0, 0] + c[0, 1] * c[0, 1] + c[0, 2] * c[0, 2])
    return a, b, y


@njit(cache=True)
def scatter_sums(n, index, values):
    """out (n,): out[index[i]] += values[i] in order of i (the sums of np.add.at; np.bincount's
    differ in the last bits)."""
    out = np.zeros(n)
    for i in range(index.shape[0]):
        out[index[i]] += values[i]
    return out


@njit(cache=True)
def face_normals(vertices, faces):
    """Unit normals (m, 3) of CCW faces, zero rows for degenerate faces (as mesh.face_normals)."""
    m = faces.shape[0]
    n = np.empty((m, 3))
    for f in range(m):
        p = faces[f, 0]
        q = faces[f, 1]
        r = faces[f, 2]
        _cross_into(vertices[q, 0] - vertices[p, 0], vertices[q, 1] - vertices[p, 1], vertices[q, 2] - vertices[p, 2],
                    vertices[r, 0] - vertices[p, 0], vertices[r, 1] - vertices[p, 1], vertices[r, 2] - vertices[p, 2],
                    n, f)
        norm = np.sqrt(n[f, 0] * n[f, 0] + n[f, 1] * n[f, 1] + n[f, 2] * n[f, 2])
        for i in range(3):
            n[f, i] = n[f, i] / norm if norm > 0 else 0.0
    return n


@njit(cache=True, error_model="numpy")  # a zero-length edge divides by 0 as numpy does (nan)
def fold_angle_vectors(vertices, faces, edges, edge_faces):
    """Interior edges inner (I,) ascending and, per interior edge, n0 x n1 and the unit edge
    direction u (as run by face 0), and the unit normals n0, n1 of its faces (`face_normals`);
    all (I, 3). rho = atan2((n0 x n1) . u, n0 . n1)."""
    normals = face_normals(vertices, faces)
    n_i = 0
    for e in range(edges.shape[0]):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            n_i += 1
    inner = np.empty(n_i, dtype=np.int64)
    cr = np.empty((n_i, 3))
    u = np.empty((n_i, 3))
    n0 = np.empty((n_i, 3))
    n1 = np.empty((n_i, 3))
    i = 0
    for e in range(edges.shape[0]):
        f0 = edge_faces[e, 0]
        f1 = edge_faces[e, 1]
        if f0 < 0 or f1 < 0:
            continue
        inner[i] = e
        for j in range(3):
            u[i, j] = vertices[edges[e, 1], j] - vertices[edges[e, 0], j]
            n0[i, j] = normals[f0, j]
            n1[i, j] = normals[f1, j]
        norm = np.sqrt(u[i, 0] * u[i, 0] + u[i, 1] * u[i, 1] + u[i, 2] * u[i, 2])
        for j in range(3):
            u[i, j] = u[i, j] / norm
        _cross_into(n0[i, 0], n0[i, 1], n0[i, 2], n1[i, 0], n1[i, 1], n1[i, 2], cr, i)
        i += 1
    return inner, cr, u, n0, n1
