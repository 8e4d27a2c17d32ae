"""The crease tree of a net, as the folding kernels take it: `FoldTree`.

`FoldTree.from_net` / `from_pattern` build it from the unfold stage's result in memory (through
`unfold.pattern.crease_pattern`, the same arrays a FOLD file holds, so a net and its file give the
same tree bit for bit); `formats.fold.fold_tree` builds it from a FOLD file. Both end in
`build_tree`: one numba kernel (`tree_kernels.net_tree`) for the edge table, the crease tree and
the crease axes, and the one-line errors (`malformed net: ...`, naming the face or edge) when a
net cannot be folded. `fold_positions`, `collides` and `colliding_pairs` fold a configuration
(rho radians per net edge, `kinematics.py`) and test it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..collide.sweep import all_collisions
from ..collide.tolerance import CONTACT_TOL
from ..errors import PolyfoldError
from ..mesh.geometry import vector_norm
from ..unfold.net import Net
from ..unfold.pattern import CreasePattern, crease_pattern
from . import tree_kernels as TK
from .checker import config_collides
from .kinematics import forward_kinematics

CUT_ASSIGNMENTS = ("B", "C")  # FOLD assignments that do not join faces (FOLD 1.2 adds C = cut)
CREASE_ASSIGNMENTS = ("M", "V", "F", "U", "J")
ASSIGNMENT_CODES = CUT_ASSIGNMENTS + CREASE_ASSIGNMENTS  # `kind` of `build_tree`: an index into these
ASSIGNMENT_KIND = {a: i for i, a in enumerate(ASSIGNMENT_CODES)}  # kind < len(CUT_ASSIGNMENTS): a cut
MOUNTAIN, VALLEY = ASSIGNMENT_KIND["M"], ASSIGNMENT_KIND["V"]
# unfold.pattern's kinds (CUT, FLAT, MOUNTAIN, VALLEY) as build_tree kinds
_PATTERN_KIND = np.array([ASSIGNMENT_KIND[a] for a in ("B", "F", "M", "V")], dtype=np.int8)


def malformed_net(message: str) -> PolyfoldError:
    """The error of a net that cannot be folded: one line, `malformed net: ...`."""
    return PolyfoldError(f"malformed net: {message}")


@dataclass(frozen=True, eq=False)
class FoldTree:
    """The arrays of a net for the kernels (see the module docstring for the conventions).

    flat (F, 3, 3) flat corners (x, y, 0) in faces_vertices order; faces (F, 3) net vertex ids;
    order (F,) parents first; parent / crease (F,) parent face and crease edge index, -1 at roots;
    axis (F, 2) the parent's corners at the crease ends, a -> b in the parent's CCW order;
    piece (F,); goal (E,) goal angle per edge (rho, radians; 0 for cuts); creases (n,) the tree
    creases (the DOF), ascending; scale = bounding-box diagonal (foldedForm, else flat net);
    tol = contact tolerance (CONTACT_TOL * scale); folded (V, 3) foldedForm coords or None;
    mesh_faces (F, 3) the mesh vertex of every corner (-1 unknown: faces of a FOLD file without
    `polyfold:vertices_meshVertex`); thickness: of the material, in the net's units (0: none; see
    `with_thickness` and the README's "Paper thickness").
    """

    flat: np.ndarray
    faces: np.ndarray
    order: np.ndarray
    parent: np.ndarray
    crease: np.ndarray
    axis: np.ndarray
    piece: np.ndarray
    goal: np.ndarray
    creases: np.ndarray
    scale: float
    tol: float
    folded: np.ndarray | None
    mesh_faces: np.ndarray | None = None
    thickness: float = 0.0

    def with_thickness(self, thickness: float) -> FoldTree:
        """The same tree whose collision test counts faces closer than `thickness` (net units)
        with overlapping projections as colliding."""
        mesh_faces = self.mesh_faces if self.mesh_faces is not None else np.full_like(self.faces, -1)
        return replace(self, thickness=float(thickness), mesh_faces=np.ascontiguousarray(mesh_faces, dtype=np.int64))

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @property
    def n_edges(self) -> int:
        return len(self.goal)

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fresh (R, T, out) work arrays for forward_kinematics / config_collides."""
        n = self.n_faces
        return np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3, 3))

    @classmethod
    def from_pattern(cls, pattern: CreasePattern, contact_tol: float = CONTACT_TOL) -> FoldTree:
        """The tree of a crease pattern (`unfold.pattern.crease_pattern`); contact_tol is relative
        to the model's bounding-box diagonal."""
        tree = build_tree(pattern.coords, pattern.faces, pattern.edges, _PATTERN_KIND[pattern.kind], pattern.parent,
                          pattern.piece, pattern.fold_deg, pattern.folded, contact_tol)
        return replace(tree, mesh_faces=np.ascontiguousarray(pattern.mesh_vertex[pattern.faces], dtype=np.int64))

    @classmethod
    def from_net(cls, net: Net, contact_tol: float = CONTACT_TOL) -> FoldTree:
        """The tree of a net (one component; its pieces are folded side by side)."""
        return cls.from_pattern(crease_pattern([net]), contact_tol)


def bbox_diagonal(pts: np.ndarray) -> float:
    """Bounding-box diagonal of finite points (V, 2 or 3)."""
    return vector_norm(TK.extent(pts)) if len(pts) else 0.0


def _goal_from_folded(kind: np.ndarray, edges: np.ndarray, edge_faces: np.ndarray, faces: np.ndarray,
                      folded: np.ndarray | None) -> np.ndarray:
    """Goal angles (E,) of a file without fold angles: from the foldedForm frame, else +-pi by the
    assignment (0 on cuts)."""
    n_e = len(edges)
    goal = np.zeros(n_e)
    is_cut = kind < len(CUT_ASSIGNMENTS)
    for e in range(n_e):  # files without fold angles only (net_to_fold always writes them)
        if is_cut[e]:
            continue
        if folded is not None and edge_faces[e, 1] >= 0:
            f0, f1 = edge_faces[e]
            u, v = edges[e]
            k = int(np.flatnonzero(faces[f0] == u)[0])
            a, b = (u, v) if faces[f0][(k + 1) % 3] == v else (v, u)
            n0 = np.cross(*(folded[faces[f0][1:]] - folded[faces[f0][0]]))
            n1 = np.cross(*(folded[faces[f1][1:]] - folded[faces[f1][0]]))
            n0 /= max(np.linalg.norm(n0), 1e-300)
            n1 /= max(np.linalg.norm(n1), 1e-300)
            goal[e] = math.atan2(float(np.cross(n0, n1) @ (folded[b] - folded[a])) / max(np.linalg.norm(folded[b] - folded[a]), 1e-300),
                                 float(n0 @ n1))
        elif kind[e] in (MOUNTAIN, VALLEY):
            goal[e] = math.pi if kind[e] == MOUNTAIN else -math.pi
    return goal


_SIDE_ERRORS = {  # messages of the edge-table codes of tree_kernels (info, then the edge's vertex pair)
    TK.BAD_EDGE: "edge {0} has invalid vertices {pair}",
    TK.DUPLICATE_EDGE: "edges {0} and {1} join the same vertices {uv}",
    TK.MISSING_SIDE: "side {0}-{1} of face {2} is not in 'edges_vertices'",
    TK.THIRD_FACE: "edge {0} borders more than two faces",
    TK.CLOCKWISE: "face {0} is clockwise seen from +z (faces must be CCW, outer side up)",
}


def _tree_error(code: int, info: np.ndarray, parent: np.ndarray, piece: np.ndarray, kind: np.ndarray) -> PolyfoldError:
    """The one-line message of a `tree_kernels.net_tree` error code."""
    a, b, c = info[:3].tolist()
    if code == TK.INVALID_PARENT:
        return malformed_net(f"face {a} has invalid parent {b}")
    if code == TK.NO_COMMON_EDGE:
        return malformed_net(f"face {a} shares no edge with its parent face {b}")
    if code == TK.CUT_PARENT_EDGE:
        return malformed_net(f"face {a} is joined to its parent face {b} by cut edge {c} (assignment {ASSIGNMENT_CODES[kind[c]]})")
    if code == TK.PIECE_CREASE:
        return malformed_net(f"crease edge {a} joins face {b} (piece {piece[b]}) to face {c} (piece {piece[c]})")
    if code == TK.CYCLE:
        return malformed_net(f"face {a} is on a cycle of 'polyfold:faces_parent' (no path to a root)")
    if code == TK.PARENT_PIECE:
        return malformed_net(f"face {a} (piece {piece[a]}) has its parent face {parent[a]} in piece {piece[parent[a]]}")
    return malformed_net(f"piece {a} is not connected by creases (faces {b} and {c} are both roots)")


def _config(tree: FoldTree, q) -> np.ndarray:
    q = np.ascontiguousarray(q, dtype=np.float64)
    if q.shape != (tree.n_edges,):
        raise ValueError(f"q must have one angle per net edge: shape ({tree.n_edges},), got {q.shape}")
    return q


def fold_positions(tree: FoldTree, q: np.ndarray) -> np.ndarray:
    """Folded face corners (F, 3, 3) at configuration q (E,) (radians, rho convention)."""
    R, T, out = tree.buffers()
    return forward_kinematics(_config(tree, q), tree.order, tree.parent, tree.crease, tree.axis, tree.flat, R, T, out)


def collides(tree: FoldTree, q: np.ndarray) -> bool:
    """True if the net folded to q self-intersects."""
    R, T, out = tree.buffers()
    return bool(config_collides(_config(tree, q), tree.order, tree.parent, tree.crease, tree.axis, tree.flat,
                                tree.piece, tree.tol, R, T, out))


def colliding_pairs(tree: FoldTree, q: np.ndarray) -> np.ndarray:
    """All colliding face pairs (k, 2), i < j, sorted, of the net folded to q."""
    tris = fold_positions(tree, q)
    count, _ = all_collisions(tris, tree.parent, tree.piece, tree.tol, 0)
    _, pairs = all_collisions(tris, tree.parent, tree.piece, tree.tol, int(count))
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def crease_depth_size(tree: FoldTree) -> tuple[np.ndarray, np.ndarray]:
    """Per crease of tree.creases: depth of its child face in the tree, faces in the child's subtree."""
    n_f = len(tree.order)
    depth = np.zeros(n_f, dtype=np.int64)
    size = np.ones(n_f, dtype=np.int64)
    for f in tree.order:
        if tree.parent[f] >= 0:
            depth[f] = depth[tree.parent[f]] + 1
    for f in tree.order[::-1]:
        if tree.parent[f] >= 0:
            size[tree.parent[f]] += size[f]
    child = np.full(len(tree.goal), -1, dtype=np.int64)
    has = tree.crease >= 0
    child[tree.crease[has]] = np.flatnonzero(has)
    kids = child[tree.creases]
    return depth[kids], size[kids]


def build_tree(xy: np.ndarray, faces: np.ndarray, edges: np.ndarray, kind: np.ndarray, parent_in: np.ndarray,
               piece_in: np.ndarray, deg: np.ndarray, folded: np.ndarray | None, contact_tol: float = CONTACT_TOL,
               scale: float | None = None, stage: int = 4, late: Exception | None = None) -> FoldTree:
    """The FoldTree of a net's arrays, or a `malformed_net` error naming the face / edge.

    xy (V, 2) flat coordinates; faces (F, 3) (F >= 1) CCW net vertex ids; edges (E, 2); kind (E,)
    int8 codes into ASSIGNMENT_CODES; parent_in / piece_in (F,) the tree and pieces, or empty (then
    a BFS over the creases from the lowest face of each piece); deg (E,) FOLD fold angles (degrees,
    valley positive; empty: from `folded`, else +-180 by the assignment); folded (V, 3) the folded
    position of every vertex, or None; scale: the model size (default: the bounding-box diagonal of
    `folded`, else of xy), contact_tol is relative to it. Errors come in this order: faces, the edge table and
    clockwise faces, the crease tree, zero-length creases, fold angles. For a file reader: `stage`
    says how far the inputs are usable (1 faces only, 2 + edges and kinds, 3 + tree, 4 + fold
    angles) and `late` is the parse error of the first unusable one, raised where its check comes.
    """
    if scale is None:
        scale = bbox_diagonal(folded if folded is not None else xy)
    n_f, n_e, n_v = len(faces), len(edges), len(xy)
    info = np.empty(4, dtype=np.int64)
    face_edges, edge_faces, flat = np.empty((n_f, 3), dtype=np.int64), np.empty((n_e, 2), dtype=np.int64), np.empty((n_f, 3, 3))
    parent, crease, order = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    piece, short, creases = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    axis = np.empty((n_f, 2), dtype=np.int64)
    goal = np.empty(n_e)
    code, n_short, n_creases, bad_angle, out_of_range = TK.net_tree(
        faces, n_v, edges, kind, len(CUT_ASSIGNMENTS), xy, -1e-12 * scale * scale, parent_in, piece_in, (2e-12 * scale) ** 2,
        MOUNTAIN, VALLEY, deg, stage, info, face_edges, edge_faces, flat, parent, crease, order, piece, axis, short,
        creases, goal)
    i = info.tolist()
    if code in (TK.FACE_OUT_OF_RANGE, TK.FACE_REPEAT):
        raise malformed_net(f"face {i[0]} refers to a vertex outside 0..{n_v - 1}" if code == TK.FACE_OUT_OF_RANGE
                    else f"face {i[0]} repeats a vertex")
    if stage < 2:
        raise late
    if code in _SIDE_ERRORS:
        raise malformed_net(_SIDE_ERRORS[code].format(*i, pair=edges[i[0]].tolist() if code == TK.BAD_EDGE else None, uv=i[2:]))
    if stage < 3:
        raise late
    if code != TK.OK:
        raise _tree_error(code, info, parent, piece_in if len(piece_in) else piece, kind)
    for f in short[:n_short].tolist():  # the exact test (as always) of the creases the kernel could not clear
        p, e = int(parent[f]), int(crease[f])
        u, v = edges[e]
        if not np.linalg.norm(xy[u] - xy[v]) > 1e-12 * scale:
            raise malformed_net(f"crease edge {e} (between faces {p} and {f}) has zero length")
    if late is not None:
        raise late
    if bad_angle >= 0:
        d = deg[bad_angle]
        if out_of_range:
            raise malformed_net(f"edge {bad_angle} has fold angle {d} (must be within [-180, 180] degrees)")
        raise malformed_net(f"edge {bad_angle} is a {'mountain' if kind[bad_angle] == MOUNTAIN else 'valley'} with fold angle {d} "
                    "(FOLD: valley positive, mountain negative)")
    if stage < 4:  # no fold angles in the file: from the foldedForm, else +-180 degrees
        goal = _goal_from_folded(kind, edges, edge_faces, faces, folded)
    return FoldTree(
        flat=flat, faces=faces, order=order, parent=parent, crease=crease, axis=axis,
        piece=piece, goal=goal, creases=creases[:n_creases], scale=scale,
        tol=contact_tol * scale, folded=folded,
    )
