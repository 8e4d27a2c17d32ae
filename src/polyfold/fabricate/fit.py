"""Splitting a net to fit a page: cut creases until every piece, with room for its tabs, fits.

Cutting creases never moves a face, so the pieces stay overlap-free. The merged creases of a flat
region (`mesh.geometry.merged_edges`) are never cut: a flat polygon too large for the page is an
error, like a single face.
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
    """A single face, or a flat polygon that is never cut (its faces, ids in the input file: `faces`,
    the first is `face`), does not fit the page with room for its tabs; `factor` is the largest
    scale factor of the model at which it would."""

    def __init__(self, faces: Sequence[int], factor: float) -> None:
        self.faces = tuple(sorted({int(f) for f in faces}))
        self.face = self.faces[0]
        self.factor = factor
        super().__init__(f"{self.what} alone does not fit the page with its tabs (fits at {factor:.3f} times the size)")

    @property
    def what(self) -> str:
        """"face 3", or "the flat polygon of faces 3, 4" (input file face ids)."""
        if len(self.faces) == 1:
            return f"face {self.face}"
        shown = ", ".join(map(str, self.faces[:6])) + (", ..." if len(self.faces) > 6 else "")
        return f"the flat polygon of faces {shown}"


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


def _model_factor(points_mm: np.ndarray, page_size, margin: float, pad: float) -> float:
    """Largest factor of the model's scale at which the convex hull of the points, grown by `pad` mm
    (the tab room does not scale with the model), fits the page as `split_to_fit` checks it.

    Bisection between the hull alone in the page less the pad (a lower bound: the grown hull is
    inside the hull's round `pad` neighbourhood) and the grown hull's own scale (an upper bound
    when below 1: the pad shrinks with it there)."""
    import shapely

    def fits(factor: float) -> bool:
        return _hull_scale(points_mm * factor, page_size, margin, pad) >= 1.0

    lo = fits_page(shapely.convex_hull(shapely.multipoints(points_mm)), page_size, margin + pad)
    for _ in range(100):  # rotations tried for the bare and the grown hull may differ a little
        if lo <= 0 or fits(lo):
            break
        lo *= 0.999
    hi = _hull_scale(points_mm, page_size, margin, pad)
    for _ in range(30):
        if hi - lo <= 1e-6 * hi:
            break
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def split_to_fit(net: Net, scale: float, page_size: tuple[float, float], margin: float,
                 pad: float = TAB_MAX_MM + 1.0) -> tuple[Net, int]:
    """Cut creases of `net` until every piece, grown by `pad` mm (room for tabs), fits the page.

    Greedy: peel off a subtree that fits (the largest whose rest also fits, else the largest),
    until the rest fits; only subtrees whose crease to their parent may be cut (`Net.cuttable`:
    not inside a flat polygon). Returns the new net and the number of creases cut. Raises
    PieceTooLarge (a PolyfoldError) when a single face or flat polygon is too large, with the
    scale factor that would fit."""
    xy = net.coords * scale
    cuts = 0
    cuttable = net.cuttable  # cutting a crease changes no other crease's
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
        cand = todo[cuttable[todo]]
        if len(cand) == 0:  # one face, or one flat polygon
            raise PieceTooLarge(net.mesh.face_source[todo], _model_factor(xy[todo].reshape(-1, 2), page_size, margin, pad))
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
        cuttable[chosen] = False
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
