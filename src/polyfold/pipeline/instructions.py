"""instructions.html of a make folder: pictures, the sheets, and what glues to what."""

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


def instructions_html(name: str, mesh: Mesh, part_faces: list[np.ndarray], pieces, glue, page_of_piece: list[int],
                      n_pages: int, opts: MakeOptions, sheet_files: list[str]) -> str:
    """instructions.html: the model with its parts in colour, the sheets, and per part its pieces
    and what glues to what (pieces: `SheetPiece`s, glue: `GlueEdge`s, pages 0-based)."""
    part_pieces: dict[int, list[int]] = {}
    for i, p in enumerate(pieces):
        part_pieces.setdefault(p.part, []).append(i)
    css = ("body{font-family:sans-serif;max-width:980px;margin:2em auto;line-height:1.4;color:#222}"
           "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 8px;text-align:left}"
           "img.sheet{width:100%;border:1px solid #ccc;margin:.5em 0}.step{margin:1.5em 0;overflow:auto}"
           ".step img{float:right;margin-left:1em}")
    h = [f"<!doctype html><html><head><meta charset='utf-8'><title>{escape(name)}: assembly</title>"
         f"<style>{css}</style></head><body>",
         f"<h1>Building {escape(name)}</h1>",
         f"<p><img src='data:image/png;base64,{_png_b64(mesh, part_faces, None)}' alt='the model, parts in colour'></p>",
         f"<p>{len(part_faces)} part(s), {len(pieces)} piece(s) on {n_pages} {escape(opts.paper)} page(s); "
         f"model {opts.size:g} mm long. Print <code>sheets.pdf</code> (or <code>sheet-NN.svg</code>) at 100 % "
         "(no scaling: measure the scale bar in the footer) and cut with <code>cut-NN.svg</code> on a cutting "
         "machine (black is cut; red mountain and blue valley lines are scored), or by hand along the black lines; "
         "on paper mountains are red dash-dot and valleys blue dashed. "
         + ("The pages carry print-and-cut registration marks in Silhouette Studio's Type 1 layout "
            f"({MARK_INSET_MM:g} mm inset, {MARK_LEG_MM:g} mm legs, {MARK_LINE_MM:g} mm thick): set the same in its "
            "Registration Marks panel. " if opts.marks else "")
         + "The printed side is the outside of the model: every line is marked as seen from it, so fold "
         "mountains away from you and valleys towards you, tab folds included (a tab folds like its seam, "
         "and tucks under the other copy). Every edge label appears twice: glue the tab of one copy under "
         "the other copy. A label that has no room in its face is printed on its tab or beside its edge "
         "(with a thin leader line); a seam with no room for a tab has a glue strip (piece S and the "
         "label): glue it behind both copies.</p>"
         + ("<p>Some seams are too dense for a label per edge: there, one label names a whole <b>seam "
            "run</b>, several edges in a row between two short ticks drawn into the faces. Glue the run "
            "between the ticks to the run with the same label between its ticks, edge by edge (the tables "
            "list each edge with its run's label).</p>" if any(g.printed != g.label for g in glue) else ""),
         "<h2>Sheets</h2>"]
    for f in sheet_files:
        h.append(f"<img class='sheet' src='{escape(f)}' alt='{escape(f)}'>")
    for part, idx in sorted(part_pieces.items()):
        h.append(f"<div class='step'><h2>Part {part + 1}</h2>"
                 f"<img src='data:image/png;base64,{_png_b64(mesh, part_faces, part)}' alt='part {part + 1}'>")
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
