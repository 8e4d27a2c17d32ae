"""The sheet model: a `Page` of placed pieces (cut outlines, scored creases, tabs, labels) in
millimetres, origin at the page's top-left corner, y pointing down (as in SVG).

Text placement: (x, y) is the centre of the text, `size` is the font size (em) in mm, `angle` is
the reading direction in degrees, counter-clockwise as seen on the page. The writers of
`formats/` (SVG, PDF, DXF, PNG) draw a Page the same way in every format.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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
