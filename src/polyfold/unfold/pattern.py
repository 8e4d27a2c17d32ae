"""A net as a crease pattern: the nets of a mesh's components drawn together in one plane.

`crease_pattern(nets)` gives a `CreasePattern`: net vertices (face corners joined by creases are
one vertex), every piece translated so no two pieces' boxes overlap, net edges with their
assignment (cut, flat, mountain, valley) and FOLD fold angle, and the maps back to the mesh. It is
what a FOLD file holds (`formats/fold.py` writes it, key for key) and what the fold stage builds
its crease tree from (`fold.tree.FoldTree.from_pattern`), so a net and its FOLD file give the same
tree, bit for bit, without a file in between.

Fold angles follow FOLD: degrees, valley positive, mountain negative (`mesh.geometry.fold_degrees`
of the mesh's signed angle rho, + = convex = mountain); flat creases (|rho| < FLAT_EPS) and cuts
have 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..mesh.geometry import FLAT_EPS, vector_norm
from ..shelves import shelf_offsets
from . import pattern_kernels as PK
from .net import Net

PIECE_GAP = 0.05  # gap between placed pieces, as a fraction of the model's bounding-box diagonal
CUT, FLAT, MOUNTAIN, VALLEY = 0, 1, 2, 3  # `CreasePattern.kind`
ASSIGNMENTS = ("B", "F", "M", "V")  # FOLD edges_assignment of each kind


@dataclass(frozen=True, eq=False)
class CreasePattern:
    """The nets of one mesh in one plane (V net vertices, F faces, E net edges, P pieces).

    coords (V, 2) flat positions (outer side of the surface facing +z); folded (V, 3) the 3D
    point of each net vertex; faces (F, 3) net vertex ids, CCW seen from +z; parent (F,) the face
    each face is joined to by a crease (-1 at the root of a piece); piece (F,) and component (F,)
    numbered across all nets; mesh_face (F,) the source face in the input file's order; edges
    (E, 2) net vertex pairs; kind (E,) CUT / FLAT / MOUNTAIN / VALLEY; fold_deg (E,) FOLD fold
    angles; mesh_edge (E,) (the two sides of a cut share it); mesh_vertex (V,) (numbered across
    the nets' meshes, one after the other).
    """

    coords: np.ndarray
    folded: np.ndarray
    faces: np.ndarray
    parent: np.ndarray
    piece: np.ndarray
    component: np.ndarray
    mesh_face: np.ndarray
    edges: np.ndarray
    kind: np.ndarray
    fold_deg: np.ndarray
    mesh_edge: np.ndarray
    mesh_vertex: np.ndarray

    @property
    def assignments(self) -> list[str]:
        """FOLD edges_assignment (E,): "B", "F", "M" or "V"."""
        return list(map(ASSIGNMENTS.__getitem__, self.kind.tolist()))


def _piece_offsets(lo: np.ndarray, hi: np.ndarray, gap: float) -> np.ndarray:
    """Translations (P, 2) that put the pieces' bounding boxes (lo, hi (P, 2)) on shelves, rows
    going down from y = 0 (`shelves.shelf_offsets`; rows about 1.5 times as wide as the pieces'
    total area is deep)."""
    size = (hi - lo).tolist()
    row_width = max(max(w for w, _ in size), math.sqrt(sum(w * h for w, h in size)) * 1.5) if len(size) > 1 else 0.0
    return np.array([(x - lo_p[0], -(y + h) - lo_p[1])
                     for (_, x, y), (_, h), lo_p in zip(shelf_offsets(size, row_width, math.inf, gap), size, lo.tolist())])


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    """The parts (one per net) as one array (a single part is not copied)."""
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def crease_pattern(nets: Sequence[Net]) -> CreasePattern:
    """The crease pattern of the nets of one mesh (one Net per component, each with one or more
    pieces); all pieces of all nets are placed apart, so the pattern has no overlaps either."""
    # per net (numba): net vertices, numbered on from the previous nets', their 3D points, piece boxes
    found = []
    mv_off = 0
    for n in nets:
        found.append(PK.net_vertices(n.mesh.faces, n.parent, n.parent_edge, n.mesh.topology.edges, n.mesh.vertices,
                                     n.coords, n.piece, mv_off))
        mv_off += len(n.mesh.vertices)
    # the net vertices' 3D points are the mesh's used vertices: their box is Mesh.bbox_diagonal's
    scale = max(max(vector_norm(extent) for _, _, _, extent, _, _ in found), 1e-300)
    boxes = [(lo, hi) for *_, lo, hi in found]
    lo, hi = boxes[0] if len(boxes) == 1 else (np.concatenate([b[0] for b in boxes]), np.concatenate([b[1] for b in boxes]))
    offsets = _piece_offsets(lo, hi, PIECE_GAP * scale)
    cols: dict[str, list] = {k: [] for k in ("coords", "folded", "faces", "parent", "piece", "component", "mesh_face",
                                             "edges", "kind", "fold_deg", "mesh_edge", "mesh_vertex")}
    v_off = f_off = p_off = e_off = 0
    for c, (net, (corner_v, mv, folded, _, lo, _)) in enumerate(zip(nets, found)):
        mesh = net.mesh
        topo = mesh.topology
        xy, fv, piece, parent, ev, em, angle, kind = PK.net_edges(
            corner_v, len(mv), net.coords, offsets[p_off:p_off + len(lo)], net.piece, topo.face_edges, net.parent,
            net.parent_edge, mesh.fold_angles, FLAT_EPS, v_off, f_off, p_off, e_off)
        for key, value in (("coords", xy), ("folded", folded), ("faces", fv), ("parent", parent), ("piece", piece),
                           ("component", np.full(mesh.n_faces, c, dtype=np.int64)), ("mesh_face", mesh.face_source),
                           ("edges", ev), ("kind", kind), ("fold_deg", angle), ("mesh_edge", em), ("mesh_vertex", mv)):
            cols[key].append(value)
        v_off += len(mv)
        f_off += mesh.n_faces
        p_off += len(lo)
        e_off += topo.n_edges
    return CreasePattern(**{k: _joined(v) for k, v in cols.items()})
