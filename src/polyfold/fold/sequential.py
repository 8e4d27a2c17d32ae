"""The sequential planner (ours, not the paper's): unfold the folded shape one crease at a time.

`plan_sequential` opens creases from the goal towards the flat net, each move checked by the
`ValidityChecker` at half the resolution as it goes, and reverses the sequence; when only a few
creases lock in the discrete domain, `rrt_connect` searches their continuous subspace.
"""

from __future__ import annotations

import math

import numpy as np

from ..deadline import Deadline

from .checker import ValidityChecker, shortcut
from .tree import FoldTree, crease_depth_size


# The sequential planner's continuous search over the creases it cannot open (`rrt_connect`):
RRT_MAX_DOF = 32  # stuck sets of up to this many creases get one
RRT_STEP_DEG = 15.0  # longest extension of a tree, per crease
RRT_MARGIN_DEG = 30.0  # a crease may overshoot its range [0, goal] by this much on either side
# A continuous search costs far more than a restart (a second, where a restart of a 382-face net
# takes 0.2-0.35 s and most take 0.01-0.1 s), and restarts alone unlock nearly every net: of the 184
# pieces that needed this planner in 96 makes (8 Loop-subdivided shared models at 800-2,500 faces,
# seeds 1-5) and bench_start's decimated bunny's 382-face piece, planned with seeds 1-3, 12 ever
# locked on a set of at most RRT_MAX_DOF creases; 11 of them fold without any search, in 0.08-3.3 s,
# while with a search at every such lock they took 0.08-15 s (the 382-face piece 6-15 s: nine 1 s
# searches that all failed, while its twelfth restart folds it). So a set the restarts meet for the
# first time is searched only from an allowance, RRT_SHARE of the work the restarts have done less
# that of the searches, at most RRT_FIRST, none under RRT_MIN; a set they lock on again (they go
# round in circles) gets RRT_FIRST, twice the last each further time, never more than half the
# time left. With that allowance in seconds (as it first was), the one piece that needs the search,
# the horse's 320-face one at 800 faces, folded in 1.8-7.6 s over two runs (a search at every lock:
# 1.9-9.9 s); the 12 pieces x 3 seeds and 7 whole-horse nets that use the search took 53-54 s in
# all (102 s).
# Work is counted in configurations checked (`ValidityChecker.configs`), not in seconds as it
# was: with seconds, whether a search found its path within its allowance depended on the
# machine's speed and load, and so did the path (and the random numbers the restarts drew after
# it). Those 19 nets x 3 seeds, planned twice on an idle machine, gave 12 of the 57 paths
# differently the second time; in work, 4 runs (one beside three busy processes, twice as slow)
# gave the same 57 paths. A search checks 20-135 thousand configurations a second on those nets
# (0.3-1.3 times the restarts' rate), so RRT_FIRST is about the second it was. The 57 plans take
# 36-37 s in all (seconds: 38-50 s, the slowest 3.8-12 s; now 3.6-3.7 s); of RRT_SHARE 0.075,
# 0.1, 0.15, 0.2 and 0.3 with RRT_FIRST 25,000-100,000, 0.15 and 0.2 with 50,000 were fastest
# (35.6-37.2 s, 0.2 within noise).
RRT_FIRST = 50_000
RRT_SHARE = 0.15
RRT_MIN = 1_000


def plan_sequential(tree: FoldTree, check: ValidityChecker, deadline: Deadline,
                    rng: np.random.Generator) -> tuple[np.ndarray, bool] | None:
    """Reverse sequential unfolding: (frames flat -> goal, continuous?), or None (stuck or out of time).

    Start at the folded goal and open one crease at a time (its angle to 0), always the first
    crease in priority order whose motion is collision-free; the path is that sequence reversed.
    Every frame stays in the paper's discrete domain (each crease flat or at its goal), so this is
    a path the Lazy PRM could also find, but found directly instead of by sampling 2^n states.
    Priority: creases splitting the net most evenly first (the largest smaller side), so a closed
    shape first opens into big halves that swing apart, and small flaps open last, when little is
    left in their way. When no remaining crease can open, start again from the goal with the
    stuck creases promoted to the front: opened early, while the shape around them is still
    folded, they usually swing out freely (a curled strip of faces, say, that would sweep through
    a flattened neighbour). Restarts alternate between two base orders (see `tracks`), each with
    its own promotions; a track stuck on the same creases again shuffles them (rng, so the seed
    decides). Restarts go on until the deadline.
    When a restart is stuck with at most RRT_MAX_DOF creases left closed, their continuous
    subspace is searched by `rrt_connect` from the stuck state to flat: some creases can open
    neither alone, nor first, nor together in the discrete domain (a tightly curled strip carrying
    a large flap, say) but can by partial, coordinated moves. Restarts are cheap and usually
    unlock the net, a search is costly: a set met for the first time is searched only within an
    allowance of work, configurations checked (RRT_SHARE of the restarts' less the searches'); a
    set the restarts lock on again gets RRT_FIRST, twice as much as the last each further time,
    never more than half the time left. Counted in work, not seconds, the path a seed gives is
    the same on every machine, however loaded, unless the deadline cuts the planning short.
    Such a path leaves the discrete domain in its first frames (`continuous?` is then True).
    Not in the paper: it finds paths for whole meshes (horse, fish) where the Lazy PRM finds none.
    """
    creases = tree.creases
    depth, size = crease_depth_size(tree)
    smaller_side = np.minimum(size, len(tree.order) - size)
    # Two tracks of restarts, taken in turn, each with its own base order and promotions: creases
    # splitting the net most evenly first (ties: shallower first), and the shallowest first (ties:
    # larger smaller side first), which unlocks some nets the first order cannot.
    tracks = [list(np.lexsort((depth, -smaller_side))), list(np.lexsort((-smaller_side, depth)))]
    tried: list[set[frozenset]] = [set(), set()]
    searched: dict[frozenset, int] = {}  # configurations given to each stuck set's last search
    restarts_work = searches_work = 0  # configurations the restarts, and the searches, have checked
    restart = 0
    while not deadline.expired():
        track = restart % 2
        prio = tracks[track]
        restart += 1
        done = check.configs
        opened = _open_in_order(tree, check, prio, deadline)
        restarts_work += check.configs - done
        if opened is None:
            return None
        frames, is_open = opened
        if is_open.all():
            frames.reverse()  # (plan_fold answers nets without creases before this runs)
            return np.stack(frames), False
        stuck = [i for i in prio if not is_open[i]]
        if deadline.expired():
            return None
        key = frozenset(stuck)
        if len(stuck) <= RRT_MAX_DOF:
            # Locked in the discrete domain, but only a few creases are left: search their
            # continuous subspace (see RRT_SHARE), longer each time the restarts lock on them again
            if key in tried[track]:
                work = searched[key] = 2 * searched.get(key, RRT_FIRST // 2)
            else:
                work = min(RRT_FIRST, int(RRT_SHARE * restarts_work) - searches_work)
            rest = None
            if work >= RRT_MIN:
                done = check.configs
                until = done + work
                rest = rrt_connect(check, frames[-1], creases[stuck],
                                   deadline.within(0.5 * deadline.left()).or_when(lambda end=until: check.configs >= end),
                                   rng)
                searches_work += check.configs - done
            if rest is not None:
                frames += rest
                frames.reverse()
                return np.stack(frames), True
        if key in tried[track]:
            rng.shuffle(stuck)
        tried[track].add(key)
        tracks[track] = stuck + [i for i in prio if is_open[i]]
    return None


def _open_in_order(tree: FoldTree, check: ValidityChecker, prio: list[int],
                   deadline: Deadline) -> tuple[list[np.ndarray], np.ndarray] | None:
    """One restart of `plan_sequential`: from the goal, open creases (indices into tree.creases)
    in priority order `prio` while one can move. Returns (frames goal -> last state, which creases
    are open), or None when time ran out in the middle of a scan."""
    creases = tree.creases
    n = len(creases)
    fine = check.step / 2
    q = tree.goal.copy()
    frames = [q]  # q is replaced, never changed in place
    is_open = np.zeros(n, dtype=bool)
    fails = np.zeros(n, dtype=np.int64)
    retry_at = np.zeros(n, dtype=np.int64)
    group, step = 1, 0
    while not is_open.all() and not deadline.expired():
        step += 1
        todo = [i for i in prio if not is_open[i]]
        # Open the next `group` creases in one motion when that is free (one check instead of
        # `group`: a segment costs its largest angle change, not its crease count); the group
        # doubles after each success, else one crease at a time: the first free one. A crease
        # that was blocked waits 2, 4, 8, ... steps before it is tried again (it is usually
        # still blocked); only when nothing else moves are the waiting ones tried at once.
        ready = [i for i in todo if retry_at[i] <= step]
        waiting = [i for i in todo if retry_at[i] > step]
        moves = [ready[:group]] if group > 1 and len(ready) > 1 else []
        moves += ([i] for i in ready + waiting)
        for move in moves:
            if deadline.expired():  # a scan of a large net can take a while
                return None
            nxt = q.copy()
            nxt[creases[move]] = 0.0
            # the new state itself first (as a sample of the motion), then the motion, at half
            # the resolution straight away: the path needs no re-validation
            if check.move(q, nxt, fine):
                is_open[move] = True
                q = nxt  # a fresh array: frames may keep it
                frames.append(q)
                group = min(2 * len(move), len(todo))
                break
            if len(move) == 1:
                fails[move[0]] += 1
                retry_at[move[0]] = step + (1 << min(int(fails[move[0]]), 6))
        else:
            break
    return frames, is_open


def rrt_connect(check: ValidityChecker, start: np.ndarray, moving: np.ndarray, deadline: Deadline,
                 rng: np.random.Generator) -> list[np.ndarray] | None:
    """Continuous path from the valid state `start` to `start` with the edges `moving` at 0, by
    RRT-Connect (Kuffner & LaValle 2000) in the subspace of those edges; None when out of time.

    Out: the frames after `start`, ending at the target, every move checked at half the
    resolution (as the sequential planner's own moves). Each moving edge ranges over [0, goal]
    widened by RRT_MARGIN_DEG (within [-pi, pi]); trees grow by at most RRT_STEP_DEG per edge
    (distances are max-norms: a segment's check costs its largest angle change). The joined
    path is shortened greedily (`shortcut`) at the same resolution.
    """
    fine = check.step / 2
    a = start[moving]
    lo = np.maximum(np.minimum(a, 0.0) - math.radians(RRT_MARGIN_DEG), -math.pi)
    hi = np.minimum(np.maximum(a, 0.0) + math.radians(RRT_MARGIN_DEG), math.pi)
    step = math.radians(RRT_STEP_DEG)

    def state(x: np.ndarray) -> np.ndarray:
        q = start.copy()
        q[moving] = x
        return q

    target = state(np.zeros(len(moving)))
    if not check.valid(target):
        return None
    # two trees (node angles of the moving edges, parent index); tree 0 grows from start
    nodes = [[a.copy()], [np.zeros(len(moving))]]
    parents = [[-1], [-1]]

    def extend(t: int, x: np.ndarray) -> tuple[int, bool]:
        """Grow tree t one step towards x: (new node or -1 when blocked, x reached?)."""
        pts = np.asarray(nodes[t])
        i = int(np.argmin(np.abs(pts - x).max(axis=1)))
        y = pts[i]
        d = float(np.abs(x - y).max())
        z = x if d <= step else y + (x - y) * (step / d)
        if not check.move(state(y), state(z), fine):
            return -1, False
        nodes[t].append(z)
        parents[t].append(i)
        return len(nodes[t]) - 1, d <= step

    def branch(t: int, i: int) -> list[np.ndarray]:
        out = []
        while i >= 0:
            out.append(nodes[t][i])
            i = parents[t][i]
        return out

    t = 0
    while not deadline.expired():
        k, _ = extend(t, lo + rng.random(len(moving)) * (hi - lo))
        if k >= 0:
            x = nodes[t][k]
            while not deadline.expired():  # connect: the other tree steps towards x
                j, reached = extend(1 - t, x)
                if j < 0:
                    break
                if reached:
                    ends = {t: k, 1 - t: j}
                    path = branch(0, ends[0])[::-1] + branch(1, ends[1])[1:]
                    return list(shortcut([state(p) for p in path], check, deadline, fine)[1:])
        t = 1 - t
    return None
