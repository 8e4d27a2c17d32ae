"""Labels printed on the pieces, in mm (y down): the glue label beside each side of a glued edge,
inside its face, and the piece's name inside its largest face.
"""

from __future__ import annotations

import math

import numpy as np

from .page import TextItem, upright

LABEL_MAX_MM = 3.0
LABEL_MIN_MM = 0.8  # a label smaller than this is reported (it is still placed inside its face)
CHAR_EM = 0.62  # mean advance width of a Helvetica digit/capital, in em


def piece_name(i: int) -> str:
    """A, B, ..., Z, AA, AB, ... (short ids printed on the pieces) for piece index i."""
    s = ""
    i += 1
    while i:
        i, r = divmod(i - 1, 26)
        s = chr(65 + r) + s
    return s


def _inside(tri: np.ndarray, pts: np.ndarray, pad: float) -> bool:
    """All points inside triangle `tri` (either orientation), at least `pad` from its sides."""
    a, b, c = tri
    area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    sgn = 1.0 if area2 > 0 else -1.0
    for p, q in ((a, b), (b, c), (c, a)):
        e = q - p
        ln = math.hypot(e[0], e[1])
        if ln == 0:
            return False
        d = sgn * (e[0] * (pts[:, 1] - p[1]) - e[1] * (pts[:, 0] - p[0])) / ln
        if (d < pad).any():
            return False
    return True


def _text_box(center: np.ndarray, u: np.ndarray, n: np.ndarray, width: float, height: float) -> np.ndarray:
    """The 4 corners of a width x height box centred at `center`, along unit vectors u and n."""
    hw, hh = width / 2, height / 2
    return np.array([center + su * hw * u + sn * hh * n for su in (-1, 1) for sn in (-1, 1)])


def edge_label(tri: np.ndarray, k: int, text: str) -> tuple[TextItem, bool]:
    """Label of edge k (corners k, k+1) of triangle `tri` (3, 2) mm, inside the triangle along
    the edge, as large as fits up to LABEL_MAX_MM. Returns the item and whether it is at least
    LABEL_MIN_MM."""
    p0, p1, third = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
    d = p1 - p0
    length = math.hypot(d[0], d[1])
    u = d / length
    n = np.array([-u[1], u[0]])
    if np.dot(third - p0, n) < 0:
        n = -n
    mid = (p0 + p1) / 2
    angle = upright(math.degrees(math.atan2(-d[1], d[0])))  # y down: visual CCW angle
    s = LABEL_MAX_MM
    while s >= 0.25:
        w, h = CHAR_EM * s * len(text), 0.85 * s
        center = mid + n * (0.25 * s + h / 2)
        if _inside(tri, _text_box(center, u, n, w, h), 0.05 * s):
            return TextItem(text, float(center[0]), float(center[1]), angle, s, "edge-label"), s >= LABEL_MIN_MM
        s *= 0.85
    c = tri.mean(axis=0)  # a sliver: smallest size at the centroid
    return TextItem(text, float(c[0]), float(c[1]), angle, 0.25, "edge-label"), False


def piece_label(faces_xy: np.ndarray, text: str) -> TextItem:
    """The piece id at the incentre of its largest face (by incircle), sized to half its incircle;
    faces_xy (n, 3, 2) mm."""
    a, b, c = faces_xy[:, 0], faces_xy[:, 1], faces_xy[:, 2]
    la, lb, lc = (np.linalg.norm(b - c, axis=1), np.linalg.norm(c - a, axis=1), np.linalg.norm(a - b, axis=1))
    area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    per = la + lb + lc
    r = np.where(per > 0, 2 * area / np.maximum(per, 1e-300), 0.0)
    f = int(np.argmax(r))
    center = (la[f] * a[f] + lb[f] * b[f] + lc[f] * c[f]) / per[f]
    # text box (CHAR_EM * len * s wide, 0.85 s high) well inside the incircle
    size = float(min(6.0, 0.6 * 1.6 * r[f] / max(CHAR_EM * len(text), 0.85)))
    return TextItem(text, float(center[0]), float(center[1]), 0.0, max(size, 0.25), "piece-label")
