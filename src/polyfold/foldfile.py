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
from typing import Sequence

import numpy as np
from numba import njit

from .unfold import Net

FLAT_EPS = 1e-10  # |rho| below this (radians) is a flat crease ("F", fold angle 0)
PIECE_GAP = 0.05  # gap between packed pieces, as a fraction of the model's bounding-box diagonal
_ASSIGNMENTS = np.array(["B", "F", "M", "V"])  # edges_assignment by kind: cut, flat, mountain, valley


@njit(cache=True)
def _corner_labels(faces, parent, parent_edge, edges):
    """Net vertex (F*3,) of every face corner, numbered in order of first corner (row-major).

    A child's corners at the ends of its crease are joined to its parent's corners there; each
    child corner points to at most one parent corner, so the joins form a forest over the corners
    and a net vertex is one of its trees (found by walking up to the tree's root).
    """
    n = faces.shape[0]
    link = np.arange(3 * n)
    for f in range(n):
        p = parent[f]
        if p < 0:
            continue
        for end in range(2):
            v = edges[parent_edge[f], end]
            kc = 0
            while kc < 2 and faces[f, kc] != v:
                kc += 1
            kp = 0
            while kp < 2 and faces[p, kp] != v:
                kp += 1
            link[3 * f + kc] = 3 * p + kp
    label = np.full(3 * n, -1)
    count = 0
    for c in range(3 * n):
        r = c
        while link[r] != r:
            r = link[r]
        if label[r] < 0:
            label[r] = count
            count += 1
        label[c] = label[r]
    return label


def _net_vertices(net: Net) -> np.ndarray:
    """Net vertex id (F, 3) of every face corner: corners of one mesh vertex are the same net
    vertex when the faces are joined by creases around it."""
    faces = net.mesh.faces
    return _corner_labels(faces, net.parent, net.parent_edge, net.mesh.topology.edges).reshape(len(faces), 3)


def _piece_offsets(coords: np.ndarray, piece: np.ndarray, gap: float) -> np.ndarray:
    """Shelf-pack the pieces' bounding boxes: translation (P, 2) per piece."""
    n_p = int(piece.max()) + 1
    # boxes by segments of the faces sorted by piece (every piece has faces; faster than ufunc.at)
    order = np.argsort(piece, kind="stable")
    pts = coords[order].reshape(-1, 2)
    start = 3 * np.searchsorted(piece[order], np.arange(n_p))
    lo = np.minimum.reduceat(pts, start)
    hi = np.maximum.reduceat(pts, start)
    size = (hi - lo).tolist()
    lo = lo.tolist()
    row_width = max(max(w for w, _ in size), math.sqrt(sum(w * h for w, h in size)) * 1.5)
    offsets = np.zeros((n_p, 2))
    x = y = shelf = 0.0
    # a handful of pieces: plain Python over lists is cheaper than numpy here
    for p in sorted(range(n_p), key=lambda i: -size[i][1]):
        w, h = size[p]
        if x > 0 and x + w > row_width:
            x, y, shelf = 0.0, y + shelf + gap, 0.0
        offsets[p] = (x - lo[p][0], -(y + h) - lo[p][1])
        x += w + gap
        shelf = max(shelf, h)
    return offsets


def _first_sides(side_v: np.ndarray, n_v: int) -> np.ndarray:
    """Indices (ascending) of the face sides (S, 2) that are net edges: the first side of each net
    vertex pair (a crease is shared by two faces; each side of a cut edge is an edge of its own)."""
    u, v = side_v[:, 0], side_v[:, 1]
    key = np.minimum(u, v) * n_v + np.maximum(u, v)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    first = np.ones(len(key), dtype=bool)
    first[1:] = ks[1:] != ks[:-1]
    return np.sort(order[first])


def net_to_fold(nets: Sequence[Net], *, creator: str = "polyfold", title: str | None = None) -> dict:
    """FOLD dict of the nets of one mesh (one Net per component, each with one or more pieces)."""
    coords2d, coords3d, mesh_vertex = [], [], []
    faces_v, faces_src, faces_piece, faces_comp, faces_parent = [], [], [], [], []
    edges_v, edges_a, edges_ang, edges_mesh = [], [], [], []
    v_off = f_off = p_off = e_off = mv_off = 0
    corners, mesh_vs = [], []
    for net in nets:
        corner_v = _net_vertices(net)
        mv = np.zeros(int(corner_v.max()) + 1, dtype=np.int64)
        mv[corner_v.reshape(-1)] = net.mesh.faces.reshape(-1)
        corners.append(corner_v)
        mesh_vs.append(mv)
        coords3d.append(net.mesh.vertices[mv])
    # the net vertices' 3D points are the mesh's used vertices: their box is Mesh.bbox_diagonal's
    scale = max(max(float(np.linalg.norm(p.max(axis=0) - p.min(axis=0))) for p in coords3d), 1e-300)
    # Pack all pieces of all components together, so the sheet has no overlaps between pieces either.
    n_pieces = [n.n_pieces for n in nets]
    piece_all = np.concatenate([n.piece + sum(n_pieces[:i]) for i, n in enumerate(nets)])
    coords_all = np.concatenate([n.coords for n in nets])
    offsets = _piece_offsets(coords_all, piece_all, PIECE_GAP * scale)
    for c, (net, corner_v, mv) in enumerate(zip(nets, corners, mesh_vs)):
        mesh = net.mesh
        topo = mesh.topology
        n_v = len(mv)
        placed = net.coords + offsets[net.piece + p_off][:, None, :]
        xy = np.zeros((n_v, 2))
        xy[corner_v.reshape(-1)] = placed.reshape(-1, 2)
        coords2d.append(xy)
        mesh_vertex.append(mv + mv_off)
        faces_v.append(corner_v + v_off)
        faces_src.append(mesh.face_source)
        faces_piece.append(net.piece + p_off)
        faces_comp.append(np.full(mesh.n_faces, c))
        faces_parent.append(np.where(net.parent >= 0, net.parent + f_off, -1))
        side_v = corner_v[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)  # (3F, 2) face sides, corner k -> k + 1
        first = _first_sides(side_v, n_v)
        ev = side_v[first]
        em = topo.face_edges.reshape(-1)[first]
        rho = mesh.fold_angles[em]
        kind = np.where(net.crease_mask[em], np.where(np.abs(rho) < FLAT_EPS, 1, np.where(rho > 0, 2, 3)), 0)
        edges_v.append(ev + v_off)
        edges_a.extend(_ASSIGNMENTS[kind].tolist())
        edges_ang.append(np.where(kind >= 2, -np.degrees(rho), 0.0))
        edges_mesh.append(em + e_off)
        v_off += n_v
        f_off += mesh.n_faces
        p_off += n_pieces[c]
        e_off += topo.n_edges
        mv_off += len(mesh.vertices)
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
