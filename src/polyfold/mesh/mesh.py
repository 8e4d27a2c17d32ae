"""Triangle meshes: the `Mesh` record and its edge topology.

Conventions: faces are CCW seen from outside (outward normals); `geometry.py` holds the
quantities every stage computes on them (normals, corner and fold angles, concavity) and the one
sign convention of fold angles.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import kernels as MK
from .geometry import HYPERBOLIC_EPS, edge_fold_angles, face_normals, vertex_angle_sums


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
    One numba pass (`kernels.edge_table`): this is set-up work of every mesh and part.
    """
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    edges, edge_faces, face_edges, counts = MK.edge_table(faces)
    return Topology(edges=edges, edge_faces=edge_faces, face_edges=face_edges, face_count=counts)


def face_components(n_faces: int, topo: Topology, join: np.ndarray | None = None) -> np.ndarray:
    """Label (m,) of the edge-connected component of every face (faces joined across every
    interior edge, or only across those in the mask `join` (E,))."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    inner = topo.interior if join is None else topo.interior & join
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
