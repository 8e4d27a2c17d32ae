"""Continuous folding: a collision-free path from the flat net (all angles 0) to the folded shape.

In: a `FoldTree` (kinematics.py) built from a FOLD net. Out: a `FoldPath` — configurations q
(radians per FOLD edge, + = mountain) whose consecutive straight segments are collision-free when
sampled at `resolution` (ALGORITHMS.md 6.3-6.5).

Planner: the straight line C_s -> C_g first (bisection order, early exit); otherwise Lazy PRM over
discrete configurations (each crease either flat or at its goal angle) with Hamming-distance
neighbours, lazily checked edges, A* search, and greedy shortcutting. Every returned path is
re-validated at half the resolution before it is reported.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from .kinematics import FoldTree, config_collides


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
def segment_free(qa, qb, step, order, parent, crease, axis, flat, piece, tol, R, T, out, q) -> tuple:
    """Check the straight segment qa -> qb at interior samples k/m, m = ceil(max|qb - qa| / step).

    Endpoints are assumed valid. Returns (free, configurations checked).
    """
    span = 0.0
    for i in range(qa.shape[0]):
        span = max(span, abs(qb[i] - qa[i]))
    m = int(math.ceil(span / step - 1e-12))
    checked = 0
    for k in _bisection_order(m):
        t = k / m
        for i in range(qa.shape[0]):
            q[i] = qa[i] + t * (qb[i] - qa[i])
        checked += 1
        if config_collides(q, order, parent, crease, axis, flat, piece, tol, R, T, out):
            return False, checked
    return True, checked


class _Checker:
    """Collision queries on one tree with preallocated work arrays; counts what it does."""

    def __init__(self, tree: FoldTree, resolution: float):
        self.tree = tree
        self.step = resolution
        n_f = len(tree.order)
        self.R = np.empty((n_f, 3, 3))
        self.T = np.empty((n_f, 3))
        self.out = np.empty((n_f, 3, 3))
        self.q = np.empty(len(tree.goal))
        self.configs = 0
        self.edges = 0

    def valid(self, q: np.ndarray) -> bool:
        t = self.tree
        self.configs += 1
        return not config_collides(q, t.order, t.parent, t.crease, t.axis, t.flat, t.piece, t.tol, self.R, self.T, self.out)

    def segment(self, qa: np.ndarray, qb: np.ndarray, step: float | None = None) -> bool:
        t = self.tree
        self.edges += 1
        free, n = segment_free(qa, qb, self.step if step is None else step, t.order, t.parent, t.crease, t.axis,
                               t.flat, t.piece, t.tol, self.R, self.T, self.out, self.q)
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
    return check.segment(zero, tree.goal) and check.segment(zero, tree.goal, check.step / 2)


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

    planner: "linear" (straight line only), "lazy-prm" (skip the straight-line shortcut), "auto"
    (straight line first, then Lazy PRM). Raises PolyfoldError when the flat net or the goal
    itself self-intersects (then no path can exist).
    """
    from .errors import PolyfoldError

    if planner not in ("auto", "linear", "lazy-prm"):
        raise ValueError(f"unknown planner {planner!r}")
    t0 = time.perf_counter()
    deadline = t0 + time_limit
    check = _Checker(tree, math.radians(resolution_deg))
    zero = np.zeros(len(tree.goal))
    goal = tree.goal.copy()
    if not check.valid(zero):
        raise PolyfoldError("the flat net overlaps itself: not a valid net")
    if not check.valid(goal):
        raise PolyfoldError("the folded goal shape intersects itself: no folding path can exist")

    def done(frames: np.ndarray, linear: bool, name: str, nodes: int) -> FoldPath:
        return FoldPath(frames=frames, linear=linear, planner=name, seconds=time.perf_counter() - t0,
                        edges_checked=check.edges, configs_checked=check.configs, nodes=nodes)

    if planner in ("auto", "linear"):
        straight = np.stack([zero, goal])
        if _path_free(check, straight, check.step) < 0 and _path_free(check, straight, check.step / 2) < 0:
            return done(straight, True, "linear", 2)
        if planner == "linear":
            return None
    result = _lazy_prm(tree, check, deadline, np.random.default_rng(seed), n0, k_neighbours)
    if result is None:
        return None
    frames, nodes = result
    return done(frames, len(frames) == 2, "lazy-prm", nodes)


def _lazy_prm(tree: FoldTree, check: _Checker, deadline: float, rng: np.random.Generator, n0: int, k: int):
    """Lazy PRM over discrete configurations b in {0,1}^n, q = b * goal (ALGORITHMS.md 6.5)."""
    creases = tree.creases
    n = len(creases)
    goal_c = tree.goal[creases]

    def config(bits: np.ndarray) -> np.ndarray:
        q = np.zeros(len(tree.goal))
        q[creases] = bits * goal_c
        return q

    bits = [np.zeros(n, dtype=bool), np.ones(n, dtype=bool)]
    seen = {bits[0].tobytes(), bits[1].tobytes()}
    adj: list[dict[int, float]] = [{}, {}]
    edge_state: dict[tuple[int, int], bool] = {}  # checked edges: True free, False blocked
    weight_scale = np.abs(goal_c)
    batch = n0
    S, G = 0, 1

    def dist(i: int, j: int) -> float:
        return float(np.linalg.norm((bits[i] != bits[j]) * weight_scale))

    def connect(new_ids: list[int]) -> None:
        B = np.array(bits)
        for i in new_ids:
            ham = (B != B[i]).sum(axis=1)
            ham[i] = n + 1
            near = set(np.argsort(ham, kind="stable")[:k].tolist()) | set(np.flatnonzero(ham == 1).tolist())
            for j in near:
                if j == i or ham[j] > n:
                    continue
                key = (min(i, j), max(i, j))
                if edge_state.get(key) is False:
                    continue
                w = dist(i, j)
                adj[i][j] = w
                adj[j][i] = w

    def astar() -> list[int] | None:
        h = lambda i: dist(i, G)
        best = {S: 0.0}
        prev = {S: -1}
        heap = [(h(S), 0.0, S)]
        closed = set()
        while heap:
            _, g, u = heapq.heappop(heap)
            if u in closed:
                continue
            if u == G:
                path = [u]
                while prev[path[-1]] >= 0:
                    path.append(prev[path[-1]])
                return path[::-1]
            closed.add(u)
            for v, w in adj[u].items():
                ng = g + w
                if ng < best.get(v, math.inf):
                    best[v] = ng
                    prev[v] = u
                    heapq.heappush(heap, (ng + h(v), ng, v))
        return None

    def edge_free(i: int, j: int) -> bool:
        key = (min(i, j), max(i, j))
        state = edge_state.get(key)
        if state is None:
            state = check.segment(config(bits[i]), config(bits[j]))
            edge_state[key] = state
        return state

    connect([S, G])
    while time.perf_counter() < deadline:
        new_ids = []
        tries = 0
        while len(new_ids) < batch and tries < 20 * batch and time.perf_counter() < deadline:
            tries += 1
            p = rng.random()
            b = rng.random(n) < p
            key = b.tobytes()
            if key in seen:
                continue
            seen.add(key)
            if not check.valid(config(b)):
                continue
            bits.append(b)
            adj.append({})
            new_ids.append(len(bits) - 1)
        connect(new_ids)
        while time.perf_counter() < deadline:
            path = astar()
            if path is None:
                break
            blocked = False
            for a, b in zip(path[:-1], path[1:]):
                if not edge_free(a, b):
                    adj[a].pop(b, None)
                    adj[b].pop(a, None)
                    blocked = True
                    break
            if blocked:
                continue
            frames = _shortcut([config(bits[i]) for i in path], check, deadline)
            bad = _path_free(check, frames, check.step / 2)  # re-validate at half the resolution
            if bad < 0:
                return frames, len(bits)
            # A segment that only fails the finer check: drop the roadmap edge it came from.
            for a, b in zip(path[:-1], path[1:]):
                key = (min(a, b), max(a, b))
                fa, fb = config(bits[a]), config(bits[b])
                if not check.segment(fa, fb, check.step / 2):
                    edge_state[key] = False
                    adj[a].pop(b, None)
                    adj[b].pop(a, None)
        batch *= 2
    return None


def _shortcut(frames: list[np.ndarray], check: _Checker, deadline: float) -> np.ndarray:
    """Greedy shortcut: from each kept frame jump to the farthest later frame reachable directly."""
    out = [frames[0]]
    i = 0
    while i < len(frames) - 1:
        j = len(frames) - 1
        while j > i + 1 and (time.perf_counter() >= deadline or not check.segment(frames[i], frames[j])):
            j -= 1
        out.append(frames[j])
        i = j
    return np.stack(out)


def sample_ratio(tree: FoldTree, samples: int = 1000, strategy: str = "discrete", seed: int = 0) -> tuple[int, int]:
    """Valid configuration ratio of ALGORITHMS.md 6.6: (valid, sampled).

    discrete: each crease flat or at its goal, i.i.d. Bernoulli(1/2); continuous: each crease
    uniform between 0 and its goal angle.
    """
    if strategy not in ("discrete", "continuous"):
        raise ValueError(f"unknown strategy {strategy!r}")
    rng = np.random.default_rng(seed)
    check = _Checker(tree, 1.0)
    creases = tree.creases
    valid = 0
    q = np.zeros(len(tree.goal))
    for _ in range(samples):
        u = (rng.random(len(creases)) < 0.5) if strategy == "discrete" else rng.random(len(creases))
        q[creases] = u * tree.goal[creases]
        valid += check.valid(q)
    return valid, samples


def with_path(fold: dict, path: FoldPath, resolution_deg: float) -> dict:
    """A copy of the FOLD dict with the path: `polyfold:path` (frames of FOLD fold angles in
    degrees, one per edge, 0 for B edges; first all 0, last = edges_foldAngle) and its facts."""
    out = dict(fold)
    frames = path.degrees_fold()
    # The last frame is the goal itself: write the file's own angles so it matches bit for bit.
    frames[-1] = [float(a) for a in fold["edges_foldAngle"]]
    frames[0] = [0.0] * len(frames[0])
    out["polyfold:path"] = frames
    out["polyfold:path_planner"] = path.planner
    out["polyfold:path_linear"] = bool(path.linear)
    out["polyfold:path_resolutionDeg"] = float(resolution_deg)
    return out
