"""fold/kinematics.py: forward kinematics (fold_positions over the `forward_kinematics` kernel) on
real nets and a deep chain, and against the independent folding of tests/path_checker.py (itself
checked first: rigid faces, joined creases, no reflections)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from conftest import api_net, kabsch_error, random_q, strip_fold
from path_checker import FoldNet
from polyfold.fold.kinematics import forward_kinematics
from polyfold.fold.tree import fold_positions
from polyfold.formats.fold import fold_tree


def side_lengths(tris):
    return np.linalg.norm(tris - np.roll(tris, -1, axis=-2), axis=-1)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(["uniform", "toward-goal", "discrete"]))
def test_fk_is_rigid_per_face(net, seed, kind):
    fold, tree = net
    q = random_q(tree, np.random.default_rng(seed), kind)
    X = fold_positions(tree, q)
    tol = 1e-10 * tree.scale
    np.testing.assert_allclose(side_lengths(X), side_lengths(tree.flat), atol=tol)  # congruent faces
    # orientation is kept too (a rotation, not a reflection): same normal-vs-corner handedness
    n = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    m = np.cross(tree.flat[:, 1] - tree.flat[:, 0], tree.flat[:, 2] - tree.flat[:, 0])
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), np.linalg.norm(m, axis=1), atol=tol * tree.scale)
    # all corners of one net vertex coincide (crease ends shared by parent and child in particular)
    corners = X.reshape(-1, 3)
    vid = tree.faces.reshape(-1)
    where = np.zeros((vid.max() + 1, 3))
    where[vid] = corners
    assert np.abs(corners - where[vid]).max() < tol
    for f in np.flatnonzero(tree.parent >= 0):
        p = tree.parent[f]
        for k in tree.axis[f]:
            kc = int(np.flatnonzero(tree.faces[f] == tree.faces[p, k])[0])
            assert np.abs(X[f, kc] - X[p, k]).max() < tol
    # every net edge keeps its length
    ev = np.array(fold["edges_vertices"])
    xy = np.array(fold["vertices_coords"], dtype=float)
    np.testing.assert_allclose(np.linalg.norm(where[ev[:, 0]] - where[ev[:, 1]], axis=1),
                               np.linalg.norm(xy[ev[:, 0]] - xy[ev[:, 1]], axis=1), atol=tol)
    # roots never move
    roots = tree.parent < 0
    assert np.array_equal(X[roots], tree.flat[roots])


def test_deep_chain_round_off_stays_far_below_tol():
    tree = fold_tree(strip_fold(500))
    assert len(tree.creases) == 499 and tree.folded is None and (tree.goal == 0).all()
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(5):
        q = np.zeros(tree.n_edges)
        q[tree.creases] = rng.uniform(-np.pi, np.pi, len(tree.creases))
        X = fold_positions(tree, q)
        where = np.zeros((tree.faces.max() + 1, 3))
        where[tree.faces.reshape(-1)] = X.reshape(-1, 3)
        worst = max(worst, np.abs(X - where[tree.faces]).max())
        np.testing.assert_allclose(side_lengths(X), side_lengths(tree.flat), atol=1e-12 * tree.scale)
    assert worst < 1e-6 * tree.tol


def test_fk_reproduces_folded_form(net):
    fold, tree = net
    X = fold_positions(tree, tree.goal)
    for p in np.unique(tree.piece):
        m = tree.piece == p
        err = kabsch_error(X[m].reshape(-1, 3), tree.folded[tree.faces[m]].reshape(-1, 3))
        assert err < 1e-9 * tree.scale
    flat = fold_positions(tree, np.zeros(tree.n_edges))
    assert np.array_equal(flat, tree.flat) and (flat[:, :, 2] == 0).all()


def test_positive_angle_is_mountain(net):
    # a single small positive fold moves the child's subtree below the parent's plane (z < 0)
    _, tree = net
    f = int([g for g in tree.order if tree.parent[g] >= 0][-1])
    q = np.zeros(tree.n_edges)
    q[tree.crease[f]] = 0.3
    X = fold_positions(tree, q)
    other = [k for k in range(3) if tree.faces[f, k] not in tree.faces[tree.parent[f]]]
    assert X[f, other[0], 2] < 0


def test_forward_kinematics_kernel_reuses_buffers(net):
    _, tree = net
    R, T, out = tree.buffers()
    q = random_q(tree, np.random.default_rng(0), "uniform")
    res = forward_kinematics(q, tree.order, tree.parent, tree.crease, tree.axis, tree.flat, R, T, out)
    assert res is out or np.shares_memory(res, out)
    np.testing.assert_array_equal(out, fold_positions(tree, q))
    np.testing.assert_allclose(np.einsum("fij,fkj->fik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)


# ----------------------------------------------------------------------------------------------
# Two implementations of the kinematics agree (hypothesis)


@pytest.fixture(scope="module")
def nets(models_dir) -> list[tuple[dict, FoldNet]]:
    """A one-piece and a five-piece net of horse parts, and a seven-piece torus net (its steepest-edge
    tree, two pieces before, is one piece since its quads are kept whole)."""
    out = []
    for name, method in (("paper-parts/horse/part-3", "auto"), ("paper-parts/horse/part-5", "steepest-edge"),
                         ("torus-8x4-64", "max-perimeter")):
        fold = api_net(models_dir / f"{name}.obj", method)
        out.append((fold, FoldNet(fold)))
    assert out[1][1].n_pieces > 1 and out[2][1].n_pieces > 1
    return out


def _angles(net: FoldNet, values: np.ndarray) -> np.ndarray:
    assert len(values) >= len(net.edges)
    return np.where(net.cut, 0.0, values[: len(net.edges)])


ANGLES = hnp.arrays(np.float64, 300, elements=st.floats(-180.0, 180.0, allow_nan=False))


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 2), values=ANGLES)
def test_independent_folding_preserves_edge_lengths(nets, which, values):
    fold, net = nets[which]
    q = _angles(net, values)
    pos = net.fold(q)  # (F, 3, 3)
    flat = np.zeros((len(net.xy), 3))
    flat[:, :2] = net.xy
    flat = flat[net.faces]
    side = lambda t: np.linalg.norm(t - np.roll(t, -1, axis=-2), axis=-1)
    assert np.abs(side(pos) - side(flat)).max() < 1e-9 * net.scale
    # every net vertex lands at one point: faces joined by creases stay joined
    for v in range(len(net.xy)):
        pts = pos[net.faces == v]
        assert np.abs(pts - pts[0]).max() < 1e-9 * net.scale
    # faces stay proper (no reflection): folded normals agree with the rigid motion of each face
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    area = 0.5 * np.linalg.norm(n, axis=1)
    flat_area = 0.5 * np.cross(flat[:, 1] - flat[:, 0], flat[:, 2] - flat[:, 0])[:, 2]
    assert np.allclose(area, flat_area, rtol=1e-9, atol=1e-12 * net.scale ** 2)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 2), values=ANGLES)
def test_fold_positions_agrees_with_independent_folding(nets, which, values):
    fold, net = nets[which]
    q = _angles(net, values)
    tree = fold_tree(fold)
    theirs = fold_positions(tree, -np.radians(q))
    mine = net.fold(q)
    for k in range(net.n_pieces):
        members = np.flatnonzero(net.piece == k)
        err = kabsch_error(theirs[members].reshape(-1, 3), mine[members].reshape(-1, 3))
        assert err < 1e-9 * net.scale, (k, err)


def test_mountain_goes_below_in_both_implementations():
    """One crease, two triangles: a negative (mountain) FOLD angle turns the child below z = 0."""
    fold = {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3]],
        "edges_vertices": [[0, 1], [1, 2], [2, 0], [2, 3], [3, 0]],
        "edges_assignment": ["B", "B", "M", "B", "B"],
        "edges_foldAngle": [0, 0, -90.0, 0, 0],
    }
    net = FoldNet(fold)
    pos = net.fold(np.array([0, 0, -90.0, 0, 0]))
    assert np.allclose(pos[0, :, 2], 0) and pos[1, 2, 2] < -0.5  # vertex 3 of face 1 went down
    theirs = fold_positions(fold_tree(fold), -np.radians([0, 0, -90.0, 0, 0]))
    assert np.allclose(theirs, pos)
