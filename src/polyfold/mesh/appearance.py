"""What a mesh's faces look like when printed: a texture (an image and the UVs of each face's
corners) or a colour per corner, face by face (`Appearance`), and the one way colours are read
from it (`sample`, `face_colors`).

Conventions: texture coordinates are OpenGL's (u to the right, v UP, (0, 0) the image's
bottom-left corner, 1 its width / height; outside 0..1 the image repeats, as glTF's default
wrap and most OBJ viewers do). Images are (h, w, 3) uint8 RGB arrays, row 0 the top row.
A texel (x, y) is sampled bilinearly at x = u * w - 0.5, y = (1 - v) * h - 0.5. Faces follow
the mesh's face order and corner order: uv[f, k] belongs to the corner faces[f, k].
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

KINDS = ("texture", "vertex", "face")  # what the file had: an image, colours per vertex, per face
WHITE = (255, 255, 255)


@dataclass(frozen=True, eq=False)
class Appearance:
    """The look of every face of a mesh (F faces).

    images: (h, w, 3) uint8 textures; face_image: (F,) int64, the texture of each face, -1 for
    none (the face is printed in its corner colours); uv: (F, 3, 2) float64 texture coordinates
    of each corner (NaN where face_image is -1); colors: (F, 3, 3) uint8 colour of each corner
    (white where the file gave none); kind: one of KINDS, what the file had.
    """

    images: tuple[np.ndarray, ...]
    face_image: np.ndarray
    uv: np.ndarray
    colors: np.ndarray
    kind: str

    def __post_init__(self) -> None:
        n = len(self.face_image)
        object.__setattr__(self, "face_image", np.asarray(self.face_image, dtype=np.int64).reshape(n))
        object.__setattr__(self, "uv", np.asarray(self.uv, dtype=np.float64).reshape(n, 3, 2))
        object.__setattr__(self, "colors", np.asarray(self.colors, dtype=np.uint8).reshape(n, 3, 3))
        object.__setattr__(self, "images", tuple(np.ascontiguousarray(im, dtype=np.uint8) for im in self.images))
        if self.kind not in KINDS:
            raise ValueError(f"Appearance kind must be one of {KINDS}, got {self.kind!r}")
        if n and (self.face_image.max() >= len(self.images) or self.face_image.min() < -1):
            raise ValueError("Appearance: a face refers to a texture that is not there")

    @property
    def n_faces(self) -> int:
        return len(self.face_image)

    @property
    def textured(self) -> np.ndarray:
        """(F,) bool: faces printed from a texture."""
        return self.face_image >= 0

    @cached_property
    def shaded(self) -> np.ndarray:
        """(F,) bool: faces whose colour varies across them (a texture, or corners that differ):
        printed as a picture rather than one fill colour."""
        c = self.colors.astype(np.int16)
        return self.textured | (np.abs(c - c[:, :1]).max(axis=(1, 2)) > 0)

    def take(self, faces: np.ndarray, corners: np.ndarray | None = None) -> "Appearance":
        """The appearance of the faces `faces` (indices into this one), in that order; corners
        (len(faces), 3): which of its corners each new corner is (default 0, 1, 2)."""
        faces = np.asarray(faces, dtype=np.int64)
        k = np.tile(np.arange(3), (len(faces), 1)) if corners is None else np.asarray(corners, dtype=np.int64)
        rows = faces[:, None]
        return Appearance(self.images, self.face_image[faces], self.uv[rows, k], self.colors[rows, k], self.kind)

    def sample(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """(N, 3) uint8 colours at the points with barycentric coordinates `bary` (N, 3) in the
        faces `faces` (N,): the texture under the interpolated UVs, or the corner colours
        interpolated."""
        faces = np.asarray(faces, dtype=np.int64)
        bary = np.asarray(bary, dtype=np.float64).reshape(len(faces), 3)
        out = (np.einsum("nk,nkc->nc", bary, self.colors[faces].astype(np.float64)) + 0.5).astype(np.uint8)
        img = self.face_image[faces]
        for k, image in enumerate(self.images):
            on = np.flatnonzero(img == k)
            if len(on):
                uv = np.einsum("nk,nkc->nc", bary[on], self.uv[faces[on]])
                out[on] = sample_texture(image, texel_coords(uv, image.shape))
        return out

    @cached_property
    def mean_colors(self) -> np.ndarray:
        """(F, 3) uint8 the mean colour of every face (over 12 points spread across it)."""
        n = self.n_faces
        faces = np.repeat(np.arange(n), len(_SPREAD))
        rgb = self.sample(faces, np.tile(_SPREAD, (n, 1))).reshape(n, len(_SPREAD), 3)
        return (rgb.mean(axis=1) + 0.5).astype(np.uint8)


# barycentric points spread over a triangle (its centre, and rings towards the corners)
_SPREAD = np.array([[1, 1, 1], [4, 1, 1], [1, 4, 1], [1, 1, 4], [2, 2, 1], [2, 1, 2], [1, 2, 2],
                    [10, 1, 1], [1, 10, 1], [1, 1, 10], [6, 5, 1], [1, 6, 5]], dtype=np.float64)
_SPREAD /= _SPREAD.sum(axis=1, keepdims=True)


def flat_look(look: Appearance) -> Appearance:
    """Every face in its mean colour (`--color flat`), no texture."""
    n = look.n_faces
    return Appearance((), np.full(n, -1), np.full((n, 3, 2), np.nan), np.repeat(look.mean_colors[:, None, :], 3, axis=1),
                      "face")


def texel_coords(uv: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """(..., 2) texel coordinates (x right, y down, pixel centres at integers + 0.5 - 0.5) of
    texture coordinates uv (..., 2) in an image of `shape` (h, w, ...)."""
    h, w = shape[0], shape[1]
    out = np.empty_like(np.asarray(uv, dtype=np.float64))
    out[..., 0] = uv[..., 0] * w - 0.5
    out[..., 1] = (1.0 - uv[..., 1]) * h - 0.5
    return out


def sample_texture(image: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 bilinear colours of `image` at texel coordinates xy (N, 2) (`texel_coords`);
    white where a coordinate is not finite."""
    from .kernels import sample_many

    xy = np.ascontiguousarray(xy, dtype=np.float64).reshape(-1, 2)
    out = np.empty((len(xy), 3), dtype=np.uint8)
    sample_many(np.ascontiguousarray(image, dtype=np.uint8), xy, out)
    return out
