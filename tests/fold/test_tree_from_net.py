"""FoldTree.from_net / from_pattern (stages in memory) give the tree a FOLD file gives, bit for bit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from polyfold.fold.plan import plan_fold
from polyfold.fold.tree import FoldTree
from polyfold.formats.fold import dumps, fold_tree, net_to_fold, pattern_fold
from polyfold.formats.meshes import load_mesh
from polyfold.unfold.pattern import crease_pattern
from polyfold.unfold.search import unfold

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
