"""The sheet model: a `Page` of placed pieces (cut outlines, scored creases, tabs, labels) in
millimetres, origin at the page's top-left corner, y pointing down (as in SVG); and putting
pieces on it (`place` a piece where packing put it, `page_of` the placed pieces).

Text placement: (x, y) is the centre of the text, `size` is the font size (em) in mm, `angle` is
the reading direction in degrees, counter-clockwise as seen on the page. The writers of
`formats/` (SVG, PDF, DXF, PNG) draw a Page the same way in every format.

Besides the pieces a page may carry print-only furniture, drawn by the print writers (SVG, PDF,
PNG) and left out of the cut SVG and the DXF: a `ScaleBar` in the footer strip (`footer`) and
print-and-cut `RegistrationMarks` (`registration_marks`, sizes in `paper.py`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .paper import (FOOTER_FONT_MM, FOOTER_MM, MARK_INSET_MM, MARK_LEG_MM, MARK_LINE_MM, MARK_SQUARE_MM,
                    SCALE_BAR_MM)

if TYPE_CHECKING:
    from .pack import Placement
    from .pieces import SheetPiece


TEXT_KINDS = frozenset({"edge-label", "piece-label", "title", "scale-label"})


@dataclass(frozen=True)
class TextItem:
    """A label: `text` centred at (x, y) mm, `angle` degrees CCW as seen on the page, `size` mm
    font size, `kind` one of "edge-label", "piece-label", "title", "scale-label"."""

    text: str
    x: float
    y: float
    angle: float
    size: float
    kind: str

    def __post_init__(self) -> None:
        if self.kind not in TEXT_KINDS:
            raise ValueError(f"TextItem kind must be one of {sorted(TEXT_KINDS)}, got {self.kind!r}")
        if not all(math.isfinite(v) for v in (self.x, self.y, self.angle, self.size)) or self.size <= 0:
            raise ValueError(f"TextItem {self.text!r}: position/angle must be finite and size > 0")


SCALE_TICK_MM = 2.0  # height of the scale bar's end ticks


@dataclass(frozen=True)
class ScaleBar:
    """A printed length to check 100 % printing: a bar from (x, y) to (x + length, y) mm with end
    ticks `tick` mm tall pointing up (y down: towards smaller y), and `label` (e.g. "50 mm")
    centred above the ticks."""

    x: float
    y: float
    length: float
    tick: float
    label: TextItem

    def __post_init__(self) -> None:
        if not all(math.isfinite(v) for v in (self.x, self.y, self.length, self.tick)) or self.length <= 0:
            raise ValueError(f"scale bar: position must be finite and length > 0, got {self.length}")

    def segments(self) -> np.ndarray:
        """(3, 2, 2) the bar, the left tick, the right tick (page mm)."""
        x0, x1, y, top = self.x, self.x + self.length, self.y, self.y - self.tick
        return np.array([[[x0, y], [x1, y]], [[x0, top], [x0, y]], [[x1, top], [x1, y]]], dtype=np.float64)


# eq=False: numpy fields make a generated __eq__/__hash__ meaningless (ambiguous truth values).
@dataclass(frozen=True, eq=False)
class RegistrationMarks:
    """Print-and-cut registration marks (page mm): `square` (4, 2) a filled polygon; `corners`
    (2, 3, 2) two L-shaped polylines (corner point in the middle) stroked `line` mm wide."""

    square: np.ndarray
    corners: np.ndarray
    line: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "square", _finite(self.square, "marks.square", (-1, 2)))
        object.__setattr__(self, "corners", _finite(self.corners, "marks.corners", (-1, 3, 2)))
        if not (math.isfinite(self.line) and self.line > 0):
            raise ValueError(f"marks: line width must be > 0, got {self.line}")


def registration_marks(width: float, height: float) -> RegistrationMarks:
    """Silhouette Studio's "Type 1" marks on a width x height mm page (see `paper.py`): the filled
    square at the top-left, L-shaped corners at the top-right and bottom-left."""
    i, s, leg = MARK_INSET_MM, MARK_SQUARE_MM, MARK_LEG_MM
    square = [[i, i], [i + s, i], [i + s, i + s], [i, i + s]]
    top_right = [[width - i - leg, i], [width - i, i], [width - i, i + leg]]
    bottom_left = [[i, height - i - leg], [i, height - i], [i + leg, height - i]]
    return RegistrationMarks(np.array(square, float), np.array([top_right, bottom_left], float), MARK_LINE_MM)


def footer(text: str, x0: float, x1: float, top: float) -> tuple[TextItem, ScaleBar | None]:
    """The footer strip [x0, x1] x [top, top + FOOTER_MM] mm: a scale bar at its right end
    (SCALE_BAR_MM, or 20 or 10 mm when the strip is under twice that; none under 20 mm) and
    `text` centred on the rest of the strip."""
    gap = 3.0
    length = next((v for v in (SCALE_BAR_MM, 20.0, 10.0) if 2 * v <= x1 - x0), None)
    bar = None
    if length is not None:
        bx = x1 - length
        # label glyphs (cap height ~0.72 em) in the strip's top half, ticks and bar below them
        label = TextItem(f"{length:g} mm", bx + length / 2, top + 1.5, 0.0, FOOTER_FONT_MM, "scale-label")
        bar = ScaleBar(bx, top + 3.2 + SCALE_TICK_MM, length, SCALE_TICK_MM, label)
        x1 = bx - gap
    return TextItem(text, (x0 + x1) / 2, top + FOOTER_MM / 2, 0.0, FOOTER_FONT_MM, "title"), bar


# eq=False: numpy fields make a generated __eq__/__hash__ meaningless (ambiguous truth values).
@dataclass(frozen=True, eq=False)
class PageImage:
    """A picture printed on a page (a piece's texture, `fabricate.paint`): `pixels` (h, w, 3)
    uint8, row 0 at the top, covering [x, x + width] x [y, y + height] page mm, shown only inside
    `clip` (closed rings in page mm, even-odd: the piece's faces, not its tabs)."""

    x: float
    y: float
    width: float
    height: float
    pixels: np.ndarray
    clip: tuple[np.ndarray, ...]

    def __post_init__(self) -> None:
        if not all(math.isfinite(v) for v in (self.x, self.y, self.width, self.height)) or min(self.width, self.height) <= 0:
            raise ValueError(f"page image: position must be finite and size > 0, got {self.width} x {self.height}")
        px = np.asarray(self.pixels)
        if px.ndim != 3 or px.shape[2] != 3 or px.dtype != np.uint8 or 0 in px.shape:
            raise ValueError(f"page image: pixels must be (h, w, 3) uint8, got {px.shape} {px.dtype}")
        object.__setattr__(self, "clip", tuple(_finite(r, "image.clip", (-1, 2)) for r in self.clip))

    @cached_property
    def jpeg(self) -> bytes:
        """The pixels as a JPEG file (quality JPEG_QUALITY): what the PDF and the SVG embed."""
        import io

        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(self.pixels).save(buf, format="JPEG", quality=JPEG_QUALITY, optimize=True)
        return buf.getvalue()


JPEG_QUALITY = 90  # a printed texture: no visible artefacts, about a tenth of the raw pixels


# eq=False: numpy fields make a generated __eq__/__hash__ meaningless (ambiguous truth values).
@dataclass(frozen=True, eq=False)
class Page:
    """One sheet, `width` x `height` mm, origin top-left, y down.

    cut: closed polylines (k, 2), k >= 3, piece outlines incl. tabs, not repeating the first point
    (a repeated closing point is dropped); mountain / valley / tab_folds: (n, 2, 2) segments;
    tab_mountain: (len(tab_folds),) bool, True where a tab folds as a mountain seen from the printed
    side (its seam is convex), False for a valley (concave seam; default: all valleys);
    texts: labels; faces: optional (n, 3, 2) triangles per piece, filled light in previews only;
    slits: (n, 2, 2) cut segments inside an outline (two faces of one piece that touch along a cut
    edge: the outline alone would not separate them); scale_bar, marks: optional print-only
    furniture (see the module docstring). Arrays are coerced to float64 and validated on construction.
    """

    width: float
    height: float
    cut: tuple[np.ndarray, ...]
    mountain: np.ndarray
    valley: np.ndarray
    tab_folds: np.ndarray
    texts: tuple[TextItem, ...]
    faces: tuple[np.ndarray, ...] = ()
    slits: np.ndarray = ()  # type: ignore[assignment]
    tabs: tuple[np.ndarray, ...] = ()  # optional (4, 2) glue-tab polygons, shaded in previews only
    tab_mountain: np.ndarray = ()  # type: ignore[assignment]
    scale_bar: ScaleBar | None = None
    marks: RegistrationMarks | None = None
    leaders: np.ndarray = ()  # type: ignore[assignment]  # (n, 2, 2) thin printed lines to off-face labels
    face_colors: tuple[np.ndarray, ...] = ()  # optional (n, 3) uint8 fill of each face of faces[i] (the model's colours)
    images: tuple[PageImage, ...] = ()  # pictures printed over the face fills (the model's texture)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.width) and math.isfinite(self.height) and self.width > 0 and self.height > 0):
            raise ValueError(f"page size must be positive, got {self.width} x {self.height} mm")
        cut = []
        for i, poly in enumerate(self.cut):
            p = _finite(poly, f"cut[{i}]", (-1, 2))
            if len(p) > 1 and np.array_equal(p[0], p[-1]):
                p = p[:-1]  # writers close outlines themselves; a doubled vertex would be a zero-length edge
            if len(p) < 3:
                raise ValueError(f"cut[{i}] needs at least 3 distinct points, got {len(p)}")
            cut.append(p)
        object.__setattr__(self, "cut", tuple(cut))
        for name in ("mountain", "valley", "tab_folds", "slits", "leaders"):
            object.__setattr__(self, name, _finite(getattr(self, name), name, (-1, 2, 2)))
        faces = tuple(_finite(f, f"faces[{i}]", (-1, 3, 2)) for i, f in enumerate(self.faces))
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "tabs", tuple(_finite(t, f"tabs[{i}]", (-1, 2)) for i, t in enumerate(self.tabs)))
        object.__setattr__(self, "texts", tuple(self.texts))
        tm = np.asarray(self.tab_mountain, dtype=bool).reshape(-1)
        if tm.size == 0:
            tm = np.zeros(len(self.tab_folds), dtype=bool)
        if len(tm) != len(self.tab_folds):
            raise ValueError(f"tab_mountain: expected {len(self.tab_folds)} flags, got {len(tm)}")
        object.__setattr__(self, "tab_mountain", tm)
        if self.face_colors:
            if len(self.face_colors) != len(faces):
                raise ValueError(f"face_colors: expected {len(faces)} arrays (one per faces entry), got {len(self.face_colors)}")
            fc = tuple(np.asarray(c, dtype=np.uint8).reshape(len(f), 3) for c, f in zip(self.face_colors, faces))
            object.__setattr__(self, "face_colors", fc)
        object.__setattr__(self, "images", tuple(self.images))
        if not all(isinstance(im, PageImage) for im in self.images):
            raise ValueError("images must be PageImages")
        if self.scale_bar is not None and not isinstance(self.scale_bar, ScaleBar):
            raise ValueError(f"scale_bar must be a ScaleBar, got {type(self.scale_bar).__name__}")
        if self.marks is not None and not isinstance(self.marks, RegistrationMarks):
            raise ValueError(f"marks must be RegistrationMarks, got {type(self.marks).__name__}")


def _finite(a, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """`a` as a float64 array reshaped to `shape` (-1 first); ValueError if it does not fit or
    holds NaN / inf (which would silently corrupt every output format)."""
    arr = np.asarray(a, dtype=np.float64)
    try:
        arr = arr.reshape(shape)
    except ValueError:
        raise ValueError(f"{name}: expected shape {('n',) + shape[1:]}, got {arr.shape}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: coordinates must be finite")
    return arr


def upright(angle: float) -> float:
    """Angle (deg) turned by 180 if needed so text never reads upside down: in (-90, 90]."""
    a = (angle + 180.0) % 360.0 - 180.0
    if a > 90.0:
        a -= 180.0
    elif a <= -90.0:
        a += 180.0
    return a


def place(piece: SheetPiece, placement: Placement) -> SheetPiece:
    """The piece moved by a `pack.Placement` (rotation then translation, in page mm, y down)."""
    from shapely import affinity

    def tf(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=np.float64)
        return placement.apply(a.reshape(-1, 2)).reshape(a.shape) if a.size else a

    def tg(g):
        g = affinity.rotate(g, placement.angle, origin=(0, 0), use_radians=False)
        return affinity.translate(g, *placement.offset)

    # Placement rotates by +angle in the (x, y-down) frame, which looks clockwise on the page.
    texts = []
    for t in piece.texts:
        x, y = placement.apply(np.array([[t.x, t.y]]))[0]
        texts.append(replace(t, x=float(x), y=float(y), angle=upright(t.angle - placement.angle)))
    return replace(piece, faces_xy=tf(piece.faces_xy), body=tg(piece.body), outline=tg(piece.outline),
                   footprint=tg(piece.footprint), leaders=tf(piece.leaders),
                   mountain=tf(piece.mountain), valley=tf(piece.valley), slits=tf(piece.slits),
                   tabs=tuple(tf(t) for t in piece.tabs), tab_folds=tf(piece.tab_folds), texts=tuple(texts))


def page_of(pieces: list[SheetPiece], width: float, height: float, footer: str | None = None,
            footer_y: float | None = None) -> Page:
    """A `Page` with the (already placed) pieces; an optional footer line of text."""
    texts = [t for p in pieces for t in p.texts]
    if footer:
        texts.append(TextItem(footer, width / 2, footer_y if footer_y is not None else height - 12, 0.0, FOOTER_FONT_MM, "title"))
    cat = lambda name: np.concatenate([getattr(p, name).reshape(-1, 2, 2) for p in pieces]) if pieces else np.zeros((0, 2, 2))
    return Page(width=width, height=height, cut=tuple(r for p in pieces for r in p.cut_rings()),
                mountain=cat("mountain"), valley=cat("valley"), tab_folds=cat("tab_folds"), texts=tuple(texts),
                faces=tuple(p.faces_xy for p in pieces), slits=cat("slits"), leaders=cat("leaders"),
                tabs=tuple(t for p in pieces for t in p.tabs),
                tab_mountain=np.concatenate([p.tab_mountain for p in pieces]) if pieces else np.zeros(0, bool))
