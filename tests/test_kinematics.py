"""Folding nets in 3D: forward kinematics and the self-intersection test, on real nets."""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from polyfold.errors import PolyfoldError
from polyfold.formats.fold import net_to_fold
from polyfold.formats.meshes import load_mesh
from polyfold.collide.sweep import first_collision
from polyfold.collide.triangles import triangles_collide
from polyfold.fold.checker import config_collides
from polyfold.fold.kinematics import forward_kinematics
from polyfold.fold.tree import collides, colliding_pairs, fold_positions
from polyfold.formats.fold import fold_tree
from polyfold.unfold.net import Net
from polyfold.unfold.problem import UnfoldProblem
from polyfold.unfold.search import unfold

# (model, unfolding method): single- and multi-piece nets, closed meshes and an open paper part
NETS = [
    ("bunny-128", "auto"),
    ("bunny-128", "steepest-edge"),  # several pieces
    ("paper-parts/bunny-128/part-0", "auto"),
    ("paper-parts/horse/part-5", "steepest-edge"),
    ("dodecahedron-36", "auto"),
    ("torus-8x4-64", "steepest-edge"),
]

_cache: dict = {}


def get_fold(models_dir, name, method="auto", seed=1):
    key = (name, method, seed)
    if key not in _cache:
        loaded = load_mesh(models_dir / f"{name}.obj")
        nets = [unfold(c, method=method, seed=seed)[0] for c in loaded.components]
        _cache[key] = net_to_fold(nets)
    return _cache[key]


@pytest.fixture(scope="module", params=NETS, ids=["-".join(n).replace("/", ":") for n in NETS])
def net(request, models_dir):
    fold = get_fold(models_dir, *request.param)
    return fold, fold_tree(fold)


def side_lengths(tris):
    return np.linalg.norm(tris - np.roll(tris, -1, axis=-2), axis=-1)


def kabsch_error(P, Q):
    """Max distance between P and Q (n, 3) after the best rigid motion of P onto Q."""
    pc, qc = P.mean(axis=0), Q.mean(axis=0)
    U, _, Vt = np.linalg.svd((P - pc).T @ (Q - qc))
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    rot = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return np.linalg.norm((P - pc) @ rot.T + qc - Q, axis=1).max()


def random_q(tree, rng, kind):
    q = np.zeros(tree.n_edges)
    c = tree.creases
    if kind == "uniform":
        q[c] = rng.uniform(-np.pi, np.pi, len(c))
    elif kind == "toward-goal":
        q[c] = rng.uniform(0, 1) * tree.goal[c]
    else:  # discrete: each crease at 0 or its goal (the PRM samples), plus a little noise
        q[c] = rng.integers(0, 2, len(c)) * tree.goal[c] + rng.normal(0, 0.02, len(c))
    return q


# --------------------------------------------------------------------------------------------------
# tree construction
# --------------------------------------------------------------------------------------------------


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


def _small_fold():
    # two triangles joined by a crease (edge 0-2), a mountain of 90 degrees
    return {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3]],
        "edges_vertices": [[0, 1], [1, 2], [2, 0], [2, 3], [3, 0]],
        "edges_assignment": ["B", "B", "M", "B", "B"],
        "edges_foldAngle": [0, 0, -90, 0, 0],
        "polyfold:faces_parent": [-1, 0],
    }


def test_small_fold_mountain_goes_below():
    tree = fold_tree(_small_fold())
    assert tree.goal[2] == pytest.approx(np.pi / 2) and tree.folded is None
    assert tuple(tree.axis[1]) == (2, 0)  # corners of face 0 at vertices 2 -> 0 (CCW in face 0)
    X = fold_positions(tree, tree.goal)
    assert X[1, 2, 2] < -0.5  # vertex 3 moved below the parent's plane (away from the outer side)
    assert not collides(tree, tree.goal)
    q = tree.goal.copy()
    q[2] = np.pi  # folded flat onto the parent: crease pair, never tested
    assert not collides(tree, q)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda f: f.update(faces_vertices=[[0, 1, 2, 3], [0, 2, 3]]), "face 0 is not a triangle"),
        (lambda f: f.update(faces_vertices=[[0, 1, 2], [0, 2, 9]]), "face 1 refers to a vertex"),
        (lambda f: f.update(faces_vertices=[[0, 2, 1], [0, 2, 3]]), "face 0 is clockwise"),
        (lambda f: f["edges_assignment"].__setitem__(2, "B"), "face 1 is joined to its parent face 0 by cut edge 2"),
        (lambda f: f.update({"polyfold:faces_parent": [1, 0]}), "cycle"),
        (lambda f: f.update({"polyfold:faces_parent": [-1, 5]}), "face 1 has invalid parent 5"),
        (lambda f: f.update(edges_vertices=[[0, 1], [1, 2], [2, 0], [2, 3]]), "'edges_assignment' must have one entry"),
        (lambda f: f.update(edges_foldAngle=[0, 0, 90, 0, 0]), "edge 2 is a mountain with fold angle 90"),
        (lambda f: f.update({"polyfold:faces_piece": [0, 1]}), "face 1 (piece 1) has its parent face 0 in piece 0"),
    ],
)
def test_malformed_nets_name_the_problem(edit, message):
    fold = _small_fold()
    edit(fold)
    with pytest.raises(PolyfoldError, match=message.replace("(", r"\(").replace(")", r"\)")) as info:
        fold_tree(fold)
    assert "\n" not in str(info.value)


def test_side_not_an_edge():
    fold = _small_fold()
    fold["edges_vertices"] = [[0, 1], [1, 2], [2, 0], [2, 3], [3, 1]]
    with pytest.raises(PolyfoldError, match="side 3-0 of face 1 is not in 'edges_vertices'"):
        fold_tree(fold)


# --------------------------------------------------------------------------------------------------
# forward kinematics
# --------------------------------------------------------------------------------------------------


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


def strip_fold(n_faces):
    """A zigzag strip of n_faces unit triangles: a chain n_faces deep (tree built by BFS)."""
    xy = [[i / 2, i % 2] for i in range(n_faces + 2)]
    faces = [[i, i + 2, i + 1] if i % 2 == 0 else [i, i + 1, i + 2] for i in range(n_faces)]
    edges = [[i, i + 1] for i in range(n_faces + 1)] + [[i, i + 2] for i in range(n_faces)]
    assign = ["B"] + ["F"] * (n_faces - 1) + ["B"] + ["B"] * n_faces
    return {"vertices_coords": xy, "faces_vertices": faces, "edges_vertices": edges, "edges_assignment": assign}


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


# --------------------------------------------------------------------------------------------------
# triangle-triangle test
# --------------------------------------------------------------------------------------------------


def _orient(a, b, c, d):
    """Exact sign of det(b - a, c - a, d - a) (Fractions of the float inputs)."""
    a, b, c, d = ([Fraction(float(x)) for x in p] for p in (a, b, c, d))
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    w = [d[i] - a[i] for i in range(3)]
    det = (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] + (u[0] * v[1] - u[1] * v[0]) * w[2]
    return (det > 0) - (det < 0)


def segment_crosses_triangle(p, q, t):
    """Exact: segment pq crosses the interior of triangle t (general position)."""
    if _orient(t[0], t[1], t[2], p) * _orient(t[0], t[1], t[2], q) >= 0:
        return False
    s = [_orient(p, q, t[k], t[(k + 1) % 3]) for k in range(3)]
    return all(x > 0 for x in s) or all(x < 0 for x in s)


def oracle_general_position(a, b):
    return any(segment_crosses_triangle(a[k], a[(k + 1) % 3], b) for k in range(3)) or any(
        segment_crosses_triangle(b[k], b[(k + 1) % 3], a) for k in range(3)
    )


def test_triangles_collide_matches_segment_oracle():
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(3000):
        a = rng.uniform(-1, 1, (3, 3))
        b = rng.uniform(-1, 1, (3, 3)) * rng.uniform(0.2, 1.5) + rng.uniform(-0.5, 0.5, 3)
        expected = oracle_general_position(a, b)
        hits += expected
        assert triangles_collide(a, b, 1e-12) == expected
        assert triangles_collide(b, a, 1e-12) == expected
        assert triangles_collide(a[::-1].copy(), b[[1, 2, 0]].copy(), 1e-12) == expected
    assert 300 < hits < 2700  # both verdicts well represented


def relint_oracle(a, b):
    """Exact semantics on non-degenerate triangles: the relative interiors meet, i.e. some point is
    a strictly positive convex combination of both (LP: maximise the smallest weight)."""
    # variables: lambda (3), mu (3), t; maximise t; lambda_i >= t, mu_j >= t
    A_eq = np.zeros((5, 7))
    A_eq[0:3, 0:3] = a.T
    A_eq[0:3, 3:6] = -b.T
    A_eq[3, 0:3] = 1
    A_eq[4, 3:6] = 1
    A_ub = np.zeros((6, 7))
    A_ub[:, :6] = -np.eye(6)
    A_ub[:, 6] = 1
    res = linprog(c=[0, 0, 0, 0, 0, 0, -1], A_ub=A_ub, b_ub=np.zeros(6), A_eq=A_eq, b_eq=[0, 0, 0, 1, 1],
                  bounds=[(0, 1)] * 6 + [(None, 1)], method="highs")
    return res.status == 0 and -res.fun > 1e-7


grid_point = st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 2))
grid_tri = st.lists(grid_point, min_size=3, max_size=3)


@settings(max_examples=1500, deadline=None)
@given(grid_tri, grid_tri)
def test_triangles_collide_matches_relint_oracle_on_grid(t1, t2):
    # Integer grids make every kind of contact common: shared vertices and edges, coplanar pairs,
    # vertices on faces, edges through edges.
    a = np.array(t1, dtype=np.float64)
    b = np.array(t2, dtype=np.float64)
    nonzero = lambda t: np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) > 0
    if not (nonzero(a) and nonzero(b)):
        assert not triangles_collide(a, b, 1e-9)  # degenerate triangles never collide
        return
    assert triangles_collide(a, b, 1e-9) == relint_oracle(a, b)


A = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
TOUCHING = {
    "shared vertex, rotated away": np.array([[0.0, 0, 0], [-1, 0.2, 0.5], [0.1, -1, 0.3]]),
    "shared vertex, edge through the other's vertex region": np.array([[0.0, 0, 0], [-1, -1, 0.5], [-1, -1, -0.5]]),
    "shared edge, dihedral 90": np.array([[1.0, 0, 0], [0, 0, 0], [0.3, 0, -0.8]]),
    "shared edge, folded over": np.array([[1.0, 0, 0], [0, 0, 0], [0.3, 0.4, 0.1]]),
    "coplanar, shared edge": np.array([[1.0, 0, 0], [0, 0, 0], [0.5, -1, 0]]),
    "coplanar, shared vertex": np.array([[0.0, 0, 0], [-1, 0, 0], [0, -1, 0]]),
    "coplanar, hypotenuse contact": np.array([[1.0, 0, 0], [1, 1, 0], [0, 1, 0]]),
    "vertex on the interior": np.array([[0.2, 0.2, 0], [0.5, 0.5, 1], [0, 0.5, 1]]),
    "edge lying on the face": np.array([[0.1, 0.1, 0], [0.6, 0.2, 0], [0.3, 0.3, 0.7]]),
    "apart": np.array([[0.0, 0, 0.1], [1, 0, 0.1], [0, 1, 0.1]]),
    "degenerate crossing segment": np.array([[0.2, 0.2, -1], [0.2, 0.2, 1], [0.2, 0.2, 0.5]]),
}
CROSSING = {
    "shared vertex, passing through": np.array([[0.0, 0, 0], [0.5, 0.3, 1], [0.3, 0.5, -1]]),
    "coplanar overlap": np.array([[0.2, 0.2, 0], [1.2, 0.2, 0], [0.2, 1.2, 0]]),
    "coplanar, same triangle": A.copy(),
    "coplanar, contained": np.array([[0.1, 0.1, 0], [0.3, 0.1, 0], [0.1, 0.3, 0]]),
    "piercing": np.array([[0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.3, 1]]),
    "interlocked (each pierces the other)": np.array([[0.5, 0.2, -0.5], [0.5, 0.2, 0.5], [2, 0.2, 0]]),
    "edges cross, interiors cross": np.array([[0.5, -0.5, 0.5], [0.5, 0.5, -0.5], [0.2, 0.3, 0]]),
}


@pytest.mark.parametrize("name", TOUCHING)
def test_touching_is_not_a_collision(name):
    b = TOUCHING[name]
    for tol in (0.0, 1e-9):
        assert not triangles_collide(A, b, tol) and not triangles_collide(b, A, tol)
    # round-off noise well below tol must not turn contact into a collision
    rng = np.random.default_rng(1)
    for _ in range(20):
        assert not triangles_collide(A + rng.normal(0, 1e-12, (3, 3)), b + rng.normal(0, 1e-12, (3, 3)), 1e-9)


@pytest.mark.parametrize("name", CROSSING)
def test_crossing_is_a_collision(name):
    b = CROSSING[name]
    assert triangles_collide(A, b, 1e-9) and triangles_collide(b, A, 1e-9)


def test_hinged_pair_touches_unless_folded_flat_onto_each_other():
    # B hinged on A's edge y = 0: its plane meets A's plane only along the hinge, so the pair only
    # touches at every fold angle except 180 degrees, where B lies on A (coplanar overlap)
    for deg in (-170, -90, -10, 10, 90, 170, 179, 181, 190, 300):
        th = np.radians(deg)
        b = np.array([[1.0, 0, 0], [0, 0, 0], [0.3, -0.6 * np.cos(th), -0.6 * np.sin(th)]])
        assert not triangles_collide(A, b, 1e-9), deg
    b = np.array([[1.0, 0, 0], [0, 0, 0], [0.3, 0.6, 0.0]])
    assert triangles_collide(A, b, 1e-9)


# --------------------------------------------------------------------------------------------------
# broad phase and whole configurations
# --------------------------------------------------------------------------------------------------


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


def test_forward_kinematics_kernel_reuses_buffers(net):
    _, tree = net
    R, T, out = tree.buffers()
    q = random_q(tree, np.random.default_rng(0), "uniform")
    res = forward_kinematics(q, tree.order, tree.parent, tree.crease, tree.axis, tree.flat, R, T, out)
    assert res is out or np.shares_memory(res, out)
    np.testing.assert_array_equal(out, fold_positions(tree, q))
    np.testing.assert_allclose(np.einsum("fij,fkj->fik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)


# --------------------------------------------------------------------------------------------------
# the dodecahedron: faces that only share a vertex of the folded mesh do cross
# --------------------------------------------------------------------------------------------------

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
