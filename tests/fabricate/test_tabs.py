"""fabricate/tabs.py: a glue tab goes on the other side of the edge when the first is blocked (by
a face or a tab already placed), and on neither when both are."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

from polyfold.fabricate.tabs import TAB_VARIANTS, CutSide, choose_tab


def test_tab_moves_to_the_other_side_when_the_first_is_blocked():
    # two unit-ish triangles 20 mm apart; in front of side 0's edge (y = 0, tab downwards) lies
    # another face of its piece, 0.5 mm away: too close for any tab variant
    tri0 = np.array([[0.0, 0.0], [20.0, 0.0], [10.0, 15.0]])
    tri1 = tri0 + [40.0, 0.0]
    blocker = Polygon([(-5, -0.5), (25, -0.5), (10, -20)])
    bodies = [shapely.union_all([Polygon(tri0), blocker]), Polygon(tri1)]
    side0 = CutSide(0, 0, 0, tri0[0], tri0[1], tri0)
    side1 = CutSide(1, 0, 0, tri1[0], tri1[1], tri1)
    tab = choose_tab((side0, side1), bodies, bodies, [[], []])
    assert tab is not None and tab.side == 1 and tab.variant == 0
    assert tab.polygon[:, 1].max() <= 1e-9  # below the edge, away from its face
    assert np.allclose(tab.polygon[[0, 3]], tri1[:2])
    # nothing in the way: the first side
    free = choose_tab((side0, side1), [Polygon(tri0), Polygon(tri1)], [Polygon(tri0), Polygon(tri1)], [[], []])
    assert free.side == 0
    # a tab already there blocks as a face does
    placed = [[Polygon([(0, 0), (20, 0), (20, -3), (0, -3)])], []]
    assert choose_tab((side0, side1), [Polygon(tri0), Polygon(tri1)], [Polygon(tri0), Polygon(tri1)], placed).side == 1
    # both sides blocked: no tab
    blocker1 = Polygon([(35, -0.5), (65, -0.5), (50, -20)])
    both = [bodies[0], shapely.union_all([Polygon(tri1), blocker1])]
    assert choose_tab((side0, side1), both, both, [[], []]) is None
    assert TAB_VARIANTS[0] == (1.0, 45.0)
