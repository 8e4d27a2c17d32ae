"""Triangle meshes: the `Mesh` record, its edge topology and the geometric quantities every stage uses.

Conventions: faces are CCW seen from outside (outward normals). The signed fold angle `rho` of an
edge is the angle between the normals of its two faces, positive on convex edges (mountains seen
from outside), negative on reflex edges, 0 on flat ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import _mesh_kernels as MK

HYPERBOLIC_EPS = 1e-9


@dataclass(frozen=True, eq=False)
class Mesh:
    """A manifold, consistently oriented triangle mesh.

    vertices: (n, 3) float64; faces: (m, 3) int64, CCW seen from outside;
    face_source: (m,) int64, the index of each face in the input file's face order
    (several triangles share one index when a polygon was triangulated).
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_source: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, dtype=np.float64)
        f = np.ascontiguousarray(self.faces, dtype=np.int64)
        src = np.arange(len(f), dtype=np.int64) if self.face_source is None else np.asarray(self.face_source, np.int64)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        object.__setattr__(self, "face_source", src)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @cached_property
    def topology(self) -> "Topology":
        return edge_topology(self.faces)

    @cached_property
    def face_normals(self) -> np.ndarray:
        return face_normals(self.vertices, self.faces)

    @cached_property
    def fold_angles(self) -> np.ndarray:
        """Signed fold angle per edge of `topology` (radians, + convex); 0 on boundary edges."""
        return edge_fold_angles(self.vertices, self.faces, self.topology)

    @cached_property
    def angle_sums(self) -> np.ndarray:
        return vertex_angle_sums(self.vertices, self.faces)

    @property
    def hyperbolic(self) -> np.ndarray:
        """Boolean mask of hyperbolic vertices (angle sum > 2*pi + 1e-9)."""
        return self.angle_sums > 2 * np.pi + HYPERBOLIC_EPS

    @property
    def bbox_diagonal(self) -> float:
        used = self.vertices[np.unique(self.faces)] if len(self.faces) else self.vertices
        return float(np.linalg.norm(used.max(0) - used.min(0)))

    def submesh(self, face_ids: np.ndarray) -> "Mesh":
        """The faces `face_ids` as a mesh of their own (vertices renumbered, face_source kept)."""
        face_ids = np.asarray(face_ids, dtype=np.int64)
        sub = self.faces[face_ids]
        used, inverse = np.unique(sub, return_inverse=True)
        return Mesh(self.vertices[used], inverse.reshape(-1, 3), self.face_source[face_ids])


@dataclass(frozen=True, eq=False)
class Topology:
    """Edges of a triangle mesh.

    edges: (E, 2) vertex ids (sorted); edge_faces: (E, 2) incident faces, -1 where missing
    (edge_faces[e, 0] is a face that contains the edge as directed edges[e,0] -> edges[e,1] when
    there is one); face_edges: (F, 3), face_edges[f, k] is the edge from corner k to corner k+1.
    face_count: (E,) number of incident faces (> 2 means a non-manifold edge).
    """

    edges: np.ndarray
    edge_faces: np.ndarray
    face_edges: np.ndarray
    face_count: np.ndarray

    @property
    def n_edges(self) -> int:
        return len(self.edges)

    @property
    def interior(self) -> np.ndarray:
        return (self.edge_faces >= 0).all(axis=1)

    @property
    def boundary(self) -> np.ndarray:
        return self.face_count == 1


def edge_topology(faces: np.ndarray) -> Topology:
    """Build the edge table of `faces` (m, 3). Works on non-manifold input too (face_count > 2).

    Edges in lexicographic order of their sorted vertex pair; slot 0 of edge_faces takes a face
    that runs the edge low -> high, slot 1 the other; when orientation is inconsistent both may run
    the same way, then the second such face goes to the free slot (a third face is only counted).
    One numba pass (`_mesh_kernels.edge_table`): this is set-up work of every mesh and part.
    """
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    edges, edge_faces, face_edges, counts = MK.edge_table(faces)
    return Topology(edges=edges, edge_faces=edge_faces, face_edges=face_edges, face_count=counts)


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit normals (m, 3) of CCW faces; zero rows for degenerate faces."""
    return MK.face_normals(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int64))


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


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
    a, b, y = MK.corner_vectors(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int64))
    out = np.empty((y.shape[1], 3))
    for k in range(3):  # one numpy call per corner, on the same (m,) layout as always
        out[:, k] = np.arctan2(y[k], row_dots(a[k], b[k]))
    return out


def vertex_angle_sums(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Sum of corner angles at every vertex (n,)."""
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    return MK.scatter_sums(len(vertices), faces.reshape(-1), corner_angles(vertices, faces).reshape(-1))


def edge_fold_angles(vertices: np.ndarray, faces: np.ndarray, topo: Topology) -> np.ndarray:
    """Signed fold angle rho per edge: atan2((n0 x n1).u, n0.n1), u along the edge as run by face 0.

    Positive on convex edges; 0 on boundary edges.
    """
    inner, cross, u, n0, n1 = MK.fold_angle_vectors(np.ascontiguousarray(vertices, dtype=np.float64),
                                                    np.ascontiguousarray(faces, dtype=np.int64), topo.edges, topo.edge_faces)
    rho = np.zeros(topo.n_edges)
    if len(inner):
        rho[inner] = np.arctan2(row_dots(cross, u), row_dots(n0, n1))
    return rho


def face_components(n_faces: int, topo: Topology) -> np.ndarray:
    """Label (m,) of the edge-connected component of every face."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    inner = topo.interior
    f0, f1 = topo.edge_faces[inner, 0], topo.edge_faces[inner, 1]
    graph = coo_matrix((np.ones(len(f0)), (f0, f1)), shape=(n_faces, n_faces))
    _, labels = connected_components(graph, directed=False)
    return labels


def boundary_loops(topo: Topology) -> list[np.ndarray]:
    """Boundary edges chained into closed vertex loops (a pinched boundary may share a vertex)."""
    bnd = np.flatnonzero(topo.boundary)
    # Each boundary edge, as run by its face, goes edges[e,0] -> edges[e,1].
    nxt: dict[int, list[int]] = {}
    for e in bnd:
        nxt.setdefault(int(topo.edges[e, 0]), []).append(int(e))
    used = np.zeros(topo.n_edges, dtype=bool)
    loops = []
    for e in bnd:
        if used[e]:
            continue
        loop = []
        cur = int(e)
        while not used[cur]:
            used[cur] = True
            loop.append(int(topo.edges[cur, 0]))
            cands = [c for c in nxt.get(int(topo.edges[cur, 1]), []) if not used[c]]
            if not cands:
                break
            cur = cands[0]
        loops.append(np.array(loop, dtype=np.int64))
    return loops


def concavity(mesh: Mesh, samples_per_face: int = 3, seed: int = 0) -> float:
    """Max distance from the surface to its convex hull, relative to the bounding-box diagonal.

    Samples the vertices plus `samples_per_face` random points per face; for a point inside the
    hull the distance to the hull boundary is min_j (-(n_j . x + d_j)) over hull facet planes.
    """
    from scipy.spatial import ConvexHull, QhullError

    tri = mesh.vertices[mesh.faces]
    rng = np.random.default_rng(seed)
    r = rng.random((len(tri), samples_per_face, 2))
    flip = r.sum(axis=2) > 1
    r[flip] = 1 - r[flip]
    pts = tri[:, None, 0] + r[..., :1] * (tri[:, None, 1] - tri[:, None, 0]) + r[..., 1:] * (tri[:, None, 2] - tri[:, None, 0])
    pts = np.concatenate([mesh.vertices[np.unique(mesh.faces)], pts.reshape(-1, 3)])
    diag = mesh.bbox_diagonal
    try:
        hull = ConvexHull(mesh.vertices[np.unique(mesh.faces)])
    except (QhullError, ValueError):
        return 0.0  # flat or degenerate point set: no volume, the surface is its own hull
    eq = hull.equations
    # Chunked so points x facets stays small on large meshes (~8 MB per chunk).
    rows = max(1, 1_000_000 // len(eq))
    dist = 0.0
    for start in range(0, len(pts), rows):
        depth = -(pts[start:start + rows] @ eq[:, :3].T + eq[:, 3])  # >= 0 inside, per facet
        dist = max(dist, float(np.clip(depth.min(axis=1), 0.0, None).max()))
    return dist / diag if diag > 0 else 0.0
