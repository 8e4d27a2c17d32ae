"""numba kernels of the mesh package: face normals and the per-edge vectors of fold angles
(`geometry.py`), the compiled fold-angle conversions other stages' kernels call, and texture
sampling (`appearance.py`). Imported where they are used: loading and checking a mesh compiles
nothing (`polyfold info` starts without numba).

The floating-point results must stay bitwise equal to the numpy formulas they replace, so the
kernels only do what rounds the same way in both (differences, products, sums in numpy's order,
sqrt); dot products (einsum) and atan2 stay in numpy, whose SIMD loops round differently.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from . import geometry

# geometry's conversions, compiled for kernels (one formula: the sign flips in geometry.py only)
rho_to_fold_deg = njit(cache=True)(geometry.rho_to_fold_deg)
fold_deg_to_rho = njit(cache=True)(geometry.fold_deg_to_rho)


@njit(cache=True, inline="always")
def _cross_into(ax, ay, az, bx, by, bz, out, i):
    # the component formulas of np.cross (a1 b2 - a2 b1, ...), so the rounding is the same
    out[i, 0] = ay * bz - az * by
    out[i, 1] = az * bx - ax * bz
    out[i, 2] = ax * by - ay * bx


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


@njit(cache=True)
def texel(image, x, y):
    """The bilinear colour (3 floats, 0..255) of `image` (h, w, 3) uint8 at texel coordinates
    (x, y), the image repeating outside."""
    h, w = image.shape[0], image.shape[1]
    fx, fy = np.floor(x), np.floor(y)
    ax, ay = x - fx, y - fy
    x0, y0 = int(fx) % w, int(fy) % h
    x1, y1 = (x0 + 1) % w, (y0 + 1) % h
    r = np.empty(3)
    for c in range(3):
        top = image[y0, x0, c] * (1.0 - ax) + image[y0, x1, c] * ax
        bottom = image[y1, x0, c] * (1.0 - ax) + image[y1, x1, c] * ax
        r[c] = top * (1.0 - ay) + bottom * ay
    return r


@njit(cache=True)
def sample_many(image, xy, out):
    """out (N, 3) uint8: the `texel` colours of `image` at texel coordinates xy (N, 2) (rounded),
    white where a coordinate is not finite (`appearance.sample_texture`)."""
    for i in range(xy.shape[0]):
        if not (np.isfinite(xy[i, 0]) and np.isfinite(xy[i, 1])):
            out[i, :] = 255
            continue
        c = texel(image, xy[i, 0], xy[i, 1])
        for k in range(3):
            out[i, k] = min(255, max(0, int(c[k] + 0.5)))
