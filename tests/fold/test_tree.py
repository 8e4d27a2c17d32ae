"""fold/tree.py: the FoldTree of a net (parents first, creases, goal angles, hinge axes), built
from a FOLD file with or without parents and fold angles, and FoldTree.from_net / from_pattern
(stages in memory) giving the tree a FOLD file gives, bit for bit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import kabsch_error, small_fold
from polyfold.fold.plan import plan_fold
from polyfold.fold.tree import FoldTree, collides, fold_positions
from polyfold.formats.fold import dumps, fold_tree, net_to_fold, pattern_fold
from polyfold.formats.meshes import load_mesh
from polyfold.unfold.pattern import crease_pattern
from polyfold.unfold.search import unfold


# ----------------------------------------------------------------------------------------------
# trees of nets in memory


# single- and multi-piece nets, several components, an open part
CASES = [("bunny-128", "auto"), ("bunny-128", "steepest-edge"), ("bad/two-cubes", "auto"),
         ("paper-parts/horse/part-5", "steepest-edge"), ("open/tube-132", "auto")]
ARRAYS = ("flat", "faces", "order", "parent", "crease", "axis", "piece", "goal", "creases", "folded")


@pytest.fixture(scope="module", params=CASES, ids=["-".join(c).replace("/", ":") for c in CASES])
def nets(request, models_dir):
    name, method = request.param
    loaded = load_mesh(models_dir / f"{name}.obj")
    return [unfold(c, method=method, seed=3, time_limit=20)[0] for c in loaded.components]


def same_tree(a: FoldTree, b: FoldTree) -> None:
    for key in ARRAYS:
        x, y = getattr(a, key), getattr(b, key)
        assert x.dtype == y.dtype and x.shape == y.shape, key
        assert x.tobytes() == y.tobytes(), key
    assert (a.scale, a.tol) == (b.scale, b.tol)


def test_pattern_tree_equals_file_tree(nets, tmp_path):
    pattern = crease_pattern(nets)
    path = tmp_path / "net.fold"
    path.write_text(dumps(pattern_fold(pattern)))
    from_file = fold_tree(json.loads(path.read_text()), 1e-6)
    same_tree(FoldTree.from_pattern(pattern, 1e-6), from_file)
    assert pattern_fold(pattern) == net_to_fold(nets)


def test_net_tree_plans_the_same_path_as_the_file_tree(nets):
    for net in nets:  # one tree per component
        tree = FoldTree.from_net(net)
        same_tree(tree, fold_tree(net_to_fold([net])))
        a = plan_fold(tree, planner="sequential", time_limit=20, seed=2)
        b = plan_fold(fold_tree(net_to_fold([net])), planner="sequential", time_limit=20, seed=2)
        assert (a is None) == (b is None)
        if a is not None:
            assert np.array_equal(a.frames, b.frames) and a.planner == b.planner


# ----------------------------------------------------------------------------------------------
# tree construction from a FOLD file (the `net` fixture: nets of real models)


def test_tree_matches_fold(net):
    fold, tree = net
    n_f = len(fold["faces_vertices"])
    assert tree.flat.shape == (n_f, 3, 3) and (tree.flat[:, :, 2] == 0).all()
    pos = np.empty(n_f, dtype=np.int64)
    pos[tree.order] = np.arange(n_f)
    child = np.flatnonzero(tree.parent >= 0)
    assert (pos[tree.parent[child]] < pos[child]).all()  # parents first
    assert len(tree.creases) == n_f - len(np.unique(tree.piece))
    assert np.array_equal(tree.creases, np.sort(tree.crease[child]))
    assign = np.array(fold["edges_assignment"])
    assert (assign[tree.creases] != "B").all()
    assert (tree.goal[assign == "B"] == 0).all()
    np.testing.assert_array_equal(tree.goal, -np.radians(fold["edges_foldAngle"]))
    assert (tree.goal[assign == "M"] > 0).all() and (tree.goal[assign == "V"] < 0).all()
    # axis: the crease's end corners in the parent, a -> b along the parent's CCW order
    ev = np.array(fold["edges_vertices"])
    for f in child:
        a, b = tree.axis[f]
        assert b == (a + 1) % 3
        assert sorted(tree.faces[tree.parent[f], [a, b]]) == sorted(ev[tree.crease[f]])
    assert tree.tol == pytest.approx(1e-7 * tree.scale)


def test_bfs_tree_when_parents_missing(net):
    fold, tree = net
    stripped = {k: v for k, v in fold.items() if k != "polyfold:faces_parent"}
    bfs = fold_tree(stripped)
    np.testing.assert_array_equal(bfs.creases, tree.creases)  # non-B edges are exactly the creases
    X = fold_positions(bfs, bfs.goal)
    for p in np.unique(bfs.piece):
        m = bfs.piece == p
        assert kabsch_error(X[m].reshape(-1, 3), bfs.folded[bfs.faces[m]].reshape(-1, 3)) < 1e-9 * bfs.scale


def test_goal_from_folded_form_when_fold_angles_missing(net):
    fold, tree = net
    stripped = {k: v for k, v in fold.items() if k != "edges_foldAngle"}
    np.testing.assert_allclose(fold_tree(stripped).goal, tree.goal, atol=1e-9)


def test_small_fold_mountain_goes_below():
    tree = fold_tree(small_fold())
    assert tree.goal[2] == pytest.approx(np.pi / 2) and tree.folded is None
    assert tuple(tree.axis[1]) == (2, 0)  # corners of face 0 at vertices 2 -> 0 (CCW in face 0)
    X = fold_positions(tree, tree.goal)
    assert X[1, 2, 2] < -0.5  # vertex 3 moved below the parent's plane (away from the outer side)
    assert not collides(tree, tree.goal)
    q = tree.goal.copy()
    q[2] = np.pi  # folded flat onto the parent: crease pair, never tested
    assert not collides(tree, q)
