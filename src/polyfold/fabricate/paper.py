"""Sizes on paper shared by the sheet code and the front ends, in mm (light: the command line
reads them at start-up)."""

import math

GAP_MM = 3.0  # minimum distance between pieces on a page, tabs included (room for scissors)
FOOTER_MM = 6.0  # strip at the bottom of the printable area for the footer line
FOOTER_FONT_MM = 2.5  # the footer line's font size
BUILDABLE_EDGE_MM = 5.0  # shorter printed edges are hard to cut, fold and glue: make warns


def size_for_edge(size_mm: float, smallest_edge_mm: float, edge_mm: float = BUILDABLE_EDGE_MM) -> int:
    """The --size (mm, rounded up to a whole mm) at which the smallest printed edge, now
    smallest_edge_mm at size_mm, becomes edge_mm (the scale is proportional to the size)."""
    return math.ceil(size_mm * edge_mm / smallest_edge_mm)
