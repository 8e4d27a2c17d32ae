"""Paper geometry of net pieces, in millimetres: cut outline, scored creases, glue tabs, labels.

In: single-piece nets (`unfold.piece_net`) with maps to the whole mesh's vertices, and a scale
(mm per model unit). Out: `SheetPiece`s in their own frame (y down, as on the page, outer side of
the surface facing the reader) and the `GlueEdge`s: which two cut edges glue together, the short
label printed beside both, and which side carries the glue tab.

Also `split_to_fit`: cut a net's creases until every piece (with room for its tabs) fits a page.
Cutting creases never moves a face, so the pieces stay overlap-free.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import PolyfoldError
from ..mesh.geometry import FLAT_EPS  # flat creases are not scored, as in the FOLD files
from .page import Page, TextItem
from ..unfold.net import Net, cut_creases, subtree_areas

TAB_MAX_MM = 6.0  # full tab height
TAB_REL = 0.4  # tab height as a fraction of its edge length (before the cap)
TAB_MIN_MM = 1.0  # smaller tabs are useless: no tab instead
LABEL_MAX_MM = 3.0
LABEL_MIN_MM = 0.8  # a label smaller than this is reported (it is still placed inside its face)
CHAR_EM = 0.62  # mean advance width of a Helvetica digit/capital, in em


class PieceTooLarge(PolyfoldError):
    """A single face (with room for its tabs) does not fit the page; `factor` is the largest
    scale factor of the model at which it would."""

    def __init__(self, face: int, factor: float) -> None:
        super().__init__(f"face {face} alone does not fit the page with its tabs (fits at {factor:.3f} times the size)")
        self.face = face
        self.factor = factor


@dataclass(frozen=True, eq=False)
class PieceInput:
    """One piece to draw: a single-piece net, its part, and its maps into the whole mesh."""

    net: Net
    part: int
    vertex_ids: np.ndarray  # piece-mesh vertex -> whole-mesh vertex
    face_ids: np.ndarray  # piece-mesh face -> whole-mesh face


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


@dataclass(frozen=True)
class LayoutStats:
    glue_edges: int
    tabs: int
    tabs_shrunk: int
    tabs_moved: int  # put on the second side because the first had no room
    untabbed: tuple[str, ...]  # labels of the edges without a tab
    small_labels: int  # labels below LABEL_MIN_MM (they still fit inside their face)
    open_edges: int  # boundary edges of the input mesh (cut, nothing to glue to)


# ----------------------------------------------------------------------------------------------
# Splitting pieces to fit a page


MAX_PEEL_TRIES = 64


def _hull_scale(points_mm: np.ndarray, page_size, margin: float, pad: float) -> float:
    """Largest scale at which the convex hull of the points, grown by `pad` mm, fits the page."""
    import shapely

    from .pack import fits_page

    hull = shapely.convex_hull(shapely.multipoints(points_mm)).buffer(pad, quad_segs=2)
    return fits_page(hull, page_size, margin)


def split_to_fit(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                 pad: float = TAB_MAX_MM + 1.0) -> tuple[Net, int]:
    """Cut creases of `net` until every piece, grown by `pad` mm (room for tabs), fits the page.

    Greedy: peel off a subtree that fits (the largest whose rest also fits, else the largest),
    until the rest fits. Returns the new
    net and the number of creases cut. Raises PolyfoldError when a single face is too large,
    naming the largest model size that would fit."""
    xy = net.coords * scale
    cuts = 0
    for _ in range(len(net.piece)):
        sub_area, tin, tout = subtree_areas(net)
        by_tin = np.argsort(tin)
        todo = None
        for p in range(net.n_pieces):
            faces = np.flatnonzero(net.piece == p)
            if _hull_scale(xy[faces].reshape(-1, 2), page_size, margin, pad) < 1.0:
                todo = faces
                break
        if todo is None:
            return net, cuts
        if len(todo) == 1:
            f = int(todo[0])
            raise PieceTooLarge(int(net.mesh.face_source[f]), _hull_scale(xy[f], page_size, margin, pad))
        cand = todo[net.parent[todo] >= 0]
        cand = cand[np.argsort(-sub_area[cand], kind="stable")]
        # Peel a subtree that fits; best one whose rest fits too (two pieces instead of three),
        # else the largest that fits. Only the MAX_PEEL_TRIES largest fitting subtrees are weighed.
        chosen, fitting = None, []
        in_piece = np.zeros(len(net.piece), dtype=bool)
        in_piece[todo] = True
        for c in cand:
            members = by_tin[tin[c]:tout[c]]
            if _hull_scale(xy[members].reshape(-1, 2), page_size, margin, pad) >= 1.0:
                fitting.append(int(c))
                rest = in_piece.copy()
                rest[members] = False
                if _hull_scale(xy[rest].reshape(-1, 2), page_size, margin, pad) >= 1.0:
                    chosen = int(c)
                    break
                if len(fitting) >= MAX_PEEL_TRIES:
                    break
        if chosen is None and fitting:
            chosen = fitting[0]
        if chosen is None:  # not even one face fits on its own below the root: cut the root off
            chosen = int(cand[-1])
        net = cut_creases(net, np.array([chosen]))
        cuts += 1
    return net, cuts


# ----------------------------------------------------------------------------------------------
# Geometry of one piece


def _piece_name(i: int) -> str:
    """A, B, ..., Z, AA, AB, ... (short ids printed on the pieces)."""
    s = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        s = chr(65 + r) + s
    return s


def _upright(angle: float) -> float:
    """Angle (deg) turned by 180 if needed so text never reads upside down: in (-90, 90]."""
    a = (angle + 180.0) % 360.0 - 180.0
    if a > 90.0:
        a -= 180.0
    elif a <= -90.0:
        a += 180.0
    return a


def _inside(tri: np.ndarray, pts: np.ndarray, pad: float) -> bool:
    """All points inside triangle `tri` (either orientation), at least `pad` from its sides."""
    a, b, c = tri
    area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    sgn = 1.0 if area2 > 0 else -1.0
    for p, q in ((a, b), (b, c), (c, a)):
        e = q - p
        ln = math.hypot(e[0], e[1])
        if ln == 0:
            return False
        d = sgn * (e[0] * (pts[:, 1] - p[1]) - e[1] * (pts[:, 0] - p[0])) / ln
        if (d < pad).any():
            return False
    return True


def _text_box(center: np.ndarray, u: np.ndarray, n: np.ndarray, width: float, height: float) -> np.ndarray:
    hw, hh = width / 2, height / 2
    return np.array([center + su * hw * u + sn * hh * n for su in (-1, 1) for sn in (-1, 1)])


def _edge_label(tri: np.ndarray, k: int, text: str) -> tuple[TextItem, bool]:
    """Label of edge k (corners k, k+1) of triangle `tri`, inside the triangle along the edge.
    Returns the item and whether it is at least LABEL_MIN_MM."""
    p0, p1, third = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
    d = p1 - p0
    length = math.hypot(d[0], d[1])
    u = d / length
    n = np.array([-u[1], u[0]])
    if np.dot(third - p0, n) < 0:
        n = -n
    mid = (p0 + p1) / 2
    angle = _upright(math.degrees(math.atan2(-d[1], d[0])))  # y down: visual CCW angle
    s = LABEL_MAX_MM
    while s >= 0.25:
        w, h = CHAR_EM * s * len(text), 0.85 * s
        center = mid + n * (0.25 * s + h / 2)
        if _inside(tri, _text_box(center, u, n, w, h), 0.05 * s):
            return TextItem(text, float(center[0]), float(center[1]), angle, s, "edge-label"), s >= LABEL_MIN_MM
        s *= 0.85
    c = tri.mean(axis=0)  # a sliver: smallest size at the centroid
    return TextItem(text, float(c[0]), float(c[1]), angle, 0.25, "edge-label"), False


def _piece_label(faces_xy: np.ndarray, text: str) -> TextItem:
    """The piece id at the incentre of its largest face, sized to half its incircle."""
    a, b, c = faces_xy[:, 0], faces_xy[:, 1], faces_xy[:, 2]
    la, lb, lc = (np.linalg.norm(b - c, axis=1), np.linalg.norm(c - a, axis=1), np.linalg.norm(a - b, axis=1))
    area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    per = la + lb + lc
    r = np.where(per > 0, 2 * area / np.maximum(per, 1e-300), 0.0)
    f = int(np.argmax(r))
    center = (la[f] * a[f] + lb[f] * b[f] + lc[f] * c[f]) / per[f]
    # text box (CHAR_EM * len * s wide, 0.85 s high) well inside the incircle
    size = float(min(6.0, 0.6 * 1.6 * r[f] / max(CHAR_EM * len(text), 0.85)))
    return TextItem(text, float(center[0]), float(center[1]), 0.0, max(size, 0.25), "piece-label")


OVERLAP_MM2 = 1e-4  # intersections below this area (0.01 x 0.01 mm) are touching, not overlap


def _overlap(a, b, prepared_b=None) -> bool:
    """True when polygons a and b share more than OVERLAP_MM2 of area (touching is fine)."""
    import shapely

    if not (prepared_b or b).intersects(a):
        return False
    return shapely.area(shapely.intersection(a, b)) > OVERLAP_MM2


@dataclass
class _Occ:
    piece: int
    face: int
    k: int
    p0: np.ndarray
    p1: np.ndarray
    tri: np.ndarray


def _tab_polygon(occ: _Occ, factor: float, side_deg: float) -> np.ndarray | None:
    """Trapezoid on the outer side of the cut edge: height factor * min(TAB_REL * length, TAB_MAX_MM),
    sides at `side_deg` to the base (a flatter side slips into a narrow notch of the net)."""
    d = occ.p1 - occ.p0
    length = math.hypot(d[0], d[1])
    if length < 1e-9:
        return None
    u = d / length
    n = np.array([-u[1], u[0]])
    if np.dot(occ.tri.mean(axis=0) - occ.p0, n) > 0:
        n = -n  # away from the face
    h = min(TAB_REL * length, TAB_MAX_MM) * factor
    inset = h / math.tan(math.radians(side_deg))
    if 2 * inset > 0.9 * length:  # the sides would cross: lower the tab so its top keeps 10 %
        inset = 0.45 * length
        h = inset * math.tan(math.radians(side_deg))
    if h < TAB_MIN_MM:
        return None
    return np.array([occ.p0, occ.p0 + u * inset + n * h, occ.p1 - u * inset + n * h, occ.p1])


# (height factor, side angle) in order of preference: full 45-degree trapezoids first, then flatter
# and lower ones that fit into the notches of a net
TAB_VARIANTS = ((1.0, 45.0), (1.0, 30.0), (0.6, 30.0), (0.6, 18.0), (0.35, 18.0), (0.35, 10.0))


def build_sheet_pieces(inputs: list[PieceInput], scale: float, tabs: bool = True
                       ) -> tuple[list[SheetPiece], list[GlueEdge], LayoutStats]:
    """Draw every piece in mm and pair up their cut edges (see the module docstring).

    Tabs: for each glued pair, a trapezoid on the first side; if it would overlap a face or
    another tab of its piece, the other side; then both sides again with the lower / flatter
    TAB_VARIANTS; else none (listed in LayoutStats.untabbed). A tab may touch faces and tabs (its
    fold line, corners) but not share more than OVERLAP_MM2 of area with them (shapely)."""
    import shapely
    from shapely.geometry import Polygon
    from shapely.prepared import prep

    bodies, faces_xy, creases, occs = [], [], [], []
    for i, inp in enumerate(inputs):
        net = inp.net
        mesh = net.mesh
        topo = mesh.topology
        xy = net.coords * scale
        xy[..., 1] *= -1.0  # y down, seen from the outer side
        faces_xy.append(xy)
        bodies.append(shapely.union_all(shapely.polygons(xy)))
        child = np.flatnonzero(net.parent >= 0)
        e = net.parent_edge[child]
        ends = topo.edges[e]
        k0 = np.argmax(mesh.faces[child] == ends[:, :1], axis=1)
        k1 = np.argmax(mesh.faces[child] == ends[:, 1:], axis=1)
        seg = np.stack([xy[child, k0], xy[child, k1]], axis=1)
        rho = mesh.fold_angles[e]
        creases.append((seg[rho > FLAT_EPS], seg[rho < -FLAT_EPS]))
        # cut occurrences: face sides that are not creases of this piece
        E = topo.n_edges
        crease_keys = np.concatenate([child * E + e, net.parent[child] * E + e])
        F = len(mesh.faces)
        occ_key = np.arange(F)[:, None] * E + topo.face_edges
        is_cut = ~np.isin(occ_key, crease_keys)
        for f, k in zip(*np.nonzero(is_cut)):
            a, b = mesh.faces[f, k], mesh.faces[f, (k + 1) % 3]
            key = (int(min(inp.vertex_ids[a], inp.vertex_ids[b])), int(max(inp.vertex_ids[a], inp.vertex_ids[b])))
            occs.append((key, _Occ(i, int(f), int(k), xy[f, k], xy[f, (k + 1) % 3], xy[f])))

    groups: dict[tuple[int, int], list[_Occ]] = {}
    for key, o in occs:
        groups.setdefault(key, []).append(o)
    pairs = [(key, v) for key, v in groups.items() if len(v) == 2]
    open_edges = sum(1 for v in groups.values() if len(v) == 1)
    pairs.sort(key=lambda kv: (min(o.piece for o in kv[1]), kv[0]))

    prepared = [prep(b) for b in bodies] if tabs else []
    piece_tabs: list[list] = [[] for _ in inputs]
    slits: list[list] = [[] for _ in inputs]
    glue, untabbed = [], []
    n_tabs = shrunk = moved = 0
    texts: list[list[TextItem]] = [[] for _ in inputs]
    small = 0
    for idx, (key, (o1, o2)) in enumerate(pairs):
        label = str(idx + 1)
        if o1.piece == o2.piece and np.allclose(o1.p0, o2.p1, atol=1e-6) and np.allclose(o1.p1, o2.p0, atol=1e-6):
            slits[o1.piece].append(np.array([o1.p0, o1.p1]))  # the two sides touch in the plane
        for o in (o1, o2):
            item, big = _edge_label(o.tri, o.k, label)
            texts[o.piece].append(item)
            small += not big
        chosen, height = None, 0.0
        if tabs:
            for factor, side_deg in TAB_VARIANTS:
                for side, o in enumerate((o1, o2)):
                    poly = _tab_polygon(o, factor, side_deg)
                    if poly is None:
                        continue
                    tab = Polygon(poly)
                    if not tab.is_valid or _overlap(tab, bodies[o.piece], prepared[o.piece]):
                        continue
                    if any(_overlap(tab, t) for t in piece_tabs[o.piece]):
                        continue
                    chosen, height = (o, poly, side, factor, side_deg), float(np.linalg.norm(
                        (poly[1] + poly[2]) / 2 - (poly[0] + poly[3]) / 2))
                    break
                if chosen is not None:
                    break
        if chosen is None:
            untabbed.append(label) if tabs else None
            glue.append(GlueEdge(label, key, (o1.piece, o2.piece), None, 0.0))
            continue
        o, poly, side, factor, side_deg = chosen
        piece_tabs[o.piece].append(Polygon(poly))
        n_tabs += 1
        shrunk += (factor, side_deg) != TAB_VARIANTS[0]
        moved += side == 1
        glue.append(GlueEdge(label, key, (o1.piece, o2.piece), o.piece, height))

    pieces = []
    for i, inp in enumerate(inputs):
        name = _piece_name(i)
        tab_polys = piece_tabs[i]
        outline = shapely.union_all([bodies[i], *tab_polys]) if tab_polys else bodies[i]
        tab_arr = tuple(np.asarray(t.exterior.coords)[:-1] for t in tab_polys)
        folds = np.array([[t[0], t[3]] for t in tab_arr]).reshape(-1, 2, 2)
        texts[i].append(_piece_label(faces_xy[i], name))
        pieces.append(SheetPiece(
            name=name, part=inp.part, face_ids=np.asarray(inp.face_ids), faces_xy=faces_xy[i], body=bodies[i],
            outline=outline, mountain=creases[i][0].reshape(-1, 2, 2), valley=creases[i][1].reshape(-1, 2, 2),
            slits=np.array(slits[i]).reshape(-1, 2, 2), tabs=tab_arr, tab_folds=folds, texts=tuple(texts[i])))
    stats = LayoutStats(glue_edges=len(pairs), tabs=n_tabs, tabs_shrunk=shrunk, tabs_moved=moved,
                        untabbed=tuple(untabbed), small_labels=small, open_edges=open_edges)
    return pieces, glue, stats


# ----------------------------------------------------------------------------------------------
# Placing pieces on pages


def place(piece: SheetPiece, placement) -> SheetPiece:
    """The piece moved by a `pack.Placement` (rotation then translation, in page mm, y down)."""
    from shapely import affinity

    def tf(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=np.float64)
        return placement.apply(a.reshape(-1, 2)).reshape(a.shape) if a.size else a

    def tg(g):
        g = affinity.rotate(g, placement.angle, origin=(0, 0), use_radians=False)
        return affinity.translate(g, *placement.offset)

    # Placement rotates by +angle in the (x, y-down) frame, which looks clockwise on the page.
    texts = []
    for t in piece.texts:
        x, y = placement.apply(np.array([[t.x, t.y]]))[0]
        texts.append(replace(t, x=float(x), y=float(y), angle=_upright(t.angle - placement.angle)))
    return replace(piece, faces_xy=tf(piece.faces_xy), body=tg(piece.body), outline=tg(piece.outline),
                   mountain=tf(piece.mountain), valley=tf(piece.valley), slits=tf(piece.slits),
                   tabs=tuple(tf(t) for t in piece.tabs), tab_folds=tf(piece.tab_folds), texts=tuple(texts))


def page_of(pieces: list[SheetPiece], width: float, height: float, footer: str | None = None,
            footer_y: float | None = None) -> Page:
    """A `pages.Page` with the (already placed) pieces; an optional footer line of text."""
    texts = [t for p in pieces for t in p.texts]
    if footer:
        texts.append(TextItem(footer, width / 2, footer_y if footer_y is not None else height - 12, 0.0, 2.5, "title"))
    cat = lambda name: np.concatenate([getattr(p, name).reshape(-1, 2, 2) for p in pieces]) if pieces else np.zeros((0, 2, 2))
    return Page(width=width, height=height, cut=tuple(r for p in pieces for r in p.cut_rings()),
                mountain=cat("mountain"), valley=cat("valley"), tab_folds=cat("tab_folds"), texts=tuple(texts),
                faces=tuple(p.faces_xy for p in pieces), slits=cat("slits"),
                tabs=tuple(t for p in pieces for t in p.tabs))
