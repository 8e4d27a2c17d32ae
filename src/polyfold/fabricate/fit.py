"""Splitting a net to fit a page: cut creases until every piece, with room for its tabs, fits.

Cutting creases never moves a face, so the pieces stay overlap-free.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import PolyfoldError
from ..mesh.geometry import face_areas
from ..mesh.mesh import Mesh
from ..unfold.net import Net, cut_creases, subtree_areas
from .pack import fits_page
from .tabs import TAB_MAX_MM

MAX_PEEL_TRIES = 64


class PieceTooLarge(PolyfoldError):
    """A single face (with room for its tabs) does not fit the page; `factor` is the largest
    scale factor of the model at which it would."""

    def __init__(self, face: int, factor: float) -> None:
        super().__init__(f"face {face} alone does not fit the page with its tabs (fits at {factor:.3f} times the size)")
        self.face = face
        self.factor = factor


def _hull_scale(points_mm: np.ndarray, page_size, margin: float, pad: float) -> float:
    """Largest scale at which the convex hull of the points, grown by `pad` mm, fits the page."""
    import shapely

    hull = shapely.convex_hull(shapely.multipoints(points_mm)).buffer(pad, quad_segs=2)
    return fits_page(hull, page_size, margin)


def smallest_printed(mesh: Mesh, scale: float) -> tuple[float, float]:
    """(shortest edge, smallest face height) of the mesh's faces printed at `scale` mm per model
    unit, in mm. A face's smallest height is twice its area over its longest side: the width of
    the narrowest strip of paper it makes (0 for a degenerate face)."""
    tri = mesh.vertices[mesh.faces]
    sides = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)
    heights = 2.0 * face_areas(mesh.vertices, mesh.faces) / np.maximum(sides.max(axis=1), 1e-300)
    return float(sides.min()) * scale, float(heights.min()) * scale


def split_to_fit(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                 pad: float = TAB_MAX_MM + 1.0) -> tuple[Net, int]:
    """Cut creases of `net` until every piece, grown by `pad` mm (room for tabs), fits the page.

    Greedy: peel off a subtree that fits (the largest whose rest also fits, else the largest),
    until the rest fits. Returns the new net and the number of creases cut. Raises PieceTooLarge
    (a PolyfoldError) when a single face is too large, with the scale factor that would fit."""
    xy = net.coords * scale
    cuts = 0
    for _ in range(len(net.piece)):
        sub_area, tin, tout = subtree_areas(net)
        by_tin = np.argsort(tin)
        todo = None
        for p in range(net.n_pieces):
            faces = np.flatnonzero(net.piece == p)
            if _hull_scale(xy[faces].reshape(-1, 2), page_size, margin, pad) < 1.0:
                todo = faces
                break
        if todo is None:
            return net, cuts
        if len(todo) == 1:
            f = int(todo[0])
            raise PieceTooLarge(int(net.mesh.face_source[f]), _hull_scale(xy[f], page_size, margin, pad))
        cand = todo[net.parent[todo] >= 0]
        cand = cand[np.argsort(-sub_area[cand], kind="stable")]
        # Peel a subtree that fits; best one whose rest fits too (two pieces instead of three),
        # else the largest that fits. Only the MAX_PEEL_TRIES largest fitting subtrees are weighed.
        chosen, fitting = None, []
        in_piece = np.zeros(len(net.piece), dtype=bool)
        in_piece[todo] = True
        for c in cand:
            members = by_tin[tin[c]:tout[c]]
            if _hull_scale(xy[members].reshape(-1, 2), page_size, margin, pad) >= 1.0:
                fitting.append(int(c))
                rest = in_piece.copy()
                rest[members] = False
                if _hull_scale(xy[rest].reshape(-1, 2), page_size, margin, pad) >= 1.0:
                    chosen = int(c)
                    break
                if len(fitting) >= MAX_PEEL_TRIES:
                    break
        if chosen is None and fitting:
            chosen = fitting[0]
        if chosen is None:  # not even one face fits on its own below the root: cut the root off
            chosen = int(cand[-1])
        net = cut_creases(net, np.array([chosen]))
        cuts += 1
    return net, cuts


def model_scale(meshes: Sequence[Mesh], size_mm: float) -> float:
    """mm per model unit: the longest bounding-box side of the meshes' used vertices (a model's
    components together) becomes size_mm. PolyfoldError when the model has zero size."""
    pts = np.concatenate([m.vertices[np.unique(m.faces)] for m in meshes])
    extent = float(np.ptp(pts, axis=0).max())
    if not (extent > 0 and math.isfinite(extent)):
        raise PolyfoldError("the model has zero size")
    return size_mm / extent
