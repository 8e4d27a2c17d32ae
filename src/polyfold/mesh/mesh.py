"""Triangle meshes: the `Mesh` record and its edge topology.

Conventions: faces are CCW seen from outside (outward normals); `geometry.py` holds the
quantities every stage computes on them (normals, corner and fold angles, concavity) and the one
sign convention of fold angles.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

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

    Edges in lexicographic order of their sorted vertex pair (as np.unique of the rows); slot 0 of
    edge_faces takes the first face (in face order) that runs the edge low -> high, slot 1 the
    first that runs it high -> low; a second face running the same way takes a free slot and
    further faces are only counted (non-manifold input). Boundary edges keep their face in slot 0
    and are flipped so that face runs edges[e, 0] -> edges[e, 1]. One stable lexsort of the 3m
    sides (numpy: as fast as a compiled pass from a few hundred faces up, and `info` needs no
    numba).
    """
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    m = len(faces)
    a, b = faces.reshape(-1), faces[:, [1, 2, 0]].reshape(-1)  # side 3f + k runs corner k -> k + 1
    forward = a <= b
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((~forward, hi, lo))  # by edge, the forward sides first, each run in face order
    slo, shi, sfw = lo[order], hi[order], forward[order]
    n_sides = len(order)
    new_edge = np.ones(n_sides, dtype=bool)
    new_edge[1:] = (slo[1:] != slo[:-1]) | (shi[1:] != shi[:-1])
    edge_of = np.cumsum(new_edge) - 1
    n_edges = int(edge_of[-1]) + 1 if n_sides else 0
    inverse = np.empty(n_sides, dtype=np.int64)
    inverse[order] = edge_of
    starts = np.flatnonzero(new_edge)
    edges = np.stack([slo[starts], shi[starts]], axis=1)
    counts = np.diff(np.append(starts, n_sides)).astype(np.int64)
    # rank of each side among the sides that run its edge the same way
    new_run = new_edge.copy()
    new_run[1:] |= sfw[1:] != sfw[:-1]
    rank = np.arange(n_sides) - np.maximum.accumulate(np.where(new_run, np.arange(n_sides), 0))
    face = order // 3
    firsts = {}
    for way in (True, False):
        for r in (0, 1):
            got = np.full(n_edges, -1, dtype=np.int64)
            pick = (sfw == way) & (rank == r)
            got[edge_of[pick]] = face[pick]
            firsts[way, r] = got
    # slot 0: the first forward face, else (no forward face) the second backward one; slot 1: the
    # second forward face, else the first backward one
    edge_faces = np.empty((n_edges, 2), dtype=np.int64)
    edge_faces[:, 0] = np.where(firsts[True, 0] >= 0, firsts[True, 0], firsts[False, 1])
    edge_faces[:, 1] = np.where(firsts[True, 1] >= 0, firsts[True, 1], firsts[False, 0])
    flip = (edge_faces[:, 0] < 0) & (edge_faces[:, 1] >= 0)
    edge_faces[flip] = edge_faces[flip][:, ::-1]
    edges[flip] = edges[flip][:, ::-1]
    return Topology(edges=edges, edge_faces=edge_faces, face_edges=inverse.reshape(m, 3), face_count=counts)


def face_components(n_faces: int, topo: Topology, join: np.ndarray | None = None) -> np.ndarray:
    """Label (m,) of the edge-connected component of every face (faces joined across every
    interior edge, or only across those in the mask `join` (E,))."""
    from ..graphs import connected_components

    inner = topo.interior if join is None else topo.interior & join
    return connected_components(n_faces, topo.edge_faces[inner, 0], topo.edge_faces[inner, 1])[1]


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
