"""Glue tabs: the one routine that puts a trapezoid on one side of a glued cut edge.

In: the two sides (`CutSide`) of a cut edge in mm (y down), the faces of each piece and the tabs
already on it. Out: the `Tab` (which side, its polygon, its height), or None when no variant has
room on either side.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

TAB_MAX_MM = 6.0  # full tab height
TAB_REL = 0.4  # tab height as a fraction of its edge length (before the cap)
TAB_MIN_MM = 1.0  # smaller tabs are useless: no tab instead
OVERLAP_MM2 = 1e-4  # intersections below this area (0.01 x 0.01 mm) are touching, not overlap

# (height factor, side angle) in order of preference: full 45-degree trapezoids first, then flatter
# and lower ones that fit into the notches of a net
TAB_VARIANTS = ((1.0, 45.0), (1.0, 30.0), (0.6, 30.0), (0.6, 18.0), (0.35, 18.0), (0.35, 10.0))


@dataclass(frozen=True, eq=False)
class CutSide:
    """One side of a cut edge: edge k (corners k, k+1) of face `face` of piece `piece`, its ends
    p0 -> p1 and the face's triangle `tri` (3, 2), all in mm."""

    piece: int
    face: int
    k: int
    p0: np.ndarray
    p1: np.ndarray
    tri: np.ndarray


@dataclass(frozen=True, eq=False)
class Tab:
    """The tab of a glued edge: on `sides[side]`, trapezoid `polygon` (4, 2) = (base start, top,
    top, base end), `height` mm, made with TAB_VARIANTS[variant] (0: full size)."""

    side: int
    polygon: np.ndarray
    height: float
    variant: int


def overlap(a, b, prepared_b=None) -> bool:
    """True when polygons a and b share more than OVERLAP_MM2 of area (touching is fine)."""
    import shapely

    if not (prepared_b or b).intersects(a):
        return False
    return shapely.area(shapely.intersection(a, b)) > OVERLAP_MM2


def tab_polygon(side: CutSide, factor: float, side_deg: float) -> np.ndarray | None:
    """Trapezoid on the outer side of the cut edge: height factor * min(TAB_REL * length, TAB_MAX_MM),
    sides at `side_deg` to the base (a flatter side slips into a narrow notch of the net)."""
    d = side.p1 - side.p0
    length = math.hypot(d[0], d[1])
    if length < 1e-9:
        return None
    u = d / length
    n = np.array([-u[1], u[0]])
    if np.dot(side.tri.mean(axis=0) - side.p0, n) > 0:
        n = -n  # away from the face
    h = min(TAB_REL * length, TAB_MAX_MM) * factor
    inset = h / math.tan(math.radians(side_deg))
    if 2 * inset > 0.9 * length:  # the sides would cross: lower the tab so its top keeps 10 %
        inset = 0.45 * length
        h = inset * math.tan(math.radians(side_deg))
    if h < TAB_MIN_MM:
        return None
    return np.array([side.p0, side.p0 + u * inset + n * h, side.p1 - u * inset + n * h, side.p1])


def choose_tab(sides: tuple[CutSide, CutSide], bodies: Sequence, prepared: Sequence,
               piece_tabs: Sequence[list]) -> Tab | None:
    """The tab of a glued pair: a trapezoid on the first side; if it would overlap a face
    (bodies[piece], shapely; prepared[piece] its prepared form) or a tab already on that piece
    (piece_tabs[piece], shapely Polygons), the other side; then both sides again with the lower /
    flatter TAB_VARIANTS. A tab may touch faces and tabs (its fold line, corners) but not share
    more than OVERLAP_MM2 of area with them. None when nothing fits."""
    from shapely.geometry import Polygon

    for variant, (factor, side_deg) in enumerate(TAB_VARIANTS):
        for s, side in enumerate(sides):
            poly = tab_polygon(side, factor, side_deg)
            if poly is None:
                continue
            tab = Polygon(poly)
            if not tab.is_valid or overlap(tab, bodies[side.piece], prepared[side.piece]):
                continue
            if any(overlap(tab, t) for t in piece_tabs[side.piece]):
                continue
            height = float(np.linalg.norm((poly[1] + poly[2]) / 2 - (poly[0] + poly[3]) / 2))
            return Tab(s, poly, height, variant)
    return None
