"""Tiny software rasteriser: distinct part colours, filled triangles, line segments and a
flat-shaded 3D mesh view.

Used for previews (segmentation pictures, sheet PNGs) without Pillow or matplotlib. In: numpy
arrays; out: (H, W, 3) uint8 images (`png.png_bytes` encodes them).
"""

from __future__ import annotations

import colorsys
import math

import numpy as np

from ..jit import njit


def part_colors(n: int, saturation: float = 0.65, value: float = 0.92) -> np.ndarray:
    """(n, 3) uint8 colours with well separated hues (golden-ratio steps), for labelling parts."""
    out = np.empty((n, 3), dtype=np.uint8)
    for i in range(n):
        r, g, b = colorsys.hsv_to_rgb((0.08 + 0.618033988749895 * i) % 1.0, saturation, value)
        out[i] = (round(r * 255), round(g * 255), round(b * 255))
    return out


@njit(cache=True)
def _zindex(index, zbuf, tri, depth, ids):
    """Rasterise 2D pixel-space triangles tri (n, 3, 2) with corner depths (n, 3) (smaller is
    nearer) over index (H, W) int64 and zbuf (H, W), in place: where a triangle covers a pixel's
    centre nearer than zbuf says, or as near with a smaller id, index gets its id (ids (n,)) and
    zbuf its depth. So each pixel ends with the nearest triangle, ties to the smallest id, in
    whatever order and batches the triangles come."""
    H, W = zbuf.shape
    for t in range(tri.shape[0]):
        ax, ay = tri[t, 0, 0], tri[t, 0, 1]
        bx, by = tri[t, 1, 0], tri[t, 1, 1]
        cx, cy = tri[t, 2, 0], tri[t, 2, 1]
        area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if abs(area2) < 1e-12:
            continue
        x0 = max(0, int(math.floor(min(ax, bx, cx))))
        x1 = min(W - 1, int(math.ceil(max(ax, bx, cx))))
        y0 = max(0, int(math.floor(min(ay, by, cy))))
        y1 = min(H - 1, int(math.ceil(max(ay, by, cy))))
        inv = 1.0 / area2
        own = ids[t]
        for py in range(y0, y1 + 1):
            yy = py + 0.5
            for px in range(x0, x1 + 1):
                xx = px + 0.5
                w0 = ((bx - xx) * (cy - yy) - (by - yy) * (cx - xx)) * inv
                w1 = ((cx - xx) * (ay - yy) - (cy - yy) * (ax - xx)) * inv
                w2 = 1.0 - w0 - w1
                if w0 < -1e-9 or w1 < -1e-9 or w2 < -1e-9:
                    continue
                z = w0 * depth[t, 0] + w1 * depth[t, 1] + w2 * depth[t, 2]
                if z < zbuf[py, px] or (z == zbuf[py, px] and own < index[py, px]):
                    zbuf[py, px] = z
                    index[py, px] = own


def triangle_index(shape: tuple[int, int], tris: np.ndarray, depth: np.ndarray, ids: np.ndarray | None = None,
                   into: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(index (H, W) int64, the nearest triangle at each pixel centre (ties: the smaller id), -1
    where none; depth (H, W), inf where none) of 2D pixel-space triangles tris (n, 3, 2) with
    corner depths (n, 3). ids (n,): the triangles' numbers in index (default 0..n-1). into: the
    (index, depth) of triangles drawn before, drawn over in place and returned (the same as
    drawing all at once)."""
    index, zbuf = into if into is not None else (np.full(shape, -1, dtype=np.int64), np.full(shape, np.inf))
    if len(tris):
        _zindex(index, zbuf, np.ascontiguousarray(tris, dtype=np.float64), np.ascontiguousarray(depth, dtype=np.float64),
                np.arange(len(tris), dtype=np.int64) if ids is None else np.ascontiguousarray(ids, dtype=np.int64))
    return index, zbuf


def _paint(img: np.ndarray, index: np.ndarray, colors: np.ndarray) -> None:
    """img[pixel] = colors[index[pixel]] where index >= 0, in place."""
    hit = index >= 0
    img[hit] = np.asarray(colors, dtype=np.uint8)[index[hit]]


@njit(cache=True)
def _squared_distances(mask, far):
    """Squared distance of every pixel of mask (H, W) bool to the nearest False pixel (0 there;
    `far` where the image has none), exact in integers: per column the distance along it, then per
    row the lower envelope of the parabolas (q - v)^2 + column distance (Felzenszwalb and
    Huttenlocher, "Distance transforms of sampled functions", 2012)."""
    h, w = mask.shape
    col = np.empty((h, w))
    for c in range(w):
        last = -1  # the nearest False row above, then the nearer of above and below
        for r in range(h):
            if not mask[r, c]:
                last = r
            col[r, c] = far if last < 0 else float((r - last) * (r - last))
        last = -1
        for r in range(h - 1, -1, -1):
            if not mask[r, c]:
                last = r
            elif last >= 0:
                col[r, c] = min(col[r, c], float((last - r) * (last - r)))
    out = np.empty((h, w))
    v = np.empty(w, dtype=np.int64)  # the parabolas of the envelope, left to right
    z = np.empty(w + 1)  # where each starts to be the lowest
    for r in range(h):
        f = col[r]
        k = 0
        v[0] = 0
        z[0], z[1] = -np.inf, np.inf
        for q in range(1, w):
            s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * (q - v[k]))
            while s <= z[k]:
                k -= 1
                s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * (q - v[k]))
            k += 1
            v[k] = q
            z[k], z[k + 1] = s, np.inf
        k = 0
        for q in range(w):
            while z[k + 1] < q:
                k += 1
            out[r, q] = min((q - v[k]) * (q - v[k]) + f[v[k]], far)
    return out


def distance_to_background(mask: np.ndarray) -> np.ndarray:
    """(H, W) float64: each pixel's Euclidean distance (in pixels) to the nearest False pixel of
    mask (H, W) bool, 0 on False pixels, as scipy.ndimage.distance_transform_edt gives it (a test
    compares them), inf where the image has no False pixel. Own kernel, not scipy's: importing
    scipy.ndimage cost 50-70 ms of every make, for the guide's label spots alone."""
    mask = np.ascontiguousarray(mask, dtype=np.bool_)
    if mask.size == 0:
        return np.zeros(mask.shape)
    far = float(mask.shape[0] ** 2 + mask.shape[1] ** 2) * 4.0 + 1.0  # beyond any distance inside
    d2 = _squared_distances(mask, far)
    out = np.sqrt(d2)
    out[d2 >= far] = np.inf
    return out


def fill_triangles(img: np.ndarray, tris: np.ndarray, colors: np.ndarray) -> None:
    """Paint 2D pixel-space triangles (n, 3, 2) with flat colours (n, 3) into img (H, W, 3), in
    place; where triangles overlap, the first one drawn stays (a net has no overlaps to resolve)."""
    tris = np.asarray(tris, dtype=np.float64)
    index, _ = triangle_index(img.shape[:2], tris, np.zeros(tris.shape[:2]))
    _paint(img, index, colors)


def segment_samples(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points every half pixel along pixel-space segments (n, 2, 2+) (ends included): (segment
    of each point, its fraction t along it), from the first two coordinates' lengths."""
    length = np.hypot(seg[:, 1, 0] - seg[:, 0, 0], seg[:, 1, 1] - seg[:, 0, 1])
    counts = np.ceil(length / 0.5).astype(np.int64) + 1
    idx = np.repeat(np.arange(len(seg)), counts)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    return idx, (np.arange(counts.sum()) - starts) / np.repeat(np.maximum(counts - 1, 1), counts)


def draw_segments(img: np.ndarray, seg: np.ndarray, color: tuple[int, int, int], thick: int = 1) -> None:
    """Draw pixel-space segments (n, 2, 2) into img (H, W, 3) in place: points every half pixel
    along each segment, one pixel wide, or a 2 x 2 pixel pen when thick > 1."""
    if len(seg) == 0:
        return
    H, W = img.shape[:2]
    idx, t = segment_samples(seg)
    a, b = seg[:, 0], seg[:, 1]
    pts = a[idx] + t[:, None] * (b - a)[idx]
    offs = [0.0] if thick <= 1 else [-0.5, 0.5]
    for dx in offs:
        for dy in offs:
            ix = np.floor(pts[:, 0] + dx).astype(np.int64)
            iy = np.floor(pts[:, 1] + dy).astype(np.int64)
            ok = (ix >= 0) & (ix < W) & (iy >= 0) & (iy < H)
            img[iy[ok], ix[ok]] = color


def view_rotation(elevation_deg: float, azimuth_deg: float, up_axis: int) -> np.ndarray:
    """3x3 rotation taking model coordinates to view coordinates (x right, y up, z towards the viewer).

    The model's `up_axis` (0, 1, 2) points up on screen; azimuth turns about it, elevation tilts."""
    # permute so the up axis becomes y
    perm = {0: [1, 0, 2], 1: [0, 1, 2], 2: [0, 2, 1]}[int(up_axis)]
    P = np.eye(3)[perm]
    if up_axis == 2:
        P[2] *= -1  # keep the frame right-handed: (x, z, -y)
    a, e = math.radians(azimuth_deg), math.radians(elevation_deg)
    Ry = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(e), -math.sin(e)], [0, math.sin(e), math.cos(e)]])
    return Rx @ Ry @ P


def render_mesh(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray, *, width: int = 800,
                height: int = 600, elevation_deg: float = 20.0, azimuth_deg: float = -35.0,
                up_axis: int | None = None, background=(255, 255, 255)) -> np.ndarray:
    """Orthographic, flat-shaded (two-sided Lambert + ambient) picture of a triangle mesh.

    vertices (n, 3), faces (m, 3), face_colors (m, 3) uint8 -> (height, width, 3) uint8 image.
    up_axis: model axis drawn vertically (default: the bbox axis of middle extent, which keeps the
    longest axis horizontal — how most models are best seen)."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if up_axis is None:
        ext = np.ptp(v[np.unique(f)], axis=0) if len(f) else np.ones(3)
        up_axis = int(np.argsort(ext)[1])
    R = view_rotation(elevation_deg, azimuth_deg, up_axis)
    p = (v - v.mean(axis=0)) @ R.T
    used = p[np.unique(f)] if len(f) else p
    lo, hi = used.min(axis=0), used.max(axis=0)
    margin = 0.05
    s = min(width * (1 - 2 * margin) / max(hi[0] - lo[0], 1e-12), height * (1 - 2 * margin) / max(hi[1] - lo[1], 1e-12))
    px = np.empty((len(p), 2))
    px[:, 0] = (p[:, 0] - (lo[0] + hi[0]) / 2) * s + width / 2
    px[:, 1] = ((lo[1] + hi[1]) / 2 - p[:, 1]) * s + height / 2
    depth = -p[:, 2]  # smaller = nearer to the viewer
    tri3 = p[f]
    n = np.cross(tri3[:, 1] - tri3[:, 0], tri3[:, 2] - tri3[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = np.array([-0.35, 0.55, 0.76])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.abs(n @ light)
    cols = np.clip(np.asarray(face_colors, dtype=np.float64) * shade[:, None], 0, 255).astype(np.uint8)
    img = np.empty((height, width, 3), dtype=np.uint8)
    img[:] = background
    index, _ = triangle_index((height, width), px[f], depth[f])
    _paint(img, index, cols)
    return img
