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
import os
from typing import Sequence

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .unfold import Net

FLAT_EPS = 1e-10  # |rho| below this (radians) is a flat crease ("F", fold angle 0)
PIECE_GAP = 0.05  # gap between packed pieces, as a fraction of the model's bounding-box diagonal


def _net_vertices(net: Net) -> np.ndarray:
    """Net vertex id (F, 3) of every face corner: corners of one mesh vertex are the same net
    vertex when the faces are joined by creases around it."""
    faces = net.mesh.faces
    n = len(faces)
    child = np.flatnonzero(net.parent >= 0)
    par = net.parent[child]
    ends = net.mesh.topology.edges[net.parent_edge[child]]
    rows, cols = [], []
    for end in (ends[:, 0], ends[:, 1]):
        kc = np.argmax(faces[child] == end[:, None], axis=1)
        kp = np.argmax(faces[par] == end[:, None], axis=1)
        rows.append(child * 3 + kc)
        cols.append(par * 3 + kp)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(3 * n, 3 * n))
    _, labels = connected_components(graph, directed=False)
    return labels.reshape(n, 3)


def _piece_offsets(coords: np.ndarray, piece: np.ndarray, gap: float) -> np.ndarray:
    """Shelf-pack the pieces' bounding boxes: translation (P, 2) per piece."""
    n_p = int(piece.max()) + 1
    lo = np.full((n_p, 2), np.inf)
    hi = np.full((n_p, 2), -np.inf)
    pts = coords.reshape(-1, 2)
    pid = np.repeat(piece, 3)
    np.minimum.at(lo, pid, pts)
    np.maximum.at(hi, pid, pts)
    size = hi - lo
    row_width = max(float(size[:, 0].max()), float(np.sqrt((size[:, 0] * size[:, 1]).sum()) * 1.5))
    offsets = np.zeros((n_p, 2))
    x = y = shelf = 0.0
    for p in np.argsort(-size[:, 1], kind="stable"):
        if x > 0 and x + size[p, 0] > row_width:
            x, y, shelf = 0.0, y + shelf + gap, 0.0
        offsets[p] = (x - lo[p, 0], -(y + size[p, 1]) - lo[p, 1] + 0.0)
        x += size[p, 0] + gap
        shelf = max(shelf, size[p, 1])
    return offsets


def net_to_fold(nets: Sequence[Net], *, creator: str = "polyfold", title: str | None = None) -> dict:
    """FOLD dict of the nets of one mesh (one Net per component, each with one or more pieces)."""
    coords2d, coords3d, mesh_vertex = [], [], []
    faces_v, faces_src, faces_piece, faces_comp, faces_parent = [], [], [], [], []
    edges_v, edges_a, edges_ang, edges_mesh = [], [], [], []
    v_off = f_off = p_off = e_off = 0
    scale = max(max(n.mesh.bbox_diagonal for n in nets), 1e-300)
    all_coords = []
    for c, net in enumerate(nets):
        mesh = net.mesh
        topo = mesh.topology
        corner_v = _net_vertices(net)
        n_v = int(corner_v.max()) + 1
        # Pieces are moved apart so the sheet has no overlaps between pieces either.
        all_coords.append((net, corner_v, n_v))
    # Pack all pieces of all components together.
    piece_all = np.concatenate([n.piece + sum(m.n_pieces for m in nets[:i]) for i, n in enumerate(nets)])
    coords_all = np.concatenate([n.coords for n in nets])
    offsets = _piece_offsets(coords_all, piece_all, PIECE_GAP * scale)
    for c, (net, corner_v, n_v) in enumerate(all_coords):
        mesh = net.mesh
        topo = mesh.topology
        placed = net.coords + offsets[net.piece + p_off][:, None, :]
        xy = np.zeros((n_v, 2))
        xy[corner_v.reshape(-1)] = placed.reshape(-1, 2)
        mv = np.zeros(n_v, dtype=np.int64)
        mv[corner_v.reshape(-1)] = mesh.faces.reshape(-1)
        coords2d.append(xy)
        coords3d.append(mesh.vertices[mv])
        mesh_vertex.append(mv + sum(len(n.mesh.vertices) for n in nets[:c]))
        faces_v.append(corner_v + v_off)
        faces_src.append(mesh.face_source)
        faces_piece.append(net.piece + p_off)
        faces_comp.append(np.full(mesh.n_faces, c))
        faces_parent.append(np.where(net.parent >= 0, net.parent + f_off, -1))
        # Net edges: each face side; creases are shared by two faces, cut edges appear twice.
        side_v = np.stack([corner_v, np.roll(corner_v, -1, axis=1)], axis=2).reshape(-1, 2)
        side_e = topo.face_edges.reshape(-1)
        key = np.sort(side_v, axis=1)
        uniq, first = np.unique(key, axis=0, return_index=True)
        first = np.sort(first)
        ev = side_v[first]
        em = side_e[first]
        crease = net.crease_mask[em]
        rho = mesh.fold_angles[em]
        assign = np.where(~crease, "B", np.where(np.abs(rho) < FLAT_EPS, "F", np.where(rho > 0, "M", "V")))
        angle = np.where((assign == "M") | (assign == "V"), -np.degrees(rho), 0.0)
        edges_v.append(ev + v_off)
        edges_a.extend(assign.tolist())
        edges_ang.append(angle)
        edges_mesh.append(em + e_off)
        v_off += n_v
        f_off += mesh.n_faces
        p_off += net.n_pieces
        e_off += topo.n_edges
    fold = {
        "file_spec": 1.1,
        "file_creator": creator,
        "file_classes": ["singleModel"],
        "frame_title": title or "polyfold net",
        "frame_classes": ["creasePattern"],
        "frame_attributes": ["2D"],
        "frame_unit": "unit",
        "vertices_coords": np.concatenate(coords2d).tolist(),
        "faces_vertices": np.concatenate(faces_v).tolist(),
        "edges_vertices": np.concatenate(edges_v).tolist(),
        "edges_assignment": edges_a,
        "edges_foldAngle": np.concatenate(edges_ang).tolist(),
        "polyfold:faces_meshFace": np.concatenate(faces_src).tolist(),
        "polyfold:faces_piece": np.concatenate(faces_piece).tolist(),
        "polyfold:faces_component": np.concatenate(faces_comp).tolist(),
        "polyfold:faces_parent": np.concatenate(faces_parent).tolist(),
        "polyfold:edges_meshEdge": np.concatenate(edges_mesh).tolist(),
        "polyfold:vertices_meshVertex": np.concatenate(mesh_vertex).tolist(),
        "file_frames": [
            {
                "frame_classes": ["foldedForm"],
                "frame_attributes": ["3D"],
                "frame_inherit": True,
                "frame_parent": 0,
                "vertices_coords": np.concatenate(coords3d).tolist(),
            }
        ],
    }
    return fold


def dumps(fold: dict) -> str:
    """FOLD JSON text (floats written with full precision)."""
    return json.dumps(fold, separators=(",", ":"))


def read_fold(path: str | os.PathLike) -> dict:
    """Read a FOLD file; raises PolyfoldError with a one-line message when it is not usable."""
    from .errors import PolyfoldError

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
