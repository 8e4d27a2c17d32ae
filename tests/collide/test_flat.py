"""collide/flat.py: the numba 2D overlap test (`triangles_overlap`, `find_overlaps`) against an
exact brute-force oracle (rational clipping)."""

from fractions import Fraction

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from polyfold.collide.flat import find_overlaps, triangles_overlap


def _clip(poly, a, b):
    """Sutherland-Hodgman: keep the part of `poly` left of the directed line a->b (exact)."""
    out = []
    side = lambda p: (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        sp, sq = side(p), side(q)
        if sp >= 0:
            out.append(p)
        if (sp > 0 > sq) or (sp < 0 < sq):
            t = sp / (sp - sq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def _area(poly):
    return sum(poly[i][0] * poly[(i + 1) % len(poly)][1] - poly[(i + 1) % len(poly)][0] * poly[i][1]
               for i in range(len(poly))) / 2


def oracle_overlap(t1, t2) -> bool:
    """Interiors intersect <=> the exact intersection polygon has positive area."""
    t1 = [tuple(map(Fraction, p)) for p in t1]
    t2 = [tuple(map(Fraction, p)) for p in t2]
    if _area(t1) == 0 or _area(t2) == 0:
        return False  # a degenerate triangle has no interior
    if _area(t1) < 0:
        t1 = t1[::-1]
    poly = t2 if _area(t2) > 0 else t2[::-1]
    for i in range(3):
        poly = _clip(poly, t1[i], t1[(i + 1) % 3])
        if len(poly) < 3:
            return False
    return _area(poly) > 0


grid_tri = st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=3, max_size=3)


@settings(max_examples=3000, deadline=None)
@given(grid_tri, grid_tri)
def test_matches_exact_oracle_on_small_grid(t1, t2):
    # Small integer grids make touching (shared edges, vertices, collinear sides) very common, and
    # all arithmetic of the kernel is exact there, so tol = 0 must agree with the oracle exactly.
    a = np.array(t1, dtype=np.float64)
    b = np.array(t2, dtype=np.float64)
    assert triangles_overlap(a, b, 0.0) == oracle_overlap(t1, t2)


def test_random_float_triangles_against_oracle():
    rng = np.random.default_rng(7)
    disagreements = 0
    for _ in range(3000):
        a = rng.random((3, 2))
        b = rng.random((3, 2)) * 0.8 + 0.2
        disagreements += triangles_overlap(a, b, 0.0) != oracle_overlap(a.tolist(), b.tolist())
    assert disagreements == 0


def test_touching_is_not_overlap():
    a = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert not triangles_overlap(a, np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), 1e-12)  # shared edge
    assert not triangles_overlap(a, np.array([[1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]), 1e-12)  # shared vertex
    assert not triangles_overlap(a, np.array([[0.5, 0.0], [1.5, 0.0], [1.0, -1.0]]), 1e-12)  # collinear side
    assert triangles_overlap(a, np.array([[0.2, 0.2], [2.0, 0.2], [0.2, 2.0]]), 1e-12)  # corner inside
    assert triangles_overlap(a, a.copy(), 1e-12)  # identical


def test_sweep_finds_all_pairs_of_brute_force():
    rng = np.random.default_rng(3)
    for n in (5, 40, 200):
        tris = rng.random((n, 1, 2)) * 10 + rng.random((n, 3, 2)) - 0.5
        parent = np.full(n, -1)
        got = {tuple(p) for p in find_overlaps(tris, parent, 0.0)}
        want = {(i, j) for i in range(n) for j in range(i + 1, n) if oracle_overlap(tris[i].tolist(), tris[j].tolist())}
        assert got == want


def test_every_pair_of_a_crowded_net_in_one_sweep_as_counted_and_capped():
    """`all_overlapping_pairs` collects in one sweep, its buffer doubling past 64 pairs: on
    triangles crowded into a small square (hundreds of pairs: three doublings), the oracle's pairs, as many as
    the counting sweep (max_pairs 0) counts, and the capped sweep's pairs are its first ones."""
    from polyfold.collide.flat import overlapping_pairs

    rng = np.random.default_rng(11)
    n = 120
    tris = rng.random((n, 1, 2)) * 3 + rng.random((n, 3, 2)) - 0.5
    parent = np.full(n, -1, dtype=np.int64)
    every = find_overlaps(tris, parent, 0.0)
    want = {(i, j) for i in range(n) for j in range(i + 1, n) if oracle_overlap(tris[i].tolist(), tris[j].tolist())}
    assert len(want) > 256 and {tuple(p) for p in every} == want and len(every) == len(want)
    count, none = overlapping_pairs(tris, parent, 0.0, 0)
    assert count == len(want) and len(none) == 0
    count, first = overlapping_pairs(tris, parent, 0.0, 100)
    assert count == len(want) and np.array_equal(first, every[:100])


def test_crease_pairs_are_skipped():
    a = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    tris = np.stack([a, a + 0.1])
    assert len(find_overlaps(tris, np.array([-1, -1]))) == 1
    assert len(find_overlaps(tris, np.array([-1, 0]))) == 0


def test_pairs_between_two_sets_are_the_brute_force_pairs_across():
    """`overlapping_pairs_between` (the grid of the smaller set) finds exactly the oracle's
    overlapping pairs with one face in each set: random triangles of mixed sizes (the grid's cell
    follows the smaller set), sets of every proportion, some crease pairs skipped."""
    from polyfold.collide.flat import face_bounds, overlapping_pairs_between

    rng = np.random.default_rng(5)
    for n, share in ((30, 0.5), (120, 0.1), (120, 0.9), (200, 0.02), (60, 1.0)):
        scale = np.where(rng.random(n) < 0.2, 4.0, 1.0)[:, None, None]
        tris = rng.random((n, 1, 2)) * 12 + (rng.random((n, 3, 2)) - 0.5) * scale
        parent = np.where(rng.random(n) < 0.3, rng.integers(0, n, n), -1)
        bounds = [np.empty(n) for _ in range(4)]
        face_bounds(tris, np.arange(n), *bounds)
        in_a = rng.random(n) < share
        a, b = np.flatnonzero(in_a), np.flatnonzero(~in_a)
        got = overlapping_pairs_between(tris, parent, a, b, *bounds, 0.0, np.int64(2**62))
        assert len({tuple(p) for p in got}) == len(got)  # each pair once
        want = {(min(i, j), max(i, j)) for i in a for j in b
                if parent[i] != j and parent[j] != i and oracle_overlap(tris[i].tolist(), tris[j].tolist())}
        assert {tuple(p) for p in got} == want and (len(want) > 0 or len(a) in (0, n))
        for limit in (1, 3, len(want)):  # the first `limit` of them, then it stops
            some = overlapping_pairs_between(tris, parent, a, b, *bounds, 0.0, np.int64(limit))
            assert len(some) == min(limit, len(want)) and {tuple(p) for p in some} <= want
