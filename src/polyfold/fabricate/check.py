"""Independent checks of finished sheets (shapely, on the placed geometry), before anything is
written: pieces apart, no overlapping faces or tabs, everything inside the margins."""

from __future__ import annotations

from .pieces import SheetPiece
from .tabs import OVERLAP_MM2


def check_pages(placed: list[SheetPiece], page_index: list[int], n_pages: int,
                box: tuple[float, float, float, float], gap: float) -> dict:
    """Independent checks of the final sheets (shapely), on the placed geometry: no two pieces
    (with their tabs) overlap or come closer than `gap`, no two faces of a piece overlap, no tab
    overlaps a face or another tab, every outline and label lies inside `box` (x0, y0, x1, y1) mm,
    the area available to pieces (inside the margins, above the footer strip, clear of
    registration marks). Returns counts per kind and the problems as text."""
    import shapely
    from shapely.geometry import Polygon

    counts = {"page_overlaps": 0, "net_overlaps": 0, "tab_overlaps": 0, "outside_margins": 0}
    problems: list[str] = []
    x0, y0, x1, y1 = box
    inner = shapely.box(x0, y0, x1, y1).buffer(1e-6)
    for page in range(n_pages):
        on = [p for i, p in enumerate(placed) if page_index[i] == page]
        outlines = [p.footprint for p in on]  # outlines and off-face labels
        for a in range(len(on)):
            for b in range(a + 1, len(on)):
                if outlines[a].distance(outlines[b]) < gap - 1e-6:
                    counts["page_overlaps"] += 1
                    problems.append(f"page {page + 1}: pieces {on[a].name} and {on[b].name} overlap or touch")
        for p in on:
            if not inner.contains(p.footprint):
                counts["outside_margins"] += 1
                problems.append(f"page {page + 1}: piece {p.name} crosses the margin")
            tris = shapely.polygons(p.faces_xy)
            i, j = shapely.STRtree(tris).query(tris, predicate="intersects")
            keep = i < j
            if keep.any():
                bad = int((shapely.area(shapely.intersection(tris[i[keep]], tris[j[keep]])) > OVERLAP_MM2).sum())
                if bad:
                    counts["net_overlaps"] += bad
                    problems.append(f"piece {p.name}: {bad} overlapping face pairs")
            tabs = [Polygon(t) for t in p.tabs]
            for k, t in enumerate(tabs):
                if shapely.area(shapely.intersection(t, p.body)) > OVERLAP_MM2:
                    counts["tab_overlaps"] += 1
                    problems.append(f"piece {p.name}: a tab overlaps a face")
                for u in tabs[k + 1:]:
                    if shapely.area(shapely.intersection(t, u)) > OVERLAP_MM2:
                        counts["tab_overlaps"] += 1
                        problems.append(f"piece {p.name}: two tabs overlap")
            for t in p.texts:
                if not (x0 <= t.x <= x1 and y0 <= t.y <= y1):
                    counts["outside_margins"] += 1
                    problems.append(f"page {page + 1}: a label of piece {p.name} lies outside the margins")
    return {**counts, "problems": problems}
