"""What every sheet writer shares (SVG, PDF, DXF): line styles, colours and text placement.

Page coordinates are millimetres with the origin at the page's top-left corner and y pointing
down (as in SVG). PDF and DXF have y pointing up, so their writers flip y (y' = height - y): the
drawing looks the same in every format, never mirrored.

Text placement, the same in all three writers: (x, y) is the centre of the text, `size` is the
font size (em) in mm, `angle` is the reading direction in degrees, counter-clockwise as seen on
the page. The baseline is placed explicitly (half a cap height below the centre) rather than via
SVG's dominant-baseline, which cutting-machine software ignores.

Line styles: cut = solid black; mountain = red dash-dot; valley = blue dashed; a glue-tab fold
is a mountain on a convex seam and a valley on a concave one (seen from the printed side). Every file is written atomically (`files.atomic_write`).
"""

from __future__ import annotations

import math

import numpy as np

from ..fabricate.page import Page, TextItem
from ..fabricate.paper import CAP_HEIGHT  # centres text vertically, gives the DXF text height


MM_TO_PT = 72.0 / 25.4




# One style table for all writers so SVG, PDF and DXF agree. Pure red / blue because cutting
# software (Silhouette "cut by colour", DXF ACI 1 / 5) maps exact colours to tools.
STROKE_MM = 0.25
LEADER_MM = 0.12  # leader lines to off-face labels: thinner than any cut or score line, black


STYLES = {
    "cut": {"rgb": (0, 0, 0), "dash": ()},
    "mountain": {"rgb": (255, 0, 0), "dash": (3.0, 1.0, 0.5, 1.0)},
    "valley": {"rgb": (0, 0, 255), "dash": (1.5, 1.0)},
}


PREVIEW_RGB = (225, 232, 245)  # light fill under the lines, for on-screen / printed previews


TAB_RGB = (236, 236, 236)  # glue tabs, lighter than the faces


TEXT_RGB = (0, 0, 0)


# On a page printed in the model's colours, lines and labels get a white halo so they stay
# readable on dark textures: lines a HALO_MM wider white stroke under them, labels a white outline
# HALO_TEXT em wide (half of it outside the glyphs).
HALO_RGB = (255, 255, 255)
HALO_MM = 0.2
HALO_TEXT = 0.18


def coloured(page: Page) -> bool:
    """Whether the page prints the model's colours (then lines and labels get halos)."""
    return bool(page.images or page.face_colors)


def text_baseline(t: TextItem) -> tuple[float, float]:
    """Page point (mm, y down) where the centred baseline of `t` starts: half a cap height
    'below' the centre in the text's own frame, so the glyphs end up centred on (x, y)."""
    a = math.radians(t.angle)
    down = (math.sin(a), math.cos(a))  # text-frame "down" on a y-down page, for CCW angle a
    shift = 0.5 * CAP_HEIGHT * t.size
    return t.x + shift * down[0], t.y + shift * down[1]


def crease_layers(page: Page) -> tuple[tuple[str, str, np.ndarray], ...]:
    """(layer style, class, segments) for every scored line. A glue tab tucks under its partner,
    so seen from the printed side it folds like its seam: mountain on a convex seam, valley on a
    concave one (`Page.tab_mountain`)."""
    return (
        ("mountain", "mountain", page.mountain),
        ("valley", "valley", page.valley),
        ("mountain", "tab-fold", page.tab_folds[page.tab_mountain]),
        ("valley", "tab-fold", page.tab_folds[~page.tab_mountain]),
    )
