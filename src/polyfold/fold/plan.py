"""Continuous folding: a collision-free path from the flat net (all angles 0) to the folded shape.

In: a `FoldTree` (tree.py). Out: a `FoldPath` — configurations q
(radians per FOLD edge, + = mountain) whose consecutive straight segments are collision-free when
sampled at `resolution` (ALGORITHMS.md 6.3-6.5).

Planners ("auto" runs them in this order):
1. linear: the straight line C_s -> C_g (bisection order, early exit) — the paper's LC test;
2. sequential: unfold the folded shape one crease at a time (not in the paper, `sequential.py`),
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

from .checker import ValidityChecker, first_blocked_segment
from .lazy_prm import plan_lazy_prm
from .sequential import plan_sequential
from ..errors import PolyfoldError
from .tree import FoldTree, colliding_pairs


PLANNERS = ("auto", "linear", "sequential", "lazy-prm")


SEQUENTIAL_SHARE = 2 / 3  # of the time limit for the sequential planner when planner="auto"


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
    if planner not in PLANNERS:
        raise ValueError(f"unknown planner {planner!r}")
    t0 = time.perf_counter()
    deadline = t0 + time_limit
    check = ValidityChecker(tree, math.radians(resolution_deg))
    zero = np.zeros(len(tree.goal))
    goal = tree.goal.copy()
    if not check.valid(zero):
        raise PolyfoldError("the flat net overlaps itself: not a valid net")
    if not check.valid(goal):
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
        if first_blocked_segment(check, straight, check.step / 2) < 0:
            return done(straight, True, "linear", 2)
        if planner == "linear":
            return None
    if planner in ("auto", "sequential"):
        # auto: the Lazy PRM keeps a third of the time for the rare net the sequential planner
        # cannot unlock (it finds nothing on large nets, but may on a small one)
        seq_deadline = deadline if planner == "sequential" else t0 + time_limit * SEQUENTIAL_SHARE
        found = plan_sequential(tree, check, seq_deadline, np.random.default_rng(seed))
        if found is not None:
            frames, continuous = found
            return done(frames, False, "sequential-rrt" if continuous else "sequential", len(frames))
        if planner == "sequential":
            return None
    result = plan_lazy_prm(tree, check, deadline, np.random.default_rng(seed), n0, k_neighbours)
    if result is None:
        return None
    frames, nodes = result
    return done(frames, len(frames) == 2, "lazy-prm", nodes)


def is_linearly_foldable(tree: FoldTree, resolution_deg: float = 1.0) -> bool:
    """True if the straight segment flat -> goal is collision-free at the resolution (and at half of it)."""
    check = ValidityChecker(tree, math.radians(resolution_deg))
    zero = np.zeros(len(tree.goal))
    if not check.valid(zero) or not check.valid(tree.goal):
        return False
    return check.segment(zero, tree.goal, check.step / 2)  # half the resolution covers the full one
