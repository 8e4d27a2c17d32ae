"""Carrying a mesh's look over to another mesh of the same surface (a simplified one): the new
faces get a texture of their own, baked from the old surface.

A simplified face spans many old faces, often across the old texture's UV seams, so old UVs
cannot simply be interpolated onto it. Instead every new face gets its own triangle in a new
texture (an atlas, faces on shelves, `shelves.shelf_offsets`) at the old texture's density, and
every texel of it takes the old look at the closest point of the old surface (among the
BAKE_NEAREST old faces nearest by centroid; faces turned away from the new face's normal only
when no other is near). Meshes coloured per vertex or per face get colours the same way, at
their corners (per vertex) or centres (per face): no atlas.

In: the old mesh and its `Appearance`, the new mesh. Out: the new mesh's `Appearance`.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from .appearance import Appearance
from .closest import closest_points
from .geometry import face_areas
from .mesh import Mesh

BAKE_NEAREST = 8  # old faces (nearest by centroid) searched for each texel's closest point
MAX_ATLAS_TEXELS = 4096 * 4096  # the baked texture's area at most (the old density is kept below it)
MIN_FACE_TEXELS = 12  # the longest side of a new face in the atlas at least (texels)
PAD = 2  # texels around every face in the atlas (bleed for bilinear samples at its edges)
BACKFACE_PENALTY = 1e3  # x the model size: a closest point on a face turned away loses to any other


@njit(cache=True)
def cover_triangles(tri, owner, bary, pad):
    """Which triangle (tri (n, 3, 2), pixel coordinates, x right, y down) covers each pixel centre
    of an image, into owner (H, W) (-1: none; pass it filled with -1) and bary (H, W, 3) the
    barycentric coordinates there. A pixel up to `pad` px outside every triangle that covers it
    takes the nearest point of the first triangle that reaches it (the bleed that keeps bilinear
    samples and clipped edges free of background); a covering triangle always wins over a bleed.
    The one rasteriser of the baked atlas (`bake`) and of the printed pictures (`fabricate.paint`)."""
    H, W = owner.shape
    for t in range(tri.shape[0]):
        ax, ay = tri[t, 0, 0], tri[t, 0, 1]
        bx, by = tri[t, 1, 0], tri[t, 1, 1]
        cx, cy = tri[t, 2, 0], tri[t, 2, 1]
        area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if abs(area2) < 1e-12:
            continue
        la = math.hypot(cx - bx, cy - by)  # side opposite each corner
        lb = math.hypot(ax - cx, ay - cy)
        lc = math.hypot(bx - ax, by - ay)
        x0 = max(0, int(math.floor(min(ax, bx, cx) - pad)))
        x1 = min(W - 1, int(math.ceil(max(ax, bx, cx) + pad)))
        y0 = max(0, int(math.floor(min(ay, by, cy) - pad)))
        y1 = min(H - 1, int(math.ceil(max(ay, by, cy) + pad)))
        for py in range(y0, y1 + 1):
            for px in range(x0, x1 + 1):
                sx, sy = px + 0.5, py + 0.5
                wa = ((bx - sx) * (cy - sy) - (by - sy) * (cx - sx)) / area2
                wb = ((cx - sx) * (ay - sy) - (cy - sy) * (ax - sx)) / area2
                wc = 1.0 - wa - wb
                d = min(wa * abs(area2) / la, wb * abs(area2) / lb, wc * abs(area2) / lc)  # px, < 0 outside
                if d < -pad or (d < 0.0 and owner[py, px] >= 0):
                    continue
                wa, wb, wc = max(wa, 0.0), max(wb, 0.0), max(wc, 0.0)
                s = wa + wb + wc
                owner[py, px] = t
                bary[py, px, 0], bary[py, px, 1], bary[py, px, 2] = wa / s, wb / s, wc / s


def _look_at(points: np.ndarray, normals: np.ndarray, old: Mesh, look: Appearance) -> np.ndarray:
    """(N, 3) uint8: the old look at the old surface's closest point to each point (module docstring)."""
    from scipy.spatial import cKDTree

    tri = old.vertices[old.faces]
    k = min(BAKE_NEAREST, len(tri))
    _, near = cKDTree(tri.mean(axis=1)).query(points, k=k, workers=-1)
    near = np.ascontiguousarray(near.reshape(len(points), k), dtype=np.int64)
    face = np.zeros(len(points), dtype=np.int64)
    bary = np.zeros((len(points), 3))
    penalty = BACKFACE_PENALTY * max(old.bbox_diagonal, 1e-300)
    closest_points(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(normals, dtype=np.float64),
                   near, np.ascontiguousarray(tri), old.face_normals, penalty, face, bary)
    return look.sample(face, bary)


def _density(old: Mesh, look: Appearance) -> float:
    """Texels per model unit of the old texture (its mapped area over the surface it covers)."""
    on = np.flatnonzero(look.textured)
    if not len(on):
        return 0.0
    texels = 0.0
    for k, image in enumerate(look.images):
        f = on[look.face_image[on] == k]
        uv = look.uv[f] * np.array([image.shape[1], image.shape[0]])
        e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
        texels += 0.5 * float(np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum())
    area = float(face_areas(old.vertices, old.faces[on]).sum())
    return math.sqrt(texels / area) if area > 0 else 0.0


def _flat_triangles(mesh: Mesh) -> np.ndarray:
    """(F, 3, 2) every face laid flat, true to shape (model units): corner 0 at the origin,
    corner 1 on +x, corner 2 above (y > 0)."""
    tri = mesh.vertices[mesh.faces]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    l1 = np.maximum(np.linalg.norm(e1, axis=1), 1e-300)
    x2 = (e1 * e2).sum(axis=1) / l1
    y2 = np.linalg.norm(np.cross(e1, e2), axis=1) / l1
    out = np.zeros((len(tri), 3, 2))
    out[:, 1, 0] = l1
    out[:, 2, 0], out[:, 2, 1] = x2, y2
    return out


def bake(old: Mesh, look: Appearance, new: Mesh) -> Appearance:
    """The look of `old` (its `Appearance`) carried over to `new`, a mesh of (about) the same
    surface (module docstring)."""
    from ..shelves import shelf_offsets

    n = new.n_faces
    tri = new.vertices[new.faces]
    if not look.textured.any():  # colours: sampled at the corners (per vertex) or centres (per face)
        if look.kind == "face":
            rgb = _look_at(tri.mean(axis=1), new.face_normals, old, look)
            colors = np.repeat(rgb[:, None, :], 3, axis=1)
        else:
            inset = 0.98 * tri + 0.02 * tri.mean(axis=1, keepdims=True)  # just inside: the face's own side
            rgb = _look_at(inset.reshape(-1, 3), np.repeat(new.face_normals, 3, axis=0), old, look)
            colors = rgb.reshape(n, 3, 3)
        return Appearance((), np.full(n, -1), np.full((n, 3, 2), np.nan), colors, look.kind)

    flat = _flat_triangles(new)
    area = float(face_areas(new.vertices, new.faces).sum())
    scale = min(_density(old, look), math.sqrt(MAX_ATLAS_TEXELS / max(area, 1e-300)) * 0.7)
    longest = flat.reshape(n, -1).max(axis=1)
    scale_f = np.maximum(scale, MIN_FACE_TEXELS / np.maximum(longest, 1e-300))  # tiny faces: a few texels anyway
    px = flat * scale_f[:, None, None]
    lo = px.min(axis=1)
    sizes = px.max(axis=1) - lo + 2 * PAD
    width = max(float(sizes[:, 0].max()), math.sqrt(float((sizes.prod(axis=1)).sum()) * 1.1))
    offsets = shelf_offsets(sizes.tolist(), width, math.inf, 0.0)
    origin = np.array([(x, y) for _, x, y in offsets]) + PAD - lo
    px = px + origin[:, None, :]
    H = int(math.ceil(float(px[..., 1].max()))) + 2 * PAD
    W = int(math.ceil(float(px[..., 0].max()))) + 2 * PAD
    owner = np.full((H, W), -1, dtype=np.int64)
    bary = np.zeros((H, W, 3))
    cover_triangles(np.ascontiguousarray(px), owner, bary, float(PAD))
    atlas = np.full((H, W, 3), 255, dtype=np.uint8)
    ys, xs = np.nonzero(owner >= 0)
    f = owner[ys, xs]
    points = np.einsum("nk,nkc->nc", bary[ys, xs], tri[f])
    atlas[ys, xs] = _look_at(points, new.face_normals[f], old, look)
    uv = np.empty((n, 3, 2))
    uv[..., 0] = px[..., 0] / W
    uv[..., 1] = 1.0 - px[..., 1] / H
    return Appearance((atlas,), np.zeros(n, dtype=np.int64), uv, np.full((n, 3, 3), 255, np.uint8), "texture")
