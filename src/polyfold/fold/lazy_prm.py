"""The paper's planner (ALGORITHMS.md 6.5): Lazy PRM over discrete configurations.

Each crease is either flat or at its goal angle; roadmap nodes are such bit vectors, joined to
their Hamming-distance neighbours; edges are checked lazily (a coarse look first, then the full
check) only when A* puts them on a candidate path; the path found is shortcut and re-validated at
half the resolution.
"""

from __future__ import annotations

import numpy as np

from ..deadline import Deadline
from ..graphs import heap_pop, heap_push
from ..jit import njit
from .checker import ValidityChecker, first_blocked_segment, shortcut
from .tree import FoldTree, crease_depth_size


COARSE_SAMPLES = 7  # bisection levels 1-3 of a segment: the cheap first look of the Lazy PRM


MAX_BATCH = 1600  # new roadmap samples per round at most (the batch doubles from n0 up to this)


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
    g[start] = 0.0
    size = heap_push(hk, hn, 0, h[start], start)
    while size > 0:
        _, u, size = heap_pop(hk, hn, size)
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
                size = heap_push(hk, hn, size, ng + h[v], v)
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


def _ordered_states(tree: FoldTree, levels: int = 8) -> list[np.ndarray]:
    """Discrete states (bits per crease of tree.creases) folding the outer part of the tree first
    or last: thresholds on the depth and on the subtree size of each crease's child face."""
    depth, size = crease_depth_size(tree)
    states = []
    for key in (depth, -size):
        for thr in np.unique(np.quantile(key, np.linspace(0, 1, levels + 2)[1:-1], method="nearest")):
            outer = key >= thr
            states.extend([outer, ~outer])
    return states


def plan_lazy_prm(tree: FoldTree, check: ValidityChecker, deadline: Deadline, rng: np.random.Generator,
                  n0: int = 100, k: int = 10) -> tuple[np.ndarray, int] | None:
    """Lazy PRM over discrete configurations b in {0,1}^n, q = b * goal (ALGORITHMS.md 6.5):
    (frames flat -> goal, roadmap nodes), or None when out of time.

    Node 0 is the flat net, node 1 the goal. Edges are checked only when A* puts them on a
    candidate path: first a coarse look at every edge of the path (the first bisection samples),
    then the full check; blocked edges are dropped and A* runs again. More samples (doubling
    batches from n0; k nearest neighbours per node) when the start and goal are disconnected.
    """
    search = _LazySearch(tree, check, k)
    batch = n0
    while not deadline.expired():
        search.sample(batch, rng, deadline)
        found = search.solve(deadline)
        if found is not None:
            return found
        batch = min(2 * batch, MAX_BATCH)
    return None


class _LazySearch:
    """The roadmap of `plan_lazy_prm` and the lazy checks of its edges."""

    def __init__(self, tree: FoldTree, check: ValidityChecker, k: int) -> None:
        self.tree, self.check, self.k = tree, check, k
        self.creases = tree.creases
        n = len(self.creases)
        self.goal_c = tree.goal[self.creases]
        self.rm = _Roadmap(n, np.abs(self.goal_c))
        start_bits, goal_bits = np.zeros(n, dtype=bool), np.ones(n, dtype=bool)
        self.seen = {start_bits.tobytes(), goal_bits.tobytes()}
        self.rm.add_nodes([start_bits, goal_bits], k)
        # Natural folding orders as extra nodes: fold the outer branches first (by tree depth or by
        # subtree size), or the inner ones first. Cheap, and they often give a 3-frame path at once.
        seeded = []
        for b in _ordered_states(tree):
            key = b.tobytes()
            if key not in self.seen:
                self.seen.add(key)
                if check.valid(self.config(b)):
                    seeded.append(b)
        self.rm.add_nodes(seeded, k)

    def config(self, bits: np.ndarray) -> np.ndarray:
        q = np.zeros(len(self.tree.goal))
        q[self.creases] = bits * self.goal_c
        return q

    def sample(self, batch: int, rng: np.random.Generator, deadline: Deadline) -> None:
        """Add up to `batch` new valid nodes (at most 20 * batch draws)."""
        new = []
        tries = 0
        n = len(self.creases)
        while len(new) < batch and tries < 20 * batch and not deadline.expired():
            tries += 1
            b = rng.random(n) < rng.random()  # Hamming level p ~ U(0, 1), then bits ~ Bernoulli(p)
            key = b.tobytes()
            if key in self.seen:
                continue
            self.seen.add(key)
            if self.check.valid(self.config(b)):
                new.append(b)
        self.rm.add_nodes(new, self.k)

    def check_edge(self, e: int, coarse: bool) -> bool:
        rm = self.rm
        st = rm.state[e]
        if st == rm.BLOCKED:
            return False
        if st == rm.FREE or (coarse and st == rm.COARSE_OK):
            return True
        qa, qb = self.config(rm.bits[rm.eu[e]]), self.config(rm.bits[rm.ev[e]])
        ok = self.check.segment(qa, qb, max_samples=COARSE_SAMPLES) if coarse else self.check.segment(qa, qb)
        rm.state[e] = (rm.COARSE_OK if coarse else rm.FREE) if ok else rm.BLOCKED
        return ok

    def solve(self, deadline: Deadline) -> tuple[np.ndarray, int] | None:
        """Shortest roadmap paths, checked lazily, until one is free (-> frames, nodes) or none is
        left on the roadmap (-> None: sample more)."""
        rm, check = self.rm, self.check
        while not deadline.expired():
            path = rm.shortest_path()
            if len(path) == 0:
                break
            edges = [rm.edge_id[(min(a, b), max(a, b))] for a, b in zip(path[:-1].tolist(), path[1:].tolist())]
            # Coarse pass over every edge of the path first: most blocked edges show up within a
            # few samples, and dropping all of them at once saves A* runs and full checks of edges
            # on paths that are blocked elsewhere anyway.
            if not all([self.check_edge(e, True) for e in edges]):
                continue
            if not all(self.check_edge(e, False) for e in edges):
                continue
            raw = np.stack([self.config(rm.bits[i]) for i in path.tolist()])
            frames = shortcut(list(raw), check, deadline)
            if first_blocked_segment(check, frames, check.step / 2) < 0:  # re-validate at half the resolution
                return frames, len(rm.bits)
            if first_blocked_segment(check, raw, check.step / 2) < 0:  # only a shortcut failed the finer check
                return raw, len(rm.bits)
            # Some roadmap edge fails only the finer check: block the ones that do.
            for e in edges:
                if not check.segment(self.config(rm.bits[rm.eu[e]]), self.config(rm.bits[rm.ev[e]]), check.step / 2):
                    rm.state[e] = rm.BLOCKED
        return None
