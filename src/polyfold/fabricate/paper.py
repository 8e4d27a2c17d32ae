"""Sizes on paper shared by the sheet code and the front ends, in mm (light: the command line
reads them at start-up).

Registration marks (`make --marks`) follow Silhouette Studio's "Type 1" print-and-cut layout
(CAMEO, Portrait, Curio): a filled square at the top-left corner and L-shaped corner marks at
the top-right and bottom-left, `MARK_INSET_MM` from the page's edges (Studio's smallest inset;
to the square's outer sides and the centre lines of the L legs, as the inkscape-silhouette
extension draws them), the L legs `MARK_LEG_MM` long and `MARK_LINE_MM` thick. Studio hatches the corner squares
`MARK_CLEAR_MM` from the edges (the marks and the area the optical sensor scans) as "do not
print"; pieces keep out of them.
"""

import math

GAP_MM = 3.0  # minimum distance between pieces on a page, tabs included (room for scissors)
FOOTER_MM = 6.0  # strip at the bottom of the printable area for the footer line and the scale bar
FOOTER_FONT_MM = 2.5  # the footer line's font size
SCALE_BAR_MM = 50.0  # the scale bar in every page's footer: measure it to check 100 % printing

MARK_INSET_MM = 10.0  # page edges to a registration mark
MARK_SQUARE_MM = 5.0  # the filled top-left square's side
MARK_LEG_MM = 20.0  # length of each leg of the L-shaped corner marks
MARK_LINE_MM = 0.5  # thickness of the L legs
MARK_CLEAR_MM = MARK_INSET_MM + MARK_LEG_MM  # corner squares kept free of pieces, from the page's edges
CAP_HEIGHT = 0.718  # Helvetica's cap height per em: a label's printed height, the DXF text height
MIN_LABEL_MM = 2.0  # default least cap height of a label (`--min-label-mm`): readable when printed
BUILDABLE_EDGE_MM = 5.0  # shorter printed edges are hard to cut, fold and glue: make warns


def size_for_edge(size_mm: float, smallest_edge_mm: float, edge_mm: float = BUILDABLE_EDGE_MM) -> int:
    """The --size (mm, rounded up to a whole mm) at which the smallest printed edge, now
    smallest_edge_mm at size_mm, becomes edge_mm (the scale is proportional to the size)."""
    return math.ceil(size_mm * edge_mm / smallest_edge_mm)


# The model's look on the sheets (`fabricate.paint`): --color texture (the file's texture and
# colours), flat (one mean colour per face) or none (plain); textures rastered at --dpi.
COLOR_MODES = ("texture", "flat", "none")
DPI = 300.0
DPI_RANGE = (30.0, 1200.0)
