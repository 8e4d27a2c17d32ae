"""Continuous folding: a collision-free path from the flat net (all angles 0) to the folded shape.

In: a `FoldTree` (kinematics.py) built from a FOLD net. Out: a `FoldPath` — configurations q
(radians per FOLD edge, + = mountain) whose consecutive straight segments are collision-free when
sampled at `resolution` (ALGORITHMS.md 6.3-6.5).

Planners ("auto" runs them in this order):
1. linear: the straight line C_s -> C_g (bisection order, early exit) — the paper's LC test;
2. sequential: unfold the folded shape one crease at a time (not in the paper, see `_sequential`),
   with a continuous RRT-Connect search over the last few creases when they lock (the path is
   then reported as "sequential-rrt");
3. lazy-prm: Lazy PRM over discrete configurations (each crease either flat or at its goal angle)
   with Hamming-distance neighbours, lazily checked edges, A* search, and greedy shortcutting —
   the paper's planner (ALGORITHMS.md 6.5).
Every returned path is checked at half the resolution before it is reported (the sequential
planner checks each move at that resolution as it goes; the others re-validate the final path).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from .kinematics import FoldTree, collision_work, config_collides_cached, segment_collides

PLANNERS = ("auto", "linear", "sequential", "lazy-prm")
SEQUENTIAL_SHARE = 2 / 3  # of the time limit for the sequential planner when planner="auto"
COARSE_SAMPLES = 7  # bisection levels 1-3 of a segment: the cheap first look of the Lazy PRM
MAX_BATCH = 1600  # new roadmap samples per round at most (the batch doubles from n0 up to this)
# The sequential planner's continuous search over the creases it cannot open (`_rrt_connect`):
RRT_MAX_DOF = 32  # stuck sets of up to this many creases get one
RRT_STEP_DEG = 15.0  # longest extension of a tree, per crease
RRT_MARGIN_DEG = 30.0  # a crease may overshoot its range [0, goal] by this much on either side


@dataclass(frozen=True, eq=False)
class FoldPath:
    """frames (K, E): fold angles in radians per FOLD edge (+ = mountain), frames[0] = 0, frames[-1] = goal."""

    frames: np.ndarray
    linear: bool
    planner: str
    seconds: float
    edges_checked: int
    configs_checked: int
    nodes: int

    def degrees_fold(self) -> list[list[float]]:
        """The path in FOLD convention (degrees, valley positive) for `polyfold:path`."""
        return (-np.degrees(self.frames)).tolist()


@njit(cache=True)
def _bisection_order(m: int) -> np.ndarray:
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
def segment_free(qa, qb, step, order, parent, crease, axis, flat, piece, tol, q, max_samples, work) -> tuple:
    """Check the straight segment qa -> qb at interior samples k/m, m = ceil(max|qb - qa| / step).

    Samples go in bisection order; only the first `max_samples` are checked (a cheap coarse test
    when small; pass a huge number for the full check). Endpoints are assumed valid. q (E,)
    scratch; work: the tree's `collision_work` arrays. Returns (free, configurations checked).
    """
    span = 0.0
    for i in range(qa.shape[0]):
        span = max(span, abs(qb[i] - qa[i]))
    m = int(math.ceil(span / step - 1e-12))
    # Rigid groups: faces joined through creases that do not move on this segment keep their
    # relative pose, and both endpoints are valid, so pairs inside one group are skipped.
    rigid = np.empty(order.shape[0], dtype=np.int64)
    for f in order:
        if parent[f] < 0 or qa[crease[f]] != qb[crease[f]]:
            rigid[f] = f
        else:
            rigid[f] = rigid[parent[f]]
    hit, checked = segment_collides(qa, qb, _bisection_order(m)[:max_samples], m, order, parent, crease, axis, flat,
                                    piece, rigid, tol, work, q)
    return not hit, checked


class _Checker:
    """Collision queries on one tree with preallocated work arrays; counts what it does."""

    def __init__(self, tree: FoldTree, resolution: float):
        self.tree = tree
        self.step = resolution
        self.q = np.empty(len(tree.goal))
        self.work = collision_work(len(tree.order))
        self.no_groups = np.full(len(tree.order), -1, dtype=np.int64)
        self.configs = 0
        self.edges = 0

    def valid(self, q: np.ndarray) -> bool:
        t = self.tree
        self.configs += 1
        return not config_collides_cached(q, t.order, t.parent, t.crease, t.axis, t.flat, t.piece, self.no_groups,
                                          t.tol, self.work)

    def segment(self, qa: np.ndarray, qb: np.ndarray, step: float | None = None, max_samples: int = 1 << 40) -> bool:
        t = self.tree
        self.edges += 1
        free, n = segment_free(qa, qb, self.step if step is None else step, t.order, t.parent, t.crease, t.axis,
                               t.flat, t.piece, t.tol, self.q, max_samples, self.work)
        self.configs += n
        return bool(free)


def _path_free(check: _Checker, frames: np.ndarray, step: float) -> int:
    """Index of the first segment that collides at `step`, or -1 if the whole path is free."""
    for i in range(len(frames) - 1):
        if not check.segment(frames[i], frames[i + 1], step):
            return i
    return -1


def is_linearly_foldable(tree: FoldTree, resolution_deg: float = 1.0) -> bool:
    """True if the straight segment flat -> goal is collision-free at the resolution (and at half of it)."""
    check = _Checker(tree, math.radians(resolution_deg))
    zero = np.zeros(len(tree.goal))
    if not check.valid(zero) or not check.valid(tree.goal):
        return False
    return check.segment(zero, tree.goal, check.step / 2)  # half the resolution covers the full one


def plan_fold(
    tree: FoldTree,
    planner: str = "auto",
    resolution_deg: float = 1.0,
    time_limit: float = 60.0,
    seed: int = 0,
    n0: int = 100,
    k_neighbours: int = 10,
) -> FoldPath | None:
    """Plan a collision-free folding path; None when none is found within `time_limit`.

    planner: "linear" (straight line only), "sequential" (crease-by-crease unfolding of the goal
    only), "lazy-prm" (Lazy PRM only, as the paper after its LC test), "auto" (straight line,
    then sequential, then Lazy PRM for the time left). Raises PolyfoldError when the flat net or
    the goal itself self-intersects (then no path can exist).
    """
    from .errors import PolyfoldError

    if planner not in PLANNERS:
        raise ValueError(f"unknown planner {planner!r}")
    t0 = time.perf_counter()
    deadline = t0 + time_limit
    check = _Checker(tree, math.radians(resolution_deg))
    zero = np.zeros(len(tree.goal))
    goal = tree.goal.copy()
    if not check.valid(zero):
        raise PolyfoldError("the flat net overlaps itself: not a valid net")
    if not check.valid(goal):
        from .kinematics import colliding_pairs

        pairs = colliding_pairs(tree, goal)
        raise PolyfoldError(
            f"the folded goal shape intersects itself (net faces {pairs[0, 0]} and {pairs[0, 1]} cross, "
            f"{len(pairs)} pair{'s' if len(pairs) != 1 else ''} in all, beyond the contact tolerance "
            f"{tree.tol / tree.scale:.0e} of the model size): no folding path can exist; if that is within "
            f"the paper's thickness, raise --contact-tol")

    def done(frames: np.ndarray, linear: bool, name: str, nodes: int) -> FoldPath:
        return FoldPath(frames=frames, linear=linear, planner=name, seconds=time.perf_counter() - t0,
                        edges_checked=check.edges, configs_checked=check.configs, nodes=nodes)

    if len(tree.creases) == 0:  # single faces (no DOF): the flat net is the goal, whatever the planner
        return done(np.stack([zero, goal]), True, "linear", 2)
    if planner in ("auto", "linear"):
        straight = np.stack([zero, goal])
        # at half the resolution at once (its samples include the full-resolution ones; a blocked
        # line fails as early, at its first bisection samples)
        if _path_free(check, straight, check.step / 2) < 0:
            return done(straight, True, "linear", 2)
        if planner == "linear":
            return None
    if planner in ("auto", "sequential"):
        # auto: the Lazy PRM keeps a third of the time for the rare net the sequential planner
        # cannot unlock (it finds nothing on large nets, but may on a small one)
        seq_deadline = deadline if planner == "sequential" else t0 + time_limit * SEQUENTIAL_SHARE
        found = _sequential(tree, check, seq_deadline, np.random.default_rng(seed))
        if found is not None:
            frames, continuous = found
            return done(frames, False, "sequential-rrt" if continuous else "sequential", len(frames))
        if planner == "sequential":
            return None
    result = _lazy_prm(tree, check, deadline, np.random.default_rng(seed), n0, k_neighbours)
    if result is None:
        return None
    frames, nodes = result
    return done(frames, len(frames) == 2, "lazy-prm", nodes)


@njit(cache=True)
def _astar(indptr, nbr, eid, weight, blocked, h, start, goal):
    """A* on the roadmap (CSR; edges with blocked[e] skipped). Returns the node path or empty."""
    n = indptr.shape[0] - 1
    g = np.full(n, np.inf)
    prev = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    cap = nbr.shape[0] + 1
    hk = np.empty(cap)
    hn = np.empty(cap, dtype=np.int64)
    size = 0
    g[start] = 0.0
    hk[0] = h[start]
    hn[0] = start
    size = 1
    while size > 0:
        # pop min
        u = hn[0]
        size -= 1
        hk[0] = hk[size]
        hn[0] = hn[size]
        i = 0
        while True:
            c = 2 * i + 1
            if c >= size:
                break
            if c + 1 < size and hk[c + 1] < hk[c]:
                c += 1
            if hk[i] <= hk[c]:
                break
            hk[i], hk[c] = hk[c], hk[i]
            hn[i], hn[c] = hn[c], hn[i]
            i = c
        if closed[u]:
            continue
        if u == goal:
            length = 1
            x = u
            while prev[x] >= 0:
                x = prev[x]
                length += 1
            path = np.empty(length, dtype=np.int64)
            x = u
            for m in range(length - 1, -1, -1):
                path[m] = x
                x = prev[x]
            return path
        closed[u] = True
        for k in range(indptr[u], indptr[u + 1]):
            if blocked[eid[k]]:
                continue
            v = nbr[k]
            ng = g[u] + weight[eid[k]]
            if ng < g[v]:
                g[v] = ng
                prev[v] = u
                if size >= cap:
                    continue
                i = size
                hk[i] = ng + h[v]
                hn[i] = v
                size += 1
                while i > 0:
                    par = (i - 1) >> 1
                    if hk[par] <= hk[i]:
                        break
                    hk[par], hk[i] = hk[i], hk[par]
                    hn[par], hn[i] = hn[i], hn[par]
                    i = par
    return np.empty(0, dtype=np.int64)


class _Roadmap:
    """Nodes (bit vectors) and lazily checked edges; CSR adjacency rebuilt when nodes are added."""

    UNKNOWN, COARSE_OK, FREE, BLOCKED = 0, 1, 2, 3

    def __init__(self, n_bits: int, weight_scale: np.ndarray):
        self.bits: list[np.ndarray] = []
        self.weight_scale = weight_scale
        self.n_bits = n_bits
        self.edge_id: dict[tuple[int, int], int] = {}
        self.eu: list[int] = []
        self.ev: list[int] = []
        self.ew: list[float] = []
        self.state = np.zeros(0, dtype=np.int8)

    def add_nodes(self, new: list[np.ndarray], k: int) -> None:
        first = len(self.bits)
        self.bits.extend(new)
        B = np.array(self.bits)
        W = B * self.weight_scale
        all_rows = np.arange(first, len(self.bits))
        Bf = B.astype(np.float32)
        kk = min(k, len(self.bits) - 1)
        found = []
        # Hamming distances by matrix products, a block of new nodes at a time (memory stays
        # ~block x nodes floats however large the roadmap grows).
        block = max(1, 4_000_000 // max(len(self.bits), 1))
        for start in range(0, len(all_rows), block):
            rows = all_rows[start:start + block]
            ham = Bf[rows] @ (1.0 - Bf).T + (1.0 - Bf[rows]) @ Bf.T  # (block, all)
            ham = np.rint(ham).astype(np.int64)
            ham[np.arange(len(rows)), rows] = self.n_bits + 1
            nearest = np.argpartition(ham, kk - 1, axis=1)[:, :kk] if kk > 0 else np.empty((len(rows), 0), np.int64)
            r_near, c_near = np.repeat(np.arange(len(rows)), kk), nearest.ravel()
            r_one, c_one = np.nonzero(ham == 1)  # every neighbour at Hamming distance 1
            r = np.concatenate([r_near, r_one])
            c = np.concatenate([c_near, c_one])
            keep = ham[r, c] <= self.n_bits
            found.append(np.stack([rows[r[keep]], c[keep]], axis=1))
        if found:
            ij = np.concatenate(found)
            i, j = ij[:, 0], ij[:, 1]
            keys = np.unique(np.stack([np.minimum(i, j), np.maximum(i, j)], axis=1), axis=0)
            keys = keys[keys[:, 0] != keys[:, 1]]
            weights = np.linalg.norm(W[keys[:, 0]] - W[keys[:, 1]], axis=1)  # Euclidean distance of the q's
            for (a, b), w in zip(keys.tolist(), weights.tolist()):
                if (a, b) not in self.edge_id:
                    self.edge_id[(a, b)] = len(self.eu)
                    self.eu.append(a)
                    self.ev.append(b)
                    self.ew.append(w)
        state = np.zeros(len(self.eu), dtype=np.int8)
        state[: len(self.state)] = self.state
        self.state = state
        eu, ev = np.array(self.eu, dtype=np.int64), np.array(self.ev, dtype=np.int64)
        src = np.concatenate([eu, ev])
        dst = np.concatenate([ev, eu])
        ids = np.concatenate([np.arange(len(eu)), np.arange(len(eu))])
        order = np.argsort(src, kind="stable")
        self.indptr = np.searchsorted(src[order], np.arange(len(self.bits) + 1)).astype(np.int64)
        self.nbr = dst[order]
        self.eid = ids[order]
        self.weight = np.array(self.ew)
        goal = self.bits[1] * self.weight_scale
        self.h = np.linalg.norm(W - goal, axis=1)

    def shortest_path(self) -> np.ndarray:
        return _astar(self.indptr, self.nbr, self.eid, self.weight, self.state == self.BLOCKED, self.h, 0, 1)


def _crease_depth_size(tree: FoldTree) -> tuple[np.ndarray, np.ndarray]:
    """Per crease of tree.creases: depth of its child face in the tree, faces in the child's subtree."""
    n_f = len(tree.order)
    depth = np.zeros(n_f, dtype=np.int64)
    size = np.ones(n_f, dtype=np.int64)
    for f in tree.order:
        if tree.parent[f] >= 0:
            depth[f] = depth[tree.parent[f]] + 1
    for f in tree.order[::-1]:
        if tree.parent[f] >= 0:
            size[tree.parent[f]] += size[f]
    child = np.full(len(tree.goal), -1, dtype=np.int64)
    has = tree.crease >= 0
    child[tree.crease[has]] = np.flatnonzero(has)
    kids = child[tree.creases]
    return depth[kids], size[kids]


def _ordered_states(tree: FoldTree, levels: int = 8) -> list[np.ndarray]:
    """Discrete states (bits per crease of tree.creases) folding the outer part of the tree first
    or last: thresholds on the depth and on the subtree size of each crease's child face."""
    depth, size = _crease_depth_size(tree)
    states = []
    for key in (depth, -size):
        for thr in np.unique(np.quantile(key, np.linspace(0, 1, levels + 2)[1:-1], method="nearest")):
            outer = key >= thr
            states.extend([outer, ~outer])
    return states


def _sequential(tree: FoldTree, check: _Checker, deadline: float, rng: np.random.Generator) -> tuple[np.ndarray, bool] | None:
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
    When a restart is stuck with at most RRT_MAX_DOF creases left closed (a set not searched
    before), their continuous subspace is searched by `_rrt_connect` from the stuck state to
    flat: some creases can open neither alone, nor first, nor together in the discrete domain
    (a tightly curled strip carrying a large flap, say) but can by partial, coordinated moves.
    Such a path leaves the discrete domain in its first frames (`continuous?` is then True).
    Not in the paper: it finds paths for whole meshes (horse, fish) where the Lazy PRM finds none.
    """
    creases, goal = tree.creases, tree.goal
    n = len(creases)
    depth, size = _crease_depth_size(tree)
    smaller_side = np.minimum(size, len(tree.order) - size)
    # Two tracks of restarts, taken in turn, each with its own base order and promotions: creases
    # splitting the net most evenly first (ties: shallower first), and the shallowest first (ties:
    # larger smaller side first), which unlocks some nets the first order cannot.
    tracks = [list(np.lexsort((depth, -smaller_side))), list(np.lexsort((-smaller_side, depth)))]
    tried: list[set[frozenset]] = [set(), set()]
    searched: set[frozenset] = set()  # stuck sets given to the continuous search already
    fine = check.step / 2
    restart = 0
    while time.perf_counter() < deadline:
        track = restart % 2
        prio = tracks[track]
        restart += 1
        q = goal.copy()
        frames = [q]  # q is replaced, never changed in place
        is_open = np.zeros(n, dtype=bool)
        fails = np.zeros(n, dtype=np.int64)
        retry_at = np.zeros(n, dtype=np.int64)
        group, step = 1, 0
        while not is_open.all() and time.perf_counter() < deadline:
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
                if time.perf_counter() >= deadline:  # a scan of a large net can take a while
                    return None
                nxt = q.copy()
                nxt[creases[move]] = 0.0
                # the new state itself first (segments assume valid endpoints), then the motion,
                # at half the resolution straight away: the path needs no re-validation
                if check.valid(nxt) and check.segment(q, nxt, fine):
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
        if is_open.all():
            frames.reverse()  # (plan_fold answers nets without creases before this runs)
            return np.stack(frames), False
        stuck = [i for i in prio if not is_open[i]]
        if time.perf_counter() >= deadline:
            return None
        key = frozenset(stuck)
        if len(stuck) <= RRT_MAX_DOF and key not in searched:
            # Locked in the discrete domain, but only a few creases are left: search their
            # continuous subspace (once per stuck set, with half the time left).
            searched.add(key)
            sub_deadline = min(deadline, time.perf_counter() + 0.5 * (deadline - time.perf_counter()))
            rest = _rrt_connect(check, q, creases[stuck], sub_deadline, rng)
            if rest is not None:
                frames += rest
                frames.reverse()
                return np.stack(frames), True
        if key in tried[track]:
            rng.shuffle(stuck)
        tried[track].add(key)
        tracks[track] = stuck + [i for i in prio if is_open[i]]
    return None


def _rrt_connect(check: _Checker, start: np.ndarray, moving: np.ndarray, deadline: float,
                 rng: np.random.Generator) -> list[np.ndarray] | None:
    """Continuous path from the valid state `start` to `start` with the edges `moving` at 0, by
    RRT-Connect (Kuffner & LaValle 2000) in the subspace of those edges; None when out of time.

    Out: the frames after `start`, ending at the target, every move checked at half the
    resolution (as the sequential planner's own moves). Each moving edge ranges over [0, goal]
    widened by RRT_MARGIN_DEG (within [-pi, pi]); trees grow by at most RRT_STEP_DEG per edge
    (distances are max-norms: a segment's check costs its largest angle change). The joined
    path is shortened greedily (`_shortcut`) at the same resolution.
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
        if not check.valid(state(z)) or not check.segment(state(y), state(z), fine):
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
    while time.perf_counter() < deadline:
        k, _ = extend(t, lo + rng.random(len(moving)) * (hi - lo))
        if k >= 0:
            x = nodes[t][k]
            while time.perf_counter() < deadline:  # connect: the other tree steps towards x
                j, reached = extend(1 - t, x)
                if j < 0:
                    break
                if reached:
                    ends = {t: k, 1 - t: j}
                    path = branch(0, ends[0])[::-1] + branch(1, ends[1])[1:]
                    return list(_shortcut([state(p) for p in path], check, deadline, fine)[1:])
        t = 1 - t
    return None


def _lazy_prm(tree: FoldTree, check: _Checker, deadline: float, rng: np.random.Generator, n0: int, k: int):
    """Lazy PRM over discrete configurations b in {0,1}^n, q = b * goal (ALGORITHMS.md 6.5).

    Node 0 is the flat net, node 1 the goal. Edges are checked only when A* puts them on a
    candidate path: first a coarse look at every edge of the path (the first bisection samples),
    then the full check; blocked edges are dropped and A* runs again. More samples (doubling
    batches) when the start and goal are disconnected.
    """
    creases = tree.creases
    n = len(creases)
    goal_c = tree.goal[creases]

    def config(bits: np.ndarray) -> np.ndarray:
        q = np.zeros(len(tree.goal))
        q[creases] = bits * goal_c
        return q

    rm = _Roadmap(n, np.abs(goal_c))
    seen = set()
    start_bits, goal_bits = np.zeros(n, dtype=bool), np.ones(n, dtype=bool)
    seen.update((start_bits.tobytes(), goal_bits.tobytes()))
    rm.add_nodes([start_bits, goal_bits], k)
    # Natural folding orders as extra nodes: fold the outer branches first (by tree depth or by
    # subtree size), or the inner ones first. Cheap, and they often give a 3-frame path at once.
    seeded = []
    for b in _ordered_states(tree):
        key = b.tobytes()
        if key not in seen:
            seen.add(key)
            if check.valid(config(b)):
                seeded.append(b)
    rm.add_nodes(seeded, k)

    def check_edge(e: int, coarse: bool) -> bool:
        st = rm.state[e]
        if st == rm.BLOCKED:
            return False
        if st == rm.FREE or (coarse and st == rm.COARSE_OK):
            return True
        qa, qb = config(rm.bits[rm.eu[e]]), config(rm.bits[rm.ev[e]])
        ok = check.segment(qa, qb, max_samples=COARSE_SAMPLES) if coarse else check.segment(qa, qb)
        rm.state[e] = (rm.COARSE_OK if coarse else rm.FREE) if ok else rm.BLOCKED
        return ok

    batch = n0
    while time.perf_counter() < deadline:
        new = []
        tries = 0
        while len(new) < batch and tries < 20 * batch and time.perf_counter() < deadline:
            tries += 1
            b = rng.random(n) < rng.random()  # Hamming level p ~ U(0, 1), then bits ~ Bernoulli(p)
            key = b.tobytes()
            if key in seen:
                continue
            seen.add(key)
            if check.valid(config(b)):
                new.append(b)
        rm.add_nodes(new, k)
        while time.perf_counter() < deadline:
            path = rm.shortest_path()
            if len(path) == 0:
                break
            edges = [rm.edge_id[(min(a, b), max(a, b))] for a, b in zip(path[:-1].tolist(), path[1:].tolist())]
            # Coarse pass over every edge of the path first: most blocked edges show up within a
            # few samples, and dropping all of them at once saves A* runs and full checks of edges
            # on paths that are blocked elsewhere anyway.
            if not all([check_edge(e, True) for e in edges]):
                continue
            if not all(check_edge(e, False) for e in edges):
                continue
            raw = np.stack([config(rm.bits[i]) for i in path.tolist()])
            frames = _shortcut(list(raw), check, deadline)
            if _path_free(check, frames, check.step / 2) < 0:  # re-validate at half the resolution
                return frames, len(rm.bits)
            if _path_free(check, raw, check.step / 2) < 0:  # only a shortcut failed the finer check
                return raw, len(rm.bits)
            # Some roadmap edge fails only the finer check: block the ones that do.
            for e in edges:
                if not check.segment(config(rm.bits[rm.eu[e]]), config(rm.bits[rm.ev[e]]), check.step / 2):
                    rm.state[e] = rm.BLOCKED
        batch = min(2 * batch, MAX_BATCH)
    return None


def _shortcut(frames: list[np.ndarray], check: _Checker, deadline: float, step: float | None = None) -> np.ndarray:
    """Greedy shortcut: from each kept frame jump to the farthest later frame reachable directly
    (checked at `step`, default the checker's resolution); after the deadline, no more jumps."""
    out = [frames[0]]
    i = 0
    while i < len(frames) - 1:
        j = len(frames) - 1
        while j > i + 1 and (time.perf_counter() >= deadline or not check.segment(frames[i], frames[j], step)):
            j -= 1
        out.append(frames[j])
        i = j
    return np.stack(out)


def sample_ratio(tree: FoldTree, samples: int = 1000, strategy: str = "discrete", seed: int = 0) -> tuple[int, int]:
    """Valid configuration ratio of ALGORITHMS.md 6.6: (valid, sampled).

    discrete: each crease flat or at its goal, i.i.d. Bernoulli(1/2); continuous: each crease
    uniform between 0 and its goal angle; continuous-full: each crease uniform in (-pi, pi), the
    whole configuration space (ALGORITHMS.md 6.4 names both continuous variants).
    """
    if strategy not in ("discrete", "continuous", "continuous-full"):
        raise ValueError(f"unknown strategy {strategy!r}")
    rng = np.random.default_rng(seed)
    check = _Checker(tree, 1.0)
    creases = tree.creases
    valid = 0
    q = np.zeros(len(tree.goal))
    for _ in range(samples):
        if strategy == "continuous-full":
            q[creases] = rng.uniform(-np.pi, np.pi, len(creases))
            valid += check.valid(q)
            continue
        u = (rng.random(len(creases)) < 0.5) if strategy == "discrete" else rng.random(len(creases))
        q[creases] = u * tree.goal[creases]
        valid += check.valid(q)
    return valid, samples


def with_path(fold: dict, path: FoldPath, resolution_deg: float, contact_tol: float) -> dict:
    """A copy of the FOLD dict with the path: `polyfold:path` (frames of FOLD fold angles in
    degrees, one per edge, 0 for B edges; first all 0, last = edges_foldAngle) and its facts
    (planner, linear, resolution in degrees, contact tolerance relative to the model size)."""
    out = dict(fold)
    frames = path.degrees_fold()
    # The last frame is the goal itself: write the file's own angles so it matches bit for bit.
    frames[-1] = [float(a) for a in fold["edges_foldAngle"]]
    frames[0] = [0.0] * len(frames[0])
    out["polyfold:path"] = frames
    out["polyfold:path_planner"] = path.planner
    out["polyfold:path_linear"] = bool(path.linear)
    out["polyfold:path_resolutionDeg"] = float(resolution_deg)
    out["polyfold:path_contactTol"] = float(contact_tol)
    return out
