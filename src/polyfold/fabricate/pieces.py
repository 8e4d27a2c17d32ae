"""Paper geometry of net pieces, in millimetres: cut outline, scored creases, glue tabs, labels.

In: single-piece nets (`unfold.piece_net`) with maps to the whole mesh's vertices (`PieceInput`,
`piece_input`), and a scale (mm per model unit). Out (`build_sheet_pieces`): `SheetPiece`s in
their own frame (y down, as on the page, outer side of the surface facing the reader) and the
`GlueEdge`s: which two cut edges glue together, the short label printed beside both, and which
side carries the glue tab (`tabs.choose_tab`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..mesh.geometry import FLAT_EPS  # flat creases are not scored, as in the FOLD files
from ..mesh.mesh import Mesh
from ..unfold.net import Net
from .labels import edge_label, piece_label, piece_name
from .page import TextItem
from .tabs import CutSide, choose_tab


@dataclass(frozen=True, eq=False)
class PieceInput:
    """One piece to draw: a single-piece net, its part, and its maps into the whole mesh."""

    net: Net
    part: int
    vertex_ids: np.ndarray  # piece-mesh vertex -> whole-mesh vertex
    face_ids: np.ndarray  # piece-mesh face -> whole-mesh face


def piece_input(net: Net, part: int, mesh_faces: np.ndarray, face_ids: np.ndarray) -> PieceInput:
    """A single-piece net (from `unfold.piece_net`) as a PieceInput. mesh_faces (F, 3): its faces
    in whole-mesh vertex ids, in the order of net.mesh.faces; face_ids (F,): their whole-mesh ids.
    (`Mesh.submesh` numbers a piece's vertices in the order of their whole-mesh ids.)"""
    return PieceInput(net=net, part=part, vertex_ids=np.unique(mesh_faces), face_ids=np.asarray(face_ids))


@dataclass(frozen=True, eq=False)
class SheetPiece:
    """A piece on paper, in mm (y down). outline = body (the faces) plus its tabs."""

    name: str
    part: int
    face_ids: np.ndarray
    faces_xy: np.ndarray  # (n, 3, 2)
    body: object  # shapely geometry: union of the faces
    outline: object  # shapely geometry: body + tabs (what is cut out)
    mountain: np.ndarray  # (m, 2, 2)
    valley: np.ndarray  # (v, 2, 2)
    slits: np.ndarray  # (s, 2, 2) cut edges inside the outline
    tabs: tuple[np.ndarray, ...]  # (4, 2) trapezoids
    tab_folds: np.ndarray  # (t, 2, 2)
    texts: tuple[TextItem, ...]
    tab_mountain: np.ndarray  # (t,) bool: tab t folds as a mountain seen from the printed side (convex seam)

    def cut_rings(self) -> list[np.ndarray]:
        """The outline's boundary rings (exterior and holes), without the repeated last point."""
        geoms = getattr(self.outline, "geoms", [self.outline])
        rings = []
        for g in geoms:
            for ring in [g.exterior, *g.interiors]:
                rings.append(np.asarray(ring.coords)[:-1])
        return rings


@dataclass(frozen=True)
class GlueEdge:
    """Two cut edges that are one mesh edge: glued together, labelled `label` on both sides."""

    label: str
    mesh_edge: tuple[int, int]  # whole-mesh vertex ids
    pieces: tuple[int, int]  # piece index of each side
    tab_piece: int | None  # the piece whose side carries the tab; None: no tab fits either side
    tab_height_mm: float
    fold_angle: float = 0.0  # the seam's signed fold angle rho (radians, + convex) in the model


@dataclass(frozen=True)
class LayoutStats:
    glue_edges: int
    tabs: int
    tabs_shrunk: int
    tabs_moved: int  # put on the second side because the first had no room
    untabbed: tuple[str, ...]  # labels of the edges without a tab
    small_labels: int  # labels below LABEL_MIN_MM (they still fit inside their face)
    open_edges: int  # boundary edges of the input mesh (cut, nothing to glue to)


@dataclass(frozen=True, eq=False)
class _Drawn:
    """One piece in mm before gluing: faces, their union, scored creases, its cut sides."""

    faces_xy: np.ndarray
    body: object
    mountain: np.ndarray
    valley: np.ndarray
    sides: list[tuple[tuple[int, int], CutSide]]  # (whole-mesh edge key, side)


def _draw(inp: PieceInput, i: int, scale: float) -> _Drawn:
    """Piece `i` in mm, y down (seen from the outer side): faces, creases by fold sign, cut sides."""
    import shapely

    net = inp.net
    mesh = net.mesh
    topo = mesh.topology
    xy = net.coords * scale
    xy[..., 1] *= -1.0  # y down, seen from the outer side
    body = shapely.union_all(shapely.polygons(xy))
    child = np.flatnonzero(net.parent >= 0)
    e = net.parent_edge[child]
    ends = topo.edges[e]
    k0 = np.argmax(mesh.faces[child] == ends[:, :1], axis=1)
    k1 = np.argmax(mesh.faces[child] == ends[:, 1:], axis=1)
    seg = np.stack([xy[child, k0], xy[child, k1]], axis=1)
    rho = mesh.fold_angles[e]
    # cut sides: face sides that are not creases of this piece
    E = topo.n_edges
    crease_keys = np.concatenate([child * E + e, net.parent[child] * E + e])
    occ_key = np.arange(len(mesh.faces))[:, None] * E + topo.face_edges
    is_cut = ~np.isin(occ_key, crease_keys)
    sides = []
    for f, k in zip(*np.nonzero(is_cut)):
        a, b = inp.vertex_ids[mesh.faces[f, k]], inp.vertex_ids[mesh.faces[f, (k + 1) % 3]]
        key = (int(min(a, b)), int(max(a, b)))
        sides.append((key, CutSide(i, int(f), int(k), xy[f, k], xy[f, (k + 1) % 3], xy[f])))
    return _Drawn(xy, body, seg[rho > FLAT_EPS], seg[rho < -FLAT_EPS], sides)


def _pair_sides(drawn: list[_Drawn]) -> tuple[list[tuple[tuple[int, int], list[CutSide]]], int]:
    """Cut sides grouped by mesh edge: the glued pairs (ordered by their first piece, then mesh
    edge) and the number of open edges (one side only: a boundary of the input mesh)."""
    groups: dict[tuple[int, int], list[CutSide]] = {}
    for d in drawn:
        for key, side in d.sides:
            groups.setdefault(key, []).append(side)
    pairs = [(key, v) for key, v in groups.items() if len(v) == 2]
    open_edges = sum(1 for v in groups.values() if len(v) == 1)
    pairs.sort(key=lambda kv: (min(s.piece for s in kv[1]), kv[0]))
    return pairs, open_edges


@dataclass
class _Glued:
    """What gluing adds to each piece (lists per piece index) and the counts of LayoutStats."""

    n: int
    tabs: list = field(init=False)  # shapely Polygons
    tab_mountain: list = field(init=False)  # per tab: its seam is convex
    slits: list = field(init=False)
    texts: list = field(init=False)
    glue: list = field(default_factory=list)
    untabbed: list = field(default_factory=list)
    n_tabs: int = 0
    shrunk: int = 0
    moved: int = 0
    small: int = 0

    def __post_init__(self) -> None:
        self.tabs, self.tab_mountain, self.slits, self.texts = ([[] for _ in range(self.n)] for _ in range(4))


def seam_fold_angles(inputs: list[PieceInput]) -> dict[tuple[int, int], float]:
    """Signed fold angle rho (radians, + convex) of every edge of the model the pieces make, keyed
    by its whole-mesh vertex ids (low, high): the pieces' faces put back together in 3D, so a seam
    between two pieces gets the angle of its two faces in the model."""
    n = max(int(inp.vertex_ids.max()) for inp in inputs) + 1
    vertices = np.zeros((n, 3))
    for inp in inputs:
        vertices[inp.vertex_ids] = inp.net.mesh.vertices
    whole = Mesh(vertices, np.concatenate([inp.vertex_ids[inp.net.mesh.faces] for inp in inputs]))
    keys = np.sort(whole.topology.edges, axis=1)
    return {(int(a), int(b)): float(r) for (a, b), r in zip(keys, whole.fold_angles)}


def _glue(pairs, drawn: list[_Drawn], tabs: bool, rho: dict[tuple[int, int], float]) -> _Glued:
    """Label both sides of every glued pair (label = its 1-based rank), note slits (two sides of
    one piece that touch in the plane) and give each pair its tab (`choose_tab`)."""
    from shapely.geometry import Polygon
    from shapely.prepared import prep

    bodies = [d.body for d in drawn]
    prepared = [prep(b) for b in bodies] if tabs else []
    out = _Glued(len(drawn))
    for idx, (key, (o1, o2)) in enumerate(pairs):
        label = str(idx + 1)
        if o1.piece == o2.piece and np.allclose(o1.p0, o2.p1, atol=1e-6) and np.allclose(o1.p1, o2.p0, atol=1e-6):
            out.slits[o1.piece].append(np.array([o1.p0, o1.p1]))  # the two sides touch in the plane
        for o in (o1, o2):
            item, big = edge_label(o.tri, o.k, label)
            out.texts[o.piece].append(item)
            out.small += not big
        tab = choose_tab((o1, o2), bodies, prepared, out.tabs) if tabs else None
        if tab is None:
            if tabs:
                out.untabbed.append(label)
            out.glue.append(GlueEdge(label, key, (o1.piece, o2.piece), None, 0.0, rho[key]))
            continue
        piece = (o1, o2)[tab.side].piece
        out.tabs[piece].append(Polygon(tab.polygon))
        out.tab_mountain[piece].append(rho[key] > 0)
        out.n_tabs += 1
        out.shrunk += tab.variant != 0
        out.moved += tab.side == 1
        out.glue.append(GlueEdge(label, key, (o1.piece, o2.piece), piece, tab.height, rho[key]))
    return out


def build_sheet_pieces(inputs: list[PieceInput], scale: float, tabs: bool = True
                       ) -> tuple[list[SheetPiece], list[GlueEdge], LayoutStats]:
    """Draw every piece in mm and pair up their cut edges (see the module docstring). Tabs:
    `tabs.choose_tab` per glued pair; pairs without one are listed in LayoutStats.untabbed."""
    import shapely

    drawn = [_draw(inp, i, scale) for i, inp in enumerate(inputs)]
    pairs, open_edges = _pair_sides(drawn)
    g = _glue(pairs, drawn, tabs, seam_fold_angles(inputs))
    pieces = []
    for i, (inp, d) in enumerate(zip(inputs, drawn)):
        name = piece_name(i)
        tab_polys = g.tabs[i]
        outline = shapely.union_all([d.body, *tab_polys]) if tab_polys else d.body
        tab_arr = tuple(np.asarray(t.exterior.coords)[:-1] for t in tab_polys)
        folds = np.array([[t[0], t[3]] for t in tab_arr]).reshape(-1, 2, 2)
        g.texts[i].append(piece_label(d.faces_xy, name))
        pieces.append(SheetPiece(
            name=name, part=inp.part, face_ids=np.asarray(inp.face_ids), faces_xy=d.faces_xy, body=d.body,
            outline=outline, mountain=d.mountain.reshape(-1, 2, 2), valley=d.valley.reshape(-1, 2, 2),
            slits=np.array(g.slits[i]).reshape(-1, 2, 2), tabs=tab_arr, tab_folds=folds, texts=tuple(g.texts[i]),
            tab_mountain=np.array(g.tab_mountain[i], dtype=bool)))
    stats = LayoutStats(glue_edges=len(pairs), tabs=g.n_tabs, tabs_shrunk=g.shrunk, tabs_moved=g.moved,
                        untabbed=tuple(g.untabbed), small_labels=g.small, open_edges=open_edges)
    return pieces, g.glue, stats
