"""The two documents of a make folder, as types: `MakeReport` (report.json) and `Assembly`
(assembly.json). `make` writes them, the viewer and batch read them back through `from_dict`,
so the keys live here only (the README documents them).

`to_json` gives the files' exact text (key order = field order). `from_dict` raises ValueError
(with the offending key) on a document of another layout: callers treat that as "not a finished
make of this version".
"""

from __future__ import annotations

import json
import types
import typing
from dataclasses import MISSING, dataclass, fields, is_dataclass

import numpy as np

from .options import MakeOptions

REPORT_VERSION = 1


# ----------------------------------------------------------------------------------------------
# report.json


@dataclass(frozen=True)
class InputReport:
    file: str
    faces: int
    vertices: int
    components: int
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class LoadReport:
    seconds: float


@dataclass(frozen=True)
class SimplifyReport:
    """--faces: what the simplification did (`mesh.simplify.Simplified`); hausdorff is relative to
    the input's bounding-box diagonal."""

    spec: str
    faces_before: int
    faces_after: int
    hausdorff: float
    min_angle_deg: float
    seconds: float


@dataclass(frozen=True)
class InflateReport:
    """mode "none": only mode and seconds are written."""

    mode: str
    seconds: float
    steps: int | None = None
    stop_reason: str | None = None
    hyperbolic_before: int | None = None
    hyperbolic_after: int | None = None
    inflation_rate: float | None = None
    notes: tuple[str, ...] | None = None


@dataclass(frozen=True)
class SegmentReport:
    mode: str
    tau: float | None
    parts: int
    concavity: tuple[float, ...]
    seconds: float
    segmented_components: tuple[int, ...]


@dataclass(frozen=True)
class ApproximateReport:
    """`make --approximate hulls`: every part of the segmentation built as a convex polyhedron.

    Per part: faces_before (triangles of its clipped hull), faces_after (of the piece built),
    facets (its flat sides), hausdorff_out / hausdorff_in (approximation to the part's surface /
    surface to approximation, over the mesh's bbox diagonal), volume_ratio (approximation over
    the model's volume, all parts). clip_planes: planes that cut overlapping hulls apart;
    overlapping_pairs: pairs of parts the independent check (an LP per pair) found overlapping
    (0: interior-disjoint); contacts: (part i, part j, area in model units squared) of the sides
    where two parts touch, to glue them together (each side marked "glue to X" on the sheets, X
    the other side's piece, but `unmarked_sides`, too small to hold the note)."""

    mode: str
    parts: int
    faces_before: tuple[int, ...]
    faces_after: tuple[int, ...]
    facets: tuple[int, ...]
    hausdorff_out: tuple[float, ...]
    hausdorff_in: tuple[float, ...]
    hausdorff_max: float
    volume_ratio: float | None  # None for an open mesh (no volume)
    clip_planes: int
    overlapping_pairs: int
    contacts: tuple[tuple[int, int, float], ...]
    seconds: float
    unmarked_sides: int = 0  # glued sides too small for their "glue to X" note on the sheets


@dataclass(frozen=True)
class NetReport:
    faces: int
    pieces: int
    seconds: float
    method: str
    timed_out: bool
    no_single_net: str | None = None  # why the part has none, when told without a search (`UnfoldStats`)


@dataclass(frozen=True)
class UnfoldReport:
    seconds: float
    nets: tuple[NetReport, ...]


@dataclass(frozen=True)
class FoldReport:
    enabled: bool
    seconds: float
    splits_for_folding: int
    verified: int  # pieces whose path the independent check (verify.paths) accepted
    pieces: int
    thickness_mm: float = 0.0  # the paper thickness the paths were checked at
    rejected_paths: int = 0  # planned paths the independent check rejected (split or reported)


@dataclass(frozen=True)
class LayoutReport:
    seconds: float
    scale_mm_per_unit: float
    paper: str
    page_mm: tuple[float, float]
    margin_mm: float
    pages: int
    utilisation: float  # area cut out (faces and tabs) / (pages x the page area pieces may use)
    splits_for_page: int
    glue_edges: int
    tabs: int
    tabs_shrunk: int
    tabs_moved: int
    untabbed_edges: tuple[str, ...]
    small_labels: int  # glue labels with no readable place (never shrunk: at their face's centroid)
    open_edges: int
    smallest_edge_mm: float  # shortest printed face edge
    smallest_face_mm: float  # smallest height of a printed face (twice its area over its longest side)
    reduced_tabs: tuple[tuple[str, str], ...] = ()  # (edge label, why): "flatter", "lower", "tapered", "split", "glue strip"
    labels_on_tabs: int = 0
    labels_outside: int = 0  # beside their edge, with a leader line when further away
    seam_runs: int = 0  # runs of several glue edges printed with one label (no room for one per edge)
    min_label_mm: float = 2.0  # the least cap height asked for
    splits_for_packing: int = 0  # creases cut so that the pieces fill fewer pages
    splits_for_labels: int = 0  # creases cut where labels found no readable place (before the page split)
    faces_for_size: int = 0  # --faces for faces ~12 mm across at this size (`auto_face_count`) if fewer; else 0
    packing_ran_out: bool = False  # the packer's time budget stopped its search
    labels_ran_out: bool = False  # the time limit stopped the cuts for labels with no readable place


@dataclass(frozen=True)
class ExportReport:
    seconds: float
    pages: int
    pdf_bytes: int = 0  # the size of sheets.pdf


@dataclass(frozen=True)
class ColorReport:
    """--color: what the sheets print of the model's look. source: what the file had (texture,
    vertex, face colours, or none); mode: the --color asked for; printed: texture, flat or none
    (what was printed); faces_textured / faces_coloured: faces printed from a texture / in
    colours; pictures: pieces printed as a picture at `dpi`."""

    source: str
    mode: str
    printed: str
    faces_textured: int
    faces_coloured: int
    pictures: int
    dpi: float


@dataclass(frozen=True)
class GuideReport:
    """The assembly guide (guide.pdf and instructions.html): seconds to build it (plan and
    pictures; writing is in export's), its steps, pictures, pages of guide.pdf, and the seams
    glued once no finger fits inside (closed from outside)."""

    seconds: float
    steps: int
    pictures: int
    pdf_pages: int
    closing_seams: tuple[str, ...] = ()


@dataclass(frozen=True)
class StageReports:
    load: LoadReport
    inflate: InflateReport
    segment: SegmentReport
    unfold: UnfoldReport
    fold: FoldReport
    layout: LayoutReport
    export: ExportReport
    simplify: SimplifyReport | None = None  # only when the mesh was simplified
    color: ColorReport | None = None  # the model's look on the sheets
    guide: GuideReport | None = None  # None with --no-guide
    approximate: ApproximateReport | None = None  # --approximate hulls


@dataclass(frozen=True)
class PieceReport:
    piece: str
    part: int
    faces: int
    page: int  # 1-based
    fold_file: str
    path_verified: bool
    linear: bool | None
    planner: str | None
    path_seconds: float
    frames: int
    note: str


@dataclass(frozen=True)
class ChecksReport:
    seconds: float
    page_overlaps: int
    net_overlaps: int
    tab_overlaps: int
    outside_margins: int
    problems: tuple[str, ...]
    paths_verified: int
    pieces: int
    untabbed_edges: tuple[str, ...]


@dataclass(frozen=True)
class StageSeconds:
    stage: str
    seconds: float


@dataclass(frozen=True)
class MakeReport:
    """report.json. polyfold_report: REPORT_VERSION."""

    input: InputReport
    options: MakeOptions
    stages: StageReports
    pieces: tuple[PieceReport, ...]
    checks: ChecksReport
    outputs: tuple[str, ...]
    seconds: float
    polyfold_report: int = REPORT_VERSION
    # numba compiling its kernels in this run (a first run after install; none once cached), by
    # stage; not counted against --time-limit (`deadline.clock`)
    compile_seconds: tuple[StageSeconds, ...] = ()

    def to_dict(self) -> dict:
        d = _plain(self)
        d = {"polyfold_report": d.pop("polyfold_report"), **d}
        if self.stages.inflate.mode == "none":
            d["stages"]["inflate"] = {"mode": "none", "seconds": self.stages.inflate.seconds}
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1) + "\n"

    @classmethod
    def from_dict(cls, data: dict) -> MakeReport:
        if not isinstance(data, dict) or data.get("polyfold_report") != REPORT_VERSION:
            raise ValueError("not a polyfold make report of this version")
        return _build(cls, data, "report")


# ----------------------------------------------------------------------------------------------
# assembly.json


@dataclass(frozen=True)
class AssemblyPart:
    part: int
    faces: int
    obj: str
    pieces: tuple[str, ...]


@dataclass(frozen=True)
class AssemblyPiece:
    piece: str
    part: int
    page: int  # 1-based
    fold: str


@dataclass(frozen=True)
class GlueRow:
    """Two cut edges glued together: their label, the two pieces, whether they join two parts,
    the piece whose side carries the tab (None: no tab fits), the mesh edge's two vertices, and
    the label printed for them (their own, or that of the seam run they are in)."""

    label: str
    pieces: tuple[str, str]
    between_parts: bool
    tab_on: str | None
    mesh_vertices: tuple[int, int]
    printed_label: str  # the label printed beside both copies: `label`, or its seam run's


@dataclass(frozen=True)
class AssemblyStep:
    """One build step of the guide: its number and kind (piece: fold and attach a new piece;
    glue: more seams; join: a built part to the others), the part, the new piece (None for glue
    and join steps), the glue labels in gluing order, the placed pieces they glue to, the sheets
    used (1-based) and the glue strips."""

    step: int
    kind: str
    part: int
    piece: str | None
    labels: tuple[str, ...]
    attach_to: tuple[str, ...]
    sheets: tuple[int, ...]
    strips: tuple[str, ...] = ()


@dataclass(frozen=True)
class Assembly:
    """assembly.json: what the pieces are, where they go, what glues to what."""

    model: str
    size_mm: float
    paper: str
    pages: int
    parts: tuple[AssemblyPart, ...]
    pieces: tuple[AssemblyPiece, ...]
    glue: tuple[GlueRow, ...]
    steps: tuple[AssemblyStep, ...] = ()  # the guide's build order (none with --no-guide)

    def to_json(self) -> str:
        return json.dumps(_plain(self), indent=1) + "\n"

    @classmethod
    def from_dict(cls, data: dict) -> Assembly:
        return _build(cls, data, "assembly")


# ----------------------------------------------------------------------------------------------
# (de)serialisation


def _plain(obj):
    """JSON-ready value of a report dataclass (numpy scalars as Python numbers)."""
    if is_dataclass(obj):
        return {f.name: _plain(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def _build(cls, data, where: str):
    """An instance of dataclass `cls` from its JSON dict (nested dataclasses and tuples by the
    field types); ValueError naming the key when something is missing or of the wrong kind."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected an object")
    hints = typing.get_type_hints(cls)
    kw = {}
    for f in fields(cls):
        if f.name in data:
            kw[f.name] = _value(hints[f.name], data[f.name], f"{where}.{f.name}")
        elif f.default is MISSING:
            raise ValueError(f"{where}: no {f.name!r}")
    return cls(**kw)


def _value(tp, value, where: str):
    """`value` (from JSON) as type `tp`: X | None, tuple[X, ...], tuple[X, Y], a dataclass, or a
    plain int / float / str / bool."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        if value is None and type(None) in typing.get_args(tp):
            return None
        (tp,) = [a for a in typing.get_args(tp) if a is not type(None)]
    if is_dataclass(tp):
        return _build(tp, value, where)
    if typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, list) or (args[-1] is not Ellipsis and len(value) != len(args)):
            raise ValueError(f"{where}: expected a list of {len(args) if args[-1] is not Ellipsis else 'any'} values")
        items = [args[0]] * len(value) if args[-1] is Ellipsis else args
        return tuple(_value(t, v, f"{where}[{k}]") for k, (t, v) in enumerate(zip(items, value)))
    if tp is float and isinstance(value, (int, float)) and not isinstance(value, bool):
        return value  # kept as written (JSON 30 is a float field's 30): the round trip is exact
    if not isinstance(value, tp) or (tp is int and isinstance(value, bool)):
        raise ValueError(f"{where}: expected {tp.__name__}, got {type(value).__name__}")
    return value
