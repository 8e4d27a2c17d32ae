"""The whole job: mesh file in, a folder of printable, assemblable sheets out.

load -> inflate -> segment -> unfold -> fit to pages -> fold -> tabs & labels -> pack -> check ->
export. In: a mesh path and `MakeOptions`. Out: the files listed in `make`'s docstring, written
into a temporary folder and moved into place only after every check passed, and a `MakeResult`
whose `report` is what report.json holds (keys documented in the README).
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import NoNetFound, PolyfoldError

PAPERS = {"a4": (210.0, 297.0), "letter": (215.9, 279.4), "a3": (297.0, 420.0), "12x12in": (304.8, 304.8)}
FOOTER_MM = 6.0  # strip at the bottom of the printable area for the page footer
GAP_MM = 3.0  # minimum distance between pieces on a page (room for scissors)
REPORT_VERSION = 1
FOLD_BUDGET_S = 3.0  # planning time per piece before it is split: this + per face
FOLD_BUDGET_PER_FACE_S = 0.03


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


@dataclass(frozen=True)
class MakeOptions:
    inflate: str = "none"  # none | constrained | uniform
    segment: str = "auto"  # auto | none (ignored when tau or parts is given)
    tau: float | None = None
    parts: int | None = None
    paper: str = "a4"
    size: float = 150.0  # longest dimension of the built model, mm
    margin: float = 10.0
    tabs: bool = True
    seed: int = 1
    time_limit: float = 60.0
    fold: bool = True  # plan and verify a folding path per piece
    contact_tol: float = 1e-7
    resolution_deg: float = 1.0


@dataclass(frozen=True)
class MakeResult:
    out_dir: Path
    files: tuple[str, ...]
    report: dict


class _Clock:
    def __init__(self, limit: float) -> None:
        self.t0 = time.perf_counter()
        self.limit = limit

    def left(self) -> float:
        return max(0.0, self.limit - (time.perf_counter() - self.t0))


def _progress_noop(stage: str, message: str) -> None:
    pass


# ----------------------------------------------------------------------------------------------
# Stages


def _inflate(mesh, opts: MakeOptions, say) -> tuple[object, dict]:
    t0 = time.perf_counter()
    if opts.inflate == "none":
        return mesh, {"mode": "none", "seconds": 0.0}
    from ..inflate.inflate import inflate

    say("inflate", f"{opts.inflate} inflation")
    res = inflate(mesh, mode=opts.inflate)
    return res.mesh, {"mode": opts.inflate, "seconds": time.perf_counter() - t0, "steps": res.steps,
                      "stop_reason": res.stop_reason, "hyperbolic_before": res.hyperbolic_start,
                      "hyperbolic_after": res.hyperbolic, "inflation_rate": res.inflation_rate,
                      "notes": list(res.notes)}


def _unfold_parts(mesh, opts: MakeOptions, clock: _Clock, say) -> tuple[list, dict, dict]:
    """(parts as [(face ids, net)], segment report, unfold report)."""
    from ..mesh.mesh import face_components
    from ..segment.segment import DEFAULT_TAU, segment
    from ..unfold.search import unfold

    comp = face_components(mesh.n_faces, mesh.topology)
    components = [np.flatnonzero(comp == c) for c in range(int(comp.max()) + 1)]
    explicit = opts.tau is not None or opts.parts is not None
    mode = "tau" if opts.tau is not None else "parts" if opts.parts is not None else opts.segment
    seg_report = {"mode": mode, "tau": None, "parts": 0, "concavity": [], "seconds": 0.0, "segmented_components": []}
    unfold_report = {"seconds": 0.0, "nets": []}
    budget = max(1.0, 0.5 * opts.time_limit)

    def run_segment(faces: np.ndarray, tau: float | None, parts: int | None) -> list[np.ndarray]:
        ts = time.perf_counter()
        sub = mesh.submesh(faces)
        seg = segment(sub, tau=DEFAULT_TAU if tau is None else tau, parts=parts, seed=0)
        seg_report["seconds"] += time.perf_counter() - ts
        seg_report["tau"] = seg.tau
        seg_report["concavity"] += [float(c) for c in seg.concavity]
        return [faces[f] for f in seg.face_ids]

    if explicit:
        say("segment", f"segmenting ({mode})")
        groups = run_segment(np.arange(mesh.n_faces), opts.tau, opts.parts)
    else:
        groups = components
    out = []
    todo = list(groups)
    while todo:
        faces = todo.pop(0)
        part_mesh = mesh.submesh(faces)
        left = max(0.5, min(budget, clock.left()) / max(1, len(todo) + 1))
        say("unfold", f"part {len(out) + 1}: {len(faces)} faces")
        tu = time.perf_counter()
        try:
            single = mode == "auto" and len(faces) > 1
            net, st = unfold(part_mesh, seed=opts.seed, time_limit=left, max_pieces=1 if single else None)
        except NoNetFound:
            # auto: no single net for this component in time -> split it into nearly convex parts
            unfold_report["seconds"] += time.perf_counter() - tu
            say("segment", f"no single net for a {len(faces)}-face component: segmenting it")
            seg_report["segmented_components"].append(int(comp[faces[0]]))
            subs = run_segment(faces, None, None)
            if len(subs) == 1:  # already nearly convex: accept several pieces instead
                net, st = unfold(part_mesh, seed=opts.seed, time_limit=left)
            else:
                todo = subs + todo
                continue
        unfold_report["seconds"] += time.perf_counter() - tu
        unfold_report["nets"].append({"faces": int(len(faces)), "pieces": int(net.n_pieces), "seconds": st.seconds,
                                      "method": st.method, "timed_out": bool(st.timed_out)})
        out.append((faces, net))
    seg_report["parts"] = len(out)
    if not explicit:
        seg_report["tau"] = DEFAULT_TAU if seg_report["segmented_components"] else None
    return out, seg_report, unfold_report


def _fold_pieces(parts: list, opts: MakeOptions, clock: _Clock, say) -> tuple[list, dict]:
    """Plan a verified folding path per piece. A piece without a path in its time share is split
    in two (fewer faces always fold more easily) and both halves are planned again, at most 3
    times per piece. Returns [(part index, part faces, piece net, piece face ids, FOLD dict,
    fold report)] and the stage report."""
    from ..fold.plan import plan_fold
    from ..formats.fold import with_path
    from ..formats.fold import net_to_fold
    from ..fold.tree import collides, fold_tree
    from ..unfold.net import balanced_cut
    from ..unfold.net import cut_creases, piece_net

    t0 = time.perf_counter()
    results = []
    pending = sum(net.n_pieces for _, net in parts)  # pieces not planned yet (for the time shares)
    splits = 0

    def plan(pi: int, faces: np.ndarray, pnet, fids: np.ndarray, depth: int) -> None:
        """Plan one single-piece net (fids: its faces in the part); split and recurse on failure."""
        nonlocal pending, splits
        fold = net_to_fold([pnet], title=f"part {pi} piece")
        info = {"path": False, "linear": None, "planner": None, "seconds": 0.0, "frames": 0, "note": ""}
        if pnet.mesh.n_faces == 1:
            info.update(path=True, linear=True, planner="trivial", note="single face")
        elif opts.fold:
            say("fold", f"part {pi + 1}/{len(parts)}: planning a path for {pnet.mesh.n_faces} faces")
            tf = time.perf_counter()
            tree = fold_tree(fold, opts.contact_tol)
            if collides(tree, tree.goal):
                info["note"] = "the folded shape itself intersects (input geometry); no path can exist"
            else:
                # a short budget, then split: two halves usually fold at once, while a hard
                # piece can eat the whole time limit
                share = max(0.5, min(clock.left() / max(1, pending),
                                     FOLD_BUDGET_S + FOLD_BUDGET_PER_FACE_S * pnet.mesh.n_faces))
                try:
                    path = plan_fold(tree, resolution_deg=opts.resolution_deg, time_limit=share, seed=opts.seed)
                except PolyfoldError as exc:
                    path, info["note"] = None, str(exc)
                if path is None and depth < 3 and clock.left() > 0:
                    say("fold", f"no path in {share:.1f} s: split the piece in two")
                    halves = cut_creases(pnet, np.array([balanced_cut(pnet, 0)]))
                    splits += 1
                    pending += 1
                    for h in range(2):
                        sub, sub_fids = piece_net(halves, h)
                        plan(pi, faces, sub, fids[sub_fids], depth + 1)
                    return
                if path is not None:
                    fold = with_path(fold, path, opts.resolution_deg, opts.contact_tol)
                    info.update(path=True, linear=bool(path.linear), planner=path.planner, frames=len(path.frames))
                elif not info["note"]:
                    info["note"] = "no path within the time limit"
            info["seconds"] = time.perf_counter() - tf
        pending -= 1
        results.append((pi, faces, pnet, fids, fold, info))

    for pi, (faces, net) in enumerate(parts):
        for k in range(net.n_pieces):
            plan(pi, faces, *piece_net(net, k), 0)
    report = {"enabled": opts.fold, "seconds": time.perf_counter() - t0, "splits_for_folding": splits,
              "verified": sum(r[5]["path"] for r in results), "pieces": len(results)}
    return results, report


# ----------------------------------------------------------------------------------------------
# Outputs


def _png_b64(mesh, part_faces: list[np.ndarray], highlight: int | None) -> str:
    import base64

    from ..formats.png import png_bytes
    from ..formats.raster import part_colors, render_mesh

    colors = np.full((mesh.n_faces, 3), 215, dtype=np.uint8)
    pal = part_colors(len(part_faces))
    for k, f in enumerate(part_faces):
        if highlight is None or highlight == k:
            colors[f] = pal[k]
    img = render_mesh(mesh.vertices, mesh.faces, colors, width=360, height=270)
    return base64.b64encode(png_bytes(img)).decode("ascii")


def _instructions_html(name: str, mesh, part_faces, pieces, glue, page_of_piece, n_pages, opts, sheet_files) -> str:
    from html import escape

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
         f"model {opts.size:g} mm long. Print <code>sheets.pdf</code> at 100 % (no scaling), or send the SVG/DXF "
         "sheets to a cutting machine: layer <b>cut</b> is cut, <b>mountain</b> (red, dash-dot) and "
         "<b>valley</b> (blue, dashed) are scored. Fold mountains away from you and valleys towards you, "
         "with the printed side outside. Every edge label appears twice: glue the tab of one copy under the "
         "other copy.</p>",
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
                h.append(f"<tr><td>{g.label}</td><td>{a} &harr; {b}</td><td>{tab}</td></tr>")
            h.append("</table>")
        h.append("</div>")
    between = [g for g in glue if pieces[g.pieces[0]].part != pieces[g.pieces[1]].part]
    if between:
        h.append("<h2>Joining the parts</h2><table><tr><th>edge</th><th>glue</th><th>tab on</th></tr>")
        for g in sorted(between, key=lambda g: int(g.label)):
            a, b = pieces[g.pieces[0]], pieces[g.pieces[1]]
            tab = pieces[g.tab_piece].name if g.tab_piece is not None else "none (tape it)"
            h.append(f"<tr><td>{g.label}</td><td>{a.name} (part {a.part + 1}) &harr; {b.name} (part {b.part + 1})"
                     f"</td><td>{tab}</td></tr>")
        h.append("</table>")
    h.append("<p>Every piece's folding path is in its <code>piece-*.fold</code> file "
             "(FOLD 1.1, <code>polyfold:path</code>).</p></body></html>")
    return "\n".join(h) + "\n"


# ----------------------------------------------------------------------------------------------
# The job


def make(mesh_path: str | os.PathLike, out_dir: str | os.PathLike, opts: MakeOptions = MakeOptions(),
         progress: Callable[[str, str], None] | None = None) -> MakeResult:
    """Run the whole pipeline on `mesh_path` and write into `out_dir`:

    sheets.pdf (all pages), sheet-NN.svg and sheet-NN.dxf per page, piece-X.fold per piece (net +
    verified folding path), part-K.obj per part, assembly.json (pieces, parts, glue pairs),
    instructions.html (pictures, what glues to what) and report.json. Raises PolyfoldError (nothing
    written) on bad input, a piece too large for the paper, or a failed sheet check."""
    from ..formats.fold import dumps
    from ..formats.meshes import load_mesh, obj_text
    from ..fabricate.check import check_pages
    from ..fabricate.fit import PieceTooLarge, split_to_fit
    from ..fabricate.pack import pack_outlines
    from ..fabricate.page import page_of, place
    from ..fabricate.pieces import build_sheet_pieces, piece_input
    from ..formats.dxf import dxf_document
    from ..formats.pdf import pdf_bytes
    from ..formats.svg import svg_page_string

    say = progress or _progress_noop
    if opts.inflate not in ("none", "constrained", "uniform"):
        raise PolyfoldError(f"--inflate must be none, constrained or uniform, not {opts.inflate!r}")
    if opts.segment not in ("auto", "none"):
        raise PolyfoldError(f"--segment must be auto or none, not {opts.segment!r}")
    if not (opts.size > 0 and math.isfinite(opts.size)):
        raise PolyfoldError(f"--size must be a positive number of mm, not {opts.size}")
    width, height = paper_size(opts.paper)
    if not (0 <= opts.margin and 2 * opts.margin + FOOTER_MM < min(width, height)):
        raise PolyfoldError(f"--margin {opts.margin} mm leaves no room on a {width:g} x {height:g} mm page")
    clock = _Clock(opts.time_limit)
    report: dict = {"polyfold_report": REPORT_VERSION, "input": {}, "options": asdict(opts), "stages": {},
                    "pieces": [], "checks": {}, "outputs": [], "seconds": 0.0}
    name = Path(mesh_path).name

    t0 = time.perf_counter()
    say("load", f"loading {name}")
    loaded = load_mesh(mesh_path)
    mesh = loaded.mesh
    report["input"] = {"file": name, "faces": int(mesh.n_faces), "vertices": int(mesh.n_vertices),
                       "components": len(loaded.components), "warnings": list(loaded.warnings)}
    report["stages"]["load"] = {"seconds": time.perf_counter() - t0}

    mesh, report["stages"]["inflate"] = _inflate(mesh, opts, say)
    parts, report["stages"]["segment"], report["stages"]["unfold"] = _unfold_parts(mesh, opts, clock, say)

    # Scale: the model's longest bounding-box side becomes opts.size mm.
    extent = float(np.ptp(mesh.vertices[np.unique(mesh.faces)], axis=0).max())
    if not extent > 0:
        raise PolyfoldError(f"{name}: the model has zero size")
    scale = opts.size / extent
    pack_page = (width, height - FOOTER_MM)
    ts = time.perf_counter()
    say("layout", "fitting pieces to the page")
    fitted, page_splits = [], 0
    for faces, net in parts:
        try:
            net, cuts = split_to_fit(net, scale, pack_page, opts.margin)
        except PieceTooLarge as exc:
            largest = math.floor(opts.size * exc.factor * 10) / 10
            raise PolyfoldError(f"{name}: at --size {opts.size:g} mm face {exc.face} alone (with its tabs) does not "
                                f"fit on {opts.paper} paper with {opts.margin:g} mm margins; the largest size that "
                                f"fits is {largest:g} mm (or use larger --paper)") from None
        page_splits += cuts
        fitted.append((faces, net))
    fit_seconds = time.perf_counter() - ts

    folded, report["stages"]["fold"] = _fold_pieces(fitted, opts, clock, say)

    tl = time.perf_counter()
    say("layout", f"tabs and labels for {len(folded)} pieces")
    inputs = [piece_input(pnet, pi, mesh.faces[faces[fids]], faces[fids]) for pi, faces, pnet, fids, _, _ in folded]
    pieces, glue, lstats = build_sheet_pieces(inputs, scale, tabs=opts.tabs)
    say("layout", f"packing {len(pieces)} pieces onto {opts.paper} pages")
    outlines = [p.outline for p in pieces]
    packing = pack_outlines(outlines, pack_page, margin=opts.margin, gap=GAP_MM, seed=opts.seed,
                            time_limit=max(2.0, min(10.0, clock.left())))
    placed = [place(p, packing.placements[i]) for i, p in enumerate(pieces)]
    layout_seconds = time.perf_counter() - tl + fit_seconds

    say("check", "checking every page")
    tc = time.perf_counter()
    checks = check_pages(placed, [pl.page for pl in packing.placements], packing.n_pages, width,
                         height - FOOTER_MM, opts.margin, GAP_MM)
    problems = checks["problems"]
    report["checks"] = {"seconds": time.perf_counter() - tc, **checks,
                        "paths_verified": report["stages"]["fold"]["verified"], "pieces": len(pieces),
                        "untabbed_edges": list(lstats.untabbed)}
    if problems:
        raise PolyfoldError(f"{name}: sheet check failed, nothing written: {problems[0]}"
                            + (f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""))

    report["stages"]["layout"] = {
        "seconds": layout_seconds, "scale_mm_per_unit": scale, "paper": opts.paper, "page_mm": [width, height],
        "margin_mm": opts.margin, "pages": packing.n_pages, "utilisation": packing.utilisation,
        "splits_for_page": page_splits, "glue_edges": lstats.glue_edges, "tabs": lstats.tabs,
        "tabs_shrunk": lstats.tabs_shrunk, "tabs_moved": lstats.tabs_moved, "untabbed_edges": list(lstats.untabbed),
        "small_labels": lstats.small_labels, "open_edges": lstats.open_edges}

    # ---- export: everything into a temporary folder, then moved in
    te = time.perf_counter()
    say("export", "writing sheets and files")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".polyfold-make-", dir=out))
    files: list[str] = []
    try:
        page_pieces = [[placed[i] for i in range(len(placed)) if packing.placements[i].page == k]
                       for k in range(packing.n_pages)]
        footer_y = height - opts.margin - FOOTER_MM / 2
        pages = [page_of(pp, width, height, f"{name} - sheet {k + 1}/{packing.n_pages} - "
                         f"{opts.size:g} mm - polyfold", footer_y) for k, pp in enumerate(page_pieces)]
        (tmp / "sheets.pdf").write_bytes(pdf_bytes(pages, title=f"{name}: polyfold sheets"))
        files.append("sheets.pdf")
        sheet_svgs = []
        for k, page in enumerate(pages):
            svg = f"sheet-{k + 1:02d}.svg"
            (tmp / svg).write_text(svg_page_string(page))
            dxf_document(page).saveas(tmp / f"sheet-{k + 1:02d}.dxf")
            files += [svg, f"sheet-{k + 1:02d}.dxf"]
            sheet_svgs.append(svg)
        part_faces = [faces for faces, _ in parts]
        for k, faces in enumerate(part_faces):
            sub = mesh.submesh(faces)
            (tmp / f"part-{k}.obj").write_text(obj_text(sub.vertices, sub.faces, f"part {k} of {name} (polyfold make)"))
            files.append(f"part-{k}.obj")
        piece_rows = []
        for i, (pi, faces, pnet, fids, fold, info) in enumerate(folded):
            fname = f"piece-{pieces[i].name}.fold"
            fold = dict(fold)
            fold["file_title"] = f"{name} piece {pieces[i].name} (part {pi})"
            fold["polyfold:faces_wholeMeshFace"] = [int(x) for x in faces[fids]]
            (tmp / fname).write_text(dumps(fold))
            files.append(fname)
            pl = packing.placements[i]
            piece_rows.append({"piece": pieces[i].name, "part": pi, "faces": int(len(fids)), "page": pl.page + 1,
                               "fold_file": fname, "path_verified": info["path"], "linear": info["linear"],
                               "planner": info["planner"], "path_seconds": info["seconds"], "frames": info["frames"],
                               "note": info["note"]})
        report["pieces"] = piece_rows
        assembly = {
            "model": name, "size_mm": opts.size, "paper": opts.paper, "pages": packing.n_pages,
            "parts": [{"part": k, "faces": int(len(f)), "obj": f"part-{k}.obj",
                       "pieces": [p.name for p in pieces if p.part == k]} for k, f in enumerate(part_faces)],
            "pieces": [{"piece": r["piece"], "part": r["part"], "page": r["page"], "fold": r["fold_file"]} for r in piece_rows],
            "glue": [{"label": g.label, "pieces": [pieces[g.pieces[0]].name, pieces[g.pieces[1]].name],
                      "between_parts": pieces[g.pieces[0]].part != pieces[g.pieces[1]].part,
                      "tab_on": pieces[g.tab_piece].name if g.tab_piece is not None else None,
                      "mesh_vertices": list(g.mesh_edge)} for g in glue],
        }
        (tmp / "assembly.json").write_text(json.dumps(assembly, indent=1) + "\n")
        files.append("assembly.json")
        page_of_piece = [pl.page for pl in packing.placements]
        (tmp / "instructions.html").write_text(_instructions_html(
            name, mesh, part_faces, pieces, glue, page_of_piece, packing.n_pages, opts, sheet_svgs))
        files.append("instructions.html")
        report["stages"]["export"] = {"seconds": time.perf_counter() - te, "pages": packing.n_pages}
        report["outputs"] = files + ["report.json"]
        report["seconds"] = time.perf_counter() - t0
        (tmp / "report.json").write_text(json.dumps(report, indent=1, default=_json_default) + "\n")
        files.append("report.json")
        # stale outputs of an earlier run in the same folder would be mistaken for this one's
        for old in list(out.glob("sheet-*.svg")) + list(out.glob("sheet-*.dxf")) + list(out.glob("piece-*.fold")) \
                + list(out.glob("part-*.obj")):
            if old.name not in files:
                old.unlink()
        for f in files:
            os.replace(tmp / f, out / f)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return MakeResult(out_dir=out, files=tuple(files), report=report)


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)
