"""The independent path checker (tests/path_checker.py) itself: its triangle crossing test, and
paths with bad end points or a goal that does not fold into the foldedForm are rejected. (Its
folding is checked in fold/test_kinematics.py.)"""

from __future__ import annotations

import json

import numpy as np

from path_checker import check_path, triangles_cross


def test_triangle_crossing_cases():
    T = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], float)
    cases = {
        "pierced": ([[0.5, 0.5, -1], [0.5, 0.5, 1], [3, 3, 0.5]], True),
        "corner resting on interior": ([[0.5, 0.5, 0], [0.5, 0.5, 1], [1, 0.2, 1]], False),
        "shared edge, folded": ([[0, 0, 0], [2, 0, 0], [1, -1, 1]], False),
        "shared edge, folded flat onto it": ([[0, 0, 0], [2, 0, 0], [0.5, 1, 0]], True),
        "coplanar side by side": ([[2, 0, 0], [0, 2, 0], [2, 2, 0]], False),
        "shared corner, crossing through it": ([[0, 0, 0], [1, 1, 1], [1, 1, -1]], True),
        "shared corner, both straddle, apart": ([[0, 0, 0], [-1, -1, 1], [-1, -1, -1]], False),
        "shared corner, one side": ([[0, 0, 0], [-1, -1, 1], [-1, 1, -1]], False),
        "far above": ([[0, 0, 1], [2, 0, 1], [0, 2, 1]], False),
    }
    A = np.repeat(T[None], len(cases), axis=0)
    B = np.array([c[0] for c in cases.values()], float)
    got = triangles_cross(A, B, 1e-9)
    assert dict(zip(cases, got.tolist())) == {k: v[1] for k, v in cases.items()}
    assert (triangles_cross(B, A, 1e-9) == got).all()  # symmetric


def test_checker_rejects_bad_endpoints(folded_parts):
    _, net, proc = folded_parts["paper-parts/horse/part-0"]
    assert proc.returncode == 0, proc.stderr
    fold = json.loads(net.read_text())
    cut = [e for e, a in enumerate(fold["edges_assignment"]) if a == "B"][0]
    crease = int(np.argmax(np.abs(fold["edges_foldAngle"])))

    def mutated(edit):
        f = json.loads(json.dumps(fold))
        edit(f["polyfold:path"])
        return check_path(f)

    assert not mutated(lambda p: p[0].__setitem__(crease, 1.0)).ok
    assert not mutated(lambda p: p[-1].__setitem__(crease, p[-1][crease] * 0.5)).ok
    assert not mutated(lambda p: p[1].__setitem__(cut, 3.0)).ok
    assert not mutated(lambda p: p.pop()).ok  # stops short of the goal
    f = json.loads(json.dumps(fold))
    f["edges_foldAngle"][crease] *= 0.5  # the goal no longer folds into the foldedForm
    f["polyfold:path"][-1][crease] *= 0.5
    report = check_path(f)
    assert any("foldedForm" in p for p in report.problems), str(report)
