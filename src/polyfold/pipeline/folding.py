"""make's fold stage: a verified folding path for every piece.

A piece without a path in its time share is split in two (fewer faces always fold more easily)
and both halves are planned again, at most MAX_SPLITS times per piece. A path counts as found
only when the independent checker (`verify.paths`) accepts it as it will be written (FOLD
degrees) at the paper's thickness; one it rejects is treated as no path (split, or reported).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..deadline import Deadline
from ..errors import PolyfoldError
from ..fold.plan import FoldPath, plan_fold
from ..fold.tree import FoldTree, collides
from ..formats.fold import pattern_fold, with_path
from ..unfold.net import Net, balanced_cut, cut_creases, piece_net
from ..unfold.pattern import CreasePattern, crease_pattern
from .options import MakeOptions
from .parts import Part
from .report import FoldReport

FOLD_BUDGET_S = 3.0  # planning time per piece before it is split: this + per face
FOLD_BUDGET_PER_FACE_S = 0.03
MAX_SPLITS = 3  # halvings of one piece at most
# faces from which the pieces are planned side by side (`fold_pieces`): forked planners load the
# fold stage's kernels each (and the guide's process then again), which costs the 128-face bunny
# 0.13 s; from 300 faces it gains (make, wall: horse-302 4.7 -> 4.2 s, fish-472 3.9 -> 3.6 s,
# bunny-348 3.7 both ways, a 1,280-face sphere's fold stage 0.87 -> 0.54 s)
PARALLEL_FOLD_FACES = 300


@dataclass(frozen=True)
class PathInfo:
    """What the report says about a piece's path (`path` is whether one was found and verified)."""

    path: bool = False
    linear: bool | None = None
    planner: str | None = None
    seconds: float = 0.0
    frames: int = 0
    note: str = ""


@dataclass(frozen=True, eq=False)
class FoldedPiece:
    """One piece: its part, the part's faces (ids into the mesh), the piece as a single-piece net,
    its faces in the part (fids: ids into the part's faces), its crease pattern, its folding path
    (None when there is none or folding was not asked for) and the facts for the report."""

    part: int
    part_faces: np.ndarray
    net: Net
    fids: np.ndarray
    pattern: CreasePattern
    path: FoldPath | None
    info: PathInfo = field(default_factory=PathInfo)

    @property
    def mesh_faces(self) -> np.ndarray:
        """The piece's faces as ids into the whole mesh."""
        return self.part_faces[self.fids]


class _Planner:
    """The fold stage's state: pieces still to plan (for the time shares: `pending.value`, shared
    by the processes that plan pieces side by side), splits, results."""

    def __init__(self, opts: MakeOptions, deadline: Deadline, n_parts: int, pending,
                 say: Callable[[str, str], None], thickness: float, hard: Deadline) -> None:
        self.opts, self.deadline, self.n_parts, self.say = opts, deadline, n_parts, say
        self.hard = hard  # past it no piece is planned: OutOfTime
        self.thickness = thickness  # model units
        self.pending = pending
        self.splits = 0
        self.rejected = 0  # paths the independent check rejected
        self.results: list[FoldedPiece] = []

    def plan(self, pi: int, faces: np.ndarray, pnet: Net, fids: np.ndarray, depth: int) -> None:
        """Plan one single-piece net (fids: its faces in the part); split and recurse on failure."""
        opts = self.opts
        pattern = crease_pattern([pnet])
        path, info = None, PathInfo()
        if pnet.mesh.n_faces == 1:
            info = PathInfo(path=True, linear=True, planner="trivial", note="single face")
        elif opts.fold:
            self.hard.check(f"planning folding paths ({self.pending.value} pieces to go)")
            self.say("fold", f"part {pi + 1}/{self.n_parts}: planning a path for {pnet.mesh.n_faces} faces")
            tf = time.perf_counter()
            tree = FoldTree.from_pattern(pattern, opts.contact_tol).with_thickness(self.thickness)
            note = ""
            if collides(tree, tree.goal):
                note = "the folded shape itself intersects (input geometry); no path can exist"
            else:
                # a short budget, then split: two halves usually fold at once, while a hard
                # piece can eat the whole time limit
                share = max(0.5, min(self.deadline.left() / max(1, self.pending.value),
                                     FOLD_BUDGET_S + FOLD_BUDGET_PER_FACE_S * pnet.mesh.n_faces))
                impossible = ""  # why no path can exist for this piece (its faces clash at the goal)
                try:
                    path = plan_fold(tree, resolution_deg=opts.resolution_deg, time_limit=share, seed=opts.seed)
                except PolyfoldError as exc:
                    path, note = None, str(exc)
                    impossible = note
                if path is not None:
                    check = verify_written(pattern, path, opts, self.thickness)
                    if not check.ok:
                        self.rejected += 1
                        self.say("fold", f"the path failed the independent check ({check.why()})")
                        path, note = None, f"the planned path failed the independent check: {check.why()}"
                may_split = path is None and depth < MAX_SPLITS and self.deadline.left() > 0
                cut = balanced_cut(pnet, 0) if may_split else None  # None: one flat polygon, never cut
                if cut is not None:
                    self.say("fold", f"{impossible}: split the piece in two" if impossible
                             else f"no verified path in {share:.1f} s: split the piece in two")
                    self._split(pi, faces, pnet, fids, cut, depth)
                    return
                if path is None and not note:
                    note = "no path within the time limit"
                elif path is None and note.startswith("the planned path failed") and depth >= MAX_SPLITS:
                    note += f" (after {MAX_SPLITS} halvings)"
            seconds = time.perf_counter() - tf
            info = PathInfo(note=note, seconds=seconds) if path is None else PathInfo(
                path=True, linear=bool(path.linear), planner=path.planner, seconds=seconds, frames=len(path.frames))
        self.pending.value -= 1
        self.results.append(FoldedPiece(pi, faces, pnet, fids, pattern, path, info))

    def _split(self, pi: int, faces: np.ndarray, pnet: Net, fids: np.ndarray, cut: int, depth: int) -> None:
        halves = cut_creases(pnet, np.array([cut]))
        self.splits += 1
        self.pending.value += 1
        for h in range(2):
            sub, sub_fids = piece_net(halves, h)
            self.plan(pi, faces, sub, fids[sub_fids], depth + 1)


def plan_checked(fold: dict, tree: FoldTree, *, planner: str, resolution_deg: float, time_limit: float, seed: int,
                 contact_tol: float, thickness_rel: float) -> tuple[dict, FoldPath | None, str | None]:
    """`polyfold fold` and `unfold --fold`: plan a path for the FOLD net `fold` (its `tree`) at the
    material thickness (thickness_rel x the model size), then check it as written with the
    independent checker (`verify.paths`); a rejected path is planned once more at half the
    resolution. Returns (the FOLD dict with the path and polyfold:path_verified, the path, None)
    or (fold, None, why there is none). Raises PolyfoldError when no path can exist."""
    t0 = time.perf_counter()
    thickness = thickness_rel * tree.scale
    tree = tree.with_thickness(thickness)
    resolution, why = resolution_deg, None
    for attempt in range(2):
        left = time_limit - (time.perf_counter() - t0)
        if attempt and left <= 0:
            break
        path = plan_fold(tree, planner=planner, resolution_deg=resolution, time_limit=max(left, 0.5), seed=seed)
        if path is None:
            return fold, None, why or f"no folding path found in {time_limit:g} s with planner {planner}"
        written, check = _checked(fold, path, resolution_deg, contact_tol, thickness)
        if check.ok:
            return dict(written, **{"polyfold:path_verified": True}), path, None
        why = f"the planned path failed the independent check ({check.why()})"
        resolution /= 2
    return fold, None, why


def _checked(fold: dict, path: FoldPath, resolution_deg: float, contact_tol: float, thickness: float):
    """(the FOLD dict with the path as written, the independent check of it at `thickness`; a
    long path's halves side by side in two processes where there are two cores)."""
    from ..processes import beside, usable_cores
    from ..verify.paths import check_fold_path

    written = with_path(fold, path, resolution_deg, contact_tol, thickness)
    return written, check_fold_path(written, thickness=thickness,
                                    side_by_side=beside if usable_cores() > 1 else None)


def verify_written(pattern: CreasePattern, path: FoldPath, opts: MakeOptions, thickness: float):
    """The independent check of a piece's path as its FOLD file holds it (degrees, the goal frame
    as written), at `thickness` model units."""
    return _checked(pattern_fold(pattern), path, opts.resolution_deg, opts.contact_tol, thickness)[1]


def fold_pieces(parts: list[Part], opts: MakeOptions, deadline: Deadline, say: Callable[[str, str], None],
                mm_per_unit: float, hard: Deadline = Deadline.never()) -> tuple[list[FoldedPiece], FoldReport]:
    """Every piece of every part's net, with its folding path (see the module docstring), in the
    order of the parts and their pieces; the paper's thickness (opts.thickness mm) is
    mm_per_unit-scaled to model units. `deadline`: the searches' (each piece still gets half a
    second past it; a piece's share of what is left is divided by the pieces not yet planned,
    counted across the processes); past `hard` OutOfTime. With two or more cores the pieces are
    planned side by side in forked processes: a piece's path depends on that piece only."""
    from multiprocessing import RawValue

    from ..processes import fork_map, usable_cores

    t0 = time.perf_counter()
    jobs = [(pi, k) for pi, part in enumerate(parts) for k in range(part.net.n_pieces)]
    faces = sum(p.net.mesh.n_faces for p in parts)
    workers = usable_cores() if opts.fold and len(jobs) > 1 and faces >= PARALLEL_FOLD_FACES else 1
    if opts.fold:  # before any of the stage's work (make's `ready` hook waits here on a first run)
        say("fold", f"planning folding paths for {len(jobs)} piece{'s' * (len(jobs) != 1)}"
                    + (f" in {min(workers, len(jobs))} processes" if workers > 1 else ""))
    pending = RawValue("l", len(jobs))  # (shared with the forked planners)
    # pieces are planned side by side in processes forked from this one (`processes.fork_map`,
    # the largest first); their own messages stay there (a forked copy of a live status line
    # could wait forever on a lock its drawing thread held): the same paths as one by one, but
    # where a time share runs out
    quiet = say if workers == 1 else (lambda stage, message: None)

    def plan(job: tuple[int, int]) -> tuple[list[FoldedPiece], int, int]:
        pi, k = job
        planner = _Planner(opts, deadline, len(parts), pending, quiet, opts.thickness / mm_per_unit, hard)
        planner.plan(pi, parts[pi].faces, *piece_net(parts[pi].net, k), 0)
        return planner.results, planner.splits, planner.rejected

    sizes = [int(np.count_nonzero(parts[pi].net.piece == k)) for pi, k in jobs]
    order = sorted(range(len(jobs)), key=lambda j: -sizes[j])
    done = dict(zip(order, fork_map(plan, [jobs[j] for j in order], workers)))
    results = [fp for j in range(len(jobs)) for fp in done[j][0]]
    report = FoldReport(enabled=opts.fold, seconds=time.perf_counter() - t0,
                        splits_for_folding=sum(d[1] for d in done.values()),
                        verified=sum(r.info.path for r in results), pieces=len(results),
                        thickness_mm=opts.thickness, rejected_paths=sum(d[2] for d in done.values()))
    return results, report
