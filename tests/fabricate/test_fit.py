"""fabricate/fit.py: the smallest printed edge and face of a model at its printed scale, and
(fabricate/paper.py) the --size that makes the smallest edge buildable. (Splitting nets to fit
the page: test_sheet.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

from polyfold.fabricate.fit import smallest_printed
from polyfold.fabricate.paper import BUILDABLE_EDGE_MM, size_for_edge
from polyfold.mesh.mesh import Mesh


def test_smallest_printed_edge_and_face_height():
    # a right tetrahedron with legs 1, 2, 3: shortest edge 1; the narrowest face is the one with
    # legs 1 and 2 (height 2 / sqrt(5) over its hypotenuse sqrt(5))
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    edge, face = smallest_printed(Mesh(v, f), 10.0)
    assert edge == pytest.approx(10.0)
    heights = []
    for tri in v[f]:
        sides = np.linalg.norm(tri - np.roll(tri, -1, axis=0), axis=1)
        area = 0.5 * np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0]))
        heights.append(2 * area / sides.max())
    assert face == pytest.approx(10.0 * min(heights))
    assert face == pytest.approx(10.0 * 2 / math.sqrt(5))


def test_size_for_edge_rounds_up():
    assert size_for_edge(150.0, 4.9) == 154  # 150 * 5 / 4.9 = 153.06
    assert size_for_edge(100.0, 2.5) == 200 == 100.0 * BUILDABLE_EDGE_MM / 2.5
    assert size_for_edge(150.0, 1.0, edge_mm=3.0) == 450
