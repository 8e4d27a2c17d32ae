"""Corners a builder can fold: a convex polyhedron without corners that crowd each other.

Clipping hulls apart and dropping facets leaves corners a hair apart (a cut passing just beside a
hull vertex makes an edge of 0.08 mm at 150 mm) and slivers of facets (a corner almost on the line
of two others: a face 0.001 mm across), which no one can cut, score or glue. Both are corners
that lie within `min_dist` of the hull of the other corners (a short edge's end is that close to
the other end; the middle corner of a sliver is that close to the segment between its
neighbours), so one rule removes them: drop the corner nearest to the hull of the others, while
that is nearer than `min_dist`. Corners on a cutting plane (`pinned`) are never dropped here:
the face where two parts are glued together is cut from both sides' corners on that plane, and
dropping them independently on the two sides leaves faces that no longer match (the horse lost 5
of its 6 glued faces); those faces are thinned in their plane, both sides alike (`thin_polygon`,
`hulls.match_glued_faces`).

Dropping a corner only shrinks the polyhedron (the hull of fewer points lies inside the hull of
more), so polyhedra that were apart stay apart, and corners on a cutting plane stay on it (the
faces two parts glue together stay in one plane). The surface moves by at most `min_dist` per
corner dropped, inwards; the errors of the result are measured afterwards (`error.part_errors`).

In: points (N, 3) whose hull is the polyhedron. Out: the corners kept (K, 3), K >= 4, and the
largest distance of a dropped corner to the hull of the ones kept after it.
"""

from __future__ import annotations

import numpy as np

from ..mesh.closest import surface_distances


def distance_to_hull_surface(point: np.ndarray, corners: np.ndarray) -> float:
    """Distance from point (3,) to the surface of the convex hull of corners (M, 3) (its qhull
    triangles, `closest.surface_distances`); inf when the corners span no volume (without `point`
    there would be no polyhedron left)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        simplices = ConvexHull(corners).simplices
    except (QhullError, ValueError):
        return np.inf
    return float(surface_distances(point[None, :], corners, simplices)[0])


def thin_polygon(ring: np.ndarray, min_dist: float) -> np.ndarray:
    """A convex polygon (K, 2, in order) without corners within min_dist of the segment between
    their two neighbours (the 2-D case of `drop_crowded_corners`, which the plane of a glued face
    needs: its corners are coplanar): the nearest dropped first, never below a triangle."""
    ring = np.asarray(ring, dtype=np.float64)
    while len(ring) > 3:
        a, b = np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0)
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", ring - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
        near = np.linalg.norm(a + t[:, None] * ab - ring, axis=1)
        i = int(np.argmin(near))
        if near[i] >= min_dist:
            break
        ring = np.delete(ring, i, axis=0)
    return ring


def drop_crowded_corners(points: np.ndarray, min_dist: float, pinned: np.ndarray | None = None
                         ) -> tuple[np.ndarray, float]:
    """(corners kept (K, 3), the largest distance a dropped corner had): the hull's corners, the
    one nearest to the hull of the others dropped while that is under min_dist; pinned (N,) bool
    per point: never dropped (module docstring). A tetrahedron is never reduced further."""
    from scipy.spatial import ConvexHull

    keep = ConvexHull(points).vertices
    corners = points[keep]
    pin = np.zeros(len(corners), dtype=bool) if pinned is None else np.asarray(pinned, dtype=bool)[keep]
    lost = 0.0
    near = np.array([np.inf if pin[i] else distance_to_hull_surface(corners[i], np.delete(corners, i, axis=0))
                     for i in range(len(corners))])
    # a corner's distance only grows as others go (the hull of fewer points lies inside), so the
    # distances found so far are lower bounds: the smallest is measured again before it is dropped
    while len(corners) > 4:
        i = int(np.argmin(near))
        if near[i] >= min_dist:
            break
        now = distance_to_hull_surface(corners[i], np.delete(corners, i, axis=0))
        if now > near[i]:
            near[i] = now
            continue
        lost = max(lost, now)
        corners, near, pin = np.delete(corners, i, axis=0), np.delete(near, i), np.delete(pin, i)
    return corners, lost
