"""FOLD 1.1 files: the canonical net format (https://github.com/edemaine/fold).

`net_to_fold` turns the nets of all components of a mesh into one FOLD dict: the flat crease
pattern (2D `vertices_coords`, outer side facing +z), `edges_assignment` B/M/V/F,
`edges_foldAngle` in degrees (valley positive, mountain negative: convex mesh edges are
mountains), and a `foldedForm` frame holding the 3D position of every net vertex. Custom keys:
`polyfold:faces_meshFace` (source face in the input file's face order), `polyfold:faces_piece`,
`polyfold:faces_component`, `polyfold:faces_parent` (the tree: net face joined to each face by a
crease, -1 at the root of a piece), `polyfold:edges_meshEdge` (twin cut edges share the number),
`polyfold:vertices_meshVertex`.
"""

from __future__ import annotations

import json
import math
import os
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..errors import PolyfoldError
from ..mesh.geometry import FLAT_EPS, vector_norm
from ..unfold import pattern_kernels as FK
from ..unfold.net import Net

if TYPE_CHECKING:
    from ..fold.plan import FoldPath
PIECE_GAP = 0.05  # gap between packed pieces, as a fraction of the model's bounding-box diagonal
_ASSIGNMENTS = ("B", "F", "M", "V")  # edges_assignment by kind: cut, flat, mountain, valley


def _piece_offsets(lo: np.ndarray, hi: np.ndarray, gap: float) -> np.ndarray:
    """Shelf-pack the pieces' bounding boxes (lo, hi (P, 2)): translation (P, 2) per piece."""
    n_p = len(lo)
    size = (hi - lo).tolist()
    lo = lo.tolist()
    # (the row width only matters once a shelf holds a piece: not for a single piece)
    row_width = max(max(w for w, _ in size), math.sqrt(sum(w * h for w, h in size)) * 1.5) if n_p > 1 else 0.0
    offsets = [None] * n_p
    x = y = shelf = 0.0
    # a handful of pieces: plain Python over lists is cheaper than numpy here
    for p in sorted(range(n_p), key=lambda i: -size[i][1]) if n_p > 1 else (0,):
        w, h = size[p]
        if x > 0 and x + w > row_width:
            x, y, shelf = 0.0, y + shelf + gap, 0.0
        offsets[p] = (x - lo[p][0], -(y + h) - lo[p][1])
        x += w + gap
        shelf = max(shelf, h)
    return np.array(offsets)


def _joined(parts: list[np.ndarray]) -> list:
    """The parts (one per component) as one list (a single part is not copied first)."""
    return (parts[0] if len(parts) == 1 else np.concatenate(parts)).tolist()


def net_to_fold(nets: Sequence[Net], *, creator: str = "polyfold", title: str | None = None) -> dict:
    """FOLD dict of the nets of one mesh (one Net per component, each with one or more pieces)."""
    # per net (numba): net vertices, numbered on from the previous nets', their 3D points, piece boxes
    found = []
    mv_off = 0
    for n in nets:
        found.append(FK.net_vertices(n.mesh.faces, n.parent, n.parent_edge, n.mesh.topology.edges, n.mesh.vertices,
                                     n.coords, n.piece, mv_off))
        mv_off += len(n.mesh.vertices)
    # the net vertices' 3D points are the mesh's used vertices: their box is Mesh.bbox_diagonal's
    scale = max(max(vector_norm(extent) for _, _, _, extent, _, _ in found), 1e-300)
    # Pack all pieces of all components together, so the sheet has no overlaps between pieces either.
    boxes = [(lo, hi) for *_, lo, hi in found]
    lo, hi = boxes[0] if len(boxes) == 1 else (np.concatenate([b[0] for b in boxes]), np.concatenate([b[1] for b in boxes]))
    offsets = _piece_offsets(lo, hi, PIECE_GAP * scale)
    coords2d, coords3d, mesh_vertex = [], [], []
    faces_v, faces_src, faces_piece, faces_comp, faces_parent = [], [], [], [], []
    edges_v, edges_a, edges_ang, edges_mesh = [], [], [], []
    v_off = f_off = p_off = e_off = 0
    for c, (net, (corner_v, mv, folded, _, lo, _)) in enumerate(zip(nets, found)):
        mesh = net.mesh
        topo = mesh.topology
        xy, fv, piece, parent, ev, em, angle, kind = FK.net_edges(
            corner_v, len(mv), net.coords, offsets[p_off:p_off + len(lo)], net.piece, topo.face_edges, net.parent,
            net.parent_edge, mesh.fold_angles, FLAT_EPS, v_off, f_off, p_off, e_off)
        coords2d.append(xy)
        coords3d.append(folded)
        mesh_vertex.append(mv)
        faces_v.append(fv)
        faces_src.append(mesh.face_source)
        faces_piece.append(piece)
        faces_comp.extend([c] * mesh.n_faces)
        faces_parent.append(parent)
        edges_v.append(ev)
        edges_a.extend(map(_ASSIGNMENTS.__getitem__, kind.tolist()))
        edges_ang.append(angle)
        edges_mesh.append(em)
        v_off += len(mv)
        f_off += mesh.n_faces
        p_off += len(lo)
        e_off += topo.n_edges
    fold = {
        "file_spec": 1.1,
        "file_creator": creator,
        "file_classes": ["singleModel"],
        "frame_title": title or "polyfold net",
        "frame_classes": ["creasePattern"],
        "frame_attributes": ["2D"],
        "frame_unit": "unit",
        "vertices_coords": _joined(coords2d),
        "faces_vertices": _joined(faces_v),
        "edges_vertices": _joined(edges_v),
        "edges_assignment": edges_a,
        "edges_foldAngle": _joined(edges_ang),
        "polyfold:faces_meshFace": _joined(faces_src),
        "polyfold:faces_piece": _joined(faces_piece),
        "polyfold:faces_component": faces_comp,
        "polyfold:faces_parent": _joined(faces_parent),
        "polyfold:edges_meshEdge": _joined(edges_mesh),
        "polyfold:vertices_meshVertex": _joined(mesh_vertex),
        "file_frames": [
            {
                "frame_classes": ["foldedForm"],
                "frame_attributes": ["3D"],
                "frame_inherit": True,
                "frame_parent": 0,
                "vertices_coords": _joined(coords3d),
            }
        ],
    }
    return fold


def dumps(fold: dict) -> str:
    """FOLD JSON text (floats written with full precision)."""
    return json.dumps(fold, separators=(",", ":"))


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
    for key in ("vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment"):
        if key not in fold:
            raise PolyfoldError(f"{name}: FOLD file has no {key!r}")
    return fold


def with_path(fold: dict, path: FoldPath, resolution_deg: float, contact_tol: float) -> dict:
    """A copy of the FOLD dict with the path: `polyfold:path` (frames of FOLD fold angles in
    degrees, one per edge, 0 for B edges; first all 0, last = edges_foldAngle) and its facts
    (planner, linear, resolution in degrees, contact tolerance relative to the model size)."""
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
    return out
