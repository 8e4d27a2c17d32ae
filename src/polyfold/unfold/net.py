"""Nets: a spanning forest of a mesh's dual graph laid out in the plane (the unfold stage's
result), and the operations on them that never move a face: cutting creases, taking one piece
as a net of its own, finding the crease that splits a piece most evenly. The merged creases of
flat regions (`mesh.geometry.merged_edges`) are never cut: `Net.cuttable` says which creases may be.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh.geometry import merged_edges
from ..mesh.mesh import Mesh
from . import kernels as K


@dataclass(frozen=True, eq=False)
class Net:
    """A net of one mesh component: a spanning forest of its dual graph laid out in the plane.

    parent (F,): parent face in the tree, -1 for the root of each piece; parent_edge (F,): the mesh
    edge (crease) joining a face to its parent, -1 for roots; order (F,): faces with parents first;
    coords (F, 3, 2): 2D position of each face's corners (same corner order as mesh.faces, CCW seen
    from +z, outer side up); piece (F,): piece label (0..pieces-1).
    """

    mesh: Mesh
    parent: np.ndarray
    parent_edge: np.ndarray
    order: np.ndarray
    coords: np.ndarray
    piece: np.ndarray

    @property
    def n_pieces(self) -> int:
        return int(self.piece.max()) + 1 if len(self.piece) else 0

    @property
    def crease_mask(self) -> np.ndarray:
        """(E,) True for mesh edges that are creases of the net."""
        mask = np.zeros(self.mesh.topology.n_edges, dtype=bool)
        pe = self.parent_edge[self.parent_edge >= 0]
        mask[pe] = True
        return mask

    @property
    def cuttable(self) -> np.ndarray:
        """(F,) True for faces whose crease to their parent may be cut: it exists and is not a
        merged edge of a flat region (those keep a flat polygon whole)."""
        merged = merged_edges(self.mesh)
        return (self.parent_edge >= 0) & ~merged[self.parent_edge]


def cut_creases(net: Net, faces: np.ndarray) -> Net:
    """The net with the creases between `faces` and their parents cut: each such face becomes the
    root of a new piece. The layout is unchanged, so every new piece is as overlap-free as before."""
    faces = np.asarray(faces, dtype=np.int64)
    parent = net.parent.copy()
    parent_edge = net.parent_edge.copy()
    parent[faces] = -1
    parent_edge[faces] = -1
    piece = K.piece_labels(net.order, parent)
    return Net(mesh=net.mesh, parent=parent, parent_edge=parent_edge, order=net.order.copy(),
               coords=net.coords.copy(), piece=piece)


def piece_net(net: Net, piece: int) -> tuple[Net, np.ndarray]:
    """One piece of a net as a single-piece Net of its own faces: (net, face ids in net.mesh).

    The piece's mesh is `net.mesh.submesh(face_ids)`; crease ids are renumbered into its edges."""
    fids = np.flatnonzero(net.piece == piece)
    sub = net.mesh.submesh(fids)
    new_id = np.full(len(net.piece), -1, dtype=np.int64)
    new_id[fids] = np.arange(len(fids))
    used = np.unique(net.mesh.faces[fids])
    old_edges = net.mesh.topology.edges
    sub_edges = sub.topology.edges
    # crease (old mesh edge) -> the same vertex pair in the sub-mesh's vertex numbering
    se = np.sort(sub_edges, axis=1)
    key = se[:, 0] * (len(used) + 1) + se[:, 1]
    order = np.argsort(key)
    parent = new_id[np.where(net.parent[fids] >= 0, net.parent[fids], 0)]
    parent[net.parent[fids] < 0] = -1
    parent_edge = np.full(len(fids), -1, dtype=np.int64)
    has = np.flatnonzero(net.parent_edge[fids] >= 0)
    if len(has):
        ends = np.searchsorted(used, old_edges[net.parent_edge[fids[has]]])
        ends.sort(axis=1)
        k = ends[:, 0] * (len(used) + 1) + ends[:, 1]
        parent_edge[has] = order[np.searchsorted(key, k, sorter=order)]
    net_order = new_id[net.order[np.isin(net.order, fids)]]
    out = Net(mesh=sub, parent=parent, parent_edge=parent_edge, order=net_order, coords=net.coords[fids].copy(),
              piece=np.zeros(len(fids), dtype=np.int64))
    return out, fids


def _dfs_intervals(parent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Euler-tour (tin, tout) per face of a forest: g is in the subtree of f iff
    tin[f] <= tin[g] < tout[f] (`kernels.dfs_intervals`)."""
    return K.dfs_intervals(np.asarray(parent, dtype=np.int64))


def subtree_areas(net: Net) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(sub_area, tin, tout) per face: the flat area of the face's subtree in the net (net units^2)
    and its Euler-tour interval (see `_dfs_intervals`)."""
    xy = net.coords
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    sub_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    tin, tout = _dfs_intervals(net.parent)
    # a subtree is a contiguous run in tin order: its area is a difference of prefix sums
    prefix = np.concatenate([[0.0], np.cumsum(sub_area[np.argsort(tin)])])
    return prefix[tout] - prefix[tin], tin, tout


def balanced_cut(net: Net, piece: int) -> int | None:
    """The face of `piece` whose crease to its parent (one that may be cut, `Net.cuttable`) splits
    the piece's area most evenly; None when the piece has no such crease (one face, or one flat
    polygon)."""
    faces = np.flatnonzero(net.piece == piece)
    cand = faces[net.cuttable[faces]]
    if len(cand) == 0:
        return None
    sub_area, _, _ = subtree_areas(net)
    root = faces[net.parent[faces] < 0][0]
    return int(cand[np.argmin(np.abs(sub_area[cand] - sub_area[root] / 2))])
