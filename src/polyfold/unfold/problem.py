"""The unfolding problem of one mesh component: the arrays the kernels need (`UnfoldProblem`),
and the heuristic edge weights that seed the search (ALGORITHMS.md 5.3).

Genome (ALGORITHMS.md 5.1, 5.5): one weight in [0, 1] per mesh edge; Prim's algorithm from the
base face keeps light edges as creases. Low weight = keep as crease. The merged edges of flat
regions (`mesh.geometry.merged_edges`) weigh MERGED_WEIGHT whatever the genome says: lighter than
every other edge, so Prim's tree grows through a whole flat region as soon as it reaches one of
its faces, and every net keeps each flat polygon whole.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..collide.flat import all_overlapping_pairs
from ..mesh.geometry import merged_edges, row_dots, vector_norm
from ..mesh.mesh import Mesh, face_components
from . import kernels as K
from . import setup_kernels as S

MERGED_WEIGHT = -1.0  # the weight of a merged edge in Prim's tree: below every genome weight (>= 0)
# A vertex whose angle sum exceeds 2 pi by less than this may still end a cut in
# `single_net_blocked`'s disk rule: a wedge that thin overlaps by less than the overlap test may
# see, so only vertices clearly hyperbolic (saddles exceed 2 pi by 0.01-1 rad) count as needing two
LEAF_EXCESS = 1e-6


@dataclass(frozen=True, eq=False)
class UnfoldProblem:
    """Arrays the kernels need, derived once per mesh component.

    adj_ptr / adj_face / adj_edge: the dual graph (CSR); local (F, 3, 2): `local_frames`;
    hyperbolic (n,): the mesh's hyperbolic vertices; tol: overlap tolerance (1e-9 of the bbox
    diagonal); interior_edges (I,); edge_vec (E, 3) / edge_len (E,): each edge as a vector
    edges[e, 0] -> edges[e, 1] and its length (for the heuristic weight rules); merged (E,): the
    edges inside flat regions (`merged_edges`), creases of every tree (`tree_weights`);
    cut_candidates (C,): the interior edges that are not merged, ascending (the edges a net may cut).
    """

    mesh: Mesh
    adj_ptr: np.ndarray
    adj_face: np.ndarray
    adj_edge: np.ndarray
    local: np.ndarray
    hyperbolic: np.ndarray
    tol: float
    base: int = 0
    interior_edges: np.ndarray = field(default=None)  # type: ignore[assignment]
    edge_vec: np.ndarray = field(default=None)  # type: ignore[assignment]
    edge_len: np.ndarray = field(default=None)  # type: ignore[assignment]
    hyperbolic_candidates: int = 0  # half-edges of cut_candidates at hyperbolic vertices
    merged: np.ndarray = field(default=None)  # type: ignore[assignment]
    cut_candidates: np.ndarray = field(default=None)  # type: ignore[assignment]

    @classmethod
    def from_mesh(cls, mesh: Mesh, base: int = 0) -> "UnfoldProblem":
        topo = mesh.topology
        # one numba pass for everything but the numpy-rounded dot products (see _unfold_setup)
        hyperbolic = mesh.hyperbolic
        inner, adj_ptr, adj_face, adj_edge, e1, e2, local, edge_vec, edge_len, box, candidates = S.problem_arrays(
            mesh.vertices, mesh.faces, topo.edges, topo.edge_faces, hyperbolic)
        local[:, 2, 0] = row_dots(e2, e1) / local[:, 1, 0]
        diagonal = vector_norm(box) if mesh.n_vertices else mesh.bbox_diagonal
        merged = merged_edges(mesh)
        cut_candidates = inner[~merged[inner]]
        if len(cut_candidates) < len(inner):
            candidates = S.incident_count(cut_candidates, topo.edges, hyperbolic)
        return cls(
            mesh=mesh,
            adj_ptr=adj_ptr,
            adj_face=adj_face,
            adj_edge=adj_edge,
            local=local,
            hyperbolic=hyperbolic,
            tol=1e-9 * max(diagonal, 1e-300),
            base=base,
            interior_edges=inner,
            edge_vec=edge_vec,
            edge_len=edge_len,
            hyperbolic_candidates=candidates,
            merged=merged,
            cut_candidates=cut_candidates,
        )

    def single_net_blocked(self) -> str | None:
        """Why no overlap-free single net exists (one line), or None when one may. An interior
        hyperbolic vertex needs two cuts (with one, its faces overlap around it). Two cases found
        without a search:

        - flat regions kept whole: a hyperbolic vertex with at most two edges that may be cut (the
          others merged) has them all cut; when it has fewer than two, or those forced cuts split
          the dual graph, no spanning tree is left;
        - a disk whose interior vertices all need two cuts: a net of a disk cuts along trees that
          each meet the boundary at one vertex (its cuts and the boundary make one cycle, the
          boundary), so each tree has another leaf, an interior vertex with one cut, which only a
          vertex of angle sum 2 pi or less allows (every saddle-shaped patch of a torus's inside).
        """
        topo = self.mesh.topology
        ends = topo.edges[self.cut_candidates]
        count = np.bincount(ends.ravel(), minlength=self.mesh.n_vertices)
        boundary_degree = np.bincount(topo.edges[~topo.interior].ravel(), minlength=self.mesh.n_vertices)
        on_boundary = boundary_degree > 0
        if self._disk_without_leaves(boundary_degree):
            return ("no single-piece net exists: a disk whose interior vertices are all hyperbolic needs a cut "
                    "ending at one of angle sum 360 degrees or less")
        if not self.merged.any():
            return None  # every vertex has three edges or more that may be cut
        tight = self.hyperbolic & ~on_boundary & (count <= 2)
        flat = ("no single-piece net can keep the flat regions whole: hyperbolic vertices on their edges "
                "need cuts that split the net")
        if (tight & (count < 2)).any():
            return flat
        forced = np.zeros(topo.n_edges, dtype=bool)
        forced[self.cut_candidates] = tight[ends].any(axis=1)
        if forced.any() and face_components(self.mesh.n_faces, topo, ~forced).max() > 0:
            return flat
        return None

    def _disk_without_leaves(self, boundary_degree: np.ndarray) -> bool:
        """True when the component is a disk (manifold, one boundary loop: Euler characteristic 1,
        every boundary vertex on two boundary edges) with interior vertices, none of which can end a
        cut: each is hyperbolic by more than LEAF_EXCESS (boundary_degree (n,): boundary edges at
        each vertex). A vertex inside a flat region (all its edges merged) may still end one: a tree
        cannot hold every merged edge around it, so a net slits the region there."""
        mesh, topo = self.mesh, self.mesh.topology
        if not boundary_degree.any() or (topo.face_count > 2).any():
            return False
        if ((boundary_degree != 0) & (boundary_degree != 2)).any():
            return False  # a pinched boundary: not a disk
        used = np.bincount(mesh.faces.ravel(), minlength=mesh.n_vertices) > 0
        if int(used.sum()) - topo.n_edges + mesh.n_faces != 1:
            return False
        interior = used & (boundary_degree == 0)
        if not interior.any():
            return False  # a strip: no cut at all
        leaf = interior & (mesh.angle_sums <= 2 * np.pi + LEAF_EXCESS)
        return not leaf.any()

    def tree_weights(self, weights: np.ndarray) -> np.ndarray:
        """The weights Prim's algorithm runs on: genomes (E,) or (B, E) with every merged edge set
        to MERGED_WEIGHT (float64, C order; the genome itself is not changed)."""
        return np.where(self.merged, MERGED_WEIGHT, np.asarray(weights, dtype=np.float64))

    def evaluate(self, weights: np.ndarray, max_pairs: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Overlap counts (G, L) of a batch of genomes (B, E)."""
        mesh = self.mesh
        cap = 4 * mesh.n_faces if max_pairs is None else max_pairs
        return K.evaluate_batch(
            self.tree_weights(weights), self.base, self.adj_ptr, self.adj_face, self.adj_edge,
            mesh.faces, mesh.topology.face_edges, mesh.topology.edges, self.hyperbolic, self.local, self.tol, cap,
        )

    def decode(self, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Genome -> (parent, parent_edge, order, coords) of the spanning tree (every merged edge
        joins its flat region's faces, see `tree_weights`)."""
        n = self.mesh.n_faces
        reached, parent, parent_edge, order, coords = K.decode_tree(
            self.tree_weights(weights), self.base, self.adj_ptr, self.adj_face, self.adj_edge,
            self.mesh.faces, self.mesh.topology.face_edges, self.local)
        if reached != n:
            raise ValueError(f"dual graph is not connected ({reached} of {n} faces reached)")
        return parent, parent_edge, order, coords

    def overlaps(self, coords: np.ndarray, parent: np.ndarray) -> np.ndarray:
        """All overlapping face pairs (k, 2) of a layout (crease pairs skipped)."""
        return all_overlapping_pairs(coords, parent, self.tol)


def local_frames(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each triangle in its own 2D frame (F, 3, 2): corner 0 at the origin, corner 1 on +x, CCW."""
    e1, e2, out = S.frame_parts(np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64))
    out[:, 2, 0] = row_dots(e2, e1) / out[:, 1, 0]
    return out


def _random_direction(rng: np.random.Generator) -> np.ndarray:
    c = rng.normal(size=3)
    return c / vector_norm(c)


def flat_tree_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    """Edges orthogonal to a random direction are kept, edges along it are cut."""
    return np.abs(problem.edge_vec @ _random_direction(rng)) / problem.edge_len


def unflat_tree_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    w = flat_tree_weights(problem, rng)
    return np.where(w > 0, 1.0 - w, w)


def min_perimeter_weights(problem: UnfoldProblem, rng: np.random.Generator | None = None) -> np.ndarray:
    """Long edges kept: short total cut length."""
    length = problem.edge_len
    span = max(length.max() - length.min(), 1e-300)
    return 1.0 - (length - length.min()) / span


def max_perimeter_weights(problem: UnfoldProblem, rng: np.random.Generator | None = None) -> np.ndarray:
    length = problem.edge_len
    span = max(length.max() - length.min(), 1e-300)
    return (length - length.min()) / span


def _steepest(problem: UnfoldProblem, rng: np.random.Generator, un: bool) -> np.ndarray:
    """Every vertex but the top one cuts its steepest upward edge (un=True: the least steep) that
    is not merged (merged edges are never cut: their slope is nan, which loses to any number)."""
    c = _random_direction(rng)
    mesh = problem.mesh
    slope = (problem.edge_vec @ c) / problem.edge_len  # from e0 toward e1
    slope[problem.merged] = np.nan
    top = int(np.argmax(mesh.vertices @ c))
    return S.steepest_cuts(slope, mesh.topology.edges, mesh.n_vertices, top, un)


def steepest_edge_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    return _steepest(problem, rng, un=False)


def unsteepest_edge_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    return _steepest(problem, rng, un=True)


def random_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    return rng.random(problem.mesh.topology.n_edges) + 0.01


def random_edge_weights(problem: UnfoldProblem, rng: np.random.Generator) -> np.ndarray:
    """Two random cuts at every hyperbolic vertex, one at every elliptic vertex that has none,
    among the edges that may be cut (not merged)."""
    edges = problem.mesh.topology.edges
    inner = problem.cut_candidates
    w = np.full(len(edges), 0.01)
    # one random draw per candidate half-edge (an interior edge at a wanted vertex)
    want, n = S.pick_random_incident(inner, edges, problem.hyperbolic, 2, rng.random(problem.hyperbolic_candidates), w,
                                     problem.hyperbolic)
    S.pick_random_incident(inner, edges, want, 1, rng.random(n), w, problem.hyperbolic)
    return w


HEURISTICS: dict[str, Callable[[UnfoldProblem, np.random.Generator], np.ndarray]] = {
    "steepest-edge": steepest_edge_weights,
    "unsteepest-edge": unsteepest_edge_weights,
    "flat-tree": flat_tree_weights,
    "unflat-tree": unflat_tree_weights,
    "min-perimeter": min_perimeter_weights,
    "max-perimeter": max_perimeter_weights,
    "random": random_weights,
    "random-edge": random_edge_weights,
}
