"""Splitting a net to fit a page: cut creases until every piece, with room for its tabs, fits,
then join pieces back where two fit together.

Cutting creases never moves a face, so the pieces stay overlap-free; a join moves a whole piece
and checks the two again. The merged creases of a flat region (`mesh.geometry.merged_edges`) are
never cut: a flat polygon too large for the page is an error, like a single face. A piece "fits"
in one of the rotations the packer tries for any outline (PACK_ANGLES), so it always packs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..deadline import Deadline
from ..errors import PolyfoldError
from ..mesh.geometry import face_areas
from ..mesh.mesh import Mesh
from ..unfold import kernels as K
from ..unfold.net import Net, cut_creases, subtree_areas
from .pack import _best_fit, _extents, hull_corners, order_among, points_hull, sorted_points
from .tabs import TAB_ROOM_MM

MAX_PEEL_TRIES = 64
# Rotations (degrees) `pack.pack_outlines` tries for every outline whatever its shape: the evenly
# spaced ones of `pack.fits_page` (its default 8), whose best rotation the packer always keeps.
PACK_ANGLES = np.arange(8) * 45.0
TOUCH_MM = 0.05  # pieces nearer than this count as touching when `join_pieces` looks for enclosed holes


class PieceTooLarge(PolyfoldError):
    """A single face, or a flat polygon that is never cut (its faces, ids in the input file: `faces`,
    the first is `face`), does not fit the page with room for its tabs; `factor` is the largest
    scale factor of the model at which it would."""

    def __init__(self, faces: Sequence[int], factor: float) -> None:
        self.faces = tuple(sorted({int(f) for f in faces}))
        self.face = self.faces[0]
        self.factor = factor
        super().__init__(f"{self.what} alone does not fit the page with its tabs (fits at {factor:.3f} times the size)")

    @property
    def what(self) -> str:
        """"face 3", or "the flat polygon of faces 3, 4" (input file face ids)."""
        if len(self.faces) == 1:
            return f"face {self.face}"
        shown = ", ".join(map(str, self.faces[:6])) + (", ..." if len(self.faces) > 6 else "")
        return f"the flat polygon of faces {shown}"


def _hull_scale(points_mm: np.ndarray, page_size, margin: float, pad: float) -> float:
    """Largest scale at which the convex hull of the points, grown by `pad` mm, fits the page in
    one of the PACK_ANGLES rotations. The packer tries those for every outline whatever its shape,
    and a piece's real outline (its tabs included) lies inside the grown hull: so the packer finds
    the fit too (a better rotation of the hull alone need not be one it tries for the outline)."""
    import shapely

    hull = points_hull(points_mm).buffer(pad, quad_segs=2)
    pw, ph = page_size[0] - 2 * margin, page_size[1] - 2 * margin
    return _best_fit(shapely.get_coordinates(hull), PACK_ANGLES, pw, ph)[0]


# In any direction the hull grown by shapely's buffer (quad_segs=2) reaches between this many
# times `pad` past the hull (its arcs are chords of at most 67.5 degrees: GEOS rounds the count of
# 45-degree steps to the nearest) and `pad` (the arc's corners and the offset sides lie on it).
_ARC_CHORD = 0.8  # < cos(67.5 / 2 degrees) = 0.83
_FIT_EPS_MM = 1e-9  # (floats in GEOS's arcs)


def _hull_fits(points_mm: np.ndarray, page_size, margin: float, pad: float, order: np.ndarray | None = None
               ) -> bool:
    """`_hull_scale(...) >= 1` (the grown hull fits the page in a PACK_ANGLES rotation), from the
    points' own extents when those decide it (the grown hull's lie within 2 pad of them, and more
    than 2 _ARC_CHORD pad out): the grown hull is built only for pieces within half a pad of
    fitting. order: the points' `pack.sorted_points`, when the caller has it."""
    pw, ph = page_size[0] - 2 * margin, page_size[1] - 2 * margin
    xy = np.ascontiguousarray(points_mm, dtype=np.float64)
    corners = xy[hull_corners(xy, order)]  # (the same hull as all the points)
    lo, hi = _extents(corners, PACK_ANGLES)
    ext = hi - lo
    room = np.array([pw, ph])
    if ((ext + 2 * pad + _FIT_EPS_MM) <= room).all(axis=1).any():
        return True
    if not ((ext + 2 * _ARC_CHORD * pad - _FIT_EPS_MM) <= room).all(axis=1).any():
        return False
    return _hull_scale(corners, page_size, margin, pad) >= 1.0


def smallest_printed(mesh: Mesh, scale: float) -> tuple[float, float]:
    """(shortest edge, smallest face height) of the mesh's faces printed at `scale` mm per model
    unit, in mm. A face's smallest height is twice its area over its longest side: the width of
    the narrowest strip of paper it makes (0 for a degenerate face)."""
    tri = mesh.vertices[mesh.faces]
    sides = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)
    heights = 2.0 * face_areas(mesh.vertices, mesh.faces) / np.maximum(sides.max(axis=1), 1e-300)
    return float(sides.min()) * scale, float(heights.min()) * scale


def _model_factor(points_mm: np.ndarray, page_size, margin: float, pad: float) -> float:
    """Largest factor of the model's scale at which the convex hull of the points, grown by `pad` mm
    (the tab room does not scale with the model), fits the page as `_hull_scale` checks it.

    Bisection between the bare hull in the page less the pad on every side (a lower bound: in any
    rotation the grown hull's extents are the bare hull's plus at most 2 pad) and the grown hull's
    own scale (an upper bound when below 1: the pad shrinks with it there)."""
    import shapely

    def fits(factor: float) -> bool:
        return _hull_fits(points_mm * factor, page_size, margin, pad)

    hull = shapely.get_coordinates(points_hull(points_mm))
    lo = _best_fit(hull, PACK_ANGLES, page_size[0] - 2 * (margin + pad), page_size[1] - 2 * (margin + pad))[0]
    while lo > 0 and not fits(lo):  # rounding only
        lo *= 1 - 1e-9
    hi = _hull_scale(points_mm, page_size, margin, pad)
    for _ in range(30):
        if hi - lo <= 1e-6 * hi:
            break
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def split_to_fit(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                 pad: float = TAB_ROOM_MM, deadline: Deadline = Deadline.never()) -> tuple[Net, int]:
    """Cut creases of `net` until every piece, grown by `pad` mm (room for tabs), fits the page.

    Greedy: peel off a subtree that fits (the largest whose rest also fits, else the largest),
    until the rest fits; only subtrees whose crease to their parent may be cut (`Net.cuttable`:
    not inside a flat polygon). Then pieces are joined back where they fit together elsewhere
    (`join_pieces`: a subtree peeled off a flat polygon's rim alone, say). Returns the new net and
    the number of pieces added (creases cut less pieces joined). Raises PieceTooLarge (a
    PolyfoldError) when a single face or flat polygon is too large, with the scale factor that
    would fit; OutOfTime past `deadline` (`Deadline.check`)."""
    net, cuts = _peel_to_fit(net, scale, page_size, margin, pad, deadline)
    if cuts == 0:
        return net, 0
    net, joins = join_pieces(net, scale, page_size, margin, pad, limit=cuts)
    return net, cuts - joins


def _peel_to_fit(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                 pad: float, deadline: Deadline) -> tuple[Net, int]:
    """`split_to_fit`'s peeling: (net, creases cut)."""
    xy = net.coords * scale
    # the faces' corners sorted once (peeling moves no face): a part's corners in `hull_corners`'
    # order are these with the others left out, when taken in increasing face order (equal points
    # may then stand in for each other, the same corners: 0.1 s of sorting at 1,500 faces)
    points = xy.reshape(-1, 2)
    ordered = sorted_points(points)

    def part_fits(faces: np.ndarray) -> bool:  # (faces increasing)
        ids = (3 * faces[:, None] + np.arange(3)).reshape(-1)
        return _hull_fits(points[ids], page_size, margin, pad, order_among(ordered, ids))

    cuts = 0
    cuttable = net.cuttable  # cutting a crease changes no other crease's
    # a set of faces whose area exceeds the printable area cannot fit: no hull to build for it
    printable = (page_size[0] - 2 * margin) * (page_size[1] - 2 * margin) / scale ** 2
    fits: set[int] = set()  # roots of pieces known to fit (peeling never changes such a piece)
    for _ in range(len(net.piece)):
        deadline.check("cutting the pieces to fit the page")
        sub_area, tin, tout = subtree_areas(net)
        by_tin = np.argsort(tin)
        todo = None
        for root in np.flatnonzero(net.parent < 0).tolist():
            if root in fits:
                continue
            faces = np.sort(by_tin[tin[root]:tout[root]])
            if sub_area[root] <= printable and part_fits(faces):
                fits.add(root)
                continue
            todo = faces
            break
        if todo is None:
            return net, cuts
        cand = todo[cuttable[todo]]
        if len(cand) == 0:  # one face, or one flat polygon
            factor = _model_factor(xy[todo].reshape(-1, 2), page_size, margin, pad)
            raise PieceTooLarge(net.mesh.face_source[todo], factor)
        cand = cand[np.argsort(-sub_area[cand], kind="stable")]
        # Peel a subtree that fits; best one whose rest fits too (two pieces instead of three),
        # else the largest that fits. Only the MAX_PEEL_TRIES largest fitting subtrees are weighed.
        chosen, fitting = None, []
        in_piece = np.zeros(len(net.piece), dtype=bool)
        in_piece[todo] = True
        whole = float(sub_area[todo[net.parent[todo] < 0][0]])
        for c in cand[sub_area[cand] <= printable]:
            members = by_tin[tin[c]:tout[c]]
            if part_fits(np.sort(members)):
                fitting.append(int(c))
                rest = in_piece.copy()
                rest[members] = False
                if whole - sub_area[c] <= printable and part_fits(np.flatnonzero(rest)):
                    chosen = int(c)
                    break
                if len(fitting) >= MAX_PEEL_TRIES:
                    break
        if chosen is None and fitting:
            chosen = fitting[0]
        if chosen is None:  # not even one face fits on its own below the root: cut the root off
            chosen = int(cand[-1])
        else:
            fits.add(chosen)
        net = cut_creases(net, np.array([chosen]))
        cuttable[chosen] = False
        cuts += 1
    return net, cuts


def join_pieces(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                pad: float = TAB_ROOM_MM, limit: int | None = None) -> tuple[Net, int]:
    """Join pieces of `net` along the mesh edges they share, at most `limit` times (None: no limit):
    a piece is moved rigidly to hinge on its neighbour's side of the edge (the edge becomes a
    crease) when the two stay overlap-free (`collide.flat`, the unfolder's tolerance), enclose no
    hole together (`_encloses`) and, grown by `pad` mm, fit the page at `scale` mm per unit
    (`_hull_scale`). Smallest pieces (by area) first, each along
    its longest shared edge first. Returns the new net and the number of joins."""
    mesh = net.mesh
    topo = mesh.topology
    parent, parent_edge, coords = net.parent.copy(), net.parent_edge.copy(), net.coords.copy()
    piece = net.piece.copy()
    e1, e2 = coords[:, 1] - coords[:, 0], coords[:, 2] - coords[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    tol = 1e-9 * max(mesh.bbox_diagonal, 1e-300)
    ef = topo.edge_faces
    inner = np.flatnonzero((ef >= 0).all(axis=1))
    length = np.linalg.norm(mesh.vertices[topo.edges[inner, 1]] - mesh.vertices[topo.edges[inner, 0]], axis=1)
    failed: set[int] = set()
    joins = 0
    while limit is None or joins < limit:
        p0, p1 = piece[ef[inner, 0]], piece[ef[inner, 1]]
        piece_area = np.bincount(piece, weights=area)
        small = np.minimum(piece_area[p0], piece_area[p1])
        cand = [int(i) for i in np.lexsort((-length, small)) if p0[i] != p1[i] and int(inner[i]) not in failed]
        for i in cand:
            e = int(inner[i])
            f, g = int(ef[e, 0]), int(ef[e, 1])
            if piece_area[piece[f]] < piece_area[piece[g]]:
                f, g = g, f  # g's piece moves
            moved = _hinged(coords, mesh.faces, topo.edges[e], f, g, piece, tol)
            fixed, moving = np.flatnonzero(piece == piece[f]), np.flatnonzero(piece == piece[g])
            both = np.concatenate([coords[fixed], moved])
            hinge = (int(np.searchsorted(fixed, f)), len(fixed) + int(np.searchsorted(moving, g)))
            if (not _hull_fits(both.reshape(-1, 2) * scale, page_size, margin, pad)
                    or _overlap(both, len(fixed), hinge, tol)
                    or _encloses(coords[fixed] * scale, moved * scale)):
                failed.add(e)
                continue
            coords[moving] = moved
            _reroot(parent, parent_edge, g)
            parent[g], parent_edge[g] = f, e
            order = _parents_first(parent)
            piece = K.piece_labels(order, parent)
            joined = np.flatnonzero(piece == piece[f])
            failed -= set(topo.face_edges[joined].ravel().tolist())  # the joined piece is new
            joins += 1
            break
        else:
            break
    if joins == 0:
        return net, 0
    return Net(mesh=mesh, parent=parent, parent_edge=parent_edge, order=order, coords=coords, piece=piece), joins


def _hinged(coords: np.ndarray, faces: np.ndarray, edge: np.ndarray, f: int, g: int, piece: np.ndarray,
            tol: float) -> np.ndarray:
    """The faces of g's piece (F_g, 3, 2) moved rigidly so g's copy of `edge` (two mesh vertex
    ids) lies on f's: g then lies across the edge from f, both outer side up. A moved corner within
    `tol` of a corner of f's piece at the same mesh vertex (the edge's ends at least) takes its
    coordinates bit for bit, as the unfolder's layout copies a parent's corners: the sheet outlines
    are unions of the faces and need shared corners equal."""
    moving = piece == piece[g]
    pts = coords[moving]
    fa, fb = (coords[f][faces[f] == v][0] for v in edge)
    ga, gb = (coords[g][faces[g] == v][0] for v in edge)
    r = complex(*(fb - fa)) / complex(*(gb - ga))
    r /= abs(r)
    z = (pts[..., 0] + 1j * pts[..., 1] - complex(*ga)) * r + complex(*fa)
    moved = np.stack([z.real, z.imag], axis=-1)
    fixed = piece == piece[f]
    at = np.argsort(faces[fixed].ravel(), kind="stable")  # the fixed corners by vertex, in order
    fixed_v, fixed_xy = faces[fixed].ravel()[at], coords[fixed].reshape(-1, 2)[at]
    flat = moved.reshape(-1, 2)
    moved_v = faces[moving].ravel()
    lo, hi = np.searchsorted(fixed_v, moved_v, "left"), np.searchsorted(fixed_v, moved_v, "right")
    todo, k = np.flatnonzero(hi > lo), 0
    while len(todo):  # each moved corner takes the first fixed corner at its vertex within tol
        at = lo[todo] + k
        todo, at = todo[at < hi[todo]], at[at < hi[todo]]
        near = (np.abs(flat[todo, 0] - fixed_xy[at, 0]) <= tol) & (np.abs(flat[todo, 1] - fixed_xy[at, 1]) <= tol)
        flat[todo[near]] = fixed_xy[at[near]]
        todo, k = todo[~near], k + 1
    return moved


def _encloses(fixed_mm: np.ndarray, moved_mm: np.ndarray) -> bool:
    """True when the faces fixed_mm and moved_mm (k, 3, 2), each grown by TOUCH_MM, enclose a hole
    together that neither does alone: joined, they would close (or nearly close, within TOUCH_MM)
    a loop around paper that is not theirs, a hole that may touch the outline's rim. Slits and
    narrow notches are no holes: they open to the outside."""
    import shapely

    def grown(tris: np.ndarray):
        return shapely.union_all(shapely.polygons(tris)).buffer(TOUCH_MM, quad_segs=2)

    def holes(geom) -> int:
        return sum(len(g.interiors) for g in getattr(geom, "geoms", [geom]))

    a, b = grown(fixed_mm), grown(moved_mm)
    return holes(shapely.union(a, b)) > holes(a) + holes(b)


def _overlap(tris: np.ndarray, n_fixed: int, hinge: tuple[int, int], tol: float) -> bool:
    """True when a triangle of tris[:n_fixed] overlaps one of tris[n_fixed:] (each set is
    overlap-free on its own), the two triangles of the new crease `hinge` excepted."""
    from ..collide.flat import overlapping_pairs

    parent = np.full(len(tris), -1, dtype=np.int64)
    parent[hinge[1]] = hinge[0]
    count, pairs = overlapping_pairs(np.ascontiguousarray(tris), parent, tol, len(tris))
    return count > len(pairs) or bool(((pairs[:, 0] < n_fixed) != (pairs[:, 1] < n_fixed)).any())


def _reroot(parent: np.ndarray, parent_edge: np.ndarray, g: int) -> None:
    """Make face g the root of its tree, in place (the creases on its path to the old root turn round)."""
    path = [g]
    while parent[path[-1]] >= 0:
        path.append(int(parent[path[-1]]))
    edges = [int(parent_edge[x]) for x in path[:-1]]
    for k in range(len(path) - 1, 0, -1):
        parent[path[k]], parent_edge[path[k]] = path[k - 1], edges[k - 1]
    parent[g], parent_edge[g] = -1, -1


def _parents_first(parent: np.ndarray) -> np.ndarray:
    """An order of the faces of a forest with every parent before its children (roots in face order)."""
    children: list[list[int]] = [[] for _ in range(len(parent))]
    for f, p in enumerate(parent.tolist()):
        if p >= 0:
            children[p].append(f)
    order = [int(f) for f in np.flatnonzero(parent < 0)]
    k = 0
    while k < len(order):
        order.extend(children[order[k]])
        k += 1
    return np.asarray(order, dtype=np.int64)


def model_scale(meshes: Sequence[Mesh], size_mm: float) -> float:
    """mm per model unit: the longest bounding-box side of the meshes' used vertices (a model's
    components together) becomes size_mm. PolyfoldError when the model has zero size."""
    pts = np.concatenate([m.vertices[np.unique(m.faces)] for m in meshes])
    extent = float(np.ptp(pts, axis=0).max())
    if not (extent > 0 and math.isfinite(extent)):
        raise PolyfoldError("the model has zero size")
    return size_mm / extent
