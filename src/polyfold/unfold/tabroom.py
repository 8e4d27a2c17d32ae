"""Room for glue tabs: edge swaps that open the narrow notches of a net.

A net's outline has a corner wherever its cut edges meet at a vertex. Seen from outside the net a
corner leaves a free angle (2 pi minus the face angles it holds); at a leaf of the cut tree it is
the vertex's angle defect, tiny on a smooth surface. A corner narrower than NOTCH_DEG leaves no
room for the glue tab of either edge beside it. `open_notches` swaps tree edges (cut a crease at
the notch's vertex that halves its angle, glue a cut edge that reconnects the two halves) while
the net stays overlap-free and the notches' total shortfall (`corner_penalty`) falls.

In: a single-piece `Net` of a closed or open mesh, the creases that must stay (`keep`; the merged
edges of flat regions, `mesh.geometry.merged_edges`, always stay), a `Deadline`. Out: a `Net` of
the same faces (one piece, overlap-free, re-laid out) and `TabRoomStats`. Multi-piece nets are
returned unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..collide.flat import face_bounds, overlapping_pairs, overlapping_pairs_between
from ..deadline import Deadline
from ..jit import njit
from ..mesh.geometry import corner_angles, merged_edges
from . import kernels as K
from .net import Net, _dfs_intervals
from .problem import UnfoldProblem

NOTCH_DEG = 40.0  # corners with less free angle than this leave too little room for a tab
MAX_TRIES = 24  # reconnecting cut edges tried (best first) per crease cut at a notch
MAX_PASSES = 4  # passes over the notches
MAX_CUTS = 4  # creases tried per notch (those nearest to halving its angle first)


@dataclass(frozen=True)
class TabRoomStats:
    notches_before: int  # corners narrower than NOTCH_DEG
    notches_after: int
    swaps: int
    timed_out: bool


class _Fans:
    """Corner bookkeeping of one mesh: for a vertex and a crease mask, the outline corners there."""

    def __init__(self, net: Net) -> None:
        mesh = net.mesh
        topo = mesh.topology
        self.faces = mesh.faces
        self.face_edges = topo.face_edges
        self.edge_faces = topo.edge_faces
        self.angle = corner_angles(mesh.vertices, mesh.faces)
        flat = mesh.faces.reshape(-1)
        order = np.argsort(flat, kind="stable")
        self.ptr = np.searchsorted(flat[order], np.arange(mesh.n_vertices + 1))
        self.inc_face = order // 3
        self.inc_corner = order % 3

    def corners(self, v: int, crease: np.ndarray) -> list[tuple[int, int, float]]:
        """(edge in, edge out, held angle) of every outline corner at vertex v: turning around v
        through creases from a cut (or boundary) edge to the next one. Empty when every edge at v
        is a crease (v inside the net)."""
        out = []
        for i in range(self.ptr[v], self.ptr[v + 1]):
            f, j = int(self.inc_face[i]), int(self.inc_corner[i])
            e_in = int(self.face_edges[f, (j + 2) % 3])
            if not crease[e_in]:
                e_out, held = _turn(v, f, j, crease, self.ptr[v + 1] - self.ptr[v], self.face_edges, self.edge_faces,
                                    self.faces, self.angle)
                out.append((e_in, int(e_out), float(held)))
        return out

    def penalties(self, verts: np.ndarray, crease: np.ndarray) -> np.ndarray:
        """(len(verts),) the summed `corner_penalty` of the outline corners at each vertex."""
        return _vertex_penalties(np.asarray(verts, dtype=np.int64), crease, self.ptr, self.inc_face, self.inc_corner,
                                 self.face_edges, self.edge_faces, self.faces, self.angle)

    def swap_gains(self, e2: int, cand: np.ndarray, crease: np.ndarray, edges: np.ndarray, pen: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For cutting crease e2 and gluing each cut edge of `cand`: the change of the total penalty
        (C,), the vertices it touches (C, 4; -1 pads) and their penalties after the swap (C, 4)."""
        return _swap_gains(e2, cand, crease, edges, pen, self.ptr, self.inc_face, self.inc_corner, self.face_edges,
                           self.edge_faces, self.faces, self.angle)


NOTCH_RAD = math.radians(NOTCH_DEG)


@njit(cache=True)
def corner_penalty(free: float) -> float:
    """Shortfall of a corner's free angle (radians) below NOTCH_DEG, as a fraction of it."""
    return max(0.0, 1.0 - free / NOTCH_RAD)


@njit(cache=True)
def _turn(v, f, j, crease, n_fan, face_edges, edge_faces, faces, angle):
    """From corner j of face f at vertex v, turning around v through creases (at most n_fan
    faces): (the first cut or boundary edge met, the face angle held up to it)."""
    held = 0.0
    e_out = -1
    for _ in range(n_fan):
        held += angle[f, j]
        e_out = face_edges[f, j]
        if not crease[e_out]:
            break
        f = edge_faces[e_out, 1] if edge_faces[e_out, 0] == f else edge_faces[e_out, 0]
        for m in range(3):
            if faces[f, m] == v:
                j = m
    return e_out, held


@njit(cache=True)
def _vertex_penalty(v, crease, ptr, inc_face, inc_corner, face_edges, edge_faces, faces, angle):
    """`corner_penalty` summed over the outline corners at vertex v (those of `_Fans.corners`)."""
    total = 0.0
    for i in range(ptr[v], ptr[v + 1]):
        f = inc_face[i]
        j = inc_corner[i]
        if not crease[face_edges[f, (j + 2) % 3]]:
            _, held = _turn(v, f, j, crease, ptr[v + 1] - ptr[v], face_edges, edge_faces, faces, angle)
            total += corner_penalty(2 * np.pi - held)
    return total


@njit(cache=True)
def _vertex_penalties(verts, crease, ptr, inc_face, inc_corner, face_edges, edge_faces, faces, angle):
    out = np.empty(verts.shape[0])
    for k in range(verts.shape[0]):
        out[k] = _vertex_penalty(verts[k], crease, ptr, inc_face, inc_corner, face_edges, edge_faces, faces, angle)
    return out


@njit(cache=True)
def _swap_gains(e2, cand, crease, edges, pen, ptr, inc_face, inc_corner, face_edges, edge_faces, faces, angle):
    """`_Fans.swap_gains` (crease is restored before returning)."""
    n = cand.shape[0]
    delta = np.zeros(n)
    touched = np.full((n, 4), -1, dtype=np.int64)
    new = np.zeros((n, 4))
    for c in range(n):
        g = cand[c]
        crease[e2] = False
        crease[g] = True
        k = 0
        for u in (edges[e2, 0], edges[e2, 1], edges[g, 0], edges[g, 1]):
            seen = False
            for m in range(k):
                seen |= touched[c, m] == u
            if seen:
                continue
            touched[c, k] = u
            new[c, k] = _vertex_penalty(u, crease, ptr, inc_face, inc_corner, face_edges, edge_faces, faces, angle)
            delta[c] += new[c, k] - pen[u]
            k += 1
        crease[e2] = True
        crease[g] = False
    return delta, touched, new


def _relaid(net: Net, problem: UnfoldProblem, crease: np.ndarray) -> Net | None:
    """The single-piece net of `crease` rooted where `net` is, or None when it overlaps (any pair
    of its faces: asked only for swaps whose moved faces overlap none of the others,
    `_moved_clear`)."""
    mesh = net.mesh
    n = mesh.n_faces
    parent = np.empty(n, np.int64)
    parent_edge = np.empty(n, np.int64)
    order = np.empty(n, np.int64)
    if K.tree_from_creases(crease, int(net.order[0]), problem.adj_ptr, problem.adj_face, problem.adj_edge,
                           parent, parent_edge, order) != n:
        return None
    coords = np.empty((n, 3, 2))
    K.layout_tree(order, parent, parent_edge, mesh.faces, mesh.topology.face_edges, problem.local, coords)
    count, _ = overlapping_pairs(coords, parent, problem.tol, 0)
    if count:
        return None
    return Net(mesh=mesh, parent=parent, parent_edge=parent_edge, order=order, coords=coords,
               piece=np.zeros(n, dtype=np.int64))


@dataclass(frozen=True, eq=False)
class _Laid:
    """A net's faces as `layout_tree` lays them out from its root: corners (F, 3, 2) and bounds (F,)."""

    coords: np.ndarray
    xmin: np.ndarray
    xmax: np.ndarray
    ymin: np.ndarray
    ymax: np.ndarray


def _laid(net: Net, problem: UnfoldProblem, laid_out: bool = False) -> _Laid:
    """`_Laid` of the net's tree, laid out as `_relaid` lays out a net (`layout_tree` from its root);
    laid_out: net.coords are that already (a net `_relaid` made)."""
    n = net.mesh.n_faces
    coords = net.coords
    if not laid_out:
        coords = np.empty((n, 3, 2))
        K.layout_tree(net.order, net.parent, net.parent_edge, net.mesh.faces, net.mesh.topology.face_edges,
                      problem.local, coords)
    bounds = tuple(np.empty(n) for _ in range(4))
    face_bounds(coords, net.order, *bounds)
    return _Laid(coords, *bounds)


def _moved_clear(net: Net, laid: _Laid, problem: UnfoldProblem, crease: np.ndarray, moved: np.ndarray,
                 moved_ids: np.ndarray, rest_ids: np.ndarray, glued: int) -> bool:
    """Whether no moved face overlaps another face (where a swap's overlaps start) for the swap
    that glues edge `glued` and cut the crease above the moved faces (`moved` (F,) bool, their
    ids, the others' ids; `crease` already swapped), from the moved faces alone: the others keep
    their parents and corners (`laid`: net laid out from its root), the moved ones hang from
    `glued` and are placed from there, as `layout_tree` places them (the same arithmetic, face
    by face from its parent). Most swaps fail here; only the others are laid out in full."""
    mesh = net.mesh
    a, b = mesh.topology.edge_faces[glued]
    top, below = (a, b) if moved[a] else (b, a)
    parent, parent_edge = net.parent.copy(), net.parent_edge.copy()
    parent[top], parent_edge[top] = below, glued
    order = np.empty(len(moved_ids), np.int64)
    order[0] = top
    mark = np.zeros(mesh.n_faces, np.int64)
    mark[top] = 1
    if K.crease_bfs(crease, moved, mark, np.int64(1), problem.adj_ptr, problem.adj_face, problem.adj_edge, parent,
                    parent_edge, order, np.int64(0)) != len(moved_ids):
        return False  # (the swapped creases do not make a tree: `_relaid` would say None)
    coords = laid.coords.copy()
    K.place_children(order, parent, parent_edge, mesh.faces, mesh.topology.face_edges, problem.local, coords)
    xmin, xmax, ymin, ymax = laid.xmin.copy(), laid.xmax.copy(), laid.ymin.copy(), laid.ymax.copy()
    face_bounds(coords, order, xmin, xmax, ymin, ymax)
    return not len(overlapping_pairs_between(coords, parent, moved_ids, rest_ids, xmin, xmax, ymin, ymax,
                                             problem.tol, np.int64(1)))


def open_notches(net: Net, keep: np.ndarray | None = None, deadline: Deadline = Deadline.never()
                 ) -> tuple[Net, TabRoomStats]:
    """The net with fewer narrow corners (see the module docstring); `keep` (E,) bool: creases no
    swap may cut, besides the merged edges of flat regions (never cut)."""
    crease = net.crease_mask.copy()
    fans = _Fans(net)
    n_v = net.mesh.n_vertices
    pen = fans.penalties(np.arange(n_v), crease)
    before = int(np.count_nonzero(pen > 0))
    if net.n_pieces != 1 or before == 0:
        return net, TabRoomStats(before, before, 0, False)
    problem = UnfoldProblem.from_mesh(net.mesh, base=int(net.order[0]))
    edges = net.mesh.topology.edges
    edge_faces = net.mesh.topology.edge_faces
    inner = (edge_faces >= 0).all(axis=1)
    merged = merged_edges(net.mesh)  # flat polygons stay whole
    keep = merged if keep is None else keep | merged
    mid = net.mesh.vertices[edges].mean(axis=1)
    laid = _laid(net, problem)
    swaps, timed_out = 0, False
    for _ in range(MAX_PASSES):  # a swap can open room for another: pass again while one helps
        done = swaps
        for v in np.argsort(-pen, kind="stable")[:int(np.count_nonzero(pen > 0))]:
            if pen[v] <= 0:  # opened by an earlier swap
                continue
            if deadline.expired():
                timed_out = True
                break
            swapped = _open_one(int(v), net, laid, crease, fans, pen, problem, edges, edge_faces, inner, keep, mid)
            if swapped is not None:
                net = swapped
                laid = _laid(net, problem, laid_out=True)
                swaps += 1
        if swaps == done or timed_out:
            break
    return net, TabRoomStats(before, int(np.count_nonzero(pen > 0)), swaps, timed_out)


def _open_one(v, net, laid, crease, fans, pen, problem, edges, edge_faces, inner, keep, mid) -> Net | None:
    """One swap at vertex v's narrowest corner, if one lowers the penalty and keeps the net
    overlap-free; updates crease and pen in place. Returns the new net or None. laid: `_laid`
    of net; mid (E, 3): the edges' midpoints."""
    corners = fans.corners(v, crease)
    if not corners:
        return None
    e_in, e_out, held = min(corners, key=lambda c: 2 * math.pi - c[2])
    # the creases inside this corner, with the angle held before each: cut the one nearest half
    walk = _creases_in_corner(fans, v, e_in, crease)
    if not walk:
        return None
    target = held / 2
    walk.sort(key=lambda ea: abs(ea[1] - target))
    tin, tout = _dfs_intervals(net.parent)
    here = net.mesh.vertices[v]
    for e2, _ in walk[:MAX_CUTS]:
        if keep[e2]:
            continue
        a, b = edge_faces[e2]
        child = a if net.parent[a] == b else b  # the face below the crease in the tree
        in_sub = (tin >= tin[child]) & (tin < tout[child])
        fa, fb = edge_faces[:, 0], edge_faces[:, 1]
        cand = np.flatnonzero(inner & ~crease & (in_sub[np.maximum(fa, 0)] != in_sub[np.maximum(fb, 0)]))
        delta, touched, after = fans.swap_gains(int(e2), cand, crease, edges, pen)
        scored = [(float(delta[c]), int(cand[c]), {int(u): float(p) for u, p in zip(touched[c], after[c]) if u >= 0})
                  for c in np.flatnonzero(delta < -1e-9)]
        # equal gains: the cut edge nearest v first (the moved half turns least, overlaps least)
        scored.sort(key=lambda s: (round(s[0], 2), float(np.linalg.norm(mid[s[1]] - here)), s[1]))
        moved_ids, rest_ids = np.flatnonzero(in_sub), np.flatnonzero(~in_sub)
        for delta, g, new in scored[:MAX_TRIES]:
            crease[e2], crease[g] = False, True
            clear = _moved_clear(net, laid, problem, crease, in_sub, moved_ids, rest_ids, g)
            relaid = _relaid(net, problem, crease) if clear else None
            if relaid is not None:
                for u, p in new.items():
                    pen[u] = p
                return relaid
            crease[e2], crease[g] = True, False
    return None


def _creases_in_corner(fans: _Fans, v: int, e_in: int, crease: np.ndarray) -> list[tuple[int, float]]:
    """(crease, angle held before it) for the creases met turning around v from cut edge e_in."""
    for i in range(fans.ptr[v], fans.ptr[v + 1]):
        f, j = int(fans.inc_face[i]), int(fans.inc_corner[i])
        if int(fans.face_edges[f, (j + 2) % 3]) == e_in:
            break
    else:
        return []
    out, held = [], 0.0
    for _ in range(fans.ptr[v + 1] - fans.ptr[v]):
        held += float(fans.angle[f, j])
        e = int(fans.face_edges[f, j])
        if not crease[e]:
            break
        out.append((e, held))
        a, b = fans.edge_faces[e]
        f = int(b if a == f else a)
        j = int(np.flatnonzero(fans.faces[f] == v)[0])
    return out
