"""Boxes on shelves: the one simple packing (a crease pattern's pieces, the unfold sheet, and
the page packer's fallback when its time runs out). Plain Python: a handful of boxes.
"""

from __future__ import annotations

from collections.abc import Sequence


def shelf_offsets(sizes: Sequence[Sequence[float]], width: float, height: float,
                  gap: float) -> list[tuple[int, float, float]]:
    """Boxes `sizes` (n, 2) = (width, height) on shelves: tallest first (ties in input order),
    left to right in rows no wider than `width` (a box wider than that gets a row of its own),
    boxes and rows `gap` apart, a new page when a row would pass `height` (math.inf: one page).
    Returns (page, x, y) of each box's min corner, in input order."""
    order = sorted(range(len(sizes)), key=lambda j: (-sizes[j][1], j))
    out: list[tuple[int, float, float]] = [(0, 0.0, 0.0)] * len(sizes)
    page, x, y, shelf_h = 0, 0.0, 0.0, 0.0
    for j in order:
        bw, bh = sizes[j]
        if x > 0 and x + bw > width:
            x, y, shelf_h = 0.0, y + shelf_h + gap, 0.0
        if y > 0 and y + bh > height:
            page, x, y, shelf_h = page + 1, 0.0, 0.0, 0.0
        out[j] = (page, x, y)
        x, shelf_h = x + (bw + gap), max(shelf_h, bh)
    return out
