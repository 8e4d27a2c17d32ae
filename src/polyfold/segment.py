"""Nearly convex decomposition: split a mesh into connected parts of bounded concavity.

In: a `Mesh` (one or more edge-connected components, closed or open). Out: a `Segmentation` — a
part label per face such that every part is edge-connected and its concavity (ALGORITHMS.md 4.2,
relative to the bounding-box diagonal of the WHOLE mesh) is at most `tau`. Each part is an open
patch (`Mesh.submesh`) that `unfold.unfold` and the folding planner accept directly.

Algorithm (ALGORITHMS.md 4.4, hierarchical merging on the dual graph):

1. Seed clusters: faces joined across edges that are convex or nearly flat (rho >= -12 deg). A seed
   cluster whose concavity exceeds tau falls back to single faces (concavity 0), or to the input's
   polygons when the file had polygons (they are never split).
2. Merge: a min-heap of adjacent cluster pairs keyed by
   ``cost = conc(A u B) + W_COMPACT * compactness(A u B) * tau + W_SEAM * seam(A, B) * tau``
   where compactness = perimeter^2 / (4 pi area) - 1 (0 for a disk) and seam = the shared
   boundary's length-weighted mean concave fold angle / 90 deg (merging across a deep concave seam
   costs more: part boundaries follow concave creases, the minima rule). Only pairs with
   conc(A u B) <= tau enter the heap; entries of merged clusters are skipped (ids are never reused).
3. Clean up: parts smaller than MIN_FACES faces join the neighbour with the cheapest admissible
   merge (concavity still <= tau).

The union concavity uses cached hulls (the hull of A u B is the hull of the two hulls' vertices,
by a numba kernel for small sets, qhull beyond) and a numba depth kernel with early exit;
evaluations are memoized, so `parts=K` (a bisection on tau) re-uses most of them. Merging adjacent connected clusters keeps every part edge-connected.

Concavity (`part_concavity`): max over the part's vertices plus SAMPLES_PER_FACE seeded surface
samples per face of the depth below the part's own convex hull (hull of its vertices), divided by
the whole mesh's bbox diagonal. The samples are drawn once per face of the whole mesh, so the value
of a part does not depend on how it was assembled: the reported concavities are exactly the values
the merging checked against tau.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .io import obj_text
from .mesh import Mesh, face_areas, face_components

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
    the part's face order; vertex_ids: the mesh vertex of each of the part's vertices.
    """

    labels: np.ndarray
    tau: float
    concavity: np.ndarray
    parts: tuple[Mesh, ...]
    face_ids: tuple[np.ndarray, ...]
    vertex_ids: tuple[np.ndarray, ...]

    @property
    def n_parts(self) -> int:
        return len(self.parts)


# ----------------------------------------------------------------------------------------------
# Concavity


def surface_samples(mesh: Mesh, samples_per_face: int = SAMPLES_PER_FACE, seed: int = 0) -> np.ndarray:
    """Uniform random points (F, k, 3) on every face, drawn once for the whole mesh."""
    tri = mesh.vertices[mesh.faces]
    rng = np.random.default_rng(seed)
    r = rng.random((len(tri), samples_per_face, 2))
    flip = r.sum(axis=2) > 1
    r[flip] = 1 - r[flip]
    return tri[:, None, 0] + r[..., :1] * (tri[:, None, 1] - tri[:, None, 0]) + r[..., 1:] * (tri[:, None, 2] - tri[:, None, 0])


@njit(cache=True)
def _max_depth(pts, eq, limit):
    """max_i min_j -(eq[j, :3] . pts[i] + eq[j, 3]) (>= 0); stops early once it exceeds `limit`."""
    best = 0.0
    n_f = eq.shape[0]
    hint = 0
    for i in range(pts.shape[0]):
        x, y, z = pts[i, 0], pts[i, 1], pts[i, 2]
        # The facet that bounded the previous point first: neighbouring points share facets.
        m = -(eq[hint, 0] * x + eq[hint, 1] * y + eq[hint, 2] * z + eq[hint, 3])
        if m <= best:
            continue
        for j in range(n_f):
            d = -(eq[j, 0] * x + eq[j, 1] * y + eq[j, 2] * z + eq[j, 3])
            if d < m:
                m = d
                hint = j
                if m <= best:
                    break
        if m > best:
            best = m
            if best > limit:
                return best
    return best


NOISE = 1e-12  # depths below NOISE * bbox diagonal are rounding noise of the hull planes: convex


def _denoise(depth: float, diag: float) -> float:
    return 0.0 if depth <= NOISE * diag else depth


@njit(cache=True)
def _plane(p, a, b, c):
    """Unit normal (right-hand rule a->b->c), offset d (n.x + d = 0 on the plane), and the cross
    product's length (0: degenerate triangle, the normal is then not normalized)."""
    ux, uy, uz = p[b, 0] - p[a, 0], p[b, 1] - p[a, 1], p[b, 2] - p[a, 2]
    vx, vy, vz = p[c, 0] - p[a, 0], p[c, 1] - p[a, 1], p[c, 2] - p[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    ln = math.sqrt(nx * nx + ny * ny + nz * nz)
    if ln > 0:
        nx, ny, nz = nx / ln, ny / ln, nz / ln
    return nx, ny, nz, -(nx * p[a, 0] + ny * p[a, 1] + nz * p[a, 2]), ln


@njit(cache=True)
def convex_hull(p, rel_eps):
    """3D convex hull of the points p (n, 3): (ids of hull vertices, facet equations (m, 4)).

    Facet planes are unit outward normals with offsets, n.x + d <= 0 inside (qhull's convention).
    Empty equations when the points span no volume (thinner than rel_eps * their extent).
    Incremental: start from a tetrahedron of extreme points; each point above some facets (by more
    than the tolerance) replaces them by a cone over their boundary edges, the horizon. The
    horizon is found as the edges whose reverse lies on a kept facet, so the surface stays closed
    even if rounding makes the visible region odd. O(n * facets^2): for the small sets of the
    merging, where qhull's per-call set-up (about 45 us) is most of its cost."""
    n = p.shape[0]
    empty_v = np.empty(0, dtype=np.int64)
    empty_e = np.empty((0, 4))
    if n < 4:
        return empty_v, empty_e
    ext = 0.0
    for k in range(3):
        ext = max(ext, p[:, k].max() - p[:, k].min())
    eps = rel_eps * ext
    if ext <= 0:
        return empty_v, empty_e
    # initial tetrahedron: extreme x, farthest from it, farthest from their line, farthest from the plane
    i0 = np.argmin(p[:, 0])
    i1, best = -1, -1.0
    for i in range(n):
        d = (p[i, 0] - p[i0, 0]) ** 2 + (p[i, 1] - p[i0, 1]) ** 2 + (p[i, 2] - p[i0, 2]) ** 2
        if d > best:
            best, i1 = d, i
    d01 = math.sqrt(best)
    i2, best = -1, -1.0
    for i in range(n):
        nx, ny, nz, d, ln = _plane(p, i0, i1, i)
        if ln > best:
            best, i2 = ln, i
    nx, ny, nz, d0, ln = _plane(p, i0, i1, i2)
    if ln <= eps * d01:  # all points on the line i0-i1 (ln / d01 is the distance from it)
        return empty_v, empty_e
    i3, best = -1, 0.0
    for i in range(n):
        d = nx * p[i, 0] + ny * p[i, 1] + nz * p[i, 2] + d0
        if abs(d) > abs(best):
            best, i3 = d, i
    if abs(best) <= eps:
        return empty_v, empty_e
    cap = 8 * n + 16
    F = np.empty((cap, 3), dtype=np.int64)
    E = np.empty((cap, 4))
    alive = np.zeros(cap, dtype=np.bool_)
    nf = 0
    if best > 0:  # i3 above the plane (i0, i1, i2): orient that face downwards
        i1, i2 = i2, i1
    for a, b, c in ((i0, i1, i2), (i0, i3, i1), (i1, i3, i2), (i2, i3, i0)):
        F[nf, 0], F[nf, 1], F[nf, 2] = a, b, c
        nx, ny, nz, d, ln = _plane(p, a, b, c)
        E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
        alive[nf] = True
        nf += 1
    vis = np.zeros(cap, dtype=np.bool_)
    hor = np.empty((cap, 2), dtype=np.int64)
    for i in range(n):
        if i == i0 or i == i1 or i == i2 or i == i3:
            continue
        x, y, z = p[i, 0], p[i, 1], p[i, 2]
        any_vis = False
        for f in range(nf):
            vis[f] = False
            if alive[f] and E[f, 0] * x + E[f, 1] * y + E[f, 2] * z + E[f, 3] > eps:
                vis[f] = True
                any_vis = True
        if not any_vis:
            continue
        # horizon: directed edges of visible faces whose reverse lies on an alive invisible face
        nh = 0
        for f in range(nf):
            if not vis[f]:
                continue
            for k in range(3):
                a, b = F[f, k], F[f, (k + 1) % 3]
                for g in range(nf):
                    if not alive[g] or vis[g]:
                        continue
                    if (F[g, 0] == b and F[g, 1] == a) or (F[g, 1] == b and F[g, 2] == a) or (F[g, 2] == b and F[g, 0] == a):
                        hor[nh, 0], hor[nh, 1] = a, b
                        nh += 1
                        break
        if nf + nh > cap:  # cannot happen for a consistent hull; be safe
            return empty_v, empty_e
        for f in range(nf):
            if vis[f]:
                alive[f] = False
        for h in range(nh):
            a, b = hor[h, 0], hor[h, 1]
            F[nf, 0], F[nf, 1], F[nf, 2] = a, b, i
            nx, ny, nz, d, ln = _plane(p, a, b, i)
            E[nf, 0], E[nf, 1], E[nf, 2], E[nf, 3] = nx, ny, nz, d
            alive[nf] = ln > 0
            nf += 1
        # compact when the dead faces dominate, so the loops stay short
        if nf > 2 * n + 64:
            m = 0
            for f in range(nf):
                if alive[f]:
                    F[m] = F[f]
                    E[m] = E[f]
                    alive[m] = True
                    m += 1
            nf = m
    used = np.zeros(n, dtype=np.bool_)
    m = 0
    for f in range(nf):
        if alive[f]:
            m += 1
            used[F[f, 0]] = True
            used[F[f, 1]] = True
            used[F[f, 2]] = True
    eq = np.empty((m, 4))
    m = 0
    for f in range(nf):
        if alive[f]:
            eq[m] = E[f]
            m += 1
    return np.flatnonzero(used), eq


SMALL_HULL = 64  # up to this many points our kernel; beyond, qhull (its ~45 us set-up no longer dominates)
FLAT_EPS = 1e-12  # relative to the points' extent: thinner sets have no volume (concavity 0)


def _hull(points: np.ndarray):
    """(hull vertex coordinates, facet equations) or (points, None) when the set has no volume."""
    from scipy.spatial import ConvexHull, QhullError

    if len(points) < 4:
        return points, None
    if len(points) <= SMALL_HULL:
        verts, eq = convex_hull(np.ascontiguousarray(points, dtype=np.float64), FLAT_EPS)
        return (points, None) if len(eq) == 0 else (points[verts], eq)
    try:
        h = ConvexHull(points)
    except (QhullError, ValueError):
        return points, None  # flat or degenerate: the surface is its own hull, concavity 0
    return points[h.vertices], h.equations


def part_concavity(mesh: Mesh, face_ids: np.ndarray, samples: np.ndarray | None = None, seed: int = 0) -> float:
    """Concavity of the faces `face_ids` of `mesh` relative to the bbox diagonal of the whole mesh.

    samples: `surface_samples(mesh, seed=seed)` (computed when None); this is the value
    `Segmentation.concavity` reports and that `segment` keeps <= tau.
    """
    face_ids = np.asarray(face_ids, dtype=np.int64)
    if samples is None:
        samples = surface_samples(mesh, seed=seed)
    diag = mesh.bbox_diagonal
    verts = mesh.vertices[np.unique(mesh.faces[face_ids])]
    hull_pts, eq = _hull(verts)
    if eq is None or diag <= 0:
        return 0.0
    pts = np.concatenate([verts, samples[face_ids].reshape(-1, 3)])
    return _denoise(float(_max_depth(pts, eq, np.inf)), diag) / diag


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


class _Cluster:
    __slots__ = ("faces", "pts", "hull", "conc", "area", "perim", "nbrs", "key")

    def __init__(self, faces, pts, hull, conc, area, perim, key):
        self.faces = faces  # int64 array of mesh faces
        self.pts = pts  # (n, 3) vertices + surface samples
        self.hull = hull  # (h, 3) hull vertex coordinates (all points when flat)
        self.conc = conc  # absolute concavity (not divided by the diagonal)
        self.area = area
        self.perim = perim
        self.nbrs: dict[int, list[float]] = {}  # neighbour -> [shared length, concave-weighted length]
        self.key = key


class _Merger:
    """Dual-graph state shared by all runs on one mesh (memoizes union concavities)."""

    def __init__(self, mesh: Mesh, seed: int):
        self.mesh = mesh
        self.diag = mesh.bbox_diagonal
        self.samples = surface_samples(mesh, seed=seed)
        topo = mesh.topology
        self.areas = face_areas(mesh.vertices, mesh.faces)
        e = topo.edges
        self.edge_len = np.linalg.norm(mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]], axis=1)
        self.rho = mesh.fold_angles
        # Perimeter of each face counted over all its edges; shared edges are subtracted on merges.
        self.face_perim = self.edge_len[topo.face_edges].sum(axis=1)
        inner = np.flatnonzero(topo.interior)
        self.inner = inner
        self.ef = topo.edge_faces[inner]
        self.cache: dict[tuple, tuple[float, bool, np.ndarray | None]] = {}
        self.made: dict[int, tuple] = {}
        self.polygon = _polygon_groups(mesh)

    # -- clusters --------------------------------------------------------------------------------
    def make(self, faces: np.ndarray) -> _Cluster:
        faces = np.sort(np.asarray(faces, dtype=np.int64))
        key = hash(faces.tobytes())
        # Every run (one per tau tried by `parts=K`) starts from the same seed clusters: their
        # hulls are computed once. A fresh _Cluster each time: its neighbour dict is per run.
        known = self.made.get(key)
        if known is None:
            verts = np.unique(self.mesh.faces[faces])
            vpts = self.mesh.vertices[verts]
            pts = np.concatenate([vpts, self.samples[faces].reshape(-1, 3)])
            hull, eq = _hull(vpts)
            conc = 0.0 if eq is None else _denoise(float(_max_depth(pts, eq, np.inf)), self.diag)
            known = self.made[key] = (faces, pts, hull, conc, float(self.areas[faces].sum()),
                                      float(self.face_perim[faces].sum()), key)
        return _Cluster(*known)

    def union_conc(self, a: _Cluster, b: _Cluster, limit: float) -> tuple[float, bool, np.ndarray]:
        """(absolute concavity of a u b, exact?, hull points of a u b); inexact values exceed limit."""
        key = (a.key, b.key) if a.key < b.key else (b.key, a.key)
        hit = self.cache.get(key)
        if hit is not None and (hit[1] or hit[0] > limit):
            return hit
        floor = max(a.conc, b.conc)  # a u b is at least as concave as either part
        if floor > limit:  # decided without a hull (most candidate pairs once clusters grow)
            self.cache[key] = res = (floor, False, None)
            return res
        if len(a.faces) + len(b.faces) == 2:
            # two triangles sharing an edge are two faces of their tetrahedron: concavity 0
            self.cache[key] = res = (0.0, True, np.concatenate([a.hull, b.hull]))
            return res
        hull_pts, eq = _hull(np.concatenate([a.hull, b.hull]))
        if eq is None:
            res = (0.0, True, hull_pts)
        else:
            # the kernel stops early (a lower bound) once the depth exceeds the limit; rounding
            # noise must not count as exceeding it
            stop = max(limit, NOISE * self.diag)
            d = float(_max_depth(np.concatenate([a.pts, b.pts]), eq, stop))
            res = (_denoise(d, self.diag), d <= stop, hull_pts)
        self.cache[key] = res
        return res


def _union_labels(n: int, f0: np.ndarray, f1: np.ndarray) -> np.ndarray:
    """Connected-component label of each of n faces, joined by the face pairs (f0[i], f1[i])."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    _, labels = connected_components(coo_matrix((np.ones(len(f0)), (f0, f1)), shape=(n, n)), directed=False)
    return labels


def _polygon_groups(mesh: Mesh) -> np.ndarray:
    """Label of each face: triangles of one input polygon (same face_source, edge-joined) share it.

    A polygon is one face of the user's file, so it must never be split between parts."""
    topo = mesh.topology
    ef = topo.edge_faces[topo.interior]
    same = mesh.face_source[ef[:, 0]] == mesh.face_source[ef[:, 1]]
    return _union_labels(mesh.n_faces, ef[same, 0], ef[same, 1])


def _seed_clusters(mesh: Mesh, angle_deg: float) -> np.ndarray:
    """Label of each face: faces joined across edges with rho >= -angle (locally convex regions),
    and across the inner edges of triangulated input polygons."""
    topo = mesh.topology
    ef = topo.edge_faces
    keep = topo.interior & (mesh.fold_angles >= -math.radians(angle_deg))
    keep |= topo.interior & (mesh.face_source[ef[:, 0]] == mesh.face_source[np.maximum(ef[:, 1], 0)])
    return _union_labels(mesh.n_faces, ef[keep, 0], ef[keep, 1])


def _groups(labels: np.ndarray, items: np.ndarray | None = None) -> list[np.ndarray]:
    """The items (default: indices) grouped by label, groups ordered by label value."""
    order = np.argsort(labels, kind="stable")
    _, start = np.unique(labels[order], return_index=True)
    items = order if items is None else np.asarray(items)[order]
    return np.split(items, start[1:])


def _run(m: _Merger, tau: float, target: int | None, seed_labels: np.ndarray,
         w_compact: float = W_COMPACT, w_seam: float = W_SEAM, min_faces: int = MIN_FACES) -> list[np.ndarray]:
    """One merging run: the face lists of the parts (tau absolute; stop at `target` clusters)."""
    mesh = m.mesh
    limit = tau * m.diag * (1 - 1e-9)  # margin: the final re-measure may differ by rounding
    clusters: dict[int, _Cluster] = {}
    label = np.empty(mesh.n_faces, dtype=np.int64)
    nid = 0
    for g in _groups(seed_labels):
        c = m.make(g)
        if c.conc > limit:
            # too concave a seed: restart from its polygons (single triangles unless the file had
            # polygons, which stay whole: a flat polygon has concavity 0)
            subs = [m.make(sub) for sub in _groups(m.polygon[g], g)]
        else:
            subs = [c]
        for s in subs:
            clusters[nid] = s
            label[s.faces] = nid
            nid += 1
    # Adjacency with shared and concave-weighted lengths.
    la, lb = label[m.ef[:, 0]], label[m.ef[:, 1]]
    length = m.edge_len[m.inner]
    conc_w = length * np.clip(-m.rho[m.inner], 0.0, None) / (math.pi / 2)
    for x, y, ln, cw in zip(la.tolist(), lb.tolist(), length.tolist(), conc_w.tolist()):
        if x == y:
            continue
        for p, q in ((x, y), (y, x)):
            rec = clusters[p].nbrs.get(q)
            if rec is None:
                clusters[p].nbrs[q] = [ln, cw]
            else:
                rec[0] += ln
                rec[1] += cw

    scale = limit if limit > 0 and math.isfinite(limit) else m.diag

    def cost(a: _Cluster, b: _Cluster, shared: list[float], conc: float) -> float:
        area = a.area + b.area
        perim = a.perim + b.perim - 2 * shared[0]
        compact = perim * perim / (4 * math.pi * area) - 1.0 if area > 0 else 0.0
        seam = shared[1] / shared[0] if shared[0] > 0 else 0.0
        return conc + (w_compact * compact + w_seam * seam) * scale

    heap: list = []

    def push(i: int, j: int) -> None:
        # Lazy: the key is a lower bound (a u b is at least as concave as a or b); the exact union
        # concavity (a convex hull) is computed only when the pair reaches the top of the heap.
        a, b = clusters[i], clusters[j]
        floor = max(a.conc, b.conc)
        if floor > limit:
            return
        heapq.heappush(heap, (cost(a, b, a.nbrs[j], floor), 0, i, j))

    def push_exact(i: int, j: int) -> None:
        a, b = clusters[i], clusters[j]
        conc, exact, _ = m.union_conc(a, b, limit)
        if not exact or conc > limit:  # (the memo may hold exact values from runs with a larger tau)
            return
        heapq.heappush(heap, (cost(a, b, a.nbrs[j], conc), 1, i, j))

    for i, c in clusters.items():
        for j in c.nbrs:
            if i < j:
                push(i, j)

    def merge(i: int, j: int) -> int:
        nonlocal nid
        a, b = clusters.pop(i), clusters.pop(j)
        conc, exact, hull_pts = m.union_conc(a, b, limit)
        shared = a.nbrs[j]
        faces = np.sort(np.concatenate([a.faces, b.faces]))
        c = _Cluster(faces, np.concatenate([a.pts, b.pts]), hull_pts, conc, a.area + b.area,
                     a.perim + b.perim - 2 * shared[0], hash(faces.tobytes()))
        for src in (a, b):
            for k, rec in src.nbrs.items():
                if k in (i, j):
                    continue
                other = clusters[k]
                got = c.nbrs.get(k)
                if got is None:
                    c.nbrs[k] = list(rec)
                else:
                    got[0] += rec[0]
                    got[1] += rec[1]
                other.nbrs.pop(i, None)
                other.nbrs.pop(j, None)
                other.nbrs[nid] = c.nbrs[k]
        clusters[nid] = c
        nid += 1
        return nid - 1

    stop = 1 if target is None else target
    while heap and len(clusters) > stop:
        _, exact, i, j = heapq.heappop(heap)
        if i not in clusters or j not in clusters:  # a merged cluster: its ids are never reused
            continue
        if not exact:
            push_exact(i, j)
            continue
        k = merge(i, j)
        for n in list(clusters[k].nbrs):
            push(k, n)

    # Small parts join the neighbour with the cheapest admissible merge.
    changed = True
    while changed and len(clusters) > stop:
        changed = False
        for i in sorted(clusters, key=lambda t: len(clusters[t].faces)):
            c = clusters.get(i)
            if c is None or len(c.faces) >= min_faces:
                continue
            best = None
            for j in c.nbrs:
                conc, exact, _ = m.union_conc(c, clusters[j], limit)
                if exact and conc <= limit:
                    cst = cost(c, clusters[j], c.nbrs[j], conc)
                    if best is None or cst < best[0]:
                        best = (cst, j)
            if best is not None:
                merge(i, best[1])
                changed = True
                break
    return [c.faces for c in clusters.values()]


def segment(mesh: Mesh, tau: float = DEFAULT_TAU, parts: int | None = None, seed: int = 0) -> Segmentation:
    """Decompose `mesh` into edge-connected parts whose concavity is <= tau (relative to the bbox
    diagonal of the whole mesh).

    parts=K: choose tau (bisection, the `tau` argument is then ignored) so the result has K parts;
    when no tau gives exactly K (the count jumps past K), merging continues past the last tau in
    cost order until K parts remain, and the reported tau is the largest part concavity. The count
    is bounded below by the number of edge-connected components and above by the count at tau 0
    (already-convex pieces are not split further), so the result may have fewer or more than K.
    seed: seeds the surface samples of the concavity metric.
    """
    if mesh.n_faces == 0:
        raise ValueError("empty mesh")
    if not (tau >= 0 and math.isfinite(tau)):
        raise ValueError(f"tau must be a non-negative number, not {tau!r}")
    m = _Merger(mesh, seed)
    seeds = _seed_clusters(mesh, SEED_ANGLE_DEG)
    if parts is None:
        groups = _run(m, tau, None, seeds)
    else:
        groups, tau = _fit_parts(m, seeds, int(parts))
    return _finish(m, groups, tau)


def _fit_parts(m: _Merger, seeds: np.ndarray, k: int) -> tuple[list[np.ndarray], float]:
    """Parts and tau for `parts=k`: the default tau when it already gives k parts (so `segment()`
    and `segment(parts=k)` agree), else a bisection on tau from the default towards k."""
    mesh = m.mesh
    comp = face_components(mesh.n_faces, mesh.topology)
    n_comp = int(comp.max()) + 1
    k = int(min(max(k, n_comp), mesh.n_faces))
    g = _run(m, DEFAULT_TAU, None, seeds)
    if len(g) == k:
        return g, DEFAULT_TAU
    if len(g) > k:
        lo, hi = DEFAULT_TAU, None
    else:
        lo, hi = 0.0, DEFAULT_TAU
        g0 = _run(m, 0.0, None, seeds)
        if len(g0) <= k:  # even tau 0 gives no more parts: already-convex pieces stay whole
            return g0, 0.0
    if hi is None:
        # every component as one part is admissible at its own concavity
        hi = max(part_concavity(mesh, np.flatnonzero(comp == c), m.samples) for c in range(n_comp)) * 1.001
        hi = max(hi, lo * 1.001)
        g = _run(m, hi, None, seeds)
        if len(g) == k:
            return g, hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        g = _run(m, mid, None, seeds)
        if len(g) == k:
            return g, mid
        if len(g) > k:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-6:
            break
    # No tau gives exactly k: merge on past tau (hi) until k parts, report the largest concavity.
    g = _run(m, hi, k, seeds)
    conc = max(part_concavity(mesh, f, m.samples) for f in g)
    return g, max(conc, lo)


def _finish(m: _Merger, groups: list[np.ndarray], tau: float) -> Segmentation:
    mesh = m.mesh
    # Order parts by their first face so labels are stable and readable.
    groups = sorted((np.sort(g) for g in groups), key=lambda g: int(g[0]))
    labels = np.empty(mesh.n_faces, dtype=np.int64)
    for p, g in enumerate(groups):
        labels[g] = p
    conc = np.array([part_concavity(mesh, g, m.samples) for g in groups])
    subs = tuple(mesh.submesh(g) for g in groups)
    vids = tuple(np.unique(mesh.faces[g]) for g in groups)
    return Segmentation(labels=labels, tau=float(tau), concavity=conc, parts=subs, face_ids=tuple(groups), vertex_ids=vids)


# ----------------------------------------------------------------------------------------------
# Output


def input_face_labels(seg: Segmentation, face_source: np.ndarray, n_input_faces: int) -> np.ndarray:
    """Part of every face of the input FILE (length n_input_faces, file order; -1 for faces the
    loader dropped as degenerate or duplicate). face_source: the segmented mesh's face_source."""
    out = np.full(max(int(n_input_faces), int(face_source.max()) + 1 if len(face_source) else 0), -1, dtype=np.int64)
    out[face_source] = seg.labels  # triangles of one polygon share a part (see _polygon_groups)
    return out


def write_segmentation(seg: Segmentation, mesh: Mesh, out_dir, *, n_input_faces: int | None = None,
                       source_name: str = "mesh", png: bool = True) -> list[str]:
    """Write the parts into `out_dir` and return the file names written.

    part-K.obj (one per part, faces in the part's order), labels.json ({"labels": part of each
    input face, "tau", "concavity": per part, plus "faces" per part}), segments.ply (the whole
    mesh, one colour per part, as face colours), segments.glb (same colours as vertex colours on
    unshared vertices, since glTF has no face colours) and, unless png=False, segments.png.
    Everything is written to a temporary folder beside out_dir first and then moved in, so an
    error never leaves half the files; stale part-K.obj files of an earlier run are removed."""
    import json
    import os
    import shutil
    import tempfile
    from pathlib import Path

    import trimesh

    from .raster import part_colors, write_mesh_png

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".polyfold-segment-", dir=out))
    try:
        names = []
        for k, part in enumerate(seg.parts):
            name = f"part-{k}.obj"
            (tmp / name).write_text(obj_text(part.vertices, part.faces, [
                f"part {k} of {seg.n_parts} of {source_name}, segmented by polyfold (tau {seg.tau:.6g})",
                f"{part.n_faces} faces, concavity {seg.concavity[k]:.6g} of the whole mesh's bbox diagonal"]))
            names.append(name)
        n_in = mesh.n_faces if n_input_faces is None else n_input_faces
        labels = input_face_labels(seg, mesh.face_source, n_in)
        doc = {"labels": labels.tolist(), "tau": float(seg.tau), "concavity": [float(c) for c in seg.concavity],
               "faces": [int(p.n_faces) for p in seg.parts], "source": source_name}
        (tmp / "labels.json").write_text(json.dumps(doc) + "\n")
        names.append("labels.json")
        colors = part_colors(seg.n_parts)[seg.labels]
        rgba = np.concatenate([colors, np.full((len(colors), 1), 255, np.uint8)], axis=1)
        tm = trimesh.Trimesh(mesh.vertices, mesh.faces, face_colors=rgba, process=False)
        (tmp / "segments.ply").write_bytes(tm.export(file_type="ply"))
        flat = trimesh.Trimesh(mesh.vertices[mesh.faces].reshape(-1, 3), np.arange(3 * mesh.n_faces).reshape(-1, 3),
                               vertex_colors=np.repeat(rgba, 3, axis=0), process=False)
        (tmp / "segments.glb").write_bytes(flat.export(file_type="glb"))
        names += ["segments.ply", "segments.glb"]
        if png:
            write_mesh_png(tmp / "segments.png", mesh.vertices, mesh.faces, colors)
            names.append("segments.png")
        for old in out.glob("part-*.obj"):
            if old.name not in names:
                old.unlink()
        for name in names:
            os.replace(tmp / name, out / name)
        return names
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
