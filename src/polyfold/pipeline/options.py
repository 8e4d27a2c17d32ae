"""What `make` is asked to do: `MakeOptions`, the paper sizes, and the checks every front end
(command line, batch, viewer) runs before any work. Light: no numpy, the CLI imports it at start.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..collide.tolerance import CONTACT_TOL, THICKNESS_MM
from ..errors import PolyfoldError
from ..fabricate.paper import COLOR_MODES, DPI, DPI_RANGE, FOOTER_MM, MARK_CLEAR_MM, MIN_LABEL_MM

PAPERS = {"a4": (210.0, 297.0), "letter": (215.9, 279.4), "a3": (297.0, 420.0), "12x12in": (304.8, 304.8)}
INFLATE_MODES = ("none", "constrained", "uniform")
SEGMENT_MODES = ("auto", "none")
APPROXIMATE_MODES = ("none", "hulls")


@dataclass(frozen=True)
class MakeOptions:
    """Options of `make` (the command line's `polyfold make` options, one for one)."""

    inflate: str = "none"  # none | constrained | uniform
    segment: str = "auto"  # auto | none (ignored when tau or parts is given)
    approximate: str = "none"  # none | hulls: every part built as a convex polyhedron (pipeline/approximate.py)
    tau: float | None = None
    parts: int | None = None
    paper: str = "a4"
    size: float = 150.0  # longest dimension of the built model, mm
    margin: float = 10.0
    tabs: bool = True
    seed: int = 1
    time_limit: float = 60.0
    fold: bool = True  # plan and verify a folding path per piece
    contact_tol: float = CONTACT_TOL
    resolution_deg: float = 1.0
    thickness: float = THICKNESS_MM  # of the paper (mm): faces closer than this collide (verify.paths)
    marks: bool = False  # print-and-cut registration marks (Silhouette "Type 1") on the printed pages
    min_label_mm: float = MIN_LABEL_MM  # least cap height of every label (mm)
    faces: str = "auto"  # simplify first: a face count, auto (meshes over mesh.simplify.AUTO_ABOVE faces) or none
    color: str = "texture"  # the model's look on the sheets: texture (as the file has it), flat or none
    dpi: float = DPI  # raster resolution of printed textures
    guide: bool = True  # write the assembly guide (guide.pdf, the steps in instructions.html)

    @property
    def segments(self) -> bool:
        """Whether the parts are the segmenter's (--tau or --parts), not the mesh's components."""
        return self.tau is not None or self.parts is not None

    @property
    def before_unfold(self) -> bool:
        """Whether make inflates or segments before it unfolds (--inflate, --tau, --parts,
        --approximate hulls, whose parts are segmented first)."""
        return self.inflate != "none" or self.segments or self.approximate != "none"


def paper_size(spec: str) -> tuple[float, float]:
    """'a4' | 'letter' | 'a3' | '12x12in' | 'WxHmm' (e.g. '200x300mm') -> (width, height) in mm."""
    key = spec.strip().lower()
    if key in PAPERS:
        return PAPERS[key]
    m = re.fullmatch(r"(\d+(?:\.\d+)?)x(\d+(?:\.\d+)?)(mm|in)", key)
    if not m:
        raise PolyfoldError(f"unknown paper {spec!r}: use a4, letter, a3, 12x12in or WxHmm (e.g. 200x300mm)")
    f = 25.4 if m.group(3) == "in" else 1.0
    w, h = float(m.group(1)) * f, float(m.group(2)) * f
    if not (w > 0 and h > 0):
        raise PolyfoldError(f"paper {spec!r} has zero size")
    return w, h


def check_options(opts: MakeOptions) -> tuple[float, float]:
    """PolyfoldError (one line) for options make would reject on every mesh; else the page size
    (width, height) in mm."""
    if opts.inflate not in INFLATE_MODES:
        raise PolyfoldError(f"--inflate must be none, constrained or uniform, not {opts.inflate!r}")
    if opts.segment not in SEGMENT_MODES:
        raise PolyfoldError(f"--segment must be auto or none, not {opts.segment!r}")
    if opts.approximate not in APPROXIMATE_MODES:
        raise PolyfoldError(f"--approximate must be none or hulls, not {opts.approximate!r}")
    if not (opts.size > 0 and math.isfinite(opts.size)):
        raise PolyfoldError(f"--size must be a positive number of mm, not {opts.size}")
    if not (0.5 <= opts.min_label_mm <= 10):
        raise PolyfoldError(f"--min-label-mm must be between 0.5 and 10 mm, not {opts.min_label_mm}")
    if not (0 <= opts.thickness <= 5 and math.isfinite(opts.thickness)):
        raise PolyfoldError(f"--thickness must be between 0 and 5 mm, not {opts.thickness}")
    from ..mesh.simplify import check_faces_spec

    check_faces_spec(opts.faces)
    if opts.color not in COLOR_MODES:
        raise PolyfoldError(f"--color must be one of {', '.join(COLOR_MODES)}, not {opts.color!r}")
    if not (DPI_RANGE[0] <= opts.dpi <= DPI_RANGE[1]):
        raise PolyfoldError(f"--dpi must be between {DPI_RANGE[0]:g} and {DPI_RANGE[1]:g}, not {opts.dpi:g}")
    width, height = paper_size(opts.paper)
    if not (0 <= opts.margin and 2 * opts.margin + FOOTER_MM < min(width, height)):
        raise PolyfoldError(f"--margin {opts.margin} mm leaves no room on a {width:g} x {height:g} mm page")
    if opts.marks and not (max(opts.margin, MARK_CLEAR_MM) + opts.margin + FOOTER_MM < min(width, height)
                           and 2 * MARK_CLEAR_MM <= min(width, height)):
        raise PolyfoldError(f"--marks: the registration marks leave no room on a {width:g} x {height:g} mm page "
                            f"with {opts.margin:g} mm margins")
    return width, height
