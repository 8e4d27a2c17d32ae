"""The build order: which piece to fold and attach when, and which seams to glue in each step.

In: the pieces (their part and whole-mesh faces), the seams (`Seam`: the two pieces, the two
faces, when they meet along the piece's folding path) and the mesh. Out: a `BuildPlan`, steps a
person can follow:

- parts one after another, each new part the one with the most seams to the parts already
  built (the largest first); inside a part the largest piece first, then each time the piece with
  the most seams to the pieces already placed. So every piece, and every part, attaches to what is
  already built (a piece or part joined to nothing is a separate component of the model).
- a "piece" step folds its piece and glues the seams it closes: its own seams as their copies
  meet along its folding path, then the seams that attach it to the pieces already placed; a part
  after the first is joined to the others by a "join" step once it is built. Steps hold at most
  MAX_SEAMS_PER_STEP seams (a seam run whole); the rest follow as "glue" steps.
- inside a step the seams are glued in the order their copies meet along the folding path, then
  farthest from the lid first: the lid is a large face of the last piece, so the model stays open
  around it as long as possible and the seams around it close last.
- every seam's opening: the rim (mm) of the largest hole the model has left once it is glued
  (`opening_rims`). Seams glued while that rim is under REACH_MM cannot be pressed from inside
  (no finger fits): they are marked hard, and the guide says how to close them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh.mesh import Mesh

MAX_SEAMS_PER_STEP = 10
REACH_MM = 90.0  # an opening with a shorter rim (about 29 mm across) lets no finger in to press a tab


@dataclass(frozen=True)
class Seam:
    """Two cut edges glued together: the pieces of its two sides (the same piece for a seam that
    closes the piece itself), the whole-mesh face of each side, its mesh edge (two vertex ids),
    its length on paper (mm), and when its copies meet along the folding path of its piece
    (fraction 0..1; 1 for a seam between two pieces)."""

    pieces: tuple[int, int]
    faces: tuple[int, int]
    mesh_edge: tuple[int, int]
    edge: int  # its row in the mesh's edge table (`Mesh.topology`)
    length_mm: float
    run: str  # seams with the same run are glued together (a seam run printed under one label)
    meet: float = 1.0


@dataclass(frozen=True)
class Step:
    """One step of the build: kind "piece" (fold `piece`, glue the seams it closes), "glue" (more
    seams of the step before) or "join" (a built part glued to the parts before it); the seams
    (indices into the plan's seams) in gluing order, the pieces placed before this step that
    they glue to (for a join, those of the other parts), the pieces in the model after it, and
    the seams glued through an opening under REACH_MM."""

    kind: str
    part: int
    piece: int | None
    seams: tuple[int, ...]
    attach_to: tuple[int, ...]
    placed: tuple[int, ...]
    hard: tuple[int, ...]


@dataclass(frozen=True, eq=False)
class BuildPlan:
    """steps in order; piece_order / part_order: the order pieces and parts come in; lid: the
    face the model closes around last; opening_mm (S,): per seam the rim of the largest opening
    the model has left once it is glued (0: it closed the model)."""

    steps: tuple[Step, ...]
    piece_order: tuple[int, ...]
    part_order: tuple[int, ...]
    lid: int
    opening_mm: np.ndarray


def _greedy(items: list[int], size: dict[int, float], links: dict[tuple[int, int], int], first: int | None = None
            ) -> list[int]:
    """items ordered: `first` (else the largest), then each time the one with the most links to
    those already taken (ties: larger, then lower index)."""
    left = set(items)
    start = first if first is not None else max(items, key=lambda i: (size[i], -i))
    order = [start]
    left.discard(start)
    score = {i: 0 for i in left}
    for (a, b), n in links.items():
        if a == start and b in score:
            score[b] += n
        elif b == start and a in score:
            score[a] += n
    while left:
        nxt = max(left, key=lambda i: (score[i], size[i], -i))
        order.append(nxt)
        left.discard(nxt)
        for (a, b), n in links.items():
            if a == nxt and b in left:
                score[b] += n
            elif b == nxt and a in left:
                score[a] += n
    return order


def _counts(pairs) -> dict[tuple[int, int], int]:
    out: dict[tuple[int, int], int] = {}
    for a, b in pairs:
        if a != b:
            key = (min(a, b), max(a, b))
            out[key] = out.get(key, 0) + 1
    return out


def face_distances(mesh: Mesh, source: int) -> np.ndarray:
    """(F,) distance from face `source` to every face, along the surface: shortest paths
    between face centroids across shared edges (inf for faces in other components)."""
    from ..graphs import shortest_distances

    topo = mesh.topology
    inner = topo.interior
    f0, f1 = topo.edge_faces[inner, 0], topo.edge_faces[inner, 1]
    cent = mesh.vertices[mesh.faces].mean(axis=1)
    w = np.linalg.norm(cent[f0] - cent[f1], axis=1) + 1e-300
    return shortest_distances(mesh.n_faces, f0, f1, w, source)


def _lid(mesh: Mesh, faces: np.ndarray, seam_faces: np.ndarray) -> int:
    """The face of `faces` (the last piece) the model closes around: the largest one among those
    with the most seams (a flap whose sides are seams closes like a box lid)."""
    from ..mesh.geometry import face_areas

    area = face_areas(mesh.vertices, mesh.faces[faces])
    seams = np.bincount(seam_faces, minlength=mesh.n_faces)[faces]
    return int(faces[np.lexsort((-area, -seams))[0]])


def plan_build(mesh: Mesh, piece_part: list[int], piece_faces: list[np.ndarray], seams: list[Seam],
               mm_per_unit: float, max_seams: int = MAX_SEAMS_PER_STEP) -> BuildPlan:
    """The build order of the pieces (faces as whole-mesh face ids; every piece has faces) and
    seams (see the module docstring)."""
    n = len(piece_faces)
    size = {i: float(len(f)) for i, f in enumerate(piece_faces)}
    parts = sorted(set(piece_part))
    part_size = {p: sum(size[i] for i in range(n) if piece_part[i] == p) for p in parts}
    part_links = _counts((piece_part[s.pieces[0]], piece_part[s.pieces[1]]) for s in seams)
    part_order = _greedy(parts, part_size, part_links)
    piece_links = _counts(s.pieces for s in seams)
    piece_order = []
    for p in part_order:
        mine = [i for i in range(n) if piece_part[i] == p]
        piece_order += _greedy(mine, size, {k: v for k, v in piece_links.items() if k[0] in mine and k[1] in mine})
    rank = {piece: k for k, piece in enumerate(piece_order)}
    part_rank = {p: k for k, p in enumerate(part_order)}

    seam_faces = np.array([f for s in seams for f in s.faces], dtype=np.int64)
    lid = _lid(mesh, np.asarray(piece_faces[piece_order[-1]], dtype=np.int64), seam_faces)
    dist = face_distances(mesh, lid)
    far = np.array([min(dist[s.faces[0]], dist[s.faces[1]]) for s in seams]) if seams else np.zeros(0)

    # every seam to the step where both its sides are in the model
    buckets: dict[tuple, list[int]] = {}
    for k, s in enumerate(seams):
        a, b = s.pieces
        pa, pb = piece_part[a], piece_part[b]
        if pa == pb:
            key = ("piece", rank[max(a, b, key=rank.__getitem__)])
        else:
            key = ("join", part_rank[max(pa, pb, key=part_rank.__getitem__)])
        buckets.setdefault(key, []).append(k)

    def ordered(ids: list[int]) -> list[list[int]]:
        """The seams of one step in gluing order, as runs (a run is glued whole)."""
        runs: dict[str, list[int]] = {}
        for k in ids:
            runs.setdefault(seams[k].run, []).append(k)
        groups = list(runs.values())
        groups.sort(key=lambda g: (max(seams[k].meet for k in g), -min(far[k] for k in g), min(g)))
        return groups

    def chunks(groups: list[list[int]]) -> list[tuple[int, ...]]:
        out: list[list[int]] = [[]]
        for g in groups:
            if out[-1] and len(out[-1]) + len(g) > max_seams:
                out.append([])
            out[-1] += g
        return [tuple(c) for c in out]

    steps: list[dict] = []
    placed: list[int] = []
    for p in part_order:
        for piece in (i for i in piece_order if piece_part[i] == p):
            before = tuple(placed)
            placed.append(piece)
            for j, c in enumerate(chunks(ordered(buckets.get(("piece", rank[piece]), [])))):
                steps.append(dict(kind="piece" if j == 0 else "glue", part=p, piece=piece if j == 0 else None,
                                  seams=c, placed=tuple(placed), before=before))
        joins = buckets.get(("join", part_rank[p]), [])
        for c in chunks(ordered(joins)) if joins else []:
            steps.append(dict(kind="join", part=p, piece=None, seams=c, placed=tuple(placed), before=tuple(placed)))

    opening = opening_rims(mesh, piece_faces, seams, steps, mm_per_unit)
    out = []
    for st in steps:
        c = st["seams"]
        others = sorted({q for k in c for q in seams[k].pieces if q != st["piece"]}, key=rank.__getitem__)
        out.append(Step(kind=st["kind"], part=st["part"], piece=st["piece"], seams=c,
                        attach_to=tuple(q for q in others if (piece_part[q] != st["part"] if st["kind"] == "join"
                                                              else q in st["before"])),
                        placed=st["placed"], hard=tuple(k for k in c if opening[k] < REACH_MM)))
    return BuildPlan(steps=tuple(out), piece_order=tuple(piece_order), part_order=tuple(part_order), lid=lid,
                     opening_mm=opening)


def opening_rims(mesh: Mesh, piece_faces: list[np.ndarray], seams: list[Seam], steps: list[dict],
                 mm_per_unit: float) -> np.ndarray:
    """(S,) per seam, the rim (mm on paper) of the largest opening of the model just after it is
    glued in the build order (steps: dicts with the pieces placed and the seams glued, in order):
    the open edges (a side of a placed face whose other side is not placed, or a seam not glued
    yet, counted on both copies) chained into holes. A finger or a pencil reaches the inside
    through any hole, so the largest one counts; 0 once the model is closed."""
    from ..graphs import heaviest_component

    topo = mesh.topology
    edges, ef = topo.edges, topo.edge_faces
    length = np.linalg.norm(mesh.vertices[edges[:, 0]] - mesh.vertices[edges[:, 1]], axis=1) * mm_per_unit
    seam_edge = np.array([s.edge for s in seams], dtype=np.int64)
    is_seam = np.zeros(len(edges), dtype=bool)
    is_seam[seam_edge] = True
    face_piece = np.full(mesh.n_faces, -1, dtype=np.int64)
    for i, f in enumerate(piece_faces):
        face_piece[np.asarray(f, dtype=np.int64)] = i
    glued = np.zeros(len(edges), dtype=bool)
    placed_piece = np.zeros(len(piece_faces) + 1, dtype=bool)  # (the last slot: faces of no piece)
    rim = np.zeros(len(seams))
    for st in steps:
        placed_piece[list(st["placed"])] = True
        on = (ef >= 0) & placed_piece[np.where(ef >= 0, face_piece[np.maximum(ef, 0)], -1)]
        for k in st["seams"]:
            glued[seam_edge[k]] = True
            both = on[:, 0] & on[:, 1]
            mult = np.where(on[:, 0] ^ on[:, 1], 1, 0) + np.where(both & is_seam & ~glued, 2, 0)
            open_e = np.flatnonzero(mult > 0)
            if len(open_e) == 0:
                continue
            rim[k] = heaviest_component(mesh.n_vertices, edges[open_e, 0], edges[open_e, 1],
                                        length[open_e] * mult[open_e])
    return rim
