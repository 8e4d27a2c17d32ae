"""Flat regions made whole: every flat region of a mesh (faces in one plane) re-triangulated with
as few triangles as its outline allows, the vertices inside it and on the straight stretches of
its outline dropped. Exact: the surface does not move, sharp edges stay where they are.

Why: a CAD model, an STL export or a subdivided mesh spends thousands of triangles on flat sides,
and edge collapse (`simplify`) handles them badly: every collapse inside a plane costs nothing,
so it collapses there in any order, leaving needles and cutting corners (a cube subdivided to
12,288 faces, collapsed to 48: 9 % of its size off). Made whole first, the cube is 12 triangles.

A flat region grows from a seed face across edges to faces whose normal is within FLAT_REGION_RAD
of the seed's and whose corners lie within FLAT_DIST (x the bounding-box diagonal) of its plane
(a gently curved surface never chains into one "flat" region). A vertex is dropped when all its
faces are in one region, or when it lies on a straight outline between exactly two regions (or a
region and the mesh's open boundary). Each region with more than one face becomes the
constrained Delaunay triangulation (shapely) of its outline polygon (holes included) in its plane;
a region whose outline is not a simple polygon keeps its faces and its vertices.

In: a Mesh. Out: a Mesh on the same vertices (unused ones left for the caller's repair), faces
CCW as the region's faces were.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from .geometry import FLAT_REGION_RAD
from .mesh import Mesh

FLAT_DIST = 1e-5  # x the bounding-box diagonal: a region's corners lie this close to its plane (float32 files: 1e-7)
STRAIGHT = 1e-6  # x the bounding-box diagonal: an outline vertex this close to its neighbours' line is on it (files print 6-8 digits)


@njit(cache=True)
def flat_regions(vertices, faces, normals, edge_faces, face_edges, cos_tol, dist_tol):
    """(F,) region label of every face: faces grown from a seed across edges while their normal is
    within acos(cos_tol) of the seed's and their corners within dist_tol of its plane."""
    n = faces.shape[0]
    label = np.full(n, -1, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    regions = 0
    for seed in range(n):
        if label[seed] >= 0:
            continue
        label[seed] = regions
        n0 = normals[seed]
        d0 = n0[0] * vertices[faces[seed, 0], 0] + n0[1] * vertices[faces[seed, 0], 1] + n0[2] * vertices[faces[seed, 0], 2]
        head, tail = 0, 1
        queue[0] = seed
        while head < tail:
            f = queue[head]
            head += 1
            for k in range(3):
                e = face_edges[f, k]
                g = edge_faces[e, 0] if edge_faces[e, 0] != f else edge_faces[e, 1]
                if g < 0 or label[g] >= 0:
                    continue
                if normals[g, 0] * n0[0] + normals[g, 1] * n0[1] + normals[g, 2] * n0[2] < cos_tol:
                    continue
                ok = True
                for c in range(3):
                    v = faces[g, c]
                    d = n0[0] * vertices[v, 0] + n0[1] * vertices[v, 1] + n0[2] * vertices[v, 2] - d0
                    if abs(d) > dist_tol:
                        ok = False
                if ok:
                    label[g] = regions
                    queue[tail] = g
                    tail += 1
        regions += 1
    return label


def _droppable(mesh: Mesh, label: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """(V,) bool: vertices inside one region, or on a straight outline between two (module
    docstring); never those in `keep`."""
    topo = mesh.topology
    faces, v = mesh.faces, mesh.vertices
    diag = mesh.bbox_diagonal
    pairs = np.unique(np.stack([faces.reshape(-1), np.repeat(label, 3)], axis=1), axis=0)
    n_regions = np.bincount(pairs[:, 0], minlength=len(v))
    ef = topo.edge_faces
    side = np.where(ef >= 0, label[np.maximum(ef, 0)], -1)
    outline = side[:, 0] != side[:, 1]  # region outlines and the open boundary
    ends = topo.edges[outline]
    n_out = np.bincount(ends.reshape(-1), minlength=len(v))
    open_vertex = np.zeros(len(v), dtype=bool)
    open_vertex[topo.edges[(ef < 0).any(axis=1)].reshape(-1)] = True
    inside = (n_regions == 1) & (n_out == 0)
    # straight: two outline edges, their far ends on a line through the vertex
    cand = np.flatnonzero(((n_regions == 2) | ((n_regions == 1) & open_vertex)) & (n_out == 2))
    straight = np.zeros(len(v), dtype=bool)
    if len(cand):
        order = np.argsort(ends.reshape(-1), kind="stable")
        owner = ends.reshape(-1)[order]
        other = ends[:, ::-1].reshape(-1)[order]
        first = np.searchsorted(owner, cand)
        a, b = v[other[first]], v[other[first + 1]]
        p = v[cand]
        cross = np.linalg.norm(np.cross(p - a, b - p), axis=1) / np.maximum(np.linalg.norm(b - a, axis=1), 1e-300)
        straight[cand] = (cross <= STRAIGHT * diag) & (((p - a) * (b - p)).sum(axis=1) > 0)
    return (inside | straight) & ~keep


def _loops(mesh: Mesh, faces_of: np.ndarray) -> list[list[int]] | None:
    """The closed outline loops (vertex ids, in the faces' direction) of the faces `faces_of`;
    None when a vertex has more than one outgoing outline edge (the outline touches itself)."""
    sub = mesh.faces[faces_of]
    half = np.stack([sub.reshape(-1), np.roll(sub, -1, axis=1).reshape(-1)], axis=1)
    key = half[:, 0] * (mesh.n_vertices + 1) + half[:, 1]
    rev = half[:, 1] * (mesh.n_vertices + 1) + half[:, 0]
    border = half[~np.isin(key, rev)]
    nxt: dict[int, int] = {}
    for a, b in border.tolist():
        if a in nxt:
            return None
        nxt[a] = b
    loops, seen = [], set()
    for start in nxt:
        if start in seen:
            continue
        loop, cur = [], start
        while cur not in seen:
            seen.add(cur)
            loop.append(cur)
            cur = nxt.get(cur, -1)
            if cur < 0:
                return None
        if cur != start:
            return None
        loops.append(loop)
    return loops


def _triangulate_region(mesh: Mesh, faces_of: np.ndarray, normal: np.ndarray,
                        drop: np.ndarray) -> np.ndarray | None:
    """The region's new faces (k, 3), or None when its outline is no simple polygon."""
    import shapely

    loops = _loops(mesh, faces_of)
    if not loops:
        return None
    loops = [[u for u in loop if not drop[u]] for loop in loops]
    if any(len(loop) < 3 for loop in loops):
        return None
    if len(loops) == 1 and len(loops[0]) == 3:  # (most regions of a subdivided mesh): the loop turns as its faces
        return np.array([loops[0]], dtype=np.int64)
    ex = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    ex /= np.linalg.norm(ex)
    ey = np.cross(normal, ex)
    flat = [np.stack([mesh.vertices[loop] @ ex, mesh.vertices[loop] @ ey], axis=1) for loop in loops]
    area = [0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])) for p in flat]
    outer = int(np.argmax(np.abs(area)))
    if area[outer] <= 0:  # the outline runs CCW seen along the normal; holes the other way
        return None
    polygon = shapely.Polygon(flat[outer], [flat[k] for k in range(len(flat)) if k != outer])
    if not polygon.is_valid or any(area[k] >= 0 for k in range(len(flat)) if k != outer):
        return None
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(polygon))
    ids = np.concatenate([np.asarray(loop) for loop in loops])
    points = np.concatenate(flat)
    n_holes = len(loops) - 1
    if len(tris) != len(points) + 2 * n_holes - 2:
        return None
    corners = shapely.get_coordinates(tris).reshape(len(tris), 4, 2)[:, :3]
    near = np.argmin(((corners[:, :, None, :] - points[None, None]) ** 2).sum(axis=3), axis=2)
    if not np.allclose(points[near], corners, rtol=0, atol=1e-9 * (np.ptp(points) + 1e-300)):
        return None
    out = ids[near]
    p = points[near]
    turn = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
    out[turn < 0] = out[turn < 0][:, ::-1]  # CCW seen along the normal, as the region's faces
    return out


def merge_flat(mesh: Mesh) -> Mesh:
    """The mesh with every flat region re-triangulated (module docstring); the same mesh when it
    has no flat region of more than one face."""
    topo = mesh.topology
    diag = mesh.bbox_diagonal
    label = flat_regions(mesh.vertices, mesh.faces, mesh.face_normals, topo.edge_faces, topo.face_edges,
                         float(np.cos(FLAT_REGION_RAD)), FLAT_DIST * diag)
    size = np.bincount(label)
    if not (size > 1).any():
        return mesh
    keep = np.zeros(mesh.n_vertices, dtype=bool)
    order = np.argsort(label, kind="stable")
    groups = np.split(order, np.cumsum(size)[:-1])
    big = [r for r in range(len(size)) if size[r] > 1]
    for _ in range(4):  # a region that cannot be redone keeps its vertices: its neighbours are redone again
        drop = _droppable(mesh, label, keep)
        made, failed = {}, []
        for r in big:
            tris = _triangulate_region(mesh, groups[r], mesh.face_normals[groups[r][0]], drop)
            if tris is None:
                failed.append(r)
            else:
                made[r] = tris
        fresh = [r for r in failed if not keep[mesh.faces[groups[r]]].all()]
        if not fresh:
            break
        for r in fresh:
            keep[mesh.faces[groups[r]].reshape(-1)] = True
    kept = np.concatenate([groups[r] for r in range(len(size)) if r not in made] or [np.zeros(0, np.int64)])
    faces = np.concatenate([mesh.faces[np.sort(kept)], *made.values()]) if made else mesh.faces
    return Mesh(mesh.vertices, faces)
