"""collide/triangles.py, the thickness test's quick answers for faces sharing a corner: `_beside`
against an angle oracle, and the whole-face early answer of `_thick_rest` against the definition
(the faces cut to quads away from the shared corner, then crossing or near)."""

import math

import numpy as np

from polyfold.collide.triangles import (_beside, _corner_cut, _thick_rest, face_geometry, faces_cross,
                                        faces_near)


def _tri(p: np.ndarray) -> tuple:
    return tuple(tuple(float(x) for x in row) for row in p)


def _angle_in(lo: float, span: float, x: float) -> float:
    """Signed margin of angle x inside the arc from lo over span (> 0 inside, < 0 outside)."""
    t = (x - lo) % (2 * math.pi)
    if t > math.pi + span / 2:
        t -= 2 * math.pi
    return min(t, span - t)


def test_beside_matches_an_angle_oracle() -> None:
    """b lies in a's plane sharing a's corner j: `_beside` is True exactly when, seen along a's
    normal, neither corner's arc holds a side of the other (cases within 1e-6 rad of a side skipped)."""
    rng = np.random.default_rng(7)
    checked = trues = 0
    for _ in range(3000):
        a = rng.normal(size=(3, 3))
        n = np.cross(a[1] - a[0], a[2] - a[0])
        n /= np.linalg.norm(n)
        j, k = int(rng.integers(3)), int(rng.integers(3))
        b = rng.normal(size=(3, 3))
        b -= np.outer((b - a[0]) @ n, n)
        b[k] = a[j]
        p = a[(j + 1) % 3] - a[j]
        p /= np.linalg.norm(p)
        r = np.cross(n, p)

        def ang(v: np.ndarray) -> float:
            return math.atan2(float(v @ r), float(v @ p))

        e = [ang(a[(j + 1) % 3] - a[j]), ang(a[(j + 2) % 3] - a[j])]
        u = [ang(b[(k + 1) % 3] - a[j]), ang(b[(k + 2) % 3] - a[j])]

        def arc(x: list) -> tuple[float, float]:  # (start, span < pi) of the corner between two sides
            span = (x[1] - x[0]) % (2 * math.pi)
            return (x[0], span) if span <= math.pi else (x[1], 2 * math.pi - span)

        (ea, es), (ua, us) = arc(e), arc(u)
        margins = [_angle_in(ea, es, x) for x in u] + [_angle_in(ua, us, x) for x in e]
        if min(abs(m) for m in margins) < 1e-6:
            continue
        expected = all(m < 0 for m in margins)
        at, bt = _tri(a), _tri(b)
        ga = face_geometry(at, 1e-12)
        d = tuple(float(x) for x in (b - a[0]) @ np.array(ga.u))
        assert _beside(at, ga, bt, 1 << k, d, 1e-9) == expected
        checked += 1
        trues += expected
    assert checked > 2500 and 300 < trues < checked - 300  # both answers well represented


def _by_definition(a: tuple, b: tuple, ma: int, mb: int, tol: float, thick: float, reach: float) -> bool:
    """Faces sharing one corner collide when they cross, or their quads away from it come near."""
    if faces_cross(a, b, face_geometry(a, tol), face_geometry(b, tol), tol):
        return True
    for ta in _corner_cut(a, ma, reach):
        sa = face_geometry(ta, tol)
        for tb in _corner_cut(b, mb, reach):
            sb = face_geometry(tb, tol)
            if not sa.sliver and not sb.sliver and faces_near(ta, tb, sa, sb, thick):
                return True
    return False


def test_early_answer_for_a_shared_corner_not_yet_closed_matches_the_definition() -> None:
    """Two faces sharing a mesh vertex whose copies are still apart (the answer from the whole
    faces) agree with the quad test, near and far, crossing and not."""
    rng = np.random.default_rng(11)
    tol, thick = 1e-9, 0.02
    reach = 10 * thick
    answers = []
    for _ in range(4000):
        a = rng.normal(size=(3, 3))
        b = rng.normal(size=(3, 3)) * rng.uniform(0.3, 1.0) + rng.normal(size=3) * rng.uniform(0.0, 2.0)
        ka, kb = int(rng.integers(3)), int(rng.integers(3))
        b[kb] = a[ka] + rng.normal(size=3) * rng.choice([0.0, 0.01, 0.1, 1.0])  # the corner's copies
        at, bt = _tri(a), _tri(b)
        ga, gb = face_geometry(at, tol), face_geometry(bt, tol)
        if ga.sliver or gb.sliver:
            continue
        got = _thick_rest(at, bt, ga, gb, 1 << ka, 1 << kb, 0, tol, thick, reach)
        assert got == _by_definition(at, bt, 1 << ka, 1 << kb, tol, thick, reach)
        answers.append(got)
    assert 200 < sum(answers) < len(answers) - 200
