"""collide/triangles.py: the 3D triangle pair test `triangles_collide` against exact oracles
(segment crossings in rational arithmetic, an LP for meeting relative interiors), and touching
versus crossing cases (contact is not a collision)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from conftest import oracle_general_position
from polyfold.collide.triangles import triangles_collide


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
