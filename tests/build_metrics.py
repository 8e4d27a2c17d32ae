"""How buildable a `polyfold make` folder is, measured from its written files and the mesh alone.

Stands alone (numpy, shapely, trimesh, and `sheet_reader` for the SVG / DXF / PDF; never
polyfold): used by bench/bench_build.py and the tests. `measure_folder(folder, mesh_path)` reads

- the sheets: sheet-NN.svg (print files; cut-NN.svg and other files beside them are not read),
  sheet-NN.dxf and sheets.pdf, with `sheet_reader`;
- assembly.json for the glue pairs (label, the mesh edge's two vertices, the pieces) and the size;
  report.json only for the margin option;
- the mesh file with trimesh (file order kept), scaled as make scales it (its longest bounding-box
  side becomes size_mm); its fold angles are computed here (outward normals, + = convex).

and measures (`Measures`):

- pieces (assembly), pages (SVG files), utilisation: paper area of the pieces (SVG cut outlines,
  holes removed) over pages x the page inside the margins;
- glue edges: the assembly's glue pairs. Each label is printed beside both copies of its edge;
  a copy is found on its page as the pair of printed corner points (outline corners, ends of
  lines) of the edge's printed length nearest to the label. Beside it: the face (a preview face)
  and beyond it either a tab (paper that is no face, attached along the edge, with a fold line
  on the edge in the SVG), a face (a slit) or nothing;
- untabbed: glue edges with no tab beyond either copy and no glue strip (a cut outline with no
  face, carrying the label twice); a label with a leader line stands for the edge at the
  leader's other end (a bent leader: lines joined end to end); a label printed for a seam run
  (assembly.json's printed_label shared by several edges) stands for the run's edges, followed
  corner by corner along the outline from the one nearest the label, ending at the two ticks
  (short leader lines) that mark the run's ends; reduced tabs: tabs
  shallower than the full tab, min(0.4 x edge, 6 mm) (today's full size), measured as the tab's
  depth from its edge;
- wrong-way fold marks (per format: svg, dxf, pdf): a tab whose fold line along its edge is not
  drawn as its seam folds (mountain on a convex seam, valley on a concave one, seen from the
  printed side = the outside), or is not drawn; seams within FLAT_DEG of flat take either;
- labels (SVG; the footer and other titles not counted): under the minimum (cap height below
  LABEL_MIN_MM), overlapping pairs of label boxes, and labels whose box crosses a cut or fold line;
- flat regions cut: glue edges between faces within FLAT_DEG of coplanar, or along a diagonal of
  a polygon of the input file (OBJ faces of 4 or more corners);
- smallest printed edge and smallest face height (twice area over longest side), mm.

`notes` says what could not be matched (labels not printed twice, copies not found, ...), so a
number is never silently wrong.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

from sheet_reader import FOLD_KINDS, Sheet, read_dxf, read_pdf, read_svg

FLAT_DEG = math.degrees(1e-3)  # "coplanar": within 1e-3 rad (0.057 degrees), the tolerance polyfold states (README)
LABEL_MIN_MM = 2.0  # smallest readable cap height
FULL_TAB_MM = 6.0  # today's full tab: min(FULL_TAB_REL x edge, FULL_TAB_MM) deep
FULL_TAB_REL = 0.4
LENGTH_TOL_MM = 1e-3  # printed and model edge lengths agree this well (coordinates are written to 1e-4 mm)
PROBE_MM = 0.2  # how far beside an edge its sides are probed
ATTACHED = 0.3  # a tab is attached to an edge when it runs along this fraction of it at least
ON_LINE_MM = 0.02  # a fold line lies along an edge: both ends this close to its line
LEADER_TOUCH_MM = 0.05  # a leader line ends this close to its label's box
OVERLAP_MM2 = 1e-3  # label boxes sharing less area than this only touch
ANCHORS = 4  # per edge of a seam run and length tolerance: edges near its label tried as the start
TICK_MAX_MM = 2.0  # a seam run's end mark: a leader line at most this long from a corner of its outline
NOT_LABELS = ("title", "footer", "scale", "legend")  # text classes that are not glue or piece labels


# ----------------------------------------------------------------------------------------------
# The mesh


@dataclass(frozen=True)
class Model:
    """A mesh file at its printed scale: vertices (model units), faces (F, 3), scale (mm per
    unit), per undirected edge (a, b), a < b: its fold angle in degrees (+ convex, - concave,
    None when not between exactly two faces), the corners opposite it in its faces and whether
    it is a diagonal of an input polygon."""

    vertices: np.ndarray
    faces: np.ndarray
    scale: float
    fold_deg: dict[tuple[int, int], float | None]
    diagonals: frozenset[tuple[int, int]]
    opposite: dict[tuple[int, int], tuple[int, ...]] = field(default_factory=dict)

    def corners(self, a: int, b: int) -> list[tuple[float, float]]:
        """Per face on edge (a, b): the printed distances (mm) from a and from b to the face's
        third corner."""
        key = (min(a, b), max(a, b))
        v = self.vertices
        return [(float(np.linalg.norm(v[c] - v[a])) * self.scale, float(np.linalg.norm(v[c] - v[b])) * self.scale)
                for c in self.opposite.get(key, ())]


def _obj_polygons(path: Path) -> list[list[int]]:
    """The faces of an OBJ file as 0-based vertex lists (negative indices resolved)."""
    polys, n_v = [], 0
    for line in path.read_text(errors="replace").splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            n_v += 1
        elif parts[0] == "f":
            ids = [int(p.split("/")[0]) for p in parts[1:]]
            polys.append([i - 1 if i > 0 else n_v + i for i in ids])
    return polys


def load_model(mesh_path: str | Path, size_mm: float) -> Model:
    """The mesh (trimesh, file order kept) scaled so its longest bounding-box side is size_mm."""
    import trimesh

    path = Path(mesh_path)
    mesh = trimesh.load(str(path), process=False, maintain_order=True, force="mesh")
    v = np.asarray(mesh.vertices, dtype=float)
    f = np.asarray(mesh.faces, dtype=np.int64)
    used = np.unique(f)
    scale = size_mm / float(np.ptp(v[used], axis=0).max())
    tri = v[f]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = 1.0 if float(np.einsum("ij,ij->", tri[:, 0], normal)) >= 0 else -1.0  # signed volume
    unit = normal / np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None] * outward
    sides: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for fi, face in enumerate(f.tolist()):
        for k in range(3):
            a, b = face[k], face[(k + 1) % 3]
            sides.setdefault((min(a, b), max(a, b)), []).append((fi, face[(k + 2) % 3]))
    fold_deg: dict[tuple[int, int], float | None] = {}
    for key, owners in sides.items():
        if len(owners) != 2:
            fold_deg[key] = None
            continue
        (f1, _), (_, c2) = owners
        angle = math.degrees(math.acos(float(np.clip(unit[f1] @ unit[owners[1][0]], -1.0, 1.0))))
        convex = float(unit[f1] @ (v[c2] - v[key[0]])) < 0  # the other face bends away from the outside
        fold_deg[key] = angle if convex else -angle
    diagonals = set()
    if path.suffix.lower() == ".obj":
        for poly in _obj_polygons(path):
            n = len(poly)
            for i in range(n):
                for j in range(i + 2, n - (1 if i == 0 else 0)):
                    diagonals.add((min(poly[i], poly[j]), max(poly[i], poly[j])))
    opposite = {key: tuple(c for _, c in owners) for key, owners in sides.items()}
    return Model(v, f, scale, fold_deg, frozenset(diagonals), opposite)


def smallest_sizes(model: Model) -> tuple[float, float]:
    """(shortest edge, smallest face height) as printed, mm."""
    tri = model.vertices[model.faces]
    sides = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)
    area2 = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    return float(sides.min()) * model.scale, float((area2 / sides.max(axis=1)).min()) * model.scale


# ----------------------------------------------------------------------------------------------
# The folder


@dataclass
class Copy:
    """One printed copy of a glue edge: page (0-based), ends a, b (page mm), what lies beyond it
    ("tab", "face", "none"), the tab's depth (mm, 0 without), and per format the kinds of the
    fold lines drawn along it."""

    page: int
    a: np.ndarray
    b: np.ndarray
    beyond: str
    depth: float = 0.0
    marks: dict[str, set[str]] = field(default_factory=dict)


@dataclass
class Measures:
    """What `measure_folder` measures (module docstring); the *_labels lists name the glue labels
    concerned."""

    pieces: int
    pages: int
    utilisation: float
    glue_edges: int
    untabbed: int
    reduced_tabs: int
    tabs: int
    labels: int
    small_labels: int
    label_pairs: int
    label_lines: int
    flat_cut: int
    wrong_way: dict[str, int]
    smallest_edge_mm: float
    smallest_face_mm: float
    untabbed_labels: list[str] = field(default_factory=list)
    wrong_way_labels: dict[str, list[str]] = field(default_factory=dict)
    flat_cut_labels: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    copies: dict[str, list[Copy]] = field(default_factory=dict)  # glue label -> its printed copies found
    glue_strips: int = 0  # glue edges joined by a glue strip instead of a tab


def _page_points(sheet: Sheet) -> np.ndarray:
    """Every printed corner point of a page: outline corners and line ends (rounded duplicates
    merged)."""
    pts = [r for r in sheet.outlines] + [sheet.lines().reshape(-1, 2)]
    allp = np.concatenate(pts) if pts else np.zeros((0, 2))
    return np.unique(np.round(allp, 4), axis=0)


class _Page:
    """One page with what the measures need: its points, paper, faces and tab regions."""

    def __init__(self, svg: Sheet) -> None:
        self.svg = svg
        self.points = _page_points(svg)
        pieces = svg.pieces()
        self.paper = shapely.union_all(pieces) if pieces else shapely.Polygon()
        self.area = float(sum(p.area for p in pieces))
        self.n_pieces = len(pieces)
        faces = [shapely.Polygon(f) for f in svg.faces if len(f) >= 3]
        self.faces = shapely.union_all(faces).buffer(1e-3) if faces else shapely.Polygon()
        self.has_faces = bool(faces)
        self.tabs = shapely.difference(self.paper, self.faces)
        # the ends of every short leader line: a seam run's end marks start at one of them
        short = [line for line in svg.leaders if len(line) == 2 and np.linalg.norm(line[1] - line[0]) <= TICK_MAX_MM]
        self.tick_ends = np.array([p for line in short for p in line]).reshape(-1, 2)
        shapely.prepare(self.paper)
        shapely.prepare(self.faces)

    def locate(self, label_xy: np.ndarray, length: float,
               corners: list[tuple[float, float]] = ()) -> tuple[np.ndarray, np.ndarray] | None:
        """The printed face edge of `length` mm nearest the label: two corner points that far apart
        (within LENGTH_TOL_MM; failing that, within 10 times as much: a corner merged with a
        tab corner close by) with a face all along one side (when the page has preview faces).
        `corners` (`Model.corners`): an edge whose face's third corner is printed where the mesh
        puts it is taken first (an edge of the same length nearer the label, e.g. of a sliver face
        beside it, is not the one)."""
        for tol in self._tols(length):
            found = self.segments(label_xy, length, corners, tol)
            if found:
                return found[0][:2]
        return None

    @staticmethod
    def _tols(length: float) -> tuple[float, float]:
        tol = LENGTH_TOL_MM + 1e-5 * length
        return tol, 10 * tol

    def segments(self, label_xy: np.ndarray, length: float, corners, tol: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """Every face edge `locate` could take at length tolerance tol, its pick first (cornered
        ones, then the others, each nearest the label first): (end, end, cornered)."""
        d = np.linalg.norm(self.points - label_xy, axis=1)
        near = self.points[d <= length + 20.0]
        if len(near) < 2:
            return []
        i, j = np.triu_indices(len(near), 1)
        ok = np.abs(np.linalg.norm(near[i] - near[j], axis=1) - length) <= tol
        if not ok.any():
            return []
        a, b = near[i[ok]], near[j[ok]]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", label_xy - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
        dist = np.linalg.norm(a + t[:, None] * ab - label_xy, axis=1)
        order = np.argsort(dist, kind="stable")
        faced = [k for k in order if not self.has_faces
                 or any(set(self.side(a[k], b[k], s)) == {"face"} for s in (1.0, -1.0))]
        cornered = [k for k in faced if self._cornered(a[k], b[k], corners, 10 * tol)]
        first = set(cornered)
        ranked = cornered + [k for k in faced if k not in first]
        # a cut edge (face on one side only) before a crease of the same length
        ranked.sort(key=lambda k: not self._outline_side(a[k], b[k]))
        return [(a[k], b[k], k in first) for k in ranked]

    def follow(self, p: np.ndarray, back: np.ndarray, length: float,
               corners: list[tuple[float, float]]) -> np.ndarray | None:
        """The next corner along a seam run: a printed point `length` mm from p (not `back`, the
        corner before p) such that p to it is a cut edge (a face all along one side only, not a
        crease between two faces), one whose
        face's third corner is printed where the mesh puts it taken first."""
        d = np.linalg.norm(self.points - p, axis=1)
        tol = LENGTH_TOL_MM + 1e-5 * length
        for tol in (tol, 10 * tol):  # as `locate`: then a corner merged with a tab corner close by
            cand = self.points[(np.abs(d - length) <= tol) & (np.linalg.norm(self.points - back, axis=1) > tol)]
            faced = [r for r in cand if not self.has_faces or self._outline_side(p, r)]
            cornered = [r for r in faced if self._cornered(p, r, corners, 10 * tol)]
            if cornered or faced:
                return (cornered or faced)[0]
        return None

    def locate_run(self, label_xy: np.ndarray, chain: list[tuple[int, int]], model: "Model"
                   ) -> list[tuple[np.ndarray, np.ndarray]] | None:
        """The printed copy of a seam run (its mesh edges (v0, v1), (v1, v2), ... in order) whose
        label is at label_xy: one of its edges found near the label (as `locate` finds them,
        nearest the label first), then the others corner by corner along the outline (`follow`),
        the run's two ends at its end marks (`_ticked`). Per edge its ends (printed points of v_i,
        v_i+1), or None."""
        verts = [chain[0][0]] + [b for _a, b in chain]
        k = len(chain)
        length = [float(np.linalg.norm(model.vertices[a] - model.vertices[b])) * model.scale for a, b in chain]
        anchors = []  # as `locate` prefers them: tight length tolerance, cornered, nearest the label
        for m in range(k):
            for level, tol in enumerate(self._tols(length[m])):
                for n, (a, b, cornered) in enumerate(self.segments(label_xy, length[m], model.corners(*chain[m]),
                                                                   tol)[:ANCHORS]):
                    anchors.append((level, not cornered, _distance(label_xy, a, b), m, n, (a, b)))
        for *_key, m, _n, seg in sorted(anchors, key=lambda a: a[:5]):
            for pa, pb in (seg, seg[::-1]):
                pos: dict[int, np.ndarray] = {m: pa, m + 1: pb}
                for i in range(m + 1, k):
                    r = self.follow(pos[i], pos[i - 1], length[i], model.corners(verts[i], verts[i + 1]))
                    if r is None:
                        break
                    pos[i + 1] = r
                for i in range(m - 1, -1, -1):
                    if i + 1 not in pos:
                        break
                    r = self.follow(pos[i + 1], pos[i + 2], length[i], model.corners(verts[i], verts[i + 1]))
                    if r is None:
                        break
                    pos[i] = r
                # the run found must end at its two end marks: its edges are often alike in length
                if len(pos) == k + 1 and (k == 1 or (self._ticked(pos[0]) and self._ticked(pos[k]))):
                    return [(pos[i], pos[i + 1]) for i in range(k)]
        return None

    def _ticked(self, p: np.ndarray) -> bool:
        """Whether a short leader line (a seam run's end mark) starts or ends at point p."""
        return bool(len(self.tick_ends)) and bool((np.linalg.norm(self.tick_ends - p, axis=1) <= ON_LINE_MM).any())

    def _outline_side(self, a: np.ndarray, b: np.ndarray) -> bool:
        """True when segment a-b has a face all along one side and not all along the other."""
        faced = [set(self.side(a, b, s)) == {"face"} for s in (1.0, -1.0)]
        return faced[0] != faced[1]

    def _cornered(self, a: np.ndarray, b: np.ndarray, corners, tol: float) -> bool:
        """True when a printed point lies at one of the (from a, from b) distance pairs of
        `corners` (either way round: which end is which is not known)."""
        da = np.linalg.norm(self.points - a, axis=1)
        db = np.linalg.norm(self.points - b, axis=1)
        return any(bool(((np.abs(da - x) <= tol) & (np.abs(db - y) <= tol)).any()
                        or ((np.abs(da - y) <= tol) & (np.abs(db - x) <= tol)).any()) for x, y in corners)

    def side(self, a: np.ndarray, b: np.ndarray, sign: float) -> list[str]:
        """What lies at PROBE_MM on one side (sign +1: left of a->b in page coordinates) of the
        segment, at five points along it: "face", "tab" (paper, no face) or "none"."""
        ab = b - a
        n = np.array([-ab[1], ab[0]]) / np.linalg.norm(ab) * sign
        out = []
        for t in (0.2, 0.35, 0.5, 0.65, 0.8):
            p = shapely.Point(*(a + t * ab + PROBE_MM * n))
            out.append("face" if self.faces.contains(p) else "tab" if self.paper.contains(p) else "none")
        return out

    def tab_beyond(self, a: np.ndarray, b: np.ndarray, sign: float) -> float | None:
        """Depth (mm) of the tab attached to the segment on that side (its farthest point from the
        edge), or None when no tab is: a tab region there that runs along at least ATTACHED of
        the segment (the tab of another copy reaching into a notch beside it does not count)."""
        ab = b - a
        n = np.array([-ab[1], ab[0]]) / np.linalg.norm(ab) * sign
        probes = [shapely.Point(*(a + t * ab + PROBE_MM * n)) for t in (0.2, 0.35, 0.5, 0.65, 0.8)]
        edge = shapely.LineString([a, b])
        depth = None
        for part in getattr(self.tabs, "geoms", [self.tabs]):
            if part.is_empty or not any(part.contains(p) for p in probes):
                continue
            if shapely.intersection(edge, part.buffer(ON_LINE_MM)).length < ATTACHED * edge.length:
                continue
            ring = np.asarray(part.exterior.coords)
            depth = max(depth or 0.0, float(((ring - a) @ n).max()))
        return depth


def _leader_end(leaders: list, first, at_label: int) -> np.ndarray:
    """The far end of a leader drawn as connected lines (a bent leader), from its line `first`
    whose end `at_label` (0 or -1) touches the label: each next line starts where the last ended."""
    used = {id(first)}
    end = np.asarray(first[-1 if at_label == 0 else 0], dtype=float)
    while True:
        nxt = None
        for line in leaders:
            if id(line) in used:
                continue
            for k in (0, -1):
                if np.linalg.norm(np.asarray(line[k], dtype=float) - end) < 1e-3:
                    nxt = (line, k)
                    break
            if nxt:
                break
        if nxt is None:
            return end
        used.add(id(nxt[0]))
        end = np.asarray(nxt[0][-1 if nxt[1] == 0 else 0], dtype=float)


def _distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from point p to segment a-b."""
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-300), 0.0, 1.0))
    return float(np.linalg.norm(a + t * ab - p))


def _chain(rows: list[dict]) -> tuple[list[tuple[int, int]], list[dict]] | None:
    """The glue rows of one printed label as a chain of mesh edges: the edges (v0, v1), (v1, v2),
    ... in order and the rows in that order (from a vertex on one edge only; a closed loop from
    any), or None when they do not form one."""
    ends = [(int(r["mesh_vertices"][0]), int(r["mesh_vertices"][1])) for r in rows]
    at: dict[int, list[int]] = {}
    for i, (a, b) in enumerate(ends):
        at.setdefault(a, []).append(i)
        at.setdefault(b, []).append(i)
    loose = [v for v, ids in at.items() if len(ids) == 1]
    v = min(loose) if loose else ends[0][0]
    order, edges, used = [], [], set()
    while len(order) < len(rows):
        nxt = [i for i in at[v] if i not in used]
        if not nxt:
            return None
        i = nxt[0]
        used.add(i)
        a, b = ends[i]
        w = b if a == v else a
        order.append(i)
        edges.append((v, w))
        v = w
    return edges, [rows[i] for i in order]


def _marks(sheet: Sheet, a: np.ndarray, b: np.ndarray) -> set[str]:
    """Kinds of the fold lines of a sheet that lie along segment a-b."""
    ab = b - a
    length = float(np.linalg.norm(ab))
    u = ab / length
    n = np.array([-u[1], u[0]])
    kinds = set()
    for kind in FOLD_KINDS:
        segs = sheet.folds[kind]
        if not len(segs):
            continue
        rel = segs - a
        off = np.abs(rel @ n)  # (k, 2) distances of both ends to the line
        along = rel @ u
        lo, hi = along.min(axis=1), along.max(axis=1)
        overlap = np.minimum(hi, length) - np.maximum(lo, 0.0)
        hit = (off.max(axis=1) <= ON_LINE_MM) & (overlap > 0.5 * np.minimum(hi - lo, length))
        if hit.any():
            kinds.add(kind)
    return kinds


def _label_measures(sheets: list[Sheet]) -> tuple[int, int, int, int]:
    """(labels, under the minimum, overlapping pairs, labels crossing a line) over the SVG pages."""
    n = small = pairs = crossing = 0
    for sheet in sheets:
        labels = [lb for lb in sheet.labels if not any(w in lb.kind.lower() for w in NOT_LABELS)]
        n += len(labels)
        small += sum(lb.cap < LABEL_MIN_MM - 1e-9 for lb in labels)
        if not labels:
            continue
        boxes = np.array([lb.box() for lb in labels], dtype=object)
        i, j = shapely.STRtree(boxes).query(boxes, predicate="intersects")
        keep = i < j
        if keep.any():
            pairs += int((shapely.area(shapely.intersection(boxes[i[keep]], boxes[j[keep]])) > OVERLAP_MM2).sum())
        lines = sheet.lines()
        if len(lines):
            geoms = shapely.linestrings(lines)
            hit, _ = shapely.STRtree(geoms).query(boxes, predicate="intersects")
            crossing += len(np.unique(hit))
    return n, small, pairs, crossing


def measure_folder(folder: str | Path, mesh_path: str | Path) -> Measures:
    """The build-quality measures of a make folder (module docstring)."""
    folder = Path(folder)
    assembly = json.loads((folder / "assembly.json").read_text())
    margin = 10.0
    report = folder / "report.json"
    if report.is_file():
        margin = float(json.loads(report.read_text()).get("options", {}).get("margin", margin))
    notes: list[str] = []
    svg_files = sorted(folder.glob("sheet-*.svg"), key=lambda p: int(re.sub(r"\D", "", p.stem) or 0))
    svgs = [read_svg(p) for p in svg_files]
    pages = [_Page(s) for s in svgs]
    formats: dict[str, list[Sheet]] = {"svg": svgs}
    dxf_files = [p.with_suffix(".dxf") for p in svg_files]
    if all(p.is_file() for p in dxf_files):
        formats["dxf"] = [read_dxf(p, s.height, s.width) for p, s in zip(dxf_files, svgs)]
    else:
        notes.append("some sheet-NN.dxf missing: DXF not measured")
    try:
        import pypdf  # noqa: F401 (the PDF reader's library: a test extra)
    except ImportError:
        notes.append("pypdf not installed: PDF not measured")
    else:
        pdf = read_pdf(folder / "sheets.pdf") if (folder / "sheets.pdf").is_file() else []
        if len(pdf) == len(svgs):
            formats["pdf"] = pdf
        else:
            notes.append(f"sheets.pdf has {len(pdf)} pages, {len(svgs)} SVG sheets: PDF not measured")
    model = load_model(mesh_path, float(assembly["size_mm"]))
    n_pieces = len(assembly["pieces"])
    drawn = sum(p.n_pieces for p in pages)
    n_strips = sum(1 for pg in pages for p in pg.svg.pieces() if pg.has_faces and not p.intersects(pg.faces))
    if drawn - n_strips != n_pieces:
        notes.append(f"{drawn} cut outlines ({n_strips} glue strips) for {n_pieces} pieces")
    w, h = (svgs[0].width, svgs[0].height) if svgs else (0.0, 0.0)
    usable = len(svgs) * max(w - 2 * margin, 0.0) * max(h - 2 * margin, 0.0)
    utilisation = sum(p.area for p in pages) / usable if usable else 0.0

    # every glue label where it is printed (SVG): a label with a leader line stands for the edge at
    # the leader's other end; a label on a glue strip (paper with no face) stands for the strip
    where: dict[str, list[tuple[int, np.ndarray]]] = {}
    on_strip: dict[str, int] = {}
    for k, sheet in enumerate(svgs):
        strips = [p for p in sheet.pieces() if not pages[k].has_faces or not p.intersects(pages[k].faces)]
        for lb in sheet.labels:
            box = lb.box()
            c = box.centroid
            xy = np.array([c.x, c.y])
            if any(st.contains(c) for st in strips):
                on_strip[lb.text] = on_strip.get(lb.text, 0) + 1
                continue
            for line in sheet.leaders:
                ends = [shapely.Point(*line[0]), shapely.Point(*line[-1])]
                touch = [box.distance(e) < LEADER_TOUCH_MM for e in ends]
                if touch[0] != touch[1]:
                    xy = _leader_end(sheet.leaders, line, 0 if touch[0] else -1)
                    break
            where.setdefault(lb.text, []).append((k, xy))
    untabbed, wrong, flat_cut, reduced, n_tabs = [], {f: [] for f in formats}, [], 0, 0
    unlocated = miscounted = unknown = strips_found = 0
    # where each glue edge's copies are printed: a label stands for its edge, or for a seam run
    # (assembly rows sharing one printed_label): the run's edges one after another along the
    # outline, found from the label corner by corner
    groups: dict[str, list[dict]] = {}
    for row in assembly["glue"]:
        groups.setdefault(str(row.get("printed_label", row["label"])), []).append(row)
    located: dict[str, list[tuple[int, np.ndarray, np.ndarray, np.ndarray]]] = {}
    n_runs = 0
    for printed, rows in groups.items():
        spots = where.get(printed, [])
        if len(spots) != 2:
            miscounted += len(rows)
        chain = _chain(rows)
        if chain is None:
            notes.append(f"printed label {printed}: its {len(rows)} glue edges are no chain")
            continue
        n_runs += len(rows) > 1
        for page, xy in spots:
            segs = pages[page].locate_run(xy, chain[0], model)
            if segs is None:
                unlocated += len(rows)
                continue
            for row, (p0, p1) in zip(chain[1], segs):
                located.setdefault(str(row["label"]), []).append((page, p0, p1, xy))
    found: dict[str, list[Copy]] = {}
    for row in assembly["glue"]:
        label = str(row["label"])
        a, b = (int(x) for x in row["mesh_vertices"])
        key = (min(a, b), max(a, b))
        deg = model.fold_deg.get(key)
        if key not in model.fold_deg:
            unknown += 1
            continue
        if (deg is not None and abs(deg) < FLAT_DEG) or key in model.diagonals:
            flat_cut.append(label)
        length = float(np.linalg.norm(model.vertices[a] - model.vertices[b])) * model.scale
        copies = []
        for page, p0, p1, xy in located.get(label, []):
            sides = {s: pages[page].side(p0, p1, s) for s in (1.0, -1.0)}
            faces = {s: v.count("face") for s, v in sides.items()}
            (ux, uy), (wx, wy) = p1 - p0, xy - p0
            label_side = 1.0 if ux * wy - uy * wx > 0 else -1.0
            # the copy's own face: the side with face paper; both or neither: the label's side
            own = max(sides, key=lambda s: faces[s]) if faces[1.0] != faces[-1.0] else label_side
            far = sides[-own]
            depth = pages[page].tab_beyond(p0, p1, -own) if "tab" in far else None
            if depth is not None and not _marks(svgs[page], p0, p1):
                depth = None  # paper beyond but no fold line on the edge: another edge's tab reaching here
            beyond = "tab" if depth is not None else "face" if "face" in far else "none"
            copy = Copy(page, p0, p1, beyond, depth or 0.0)
            if beyond == "tab":
                copy.marks = {f: _marks(sheets[page], p0, p1) for f, sheets in formats.items()}
            copies.append(copy)
        found[label] = copies
        tabbed = [c for c in copies if c.beyond == "tab"]
        if on_strip.get(label) == 2:
            strips_found += 1  # glued with a strip behind both copies: tabbed
        elif len(copies) == 2 and not tabbed:
            untabbed.append(label)
        for c in tabbed:
            n_tabs += 1
            if c.depth < min(FULL_TAB_REL * length, FULL_TAB_MM) - 0.05:
                reduced += 1
            want = None if deg is None or abs(deg) < FLAT_DEG else "mountain" if deg > 0 else "valley"
            for f, kinds in c.marks.items():
                if not kinds or (want is not None and kinds != {want}) or len(kinds) > 1:
                    wrong[f].append(label)
    if n_runs:
        notes.append(f"{n_runs} seam runs printed with one label")
    if miscounted:
        notes.append(f"{miscounted} glue edges whose label is not printed exactly twice")
    if unlocated:
        notes.append(f"{unlocated} printed glue-label copies without an edge of the right length nearby")
    if unknown:
        notes.append(f"{unknown} glue pairs name vertices that are no edge of the mesh file")
    n_labels, small, pairs, crossing = _label_measures(svgs)
    edge, face = smallest_sizes(model)
    return Measures(pieces=n_pieces, pages=len(svgs), utilisation=utilisation, glue_edges=len(assembly["glue"]),
                    untabbed=len(untabbed), glue_strips=strips_found, reduced_tabs=reduced, tabs=n_tabs, labels=n_labels, small_labels=small,
                    label_pairs=pairs, label_lines=crossing, flat_cut=len(flat_cut),
                    wrong_way={f: len(v) for f, v in wrong.items()}, smallest_edge_mm=edge, smallest_face_mm=face,
                    untabbed_labels=untabbed, wrong_way_labels=wrong, flat_cut_labels=flat_cut, notes=notes,
                    copies=found)
