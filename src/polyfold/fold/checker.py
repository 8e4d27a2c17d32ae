"""The one validity checker of the folding planners: is a configuration, or a straight segment
between two configurations, free of self-intersection?

Every planner asks `ValidityChecker` only (the pattern of OMPL's StateValidityChecker and
MotionValidator): `valid(q)` for a configuration, `segment(qa, qb, step)` for the straight motion
between two, sampled every `step` radians (largest angle change) in bisection order, midpoints
first, so a blocked segment fails early. It counts what it checks, and remembers the last
collision it met (`last_hit`: the two faces, a planner's hint where a motion is blocked).

Underneath are numba kernels that planners may call inside their own loops: `segment_collides`
(all the samples of a segment in one call, reusing per-face work from one configuration to the
next, see `collision_work`), `config_collides` and its variants. A segment skips the pairs of
faces whose relative pose cannot change on it (rigid groups: faces joined through creases that do
not move), since both endpoints are valid.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..collide.sweep import fill_face_geometry, gather_boxes, largest_group, sort_by_lo_x, sweep_collides
from ..collide.tolerance import EXEMPT_REACH
from ..collide.triangles import GEO_SIZE
from ..deadline import Deadline
from ..jit import njit
from .kinematics import fold_faces

if TYPE_CHECKING:
    from .tree import FoldTree


@njit(cache=True)
def collision_work(n_faces):
    """Work arrays of `segment_collides` for one tree of n_faces faces, reused across calls:
    (geo, sb, si, last, R, T, out, meta, ids, thick).

    geo (F, GEO_SIZE): per-face geometry and AABB; sb (7, F): the AABBs (lo x, hi x, lo y, hi y,
    lo z, hi z) in sweep order and the running maximum of hi x; si (6, F) int: si[0] the sweep
    order (face ids by lo x; kept from call to call, it is the next call's starting guess), then
    per position parent, piece, rigid group, non-degenerate flag, and scratch for the candidates
    of one face; last (F, 2), R, T,
    out: the folded state of the previous call (see `kinematics.fold_faces`); meta (3,): the tol geo was filled
    with (NaN: geo not of out), then the face pair of the last collision found (`last_hit`). The state changes only the cost, never a verdict. ids (F, 6),
    thick (2,): the corners' net and mesh vertex ids and (thickness, reach) for the thickness test
    (`collide.sweep.sweep_collides`; thickness 0 here: `with_thickness` sets them).
    """
    si = np.empty((6, n_faces), dtype=np.int64)
    last = np.empty((n_faces, 2))
    meta = np.empty(3)
    for f in range(n_faces):  # (loops, not np.full: that takes seconds to compile)
        si[0, f] = f
        last[f, 0] = np.nan
    meta[0] = np.nan
    meta[1] = -1.0
    meta[2] = -1.0
    ids = np.empty((n_faces, 6), dtype=np.int64)
    ids[:] = -1
    return (np.empty((n_faces, GEO_SIZE)), np.empty((7, n_faces)), si, last,
            np.empty((n_faces, 3, 3)), np.empty((n_faces, 3)), np.empty((n_faces, 3, 3)), meta, ids, np.zeros(2))


@njit(cache=True)
def segment_collides(qa, qb, ks, m, order, parent, crease, axis, flat, piece, rigid, tol, work, q):
    """The planners' collision test, at the configurations q = qa + (k / m) (qb - qa) for k in ks,
    in that order (m = 0: q = qa; k = m: q = qb, bit for bit), up to the first that
    self-intersects: (collides, checked).

    Pairs with rigid[i] == rigid[j] >= 0 are not tested (see `config_collides_moving`; -1 for
    none). work: `collision_work(F)` of this tree, reused across calls: the faces and sweep order
    of the previous configuration are the starting point (work's out holds the last configuration
    folded). q (E,) scratch. All the samples of a segment in one call: a call between compiled
    functions updates the reference count of every array argument, which per configuration
    would cost a tenth of a small net's test.
    """
    geo, sb, si, last, R, T, out, meta, ids, thick = work
    if not (meta[0] == tol):
        last[:, 0] = np.nan  # geo rows of another tol: recompute every face
        meta[0] = tol
    big = largest_group(rigid, si[5])
    checked = 0
    for k in ks:
        if m == 0:
            for i in range(qa.shape[0]):  # (not q[:] = qa: an array assignment compiles numba's
                q[i] = qa[i]              # shape-mismatch error, 2-3 s of a first run)
        elif k == m:
            for i in range(qa.shape[0]):
                q[i] = qb[i]
        else:
            t = k / m
            for i in range(qa.shape[0]):
                q[i] = qa[i] + t * (qb[i] - qa[i])
        checked += 1
        fold_faces(q, order, parent, crease, axis, flat, R, T, out, last)
        fill_face_geometry(out, tol, geo, last)
        sort_by_lo_x(geo, sb, si)
        gather_boxes(geo, parent, piece, rigid, sb, si)
        key = sweep_collides(out, geo, sb, si, tol, big, ids, thick)
        if key >= 0:
            meta[1] = key // out.shape[0]
            meta[2] = key % out.shape[0]
            return True, checked
    return False, checked


@njit(cache=True)
def config_collides_cached(q, order, parent, crease, axis, flat, piece, rigid, tol, work):
    """`config_collides_moving` with the work arrays of `segment_collides` (rigid -1: no group)."""
    # np.int64(0), not 0: a literal would compile another specialization of segment_collides
    return segment_collides(q, q, np.zeros(1, dtype=np.int64), np.int64(0), order, parent, crease, axis, flat,
                            piece, rigid, tol, work, np.empty(q.shape[0]))[0]


def config_collides_moving(q, order, parent, crease, axis, flat, piece, rigid, tol, R, T, out) -> bool:
    """Like `config_collides`, but pairs with rigid[i] == rigid[j] >= 0 are not tested.

    Along a segment on which only some creases move, faces joined by non-moving creases keep
    their relative pose; if both endpoints are collision-free such pairs never collide, so a
    planner can label those rigid groups once per segment and skip them. (Plain Python over
    `config_collides_cached`: one compiled kernel fewer to build on a first run.)
    """
    work = collision_work(order.shape[0])
    hit = config_collides_cached(q, order, parent, crease, axis, flat, piece, rigid, tol, work)
    R[:] = work[4]
    T[:] = work[5]
    out[:] = work[6]
    return bool(hit)


def config_collides(q, order, parent, crease, axis, flat, piece, tol, R, T, out) -> bool:
    """forward_kinematics into (R, T, out), then the collision test: True if q self-intersects."""
    no_groups = np.full(order.shape[0], -1, dtype=np.int64)
    return config_collides_moving(q, order, parent, crease, axis, flat, piece, no_groups, tol, R, T, out)


@njit(cache=True)
def bisection_order(m: int) -> np.ndarray:
    """Interior sample indices 1..m-1, midpoints first (early rejection of bad segments)."""
    out = np.empty(max(m - 1, 0), dtype=np.int64)
    if m <= 1:
        return out
    lo = np.empty(2 * m, dtype=np.int64)
    hi = np.empty(2 * m, dtype=np.int64)
    lo[0], hi[0] = 0, m
    head, tail, k = 0, 1, 0
    while head < tail:
        a, b = lo[head], hi[head]
        head += 1
        if b - a < 2:
            continue
        mid = (a + b) // 2
        out[k] = mid
        k += 1
        lo[tail], hi[tail] = a, mid
        tail += 1
        lo[tail], hi[tail] = mid, b
        tail += 1
    return out[:k]


@njit(cache=True)
def segment_free(qa, qb, m, order, parent, crease, axis, flat, piece, tol, q, max_samples, work, end) -> tuple:
    """Check the straight segment qa -> qb at interior samples k/m (`ValidityChecker.segment`
    chooses m), and with `end` first qb itself.

    Samples go in bisection order; only the first `max_samples` are checked (a cheap coarse test
    when small; pass a huge number for the full check). qa is assumed valid, and qb unless `end`.
    q (E,) scratch; work: the tree's `collision_work` arrays. Returns (free, configurations checked).
    """
    # Rigid groups: faces joined through creases that do not move on this segment keep their
    # relative pose, and qa is valid, so pairs inside one group are skipped (at qb too: a move's
    # end costs a sample, where `ValidityChecker.valid` tests every pair).
    rigid = np.empty(order.shape[0], dtype=np.int64)
    for f in order:
        if parent[f] < 0 or qa[crease[f]] != qb[crease[f]]:
            rigid[f] = f
        else:
            rigid[f] = rigid[parent[f]]
    ks = bisection_order(m)[:max_samples]
    if end:
        first = np.empty(len(ks) + 1, dtype=np.int64)
        first[0] = m
        for i in range(len(ks)):  # (a loop: an array assignment compiles numba's shape-mismatch error)
            first[i + 1] = ks[i]
        ks = first
    hit, checked = segment_collides(qa, qb, ks, m, order, parent, crease, axis, flat, piece, rigid, tol, work, q)
    return not hit, checked


class ValidityChecker:
    """Collision queries on one tree with preallocated work arrays; counts what it does."""

    def __init__(self, tree: FoldTree, resolution: float):
        self.tree = tree
        self.step = resolution
        self.q = np.empty(len(tree.goal))
        self.work = collision_work(len(tree.order))
        if tree.thickness > 0:
            ids, thick = self.work[8], self.work[9]
            ids[:, :3] = tree.faces
            ids[:, 3:] = tree.mesh_faces
            thick[0], thick[1] = tree.thickness, EXEMPT_REACH * tree.thickness
        self.no_groups = np.full(len(tree.order), -1, dtype=np.int64)
        self.configs = 0
        self.edges = 0

    def valid(self, q: np.ndarray) -> bool:
        t = self.tree
        self.configs += 1
        return not config_collides_cached(q, t.order, t.parent, t.crease, t.axis, t.flat, t.piece, self.no_groups,
                                          t.tol, self.work)

    def valid_without_thickness(self, q: np.ndarray) -> bool:
        """`valid` of the zero-thickness test (crossing only), on this checker's work arrays: the
        goal, where faces meet along glued seams and at mesh vertices by design."""
        thick = self.work[9]
        kept = thick[0]
        thick[0] = 0.0
        try:
            return self.valid(q)
        finally:
            thick[0] = kept

    def last_hit(self) -> tuple[int, int] | None:
        """The two faces of the last collision a query met, or None when none has failed yet (a
        planner's hint where a motion is blocked)."""
        meta = self.work[7]
        return None if meta[1] < 0 else (int(meta[1]), int(meta[2]))

    def segment(self, qa: np.ndarray, qb: np.ndarray, step: float | None = None, max_samples: int = 1 << 40) -> bool:
        """The straight motion qa -> qb sampled every `step` radians at most (default: the
        resolution) at t = k / m, m a multiple of the resolution's own count ceil(span /
        resolution): a finer check always includes the samples of a check at the resolution, the
        ones the path is written and re-verified with (half the resolution by ceil(span / step)
        alone missed them: 29 samples where the resolution has 15, a collision at t = 1/3 unseen).
        Both ends are assumed valid."""
        return self._segment(qa, qb, step, max_samples, False)

    def move(self, qa: np.ndarray, qb: np.ndarray, step: float | None = None) -> bool:
        """`valid(qb)` and `segment(qa, qb, step)`, for a valid qa, in one call: qb is tested as a
        sample of the motion, skipping the pairs of faces the motion keeps in the same pose (a
        planner's step from a configuration it reached: in the sequential planner's restarts
        `valid` took 40 % of the time at 130-330 us a call, a sample takes 20-45 us)."""
        return self._segment(qa, qb, step, 1 << 40, True)

    def _segment(self, qa: np.ndarray, qb: np.ndarray, step: float | None, max_samples: int, end: bool) -> bool:
        t = self.tree
        self.edges += 1
        step = self.step if step is None else step
        base = math.ceil(float(np.max(np.abs(qb - qa), initial=0.0)) / self.step - 1e-9)
        m = max(base, 0) * max(1, math.ceil(self.step / step - 1e-9))
        free, n = segment_free(qa, qb, m, t.order, t.parent, t.crease, t.axis,
                               t.flat, t.piece, t.tol, self.q, max_samples, self.work, end)
        self.configs += n
        return bool(free)


def first_blocked_segment(check: ValidityChecker, frames: np.ndarray, step: float) -> int:
    """Index of the first segment that collides at `step`, or -1 if the whole path is free."""
    for i in range(len(frames) - 1):
        if not check.segment(frames[i], frames[i + 1], step):
            return i
    return -1


def shortcut(frames: list[np.ndarray], check: ValidityChecker, deadline: Deadline, step: float | None = None) -> np.ndarray:
    """Greedy shortcut: from each kept frame jump to the farthest later frame reachable directly
    (checked at `step`, default the checker's resolution); after the deadline, no more jumps."""
    out = [frames[0]]
    i = 0
    while i < len(frames) - 1:
        j = len(frames) - 1
        while j > i + 1 and (deadline.expired() or not check.segment(frames[i], frames[j], step)):
            j -= 1
        out.append(frames[j])
        i = j
    return np.stack(out)
