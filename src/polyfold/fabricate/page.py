"""The sheet model: a `Page` of placed pieces (cut outlines, scored creases, tabs, labels) in
millimetres, origin at the page's top-left corner, y pointing down (as in SVG); and putting
pieces on it (`place` a piece where packing put it, `page_of` the placed pieces).

Text placement: (x, y) is the centre of the text, `size` is the font size (em) in mm, `angle` is
the reading direction in degrees, counter-clockwise as seen on the page. The writers of
`formats/` (SVG, PDF, DXF, PNG) draw a Page the same way in every format.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from .paper import FOOTER_FONT_MM

if TYPE_CHECKING:
    from .pack import Placement
    from .pieces import SheetPiece


TEXT_KINDS = frozenset({"edge-label", "piece-label", "title"})


@dataclass(frozen=True)
class TextItem:
    """A label: `text` centred at (x, y) mm, `angle` degrees CCW as seen on the page, `size` mm
    font size, `kind` one of "edge-label", "piece-label", "title"."""

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
    edge: the outline alone would not separate them). Arrays are coerced to float64 and validated on construction.
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
        for name in ("mountain", "valley", "tab_folds", "slits"):
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
                faces=tuple(p.faces_xy for p in pieces), slits=cat("slits"),
                tabs=tuple(t for p in pieces for t in p.tabs),
                tab_mountain=np.concatenate([p.tab_mountain for p in pieces]) if pieces else np.zeros(0, bool))
