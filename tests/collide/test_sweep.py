"""collide/sweep.py: the one plain sort-and-sweep (`sweep_pairs`) against an O(n^2) reference on
real meshes, and the broad phase of the fold reports (`first_collision`, `all_collisions`) against
all pairs on folded nets: which pairs are skipped (crease pairs only; faces that share just a
vertex of the folded mesh do cross)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MESHES, oracle_general_position, random_q, reference, strip_fold
from polyfold.collide.self_intersect import face_triangles, self_intersections
from polyfold.collide.sweep import NO_LIMIT, all_collisions, first_collision, sweep_pairs
from polyfold.collide.triangles import triangles_collide
from polyfold.fold.checker import config_collides
from polyfold.fold.tree import collides, colliding_pairs, fold_positions
from polyfold.formats.fold import fold_tree, net_to_fold
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh
from polyfold.unfold.net import Net
from polyfold.unfold.problem import UnfoldProblem
from polyfold.unfold.search import unfold


def swept(tris, tol, piece=None, parent=None, faces=None, keys=None, stop_after=NO_LIMIT, room=None):
    """(count, pairs in sweep order) of sweep_pairs, room rows for the pairs (default: all)."""
    if room is None:
        room = sweep_pairs(tris, tol, piece, parent, faces, keys, NO_LIMIT, np.empty((0, 2), np.int64))
    pairs = np.empty((room, 2), dtype=np.int64)
    count = sweep_pairs(tris, tol, piece, parent, faces, keys, stop_after, pairs)
    return count, [tuple(p) for p in pairs[: min(count, room)].tolist()]


def doubled(mesh: Mesh) -> np.ndarray:
    """The faces' triangles and a shrunk, shifted copy of them: many crossing pairs."""
    tris = face_triangles(mesh.vertices, mesh.faces)
    shift = 0.013 * mesh.bbox_diagonal
    return np.ascontiguousarray(np.concatenate([tris, tris * 0.97 + shift]))


@pytest.mark.parametrize("name", MESHES)
def test_fold_rule_matches_the_reference(meshes: dict, name: str) -> None:
    tris = doubled(meshes[name])
    n = len(tris)
    rng = np.random.default_rng(n)
    for piece, parent in [(np.zeros(n, np.int64), np.full(n, -1)),
                          (rng.integers(0, 2, n), rng.integers(-1, n, n))]:
        for tol in (1e-9, 1e-3 * meshes[name].bbox_diagonal):
            expected = reference(tris, tol, piece=piece, parent=parent)
            count, pairs = swept(tris, tol, piece=piece, parent=parent)
            assert count == len(expected) > 0
            assert sorted(pairs) == expected
            # the reports: the same pairs in the same (sweep) order, the first one first
            total, reported = all_collisions(tris, parent, piece, tol, count)
            assert total == count and [tuple(p) for p in reported.tolist()] == pairs
            assert tuple(first_collision(tris, parent, piece, tol)) == pairs[0]


def test_stopping_and_room(meshes: dict) -> None:
    tris = doubled(meshes["bunny-348.obj"])
    count, pairs = swept(tris, 1e-9)
    assert count > 10
    for stop in (1, 2, 7, count, count + 5):
        got, head = swept(tris, 1e-9, stop_after=stop)
        assert got == min(stop, count) and head == pairs[:got]  # the first hits, then stop
    got, head = swept(tris, 1e-9, room=3)
    assert got == count and head == pairs[:3]  # counts them all, writes what fits
    assert swept(tris, 1e-9, room=0) == (count, [])


def test_no_faces() -> None:
    tris = np.empty((0, 3, 3))
    assert swept(tris, 1e-9) == (0, [])
    assert self_intersections(Mesh(np.empty((0, 3)), np.empty((0, 3), np.int64))).shape == (0, 2)


# ----------------------------------------------------------------------------------------------
# broad phase and whole configurations (the `net` fixture: nets of real models)


def brute_force_pairs(tris, parent, piece, tol, skip=None):
    pairs = []
    for i in range(len(tris)):
        for j in range(i + 1, len(tris)):
            if piece[i] != piece[j] or parent[i] == j or parent[j] == i:
                continue
            if skip is not None and skip(i, j):
                continue
            if triangles_collide(tris[i], tris[j], tol):
                pairs.append((i, j))
    return pairs


def test_first_collision_agrees_with_all_pairs(net):
    _, tree = net
    rng = np.random.default_rng(3)
    R, T, out = tree.buffers()
    verdicts = set()
    for s in range(12):
        q = random_q(tree, rng, ["uniform", "toward-goal", "discrete"][s % 3])
        X = fold_positions(tree, q)
        expected = brute_force_pairs(X, tree.parent, tree.piece, tree.tol)
        i, j = first_collision(X, tree.parent, tree.piece, tree.tol)
        assert (i >= 0) == bool(expected)
        if i >= 0:
            assert (i, j) in expected
        assert [tuple(p) for p in colliding_pairs(tree, q)] == expected
        got = config_collides(q, tree.order, tree.parent, tree.crease, tree.axis, tree.flat, tree.piece, tree.tol, R, T, out)
        assert got == bool(expected) == collides(tree, q)
        assert np.array_equal(out, X)
        verdicts.add(bool(expected))
    assert verdicts == {False, True}  # both verdicts exercised
    assert not collides(tree, np.zeros(tree.n_edges))  # the flat net is overlap-free
    assert not collides(tree, tree.goal)  # and so is the folded part (no self-intersections)


def test_first_collision_agrees_with_all_pairs_on_a_long_strip():
    tree = fold_tree(strip_fold(300))
    rng = np.random.default_rng(11)
    verdicts = set()
    for spread in (0.01, 0.05, 0.2, 0.5, 1.0, 3.0):
        q = np.zeros(tree.n_edges)
        q[tree.creases] = rng.normal(0.0, spread, len(tree.creases))
        X = fold_positions(tree, q)
        expected = brute_force_pairs(X, tree.parent, tree.piece, tree.tol)
        assert (first_collision(X, tree.parent, tree.piece, tree.tol)[0] >= 0) == bool(expected)
        assert [tuple(p) for p in colliding_pairs(tree, q)] == expected
        verdicts.add(bool(expected))
    assert verdicts == {False, True}


# ----------------------------------------------------------------------------------------------
# the dodecahedron: faces that only share a vertex of the folded mesh do cross


# Creases (mesh edge ids of dodecahedron-36) of the net unfold(seed=4) produced when this test was
# written; used when none of the seeds tried reproduces such a case (the unfolder may change).
DODECA_CREASES = [1, 2, 3, 4, 6, 8, 9, 10, 13, 14, 15, 17, 19, 20, 21, 22, 24, 27, 28, 30, 33, 34, 35, 37, 38, 39,
                  40, 42, 43, 44, 45, 47, 48, 49, 53]


def _sweep_for_vertex_crossing(fold):
    """First state on the straight line flat -> goal (1 degree steps) where the net collides but a
    lenient test skipping every pair that shares a folded-mesh vertex finds nothing."""
    tree = fold_tree(fold)
    mesh_v = np.asarray(fold["polyfold:vertices_meshVertex"])[tree.faces]
    shares = lambda i, j: bool(set(mesh_v[i]) & set(mesh_v[j]))
    steps = int(np.ceil(np.degrees(np.abs(tree.goal).max())))
    for s in range(steps + 1):
        q = s / steps * tree.goal
        if not collides(tree, q):
            continue
        X = fold_positions(tree, q)
        if not brute_force_pairs(X, tree.parent, tree.piece, tree.tol, skip=shares):
            return tree, q, X, mesh_v
    return None


def test_dodecahedron_faces_sharing_a_vertex_cross(models_dir):
    mesh = load_mesh(models_dir / "dodecahedron-36.obj").components[0]
    found = None
    for seed in range(1, 11):
        net_, _ = unfold(mesh, seed=seed)
        found = _sweep_for_vertex_crossing(net_to_fold([net_]))
        if found:
            break
    if found is None:
        problem = UnfoldProblem.from_mesh(mesh)
        w = np.ones(mesh.topology.n_edges)
        w[DODECA_CREASES] = 0.0
        parent, parent_edge, order, coords = problem.decode(w)
        net_ = Net(mesh=mesh, parent=parent, parent_edge=parent_edge, order=order, coords=coords,
                   piece=np.zeros(mesh.n_faces, dtype=np.int64))
        found = _sweep_for_vertex_crossing(net_to_fold([net_]))
    assert found is not None
    tree, q, X, mesh_v = found
    assert collides(tree, q)
    lenient = brute_force_pairs(X, tree.parent, tree.piece, tree.tol,
                                skip=lambda i, j: bool(set(mesh_v[i]) & set(mesh_v[j])))
    assert lenient == []  # a test that skips vertex-sharing pairs misses the crossing
    pairs = colliding_pairs(tree, q)
    for i, j in pairs:
        # not crease pairs, share a vertex of the folded mesh, and really cross (exact oracle)
        assert tree.parent[i] != j and tree.parent[j] != i
        assert set(mesh_v[i]) & set(mesh_v[j])
        assert oracle_general_position(X[i], X[j])
    # the goal itself is reached without crossings: the straight path is not free, the end is
    assert not collides(tree, tree.goal)
