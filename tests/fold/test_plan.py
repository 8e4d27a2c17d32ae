"""The planners behind fold/plan.py's `plan_fold` (linear, two-phase, sequential with its
RRT-Connect unlocking, Lazy PRM), their paths judged by the independent path checker (tests/path_checker.py,
which does not import polyfold): a net whose straight-line fold collides, whole meshes, a net
without creases."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from conftest import straight, subdivided_box, whole_net
from fold_checker import check_fold
from path_checker import FoldNet, check_path
from polyfold.deadline import Deadline
from polyfold.fold import sequential
from polyfold.fold.plan import is_linearly_foldable, plan_fold
from polyfold.formats.fold import fold_tree, net_to_fold, with_path
from polyfold.formats.meshes import load_mesh
from polyfold.fold.tree import FoldTree
from polyfold.mesh.geometry import merged_edges
from polyfold.segment.segment import segment
from polyfold.unfold.search import unfold
from polyfold.verify.paths import check_fold_path


# ----------------------------------------------------------------------------------------------
# A net whose straight-line fold collides: the Lazy PRM for real


def test_lazy_prm_path_where_the_straight_line_collides(lazy_case):
    name, mesh, fold, net, path = lazy_case
    assert name.startswith("l-prism-hand.obj"), name  # the hand-made mesh suffices
    net_report = check_fold(net, mesh)
    assert net_report.ok, str(net_report)
    tree = fold_tree(fold)
    assert plan_fold(tree, planner="linear") is None
    assert not is_linearly_foldable(tree)
    # the straight line really collides (the planner checks it at 1 deg and 0.5 deg)
    hit = check_path(straight(fold), step_deg=0.5).first_collision
    assert hit is not None and 0 < hit[1] <= 1, hit
    # ... and the Lazy PRM path around it is accepted
    assert path.planner == "lazy-prm" and not path.linear and len(path.frames) > 2
    report = check_path(with_path(fold, path, 1.0, 1e-7))
    assert report.ok, f"{name}:\n{report}"
    finer = check_path(with_path(fold, path, 1.0, 1e-7), step_deg=0.25)
    assert finer.ok, f"{name}:\n{finer}"


# ----------------------------------------------------------------------------------------------
# Whole meshes: the sequential planner (crease-by-crease unfolding of the folded shape)


def _assert_monotone_discrete(tree, path) -> None:
    """Every frame is a discrete state of the paper's sampling domain (each crease flat or at its
    goal), and the frames only fold creases, from all flat to all folded."""
    goal = tree.goal[tree.creases]
    cr = path.frames[:, tree.creases]
    assert np.all(np.isclose(cr, 0.0) | np.isclose(cr, goal))
    folded = np.isclose(cr, goal).sum(axis=1)
    assert folded[0] == 0 and folded[-1] == len(goal) and np.all(np.diff(folded) > 0)


def test_sequential_planner_folds_the_whole_horse(models_dir):
    """The paper found no path for the whole horse (301 DOF) in an hour, and the Lazy PRM alone
    finds none here in seconds; crease-by-crease unfolding of the folded shape does. (The
    independent checker re-checks a whole-mesh path below, on the smaller bunny: on the horse
    it takes minutes.)"""
    tree = fold_tree(whole_net(models_dir, "horse-302", 3, 302))
    assert plan_fold(tree, planner="linear") is None
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=1)
    assert path is not None, "no sequential path for the whole horse"
    assert path.planner == "sequential" and not path.linear
    _assert_monotone_discrete(tree, path)
    assert plan_fold(tree, planner="lazy-prm", time_limit=3, seed=1) is None


def test_sequential_planner_unlocks_stuck_creases_by_a_continuous_search(models_dir, monkeypatch):
    """Horse net 13: a dozen creases of a curled strip carrying a large flap can open neither alone,
    nor first, nor together in the discrete domain (this seed had no path before). The
    RRT-Connect search over those creases opens them; its frames (the path's first ones, off the
    discrete domain) are re-checked by the independent checker at the samples the planner checked
    them at (half the resolution: twice the resolution's count ceil(span / 1 degree) per move, a
    grid that holds the resolution's, which make writes and verifies), the rest is discrete. An
    earlier restart locks on another set, whose search fails within its allowance. The searches'
    budgets are work (configurations checked), so this seed's path is the same on every machine:
    with budgets in seconds, a loaded machine's searches ran out sooner and the restarts went on to
    another path. (A check at 0.5 degree by ceil(span / 0.5 degree) instead samples elsewhere: on a
    move of 18.09 degrees, 37 samples against the planner's 38, one of which met a collision 0.35
    degree wide between the planner's samples.)"""
    searches = []  # (creases, configurations checked, found)
    search = sequential.rrt_connect

    def recorded(check, start, moving, deadline, rng):
        done = check.configs
        rest = search(check, start, moving, deadline, rng)
        searches.append((len(moving), check.configs - done, rest is not None))
        return rest

    monkeypatch.setattr(sequential, "rrt_connect", recorded)
    fold = whole_net(models_dir, "horse-302", 13, 302)
    tree = fold_tree(fold)
    resolution = 1.0  # degrees
    path = plan_fold(tree, planner="sequential", resolution_deg=resolution, time_limit=60, seed=13)
    assert path is not None and path.planner == "sequential-rrt"
    assert len(searches) >= 2 and not any(found for _n, _w, found in searches[:-1]) and searches[-1][2]
    # a search stops at the first check of its budget past it: one move, at most 2 * 720 samples
    assert all(work <= sequential.RRT_FIRST + 1440 for _n, work, _found in searches)
    goal = tree.goal[tree.creases]
    cr = path.frames[:, tree.creases]
    discrete = np.all(np.isclose(cr, 0.0) | np.isclose(cr, goal), axis=1)
    k = int(np.argmax(discrete[1:])) + 1  # the stuck state: where the discrete frames begin
    assert k > 1 and not discrete[1:k].any() and discrete[k:].all()
    folded = np.isclose(cr[k:], goal).sum(axis=1)
    assert folded[-1] == len(goal) and np.all(np.diff(folded) > 0)
    # only the stuck creases move in the continuous part, and they end where the discrete part starts
    moving = np.flatnonzero(np.ptp(cr[:k + 1], axis=0) > 0)
    assert 0 < len(moving) <= 32
    net = FoldNet(fold, 1e-7)
    deg = np.asarray(path.degrees_fold())
    for s in range(k):
        span = float(np.abs(deg[s + 1] - deg[s]).max())
        samples = 2 * math.ceil(span / resolution - 1e-9)
        _, hit = net.segment_collision(deg[s], deg[s + 1], span / samples, skip_start=s > 0)
        assert hit is None, f"segment {s} collides at {hit}"


def test_a_seed_gives_the_same_path_on_a_slower_machine(models_dir, monkeypatch):
    """Horse net 13 (a continuous search unlocks it, see above) planned again with every move of
    the planner's checker slowed by 0.2 ms, as on a loaded or slower machine: the searches' budgets
    are work, not seconds, so the same seed gives the same path frame for frame. (With budgets in
    seconds the slowed searches ran out sooner, and the restarts went on to another path.)"""
    from polyfold.fold.checker import ValidityChecker

    tree = fold_tree(whole_net(models_dir, "horse-302", 13, 302))
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=13)
    move = ValidityChecker.move
    calls = []

    def slowed(self, qa, qb, step=None):
        calls.append(1)
        time.sleep(2e-4)
        return move(self, qa, qb, step)

    monkeypatch.setattr(ValidityChecker, "move", slowed)
    again = plan_fold(tree, planner="sequential", time_limit=60, seed=13)
    assert path is not None and again is not None and path.planner == again.planner == "sequential-rrt"
    assert np.array_equal(path.frames, again.frames)
    assert again.seconds >= 2e-4 * len(calls) > 0.2  # slowed indeed (a sleep never ends early)


class _Work:
    """A stand-in for the ValidityChecker where `_open_in_order` and `rrt_connect` are faked: the
    planner reads only its count of configurations checked."""

    def __init__(self) -> None:
        self.configs = 0


def _works_until(check: _Work, until: Deadline, chunk: int = 100) -> int:
    """A search that finds nothing: checks `chunk` configurations at a time until its deadline."""
    done = check.configs
    while not until.expired():
        check.configs += chunk
    return check.configs - done


def _planned(monkeypatch, tree: FoldTree, check, deadline: Deadline, restart, search):
    """`plan_sequential` with its restarts (`_open_in_order`) and searches (`rrt_connect`) replaced
    by `restart` and `search`."""
    monkeypatch.setattr(sequential, "_open_in_order", restart)
    monkeypatch.setattr(sequential, "rrt_connect", search)
    return sequential.plan_sequential(tree, check, deadline, np.random.default_rng(1))


def _locked_on_three(tree: FoldTree):
    """A restart that locks on the same three creases every time, without checking anything."""
    stuck = np.zeros(len(tree.creases), dtype=bool)
    stuck[:3] = True
    return lambda tree, check, prio, until: ([tree.goal.copy()], ~stuck)


def test_a_stuck_sets_search_gets_twice_as_much_work_each_time_it_recurs(models_dir, monkeypatch):
    """Every restart locks on the same creases and their continuous search finds nothing: it is
    given RRT_FIRST configurations, then twice the last each time, and the planner gives up at its
    deadline (here 1,000,000 configurations: the first time the set is met the restarts have
    checked none, no allowance, no search)."""
    tree = fold_tree(whole_net(models_dir, "bunny-128", 1, 128))
    check = _Work()
    deadline = Deadline.never().or_when(lambda: check.configs >= 1_000_000)
    given = []  # (configurations the search checked, creases)

    def fails(check, start, moving, until, rng):
        given.append((_works_until(check, until), len(moving)))
        return None

    assert _planned(monkeypatch, tree, check, deadline, _locked_on_three(tree), fails) is None
    first = sequential.RRT_FIRST
    assert [w for w, _n in given] == [first, 2 * first, 4 * first, 8 * first, 1_000_000 - 15 * first]
    assert all(n == 3 for _w, n in given)


def test_a_search_never_gets_more_than_half_the_time_left(models_dir, monkeypatch):
    """The same recurring set with an RRT_FIRST no search can use up: each search is given half the
    seconds the planner has left (the limit 1 s), and the planner gives up at its deadline."""
    tree = fold_tree(whole_net(models_dir, "bunny-128", 1, 128))
    deadline = Deadline.after(1.0)
    given = []  # (seconds the search is given, seconds the planner has left)

    def fails(check, start, moving, until, rng):
        given.append((until.left(), deadline.left()))
        time.sleep(max(0.0, until.left()))
        return None

    monkeypatch.setattr(sequential, "RRT_FIRST", 10 ** 15)
    assert _planned(monkeypatch, tree, _Work(), deadline, _locked_on_three(tree), fails) is None
    assert len(given) >= 3
    assert [g for g, _l in given] == pytest.approx([left / 2 for _g, left in given], abs=2e-3)


def test_a_set_met_for_the_first_time_is_searched_only_within_the_restarts_allowance(models_dir, monkeypatch):
    """Restarts that each check 10,000 configurations and lock on a new set of creases every time
    (never round in circles), and searches that find nothing: a search is given RRT_SHARE of the
    restarts' configurations less what the searches checked, none under RRT_MIN (made 2,000 here:
    the first restart's allowance, 1,500, is under it), so the searches together check at most
    RRT_SHARE of what the restarts did and the restarts go on at almost their full pace."""
    tree = fold_tree(whole_net(models_dir, "bunny-128", 1, 128))
    n = len(tree.creases)
    monkeypatch.setattr(sequential, "RRT_MIN", 2_000)
    check = _Work()
    deadline = Deadline.never().or_when(lambda: check.configs >= 250_000)
    restarts, given = [], []  # each search's (configurations checked, restarts before it)

    def locked(tree, check, prio, until):
        stuck = np.zeros(n, dtype=bool)
        stuck[[len(restarts) % n, (len(restarts) + 1) % n]] = True  # a new pair each time
        check.configs += 10_000
        restarts.append(10_000)
        return [tree.goal.copy()], ~stuck

    def fails(check, start, moving, until, rng):
        given.append((_works_until(check, until), len(restarts)))
        return None

    assert _planned(monkeypatch, tree, check, deadline, locked, fails) is None
    # 15 % of 20,000 after the second restart, 15 % of 40,000 less 3,000 after the fourth, ...
    assert given[:3] == [(3_000, 2), (3_000, 4), (3_000, 6)]
    assert len(restarts) >= 20 and all(w <= sequential.RRT_FIRST for w, _k in given)
    assert sum(w for w, _k in given) <= sequential.RRT_SHARE * sum(restarts)


# ----------------------------------------------------------------------------------------------
# Two-phase: the straight line with one crease out of step


def test_two_phase_folds_one_crease_apart_where_the_straight_line_collides(models_dir):
    """periscope-28 in two parts: some seeds' nets of the 26-face part collide on the straight
    line (two flaps close onto each other); holding one crease back gives a 3-frame path that the
    two independent checkers accept, at zero and at the default thickness."""
    part = segment(load_mesh(models_dir / "periscope-28.obj").mesh, parts=2).parts[0]
    found = 0
    for seed in range(1, 21):
        net, stats = unfold(part, seed=seed)
        assert stats.pieces == 1
        fold = net_to_fold([net])
        tree = FoldTree.from_net(net)
        thick = tree.with_thickness(1e-3 * tree.scale)
        if plan_fold(thick, planner="linear") is not None:
            continue
        path = plan_fold(thick, planner="two-phase", seed=seed)
        assert path is not None and path.planner == "two-phase" and not path.linear
        assert path.frames.shape == (3, tree.n_edges)
        # the middle frame: one crease out of step (alone flat, the rest folded; or the reverse)
        mid, goal = path.frames[1][tree.creases], tree.goal[tree.creases]
        at_goal, flat = np.isclose(mid, goal), np.isclose(mid, 0.0)
        moving = goal != 0.0
        assert (at_goal | flat).all()
        assert min(int((flat & moving).sum()), int((at_goal & moving).sum())) == 1
        written = with_path(fold, path, 1.0, 1e-7, thick.thickness)
        assert check_path(written).ok
        report = check_fold_path(written, thickness=thick.thickness)
        assert report.ok, report.why()
        assert plan_fold(thick, seed=seed).planner == "two-phase"  # "auto" tries it before the sequential planner
        found += 1
    assert found >= 2, "expected some seeds whose straight line collides"


def test_two_phase_returns_the_straight_line_when_it_is_free(models_dir):
    net, _ = unfold(load_mesh(models_dir / "cube-12.obj").components[0], seed=1)
    tree = FoldTree.from_net(net)
    path = plan_fold(tree, planner="two-phase")
    assert path.linear and path.planner == "linear" and len(path.frames) == 2


@pytest.mark.parametrize("planner", ["auto", "linear", "two-phase", "sequential", "lazy-prm"])
def test_every_planner_handles_a_net_without_creases(models_dir, planner):
    mesh = load_mesh(models_dir / "tetrahedron-4.obj").mesh.submesh(np.array([0]))
    net, _ = unfold(mesh)
    tree = fold_tree(net_to_fold([net]))
    assert len(tree.creases) == 0
    path = plan_fold(tree, planner=planner)
    assert path is not None and path.linear and path.frames.shape == (2, tree.n_edges)
    assert np.allclose(path.frames, 0.0)


@pytest.mark.parametrize("name, planner", [("cube-12", "auto"), ("cube-12", "sequential"), ("cube-12", "lazy-prm"),
                                           ("subdivided-box", "auto"), ("subdivided-box", "sequential")])
def test_flat_regions_stay_flat_along_the_path(models_dir, name, planner):
    # issue 18: the merged creases inside a flat region (goal angle 0) never move on any planner's
    # path, and nothing divides by their zero angle; the path passes the independent checker
    mesh = subdivided_box(1) if name == "subdivided-box" else load_mesh(models_dir / f"{name}.obj").components[0]
    net, stats = unfold(mesh, seed=1)
    assert stats.pieces == 1
    fold = net_to_fold([net])
    tree = fold_tree(fold)
    flat = tree.creases[tree.goal[tree.creases] == 0.0]
    assert len(flat) == int(merged_edges(mesh).sum()) - (0 if name == "cube-12" else 6)  # box: a flat edge per cycle is cut
    path = plan_fold(tree, planner=planner, time_limit=30)
    assert path is not None and np.isfinite(path.frames).all()
    assert (path.frames[:, flat] == 0.0).all()
    assert check_path(with_path(fold, path, 1.0, 1e-7)).ok


def test_sequential_path_of_a_whole_mesh_passes_the_independent_checker(whole_bunny):
    fold, _ = whole_bunny
    tree = fold_tree(fold)
    assert plan_fold(tree, planner="linear") is None
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=1)
    assert path is not None and path.planner == "sequential"
    _assert_monotone_discrete(tree, path)
    report = check_path(with_path(fold, path, 1.0, 1e-7), step_deg=0.5)
    assert report.ok, str(report)
    assert report.frames == len(path.frames) > 2
