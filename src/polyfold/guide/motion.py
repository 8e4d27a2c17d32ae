"""What a person folding a piece needs from its verified folding path: when each crease reaches
its goal angle, in which stages the creases close, and when the two copies of a seam inside the
piece meet (only then can it be glued).

In: a path's frames (K, E) (fold angles per net edge, any angle convention; frames[-1] is the
goal) and the piece's crease tree (parent (F,) face, crease (F,) edge to it, -1 at the root:
`fold.tree.FoldTree`). A path is read as `fold.plan.path_at` reads it: frame k is at
fraction k / (K - 1) of the motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AT_GOAL_RAD = 1e-9  # a crease this close to its goal angle has reached it
MAX_STAGES = 5  # stages shown for a piece that folds crease group by crease group


def crease_done_frames(frames: np.ndarray) -> np.ndarray:
    """(E,) int: per edge the first frame index from which on it stays at its goal angle
    (frames[-1]); 0 for an edge that never moves (cuts, flat creases)."""
    frames = np.asarray(frames, dtype=np.float64)
    off = np.abs(frames - frames[-1]) > AT_GOAL_RAD  # (K, E)
    k = len(frames)
    last_off = np.where(off.any(axis=0), k - 1 - np.argmax(off[::-1], axis=0), -1)
    return (last_off + 1).astype(np.int64)


def seam_meet_frame(parent: np.ndarray, crease: np.ndarray, done: np.ndarray, face_a: int, face_b: int) -> int:
    """The frame from which on faces face_a and face_b of one piece keep their folded relative
    pose (so the seam between them has closed): the latest `done` frame of the creases on the
    tree path between them."""
    up_a = []
    f = face_a
    while f >= 0:
        up_a.append(f)
        f = int(parent[f])
    on_a = {f: i for i, f in enumerate(up_a)}
    latest = 0
    f = face_b
    while f >= 0 and f not in on_a:  # climb from b to the common ancestor
        latest = max(latest, int(done[crease[f]]))
        f = int(parent[f])
    for g in up_a[: on_a.get(f, len(up_a) - 1)]:  # and from a up to it (below the root: no crease)
        latest = max(latest, int(done[crease[g]]))
    return latest


@dataclass(frozen=True)
class FoldStage:
    """One stage of folding a piece: the path frame it ends at and the creases (edge ids) that
    reach their goal angle in it."""

    frame: int
    creases: tuple[int, ...]


def fold_stages(frames: np.ndarray, max_stages: int = MAX_STAGES) -> tuple[FoldStage, ...]:
    """The stages in which a path closes its creases: one per frame at which some crease reaches
    its goal for good, consecutive ones merged so that at most `max_stages` remain. A straight
    path (all creases together) is one stage."""
    done = crease_done_frames(frames)
    moving = np.flatnonzero(done > 0)
    ends = np.unique(done[moving])
    if len(ends) == 0:
        return ()
    groups = np.array_split(ends, min(max_stages, len(ends)))
    stages = []
    for g in groups:
        creases = moving[np.isin(done[moving], g)]
        stages.append(FoldStage(frame=int(g[-1]), creases=tuple(int(e) for e in np.sort(creases))))
    return tuple(stages)
