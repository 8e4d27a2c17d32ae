"""instructions.html of a make folder: the assembly guide (`guide.guide`), the sheets, and what
glues to what; `guide_intro`, its opening paragraphs, opens guide.pdf too."""

from __future__ import annotations

import base64
from html import escape

import numpy as np

from ..fabricate.paper import MARK_INSET_MM, MARK_LEG_MM, MARK_LINE_MM
from ..formats.png import png_bytes
from ..formats.raster import part_colors, render_mesh
from ..mesh.mesh import Mesh
from .options import MakeOptions


def _png_b64(mesh: Mesh, part_faces: list[np.ndarray], highlight: int | None) -> str:
    """A picture of the model (base64 PNG), parts in colour (only `highlight` when given)."""

    colors = np.full((mesh.n_faces, 3), 215, dtype=np.uint8)
    pal = part_colors(len(part_faces))
    for k, f in enumerate(part_faces):
        if highlight is None or highlight == k:
            colors[f] = pal[k]
    img = render_mesh(mesh.vertices, mesh.faces, colors, width=360, height=270)
    return base64.b64encode(png_bytes(img)).decode("ascii")


def _edge(g) -> str:
    """An edge's row name: its label, and the seam run's label printed for it."""
    return g.label if g.printed == g.label else f"{g.label} (run {g.printed})"


def guide_intro(opts: MakeOptions, n_pages: int, n_parts: int, pieces, seam_runs: bool,
                contacts: tuple[tuple[int, int], ...] = ()) -> list[str]:
    """The paragraphs (plain text) before the guide's pictures, in instructions.html and guide.pdf
    (pieces: the sheets' pieces, glue strips included; contacts: parts glued face to face, a
    convex approximation's)."""
    strips = sum(1 for p in pieces if len(p.face_ids) == 0)
    counted = f"{len(pieces) - strips} piece(s)" + (f" and {strips} glue strip(s)" if strips else "")
    out = [f"{n_parts} part(s), {counted} on {n_pages} {opts.paper} page(s); model {opts.size:g} mm long. "
           "Print sheets.pdf (or sheet-NN.svg) at 100 % (no scaling: measure the scale bar in the footer) and cut "
           "with cut-NN.svg on a cutting machine (black is cut; red mountain and blue valley lines are scored), or "
           "by hand along the black lines; on paper mountains are red dash-dot and valleys blue dashed."]
    if opts.marks:
        out.append("The pages carry print-and-cut registration marks in Silhouette Studio's Type 1 layout "
                   f"({MARK_INSET_MM:g} mm inset, {MARK_LEG_MM:g} mm legs, {MARK_LINE_MM:g} mm thick): set the same "
                   "in its Registration Marks panel.")
    out.append("The printed side is the outside of the model: every line is marked as seen from it, so fold "
               "mountains away from you and valleys towards you, tab folds included (a tab folds like its seam, "
               "and tucks under the other copy). Every edge label appears twice: glue the tab of one copy under "
               "the other copy. A label that has no room in its face is printed on its tab or beside its edge "
               "(with a thin leader line); a seam with no room for a tab has a glue strip (piece S and the "
               "label): glue it behind both copies.")
    if opts.approximate == "hulls":
        out.append(_approximation_intro(n_parts, pieces, contacts))
    if seam_runs:
        out.append("Some seams are too dense for a label per edge: there, one label names a whole seam run, "
                   "several edges in a row between two short ticks drawn into the faces. Glue the run between the "
                   "ticks to the run with the same label between its ticks, edge by edge.")
    return out


def _approximation_intro(n_parts: int, pieces, contacts: tuple[tuple[int, int], ...]) -> str:
    """What a convex approximation's builder does last: which closed parts glue onto which."""
    names: dict[int, list[str]] = {}
    for p in pieces:
        if len(p.face_ids):
            names.setdefault(p.part, []).append(p.name)

    def part(k: int) -> str:
        return f"part {k + 1} (piece{'s' if len(names.get(k, ())) > 1 else ''} {', '.join(names.get(k, ['?']))})"

    text = (f"The model is approximated by {n_parts} convex solids, each a closed part of its own: build every part "
            "(its steps below), then glue the parts together where they touch, flat side on flat side: each such "
            "side is printed \"glue to X\", X the piece whose side it goes onto (a side too small for the words "
            "is not; the pictures of where each piece goes show the model assembled).")
    if contacts:
        text += " Glue " + "; ".join(f"{part(i)} to {part(j)}" for i, j in contacts) + "."
    return text


def _img(pic, css: str = "") -> str:
    """An embedded picture (data URI: the page works offline, alone)."""
    b64 = base64.b64encode(pic.png).decode("ascii")
    h, w = pic.shape
    return (f"<figure{css}><img src='data:image/png;base64,{b64}' width='{w}' height='{h}' alt='{escape(pic.caption)}'>"
            f"<figcaption>{escape(pic.caption)}</figcaption></figure>")


def _guide_html(guide) -> list[str]:
    """The guide's sections: where each piece goes, then the build steps."""
    h = ["<h2 id='where'>Where each piece goes</h2>",
         "<p>Every piece in its own colour, with its letter and the sheet it is printed on.</p>",
         "<div class='grid'>" + "".join(_img(p) for p in guide.overview) + "</div>"]
    for k, pics in enumerate(guide.parts):
        h.append(f"<h3>Part {k + 1}</h3><div class='grid'>" + "".join(_img(p) for p in pics) + "</div>")
    h.append(f"<h2 id='steps'>Build steps</h2><p>{len(guide.steps)} steps. Each step names its sheet, what to fold "
             "and which labels to glue, in order; its picture shows the model after it, the new piece in full "
             "colour, the pieces before it lighter, this step's seams dark with their labels.</p>")
    for st in guide.steps:
        h.append(f"<section class='step' id='step-{st.number}'><h3>{escape(st.title)}</h3>")
        h.append(_img(st.picture, " class='pic'"))
        h += [f"<p>{escape(line)}</p>" for line in st.lines]
        if st.glue:
            h.append("<ol class='glue'>" + "".join(f"<li>{escape(g)}</li>" for g in st.glue) + "</ol>")
        h += [f"<p class='note'>{escape(n)}</p>" for n in st.notes]
        if st.folding:
            h.append("<div class='frames'>" + "".join(_img(p) for p in st.folding) + "</div>")
        h.append("</section>")
    return h


def instructions_html(name: str, mesh: Mesh, part_faces: list[np.ndarray], pieces, glue, page_of_piece: list[int],
                      n_pages: int, opts: MakeOptions, sheet_files: list[str], guide=None,
                      contacts: tuple[tuple[int, int], ...] = ()) -> str:
    """instructions.html: the assembly guide (`guide.guide.Guide`: where each piece goes, the
    build steps with their pictures; without one, the model with its parts in colour), the
    sheets, and per part its pieces and what glues to what (pieces: `SheetPiece`s, glue:
    `GlueEdge`s, pages 0-based)."""
    part_pieces: dict[int, list[int]] = {}
    for i, p in enumerate(pieces):
        part_pieces.setdefault(p.part, []).append(i)
    css = ("body{font-family:sans-serif;max-width:1000px;margin:2em auto;line-height:1.4;color:#222}"
           "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 8px;text-align:left}"
           "img.sheet{width:100%;border:1px solid #ccc;margin:.5em 0}.step{margin:1.5em 0;overflow:auto;"
           "border-top:1px solid #ddd;padding-top:.5em}.step figure.pic{float:right;margin:0 0 .5em 1em}"
           "figure{display:inline-block;margin:.2em;text-align:center}figcaption{font-size:.8em;color:#555}"
           ".frames{clear:both}.note{font-weight:bold}.grid figure{margin:.3em}"
           ".part{margin:1.5em 0;overflow:auto}.part img{float:right;margin-left:1em}")
    seam_runs = any(g.printed != g.label for g in glue)
    h = [f"<!doctype html><html><head><meta charset='utf-8'><title>{escape(name)}: assembly</title>"
         f"<style>{css}</style></head><body>",
         f"<h1>Building {escape(name)}</h1>"]
    if guide is None:
        h.append(f"<p><img src='data:image/png;base64,{_png_b64(mesh, part_faces, None)}' alt='the model, parts in colour'></p>")
    h += [f"<p>{escape(p)}</p>" for p in guide_intro(opts, n_pages, len(part_faces), pieces, seam_runs, contacts)]
    if guide is not None:
        h.append("<p>Contents: <a href='#where'>where each piece goes</a>, <a href='#steps'>build steps</a>, "
                 "<a href='#sheets'>sheets</a>, <a href='#seams'>every seam by part</a>. The same steps are in "
                 "<code>guide.pdf</code>.</p>")
        h += _guide_html(guide)
    h.append("<h2 id='sheets'>Sheets</h2>")
    for f in sheet_files:
        h.append(f"<img class='sheet' src='{escape(f)}' alt='{escape(f)}'>")
    h.append("<h2 id='seams'>Every seam, by part</h2>")
    for part, idx in sorted(part_pieces.items()):
        h.append(f"<div class='part'><h3>Part {part + 1}</h3>")
        if guide is None:
            h.append(f"<img src='data:image/png;base64,{_png_b64(mesh, part_faces, part)}' alt='part {part + 1}'>")
        h.append("<p>Pieces: " + ", ".join(f"<b>{pieces[i].name}</b> (page {page_of_piece[i] + 1})" for i in idx) + "</p>")
        inside = [g for g in glue if pieces[g.pieces[0]].part == part and pieces[g.pieces[1]].part == part]
        if inside:
            h.append("<table><tr><th>edge</th><th>glue</th><th>tab on</th></tr>")
            for g in sorted(inside, key=lambda g: int(g.label)):
                a, b = pieces[g.pieces[0]].name, pieces[g.pieces[1]].name
                tab = pieces[g.tab_piece].name if g.tab_piece is not None else "none (tape it)"
                h.append(f"<tr><td>{_edge(g)}</td><td>{a} &harr; {b}</td><td>{tab}</td></tr>")
            h.append("</table>")
        h.append("</div>")
    between = [g for g in glue if pieces[g.pieces[0]].part != pieces[g.pieces[1]].part]
    if between:
        h.append("<h2>Joining the parts</h2><table><tr><th>edge</th><th>glue</th><th>tab on</th></tr>")
        for g in sorted(between, key=lambda g: int(g.label)):
            a, b = pieces[g.pieces[0]], pieces[g.pieces[1]]
            tab = pieces[g.tab_piece].name if g.tab_piece is not None else "none (tape it)"
            h.append(f"<tr><td>{_edge(g)}</td><td>{a.name} (part {a.part + 1}) &harr; {b.name} (part {b.part + 1})"
                     f"</td><td>{tab}</td></tr>")
        h.append("</table>")
    h.append("<p>Every piece's folding path is in its <code>piece-*.fold</code> file "
             "(FOLD 1.1, <code>polyfold:path</code>).</p></body></html>")
    return "\n".join(h) + "\n"
