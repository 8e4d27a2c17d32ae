"""Continuous folding: a collision-free path from the flat net (all angles 0) to the folded shape.

In: a `FoldTree` (tree.py). Out: a `FoldPath` — configurations q
(radians per FOLD edge, + = mountain) whose consecutive straight segments are collision-free when
sampled at `resolution` (ALGORITHMS.md 6.3-6.5).

Planners ("auto" runs them in this order):
1. linear: the straight line C_s -> C_g (bisection order, early exit) — the paper's LC test;
   "auto" asks it through two-phase, which starts with the straight line;
1b. two-phase: where the straight line is blocked, the same with one crease out of step (the
   rest first with it flat, then it alone; or the reverse), the crease chosen on the tree path
   between the two faces that collided (not in the paper);
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
from typing import Callable

import numpy as np

from ..deadline import Deadline, clock
from ..errors import PolyfoldError
from ..mesh.geometry import rho_to_fold_deg
from .checker import ValidityChecker, first_blocked_segment
from .lazy_prm import plan_lazy_prm
from .sequential import plan_sequential
from .tree import FoldTree, colliding_pairs


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
        return rho_to_fold_deg(self.frames).tolist()


def path_at(frames: np.ndarray, t: float) -> np.ndarray:
    """The configuration (E,) at fraction t of a path (K, E) (any angle unit): linear between
    consecutive frames, every segment the same share of t (t clamped to 0..1)."""
    frames = np.asarray(frames, dtype=np.float64)
    t = min(1.0, max(0.0, float(t)))
    if len(frames) == 1:
        return frames[0].copy()
    s = t * (len(frames) - 1)
    i = min(int(math.floor(s)), len(frames) - 2)
    u = s - i
    return (1.0 - u) * frames[i] + u * frames[i + 1]


@dataclass(frozen=True)
class PlannerSettings:
    """What a planner may use besides the tree, the checker and the deadline: the seed of its own
    random generator, and the Lazy PRM's first batch of samples and neighbours per node."""

    seed: int = 0
    n0: int = 100
    k_neighbours: int = 10


@dataclass(frozen=True, eq=False)
class Found:
    """A planner's path: frames (K, E) flat -> goal, the name it reports, roadmap nodes, and
    whether it is the straight line."""

    frames: np.ndarray
    planner: str
    nodes: int
    linear: bool


Planner = Callable[[FoldTree, ValidityChecker, Deadline, PlannerSettings], "Found | None"]


def plan_linear(tree: FoldTree, check: ValidityChecker, deadline: Deadline, settings: PlannerSettings) -> Found | None:
    """The straight line flat -> goal (the paper's LC test), checked at half the resolution at
    once (its samples include the full-resolution ones, `ValidityChecker.segment`; a blocked line
    fails as early, at its first bisection samples)."""
    straight = np.stack([np.zeros(len(tree.goal)), tree.goal.copy()])
    if first_blocked_segment(check, straight, check.step / 2) < 0:
        return Found(straight, "linear", 2, True)
    return None


TWO_PHASE_CANDIDATES = 4  # creases the two-phase planner tries out of step, nearest the collision first


def plan_two_phase(tree: FoldTree, check: ValidityChecker, deadline: Deadline,
                   settings: PlannerSettings) -> Found | None:
    """The straight line with one crease out of step: two segments, flat -> mid -> goal.

    Where the straight line is blocked, the two faces the check found colliding are usually a
    flap closing too early onto the face it ends beside. One crease on the tree path between them
    is moved apart from the rest: the rest fold first with it held flat, then it folds alone (or
    it first, then the rest). Candidates: the creases of the two faces first, then their
    parents' and so on, at most TWO_PHASE_CANDIDATES. Each segment is checked at half the
    resolution, as the straight line; the one where a single crease moves (cheap: most pairs
    keep their pose) first. The straight line itself when it is free.
    """
    straight = plan_linear(tree, check, deadline, settings)
    if straight is not None:
        return straight
    hit = check.last_hit()  # the faces the straight line's check found colliding
    if hit is None:
        return None
    zero, goal = np.zeros(len(tree.goal)), tree.goal
    fine = check.step / 2
    moving = [c for c in _creases_between(tree, *hit) if goal[c] != 0.0]
    for c in moving[:TWO_PHASE_CANDIDATES]:
        for alone_last in (True, False):
            if deadline.expired():
                return None
            mid = goal.copy() if alone_last else zero.copy()
            mid[c] = 0.0 if alone_last else goal[c]
            single, rest = ((mid, goal), (zero, mid)) if alone_last else ((zero, mid), (mid, goal))
            if check.valid(mid) and check.segment(*single, fine) and check.segment(*rest, fine):
                return Found(np.stack([zero, mid, goal.copy()]), "two-phase", 3, False)
    return None


def _creases_between(tree: FoldTree, i: int, j: int) -> list[int]:
    """The creases (edge ids) on the tree path between faces i and j, nearest the two faces
    first (j's crease, i's crease, then their parents', ...)."""
    up_i = [i]
    while tree.parent[up_i[-1]] >= 0:
        up_i.append(int(tree.parent[up_i[-1]]))
    on_i = {f: k for k, f in enumerate(up_i)}
    up_j = [j]
    while up_j[-1] not in on_i:
        if tree.parent[up_j[-1]] < 0:
            return []  # different pieces: no path
        up_j.append(int(tree.parent[up_j[-1]]))
    side_i, side_j = up_i[:on_i[up_j[-1]]], up_j[:-1]  # faces below the common ancestor
    out = []
    for k in range(max(len(side_i), len(side_j))):
        out += [int(tree.crease[side[k]]) for side in (side_j, side_i) if k < len(side)]
    return out


def _sequential(tree: FoldTree, check: ValidityChecker, deadline: Deadline, settings: PlannerSettings) -> Found | None:
    found = plan_sequential(tree, check, deadline, np.random.default_rng(settings.seed))
    if found is None:
        return None
    frames, continuous = found
    return Found(frames, "sequential-rrt" if continuous else "sequential", len(frames), False)


def _lazy_prm(tree: FoldTree, check: ValidityChecker, deadline: Deadline, settings: PlannerSettings) -> Found | None:
    found = plan_lazy_prm(tree, check, deadline, np.random.default_rng(settings.seed), settings.n0, settings.k_neighbours)
    if found is None:
        return None
    frames, nodes = found
    return Found(frames, "lazy-prm", nodes, len(frames) == 2)


# Planners by name, interchangeable over one validity checker and one deadline.
PLANNER_REGISTRY: dict[str, Planner] = {"linear": plan_linear, "two-phase": plan_two_phase,
                                         "sequential": _sequential, "lazy-prm": _lazy_prm}
# "auto": each in turn, each until its share of the time limit (from the start) is used; the Lazy
# PRM keeps a third for the rare net the sequential planner cannot unlock (it finds nothing on
# large nets, but may on a small one).
AUTO = (("two-phase", 1.0), ("sequential", SEQUENTIAL_SHARE), ("lazy-prm", 1.0))
PLANNERS = ("auto", *PLANNER_REGISTRY)


def plan_fold(
    tree: FoldTree,
    planner: str = "auto",
    resolution_deg: float = 1.0,
    time_limit: float = 60.0,
    seed: int = 0,
    n0: int = 100,
    k_neighbours: int = 10,
    deadline: Deadline | None = None,
) -> FoldPath | None:
    """Plan a collision-free folding path; None when none is found in time (`time_limit` seconds,
    or until `deadline` when one is given).

    planner: "linear" (straight line only), "two-phase" (the straight line, else one crease out of
    step), "sequential" (crease-by-crease unfolding of the goal only), "lazy-prm" (Lazy PRM only,
    as the paper after its LC test), "auto" (straight line, two-phase, then sequential, then Lazy
    PRM for the time left). Raises PolyfoldError when the flat net or
    the goal itself self-intersects, or faces clash at the goal at the tree's thickness (then no
    path can exist).
    """
    if planner not in PLANNERS:
        raise ValueError(f"unknown planner {planner!r}")
    t0, start = time.perf_counter(), clock()
    deadline = Deadline(start + time_limit) if deadline is None else deadline
    check = ValidityChecker(tree, math.radians(resolution_deg))
    # at most two faces: their one pair is a crease pair or in two pieces, never tested, so every
    # configuration is free; single faces (no DOF): the flat net is the goal. Whatever the planner.
    trivial = tree.n_faces <= 2 or len(tree.creases) == 0
    if tree.n_faces > 2:
        _check_ends(tree, check)
    if trivial:
        found = Found(np.stack([np.zeros(len(tree.goal)), tree.goal.copy()]), "linear", 2, True)
    else:
        settings = PlannerSettings(seed, n0, k_neighbours)
        steps = AUTO if planner == "auto" else ((planner, 1.0),)
        found = None
        for name, share in steps:
            until = deadline if share >= 1.0 else Deadline(start + (deadline.at - start) * share)
            found = PLANNER_REGISTRY[name](tree, check, until, settings)
            if found is not None:
                break
    if found is None:
        return None
    return FoldPath(frames=found.frames, linear=found.linear, planner=found.planner, seconds=time.perf_counter() - t0,
                    edges_checked=check.edges, configs_checked=check.configs, nodes=found.nodes)


def _check_ends(tree: FoldTree, check: ValidityChecker) -> None:
    """PolyfoldError when the flat net (at the tree's thickness) or the folded goal (without:
    faces meet there) self-intersects, or when faces clash at the goal at the tree's thickness:
    no path can exist (at that thickness)."""
    if not check.valid(np.zeros(len(tree.goal))):
        raise PolyfoldError("the flat net overlaps itself: not a valid net")
    # the goal without thickness: there faces meet along glued seams and at mesh vertices by design
    if not check.valid_without_thickness(tree.goal):
        pairs = colliding_pairs(tree, tree.goal)
        raise PolyfoldError(
            f"the folded goal shape intersects itself (net faces {pairs[0, 0]} and {pairs[0, 1]} cross, "
            f"{len(pairs)} pair{'s' if len(pairs) != 1 else ''} in all, beyond the contact tolerance "
            f"{tree.tol / tree.scale:.0e} of the model size): no folding path can exist; if that is within "
            f"the paper's thickness, raise --contact-tol")
    # at the thickness: where two faces come closer than it at the goal without sharing a mesh vertex
    # (vertices that close but not joined), the configurations near the goal collide too and every
    # planner spends its whole budget failing: 3 of the 487 pieces make planned over 43 models
    # (hull-ellipsoid-rand-236's, two vertices 0.25 mm apart at 150 mm), none found a path, 12.6 s
    if not check.valid(tree.goal):
        i, j = check.last_hit()
        raise PolyfoldError(
            f"its faces clash at the goal: net faces {i} and {j} come closer than the paper's thickness "
            f"({tree.thickness / tree.scale:.1e} of the model size; mesh vertices that close but not joined): "
            "no folding path at this thickness")


def is_linearly_foldable(tree: FoldTree, resolution_deg: float = 1.0) -> bool:
    """True if the straight segment flat -> goal is collision-free at the resolution (and at half of it)."""
    check = ValidityChecker(tree, math.radians(resolution_deg))
    if not check.valid(np.zeros(len(tree.goal))) or not check.valid(tree.goal):
        return False
    return plan_linear(tree, check, Deadline.never(), PlannerSettings()) is not None
