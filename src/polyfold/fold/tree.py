"""The crease tree of a net, as the folding kernels take it: `FoldTree`.

Built from a FOLD net by `fold_tree` (the FOLD conventions are in `formats/fold.py`); the arrays
follow `kinematics.py`: flat corners, the tree (parents first), crease axes, pieces, and the goal
configuration (rho radians per net edge). `fold_positions`, `collides` and `colliding_pairs` fold
a configuration and test it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..collide.sweep import all_collisions
from ..collide.tolerance import CONTACT_TOL
from ..errors import PolyfoldError
from ..mesh.geometry import vector_norm
from . import tree_kernels as TK
from .checker import config_collides
from .kinematics import forward_kinematics


_CUT = ("B", "C")  # assignments that do not join faces (FOLD 1.2 adds C = cut)


_CREASE = ("M", "V", "F", "U", "J")


@dataclass(frozen=True, eq=False)
class FoldTree:
    """Arrays of a FOLD net for the kernels (see the module docstring for the conventions).

    flat (F, 3, 3) flat corners (x, y, 0) in faces_vertices order; faces (F, 3) net vertex ids;
    order (F,) parents first; parent / crease (F,) parent face and crease edge index, -1 at roots;
    axis (F, 2) the parent's corners at the crease ends, a -> b in the parent's CCW order;
    piece (F,); goal (E,) goal angle per edge (rho, radians; 0 for cuts); creases (n,) the tree
    creases (the DOF), ascending; scale = bounding-box diagonal (foldedForm, else flat net);
    tol = contact tolerance (CONTACT_TOL * scale); folded (V, 3) foldedForm coords or None.
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


def _fail(message: str) -> PolyfoldError:
    return PolyfoldError(f"malformed net: {message}")


def _int_array(fold: dict, key: str, shape_tail: tuple[int, ...], what: str) -> np.ndarray:
    try:
        arr = np.asarray(fold[key])
        if arr.size == 0:
            arr = arr.reshape((0,) + shape_tail)
        if arr.dtype == object or arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
            raise ValueError
        if arr.dtype != np.int64 and not np.issubdtype(arr.dtype, np.integer):  # (JSON ints: int64)
            if not np.issubdtype(arr.dtype, np.floating) or not np.all(arr == np.round(arr)):
                raise ValueError
        return arr.astype(np.int64)
    except (ValueError, TypeError):
        raise _fail(f"{key!r} is not a list of {what}") from None


def _float_array(value, key: str, n_cols: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (ValueError, TypeError):
        raise _fail(f"{key!r} is not a list of coordinates") from None
    if arr.ndim != 2 or arr.shape[1] not in n_cols:
        raise _fail(f"{key!r} must hold {' or '.join(map(str, n_cols))} coordinates per vertex")
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.flatnonzero(~finite.all(axis=1))
        raise _fail(f"{key!r}: vertex {bad[0]} has a non-finite coordinate")
    return arr


def _bbox_diagonal(pts: np.ndarray) -> float:
    """Bounding-box diagonal of finite points (V, 2 or 3)."""
    return vector_norm(TK.extent(pts)) if len(pts) else 0.0


def _folded_coords(fold: dict, n_v: int) -> np.ndarray | None:
    frames = fold.get("file_frames")
    if not frames:
        return None
    frame = next((fr for fr in frames if isinstance(fr, dict) and "foldedForm" in (fr.get("frame_classes") or [])), frames[0])
    if not isinstance(frame, dict) or "vertices_coords" not in frame:
        return None
    coords = _float_array(frame["vertices_coords"], "file_frames[0].vertices_coords", (3,))
    if len(coords) != n_v:
        raise _fail(f"the foldedForm frame has {len(coords)} vertices, the net has {n_v}")
    return coords


def _check_triangles(rows) -> None:
    """Every face is a sequence of 3 corners (before the corners themselves are parsed)."""
    # the usual case (lists of 3-lists, as JSON gives) without a Python loop over the faces
    if type(rows) is list and set(map(type, rows)) <= {list} and set(map(len, rows)) <= {3}:
        return
    for f, corners in enumerate(rows):
        if not isinstance(corners, (list, tuple, np.ndarray)) or len(corners) != 3:
            raise _fail(f"face {f} is not a triangle (only triangulated nets can be folded)")


_KNOWN = frozenset(_CUT + _CREASE)


_KIND = {a: i for i, a in enumerate(_CUT + _CREASE)}  # kind < len(_CUT): a cut


_MOUNTAIN, _VALLEY = _KIND["M"], _KIND["V"]


def _assignments(assign, n_e: int) -> tuple[list[str], np.ndarray]:
    """Upper-cased assignments and their kinds (E,) int8 (index into _CUT + _CREASE)."""
    if not isinstance(assign, (list, tuple)) or len(assign) != n_e:
        raise _fail(f"'edges_assignment' must have one entry per edge ({n_e})")
    if set(map(type, assign)) <= {str}:
        try:  # the usual case: all upper-case and known already
            return assign, np.fromiter(map(_KIND.__getitem__, assign), dtype=np.int8, count=n_e)
        except KeyError:
            pass
    assign = [str(a).upper() for a in assign]
    for e, a in enumerate(assign):
        if a not in _KNOWN:
            raise _fail(f"edge {e} has unknown assignment {a!r}")
    return assign, np.fromiter(map(_KIND.__getitem__, assign), dtype=np.int8, count=n_e)


def _fold_angles(fold: dict, n_e: int) -> np.ndarray:
    """'edges_foldAngle' as (E,) float64 degrees (values are checked by the kernel)."""
    try:
        deg = np.asarray(fold["edges_foldAngle"], dtype=np.float64)
    except (ValueError, TypeError):
        raise _fail("'edges_foldAngle' is not a list of numbers") from None
    if deg.shape != (n_e,):
        raise _fail(f"'edges_foldAngle' has {deg.size} entries for {n_e} edges")
    return deg


def _goal_from_folded(assign, kind: np.ndarray, edges: np.ndarray, edge_faces: np.ndarray, faces: np.ndarray,
                      folded: np.ndarray | None) -> np.ndarray:
    """Goal angles (E,) of a file without fold angles: from the foldedForm frame, else +-pi by the
    assignment (0 on cuts)."""
    n_e = len(edges)
    goal = np.zeros(n_e)
    is_cut = kind < len(_CUT)
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
        elif assign[e] in ("M", "V"):
            goal[e] = math.pi if assign[e] == "M" else -math.pi
    return goal


_SIDE_ERRORS = {  # messages of the edge-table codes of _tree_kernels (info, then the edge's vertex pair)
    TK.BAD_EDGE: "edge {0} has invalid vertices {pair}",
    TK.DUPLICATE_EDGE: "edges {0} and {1} join the same vertices {uv}",
    TK.MISSING_SIDE: "side {0}-{1} of face {2} is not in 'edges_vertices'",
    TK.THIRD_FACE: "edge {0} borders more than two faces",
    TK.CLOCKWISE: "face {0} is clockwise seen from +z (faces must be CCW, outer side up)",
}


def _tree_error(code: int, info: np.ndarray, parent: np.ndarray, piece: np.ndarray, assign: list[str]) -> PolyfoldError:
    """The one-line message of a `_tree_kernels.crease_tree` error code."""
    a, b, c = info[:3].tolist()
    if code == TK.INVALID_PARENT:
        return _fail(f"face {a} has invalid parent {b}")
    if code == TK.NO_COMMON_EDGE:
        return _fail(f"face {a} shares no edge with its parent face {b}")
    if code == TK.CUT_PARENT_EDGE:
        return _fail(f"face {a} is joined to its parent face {b} by cut edge {c} (assignment {assign[c]})")
    if code == TK.PIECE_CREASE:
        return _fail(f"crease edge {a} joins face {b} (piece {piece[b]}) to face {c} (piece {piece[c]})")
    if code == TK.CYCLE:
        return _fail(f"face {a} is on a cycle of 'polyfold:faces_parent' (no path to a root)")
    if code == TK.PARENT_PIECE:
        return _fail(f"face {a} (piece {piece[a]}) has its parent face {parent[a]} in piece {piece[parent[a]]}")
    return _fail(f"piece {a} is not connected by creases (faces {b} and {c} are both roots)")


def fold_tree(fold: dict, contact_tol: float = CONTACT_TOL) -> FoldTree:
    """The FoldTree of a FOLD net (as written by `foldfile.net_to_fold`).

    Uses `polyfold:faces_parent` when present, else a BFS over the crease (non-B) edges from the
    lowest-index face of each piece. Raises PolyfoldError (one line naming the face / edge) when the
    net cannot be folded: non-triangular faces, bad indices, clockwise faces, a parent that is not
    joined by a crease, cycles, pieces inconsistent with the tree, zero-length creases, ...
    The per-face work is one numba kernel (`_tree_kernels.net_tree`); so that it runs once, the
    later inputs are parsed first and a parse error is raised where its check comes in this order.
    """
    if not isinstance(fold, dict):
        raise _fail("not a FOLD dict")
    for key in ("vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment"):
        if key not in fold:
            raise _fail(f"no {key!r}")
    xy = _float_array(fold["vertices_coords"], "vertices_coords", (2, 3))
    n_v = len(xy)
    folded = _folded_coords(fold, n_v)
    scale = _bbox_diagonal(folded if folded is not None else xy)
    if not scale > 0:
        raise _fail("the net has zero size")
    if xy.shape[1] == 3:
        bad = np.flatnonzero(np.abs(xy[:, 2]) > 1e-9 * scale)
        if len(bad):
            raise _fail(f"vertex {bad[0]} of the crease pattern is not in the plane z = 0")
        xy = np.ascontiguousarray(xy[:, :2])
    _check_triangles(fold["faces_vertices"])
    faces = _int_array(fold, "faces_vertices", (3,), "vertex triples")
    n_f = len(faces)
    if n_f == 0:
        raise _fail("no faces")

    # parsed ahead of their checks (errors kept for later): edges, then the tree, then fold angles
    none = np.empty(0, dtype=np.int64)
    edges, kind, assign, parent_in, piece_in, deg = none.reshape(0, 2), none, [], none, none, np.empty(0)
    stage, late = 1, None
    try:
        edges = _int_array(fold, "edges_vertices", (2,), "vertex pairs")
        assign, kind = _assignments(fold["edges_assignment"], len(edges))
        stage = 2
        if "polyfold:faces_piece" in fold:
            piece_in = _int_array(fold, "polyfold:faces_piece", (), "integers")
            if len(piece_in) != n_f:
                raise _fail(f"'polyfold:faces_piece' has {len(piece_in)} entries for {n_f} faces")
        if "polyfold:faces_parent" in fold:
            parent_in = _int_array(fold, "polyfold:faces_parent", (), "integers")
            if len(parent_in) != n_f:
                raise _fail(f"'polyfold:faces_parent' has {len(parent_in)} entries for {n_f} faces")
        stage = 3
        if "edges_foldAngle" in fold:
            deg = _fold_angles(fold, len(edges))
            stage = 4
    except Exception as exc:  # noqa: BLE001 (raised below, after the checks that come first)
        late = exc
    n_e = len(edges)
    info = np.empty(4, dtype=np.int64)
    face_edges, edge_faces, flat = np.empty((n_f, 3), dtype=np.int64), np.empty((n_e, 2), dtype=np.int64), np.empty((n_f, 3, 3))
    parent, crease, order = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    piece, short, creases = np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64), np.empty(n_f, dtype=np.int64)
    axis = np.empty((n_f, 2), dtype=np.int64)
    goal = np.empty(n_e)
    code, n_short, n_creases, bad_angle, out_of_range = TK.net_tree(
        faces, n_v, edges, kind, len(_CUT), xy, -1e-12 * scale * scale, parent_in, piece_in, (2e-12 * scale) ** 2,
        _MOUNTAIN, _VALLEY, deg, stage, info, face_edges, edge_faces, flat, parent, crease, order, piece, axis, short,
        creases, goal)
    i = info.tolist()
    if code in (TK.FACE_OUT_OF_RANGE, TK.FACE_REPEAT):
        raise _fail(f"face {i[0]} refers to a vertex outside 0..{n_v - 1}" if code == TK.FACE_OUT_OF_RANGE
                    else f"face {i[0]} repeats a vertex")
    if stage < 2:
        raise late
    if code in _SIDE_ERRORS:
        raise _fail(_SIDE_ERRORS[code].format(*i, pair=edges[i[0]].tolist() if code == TK.BAD_EDGE else None, uv=i[2:]))
    if stage < 3:
        raise late
    if code != TK.OK:
        raise _tree_error(code, info, parent, piece_in if len(piece_in) else piece, assign)
    for f in short[:n_short].tolist():  # the exact test (as always) of the creases the kernel could not clear
        p, e = int(parent[f]), int(crease[f])
        u, v = edges[e]
        if not np.linalg.norm(xy[u] - xy[v]) > 1e-12 * scale:
            raise _fail(f"crease edge {e} (between faces {p} and {f}) has zero length")
    if late is not None:
        raise late
    if bad_angle >= 0:
        d = deg[bad_angle]
        if out_of_range:
            raise _fail(f"edge {bad_angle} has fold angle {d} (must be within [-180, 180] degrees)")
        raise _fail(f"edge {bad_angle} is a {'mountain' if assign[bad_angle] == 'M' else 'valley'} with fold angle {d} "
                    "(FOLD: valley positive, mountain negative)")
    if stage < 4:  # no fold angles in the file: from the foldedForm, else +-180 degrees
        goal = _goal_from_folded(assign, kind, edges, edge_faces, faces, folded)
    return FoldTree(
        flat=flat, faces=faces, order=order, parent=parent, crease=crease, axis=axis,
        piece=piece, goal=goal, creases=creases[:n_creases], scale=scale,
        tol=contact_tol * scale, folded=folded,
    )


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
