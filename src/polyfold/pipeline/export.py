"""make's export stage: the make folder, written through formats/ into a staged folder and moved
in at the end (report.json last, so it marks a finished run).

The folder: sheets.pdf (all pages), sheet-NN.svg (print), cut-NN.svg (cutting machines: cut and
score lines only) and sheet-NN.dxf per page, part-K.obj per part, model.glb (the model as made in
the look the sheets print; only for a model with a texture or colours), piece-X.fold per piece (net,
folding path, source faces; in mm where it is printed, with its page and sheet transform:
`formats.fold.piece_fold`), assembly.json (with the build steps), instructions.html, guide.pdf
(the assembly guide, `guide.guide`, as pages of the sheets' size; not with --no-guide) and
report.json. Every printed page
has a scale bar in its footer; with --marks, registration marks. Files an earlier run wrote that
this run does not produce are removed (they would be mistaken for this run's); no other file is
touched, and the input mesh is never replaced (`formats.files.StagedFolder`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from ..fabricate.pack import Placement
from ..fabricate.paint import page_looks
from ..fabricate.page import Page, footer, page_of, registration_marks
from ..formats.dxf import dxf_string
from ..formats.files import StagedFolder
from ..formats.fold import dumps, piece_fold
from ..formats.guide_pdf import guide_pdf_bytes
from ..formats.meshes import look_glb, obj_text
from ..formats.pdf import pdf_bytes
from ..formats.svg import cut_svg_string, svg_page_string
from ..mesh.appearance import Appearance, flat_look
from ..mesh.mesh import Mesh
from ..unfold.net import Net
from ..unfold.pattern import CreasePattern
from .folding import FoldedPiece
from .instructions import guide_intro, instructions_html
from .options import MakeOptions
from .parts import Part
from .report import (Assembly, AssemblyPart, AssemblyPiece, AssemblyStep, GlueRow, GuideReport, MakeReport,
                     PieceReport)
from .sheets import Sheets, pack_box

if TYPE_CHECKING:
    from ..guide.guide import Guide
    from ..processes import Standby

# pictures from which guide.pdf is written in a forked process while instructions.html is written
# here (a 1,280-face sphere's 154: 0.24 and 0.52 s; the bunny's 69: 0.04 and 0.13 s, its make
# 0.02-0.03 s shorter; periscope-28's 26: the fork costs what the html takes)
PARALLEL_GUIDE_PICTURES = 40
# every name make may write into its folder (`files.check_folder` before the run)
OUTPUTS = ("sheets.pdf", "sheet-*.svg", "cut-*.svg", "sheet-*.dxf", "part-*.obj", "model.glb", "piece-*.fold",
           "assembly.json", "instructions.html", "guide.pdf", "report.json", "original.obj")


@dataclass(frozen=True)
class PrintedLook:
    """What the sheets print of the model's look: faces from a texture, faces in colour (a fill or
    a picture), pieces printed as a picture."""

    faces_textured: int = 0
    faces_coloured: int = 0
    pictures: int = 0


def sheet_pages(sheets: Sheets, name: str, opts: MakeOptions,
                look: Appearance | None = None) -> tuple[list[Page], PrintedLook]:
    """One `Page` per sheet: its pieces in the model's look (`fabricate.paint`, --color, --dpi),
    the footer line and scale bar in the footer strip (below the packed area, beside the marks'
    corner with --marks), the registration marks with --marks; and what they print of the look."""
    n_pages = sheets.packing.n_pages
    on_page = sheets.page_of_piece()
    x0, _, x1, strip_top = pack_box(sheets.width, sheets.height, opts)
    marks = registration_marks(sheets.width, sheets.height) if opts.marks else None
    pages = []
    printed = PrintedLook()
    for k in range(n_pages):
        pieces = [p for i, p in enumerate(sheets.pieces) if on_page[i] == k]
        page = page_of(pieces, sheets.width, sheets.height)
        fills, images = page_looks(pieces, look, opts.color, opts.dpi)
        if fills:
            fids = np.concatenate([np.asarray(p.face_ids, dtype=np.int64) for p in pieces])
            printed = PrintedLook(printed.faces_textured + (int(look.textured[fids].sum()) if images else 0),
                                  printed.faces_coloured + len(fids), printed.pictures + len(images))
        text, bar = footer(f"{name} - sheet {k + 1}/{n_pages} - {opts.size:g} mm - polyfold", x0, x1, strip_top)
        pages.append(replace(page, texts=(*page.texts, text), scale_bar=bar, marks=marks, face_colors=fills,
                             images=images))
    return pages, printed


def pattern_to_page(pattern: CreasePattern, net: Net, scale: float, placement: Placement) -> np.ndarray:
    """The affine map (2, 3) from a piece's crease pattern coordinates (model units, y up; the
    net's corners translated) to where the piece is printed on its page (mm, y down): scaled and
    y flipped as `fabricate.pieces` draws it, then rotated and moved by the packer's placement."""
    shift = (pattern.coords[pattern.faces] - net.coords).reshape(-1, 2).mean(axis=0)  # pattern = net + shift
    origin, ex, ey = placement.apply(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    linear = np.column_stack([ex - origin, ey - origin]) @ np.diag([scale, -scale])  # rotation @ flip @ scale
    return np.column_stack([linear, origin - linear @ shift])


def piece_reports(folded: list[FoldedPiece], sheets: Sheets) -> tuple[PieceReport, ...]:
    """report.json's row of every piece."""
    pages = sheets.page_of_piece()
    return tuple(PieceReport(piece=p.name, part=fp.part, faces=int(len(fp.fids)), page=pages[i] + 1,
                             fold_file=f"piece-{p.name}.fold", path_verified=fp.info.path, linear=fp.info.linear,
                             planner=fp.info.planner, path_seconds=fp.info.seconds, frames=fp.info.frames,
                             note=fp.info.note)
                 for i, (fp, p) in enumerate(zip(folded, sheets.pieces)))


def assembly(model: str, opts: MakeOptions, parts: list[Part], sheets: Sheets,
             rows: tuple[PieceReport, ...], guide=None) -> Assembly:
    """assembly.json: parts, pieces, glue pairs and the guide's build steps."""
    pieces = sheets.pieces
    steps = () if guide is None else tuple(
        AssemblyStep(step=st.number, kind=st.kind, part=plan_step.part, piece=st.piece, labels=st.labels,
                     attach_to=st.attach_to, sheets=st.sheets, strips=st.strips)
        for st, plan_step in zip(guide.steps, guide.plan.steps))
    return Assembly(
        model=model, size_mm=opts.size, paper=opts.paper, pages=sheets.packing.n_pages,
        parts=tuple(AssemblyPart(part=k, faces=int(len(part.faces)), obj=f"part-{k}.obj",
                                 pieces=tuple(p.name for p in pieces if p.part == k)) for k, part in enumerate(parts)),
        pieces=tuple(AssemblyPiece(piece=r.piece, part=r.part, page=r.page, fold=r.fold_file) for r in rows),
        glue=tuple(GlueRow(label=g.label, pieces=(pieces[g.pieces[0]].name, pieces[g.pieces[1]].name),
                           between_parts=pieces[g.pieces[0]].part != pieces[g.pieces[1]].part,
                           tab_on=pieces[g.tab_piece].name if g.tab_piece is not None else None,
                           mesh_vertices=tuple(int(v) for v in g.mesh_edge), printed_label=g.printed)
                    for g in sheets.glue),
        steps=steps)


# what the sheets' and the guide's writers import when first used (`load_writers`)
WRITER_MODULES = ("ezdxf", "PIL.JpegImagePlugin", "reportlab.lib.styles", "reportlab.pdfgen.canvas", "reportlab.platypus")


def load_writers() -> None:
    """Import the libraries the file writers load when first used (ezdxf 0.13 s, reportlab's
    platypus 0.09 s here): the prepare() of make's writer process (`processes.Standby`), which
    loads them while the model is laid out."""
    import importlib

    for name in WRITER_MODULES:
        importlib.import_module(name)


def sheet_files(pages: list[Page], svgs: list[str], model: str) -> list[tuple[str, str | bytes]]:
    """sheets.pdf, then per page its SVG (named svgs[k]), cut SVG and DXF: (name, contents)."""
    out: list[tuple[str, str | bytes]] = [("sheets.pdf", pdf_bytes(pages, title=f"{model}: polyfold sheets"))]
    for k, page in enumerate(pages):
        out += [(svgs[k], svg_page_string(page)), (f"cut-{k + 1:02d}.svg", cut_svg_string(page)),
                (f"sheet-{k + 1:02d}.dxf", dxf_string(page))]
    return out


def write_make_folder(out_dir: str | Path, model: str, mesh: Mesh, opts: MakeOptions, parts: list[Part],
                      folded: list[FoldedPiece], sheets: Sheets,
                      finish: Callable[[tuple[PieceReport, ...], list[str], PrintedLook, int, GuideReport | None],
                                       MakeReport],
                      inputs: tuple[Path, ...] = (), look: Appearance | None = None, original: Mesh | None = None,
                      contacts: tuple[tuple[int, int], ...] = (), writer: Standby | None = None,
                      before_writing: Callable[[], object] | None = None) -> tuple[tuple[str, ...], MakeReport]:
    """Write the make folder (see the module docstring); return the file names, in the order
    written, and the report. finish(piece rows, outputs so far, what the sheets print of the
    model's `look`, sheets.pdf's size in bytes, the guide's report or None) gives the report,
    written last. inputs: the files make read (never replaced). original: the mesh a convex
    approximation (`--approximate hulls`) stands for, written as original.obj (the viewer shows
    it beside the parts); contacts: the pairs of parts glued face to face (the guide says which).
    writer: a process that has the writers' libraries loaded (`load_writers`): the sheets' files
    and guide.pdf are made there while the guide and instructions.html are made here; without
    one, the sheets' files are made in a process forked now. before_writing(): called when the
    files are made, before any is written (make's sheet check, which may raise: nothing written)."""
    from ..processes import beside, usable_cores

    pages, printed = sheet_pages(sheets, model, opts, look)
    rows = piece_reports(folded, sheets)
    svgs = [f"sheet-{k + 1:02d}.svg" for k in range(len(pages))]  # (instructions.html shows them)

    def build() -> Guide | None:
        if not opts.guide:
            return None
        from ..guide.guide import build_guide

        return build_guide(mesh, sheets.pieces, sheets.glue, sheets.page_of_piece(), folded, sheets.scale)

    def html_file(guide: Guide | None) -> str:
        return instructions_html(model, mesh, [p.faces for p in parts], sheets.pieces, sheets.glue,
                                 sheets.page_of_piece(), sheets.packing.n_pages, opts, svgs, guide, contacts)

    def pdf_args(guide: Guide) -> tuple:
        intro = guide_intro(opts, sheets.packing.n_pages, len(parts), sheets.pieces,
                            any(g.printed != g.label for g in sheets.glue), contacts)
        return guide, f"Building {model}", (sheets.width, sheets.height), intro

    def model_files() -> list[tuple[str, str | bytes]]:
        """part-K.obj, original.obj, model.glb and piece-X.fold: (name, contents)."""
        out: list[tuple[str, str | bytes]] = []
        for k, part in enumerate(parts):
            sub = mesh.submesh(part.faces)
            out.append((f"part-{k}.obj", obj_text(sub.vertices, sub.faces, f"part {k} of {model} (polyfold make)")))
        if original is not None:
            out.append(("original.obj", obj_text(original.vertices, original.faces,
                                                 f"{model} as approximated by the parts (polyfold make)")))
        if look is not None and opts.color != "none":  # the model as made, in the look printed (the viewer shows it)
            shown = look if opts.color == "texture" else flat_look(look)
            out.append(("model.glb", look_glb(mesh.vertices, mesh.faces, shown)))
        for fp, piece, row, placement in zip(folded, sheets.pieces, rows, sheets.packing.placements):
            out.append((row.fold_file, dumps(piece_fold(
                fp.pattern, title=f"part {fp.part} piece", file_title=f"{model} piece {piece.name} (part {fp.part})",
                whole_mesh_faces=fp.mesh_faces, path=fp.path, resolution_deg=opts.resolution_deg,
                contact_tol=opts.contact_tol, thickness=opts.thickness / sheets.scale, verified=fp.info.path,
                mm_per_unit=sheets.scale, page=row.page,
                to_page=pattern_to_page(fp.pattern, fp.net, sheets.scale, placement)))))
        return out

    def here_files(guide: Guide | None) -> tuple[str, list[tuple[str, str | bytes]]]:
        """instructions.html and `model_files`: made here while guide.pdf is made elsewhere."""
        return html_file(guide), model_files()

    def html_and_pdf(guide: Guide) -> tuple[str, list[tuple[str, str | bytes]], bytes, int]:
        """`here_files` and guide.pdf (its bytes and pages)."""
        if usable_cores() >= 2 and guide.pictures >= PARALLEL_GUIDE_PICTURES:
            # side by side: guide.pdf in a forked process (the sheets' process is done by then, or
            # nearly), the rest here meanwhile
            (html, files), (pdf, n) = beside(lambda: here_files(guide), lambda: guide_pdf_bytes(*pdf_args(guide)))
            return html, files, pdf, n
        return *here_files(guide), *guide_pdf_bytes(*pdf_args(guide))

    if writer is not None:
        # the writer's libraries were loaded while the model was laid out: the bunny's export
        # 0.47 -> 0.39 s (its sheets' files 0.05 s there, 0.18 s in a process forked now). guide.pdf
        # goes there too when the sheets are done by the time the guide is (a 1,500-face model's
        # take 0.9 s there, as long as its guide here: then a process forked now is sooner)
        sheets_ticket = writer.submit(sheet_files, pages, svgs, model)
        guide = build()
        if guide is None:
            (html, files), guide_pdf, guide_pages = here_files(None), None, 0
        elif writer.answered(sheets_ticket):
            pdf_ticket = writer.submit(guide_pdf_bytes, *pdf_args(guide))
            html, files = here_files(guide)
            guide_pdf, guide_pages = writer.result(pdf_ticket)
        else:
            html, files, guide_pdf, guide_pages = html_and_pdf(guide)
        sheet_out = writer.result(sheets_ticket)
    else:
        def guide_files() -> tuple[Guide | None, str, list[tuple[str, str | bytes]], bytes | None, int]:
            """The guide, instructions.html, `model_files`, guide.pdf and its pages (no guide: None,
            html, the files, None, 0)."""
            guide = build()
            if guide is None:
                return None, *here_files(None), None, 0
            return guide, *html_and_pdf(guide)

        # the guide and the sheets share nothing: made side by side on two cores (the bunny's 0.45 + 0.3 s,
        # a 1,280-face sphere's 2.4 + 1.3 s), the guide here (`processes.beside`): the modules and kernels
        # it loads stay loaded for the next model a process makes (in-process, the bunny's make 1.0-1.1 -> 0.84 s)
        if usable_cores() >= 2:
            (guide, html, files, guide_pdf, guide_pages), sheet_out = beside(
                guide_files, lambda: sheet_files(pages, svgs, model))
        else:
            (guide, html, files, guide_pdf, guide_pages), sheet_out = guide_files(), sheet_files(pages, svgs, model)
    guide_report = None
    if guide is not None:
        closing = tuple(sheets.glue[k].label for st in guide.plan.steps for k in st.hard)
        guide_report = GuideReport(seconds=guide.seconds, steps=len(guide.steps), pictures=guide.pictures,
                                   pdf_pages=guide_pages, closing_seams=closing)
    assembly_json = assembly(model, opts, parts, sheets, rows, guide).to_json()
    if before_writing is not None:
        before_writing()
    with StagedFolder(out_dir, "make", inputs=inputs) as stage:
        for name, data in sheet_out:
            stage.write(name, data)
        pdf = sheet_out[0][1]
        for name, data in files:
            stage.write(name, data)
        stage.write("assembly.json", assembly_json)
        stage.write("instructions.html", html)
        if guide_pdf is not None:
            stage.write("guide.pdf", guide_pdf)
        report = finish(rows, list(stage.names), printed, len(pdf), guide_report)
        stage.write("report.json", report.to_json())
        return stage.commit(), report
