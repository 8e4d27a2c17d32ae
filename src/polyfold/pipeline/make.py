"""The whole job: a mesh in, a folder of printable, assemblable sheets out.

load -> simplify (--faces) -> inflate -> segment + unfold (`parts`) -> fit to pages (`sheets.fit_parts`, then
`sheets.split_for_pages`) -> fold
(`folding`) -> tabs, labels, packing (`sheets.lay_out`) -> check (`fabricate.check`; in the writer
process beside the export's start where there is one, awaited before anything is written) -> export
(`export`). In: a mesh (a file, or a `Mesh` in memory) and `MakeOptions`. Out: the files of
`export.py`, moved into place only after every check passed, and a `MakeResult` whose `report` is
report.json (`report.MakeReport`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ..deadline import CompileTally, Deadline
from ..errors import OutOfTime, PolyfoldError
from ..fabricate.check import check_pages
from ..fabricate.fit import model_scale, smallest_printed
from ..fabricate.paper import GAP_MM
from ..formats.files import check_folder
from ..mesh.appearance import Appearance
from ..mesh.mesh import Mesh
from ..mesh.repair import LoadedMesh
from .export import OUTPUTS, PrintedLook, load_writers, write_make_folder
from .folding import fold_pieces
from .options import MakeOptions, check_options
from .parts import component_faces, make_parts
from .report import (ChecksReport, ColorReport, ExportReport, GuideReport, InflateReport, InputReport, LayoutReport,
                     LoadReport, MakeReport, PieceReport, SimplifyReport, StageReports, StageSeconds)
from .sheets import PageSplit, Sheets, fit_parts, lay_out, pack_box, split_for_pages

if TYPE_CHECKING:
    from ..processes import Standby

Progress = Callable[[str, str], None]  # (stage, message)


@dataclass(frozen=True)
class MakeResult:
    out_dir: Path
    files: tuple[str, ...]
    report: MakeReport


def _progress_noop(stage: str, message: str) -> None:
    pass


def _load(source: str | os.PathLike | Mesh | LoadedMesh, name: str | None,
          say: Progress) -> tuple[Mesh, Appearance | None, InputReport, LoadReport, str]:
    """The mesh to make, its look (None: the file has none), its report and its name (the file
    name; a Mesh in memory: `name`)."""
    t0 = time.perf_counter()
    look = None
    if isinstance(source, Mesh):
        name = name or "model"
        mesh, n_components, warnings = source, len(component_faces(source)[1]), ()
    else:
        if not isinstance(source, LoadedMesh):
            from ..formats.meshes import load_mesh

            name = name or Path(source).name
            say("load", f"loading {name}")
            source = load_mesh(source)
        name = name or Path(source.path).name
        mesh, n_components, warnings = source.mesh, len(source.components), tuple(source.warnings)
        look = source.appearance
    info = InputReport(file=name, faces=int(mesh.n_faces), vertices=int(mesh.n_vertices), components=n_components,
                       warnings=warnings)
    return mesh, look, info, LoadReport(seconds=time.perf_counter() - t0), name


def _simplify(mesh: Mesh, look: Appearance | None, name: str, opts: MakeOptions,
              say: Progress) -> tuple[Mesh, Appearance | None, SimplifyReport | None]:
    """The mesh reduced to the face count of --faces (`mesh.simplify`) with its look carried over,
    and its report (None: left as it is)."""
    from ..mesh.repair import LoadedMesh
    from ..mesh.simplify import face_target, simplify

    target = face_target(opts.faces, mesh, opts.size)
    if target is None:
        return mesh, look, None
    say("simplify", f"{mesh.n_faces:,} faces to about {target:,} (--faces {opts.faces})")
    keep = look if opts.color != "none" else None  # (no texture to bake when none is printed)
    done = simplify(LoadedMesh(path=name, mesh=mesh, components=(mesh,), warnings=(), appearance=keep), target)
    return done.loaded.mesh, done.loaded.appearance, SimplifyReport(
        spec=opts.faces, faces_before=done.faces_before, faces_after=done.faces_after, hausdorff=done.hausdorff,
        min_angle_deg=done.min_angle_deg, seconds=done.seconds)


def _inflate(mesh: Mesh, opts: MakeOptions, say: Progress) -> tuple[Mesh, InflateReport]:
    if opts.inflate == "none":
        return mesh, InflateReport(mode="none", seconds=0.0)
    from ..inflate.inflate import inflate

    t0 = time.perf_counter()
    say("inflate", f"{opts.inflate} inflation")
    res = inflate(mesh, mode=opts.inflate)
    return res.mesh, InflateReport(mode=opts.inflate, seconds=time.perf_counter() - t0, steps=res.steps,
                                   stop_reason=res.stop_reason, hyperbolic_before=res.hyperbolic_start,
                                   hyperbolic_after=res.hyperbolic, inflation_rate=res.inflation_rate,
                                   notes=tuple(res.notes))


def _check(sheets: Sheets, opts: MakeOptions, name: str, verified: int, say: Progress,
           writer: Standby | None = None) -> Callable[[], ChecksReport]:
    """The independent page checks, started: a call that gives their report, or raises
    PolyfoldError when one failed (asked before anything is written). In the writer process
    when there is one (a 1,500-face model's take 0.2 s, there beside the export's start), else
    here, at once (a failed check raises here)."""
    say("check", "checking every page")
    args = (list(sheets.pieces), sheets.page_of_piece(), sheets.packing.n_pages,
            pack_box(sheets.width, sheets.height, opts), GAP_MM)
    ticket = writer.submit(timed_check, *args) if writer is not None else None
    done = [timed_check(*args)] if writer is None else []

    def report() -> ChecksReport:
        if not done:
            done.append(writer.result(ticket))
        counts, seconds = done[0]
        problems = counts["problems"]
        if problems:
            raise PolyfoldError(f"{name}: sheet check failed, nothing written: {problems[0]}"
                                + (f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""))
        return ChecksReport(seconds=seconds, **{k: v for k, v in counts.items() if k != "problems"},
                            problems=tuple(problems), paths_verified=verified, pieces=len(sheets.pieces),
                            untabbed_edges=tuple(sheets.stats.untabbed))

    if ticket is None:
        report()  # (raises now: the export is not started)
    return report


def timed_check(*args: object) -> tuple[dict, float]:
    """`fabricate.check.check_pages`(*args) and the seconds it took (where it ran)."""
    tc = time.perf_counter()
    return check_pages(*args), time.perf_counter() - tc


# The time limit holds for the whole run. The searches (unfold, fold) end early enough to leave the
# work after them its time: drawing every piece with its tabs and labels, packing, checking and
# writing take about 2-7 ms a face (star-4split-96-loop2, 1,536 faces: 10 s a drawing; a
# 20,480-face sphere: 99 s), so a mesh gets LAYOUT_S + LAYOUT_S_PER_FACE a face of it, at most
# half the limit. The optional layout work (cuts for crowded labels, fewer pages) then stops
# TAIL_S + TAIL_S_PER_FACE a face (at most a quarter of the limit) before the end, for folding,
# packing, checking and writing; the drawing it cannot skip stops the run at the limit.
LAYOUT_S, LAYOUT_S_PER_FACE = 2.0, 0.01
TAIL_S, TAIL_S_PER_FACE = 2.0, 0.001


def time_shares(n_faces: int, time_limit: float) -> tuple[float, float]:
    """(seconds kept back from the searches for the layout and after, seconds kept back from the
    optional layout work for folding, packing, checking and writing) for a mesh of `n_faces`."""
    return (min(0.5 * time_limit, LAYOUT_S + LAYOUT_S_PER_FACE * n_faces),
            min(0.25 * time_limit, TAIL_S + TAIL_S_PER_FACE * n_faces))


def _color_report(look: Appearance | None, opts: MakeOptions, printed: PrintedLook) -> ColorReport:
    """report.json's account of the model's look on the sheets."""
    shown = "none" if look is None or opts.color == "none" else opts.color
    if shown == "texture" and not look.textured.any():
        shown = "flat" if not look.shaded.any() else "texture"  # (vertex colours are printed as pictures)
    return ColorReport(source="none" if look is None else look.kind, mode=opts.color, printed=shown,
                       faces_textured=printed.faces_textured, faces_coloured=printed.faces_coloured,
                       pictures=printed.pictures, dpi=opts.dpi)


MIN_DRAWN_MM = 1e-3  # a face narrower than this on paper (a micrometre) cannot be drawn, let alone cut


def _layout_report(mesh: Mesh, sheets: Sheets, opts: MakeOptions, scale: float, splits: int, split: PageSplit,
                   seconds: float) -> LayoutReport:
    from ..mesh.simplify import auto_face_count

    st = sheets.stats
    edge, face = smallest_printed(mesh, scale)
    fewer = auto_face_count(mesh, opts.size)  # (what a user may simplify to where edges print short)
    x0, y0, x1, y1 = pack_box(sheets.width, sheets.height, opts)
    cut_area = sum(p.outline.area for p in sheets.pieces)  # faces and tabs (glue strips too), no labels
    return LayoutReport(
        seconds=seconds, scale_mm_per_unit=scale, paper=opts.paper, page_mm=(sheets.width, sheets.height),
        margin_mm=opts.margin, pages=sheets.packing.n_pages,
        utilisation=cut_area / (sheets.packing.n_pages * (x1 - x0) * (y1 - y0)), splits_for_page=splits, glue_edges=st.glue_edges, tabs=st.tabs,
        tabs_shrunk=st.tabs_shrunk, tabs_moved=st.tabs_moved, untabbed_edges=tuple(st.untabbed),
        small_labels=st.small_labels, open_edges=st.open_edges, smallest_edge_mm=edge, smallest_face_mm=face,
        reduced_tabs=st.reduced_tabs, labels_on_tabs=st.labels_on_tabs, labels_outside=st.labels_outside,
        seam_runs=st.seam_runs, min_label_mm=opts.min_label_mm, splits_for_packing=split.cuts, splits_for_labels=split.label_cuts,
        packing_ran_out=split.ran_out or sheets.packing.ran_out, labels_ran_out=split.labels_ran_out,
        faces_for_size=fewer if fewer < mesh.n_faces else 0)


def make(source: str | os.PathLike | Mesh | LoadedMesh, out_dir: str | os.PathLike, opts: MakeOptions = MakeOptions(),
         progress: Progress | None = None, *, name: str | None = None,
         ready: Callable[[str], None] | None = None) -> MakeResult:
    """Run the whole pipeline on a mesh file (or a `Mesh` / `LoadedMesh` in memory; `name` names it
    in the report and on the sheets) and write the make folder into `out_dir` (see `export.py`).
    Raises PolyfoldError (nothing written) on bad input, a piece too large for the paper, or a
    failed sheet check. progress(stage, message) as the work goes. ready(stage): called once per
    stage as it starts, before its work (a first run waits there for kernels compiled beside it,
    `apps.warmup.Beside`)."""
    tell = progress or _progress_noop
    compiling = CompileTally()
    started: set[str] = set()

    def say(stage: str, message: str) -> None:
        compiling.enter(stage)
        if ready is not None and stage not in started:
            started.add(stage)
            ready(stage)
        tell(stage, message)

    width, height = check_options(opts)
    inputs = (Path(source),) if isinstance(source, (str, os.PathLike)) else ()
    check_folder(out_dir, OUTPUTS, inputs)
    hard = Deadline.after(opts.time_limit)  # the whole run's
    t0 = time.perf_counter()
    writer = _writer_process()
    try:
        mesh, look, input_report, load_report, name = _load(source, name, say)
        try:
            return _make(mesh, look, name, out_dir, opts, (width, height), say, hard, t0, input_report,
                         load_report, inputs, compiling, writer)
        except OutOfTime as exc:
            raise OutOfTime(f"{name}: stopped at --time-limit {opts.time_limit:g} s while {exc.doing}: its "
                            f"{mesh.n_faces:,} faces need longer (and print small); simplify the mesh first "
                            f"(--faces auto, or --faces N for about N faces) or raise --time-limit",
                            exc.doing) from None
    finally:
        if writer is not None:
            writer.close()


def _writer_process() -> Standby | None:
    """The process that checks the pages and makes the sheets' files and guide.pdf at the end
    (`export.load_writers`: it loads their libraries meanwhile, on the core the load, unfold and
    much of the layout leave idle): where there are two cores and processes may be forked, else
    None."""
    from ..processes import Standby, can_fork, usable_cores

    return Standby(load_writers) if usable_cores() >= 2 and can_fork() else None


def _make(mesh: Mesh, look: Appearance | None, name: str, out_dir: str | os.PathLike, opts: MakeOptions,
          page: tuple[float, float], say: Progress, hard: Deadline, t0: float, input_report: InputReport,
          load_report: LoadReport, inputs: tuple[Path, ...], compiling: CompileTally,
          writer: Standby | None = None) -> MakeResult:
    """`make` after loading (page: width, height in mm): OutOfTime when `hard` passes in work that
    cannot be skipped. writer: the export's (`_writer_process`)."""
    width, height = page
    mesh, look, simplify_report = _simplify(mesh, look, name, opts, say)
    layout_s, tail_s = time_shares(mesh.n_faces, opts.time_limit)
    searches, optional = hard.before(layout_s), hard.before(tail_s)
    mesh, inflate_report = _inflate(mesh, opts, say)
    approximate_report, original, contacts, glued_to = None, None, (), None
    if opts.approximate == "hulls":
        from .approximate import approximate_mesh, contacts_of_parts

        original = mesh
        mesh, segment_report, approximate_report, glued_to = approximate_mesh(mesh, opts, searches, say)
        look = None  # the polyhedra's sides are not the model's faces: nothing to print on them
        # every polyhedron is a component of its own, unfolded whole (convex: one piece)
        parts, _, unfold_report = make_parts(mesh, replace(opts, tau=None, parts=None, segment="auto"), searches,
                                             say, hard=hard)
        contacts = contacts_of_parts(approximate_report, [p.faces for p in parts])
    else:
        parts, segment_report, unfold_report = make_parts(mesh, opts, searches, say, hard=hard)
    try:
        scale = model_scale([mesh], opts.size)
    except PolyfoldError as exc:
        raise PolyfoldError(f"{name}: {exc}") from None
    edge, face = smallest_printed(mesh, scale)
    if min(edge, face) < MIN_DRAWN_MM:  # a part far smaller than the rest: nothing to cut or fold
        raise PolyfoldError(f"{name}: at --size {opts.size:g} mm its smallest face prints {min(edge, face):.3g} mm "
                            f"across, too small to draw (under {MIN_DRAWN_MM:g} mm): a part far smaller than the "
                            f"rest? make it on its own, or at a larger --size")
    ts = time.perf_counter()
    say("layout", "fitting pieces to the page")
    box = pack_box(width, height, opts)
    fitted, page_splits = fit_parts(parts, scale, opts, box, name, hard)
    split = split_for_pages(mesh, fitted, scale, opts, box, optional, say, hard=hard)
    fitted = split.parts
    fit_seconds = time.perf_counter() - ts
    folded, fold_report = fold_pieces(fitted, opts, searches, say, scale, hard=hard)
    sheets = lay_out(mesh, folded, scale, opts, width, height, hard, say, planned=split, glued_to=glued_to)
    checked = _check(sheets, opts, name, fold_report.verified, say, writer)
    if approximate_report is not None:
        approximate_report = replace(approximate_report, unmarked_sides=sheets.unnoted_sides)
    layout_report = _layout_report(mesh, sheets, opts, scale, page_splits, split, sheets.seconds + fit_seconds)
    te = time.perf_counter()
    say("export", "writing sheets and files" + (" and the assembly guide" if opts.guide else ""))

    def finish(rows: tuple[PieceReport, ...], outputs: list[str], printed: PrintedLook, pdf_size: int,
               guide: GuideReport | None) -> MakeReport:
        stages = StageReports(load=load_report, inflate=inflate_report, segment=segment_report, unfold=unfold_report,
                              fold=fold_report, layout=layout_report,
                              export=ExportReport(seconds=time.perf_counter() - te, pages=sheets.packing.n_pages,
                                                  pdf_bytes=pdf_size),
                              simplify=simplify_report, color=_color_report(look, opts, printed), guide=guide,
                              approximate=approximate_report)
        return MakeReport(input=input_report, options=opts, stages=stages, pieces=rows, checks=checked(),
                          outputs=(*outputs, "report.json"), seconds=time.perf_counter() - t0,
                          compile_seconds=tuple(StageSeconds(stage, round(s, 2))
                                                for stage, s in compiling.by_stage().items()))

    if look is not None and opts.color != "none":
        say("export", f"printing the model's {'texture' if look.textured.any() and opts.color == 'texture' else 'colours'}")
    files, report = write_make_folder(out_dir, name, mesh, opts, fitted, folded, sheets, finish, inputs,
                                      look=look, original=original, contacts=contacts, writer=writer,
                                      before_writing=checked)
    return MakeResult(out_dir=Path(out_dir), files=files, report=report)
