"""Nearly convex decomposition: split a mesh into connected parts of bounded concavity.

In: a `Mesh` (one or more edge-connected components, closed or open). Out: a `Segmentation` — a
part label per face such that every part is edge-connected and its concavity (ALGORITHMS.md 4.2,
relative to the bounding-box diagonal of the WHOLE mesh) is at most `tau`. Each part is an open
patch (`Mesh.submesh`) that `unfold.search.unfold` and the folding planner accept directly.

Algorithm (ALGORITHMS.md 4.4, hierarchical merging on the dual graph):

1. Seed clusters: faces joined across edges that are convex or nearly flat (rho >= -12 deg). A seed
   cluster whose concavity exceeds tau falls back to its flat regions (concavity 0; coplanar
   faces and the input's polygons, `mesh.geometry.merged_edges`, single faces elsewhere), which
   are never split (a nearly flat region or a non-planar input polygon may exceed a tau below its
   own tiny concavity).
2. Merge: a min-heap of adjacent cluster pairs keyed by
   ``cost = conc(A u B) + W_COMPACT * compactness(A u B) * tau + W_SEAM * seam(A, B) * tau``
   where compactness = perimeter^2 / (4 pi area) - 1 (0 for a disk) and seam = the shared
   boundary's length-weighted mean concave fold angle / 90 deg (merging across a deep concave seam
   costs more: part boundaries follow concave creases, the minima rule). Only pairs with
   conc(A u B) <= tau enter the heap; entries of merged clusters are skipped (ids are never reused).
3. Clean up: parts smaller than MIN_FACES faces join the neighbour with the cheapest admissible
   merge (concavity still <= tau).

A merging run is one numba kernel (`merge_kernels.merge_run`). The union concavity uses cached
hulls (the hull of A u B is the hull of the two hulls' vertices) and a depth kernel with early
exit; evaluations are memoized across runs, so `parts=K` (a bisection on tau) re-uses most of
them; a Deadline stops that bisection between runs (`Segmentation.timed_out`). Merging adjacent
connected clusters keeps every part edge-connected. The per-mesh arrays, the candidate initial
clusters and the parts' tables and concavities are numba kernels as well (table_kernels), one
call each per segment() (per-face or per-part numpy calls cost more than the merging).

Concavity (`part_concavity`): max over the part's vertices plus SAMPLES_PER_FACE seeded surface
samples per face of the depth below the part's own convex hull (hull of its vertices), divided by
the whole mesh's bbox diagonal. The samples are drawn once per face of the whole mesh, so the value
of a part does not depend on how it was assembled: the reported concavities are exactly the values
the merging checked against tau.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..mesh.hull_kernels import denoise, max_depth
from .memo_kernels import make_units, new_memo
from .merge_kernels import merge_run
from .table_kernels import (face_groups, face_keys, face_lengths, first_face_order, inner_edges, part_concavities, part_tables,
                            sample_points, unit_groups)
from ..deadline import Deadline
from ..mesh.geometry import hull_planes, merged_edges
from ..mesh.mesh import Mesh

DEFAULT_TAU = 0.05  # relative to the bounding-box diagonal of the whole mesh
SAMPLES_PER_FACE = 3
SEED_ANGLE_DEG = 12.0  # seed clusters grow across edges with rho >= -SEED_ANGLE_DEG
# Weights chosen on the paper's horse/fish decompositions (bench/bench_segment.py --sweep): the Rand
# index on the horse is 0.90 on the whole plateau W_SEAM 3-6, SEED_ANGLE_DEG 10-15 and drops with any
# compactness weight (it pulls legs into the body), so ALGORITHMS.md's w_c = 0.1 is not used.
W_COMPACT = 0.0
W_SEAM = 4.0
MIN_FACES = 4


@dataclass(frozen=True, eq=False)
class Segmentation:
    """A decomposition of a mesh into parts.

    labels (F,): part of every face, in the face order of the Mesh given to `segment`;
    tau: the concavity tolerance the parts satisfy (relative to the whole mesh's bbox diagonal);
    concavity (P,): each part's concavity (same scale); parts: each part as `mesh.submesh(face_ids)`
    (its face_source maps to the input file's faces); face_ids: the mesh faces of each part, in
    the part's face order; vertex_ids: the mesh vertex of each of the part's vertices;
    timed_out: the deadline passed during the `parts=K` search, so this is the closest part count
    found until then (still every part's concavity <= tau).
    """

    labels: np.ndarray
    tau: float
    concavity: np.ndarray
    parts: tuple[Mesh, ...]
    face_ids: tuple[np.ndarray, ...]
    vertex_ids: tuple[np.ndarray, ...]
    timed_out: bool = False

    @property
    def n_parts(self) -> int:
        return len(self.parts)


# ----------------------------------------------------------------------------------------------
# Concavity


def surface_samples(mesh: Mesh, samples_per_face: int = SAMPLES_PER_FACE, seed: int = 0) -> np.ndarray:
    """Uniform random points (F, k, 3) on every face, drawn once for the whole mesh."""
    r = np.random.default_rng(seed).random((mesh.n_faces, samples_per_face, 2))
    return sample_points(mesh.vertices, mesh.faces, r)


SMALL_HULL = 64  # up to this many points our kernel; beyond, qhull (its ~45 us set-up no longer dominates)


def _hull(points: np.ndarray):
    """(hull vertex coordinates, facet equations) or (points, None) when the set has no volume."""
    hull = hull_planes(points, SMALL_HULL)
    return (points, None) if hull is None else (points[hull[0]], hull[1])


def part_concavity(mesh: Mesh, face_ids: np.ndarray, samples: np.ndarray | None = None, seed: int = 0) -> float:
    """Concavity of the faces `face_ids` of `mesh` relative to the bbox diagonal of the whole mesh.

    samples: `surface_samples(mesh, seed=seed)` (computed when None); this is the value
    `Segmentation.concavity` reports and that `segment` keeps <= tau.
    """
    if samples is None:
        samples = surface_samples(mesh, seed=seed)
    return _part_concavity(mesh, np.asarray(face_ids, dtype=np.int64), samples, mesh.bbox_diagonal)


def _part_concavity(mesh: Mesh, face_ids: np.ndarray, samples: np.ndarray, diag: float) -> float:
    """`part_concavity` with the whole mesh's bbox diagonal given."""
    verts = mesh.vertices[np.unique(mesh.faces[face_ids])]
    hull_pts, eq = _hull(verts)
    if eq is None or diag <= 0:
        return 0.0
    pts = np.concatenate([verts, samples[face_ids].reshape(-1, 3)])
    return denoise(float(max_depth(pts, eq, np.inf)), diag) / diag


def _parts_concavity(m: "_Merger", tables: tuple) -> np.ndarray:
    """`part_concavity` of every part of a `part_tables` output: the small parts in one kernel
    call, parts of more than SMALL_HULL vertices with qhull's hull."""
    faces, fstart, verts, vstart, _ = tables
    conc = part_concavities(faces, fstart, verts, vstart, m.mesh.vertices, m.samples, m.diag, SMALL_HULL)
    for p in np.flatnonzero(np.isnan(conc)):
        conc[p] = _part_concavity(m.mesh, faces[fstart[p]:fstart[p + 1]], m.samples, m.diag)
    return conc


# ----------------------------------------------------------------------------------------------
# Rand index


def rand_index(a: np.ndarray, b: np.ndarray) -> float:
    """Rand index of two labelings of the same items: the fraction of item pairs on which they agree
    (both in one part, or both in different parts). 1.0 for identical partitions."""
    a = np.asarray(a).reshape(-1)
    b = np.asarray(b).reshape(-1)
    if len(a) != len(b):
        raise ValueError("labelings differ in length")
    n = len(a)
    if n < 2:
        return 1.0
    _, ia = np.unique(a, return_inverse=True)
    _, ib = np.unique(b, return_inverse=True)
    table = np.zeros((ia.max() + 1, ib.max() + 1), dtype=np.int64)
    np.add.at(table, (ia, ib), 1)

    def pairs(x):
        x = np.asarray(x, dtype=np.float64)
        return float((x * (x - 1) / 2).sum())

    total = n * (n - 1) / 2
    both = pairs(table)
    same_a = pairs(table.sum(axis=1))
    same_b = pairs(table.sum(axis=0))
    return (total + 2 * both - same_a - same_b) / total


# ----------------------------------------------------------------------------------------------
# Merging


class _Merger:
    """Per-mesh state shared by all merging runs of one `segment` call: the dual graph's arrays,
    the face labellings (seeds, input polygons, components), the candidate initial clusters of
    each seed labelling, and the memo of union concavities."""

    def __init__(self, mesh: Mesh, seed: int):
        self.mesh = mesh
        self.diag = mesh.bbox_diagonal
        self.samples = surface_samples(mesh, seed=seed)
        topo = mesh.topology
        # Perimeter of each face counted over all its edges; shared edges are subtracted on merges.
        self.areas, self.face_perim, edge_len = face_lengths(mesh.vertices, mesh.faces, topo.edges, topo.face_edges)
        self.ef0, self.ef1, self.inner_len, self.inner_conc = inner_edges(topo.edge_faces, edge_len, mesh.fold_angles)
        # random 64-bit face keys: a cluster's key is their sum (see memo_kernels.new_memo)
        self.face_key = face_keys(mesh.n_faces)
        self.memo = new_memo(mesh.n_faces)
        # seeds: faces joined across edges with rho >= -SEED_ANGLE_DEG (locally convex regions) and
        # across merged edges; polygon: the faces of one flat region (coplanar faces, the triangles
        # of one input polygon: never split between parts, as no net cuts them); components:
        # edge-connected
        self.seeds, self.polygon, self.components = face_groups(
            topo.edge_faces, merged_edges(mesh), mesh.fold_angles, -math.radians(SEED_ANGLE_DEG), mesh.n_faces)
        self.graph = (self.face_key, self.ef0, self.ef1, self.inner_len, self.inner_conc)
        self._units: dict[bytes, tuple] = {}

    def units(self, seed_labels: np.ndarray) -> tuple:
        """The candidate initial clusters for these seeds: each seed, then its input polygons
        (used when the seed is too concave), with points, hulls, concavities, areas, perimeters."""
        got = self._units.get(seed_labels.tobytes())
        if got is not None:
            return got
        mesh = self.mesh
        seed_unit, sub_lo, sub_hi, faces, start = unit_groups(seed_labels, self.polygon)
        pts, pstart, hulls, conc, self.memo = make_units(faces, start, mesh.faces, mesh.vertices, self.samples, self.diag, self.memo)
        area = np.add.reduceat(self.areas[faces], start[:-1])
        perim = np.add.reduceat(self.face_perim[faces], start[:-1])
        got = (seed_unit, sub_lo, sub_hi, faces, start, pts, pstart, hulls, conc, area, perim)
        self._units[seed_labels.tobytes()] = got
        return got


def _run(m: _Merger, tau: float, target: int | None, seed_labels: np.ndarray,
         w_compact: float = W_COMPACT, w_seam: float = W_SEAM, min_faces: int = MIN_FACES) -> tuple[np.ndarray, int]:
    """One merging run: (a cluster label per face, the number of clusters) (tau absolute; stop at
    `target` clusters). The merging itself is `merge_kernels.merge_run`."""
    limit = tau * m.diag * (1 - 1e-9)  # margin: the final re-measure may differ by rounding
    scale = limit if limit > 0 and math.isfinite(limit) else m.diag
    label, n, m.memo = merge_run(limit, scale, -1 if target is None else int(target), float(w_compact), float(w_seam),
                                 int(min_faces), m.diag, m.units(seed_labels), m.graph, m.memo)
    return label, n


def segment(mesh: Mesh, tau: float = DEFAULT_TAU, parts: int | None = None, seed: int = 0,
            deadline: Deadline | None = None) -> Segmentation:
    """Decompose `mesh` into edge-connected parts whose concavity is <= tau (relative to the bbox
    diagonal of the whole mesh).

    parts=K: choose tau (bisection, the `tau` argument is then ignored) so the result has K parts;
    when no tau gives exactly K (the count jumps past K), merging continues past the last tau in
    cost order until K parts remain, and the reported tau is the largest part concavity. The count
    is bounded below by the number of edge-connected components and above by the count at tau 0
    (already-convex pieces are not split further), so the result may have fewer or more than K.
    seed: seeds the surface samples of the concavity metric. deadline (None: no limit): when it
    passes during the parts=K search, the search stops after the merging run under way and the
    result is the run whose part count came closest to K (ties: the smaller tau), with
    `timed_out` set; one run is always made. A single tau is one run and never times out.
    """
    if mesh.n_faces == 0:
        raise ValueError("empty mesh")
    if not (tau >= 0 and math.isfinite(tau)):
        raise ValueError(f"tau must be a non-negative number, not {tau!r}")
    m = _Merger(mesh, seed)
    timed_out = False
    if parts is None:
        label, _ = _run(m, tau, None, m.seeds)
    else:
        label, tau, timed_out = _fit_parts(m, m.seeds, int(parts), deadline or Deadline.never())
    return _finish(m, label, tau, timed_out)


class _TimeUp(Exception):
    """The deadline of a `parts=K` search passed before a merging run."""


def _fit_parts(m: _Merger, seeds: np.ndarray, k: int, deadline: Deadline) -> tuple[np.ndarray, float, bool]:
    """(cluster labels, tau, timed out) for `parts=k` (see `_search_parts`); when the deadline
    passes, the run so far whose count is closest to k (ties: the smaller tau)."""
    n_comp = int(m.components.max()) + 1
    k = int(min(max(k, n_comp), m.mesh.n_faces))
    runs: list[tuple[np.ndarray, int, float]] = []

    def run(tau: float, target: int | None = None) -> tuple[np.ndarray, int]:
        if runs and deadline.expired():
            raise _TimeUp
        g, n = _run(m, tau, target, seeds)
        runs.append((g, n, tau))
        return g, n

    try:
        g, tau = _search_parts(m, k, run)
    except _TimeUp:
        g, _, tau = min(runs, key=lambda r: (abs(r[1] - k), r[2]))
        return g, tau, True
    return g, tau, False


def _search_parts(m: _Merger, k: int, run: Callable[..., tuple[np.ndarray, int]]) -> tuple[np.ndarray, float]:
    """Cluster labels and tau for `parts=k`: the default tau when it already gives k parts (so
    `segment()` and `segment(parts=k)` agree), else a bisection on tau from the default towards k.
    run(tau, target=None): one merging run (`_run` on the seeds)."""
    mesh = m.mesh
    n_comp = int(m.components.max()) + 1
    g, n = run(DEFAULT_TAU)
    if n == k:
        return g, DEFAULT_TAU
    if n > k:
        lo, hi = DEFAULT_TAU, None
    else:
        lo, hi = 0.0, DEFAULT_TAU
        g0, n0 = run(0.0)
        if n0 <= k:  # even tau 0 gives no more parts: already-convex pieces stay whole
            return g0, 0.0
    if hi is None:
        # every component as one part is admissible at its own concavity
        hi = float(_parts_concavity(m, part_tables(m.components, n_comp, mesh.faces, mesh.n_vertices)).max()) * 1.001
        hi = max(hi, lo * 1.001)
        g, n = run(hi)
        if n == k:
            return g, hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        g, n = run(mid)
        if n == k:
            return g, mid
        if n > k:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-6:
            break
    # No tau gives exactly k: merge on past tau (hi) until k parts, report the largest concavity.
    g, n = run(hi, k)
    label, n = first_face_order(g)
    conc = float(_parts_concavity(m, part_tables(label, n, mesh.faces, mesh.n_vertices)).max())
    return g, max(conc, lo)


def _finish(m: _Merger, label: np.ndarray, tau: float, timed_out: bool = False) -> Segmentation:
    """The Segmentation of a run's cluster labels: parts ordered by their first face so labels are
    stable and readable, faces and vertices ascending within each part."""
    mesh = m.mesh
    labels, n = first_face_order(label)
    tables = part_tables(labels, n, mesh.faces, mesh.n_vertices)
    faces, fstart, verts, vstart, local = tables
    conc = _parts_concavity(m, tables)
    face_ids = tuple(faces[fstart[p]:fstart[p + 1]] for p in range(n))
    vids = tuple(verts[vstart[p]:vstart[p + 1]] for p in range(n))
    # each part as mesh.submesh(face_ids[p]) builds it
    subs = tuple(Mesh(mesh.vertices[v], local[fstart[p]:fstart[p + 1]], mesh.face_source[f])
                 for p, (f, v) in enumerate(zip(face_ids, vids)))
    return Segmentation(labels=labels, tau=float(tau), concavity=conc, parts=subs, face_ids=face_ids, vertex_ids=vids,
                        timed_out=timed_out)
