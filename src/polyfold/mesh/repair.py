"""Checking and repairing loaded meshes: reject what cannot be used, repair what can, split into
components (files are read by `formats.meshes`, which calls `repair`).

The repair pipeline runs in a fixed order because each step relies on the one before:
parse -> reject checks -> drop degenerate faces -> weld coincident vertices -> drop duplicate
faces -> drop unused vertices -> reject non-manifold edges -> split non-manifold vertices ->
orient (consistently, closed components outward) -> components.

Every message names indices in the INPUT file's numbering, 0-based (faces in file order, before
triangulation), so a user can find the culprit in their file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshError
from ..graphs import breadth_first_predecessors, connected_components, summed_weights
from .appearance import Appearance
from .geometry import concavity, face_areas, signed_volumes
from .mesh import boundary_loops, edge_topology, face_components, Mesh, Topology


DEGENERATE_AREA = 1e-12  # a face is degenerate when its area <= this * (its longest side)**2: its corners
# (nearly) on one line, whatever its size; a tiny face of a tiny part beside a huge one is not degenerate


WELD_TOLERANCE = 1e-9  # vertices whose positions agree after rounding to this * bbox_diag are welded,
WELD_EDGE = 1e-3  # or to this * the shortest side of a face, when less (a tiny part beside a huge one)
SIZE_RANGE = (1e-30, 1e30)  # a model whose size is outside this is scaled by a power of two into it


@dataclass(frozen=True, eq=False)
class LoadedMesh:
    """A loaded, repaired mesh.

    mesh: the whole mesh (all components), faces CCW seen from outside; components: its
    edge-connected components, each its own Mesh (vertices renumbered); face_source everywhere is
    the face's index in the input file's face order (n_input_faces of them; faces dropped as
    degenerate or duplicate have no triangle). warnings: one line per repair / notable fact.
    manifold / oriented: facts about the INPUT (False when a non-manifold vertex had to be split /
    when faces had to be flipped), for `describe`.
    """

    path: str
    mesh: Mesh
    components: tuple[Mesh, ...]
    warnings: tuple[str, ...]
    manifold: bool = True
    oriented: bool = True
    n_input_faces: int = -1  # faces in the file (before triangulation and repairs); -1 if unknown
    appearance: Appearance | None = None  # the look of each face of `mesh` (None: the file has none)


@dataclass
class RawMesh:
    vertices: np.ndarray  # (n, 3) float64, as in the file
    tris: np.ndarray  # (m, 3) int64, 0-based vertex indices as in the file (may be out of range)
    source: np.ndarray  # (m,) index of the file face each triangle comes from
    n_triangulated: int  # file faces with more than 3 corners
    face_lines: list[int] | None = None  # line number of each file face (text formats only)
    vertex_lines: list[int] | None = None  # line number of each vertex (text formats only)
    appearance: Appearance | None = None  # the look of each triangle of `tris` (None: the file has none)
    warnings: tuple[str, ...] = ()  # what the reader could not use (a missing texture, ...): said, not fatal


def mesh_error(name: str, message: str) -> MeshError:
    """A MeshError whose message is one line starting with the file name."""
    return MeshError(" ".join(f"{name}: {message}".split()))


def _plural(n: int, word: str, plural: str | None = None) -> str:
    return f"{n} {word if n == 1 else (plural or word + 's')}"


def check_input(p: RawMesh, name: str) -> None:
    """The reject checks that need no repair: no faces, bad index, non-finite coordinate."""
    if len(p.tris) == 0:
        raise mesh_error(name, "no faces")
    n = len(p.vertices)
    bad = (p.tris < 0) | (p.tris >= n)
    if bad.any():
        t, k = np.argwhere(bad)[0]
        face = int(p.source[t])
        where = f" (line {p.face_lines[face]})" if p.face_lines else ""
        raise mesh_error(
            name,
            f"face {face}{where} refers to vertex {int(p.tris[t, k])}, past the end of the "
            f"{n}-vertex list (indices counted from 0)",
        )
    finite = np.isfinite(p.vertices).all(axis=1)
    if not finite.all():
        v = int(np.flatnonzero(~finite)[0])
        where = f" (line {p.vertex_lines[v]})" if p.vertex_lines else ""
        raise mesh_error(name, f"vertex {v} has a non-finite coordinate{where}")


def _bbox_diagonal(vertices: np.ndarray, faces: np.ndarray) -> float:
    used = vertices[np.unique(faces)]
    return float(np.linalg.norm(used.max(0) - used.min(0)))


def _repeated_index(faces: np.ndarray) -> np.ndarray:
    return (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])


def _weld_map(vertices: np.ndarray, faces: np.ndarray, step: float) -> np.ndarray:
    """Map (n,) from each vertex to the lowest-index referenced vertex at the same position
    rounded to `step` (relative to the model's size: the test is scale-free)."""
    used = np.unique(faces)
    lo = vertices[used].min(axis=0)
    if step <= 0.0:
        step = 1.0  # every side has length 0: all corners coincide anyway
    # offsets from `lo` keep the keys in int64 (a model's span over `step` is at most ~1e12)
    key = np.round((vertices[used] - lo) / step).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    remap = np.arange(len(vertices), dtype=np.int64)
    remap[used] = used[first][inverse.reshape(-1)]
    return remap


def _half_edge_pairs(topo: Topology) -> tuple[np.ndarray, np.ndarray]:
    """For every edge with exactly two faces, its two half-edges h = 3*face + corner.

    Half-edge h runs from corner h%3 to corner (h%3+1)%3 of face h//3.
    """
    e = topo.face_edges.reshape(-1)
    order = np.argsort(e, kind="stable")
    two = topo.face_count[e[order]] == 2
    order = order[two]  # half-edges of two-face edges, grouped by edge in pairs
    return order[0::2], order[1::2]


def _next_corner(h: np.ndarray) -> np.ndarray:
    return 3 * (h // 3) + (h % 3 + 1) % 3


def _split_fans(faces: np.ndarray, topo: Topology) -> tuple[np.ndarray, np.ndarray]:
    """Give every fan of faces around a vertex its own vertex (fans = faces joined by edges at it).

    Returns (new faces, old vertex of each new vertex). New vertices are numbered in the order of
    the old ones, so nothing changes when every vertex is a single fan.
    """
    h0, h1 = _half_edge_pairs(topo)
    flat = faces.reshape(-1)
    # Corners are nodes; across each two-face edge the corners holding the same vertex are joined.
    # When the faces run the edge the same way (not yet oriented) the matching corners are swapped.
    same = flat[h0] == flat[h1]
    t0, t1 = _next_corner(h0), _next_corner(h1)
    u = np.concatenate([h0, t0])
    v = np.concatenate([np.where(same, h1, t1), np.where(same, t1, h1)])
    n = len(flat)
    n_fans, fan = connected_components(n, u, v)
    if n_fans == len(np.unique(flat)):
        return faces, np.arange(faces.max() + 1)
    # Number the fans by (old vertex, first corner) so the order follows the old numbering.
    first_corner = np.full(n_fans, n, dtype=np.int64)
    np.minimum.at(first_corner, fan, np.arange(n))
    old_vertex = flat[first_corner]
    order = np.lexsort((first_corner, old_vertex))
    rank = np.empty(n_fans, dtype=np.int64)
    rank[order] = np.arange(n_fans)
    return rank[fan].reshape(-1, 3), old_vertex[order]


def _vertex_components(faces: np.ndarray) -> int:
    """Number of groups of faces connected through shared vertices."""
    m, n = len(faces), int(faces.max()) + 1
    rows = np.repeat(np.arange(m), 3)
    _, labels = connected_components(m + n, rows, m + faces.reshape(-1))
    return len(np.unique(labels[:m]))


def _orientation_parity(faces: np.ndarray, topo: Topology) -> tuple[np.ndarray, tuple[int, int] | None]:
    """Which faces to flip (bool (m,)) so each component is consistently oriented.

    BFS over the dual graph from the lowest face of each component; the side holding fewer faces is
    the one flipped, so the count is the number of "wrong" faces. Returns (flip, None), or
    (_, (half-edge, half-edge)) of an edge whose faces cannot agree (non-orientable component).
    """
    m = len(faces)
    h0, h1 = _half_edge_pairs(topo)
    flat = faces.reshape(-1)
    f0, f1 = h0 // 3, h1 // 3
    same = (flat[h0] == flat[h1]).astype(np.int64)  # 1: both faces run the edge the same way
    labels = face_components(m, topo)
    roots = np.unique(labels, return_index=True)[1]
    # A virtual node m joined to every component's root lets one BFS cover the whole forest.
    u = np.concatenate([f0, np.full(len(roots), m)])
    v = np.concatenate([f1, roots])
    w = np.concatenate([same, np.zeros(len(roots), dtype=np.int64)]) + 1  # +1: keep zeros stored
    pred = breadth_first_predecessors(m + 1, u, v, m)[:m]
    weight = summed_weights(m + 1, u, v, w, pred, np.arange(m)).astype(np.int64) - 1  # (both ways, repeats summed)
    # parity = XOR of edge weights on the tree path to the root, by pointer jumping.
    parity, up = weight.copy(), pred.copy()
    while (up != m).any():
        live = up != m
        parity[live] ^= parity[up[live]]
        up[live] = np.append(up, m)[up[live]]
    bad = (parity[f0] ^ parity[f1]) != same
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        return parity.astype(bool), (int(h0[i]), int(h1[i]))
    ones = np.bincount(labels, weights=parity, minlength=labels.max() + 1)
    sizes = np.bincount(labels)
    minority_is_zero = ones > sizes - ones  # ties keep the root face's orientation
    return (parity ^ minority_is_zero[labels]).astype(bool), None


def _edges_cross(a: Mesh, b: Mesh, lo: np.ndarray, hi: np.ndarray, chunk: int = 1 << 20) -> bool:
    """Does an edge of `a` cross a triangle of `b`? Only candidates inside the box [lo, hi].

    A crossing needs the edge's endpoints strictly on opposite sides of the triangle's plane and
    the crossing point inside the closed triangle (signs of three orientation determinants), so
    components that only touch do not count.
    """
    edges = a.vertices[a.topology.edges]
    keep = (edges.max(axis=1) >= lo).all(1) & (edges.min(axis=1) <= hi).all(1)
    tri = b.vertices[b.faces]
    tkeep = (tri.max(axis=1) >= lo).all(1) & (tri.min(axis=1) <= hi).all(1)
    edges, tri = edges[keep], tri[tkeep]
    if len(edges) == 0 or len(tri) == 0:
        return False
    A, B, C = tri[:, 0], tri[:, 1], tri[:, 2]
    normal = np.cross(B - A, C - A)
    offset = np.einsum("ij,ij->i", normal, A)
    step = max(1, chunk // len(tri))
    for s in range(0, len(edges), step):
        P, Q = edges[s : s + step, 0], edges[s : s + step, 1]
        sp = P @ normal.T - offset
        sq = Q @ normal.T - offset
        ei, ti = np.nonzero(sp * sq < 0)
        if len(ei) == 0:
            continue
        p, d = P[ei], Q[ei] - P[ei]
        a_, b_, c_ = A[ti] - p, B[ti] - p, C[ti] - p
        s1 = np.einsum("ij,ij->i", d, np.cross(a_, b_))
        s2 = np.einsum("ij,ij->i", d, np.cross(b_, c_))
        s3 = np.einsum("ij,ij->i", d, np.cross(c_, a_))
        inside = ((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))
        if inside.any():
            return True
    return False


def _intersecting_components(components: tuple[Mesh, ...]) -> list[tuple[int, int]]:
    """Pairs of components whose surfaces cross each other (AABB test first, then exact)."""
    lo = np.array([c.vertices.min(axis=0) for c in components])
    hi = np.array([c.vertices.max(axis=0) for c in components])
    # Sweep along x: only boxes starting inside [lo_i.x, hi_i.x] can overlap box i (no k x k matrix,
    # a badly fragmented file may have thousands of components).
    order = np.argsort(lo[:, 0], kind="stable")
    starts = lo[order, 0]
    pairs = []
    for rank, i in enumerate(order):
        cand = order[rank + 1 : np.searchsorted(starts, hi[i, 0], side="right")]
        cand = cand[(lo[cand] <= hi[i]).all(axis=1) & (hi[cand] >= lo[i]).all(axis=1)]
        for j in cand:
            box_lo, box_hi = np.maximum(lo[i], lo[j]), np.minimum(hi[i], hi[j])
            a, b = components[i], components[j]
            if _edges_cross(a, b, box_lo, box_hi) or _edges_cross(b, a, box_lo, box_hi):
                pairs.append((int(min(i, j)), int(max(i, j))))
    return sorted(pairs)


@dataclass
class _Work:
    """The mesh being repaired. `corners` holds the input vertex id of every corner (parallel to
    `faces`) and `source` the input face of every face, so messages can use input numbering."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    corners: np.ndarray
    source: np.ndarray
    notes: dict[str, str] = field(default_factory=dict)  # kind of repair -> its warning line
    degenerate: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # dropped faces
    tri: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # the parsed triangle of each face

    def keep(self, mask: np.ndarray) -> None:
        self.faces, self.corners, self.source = self.faces[mask], self.corners[mask], self.source[mask]
        self.tri = self.tri[mask]


def _drop_degenerate(w: _Work) -> None:
    """Drop faces with a repeated index or (near) zero area for their size (DEGENERATE_AREA)."""
    longest = _side_lengths(w.vertices, w.faces).max(axis=1)
    bad = _repeated_index(w.faces) | (face_areas(w.vertices, w.faces) <= DEGENERATE_AREA * longest**2)
    _note_degenerate(w, w.source[bad])
    w.keep(~bad)


def _side_lengths(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F, 3) lengths of the sides of every face."""
    tri = vertices[faces]
    return np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)


def _normalise(w: _Work) -> None:
    """Scale a model whose size (largest bounding-box side) lies outside SIZE_RANGE by a power of
    two (exact) into it: its squares and products would overflow or vanish in float64."""
    used = w.vertices[np.unique(w.faces)]
    size = float((used.max(axis=0) - used.min(axis=0)).max())
    if size == 0.0 or SIZE_RANGE[0] <= size <= SIZE_RANGE[1]:
        return
    k = -int(round(np.log2(size)))
    w.vertices = np.ldexp(w.vertices, k)
    w.notes["scaled"] = (f"the model's size {size:.3g} is outside {SIZE_RANGE[0]:g}..{SIZE_RANGE[1]:g}: "
                         f"coordinates scaled by 2^{k} (outputs are in those units)")


def _note_degenerate(w: _Work, dropped: np.ndarray) -> None:
    """Record dropped degenerate faces (called before and after welding; one combined note)."""
    w.degenerate = np.sort(np.concatenate([w.degenerate, dropped]))
    if len(w.degenerate):
        w.notes["degenerate"] = (
            f"dropped {_plural(len(w.degenerate), 'degenerate face')} (repeated vertex or zero area, "
            f"e.g. face {w.degenerate[0]})"
        )


def _first_copies(faces: np.ndarray) -> np.ndarray:
    """Mask keeping the first of every group of faces with the same vertex set."""
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    keep = np.zeros(len(faces), dtype=bool)
    keep[first] = True
    return keep


def _weld(w: _Work) -> None:
    """Weld vertices at identical positions (triangle soups, seams); faces that collapse are dropped.

    A weld that would make an edge non-manifold without closing anything is undone for the
    vertices of that edge: two separate vertices at one position (a pinched surface) stay apart.
    """
    sides = _side_lengths(w.vertices, w.faces)
    shortest = float(sides[sides > 0].min()) if (sides > 0).any() else 0.0
    step = min(WELD_TOLERANCE * _bbox_diagonal(w.vertices, w.faces), WELD_EDGE * shortest)
    welded = _weld_map(w.vertices, w.faces, step)[w.faces]
    welded = _unweld_nonmanifold(welded, w.corners)
    w.faces = welded
    collapsed = _repeated_index(w.faces)
    _note_degenerate(w, w.source[collapsed])
    w.keep(~collapsed)


def _unweld_nonmanifold(faces: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Restore the input ids at welded endpoints of non-manifold edges, when that opens no boundary."""
    if np.array_equal(faces, corners):
        return faces  # nothing was welded
    ok = ~_repeated_index(faces)
    faces_ok = faces[ok]
    topo = edge_topology(faces_ok[_first_copies(faces_ok)])
    bad = topo.face_count > 2
    if not bad.any():
        return faces
    pairs = np.unique(np.stack([corners.reshape(-1), faces.reshape(-1)], axis=1), axis=0)
    ids, count = np.unique(pairs[:, 1], return_counts=True)
    ends = np.intersect1d(topo.edges[bad].reshape(-1), ids[count > 1])
    if len(ends) == 0:
        return faces  # a non-manifold edge of the input itself: rejected later with its indices
    trial = np.where(np.isin(faces, ends), corners, faces)
    trial_ok = trial[~_repeated_index(trial)]
    trial_topo = edge_topology(trial_ok[_first_copies(trial_ok)])
    fewer_bad = (trial_topo.face_count > 2).sum() < bad.sum()
    if fewer_bad and trial_topo.boundary.sum() <= topo.boundary.sum():
        return trial
    return faces


def _drop_duplicates(w: _Work) -> None:
    """Drop faces with the same vertex set as an earlier face (either winding)."""
    _, first, inverse = np.unique(np.sort(w.faces, axis=1), axis=0, return_index=True, return_inverse=True)
    original = first[inverse.reshape(-1)]  # the first face with the same vertex set
    copies = np.flatnonzero(original != np.arange(len(w.faces)))
    if len(copies):
        w.notes["duplicate"] = (
            f"dropped {_plural(len(copies), 'duplicate face')} "
            f"(e.g. face {w.source[copies[0]]} repeats face {w.source[original[copies[0]]]})"
        )
    w.keep(original == np.arange(len(w.faces)))


def _drop_unused(w: _Work) -> None:
    """Drop vertices no remaining face refers to and number the rest 0..n-1."""
    unused = np.setdiff1d(np.arange(len(w.vertices)), w.corners)
    if len(unused):
        w.notes["unused"] = f"dropped {_plural(len(unused), 'unused vertex', 'unused vertices')} (e.g. vertex {unused[0]})"
    used, faces = np.unique(w.faces, return_inverse=True)
    w.faces = faces.reshape(-1, 3)
    w.vertices = w.vertices[used]


def _nonmanifold_edge_error(w: _Work, topo: Topology) -> MeshError:
    bad = np.flatnonzero(topo.face_count > 2)
    e = int(bad[0])
    owners = np.flatnonzero((topo.face_edges == e).any(axis=1))
    a, b = topo.edges[e]
    # Name the edge by the input vertex ids the first face uses for its endpoints.
    f = owners[0]
    ia = int(w.corners[f][w.faces[f] == a][0])
    ib = int(w.corners[f][w.faces[f] == b][0])
    welded = any(set(w.corners[g][np.isin(w.faces[g], (a, b))].tolist()) != {ia, ib} for g in owners)
    msg = (
        f"edge between vertices {min(ia, ib)} and {max(ia, ib)} is shared by {len(owners)} faces "
        f"({', '.join(str(int(w.source[g])) for g in owners)}); a surface edge may border at most 2 faces"
    )
    if welded:
        msg += " (after welding vertices at identical positions)"
    if len(bad) > 1:
        msg += f"; {_plural(len(bad) - 1, 'more such edge')}"
    return mesh_error(w.name, msg)


def _split_vertices(w: _Work, topo: Topology) -> tuple[Topology, np.ndarray, int]:
    """Split non-manifold vertices; returns (topology, component label per face, split input vertices).

    Also reports the net effect of welding and splitting: a weld the split undid (two separate
    vertices at one position) changed nothing, so it is not reported.
    """
    touching_groups = _vertex_components(w.faces)
    faces, old_vertex = _split_fans(w.faces, topo)
    if faces is not w.faces:
        w.faces, w.vertices = faces, w.vertices[old_vertex]
        topo = edge_topology(w.faces)  # same edges, new vertex ids
    labels = face_components(len(w.faces), topo)
    n_components = int(labels.max()) + 1

    pairs = np.unique(np.stack([w.corners.reshape(-1), w.faces.reshape(-1)], axis=1), axis=0)
    n_welded = len(pairs) - len(w.vertices)
    input_ids, per_input = np.unique(pairs[:, 0], return_counts=True)
    split_inputs = input_ids[per_input > 1]
    if n_welded:
        final_ids, per_final = np.unique(pairs[:, 1], return_counts=True)
        ids = pairs[pairs[:, 1] == final_ids[per_final > 1][0], 0]
        w.notes["welded"] = (
            f"welded {_plural(n_welded, 'vertex', 'vertices')} onto others at identical positions "
            f"(e.g. vertex {ids[1]} onto vertex {ids[0]})"
        )
    if len(split_inputs) and n_components > touching_groups:
        # Splitting inside an open surface whose boundary touches itself is normal: only a split
        # that separates the surface is worth a warning.
        w.notes["split"] = (
            f"split {_plural(len(split_inputs), 'non-manifold vertex', 'non-manifold vertices')} "
            f"(e.g. vertex {split_inputs[0]}) where faces only touch at a point: "
            f"{_plural(n_components - touching_groups, 'more component')}"
        )
    return topo, labels, len(split_inputs)


def _flip(w: _Work, mask: np.ndarray) -> None:
    w.faces[mask] = w.faces[mask][:, ::-1]
    w.corners[mask] = w.corners[mask][:, ::-1]


def _orient(w: _Work, topo: Topology, labels: np.ndarray) -> int:
    """Orient every component consistently, closed ones outward; returns the number of faces flipped."""
    flip, conflict = _orientation_parity(w.faces, topo)
    if conflict is not None:
        h0, h1 = conflict
        flat = w.corners.reshape(-1)
        a, b = int(flat[h0]), int(flat[_next_corner(np.array(h0))])
        raise mesh_error(
            w.name,
            f"a component is not orientable (like a Moebius strip): faces {w.source[h0 // 3]} and "
            f"{w.source[h1 // 3]} cannot agree on the direction of the edge between vertices "
            f"{min(a, b)} and {max(a, b)}",
        )
    if flip.any():
        w.notes["flipped"] = (
            f"flipped {_plural(int(flip.sum()), 'face')} to make the orientation consistent "
            f"(e.g. face {w.source[np.flatnonzero(flip)[0]]})"
        )
        _flip(w, flip)
    n_comp = int(labels.max()) + 1
    open_faces = topo.boundary[topo.face_edges].any(axis=1)
    closed = np.bincount(labels, weights=open_faces, minlength=n_comp) == 0
    inverted = closed & (signed_volumes(w.vertices, w.faces, labels) < 0)
    turn = inverted[labels]
    if turn.any():
        w.notes["inverted"] = (
            f"inverted {_plural(int(inverted.sum()), 'closed component')} that faced inward "
            f"(negative volume; {_plural(int(turn.sum()), 'face')} flipped, e.g. face {w.source[np.flatnonzero(turn)[0]]})"
        )
        _flip(w, turn)
    return int(flip.sum() + turn.sum())


def _note_components(w: _Work, components: tuple[Mesh, ...]) -> None:
    if len(components) < 2:
        return
    w.notes["components"] = f"{len(components)} components: each gets its own net(s)"
    crossing = _intersecting_components(components)
    if len(crossing) == 1:
        w.notes["intersect"] = f"components {crossing[0][0]} and {crossing[0][1]} intersect each other (their surfaces cross)"
    elif crossing:
        i, j = crossing[0]
        w.notes["intersect"] = f"{len(crossing)} pairs of components intersect each other (e.g. components {i} and {j})"


_NOTE_ORDER = ("scaled", "triangulated", "degenerate", "welded", "duplicate", "unused", "split", "flipped", "inverted", "components", "intersect")


def repair(parsed: RawMesh, path: str) -> LoadedMesh:
    """Check and repair the mesh of a file (`path`, as read by `formats.meshes`): the steps of the
    module docstring, in order. Raises MeshError (one line, starting with the file name) when it
    cannot be used."""
    name = os.path.basename(path)
    check_input(parsed, name)
    w = _Work(name, parsed.vertices, parsed.tris, parsed.tris.copy(), parsed.source,
              tri=np.arange(len(parsed.tris), dtype=np.int64))
    if parsed.n_triangulated:
        w.notes["triangulated"] = f"triangulated {_plural(parsed.n_triangulated, 'polygon')} with more than 3 corners"

    _normalise(w)
    _drop_degenerate(w)
    if len(w.faces):
        _weld(w)
    if len(w.faces) == 0:
        raise mesh_error(name, f"nothing left after dropping {_plural(len(w.degenerate), 'degenerate face')}")
    _drop_duplicates(w)
    _drop_unused(w)
    topo = edge_topology(w.faces)
    if (topo.face_count > 2).any():
        raise _nonmanifold_edge_error(w, topo)
    topo, labels, n_split = _split_vertices(w, topo)
    n_flipped = _orient(w, topo, labels)

    mesh = Mesh(w.vertices, w.faces, w.source)
    groups = np.split(np.argsort(labels, kind="stable"), np.cumsum(np.bincount(labels))[:-1])
    components = tuple(mesh.submesh(ids) for ids in groups)
    _note_components(w, components)
    return LoadedMesh(
        path=path,
        mesh=mesh,
        components=components,
        warnings=tuple(parsed.warnings) + tuple(w.notes[k] for k in _NOTE_ORDER if k in w.notes
                                                and not (k == "welded" and _seams(parsed))),
        manifold=n_split == 0,
        oriented=n_flipped == 0,
        n_input_faces=int(parsed.source.max()) + 1 if len(parsed.source) else 0,
        appearance=None if parsed.appearance is None else _carry_appearance(parsed, w),
    )


def _seams(parsed: RawMesh) -> bool:
    """Whether the file is textured: its vertices are split along UV seams, and welding them is
    what every textured file needs, not worth a warning."""
    return parsed.appearance is not None and bool(parsed.appearance.textured.any())


def _carry_appearance(parsed: RawMesh, w: _Work) -> Appearance:
    """The parsed triangles' look on the repaired faces: face f is parsed triangle w.tri[f], its
    corner k the parsed corner with the same input vertex (flips reversed the corners)."""
    raw = parsed.tris[w.tri]  # (F, 3) input vertex ids in parsed corner order
    corners = np.argmax(raw[:, None, :] == w.corners[:, :, None], axis=2)  # (F, 3): parsed corner of each
    return parsed.appearance.take(w.tri, corners)


def describe(loaded: LoadedMesh) -> dict:
    """The `polyfold info` report of a loaded mesh (JSON-serializable)."""
    mesh = loaded.mesh
    n_edges = n_boundary = n_loops = genus = n_hyperbolic = 0
    for comp in loaded.components:
        topo = comp.topology
        bnd = topo.boundary
        loops = len(boundary_loops(topo)) if bnd.any() else 0
        chi = comp.n_vertices - topo.n_edges + comp.n_faces
        genus += (2 - chi - loops) // 2
        n_edges += topo.n_edges
        n_boundary += int(bnd.sum())
        n_loops += loops
        # Boundary vertices are not counted (as in MODELS.md): their angle sum is not a curvature.
        on_boundary = np.zeros(comp.n_vertices, dtype=bool)
        on_boundary[topo.edges[bnd].reshape(-1)] = True
        n_hyperbolic += int((comp.hyperbolic & ~on_boundary).sum())
    return {
        "file": loaded.path,
        "faces": int(mesh.n_faces),
        "vertices": int(mesh.n_vertices),
        "edges": int(n_edges),
        "components": len(loaded.components),
        "boundary_edges": int(n_boundary),
        "boundary_loops": int(n_loops),
        "genus": int(genus),
        "closed": n_boundary == 0,
        "manifold": bool(loaded.manifold),
        "oriented": bool(loaded.oriented),
        "hyperbolic_vertices": int(n_hyperbolic),
        "concavity": float(concavity(mesh)),
        "bbox_diagonal": float(mesh.bbox_diagonal),
        "look": _look_summary(loaded.appearance),
        "warnings": list(loaded.warnings),
    }


def _look_summary(look: Appearance | None) -> str:
    """What `make` can print of the file's look, in a few words."""
    if look is None:
        return "none"
    if look.textured.any():
        sizes = ", ".join(f"{im.shape[1]}x{im.shape[0]}" for im in look.images)
        return f"texture ({sizes} px) on {int(look.textured.sum()):,} faces"
    return "colours per vertex" if look.kind == "vertex" else "colours per face"
