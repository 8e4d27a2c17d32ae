"""The assembly guide of a make folder: where each piece goes, the build steps, and how each
piece folds, as pictures and plain sentences; `formats.guide_pdf` and `pipeline.instructions`
write it out (guide.pdf, instructions.html).

In: the mesh as made, the pieces on their sheets and the seams (`fabricate.pieces.SheetPiece`,
`GlueEdge`), their pages, the folded pieces with their verified paths
(`pipeline.folding.FoldedPiece`) and the scale. Out: a `Guide`.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..fold.plan import path_at
from ..fold.tree import FoldTree, fold_positions
from ..mesh.mesh import Mesh
from . import pictures as P
from .motion import crease_done_frames, fold_stages, seam_meet_frame
from .order import BuildPlan, Seam, plan_build

OVERVIEW_PX = (300, 225)
PART_PX = (240, 180)
STEP_PX = (420, 315)
FRAME_PX = (200, 150)
CHOOSE_PX = (96, 72)  # pictures a step's view is chosen with
TRIES = 3  # views drawn part-built per step: the best ones for the whole model
FRAME_VIEW = (40.0, -30.0)  # elevation, azimuth of the folding pictures, the sheet's printed side up
LINEAR_FRACTIONS = (0.0, 1 / 3, 2 / 3, 1.0)


@dataclass(frozen=True, eq=False)
class Picture:
    """An image (H, W, 3) uint8 and what it shows (alt text); `shape`: (H, W). Its PNG
    (instructions.html) and JPEG (guide.pdf) are made when first asked for, or at once by
    `encoded` (where the picture is drawn: a guide's pictures drawn in forked processes come back
    encoded). Pickled once both are made, a Picture carries them instead of its pixels (the
    bunny's guide: 11 MB of pixels, 1 MB of files): `image` is None where it arrives."""

    image: np.ndarray | None
    caption: str

    @cached_property
    def shape(self) -> tuple[int, int]:
        return tuple(self.image.shape[:2])  # type: ignore[union-attr]

    @cached_property
    def png(self) -> bytes:
        from ..formats.png import png_bytes

        return png_bytes(self.image)

    @cached_property
    def jpeg(self) -> bytes:
        """The picture as a JPEG (quality 92: a PDF embeds it as it is, without re-encoding)."""
        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(self.image).save(buf, "JPEG", quality=92)
        return buf.getvalue()

    def encoded(self) -> Picture:
        """This picture, its shape, PNG and JPEG made."""
        self.shape, self.png, self.jpeg  # noqa: B018  (cached: made here)
        return self

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        if "png" in state and "jpeg" in state:
            state["image"] = None  # (every reader takes the files and the shape)
        return state


@dataclass(frozen=True, eq=False)
class GuideStep:
    """One step as a person reads it: its number and kind ("piece", "glue", "join"), a title,
    the instructions (plain sentences), one line per seam (or seam run) to glue, in order, notes
    after them (how to close the last seams), the picture of the model after it, the folding
    pictures of its piece (piece steps), and for checking: the glue labels of its seams, the new
    piece's name, the pieces it attaches to, the sheets it uses (the new piece's first) and the
    glue strips it uses."""

    number: int
    kind: str
    title: str
    lines: tuple[str, ...]
    glue: tuple[str, ...]
    notes: tuple[str, ...]
    picture: Picture
    folding: tuple[Picture, ...]
    labels: tuple[str, ...]
    piece: str | None
    attach_to: tuple[str, ...]
    sheets: tuple[int, ...]
    strips: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class Guide:
    """overview: the model from six sides, pieces lettered; parts: per part the same (empty for a
    model of one part); steps in order; the plan they come from; seconds it took."""

    overview: tuple[Picture, ...]
    parts: tuple[tuple[Picture, ...], ...]
    steps: tuple[GuideStep, ...]
    plan: BuildPlan
    seconds: float

    @property
    def pictures(self) -> int:
        """How many pictures it has (each embedded once in guide.pdf and in instructions.html)."""
        return len(self.overview) + sum(map(len, self.parts)) + sum(1 + len(s.folding) for s in self.steps)


def _seams(mesh: Mesh, pieces, glue, folded, scale: float) -> tuple[list[Seam], dict[int, dict]]:
    """The plan's seams of the sheets' glue pairs (meeting times from the pieces' paths), and per
    net piece its path facts (tree, done frames) for the folding pictures."""
    topo = mesh.topology
    # edges are in the order of their sorted vertex pairs, but a boundary edge is stored as its
    # face runs it (`mesh.edge_topology`): keys of the sorted pairs, or an open mesh's lookups miss
    lo, hi = np.sort(topo.edges, axis=1).T
    keys = lo * mesh.n_vertices + hi
    paths: dict[int, dict] = {}
    for i, fp in enumerate(folded):
        if fp.path is None or len(fp.path.frames) < 2:
            continue
        tree = FoldTree.from_pattern(fp.pattern)
        frames = np.asarray(fp.path.frames, dtype=np.float64)
        paths[i] = {"tree": tree, "frames": frames, "done": crease_done_frames(frames),
                    "face_of": {int(f): k for k, f in enumerate(fp.mesh_faces)}}
    out = []
    for g in glue:
        u, v = int(g.mesh_edge[0]), int(g.mesh_edge[1])
        e = int(np.searchsorted(keys, min(u, v) * mesh.n_vertices + max(u, v)))
        f0, f1 = (int(x) for x in topo.edge_faces[e])
        a, b = g.pieces
        ids_a = pieces[a].face_ids
        fa, fb = (f0, f1) if np.isin(f0, ids_a) and (a == b or not np.isin(f1, ids_a)) else (f1, f0)
        meet = 1.0
        if a == b and a in paths:
            p = paths[a]
            k = seam_meet_frame(p["tree"].parent, p["tree"].crease, p["done"], p["face_of"][fa], p["face_of"][fb])
            meet = k / (len(p["frames"]) - 1)
        length = float(np.linalg.norm(mesh.vertices[u] - mesh.vertices[v])) * scale
        out.append(Seam(pieces=(int(a), int(b)), faces=(fa, fb), mesh_edge=(u, v), edge=e, length_mm=length,
                        run=g.printed, meet=meet))
    return out, paths


def _piece_names(pieces, idx) -> str:
    names = [pieces[i].name for i in idx]
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _glue_line(g_rows: list, pieces, pages: list[int]) -> str:
    """The instruction for one seam or seam run (its GlueEdges)."""
    g = g_rows[0]
    label = g.printed
    what = f"run {label} ({len(g_rows)} edges)" if len(g_rows) > 1 else label
    a, b = g.pieces
    if g.tab_piece is None:
        return f"edge {what}: no tab; tape the two copies together from the inside"
    tab = pieces[g.tab_piece]
    if tab.name.startswith("S") and not len(tab.face_ids):
        return f"glue strip {tab.name} (sheet {pages[g.tab_piece] + 1}) behind both copies of edge {what}"
    other = b if g.tab_piece == a else a
    if a == b:
        return f"glue tab {what} under edge {what}"
    return f"glue tab {what} (on {tab.name}) under edge {what} of {pieces[other].name}"


# face x steps from which the guide's pictures are drawn in processes forked from this one
# (`processes.fork_map`): the bunny's 128 x 14 draw and encode in 0.27 s on one core, 0.15 s on
# two; a 1,280-face sphere's 1,280 x 76 in 1.1 s, half of it on each of two cores
PARALLEL_PICTURES = 1_000


def build_guide(mesh: Mesh, pieces, glue, pages: list[int], folded, scale: float) -> Guide:
    """The guide (see the module docstring). pieces: the sheets' pieces (net pieces first, in
    the order of `folded`, then glue strips); glue: the seams; pages: 0-based page per piece;
    scale: mm per model unit. The steps and their views are planned in order (a view changes
    only when it must); the pictures, which depend on their step alone, are then drawn (runs of
    steps seen from one view together: `_step_chunks`), from PARALLEL_PICTURES faces x steps in
    processes forked from this one."""
    from ..processes import fork_map, usable_cores

    t0 = time.perf_counter()
    n_net = len(folded)
    seams, paths = _seams(mesh, pieces, glue, folded, scale)
    piece_faces = [np.asarray(p.face_ids, dtype=np.int64) for p in pieces[:n_net]]
    plan = plan_build(mesh, [p.part for p in pieces[:n_net]], piece_faces, seams, scale)
    palette = P.piece_palette(n_net)
    face_piece = np.full(mesh.n_faces, -1, dtype=np.int64)
    for i, f in enumerate(piece_faces):
        face_piece[f] = i
    tris = mesh.vertices[mesh.faces]
    part_ids = sorted({p.part for p in pieces[:n_net]})
    rotations = P.corner_rotations(mesh.vertices[np.unique(mesh.faces)])
    cameras = [P.fit_camera(tris, rot, *CHOOSE_PX) for rot in rotations]  # (the same for every step)
    whole = _seen_from(tris, rotations, cameras)
    views, placed_faces = [], []
    view = 0
    for st in plan.steps:
        placed = np.flatnonzero(np.isin(face_piece, st.placed))
        focus = np.flatnonzero(face_piece == st.piece) if st.piece is not None else np.zeros(0, dtype=np.int64)
        seam_faces = np.array([f for k in st.seams for f in seams[k].faces], dtype=np.int64)
        view = _best_view(tris, placed, np.union1d(focus, seam_faces), rotations, cameras, whole, view)
        views.append(view)
        placed_faces.append(placed)

    def draw(item: tuple[str, int]):
        """One job of pictures: ("sides", -1) the model's, ("sides", k) part k's, ("steps", k) the
        pictures of the steps of chunks[k] and their instructions (with the folding pictures of
        their pieces); every picture encoded (`Picture.encoded`), on the core that drew it."""
        kind, k = item
        if kind == "sides" and k < 0:
            return tuple(p.encoded() for p in _sides(mesh, tris, np.arange(mesh.n_faces), face_piece, palette, pieces,
                                                     pages, OVERVIEW_PX, "the model"))
        if kind == "sides":
            inside = [i for i in range(n_net) if pieces[i].part == k]
            return tuple(p.encoded() for p in _sides(mesh, tris, np.flatnonzero(np.isin(face_piece, inside)),
                                                     face_piece, palette, pieces, pages, PART_PX, f"part {k + 1}"))
        group = chunks[k]  # ("steps", k): the steps of chunks[k], seen from one view
        pictures = _step_pictures(mesh, tris, [placed_faces[n] for n in group], face_piece, palette,
                                  [plan.steps[n] for n in group], seams, glue, rotations[views[group[0]]],
                                  [n + 1 for n in group])
        out = []
        for n, picture in zip(group, pictures):
            lines, notes, folding = _instructions(plan.steps[n], seams, pieces, pages, folded, paths, palette)
            out.append((picture.encoded(), (lines, notes, tuple(p.encoded() for p in folding))))
        return out

    chunks = _step_chunks(views, placed_faces)
    jobs = ([("sides", -1)] + ([("sides", k) for k in part_ids] if len(part_ids) > 1 else [])
            + [("steps", k) for k in range(len(chunks))])
    workers = usable_cores() if mesh.n_faces * len(plan.steps) >= PARALLEL_PICTURES else 1
    drawn = fork_map(draw, jobs, workers)
    overview, parts_pics = drawn[0], tuple(drawn[1:len(jobs) - len(chunks)])
    by_step = {n: one for group, got in zip(chunks, drawn[len(jobs) - len(chunks):]) for n, one in zip(group, got)}
    drawn = [by_step[n] for n in range(len(plan.steps))]
    runs: dict[str, list[int]] = {}
    for k, g in enumerate(glue):
        runs.setdefault(g.printed, []).append(k)
    steps = []
    for n, (st, (picture, (lines, notes, folding))) in enumerate(zip(plan.steps, drawn, strict=True)):
        done_runs, glue_lines, labels, strips = set(), [], [], []
        for k in st.seams:
            labels.append(glue[k].label)
            if glue[k].tab_piece is not None and glue[k].tab_piece >= n_net:
                strips.append(pieces[glue[k].tab_piece].name)
            if glue[k].printed in done_runs:
                continue
            done_runs.add(glue[k].printed)
            rows = [glue[j] for j in runs[glue[k].printed] if j in st.seams]
            glue_lines.append(_glue_line(rows, pieces, pages))
        used = ([st.piece] if st.piece is not None else []) + [glue[k].tab_piece for k in st.seams
                                                               if glue[k].tab_piece is not None
                                                               and glue[k].tab_piece >= n_net]
        sheets = list(dict.fromkeys(pages[i] + 1 for i in used))  # the new piece's sheet first
        if st.kind == "piece":
            title = f"Step {n + 1}: piece {pieces[st.piece].name} (sheet {pages[st.piece] + 1})"
        elif st.kind == "join":
            title = f"Step {n + 1}: join part {st.part + 1} to the model"
        else:
            title = f"Step {n + 1}: piece {pieces[st.placed[-1]].name}, more seams"
        steps.append(GuideStep(number=n + 1, kind=st.kind, title=title, lines=tuple(lines), glue=tuple(glue_lines),
                               notes=tuple(notes), picture=picture, folding=folding, labels=tuple(labels),
                               piece=pieces[st.piece].name if st.piece is not None else None,
                               attach_to=tuple(pieces[i].name for i in st.attach_to), sheets=tuple(sheets),
                               strips=tuple(strips)))
    return Guide(overview=overview, parts=parts_pics, steps=tuple(steps), plan=plan,
                 seconds=time.perf_counter() - t0)


# steps whose pictures one job draws at most (`_step_chunks`): their faces are drawn once for all of
# them, so more save drawing, fewer share the steps out between the two cores more evenly
STEP_CHUNK = 8


def _step_chunks(views: list[int], placed: list[np.ndarray]) -> list[list[int]]:
    """The steps in groups of at most STEP_CHUNK seen from one view, in order (the steps of a view
    need not follow one another: a model's steps turn between a dozen views), each step's placed
    faces holding the last's (`_step_pictures`); every step in one group."""
    out: list[list[int]] = []
    open_group: dict[int, list[int]] = {}  # view: its group being filled
    for k, view in enumerate(views):
        group = open_group.get(view)
        if group is None or len(group) >= STEP_CHUNK or not np.isin(placed[group[-1]], placed[k]).all():
            group = open_group[view] = []
            out.append(group)
        group.append(k)
    return out


def _sides(mesh: Mesh, tris: np.ndarray, faces: np.ndarray, face_piece: np.ndarray, palette: np.ndarray, pieces,
           pages: list[int], size: tuple[int, int], what: str) -> tuple[Picture, ...]:
    """`faces` from the six sides, every piece in its colour with its letter and sheet."""
    out = []
    rots = P.side_rotations(mesh.vertices[np.unique(mesh.faces)])
    sub = tris[faces]
    for name, rot in rots.items():
        cam = P.fit_camera(sub, rot, *size)
        img, ids, _ = P.draw_faces(cam, sub, palette[face_piece[faces]], None)
        region = np.where(ids >= 0, face_piece[faces][np.maximum(ids, 0)], -1)
        spots = P.label_spots(region, np.unique(face_piece[faces]), min_px=max(30, size[0] * size[1] // 600))
        texts = []
        for piece, (x, y, room) in spots.items():
            texts.append((x, y - 6, pieces[piece].name, 17, (0, 0, 0)))
            texts.append((x, y + 9, f"sheet {pages[piece] + 1}", 10, (40, 40, 40)))
        out.append(Picture(P.draw_texts(img, texts), f"{what} from the {name}"))
    return tuple(out)


def _seen_from(tris: np.ndarray, rotations: list, cameras: list) -> np.ndarray:
    """(R, F): pixels of every face seen from outside (its printed side) in a small picture of
    the whole model from each rotation (cameras: `fit_camera` of the model in each, CHOOSE_PX)."""
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    out = np.zeros((len(rotations), len(tris)))
    for k, rot in enumerate(rotations):
        ids, _ = P.face_ids(cameras[k], tris)
        seen = ids[ids >= 0]
        out[k] = np.bincount(seen, minlength=len(tris)) * (normal @ rot[2] > 0)
    return out


def _best_view(tris: np.ndarray, placed: np.ndarray, focus: np.ndarray, rotations: list, cameras: list,
               whole: np.ndarray, keep: int) -> int:
    """The rotation (index) that shows most of the `focus` faces of the part-built model from
    outside: the TRIES best for the whole model (`_seen_from`) drawn part-built, framed as the
    whole model is (`cameras`; ties: `keep`, the last step's, so the view changes only when it
    must)."""
    sub = tris[placed]
    want = np.isin(placed, focus)
    normal = np.cross(sub[:, 1] - sub[:, 0], sub[:, 2] - sub[:, 0])
    ranked = np.argsort(-whole[:, focus].sum(axis=1), kind="stable")[:TRIES]
    best, best_score = keep, -1
    for k in [keep] + [int(r) for r in ranked if r != keep]:
        ids, _ = P.face_ids(cameras[k], sub)
        seen = ids[ids >= 0]
        score = int((want[seen] & (normal[seen] @ rotations[k][2] > 0)).sum())
        if score > best_score * 1.15 or best_score < 0:  # a clearly better view, else the one we had
            best, best_score = k, score
    return best


def _step_pictures(mesh: Mesh, tris: np.ndarray, placed: list[np.ndarray], face_piece: np.ndarray,
                   palette: np.ndarray, steps: list, seams: list[Seam], glue, rotation: np.ndarray,
                   numbers: list[int]) -> list[Picture]:
    """`_step_picture` of steps (numbered `numbers`) seen from one `rotation` whose placed faces
    grow (each holding the last), their faces drawn once for all of them
    (`pictures.growing_face_ids`)."""
    cam = P.fit_camera(tris, rotation, *STEP_PX)
    return [_step_picture(mesh, tris, faces, face_piece, palette, st, seams, glue, cam, raster, number)
            for faces, st, raster, number in zip(placed, steps, P.growing_face_ids(cam, tris, placed), numbers)]


def _step_picture(mesh: Mesh, tris: np.ndarray, placed: np.ndarray, face_piece: np.ndarray, palette: np.ndarray,
                  st, seams: list[Seam], glue, cam, raster: tuple[np.ndarray, np.ndarray, np.ndarray],
                  number: int) -> Picture:
    """The model after a step: the new piece (or the pieces glued) in full colour, the rest
    lighter, the model still to come faint, this step's seams dark with their labels. cam: the
    step's camera (`fit_camera` of the whole model, STEP_PX); raster: the placed faces' ids and
    depths and the ghost's cover (`pictures.growing_face_ids`)."""
    involved = {st.piece} if st.piece is not None else {q for k in st.seams for q in seams[k].pieces}
    own = face_piece[placed]
    front = np.where(np.isin(own, list(involved))[:, None], palette[own], P.lighter(palette[own], 0.6))
    ids, zbuf, ghost = raster
    img = P.paint_faces(cam, tris[placed], front, np.full_like(front, P.INSIDE_RGB), ids, ghost)
    segs = np.array([mesh.vertices[list(seams[k].mesh_edge)] for k in st.seams]).reshape(-1, 2, 3)
    seen = P.draw_lines(img, cam, zbuf, segs, P.SEAM_RGB, width=3.0)
    texts, shown = [], set()
    for j, k in enumerate(st.seams):
        label = glue[k].printed
        if label in shown or seen[j] < 0.3:
            continue
        shown.add(label)
        (x, y), _ = cam.project(segs[j].mean(axis=0))
        texts.append((float(x), float(y), label, 13, (0, 0, 0)))
    caption = f"step {number}: the model after it" + (" (this step's seams drawn dark)" if st.seams else "")
    return Picture(P.draw_texts(img, texts), caption)


def _instructions(st, seams: list[Seam], pieces, pages: list[int], folded, paths: dict,
                  palette: np.ndarray) -> tuple[list[str], list[str], tuple[Picture, ...]]:
    """The sentences of a step before and after its glue list and, for a piece step, the
    pictures of its folding."""
    lines: list[str] = []
    notes: list[str] = []
    folding: tuple[Picture, ...] = ()
    if st.kind == "piece":
        name = pieces[st.piece].name
        fp = folded[st.piece]
        lines.append(f"Cut out piece {name} (sheet {pages[st.piece] + 1}) and score its fold lines.")
        if fp.path is None:
            why = fp.info.note or "folding paths were not planned: --no-fold"
            lines.append(f"Piece {name} has no verified folding path ({why}): fold it by eye, mountains away from "
                         "you and valleys towards you, to the shape in the picture.")
        elif len(folded[st.piece].net.mesh.faces) > 1:
            stages = fold_stages(paths[st.piece]["frames"]) if st.piece in paths else ()
            if fp.path.linear or len(stages) <= 1:
                lines.append("Fold all its creases together, a little at a time: mountains (red, dash-dot) away "
                             "from you, valleys (blue, dashed) towards you, as the pictures show.")
            else:
                lines.append(f"This piece does not fold in one motion (its verified path: {fp.path.planner}): "
                             f"close its creases in {len(stages)} stages, in the order of the pictures; the creases drawn thick "
                             "close in that stage, mountains red, valleys blue.")
            folding = _folding_pictures(fp, paths.get(st.piece), palette[st.piece], name, stages)
        if st.attach_to:
            lines.append(f"Then attach it to {_piece_names(pieces, st.attach_to)}.")
    elif st.kind == "join":
        lines.append(f"Part {st.part + 1} is built: glue it to {_piece_names(pieces, st.attach_to)}.")
    if st.seams:
        lines.append("Glue, in this order (each label is printed on both copies of its edge):")
    if st.hard:
        labels = list(dict.fromkeys(str(seams[k].run) for k in st.hard))
        notes.append(f"Seam{'s' if len(labels) > 1 else ''} {', '.join(labels)} close{'' if len(labels) > 1 else 's'} "
                     "the model: no finger fits inside to press {}. Put glue on the tab, close it and press the seam "
                     "from outside (a blunt pencil or a chopstick through the last opening helps); glue these last."
                     .format("their tabs" if len(labels) > 1 else "its tab"))
    return lines, notes, folding


def _folding_pictures(fp, facts: dict | None, color: np.ndarray, name: str, stages) -> tuple[Picture, ...]:
    """The piece along its verified path, from one direction (the printed side up; a stage picture
    turned a quarter at a time when that direction hides its creases, `_stage_view`), each picture
    filled by the piece: flat, a
    third, two thirds, folded for a straight path; flat and the end of each stage (the creases
    closing in it thick) for one that folds stage by stage."""
    if facts is None:
        return ()
    tree, frames = facts["tree"], facts["frames"]
    k_last = len(frames) - 1
    if fp.path.linear or len(stages) <= 1:
        shots = [(t, (), f"{name}: {round(100 * t)} % folded") for t in LINEAR_FRACTIONS]
    else:
        shots = [(0.0, (), f"{name}: flat")]
        shots += [(s.frame / k_last, s.creases, f"{name}: stage {j + 1}") for j, s in enumerate(stages)]
    poses = [fold_positions(tree, path_at(frames, t)) for t, _, _ in shots]
    from ..formats.raster import view_rotation

    rotation = view_rotation(*FRAME_VIEW, 2)
    front = np.repeat(np.asarray(color, dtype=np.uint8)[None], tree.n_faces, axis=0)
    back = np.full_like(front, P.INSIDE_RGB)
    # each net edge as a face's side: (face, corner, next corner)
    faces = fp.pattern.faces
    side = {}
    for f in range(len(faces)):
        for c in range(3):
            a, b = int(faces[f, c]), int(faces[f, (c + 1) % 3])
            side[(min(a, b), max(a, b))] = (f, c, (c + 1) % 3)
    goal = frames[-1]
    out = []
    for (t, creases, caption), pose in zip(shots, poses):
        lines = []  # (segments, colour) of the creases closing in this stage, mountains then valleys
        for want, rgb in ((True, P.MOUNTAIN_RGB), (False, P.VALLEY_RGB)):
            segs = []
            for e in creases:
                if (goal[e] > 0) == want:
                    u, v = (int(x) for x in fp.pattern.edges[e])
                    f, c0, c1 = side[(min(u, v), max(u, v))]
                    segs.append(pose[f, [c0, c1]])
            if segs:
                lines.append((np.array(segs), rgb))
        cam, img, zbuf, turned = _stage_view(pose, rotation, front, back, lines)
        for segs, rgb in lines:
            P.draw_lines(img, cam, zbuf, segs, rgb, width=3.0)
        out.append(Picture(img, caption + (" (turned to show its creases)" if turned else "")))
    return tuple(out)


def _stage_view(pose: np.ndarray, rotation: np.ndarray, front: np.ndarray, back: np.ndarray,
                lines: list) -> tuple:
    """(camera, picture of the faces, depth buffer, turned) for one folding picture: from the
    folding pictures' direction, each as large as it fits; when that hides most of the creases to
    draw (a stage's single crease behind the shape), turned about the vertical in quarter turns
    to the view that shows the most of them (turned: not the usual direction)."""
    from ..formats.raster import view_rotation

    best = None
    turns = (0.0, 90.0, 180.0, 270.0) if lines else (0.0,)
    for turn in turns:
        rot = rotation if turn == 0.0 else view_rotation(FRAME_VIEW[0], FRAME_VIEW[1] + turn, 2)
        cam = P.fit_camera(pose, rot, *FRAME_PX)  # a folded piece is small
        img, _ids, zbuf = P.draw_faces(cam, pose, front, back)
        if not lines:
            return cam, img, zbuf, False
        scratch = img.copy()
        seen = np.concatenate([P.draw_lines(scratch, cam, zbuf, segs, rgb, width=3.0) for segs, rgb in lines])
        lengths = np.concatenate([np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) for segs, _ in lines])
        score = float(seen @ lengths / max(lengths.sum(), 1e-300))  # the share of the creases' length seen
        if best is None or score > best[0] + 0.25:  # turn only for a much better view
            best = (score, cam, img, zbuf, turn != 0.0)
        if best[0] >= 0.75:
            break
    return best[1:]
