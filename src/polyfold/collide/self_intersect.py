"""Self-intersection of a triangle mesh: which faces sharing no edge cross each other?

The one plain sort-and-sweep (`sweep.sweep_pairs`) finds them, the pair test is
`triangles.triangles_collide` (touching is not crossing: faces meeting at a shared vertex count
only if they really cross). Faces sharing an edge are never tested (their fold angle tells
whether they pass through each other). Used by inflation (its guard) and for reports.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..jit import njit
from ..mesh.mesh import Mesh
from .sweep import NO_LIMIT, sweep_pairs
from .tolerance import CONTACT_TOL


@njit(cache=True)
def face_triangles(vertices, faces):
    """tris (m, 3, 3): the corners of each face (vertices[faces], without numpy's slower gather)."""
    m = faces.shape[0]
    tris = np.empty((m, 3, 3))
    for f in range(m):
        for k in range(3):
            for i in range(3):
                tris[f, k, i] = vertices[faces[f, k], i]
    return tris


def crossing_pairs(vertices: np.ndarray, faces: np.ndarray, tol: float, max_pairs: int,
                   skip_keys: Optional[np.ndarray] = None) -> tuple[int, np.ndarray]:
    """(count, pairs) of the surface vertices (n, 3), faces (m, 3) int64: count = the number of
    face pairs sharing no edge that cross, pairs (min(count, max_pairs), 2) = the first of them
    (i < j, in sweep order). tol: absolute contact tolerance. skip_keys: sorted int64 keys
    i * m + j (i < j) of pairs not to test (None or empty: none)."""
    pairs = np.empty((max_pairs, 2), dtype=np.int64)
    keys = skip_keys if skip_keys is not None and len(skip_keys) else None
    count = _crossings(vertices, faces, float(tol), keys, pairs)
    return int(count), pairs[: min(count, max_pairs)]


@njit(cache=True)
def _crossings(vertices, faces, tol, keys, pairs):
    """`crossing_pairs` in one numba call (the guard of inflation runs it every few steps)."""
    return sweep_pairs(face_triangles(vertices, faces), tol, None, None, faces, keys, NO_LIMIT, pairs)


def self_intersections(mesh: Mesh, tol: float = CONTACT_TOL) -> np.ndarray:
    """Pairs (k, 2), i < j, of faces that cross each other (faces sharing an edge are not tested;
    faces touching at a shared vertex or resting on each other do not count). tol: fraction of the
    bounding-box diagonal."""
    X, F = mesh.vertices, mesh.faces
    if len(F) == 0:
        return np.empty((0, 2), dtype=np.int64)
    diag = float(np.linalg.norm(X.max(0) - X.min(0))) if len(X) else 0.0
    count, _ = crossing_pairs(X, F, tol * diag, 0)
    if count == 0:
        return np.empty((0, 2), dtype=np.int64)
    return crossing_pairs(X, F, tol * diag, count)[1]
