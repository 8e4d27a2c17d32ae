"""Geometric quantities of triangle meshes, on plain arrays: normals, areas, corner angles,
angle sums, signed fold angles, the merged (never cut) edges of flat regions, concavity.

Sign convention: faces are CCW seen from outside (outward normals). The signed fold angle `rho`
of an edge is the angle between the normals of its two faces, positive on convex edges (mountains
seen from outside), negative on reflex edges, 0 on flat ones. Every stage works in rho (radians);
files use FOLD's fold angle (degrees, valley positive, mountain negative): `rho_to_fold_deg` and
`fold_deg_to_rho` are the one place the sign flips.

The floating-point results are bitwise those of the numpy formulas (see `kernels.py`): every stage
must see the same bits. Loading and checking a mesh (`polyfold info`) needs no compiled kernel:
the kernels are imported where they are used.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .mesh import Mesh, Topology


HYPERBOLIC_EPS = 1e-9  # hyperbolic vertex: angle sum > 2 pi + HYPERBOLIC_EPS
FLAT_EPS = 1e-10  # |rho| below this (radians) is a flat crease ("F" in FOLD, not scored on sheets)
# |rho| below this (radians, 0.057 degrees) joins two faces into one flat region that nets never cut
# through (`merged_edges`). Above the rounding of coplanar faces in real files (up to 8e-5 on the
# shared models, whose origami-derived coordinates carry 1e-5 errors), below any fold a person
# would score and fold (a 0.06 degree fold is invisible on paper): the few smooth-surface edges
# under it (fish-472: 32 edges of 5e-4 to 9e-4) are merged too, harmlessly.
FLAT_REGION_RAD = 1e-3


def rho_to_fold_deg(rho):
    """FOLD fold angle (degrees, valley positive) of signed fold angles rho (radians, + = convex =
    mountain); a scalar or an array. x * (180 / pi) is how np.degrees rounds: the same bits.
    Kernels call its compiled form (`kernels.rho_to_fold_deg`)."""
    return -(rho * (180.0 / np.pi))


def fold_deg_to_rho(deg):
    """Signed fold angle rho (radians, + = mountain) of FOLD fold angles in degrees (valley
    positive); the inverse of `rho_to_fold_deg` (np.radians rounds as x * (pi / 180)). Kernels
    call its compiled form (`kernels.fold_deg_to_rho`)."""
    return -(deg * (np.pi / 180.0))


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit normals (m, 3) of CCW faces; zero rows for degenerate faces."""
    from . import kernels as MK

    return MK.face_normals(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int64))


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def signed_volumes(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """(labels.max() + 1,) the volume each labelled set of faces encloses (closed, CCW seen from
    outside: positive; inward: negative): the sum of its triangles' tetrahedra with the origin."""
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    det = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    return np.bincount(labels, weights=det, minlength=int(labels.max()) + 1 if len(labels) else 0)


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The volume closed triangles (F, 3) enclose (`signed_volumes` of all of them as one set)."""
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def vector_norm(v: np.ndarray) -> float:
    """np.linalg.norm(v) of a 1-D float64 vector, bit for bit (the sqrt of v.dot(v)), without its
    general-case overhead (small meshes call it per heuristic and per net)."""
    return math.sqrt(v.dot(v))


def row_dots(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row dot products (n,) of a, b (n, 3). Kept in numpy: einsum's SIMD loop sums in an order of
    its own, and every stage must see the same bits."""
    return np.einsum("ij,ij->i", a, b)


def corner_angles(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Interior angle (m, 3) of each face at each corner (atan2 form, well conditioned)."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    out = np.empty((len(f), 3))
    for k in range(3):  # one numpy call per corner
        p = v[f[:, k]]
        a, b = v[f[:, (k + 1) % 3]] - p, v[f[:, (k + 2) % 3]] - p
        out[:, k] = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), row_dots(a, b))
    return out


def vertex_angle_sums(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Sum of corner angles at every vertex (n,), added in corner order (np.add.at: np.bincount's
    sums differ in the last bits)."""
    out = np.zeros(len(vertices))
    np.add.at(out, np.asarray(faces, dtype=np.int64).reshape(-1), corner_angles(vertices, faces).reshape(-1))
    return out


def edge_fold_angles(vertices: np.ndarray, faces: np.ndarray, topo: Topology) -> np.ndarray:
    """Signed fold angle rho per edge: atan2((n0 x n1).u, n0.n1), u along the edge as run by face 0.

    Positive on convex edges; 0 on boundary edges.
    """
    from . import kernels as MK

    inner, cross, u, n0, n1 = MK.fold_angle_vectors(np.ascontiguousarray(vertices, dtype=np.float64),
                                                    np.ascontiguousarray(faces, dtype=np.int64), topo.edges, topo.edge_faces)
    rho = np.zeros(topo.n_edges)
    if len(inner):
        rho[inner] = np.arctan2(row_dots(cross, u), row_dots(n0, n1))
    return rho


def merged_edges(mesh: Mesh, flat_tol: float = FLAT_REGION_RAD) -> np.ndarray:
    """(E,) bool per edge of `mesh.topology`: the interior edges inside one polygon of the net,
    which every net keeps as creases (never cut, folded flat): the two faces are coplanar
    (|rho| < flat_tol radians) or are triangles of one input polygon (same `face_source`; a
    non-planar input polygon is kept whole too). Boundary edges are never merged."""
    topo = mesh.topology
    ef = topo.edge_faces
    inner = (ef >= 0).all(axis=1) & (topo.face_count == 2)
    src = mesh.face_source[np.where(inner[:, None], ef, 0)]  # any face id where there is no second face
    return inner & ((np.abs(mesh.fold_angles) < flat_tol) | (src[:, 0] == src[:, 1]))


# A whole mesh's hull (`concavity`, `polyfold info`) is compiled up to this many points when the
# kernels are compiled ahead of time. The kernel tests every point against every facet: with every
# point on the hull (a convex mesh's vertices) 0.13 s at 5,000 points, 2 s at 20,000 (fewer on it:
# 18 ms at 3,000, 80-150 ms at 10,000); importing scipy.spatial for qhull costs 0.36-0.8 s (scipy
# 1.17: most of `info`'s time), then 3-70 ms.
MESH_HULL_COMPILED_POINTS = 5_000


def hull_planes(points: np.ndarray, compiled_up_to: int) -> tuple[np.ndarray, np.ndarray] | None:
    """3D convex hull of points (n, 3): (ids of its vertices (k,), facet planes (m, 4): unit outward
    normal and offset, n.x + d <= 0 inside, qhull's convention), or None when the points span no
    volume (flat, collinear, fewer than 4). Up to `compiled_up_to` points the compiled incremental
    hull (`hull_kernels.convex_hull`: cheaper for small sets than qhull's set-up), beyond qhull."""
    if len(points) < 4:
        return None
    if len(points) <= compiled_up_to:
        from .hull_kernels import HULL_FLAT_EPS, convex_hull

        verts, eq = convex_hull(np.ascontiguousarray(points, dtype=np.float64), HULL_FLAT_EPS)
        return None if len(eq) == 0 else (verts, eq)
    from scipy.spatial import ConvexHull, QhullError

    try:
        h = ConvexHull(points)
    except (QhullError, ValueError):
        return None  # flat or degenerate
    return h.vertices, h.equations


def concavity(mesh: Mesh, samples_per_face: int = 3, seed: int = 0) -> float:
    """Max distance from the surface to its convex hull, relative to the bounding-box diagonal.

    Samples the vertices plus `samples_per_face` random points per face; for a point inside the
    hull the distance to the hull boundary is min_j (-(n_j . x + d_j)) over hull facet planes.
    """
    from ..jit import ahead_ready

    tri = mesh.vertices[mesh.faces]
    rng = np.random.default_rng(seed)
    r = rng.random((len(tri), samples_per_face, 2))
    flip = r.sum(axis=2) > 1
    r[flip] = 1 - r[flip]
    pts = tri[:, None, 0] + r[..., :1] * (tri[:, None, 1] - tri[:, None, 0]) + r[..., 1:] * (tri[:, None, 2] - tri[:, None, 0])
    used = mesh.vertices[np.unique(mesh.faces)]
    pts = np.concatenate([used, pts.reshape(-1, 3)])
    diag = mesh.bbox_diagonal
    compiled = ahead_ready()  # (else numba would compile the kernels: longer than scipy and numpy take)
    hull = hull_planes(used, MESH_HULL_COMPILED_POINTS if compiled else 0)
    if hull is None:
        return 0.0  # flat or degenerate point set: no volume, the surface is its own hull
    eq = np.ascontiguousarray(hull[1], dtype=np.float64)
    if compiled:
        from .hull_kernels import max_depth

        # (each point's facets scanned from its neighbour's nearest, stopping below the deepest so
        # far: 82k faces 1.0 s -> 0.03 s)
        dist = float(max_depth(pts, eq, np.inf))
    else:
        # Chunked so points x facets stays small on large meshes (~8 MB per chunk).
        rows = max(1, 1_000_000 // len(eq))
        dist = 0.0
        for start in range(0, len(pts), rows):
            depth = -(pts[start:start + rows] @ eq[:, :3].T + eq[:, 3])  # >= 0 inside, per facet
            dist = max(dist, float(np.clip(depth.min(axis=1), 0.0, None).max()))
    return dist / diag if diag > 0 else 0.0
