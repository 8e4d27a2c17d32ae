"""formats/sheet_style.py: text baselines, shared by the SVG, PDF, DXF and PNG writers."""

from __future__ import annotations

import math

import numpy as np

from polyfold.fabricate.page import TextItem
from polyfold.formats import sheet_style


def test_baseline_centres_text_for_any_angle() -> None:
    for angle in (0.0, 30.0, 90.0, -135.0):
        t = TextItem("A", 10.0, 20.0, angle, 4.0, "edge-label")
        bx, by = sheet_style.text_baseline(t)
        a = math.radians(angle)
        reading = np.array([math.cos(a), -math.sin(a)])  # CCW on a y-down page
        off = np.array([bx - 10.0, by - 20.0])
        assert abs(off @ reading) < 1e-12  # shifted across the reading direction only
        assert math.isclose(np.hypot(*off), 0.5 * sheet_style.CAP_HEIGHT * 4.0)
        # Towards the glyphs' bottom: clockwise of the reading direction as seen on screen.
        assert reading[0] * off[1] - reading[1] * off[0] > 0
