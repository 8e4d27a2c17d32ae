"""FOLD 1.1 files: the canonical net format (https://github.com/edemaine/fold).

`pattern_fold` writes a crease pattern (`unfold.pattern.crease_pattern` of the nets of all components
of a mesh) as one FOLD dict: the flat crease pattern (2D `vertices_coords`, outer side facing +z), `edges_assignment` B/M/V/F,
`edges_foldAngle` in degrees (valley positive, mountain negative: convex mesh edges are
mountains), and a `foldedForm` frame holding the 3D position of every net vertex. Custom keys:
`polyfold:faces_meshFace` (source face in the input file's face order), `polyfold:faces_piece`,
`polyfold:faces_component`, `polyfold:faces_parent` (the tree: net face joined to each face by a
crease, -1 at the root of a piece), `polyfold:edges_meshEdge` (twin cut edges share the number),
`polyfold:vertices_meshVertex`. These files (`polyfold unfold`) are in the mesh's units
(`frame_unit` "unit"); `piece_fold` writes make's pieces in mm as printed.
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..collide.tolerance import CONTACT_TOL
from ..errors import PolyfoldError
from ..fold.tree import ASSIGNMENT_KIND, FoldTree, bbox_diagonal, build_tree, malformed_net
from ..mesh.geometry import rho_to_fold_deg
from ..unfold.net import Net
from ..unfold.pattern import CreasePattern, crease_pattern
from .files import atomic_write

if TYPE_CHECKING:
    from ..fold.plan import FoldPath

REQUIRED = ("vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment")


def pattern_fold(pattern: CreasePattern, *, creator: str = "polyfold", title: str | None = None) -> dict:
    """The FOLD dict of a crease pattern (see the module docstring for the keys)."""
    return {
        "file_spec": 1.1,
        "file_creator": creator,
        "file_classes": ["singleModel"],
        "frame_title": title or "polyfold net",
        "frame_classes": ["creasePattern"],
        "frame_attributes": ["2D"],
        "frame_unit": "unit",
        "vertices_coords": pattern.coords.tolist(),
        "faces_vertices": pattern.faces.tolist(),
        "edges_vertices": pattern.edges.tolist(),
        "edges_assignment": pattern.assignments,
        "edges_foldAngle": pattern.fold_deg.tolist(),
        "polyfold:faces_meshFace": pattern.mesh_face.tolist(),
        "polyfold:faces_piece": pattern.piece.tolist(),
        "polyfold:faces_component": pattern.component.tolist(),
        "polyfold:faces_parent": pattern.parent.tolist(),
        "polyfold:edges_meshEdge": pattern.mesh_edge.tolist(),
        "polyfold:vertices_meshVertex": pattern.mesh_vertex.tolist(),
        "file_frames": [
            {
                "frame_classes": ["foldedForm"],
                "frame_attributes": ["3D"],
                "frame_inherit": True,
                "frame_parent": 0,
                "vertices_coords": pattern.folded.tolist(),
            }
        ],
    }


def net_to_fold(nets: Sequence[Net], *, creator: str = "polyfold", title: str | None = None) -> dict:
    """The FOLD dict of the nets of one mesh (one Net per component, each with one or more pieces)."""
    return pattern_fold(crease_pattern(nets), creator=creator, title=title)


def dumps(fold: dict) -> str:
    """FOLD JSON text (floats written with full precision)."""
    return json.dumps(fold, separators=(",", ":"))


def write_fold(path: str | os.PathLike, fold: dict) -> None:
    """Write a FOLD dict to `path` (atomically)."""
    atomic_write(path, dumps(fold))


def _json_kind(value) -> str:
    """What a JSON value is, in words (for messages)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    return "a list" if isinstance(value, list) else type(value).__name__


def read_fold(path: str | os.PathLike) -> dict:
    """Read a FOLD file; raises PolyfoldError with a one-line message when it is not usable."""
    name = os.path.basename(os.fspath(path))
    try:
        with open(path, encoding="utf-8") as fh:
            fold = json.load(fh)
    except FileNotFoundError:
        raise PolyfoldError(f"{name}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise PolyfoldError(f"{name}: not a readable FOLD (JSON) file: {exc}") from None
    except RecursionError:
        raise PolyfoldError(f"{name}: not a readable FOLD (JSON) file: nested too deeply") from None
    if not isinstance(fold, dict):
        raise PolyfoldError(f"{name}: a FOLD file is a JSON object, this one holds {_json_kind(fold)}")
    for key in REQUIRED:
        if key not in fold:
            raise PolyfoldError(f"{name}: FOLD file has no {key!r}")
    return fold


# ----------------------------------------------------------------------------------------------
# FOLD -> FoldTree


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
        raise malformed_net(f"{key!r} is not a list of {what}") from None


def _float_array(value, key: str, n_cols: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (ValueError, TypeError):
        raise malformed_net(f"{key!r} is not a list of coordinates") from None
    if arr.ndim != 2 or arr.shape[1] not in n_cols:
        raise malformed_net(f"{key!r} must hold {' or '.join(map(str, n_cols))} coordinates per vertex")
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.flatnonzero(~finite.all(axis=1))
        raise malformed_net(f"{key!r}: vertex {bad[0]} has a non-finite coordinate")
    return arr


def _folded_coords(fold: dict, n_v: int) -> np.ndarray | None:
    frames = fold.get("file_frames")
    if not frames:
        return None
    frame = next((fr for fr in frames if isinstance(fr, dict) and "foldedForm" in (fr.get("frame_classes") or [])), frames[0])
    if not isinstance(frame, dict) or "vertices_coords" not in frame:
        return None
    coords = _float_array(frame["vertices_coords"], "file_frames[0].vertices_coords", (3,))
    if len(coords) != n_v:
        raise malformed_net(f"the foldedForm frame has {len(coords)} vertices, the net has {n_v}")
    return coords


def _check_triangles(rows) -> None:
    """Every face is a sequence of 3 corners (before the corners themselves are parsed)."""
    # the usual case (lists of 3-lists, as JSON gives) without a Python loop over the faces
    if type(rows) is list and set(map(type, rows)) <= {list} and set(map(len, rows)) <= {3}:
        return
    for f, corners in enumerate(rows):
        if not isinstance(corners, (list, tuple, np.ndarray)) or len(corners) != 3:
            raise malformed_net(f"face {f} is not a triangle (only triangulated nets can be folded)")


def _assignments(assign, n_e: int) -> np.ndarray:
    """The kinds (E,) int8 (index into ASSIGNMENT_CODES) of the assignments (any case)."""
    if not isinstance(assign, (list, tuple)) or len(assign) != n_e:
        raise malformed_net(f"'edges_assignment' must have one entry per edge ({n_e})")
    if set(map(type, assign)) <= {str}:
        try:  # the usual case: all upper-case and known already
            return np.fromiter(map(ASSIGNMENT_KIND.__getitem__, assign), dtype=np.int8, count=n_e)
        except KeyError:
            pass
    assign = [str(a).upper() for a in assign]
    for e, a in enumerate(assign):
        if a not in ASSIGNMENT_KIND:
            raise malformed_net(f"edge {e} has unknown assignment {a!r}")
    return np.fromiter(map(ASSIGNMENT_KIND.__getitem__, assign), dtype=np.int8, count=n_e)


def _fold_angles(fold: dict, n_e: int) -> np.ndarray:
    """'edges_foldAngle' as (E,) float64 degrees (values are checked by the kernel)."""
    try:
        deg = np.asarray(fold["edges_foldAngle"], dtype=np.float64)
    except (ValueError, TypeError):
        raise malformed_net("'edges_foldAngle' is not a list of numbers") from None
    if deg.shape != (n_e,):
        raise malformed_net(f"'edges_foldAngle' has {deg.size} entries for {n_e} edges")
    return deg


def _check_no_overlap(tris: np.ndarray, parent: np.ndarray, piece: np.ndarray, tol: float) -> None:
    """A malformed-net error naming two faces of one piece that overlap in the flat net (a net
    that overlaps itself flat has no collision-free folding path to plan)."""
    from ..collide.flat import find_overlaps

    pairs = find_overlaps(tris, parent, tol)
    pairs = pairs[piece[pairs[:, 0]] == piece[pairs[:, 1]]] if len(pairs) else pairs
    if len(pairs):
        a, b = (int(x) for x in pairs[0])
        raise malformed_net(f"faces {a} and {b} overlap in the flat net ({len(pairs)} overlapping pair"
                            f"{'s' * (len(pairs) > 1)})")


def fold_tree(fold: dict, contact_tol: float = CONTACT_TOL) -> FoldTree:
    """The FoldTree of a FOLD net (as written by `pattern_fold`).

    Uses `polyfold:faces_parent` when present, else a BFS over the crease (non-B) edges from the
    lowest-index face of each piece. Raises PolyfoldError (one line naming the face / edge) when the
    net cannot be folded: non-triangular faces, bad indices, clockwise faces, a parent that is not
    joined by a crease, cycles, pieces inconsistent with the tree, zero-length creases, ...
    The per-face work is `fold.tree.build_tree` (one numba kernel); so that it runs once, the later
    inputs are parsed first and a parse error is raised where its check comes in this order.
    """
    if not isinstance(fold, dict):
        raise malformed_net("not a FOLD dict")
    for key in REQUIRED:
        if key not in fold:
            raise malformed_net(f"no {key!r}")
    xy = _float_array(fold["vertices_coords"], "vertices_coords", (2, 3))
    n_v = len(xy)
    folded = _folded_coords(fold, n_v)
    scale = bbox_diagonal(folded if folded is not None else xy)
    if not scale > 0:
        raise malformed_net("the net has zero size")
    if xy.shape[1] == 3:
        bad = np.flatnonzero(np.abs(xy[:, 2]) > 1e-9 * scale)
        if len(bad):
            raise malformed_net(f"vertex {bad[0]} of the crease pattern is not in the plane z = 0")
        xy = np.ascontiguousarray(xy[:, :2])
    _check_triangles(fold["faces_vertices"])
    faces = _int_array(fold, "faces_vertices", (3,), "vertex triples")
    n_f = len(faces)
    if n_f == 0:
        raise malformed_net("no faces")

    # parsed ahead of their checks (errors kept for later): edges, then the tree, then fold angles
    none = np.empty(0, dtype=np.int64)
    edges, kind, parent_in, piece_in, deg = none.reshape(0, 2), none.astype(np.int8), none, none, np.empty(0)
    stage, late = 1, None
    try:
        edges = _int_array(fold, "edges_vertices", (2,), "vertex pairs")
        kind = _assignments(fold["edges_assignment"], len(edges))
        stage = 2
        if "polyfold:faces_piece" in fold:
            piece_in = _int_array(fold, "polyfold:faces_piece", (), "integers")
            if len(piece_in) != n_f:
                raise malformed_net(f"'polyfold:faces_piece' has {len(piece_in)} entries for {n_f} faces")
        if "polyfold:faces_parent" in fold:
            parent_in = _int_array(fold, "polyfold:faces_parent", (), "integers")
            if len(parent_in) != n_f:
                raise malformed_net(f"'polyfold:faces_parent' has {len(parent_in)} entries for {n_f} faces")
        stage = 3
        if "edges_foldAngle" in fold:
            deg = _fold_angles(fold, len(edges))
            stage = 4
    except Exception as exc:  # noqa: BLE001 (raised below, after the checks that come first)
        late = exc
    tree = build_tree(xy, faces, edges, kind, parent_in, piece_in, deg, folded, contact_tol, scale, stage, late)
    _check_no_overlap(xy[faces], tree.parent, tree.piece, tree.tol)
    mesh_vertex = fold.get("polyfold:vertices_meshVertex")
    if isinstance(mesh_vertex, list) and len(mesh_vertex) == n_v:
        try:
            ids = np.asarray(mesh_vertex, dtype=np.int64)
        except (TypeError, ValueError, OverflowError):
            return tree
        return dataclasses.replace(tree, mesh_faces=np.ascontiguousarray(ids[faces]))
    return tree


def read_net(path: str | os.PathLike, contact_tol: float = CONTACT_TOL) -> tuple[dict, FoldTree]:
    """A FOLD file and its fold tree (`read_fold`, `fold_tree`); a net it cannot use is a
    PolyfoldError naming the file."""
    fold = read_fold(path)
    try:
        return fold, fold_tree(fold, contact_tol)
    except PolyfoldError as exc:
        raise type(exc)(f"{os.path.basename(os.fspath(path))}: {exc}") from None


# ----------------------------------------------------------------------------------------------
# Folding paths


def with_path(fold: dict, path: FoldPath, resolution_deg: float, contact_tol: float, thickness: float = 0.0,
              verified: bool = False) -> dict:
    """A copy of the FOLD dict with the path: `polyfold:path` (frames of FOLD fold angles in
    degrees, one per edge, 0 for B edges; first all 0, last = edges_foldAngle) and its facts
    (planner, linear, resolution in degrees, contact tolerance and material thickness relative
    to the model size: the foldedForm's bounding-box diagonal; thickness given here in the dict's
    units) and `polyfold:path_verified`: whether the independent check (`verify.paths`) accepted
    it at that thickness."""
    out = dict(fold)
    frames = path.degrees_fold()
    # The last frame is the goal itself: write the file's own angles so it matches bit for bit.
    frames[-1] = [float(a) for a in fold["edges_foldAngle"]]
    frames[0] = [0.0] * len(frames[0])
    out["polyfold:path"] = frames
    out["polyfold:path_planner"] = path.planner
    out["polyfold:path_linear"] = bool(path.linear)
    out["polyfold:path_resolutionDeg"] = float(resolution_deg)
    out["polyfold:path_contactTol"] = float(contact_tol)
    # relative to the model size as the tree measures it: the foldedForm, else the flat net
    flat = np.asarray(fold["vertices_coords"], dtype=np.float64)
    folded = _folded_coords(fold, len(flat))
    size = bbox_diagonal(folded if folded is not None else flat)
    out["polyfold:path_thicknessRel"] = float(thickness) / max(size, 1e-300)
    out["polyfold:path_verified"] = bool(verified)
    return out


PAGE_TO_FOLD = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # page mm (y down) <-> FOLD mm (y up): its own inverse


def piece_fold(pattern: CreasePattern, *, title: str, file_title: str, whole_mesh_faces: Sequence[int],
               path: FoldPath | None = None, resolution_deg: float = 1.0, contact_tol: float = CONTACT_TOL,
               thickness: float = 0.0, verified: bool = False,
               mm_per_unit: float | None = None, page: int | None = None, to_page: np.ndarray | None = None) -> dict:
    """The FOLD document of one piece of a make folder: its crease pattern (frame_title `title`),
    its folding path when it has one (`with_path`; thickness in model units), file_title, and `polyfold:faces_wholeMeshFace`
    (the piece's faces as faces of the whole model).

    Printed scale (make): with mm_per_unit (mm per model unit), page (1-based) and to_page (2, 3),
    the affine map from the pattern's coordinates (model units, y up) to the printed piece on its
    page (mm, origin at the page's top-left corner, y down), the file is in mm (`frame_unit` "mm"):
    vertices_coords are the printed positions in the FOLD convention, (x, -y) of the page point
    (y up, the printed = outer side facing +z, faces still CCW), the foldedForm frame is the model
    scaled to mm, and the custom keys are `polyfold:page`, `polyfold:sheet_transform` (the 2x3
    matrix [[a, b, c], [d, e, f]] taking a vertex (x, y) of the file to the page point
    (a x + b y + c, d x + e y + f) in mm, origin top-left, y down: here [[1, 0, 0], [0, -1, 0]])
    and `polyfold:mmPerModelUnit` (the model, e.g. part-K.obj, times this is the foldedForm).
    Fold angles, the path and its relative contact tolerance do not depend on the unit."""
    fold = pattern_fold(pattern, title=title)
    if path is not None:
        fold = with_path(fold, path, resolution_deg, contact_tol, thickness, verified)
    fold["file_title"] = file_title
    fold["polyfold:faces_wholeMeshFace"] = [int(x) for x in whole_mesh_faces]
    if mm_per_unit is not None:
        if to_page is None or page is None:
            raise ValueError("a FOLD piece in mm needs its page and its placement (to_page)")
        a = PAGE_TO_FOLD[:, :2] @ np.asarray(to_page, dtype=np.float64)  # pattern -> FOLD mm (y up)
        fold["frame_unit"] = "mm"
        fold["vertices_coords"] = (pattern.coords @ a[:, :2].T + a[:, 2]).tolist()
        fold["file_frames"] = [dict(fold["file_frames"][0], vertices_coords=(pattern.folded * mm_per_unit).tolist())]
        fold["polyfold:page"] = int(page)
        fold["polyfold:sheet_transform"] = PAGE_TO_FOLD.tolist()
        fold["polyfold:mmPerModelUnit"] = float(mm_per_unit)
    return fold


@dataclass(frozen=True, eq=False)
class FoldNet:
    """A FOLD net read back: its crease tree; the flat net (coords (V, 2), faces (F, 3), edges
    (E, 2), assignments upper-case); path (K, E) the `polyfold:path` frames in FOLD degrees, or
    None; goal (E,) the folded angles in FOLD degrees (the path's last frame, else
    edges_foldAngle, else the tree's own goal)."""

    tree: FoldTree
    coords: np.ndarray
    faces: np.ndarray
    edges: np.ndarray
    assignments: tuple[str, ...]
    path: np.ndarray | None
    goal: np.ndarray


def fold_net(fold: dict, contact_tol: float = CONTACT_TOL) -> FoldNet:
    """The FoldNet of a FOLD dict; PolyfoldError (one line) when the net or its path is malformed."""
    tree = fold_tree(fold, contact_tol)
    path = None
    if fold.get("polyfold:path"):
        path = np.asarray(fold["polyfold:path"], dtype=np.float64)
        if path.ndim != 2 or path.shape[1] != tree.n_edges:
            raise PolyfoldError(f"polyfold:path frames must have one angle per edge ({tree.n_edges})")
        goal = path[-1]
    elif fold.get("edges_foldAngle") is not None:
        goal = np.asarray(fold["edges_foldAngle"], dtype=np.float64)
    else:  # no angles in the file: the tree's own goal
        goal = rho_to_fold_deg(tree.goal)
    coords = np.asarray(fold["vertices_coords"], dtype=np.float64)[:, :2]
    return FoldNet(tree=tree, coords=coords, faces=tree.faces, edges=np.asarray(fold["edges_vertices"], dtype=np.int64),
                   assignments=tuple(str(a).upper() for a in fold["edges_assignment"]), path=path, goal=goal)
