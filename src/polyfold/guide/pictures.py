"""The guide's pictures: the model from several sides with its pieces in colour and lettered, the
model part-built with the new piece highlighted, and a piece part-folded.

Drawn with the project's triangle rasteriser (`formats.raster`): one depth-tested pass writes each
pixel's face id, the colours come from the ids (printed side and inside apart, flat-shaded), seams
are depth-tested lines, and the letters and labels are set with Pillow's built-in font (white
outline, readable on any colour). In: numpy arrays; out: (H, W, 3) uint8 images.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..formats.raster import distance_to_background, part_colors, segment_samples, triangle_index, view_rotation

BACKGROUND = (255, 255, 255)
INSIDE_RGB = (214, 214, 214)  # the unprinted side of the paper
GHOST_RGB = (238, 238, 240)  # the model not built yet, behind what is
SEAM_RGB = (20, 20, 20)
MOUNTAIN_RGB = (214, 40, 40)  # the sheets' mountain red and valley blue
VALLEY_RGB = (30, 90, 220)
LIGHT = np.array([-0.35, 0.55, 0.76]) / np.linalg.norm([-0.35, 0.55, 0.76])

# the six sides (elevation, azimuth in degrees about the up axis) and, for choosing a step's view,
# the eight corners between them
SIDES = {"front": (0.0, 0.0), "right": (0.0, 90.0), "back": (0.0, 180.0), "left": (0.0, -90.0),
         "top": (90.0, 0.0), "bottom": (-90.0, 0.0)}
CORNERS = tuple((e, a) for e in (30.0, -30.0) for a in (45.0, 135.0, 225.0, 315.0))


def up_axis(vertices: np.ndarray) -> int:
    """The model axis drawn upright: the one of middle extent (as `raster.render_mesh` and the
    viewer: the longest runs left to right)."""
    ext = np.ptp(vertices, axis=0)
    return int(np.argsort(ext, kind="stable")[1])


def piece_palette(n: int) -> np.ndarray:
    """(n, 3) uint8: one colour per piece (the project's well separated hues)."""
    return part_colors(n, saturation=0.6, value=0.95)


def lighter(rgb: np.ndarray, amount: float) -> np.ndarray:
    """Colours (..., 3) uint8 blended towards white by `amount` (0..1)."""
    return (np.asarray(rgb, dtype=np.float64) * (1 - amount) + 255 * amount).round().astype(np.uint8)


@dataclass(frozen=True)
class Camera:
    """An orthographic camera: view = rotation @ (x - center), pixels = scale * view (y down),
    the centre of the picture at (width / 2, height / 2); depth = -view z (smaller is nearer)."""

    rotation: np.ndarray
    center: np.ndarray
    scale: float
    width: int
    height: int

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(pixels (..., 2), depth (...)) of points (..., 3)."""
        v = (np.asarray(points, dtype=np.float64) - self.center) @ self.rotation.T
        px = np.empty(v.shape[:-1] + (2,))
        px[..., 0] = v[..., 0] * self.scale + self.width / 2
        px[..., 1] = -v[..., 1] * self.scale + self.height / 2
        return px, -v[..., 2]


def fit_camera(points: np.ndarray, rotation: np.ndarray, width: int, height: int, margin: float = 0.06) -> Camera:
    """The camera with `rotation` that fits `points` (N, 3) into the picture with a margin."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    v = pts @ rotation.T
    lo, hi = v.min(axis=0), v.max(axis=0)
    mid = rotation.T @ ((lo + hi) / 2)
    span = np.maximum(hi - lo, 1e-12)
    scale = min(width * (1 - 2 * margin) / span[0], height * (1 - 2 * margin) / span[1])
    return Camera(rotation=rotation, center=mid, scale=float(scale), width=width, height=height)


def face_ids(cam: Camera, tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ids (H, W) int64, -1 on the background; depth (H, W)) of triangles (F, 3, 3), nearest
    face wins: one pass of the rasteriser (`raster.triangle_index`)."""
    px, depth = cam.project(np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3))
    return triangle_index((cam.height, cam.width), px, depth)


def shaded(cam: Camera, tris: np.ndarray, front: np.ndarray, back: np.ndarray | None = None) -> np.ndarray:
    """(F, 3) uint8: each face's colour as seen (front where its normal faces the camera, else
    back; None: front both ways), flat-shaded."""
    v = np.asarray(tris, dtype=np.float64) @ cam.rotation.T
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    base = np.asarray(front, dtype=np.float64)
    if back is not None:
        base = np.where((n[:, 2] >= 0)[:, None], base, np.asarray(back, dtype=np.float64))
    shade = 0.5 + 0.5 * np.abs(n @ LIGHT)
    return np.clip(base * shade[:, None], 0, 255).astype(np.uint8)


def draw_faces(cam: Camera, tris: np.ndarray, front: np.ndarray, back: np.ndarray | None = None,
               ghost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(image (H, W, 3) uint8, face ids, depth) of triangles (F, 3, 3) in colours front (F, 3)
    (back: their other side); ghost (G, 3, 3): triangles drawn faintly only where nothing else is
    (the model not built yet)."""
    ids, zbuf = face_ids(cam, tris)
    covered = face_ids(cam, ghost)[0] >= 0 if ghost is not None and len(ghost) else None
    return paint_faces(cam, tris, front, back, ids, covered), ids, zbuf


def paint_faces(cam: Camera, tris: np.ndarray, front: np.ndarray, back: np.ndarray | None, ids: np.ndarray,
                ghost: np.ndarray | None) -> np.ndarray:
    """`draw_faces`' image from the faces' ids (`face_ids` of tris) and where the ghost covers
    the picture ((H, W) bool, or None)."""
    # one gather from a colour table: the faces, then the ghost, then the background
    table = np.empty((len(tris) + 2, 3), dtype=np.uint8)
    table[-2], table[-1] = GHOST_RGB, BACKGROUND
    if len(tris):
        table[:-2] = shaded(cam, tris, front, back)
    pick = np.where(ids >= 0, ids, len(tris) + 1)
    if ghost is not None:
        pick[ghost & (ids < 0)] = len(tris)
    return table[pick]


def growing_face_ids(cam: Camera, tris: np.ndarray, placed: list[np.ndarray]
                     ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """For growing sets of faces (placed[k] ascending indices into tris (F, 3, 3), each holding
    the one before): per set, `face_ids` of tris[placed[k]] (ids into the set, depth) and where
    the other faces cover the picture ((H, W) bool), as `draw_faces`
    of the set with the others as its ghost has them, pixel for pixel. Each face is drawn twice
    in all instead of once per set: the sets' depths drawn over one another as they grow (the
    nearest face wins, ties to the smaller index: as drawing a set at once), the others' cover
    gathered from the last set back."""
    shape = (cam.height, cam.width)
    px, depth = cam.project(tris)  # (the same numbers as projecting any subset: row by row)
    out: list = []
    drawn, before = None, np.zeros(0, dtype=np.int64)
    local = np.full(len(tris) + 1, -1, dtype=np.int64)  # face -> its index in the set; [-1]: the background's -1
    for faces in placed:
        new = np.setdiff1d(faces, before, assume_unique=True)
        drawn = triangle_index(shape, px[new], depth[new], new, into=drawn)  # (drawn over in place)
        local[faces] = np.arange(len(faces))
        out.append((local[drawn[0]], drawn[1].copy()))
        before = faces
    rest = np.setdiff1d(np.arange(len(tris)), before, assume_unique=True)
    cover = triangle_index(shape, px[rest], depth[rest])[0] >= 0
    covers: list = [None] * len(placed)
    for k in range(len(placed) - 1, -1, -1):
        covers[k] = cover.copy()  # (all False where no face is left: no ghost, as draw_faces without one)
        if k:
            added = np.setdiff1d(placed[k], placed[k - 1], assume_unique=True)
            cover |= triangle_index(shape, px[added], depth[added])[0] >= 0
    return [(ids, zbuf, covered) for (ids, zbuf), covered in zip(out, covers)]


def draw_lines(img: np.ndarray, cam: Camera, zbuf: np.ndarray | None, segs: np.ndarray, color, width: float = 2.5,
               slack: float = 0.02) -> np.ndarray:
    """Draw 3D segments (n, 2, 3) into img in place, where they are not hidden (their depth at
    most `slack` x the picture's depth range behind the surface drawn there; zbuf None: all).
    Returns (n,) the fraction of each segment seen."""
    segs = np.asarray(segs, dtype=np.float64).reshape(-1, 2, 3)
    if len(segs) == 0:
        return np.zeros(0)
    px, depth = cam.project(segs)
    a, b = px[:, 0], px[:, 1]
    idx, t = segment_samples(px)
    pts = a[idx] + t[:, None] * (b - a)[idx]
    d = depth[idx, 0] + t * (depth[idx, 1] - depth[idx, 0])
    h, w = img.shape[:2]
    ix = np.clip(np.floor(pts[:, 0]).astype(np.int64), 0, w - 1)
    iy = np.clip(np.floor(pts[:, 1]).astype(np.int64), 0, h - 1)
    seen = np.ones(len(pts), dtype=bool)
    if zbuf is not None:
        finite = zbuf[np.isfinite(zbuf)]
        tol = slack * (float(finite.max() - finite.min()) if finite.size else 1.0) + 1e-12
        # the nearest surface around the point (a line on a face's edge lies on both faces)
        near = np.minimum.reduce([zbuf[np.clip(iy + dy, 0, h - 1), np.clip(ix + dx, 0, w - 1)]
                                  for dy in (-1, 0, 1) for dx in (-1, 0, 1)])
        seen = d <= near + tol
    r = max(0.5, width / 2)
    reach = int(math.ceil(r))
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            if dx * dx + dy * dy > r * r + 0.25:
                continue
            x = np.floor(pts[seen, 0] + dx).astype(np.int64)
            y = np.floor(pts[seen, 1] + dy).astype(np.int64)
            ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            img[y[ok], x[ok]] = color
    return np.bincount(idx, weights=seen, minlength=len(segs)) / np.bincount(idx, minlength=len(segs))


def label_spots(region: np.ndarray, labels: np.ndarray, min_px: int = 40) -> dict[int, tuple[float, float, float]]:
    """Where to write each label on a picture: region (H, W) int, the label of every pixel (-1:
    none); for every label in `labels` with at least min_px pixels, (x, y, room): its pixel
    farthest from the region's edge, and that distance in pixels."""

    inner = np.zeros(region.shape, dtype=bool)
    inner[1:-1, 1:-1] = ((region[1:-1, 1:-1] >= 0) & (region[1:-1, 1:-1] == region[:-2, 1:-1])
                         & (region[1:-1, 1:-1] == region[2:, 1:-1]) & (region[1:-1, 1:-1] == region[1:-1, :-2])
                         & (region[1:-1, 1:-1] == region[1:-1, 2:]))
    dist = distance_to_background(inner)
    spots = {}
    counts = np.bincount(region[region >= 0], minlength=int(max(labels, default=-1)) + 1) if (region >= 0).any() else []
    for lab in labels:
        if lab >= len(counts) or counts[lab] < min_px:
            continue
        where = region == lab
        k = int(np.argmax(np.where(where, dist, -1.0)))
        y, x = divmod(k, region.shape[1])
        spots[int(lab)] = (x + 0.5, y + 0.5, float(dist.flat[k]))
    return spots


_FONTS: dict[int, object] = {}


def _font(size: int):
    from PIL import ImageFont

    if size not in _FONTS:
        _FONTS[size] = ImageFont.load_default(size=size)
    return _FONTS[size]


def draw_texts(img: np.ndarray, items: list[tuple[float, float, str, int, tuple[int, int, int]]]) -> np.ndarray:
    """img with texts (x, y, text, size px, colour) centred at (x, y), each outlined in white."""
    if not items:
        return img
    from PIL import Image, ImageDraw

    pic = Image.fromarray(img)
    draw = ImageDraw.Draw(pic)
    for x, y, text, size, color in items:
        draw.text((x, y), text, fill=tuple(int(c) for c in color), font=_font(size), anchor="mm",
                  stroke_width=max(1, size // 7), stroke_fill=BACKGROUND)
    return np.asarray(pic).copy()


def side_rotations(vertices: np.ndarray) -> dict[str, np.ndarray]:
    """The rotations of the six sides (`SIDES`) for a model with these vertices."""
    up = up_axis(vertices)
    return {name: view_rotation(e, a, up) for name, (e, a) in SIDES.items()}


def corner_rotations(vertices: np.ndarray) -> list[np.ndarray]:
    """Rotations of the six sides and the eight corners, for choosing a view."""
    up = up_axis(vertices)
    return [view_rotation(e, a, up) for e, a in (*SIDES.values(), *CORNERS)]
