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

A merging run is one numba kernel (`_segment_kernels.merge_run`). The union concavity uses cached
hulls (the hull of A u B is the hull of the two hulls' vertices) and a depth kernel with early
exit; evaluations are memoized across runs, so `parts=K` (a bisection on tau) re-uses most of
them. Merging adjacent connected clusters keeps every part edge-connected.

Concavity (`part_concavity`): max over the part's vertices plus SAMPLES_PER_FACE seeded surface
samples per face of the depth below the part's own convex hull (hull of its vertices), divided by
the whole mesh's bbox diagonal. The samples are drawn once per face of the whole mesh, so the value
of a part does not depend on how it was assembled: the reported concavities are exactly the values
the merging checked against tau.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._segment_kernels import FLAT_EPS, convex_hull, denoise, make_units, max_depth, merge_run, new_memo, union_labels
from .io import obj_text
from .mesh import Mesh, face_areas

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


SMALL_HULL = 64  # up to this many points our kernel; beyond, qhull (its ~45 us set-up no longer dominates)


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
    return denoise(float(max_depth(pts, eq, np.inf)), diag) / diag


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
    the candidate initial clusters of each seed labelling, and the memo of union concavities."""

    def __init__(self, mesh: Mesh, seed: int):
        self.mesh = mesh
        self.diag = mesh.bbox_diagonal
        self.samples = np.ascontiguousarray(surface_samples(mesh, seed=seed))
        topo = mesh.topology
        self.areas = face_areas(mesh.vertices, mesh.faces)
        e = topo.edges
        edge_len = np.linalg.norm(mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]], axis=1)
        # Perimeter of each face counted over all its edges; shared edges are subtracted on merges.
        self.face_perim = edge_len[topo.face_edges].sum(axis=1)
        inner = np.flatnonzero(topo.interior)
        self.ef0 = np.ascontiguousarray(topo.edge_faces[inner, 0])
        self.ef1 = np.ascontiguousarray(topo.edge_faces[inner, 1])
        self.inner_len = edge_len[inner]
        self.inner_conc = self.inner_len * np.clip(-mesh.fold_angles[inner], 0.0, None) / (math.pi / 2)
        # random 64-bit face keys: a cluster's key is their sum (see _segment_kernels.new_memo)
        self.face_key = np.random.default_rng(0x5E6).integers(0, 2**64 - 1, mesh.n_faces, dtype=np.uint64, endpoint=True)
        self.memo = new_memo(mesh.n_faces)
        self.polygon = _polygon_groups(mesh)
        self._units: dict[bytes, tuple] = {}

    def units(self, seed_labels: np.ndarray) -> tuple:
        """The candidate initial clusters for these seeds: each seed, then its input polygons
        (used when the seed is too concave), with points, hulls, concavities, areas, perimeters."""
        got = self._units.get(seed_labels.tobytes())
        if got is not None:
            return got
        groups = []
        seed_unit, sub_lo, sub_hi = [], [], []
        for g in _groups(seed_labels):
            seed_unit.append(len(groups))
            groups.append(g)
            subs = _groups(self.polygon[g], g)
            sub_lo.append(len(groups))
            groups += subs
            sub_hi.append(len(groups))
        mesh = self.mesh
        start = np.concatenate([[0], np.cumsum([len(g) for g in groups])]).astype(np.int64)
        faces = np.concatenate(groups).astype(np.int64)
        pts, pstart, hulls, conc, self.memo = make_units(faces, start, mesh.faces, mesh.vertices, self.samples, self.diag, self.memo)
        area = np.add.reduceat(self.areas[faces], start[:-1])
        perim = np.add.reduceat(self.face_perim[faces], start[:-1])
        got = (np.array(seed_unit, dtype=np.int64), np.array(sub_lo, dtype=np.int64), np.array(sub_hi, dtype=np.int64),
               faces, start, pts, pstart, hulls, conc, area, perim)
        self._units[seed_labels.tobytes()] = got
        return got


def _union_labels(n: int, f0: np.ndarray, f1: np.ndarray) -> np.ndarray:
    """Connected-component label of each of n faces, joined by the face pairs (f0[i], f1[i])."""
    return union_labels(n, np.ascontiguousarray(f0, dtype=np.int64), np.ascontiguousarray(f1, dtype=np.int64))


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
    """One merging run: the face lists of the parts (tau absolute; stop at `target` clusters).
    The merging itself is `_segment_kernels.merge_run`."""
    limit = tau * m.diag * (1 - 1e-9)  # margin: the final re-measure may differ by rounding
    scale = limit if limit > 0 and math.isfinite(limit) else m.diag
    units = m.units(seed_labels)
    label, n, m.memo = merge_run(limit, scale, -1 if target is None else int(target), float(w_compact), float(w_seam),
                                 int(min_faces), m.diag, units, (m.face_key, m.ef0, m.ef1, m.inner_len, m.inner_conc), m.memo)
    return _groups(label)


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
    comp = _union_labels(mesh.n_faces, m.ef0, m.ef1)  # edge-connected components
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
