"""numba kernels of the segmenter's per-mesh and per-part arrays: face components and seed
groups, face keys, areas, perimeters and inner edges, the candidate initial clusters, surface
samples, and each part's faces, vertices and concavity. One call each per segment() (per-face or
per-part numpy calls cost more than the merging).
"""

from __future__ import annotations

import math

import numpy as np

from ..arrays import copy_row
from ..graphs import union_labels
from ..jit import njit
from ..mesh.hull_kernels import HULL_FLAT_EPS, convex_hull, denoise, max_depth
from ..sorting import sort_in_place, stable_argsort


# ----------------------------------------------------------------------------------------------
# Per-mesh arrays of the merging (one call each per segment(), instead of a dozen numpy calls)


@njit(cache=True)
def face_keys(n):
    """n pseudo-random 64-bit face keys (splitmix64 of the face index). A cluster's key is the sum
    of its faces' keys (see `new_memo`); any fixed random keys do."""
    out = np.empty(n, dtype=np.uint64)
    for f in range(n):
        z = np.uint64(f + 1) * np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        out[f] = z ^ (z >> np.uint64(31))
    return out


@njit(cache=True)
def _norm3(x, y, z):
    """sqrt(x^2 + y^2 + z^2) summed left to right, as np.linalg.norm(axis=1) does for 3 columns."""
    return math.sqrt((x * x + y * y) + z * z)


@njit(cache=True)
def face_lengths(vertices, faces, edges, face_edges):
    """(area (F,), perimeter (F,) over all three edges, edge length (E,)), bitwise as the numpy
    expressions 0.5 * norm(cross(b - a, c - a)), norm(v1 - v0) and edge_len[face_edges].sum(1)."""
    n_f, n_e = faces.shape[0], edges.shape[0]
    area = np.empty(n_f)
    perim = np.empty(n_f)
    length = np.empty(n_e)
    for e in range(n_e):
        a, b = edges[e, 0], edges[e, 1]
        length[e] = _norm3(vertices[b, 0] - vertices[a, 0], vertices[b, 1] - vertices[a, 1], vertices[b, 2] - vertices[a, 2])
    for f in range(n_f):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        ux, uy, uz = vertices[b, 0] - vertices[a, 0], vertices[b, 1] - vertices[a, 1], vertices[b, 2] - vertices[a, 2]
        vx, vy, vz = vertices[c, 0] - vertices[a, 0], vertices[c, 1] - vertices[a, 1], vertices[c, 2] - vertices[a, 2]
        area[f] = 0.5 * _norm3(uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
        perim[f] = (length[face_edges[f, 0]] + length[face_edges[f, 1]]) + length[face_edges[f, 2]]
    return area, perim, length


@njit(cache=True)
def inner_edges(edge_faces, length, fold):
    """The edges with two faces: (face 0, face 1, length, length * concave fold / 90 degrees), the
    last bitwise as length * np.clip(-fold, 0, None) / (pi / 2)."""
    n = 0
    for e in range(edge_faces.shape[0]):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            n += 1
    f0 = np.empty(n, dtype=np.int64)
    f1 = np.empty(n, dtype=np.int64)
    ln = np.empty(n)
    cw = np.empty(n)
    q = 0
    for e in range(edge_faces.shape[0]):
        if edge_faces[e, 0] >= 0 and edge_faces[e, 1] >= 0:
            f0[q], f1[q], ln[q] = edge_faces[e, 0], edge_faces[e, 1], length[e]
            r = -fold[e]
            cw[q] = length[e] * (r if r > 0.0 or r != r else 0.0) / (math.pi / 2)  # clip: -0.0 -> 0.0, NaN kept
            q += 1
    return f0, f1, ln, cw


@njit(cache=True)
def face_groups(edge_faces, merged, fold, min_fold, n):
    """Three labellings of the n faces by edge-connected components (numbered by smallest face, see
    `union_labels`): seeds, joined across edges with fold >= min_fold or merged (E,) (inside one flat
    region: `mesh.geometry.merged_edges`); polygons, joined across merged edges (the flat regions,
    input polygons among them); components, joined across every edge with two faces."""
    m = edge_faces.shape[0]
    s0, s1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    p0, p1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    c0, c1 = np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64)
    ns = npoly = nc = 0
    for e in range(m):
        a, b = edge_faces[e, 0], edge_faces[e, 1]
        if a >= 0 and b >= 0:
            same = merged[e]
            c0[nc], c1[nc] = a, b
            nc += 1
            if same:
                p0[npoly], p1[npoly] = a, b
                npoly += 1
            if same or fold[e] >= min_fold:
                s0[ns], s1[ns] = a, b
                ns += 1
    return (union_labels(n, s0[:ns], s1[:ns]), union_labels(n, p0[:npoly], p1[:npoly]),
            union_labels(n, c0[:nc], c1[:nc]))


@njit(cache=True)
def unit_groups(seeds, polygon):
    """The candidate initial clusters of the merging: each seed (in label order), then the input
    polygons inside it (in label order), faces ascending within each. (seed_unit, sub_lo, sub_hi
    (per seed: its unit and the range of its polygons' units), faces (2F,), start (U + 1,))."""
    n = seeds.shape[0]
    order = stable_argsort(seeds)
    n_seeds = 0
    for t in range(n):
        if t == 0 or seeds[order[t]] != seeds[order[t - 1]]:
            n_seeds += 1
    seed_unit = np.empty(n_seeds, dtype=np.int64)
    sub_lo = np.empty(n_seeds, dtype=np.int64)
    sub_hi = np.empty(n_seeds, dtype=np.int64)
    faces = np.empty(2 * n, dtype=np.int64)
    start = np.empty(n + n_seeds + 1, dtype=np.int64)
    n_units, w, t, s = 0, 0, 0, 0
    while t < n:
        e = t
        while e < n and seeds[order[e]] == seeds[order[t]]:
            e += 1
        seed_unit[s] = n_units
        start[n_units] = w
        n_units += 1
        for q in range(t, e):
            faces[w] = order[q]
            w += 1
        block = order[t:e]
        sub = block[stable_argsort(polygon[block])]
        sub_lo[s] = n_units
        for q in range(e - t):
            if q == 0 or polygon[sub[q]] != polygon[sub[q - 1]]:
                start[n_units] = w
                n_units += 1
            faces[w] = sub[q]
            w += 1
        sub_hi[s] = n_units
        s += 1
        t = e
    start[n_units] = w
    return seed_unit, sub_lo, sub_hi, faces, start[:n_units + 1].copy()


@njit(cache=True)
def sample_points(vertices, faces, r):
    """The points of the random pairs r (F, k, 2) on the faces: a + r0 (b - a) + r1 (c - a), with
    pairs beyond the diagonal (r0 + r1 > 1) reflected to 1 - r; bitwise as segment's numpy form."""
    n, k = r.shape[0], r.shape[1]
    out = np.empty((n, k, 3))
    for f in range(n):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        for s in range(k):
            r0, r1 = r[f, s, 0], r[f, s, 1]
            if r0 + r1 > 1:
                r0, r1 = 1 - r0, 1 - r1
            for x in range(3):
                out[f, s, x] = vertices[a, x] + r0 * (vertices[b, x] - vertices[a, x]) + r1 * (vertices[c, x] - vertices[a, x])
    return out


@njit(cache=True)
def first_face_order(label):
    """The labels renumbered 0, 1, ... in order of each part's smallest face: (labels, count)."""
    new = np.full(label.max() + 1, -1, dtype=np.int64)
    out = np.empty(label.shape[0], dtype=np.int64)
    n = 0
    for f in range(label.shape[0]):
        if new[label[f]] < 0:
            new[label[f]] = n
            n += 1
        out[f] = new[label[f]]
    return out, n


@njit(cache=True)
def part_tables(label, n_parts, mesh_faces, n_vertices):
    """Faces and vertices of each part p of the labels (0..n_parts-1): (faces (F,): each part's
    faces, ascending, fstart (P + 1,); verts: each part's vertex ids, ascending, vstart (P + 1,);
    local (F, 3): the corners of `faces` as indices into their part's vertices)."""
    n_f = label.shape[0]
    fstart = np.zeros(n_parts + 1, dtype=np.int64)
    for f in range(n_f):
        fstart[label[f] + 1] += 1
    for p in range(n_parts):
        fstart[p + 1] += fstart[p]
    faces = np.empty(n_f, dtype=np.int64)
    fill = fstart[:-1].copy()
    for f in range(n_f):
        faces[fill[label[f]]] = f
        fill[label[f]] += 1
    pos = np.full(n_vertices, -1, dtype=np.int64)  # a vertex's index in the current part
    verts = np.empty(3 * n_f, dtype=np.int64)
    vstart = np.zeros(n_parts + 1, dtype=np.int64)
    local = np.empty((n_f, 3), dtype=np.int64)
    for p in range(n_parts):
        lo = vstart[p]
        n = lo
        for t in range(fstart[p], fstart[p + 1]):
            for k in range(3):
                v = mesh_faces[faces[t], k]
                if pos[v] != p:
                    pos[v] = p
                    verts[n] = v
                    n += 1
        sort_in_place(verts[lo:n])
        vstart[p + 1] = n
        for q in range(lo, n):
            pos[verts[q]] = q - lo
        for t in range(fstart[p], fstart[p + 1]):
            for k in range(3):
                local[t, k] = pos[mesh_faces[faces[t], k]]
        for q in range(lo, n):
            pos[verts[q]] = -1
    return faces, fstart, verts[:vstart[n_parts]].copy(), vstart, local


@njit(cache=True)
def part_concavities(faces, fstart, verts, vstart, vertices, samples, diag, max_verts):
    """segment.part_concavity of each part of `part_tables` (relative to diag): the depth of the
    part's vertices and samples below the hull of its vertices; NaN for parts of more than
    max_verts vertices (whose hull segment.py takes from qhull)."""
    n_parts = fstart.shape[0] - 1
    out = np.zeros(n_parts)
    for p in range(n_parts):
        nv = vstart[p + 1] - vstart[p]
        nf = fstart[p + 1] - fstart[p]
        if nv > max_verts:
            out[p] = np.nan
        elif nv >= 4:
            k = samples.shape[1]
            pts = np.empty((nv + k * nf, 3))
            for q in range(nv):
                copy_row(pts, q, vertices, verts[vstart[p] + q])
            for t in range(nf):
                for s in range(k):
                    for x in range(3):
                        pts[nv + k * t + s, x] = samples[faces[fstart[p] + t], s, x]
            hv, eq = convex_hull(pts[:nv].copy(), HULL_FLAT_EPS)
            if eq.shape[0] > 0 and diag > 0:
                out[p] = denoise(max_depth(pts, eq, np.inf), diag) / diag
    return out
