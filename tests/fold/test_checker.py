"""fold/checker.py: the planners' collision test with reused work arrays (`config_collides_cached`):
whatever the previous calls left in the work arrays (folded faces, per-face geometry, sweep order),
every verdict is the one of a fresh test, and the folded faces are forward_kinematics' bit for bit."""

import numpy as np
import pytest

from polyfold.formats.fold import net_to_fold
from polyfold.formats.meshes import load_mesh
from polyfold.collide.triangles import triangles_collide
from polyfold.fold.checker import collision_work, config_collides, config_collides_cached, config_collides_moving
from polyfold.fold.tree import fold_positions
from polyfold.formats.fold import fold_tree
from polyfold.unfold.search import unfold


@pytest.fixture(scope="module", params=["periscope-28", "bunny-128", "torus-8x4-64"])
def tree(request, models_dir):
    mesh = load_mesh(models_dir / f"{request.param}.obj").mesh
    net, _ = unfold(mesh, seed=1)
    return fold_tree(net_to_fold([net]))


def rigid_groups(tree, moving):
    """Rigid groups of a segment moving the creases `moving` (as fold.segment_free labels them)."""
    rigid = np.empty(tree.n_faces, dtype=np.int64)
    for f in tree.order:
        rigid[f] = f if tree.parent[f] < 0 or moving[tree.crease[f]] else rigid[tree.parent[f]]
    return rigid


def expected(tree, q, rigid):
    """Brute force: every pair of one piece but crease pairs and pairs of one rigid group."""
    X = fold_positions(tree, q)
    for i in range(tree.n_faces):
        for j in range(i + 1, tree.n_faces):
            if tree.piece[i] != tree.piece[j] or tree.parent[i] == j or tree.parent[j] == i:
                continue
            if rigid is not None and rigid[i] >= 0 and rigid[i] == rigid[j]:
                continue
            if triangles_collide(X[i], X[j], tree.tol):
                return True
    return False


def configurations(tree, rng, n):
    """Jumps (random, discrete, toward the goal) mixed with short moves of a few creases."""
    q = np.zeros(tree.n_edges)
    cr, goal = tree.creases, tree.goal
    for s in range(n):
        kind = s % 4
        if kind == 0:
            q = np.zeros(tree.n_edges)
            q[cr] = rng.random(len(cr)) * goal[cr]
        elif kind == 1:
            q = np.zeros(tree.n_edges)
            q[cr] = (rng.random(len(cr)) < 0.5) * goal[cr]
        elif kind == 2:
            q = goal * rng.choice([1.0, 1 - 1e-9, 0.999, 0.5])
        else:
            q = q.copy()
            few = rng.choice(cr, size=min(3, len(cr)), replace=False)
            q[few] = rng.random(len(few)) * goal[few]
        yield q


def test_cached_verdicts_and_faces_equal_fresh_ones(tree):
    rng = np.random.default_rng(5)
    work = collision_work(tree.n_faces)
    R, T, out = tree.buffers()
    args = (tree.order, tree.parent, tree.crease, tree.axis, tree.flat, tree.piece)
    verdicts = set()
    for q in configurations(tree, rng, 60):
        moving = rng.random(tree.n_edges) < rng.random()
        rigid = rigid_groups(tree, moving)
        fresh = config_collides(q, *args, tree.tol, R, T, out)
        fresh_moving = config_collides_moving(q, *args, rigid, tree.tol, R, T, out)
        assert config_collides_cached(q, *args, np.full(tree.n_faces, -1), tree.tol, work) == fresh
        assert np.array_equal(work[6], fold_positions(tree, q))
        assert config_collides_cached(q, *args, rigid, tree.tol, work) == fresh_moving
        verdicts.add(fresh)
    assert verdicts == {False, True}


def test_cached_verdicts_agree_with_brute_force(tree):
    rng = np.random.default_rng(8)
    work = collision_work(tree.n_faces)
    args = (tree.order, tree.parent, tree.crease, tree.axis, tree.flat, tree.piece)
    for q in configurations(tree, rng, 16):
        # segments moving a few creases: one big rigid group (the sweep then starts from the others)
        moving = np.zeros(tree.n_edges, dtype=bool)
        moving[rng.choice(tree.creases, size=min(2, len(tree.creases)), replace=False)] = True
        for rigid in (np.full(tree.n_faces, -1), rigid_groups(tree, moving)):
            assert config_collides_cached(q, *args, rigid, tree.tol, work) == expected(tree, q, rigid)


def test_another_tol_refreshes_the_cache(tree):
    work = collision_work(tree.n_faces)
    args = (tree.order, tree.parent, tree.crease, tree.axis, tree.flat, tree.piece)
    R, T, out = tree.buffers()
    q = tree.goal * 0.7
    for tol in (tree.tol, 0.05 * tree.scale, tree.tol, 0.0):
        fresh = config_collides(q, *args, tol, R, T, out)
        assert config_collides_cached(q, *args, np.full(tree.n_faces, -1), tol, work) == fresh


def test_a_finer_segment_check_includes_the_resolutions_samples(tree):
    """A move of 14.24 degrees at 1 degree: the resolution samples t = k / 15. Checked at half the
    resolution the planners sample t = k / 30 (29 interior samples), which include them; sampling
    ceil(14.24 / 0.5) = 29 (t = k / 29) missed t = 1/3, where a Loop-subdivided moneybox piece
    collided: a path its planner accepted and the independent check (at 1 degree) rejected."""
    import math

    from polyfold.fold.checker import ValidityChecker

    check = ValidityChecker(tree, math.radians(1.0))
    q = np.zeros(tree.n_edges)
    q[tree.creases[0]] = math.radians(14.24)
    before = check.configs
    check.segment(np.zeros(tree.n_edges), q, math.radians(0.5))
    assert check.configs - before == 29
    before = check.configs
    check.segment(np.zeros(tree.n_edges), q)
    assert check.configs - before == 14


def test_a_move_is_its_ends_validity_and_its_segment(tree):
    """`ValidityChecker.move(qa, qb)` from a valid qa (a planner's step from where it is) tests qb
    as a sample of the motion, skipping the pairs the motion keeps in one pose: its verdict is
    `valid(qb) and segment(qa, qb)` (checked on a separate checker), on steps that open, close or
    partly turn a few creases of valid configurations, both verdicts occurring; it tests qb first."""
    import math

    from polyfold.fold.checker import ValidityChecker

    check, fresh = ValidityChecker(tree, math.radians(1.0)), ValidityChecker(tree, math.radians(1.0))
    rng = np.random.default_rng(3)
    cr, goal = tree.creases, tree.goal
    verdicts = []
    for q in configurations(tree, rng, 160):
        if not fresh.valid(q):
            continue
        for _ in range(3):
            nxt = q.copy()
            few = rng.choice(cr, size=min(int(rng.integers(1, 4)), len(cr)), replace=False)
            nxt[few] = rng.choice([0.0, 1.0, rng.random()], size=len(few)) * goal[few]
            step = math.radians(rng.choice([0.5, 1.0]))
            verdict = check.move(q, nxt, step)
            assert verdict == (fresh.valid(nxt) and fresh.segment(q, nxt, step))
            verdicts.append(verdict)
    assert len(verdicts) >= 60 and 0 < sum(verdicts) < len(verdicts)
    # qb first: an end that collides is found by its first sample
    bad = next(q for q in configurations(tree, rng, 400) if not fresh.valid(q))
    before = check.configs
    assert not check.move(np.zeros(tree.n_edges), bad)
    assert check.configs - before == 1
