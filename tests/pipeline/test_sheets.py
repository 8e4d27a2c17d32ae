"""pipeline/sheets.py: make's pages. Pieces are split along creases where that saves pages (issue 18,
point 9: no more pages than Blender's paper-model export at the same paper and size), the layout
after folding keeps the planned pages, and the utilisation in report.json is what the written
sheets show (read back with the tests' own SVG parser)."""

from __future__ import annotations

import json

import numpy as np

import pytest

from conftest import check_sheet, fitted_parts, read_sheet
from sheet_reader import read_svg
from polyfold.deadline import Deadline
from polyfold.fabricate.pack import pack_outlines
from polyfold.fabricate.paper import FOOTER_MM, GAP_MM
from polyfold.fabricate.pieces import build_sheet_pieces
from polyfold.pipeline.folding import fold_pieces
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions, paper_size
from polyfold.pipeline.sheets import _packer_page, lay_out, pack_box, piece_inputs, split_for_pages

# A4 pages of Blender's paper-model export at 150 mm (issue 18)
BLENDER_PAGES = {"bunny-128": 3, "horse-302": 3, "fish-472": 2, "bunny-348": 5, "bumpy-528": 5}


@pytest.mark.parametrize("name", list(BLENDER_PAGES))
def test_no_more_pages_than_blender_and_the_reported_utilisation_is_on_the_sheets(name, models_dir, tmp_path):
    out = tmp_path / name
    report = make(models_dir / f"{name}.obj", out, MakeOptions(guide=False)).report  # the defaults (A4, 150 mm, folded); the guide: tests/guide
    lay = report.stages.layout
    assert lay.pages <= BLENDER_PAGES[name]
    svgs = sorted(out.glob("sheet-*.svg"))
    assert len(svgs) == lay.pages
    printed = 0.0  # paper cut out: the SVG's cut outlines, holes removed (the tests' own reader)
    for svg in svgs:
        assert check_sheet(read_sheet(svg), 10.0) == []
        printed += sum(p.area for p in read_svg(svg).pieces())
    w, h = paper_size("a4")
    printable_area = (w - 20.0) * (h - FOOTER_MM - 20.0)
    assert lay.utilisation == pytest.approx(printed / (lay.pages * printable_area), rel=1e-3)
    assembly = json.loads((out / "assembly.json").read_text())
    assert {p["page"] for p in assembly["pieces"]} == set(range(1, lay.pages + 1))  # no empty page


def test_bumpy_is_split_to_fill_its_pages(models_dir, tmp_path):
    report = make(models_dir / "bumpy-528.obj", tmp_path / "bumpy", MakeOptions(fold=False, guide=False)).report
    lay = report.stages.layout
    assert lay.pages <= 4 and lay.splits_for_packing > 0 and lay.utilisation > 0.4
    net_pieces = [r for r in report.pieces if r.faces > 0]  # not the glue strips
    assert len(net_pieces) == 1 + lay.splits_for_page + lay.splits_for_labels + lay.splits_for_packing  # one part, one net
    assert sum(r.faces for r in report.pieces) == report.input.faces


@pytest.mark.parametrize("name", ["periscope2-44", "star-24"])
def test_sprawling_nets_are_cut_into_compact_parts_to_fit_one_page(name, models_dir, tmp_path):
    # their nets cover about half a page but, cut only where a piece fits nowhere, needed two pages
    out = tmp_path / name
    report = make(models_dir / f"{name}.obj", out, MakeOptions(fold=False, guide=False)).report
    lay = report.stages.layout
    assert lay.pages == 1 and lay.splits_for_packing > 0
    assert sum(r.faces for r in report.pieces) == report.input.faces
    svgs = sorted(out.glob("sheet-*.svg"))
    assert len(svgs) == 1 and check_sheet(read_sheet(svgs[0]), 10.0) == []  # nothing overlaps


def test_pieces_that_fit_one_page_are_not_cut(models_dir, tmp_path):
    report = make(models_dir / "bunny-128.obj", tmp_path / "b", MakeOptions(fold=False, size=80.0, guide=False)).report
    lay = report.stages.layout
    assert lay.pages == 1 and lay.splits_for_packing == 0
    assert len([r for r in report.pieces if r.faces > 0]) == 1 + lay.splits_for_page


def test_layout_after_folding_keeps_the_planned_pages_and_pieces(models_dir):
    mesh, opts, scale, w, h, fitted = fitted_parts(models_dir, "bunny-348")
    deadline = Deadline.after(60)
    split = split_for_pages(mesh, fitted, scale, opts, pack_box(w, h, opts), deadline, lambda *a: None)
    n_fitted = sum(p.net.n_pieces for p in fitted)
    assert split.cuts > 0 and split.net_pieces == n_fitted + split.cuts
    folded, _ = fold_pieces(split.parts, opts, deadline, lambda *a: None, scale)
    sheets = lay_out(mesh, folded, scale, opts, w, h, deadline, lambda *a: None, planned=split)
    assert len(sheets.pieces) == split.pieces and sheets.packing.n_pages == split.pages
    # the packing found before folding is kept: packing the same pieces again in its order, from the
    # same seed, gives the very same placements
    assert sheets.packing is split.packing and not split.packing.ran_out
    page, margin = _packer_page(pack_box(w, h, opts))
    again = pack_outlines([p.footprint for p in split.drawn[0]], page, margin=margin, gap=GAP_MM, seed=opts.seed,
                          time_limit=60, hint=list(split.order), tries=1)
    assert again.placements == split.packing.placements
    # the pieces drawn before folding, laid out again, are what drawing the folded pieces gives
    fresh, _, _ = build_sheet_pieces(piece_inputs(mesh, folded), scale, min_label_mm=opts.min_label_mm)
    assert [p.footprint.equals_exact(q.footprint, 0.0) for p, q in zip(split.drawn[0], fresh)] == [True] * len(fresh)
    # and without the split the same pieces need more pages
    unsplit, _ = fold_pieces(fitted, opts, deadline, lambda *a: None, scale)
    assert lay_out(mesh, unsplit, scale, opts, w, h, deadline, lambda *a: None).packing.n_pages > split.pages


def test_the_first_page_plan_made_beside_the_packing_is_the_one_made_after_it(models_dir, monkeypatch):
    """With two cores split_for_pages makes its first page plan in a forked process while it packs
    the pieces (`sheets._plan_ahead`), and takes it when that packing needs more pages: the same
    cuts, pieces, packing and piece order as one core planning after the packing."""
    from polyfold import processes
    from polyfold.pipeline import sheets

    mesh, opts, scale, w, h, fitted = fitted_parts(models_dir, "bunny-348")
    monkeypatch.setattr(sheets, "PARALLEL_PLAN_PIECES", 1)  # (bunny-348 has fewer pieces than a dense mesh)
    read = []
    real = sheets.ForkedStream

    def recorded(gen):
        stream = real(gen)
        plain = stream.next

        def next_value():
            got = plain()
            read.append((got[0], type(got[1]).__name__))
            return got

        stream.next = next_value
        return stream

    monkeypatch.setattr(sheets, "ForkedStream", recorded)
    runs = {}
    for cores in (1, 2):
        monkeypatch.setattr(processes, "usable_cores", lambda cores=cores: cores)
        runs[cores] = split_for_pages(mesh, fitted, scale, opts, pack_box(w, h, opts), Deadline.after(60),
                                      lambda *a: None)
    assert read == [(True, "PagePlan")]  # made ahead with two cores only, and taken
    one, two = runs[1], runs[2]
    assert one.cuts == two.cuts > 0 and (one.pieces, one.net_pieces, one.pages) == (two.pieces, two.net_pieces, two.pages)
    assert one.packing.placements == two.packing.placements and one.order == two.order
    assert np.array_equal(one.rank, two.rank)
    assert [p.footprint.equals_exact(q.footprint, 0.0) for p, q in zip(one.drawn[0], two.drawn[0])] == [True] * one.pieces


def test_a_drawing_after_folding_split_a_piece_takes_what_it_can_from_the_planned_drawings(models_dir):
    """When folding splits a piece, lay_out draws the pieces again with split_for_pages' memo: the
    pieces not split keep their tabs and labels found before, and the drawing is the one made
    afresh."""
    mesh, opts, scale, w, h, fitted = fitted_parts(models_dir, "bunny-348")
    deadline = Deadline.after(60)
    split = split_for_pages(mesh, fitted, scale, opts, pack_box(w, h, opts), deadline, lambda *a: None)
    # as folding splits a piece it cannot fold: one crease of the last one cut
    folded, _ = fold_pieces(_piece_cut(mesh, split.parts), opts, deadline, lambda *a: None, scale)
    assert not split.same_pieces(folded)
    tabs_before = len(split.memo["tabs"])
    sheets = lay_out(mesh, folded, scale, opts, w, h, deadline, lambda *a: None, planned=split)
    fresh, glue, stats = build_sheet_pieces(piece_inputs(mesh, folded), scale, min_label_mm=opts.min_label_mm,
                                            by_run=split.drawn[2].labels_by_run)
    assert len(split.memo["tabs"]) - tabs_before < stats.glue_edges  # (tabs found before were taken)
    assert list(sheets.glue) == glue and sheets.stats == stats
    from polyfold.fabricate.page import place

    for i, (p, q) in enumerate(zip(sheets.pieces, fresh, strict=True)):
        q = place(q, sheets.packing.placements[i])  # (laid out: moved onto its page as p was)
        assert p.texts == q.texts and len(p.tabs) == len(q.tabs)
        assert all(np.array_equal(a, b) for a, b in zip(p.tabs, q.tabs))
        assert p.footprint.equals_exact(q.footprint, 0.0)


def test_same_seed_same_pages(models_dir, tmp_path):
    a = make(models_dir / "bunny-128.obj", tmp_path / "a", MakeOptions(fold=False, guide=False))
    b = make(models_dir / "bunny-128.obj", tmp_path / "b", MakeOptions(fold=False, guide=False))
    assert (tmp_path / "a" / "assembly.json").read_text() == (tmp_path / "b" / "assembly.json").read_text()
    for sa, sb in zip(sorted((tmp_path / "a").glob("sheet-*.svg")), sorted((tmp_path / "b").glob("sheet-*.svg"))):
        assert sa.read_text() == sb.read_text()
    assert a.report.stages.layout.pages == b.report.stages.layout.pages


def _piece_cut(mesh, parts, which: int = -1):
    """The parts with one piece (index `which` among their pieces) cut along one crease near the
    middle of its tree."""
    from polyfold.fabricate.split import PagePlan
    from polyfold.pipeline.sheets import _cut_plan, part_piece_inputs

    inputs = part_piece_inputs(mesh, parts)
    which %= len(inputs)
    net = inputs[which].net
    creases = [f for f in range(len(net.parent)) if net.parent[f] >= 0 and net.cuttable[f]]
    cuts = tuple(np.array([creases[len(creases) // 2]] if i == which else [], dtype=np.int64)
                 for i in range(len(inputs)))
    return _cut_plan(parts, inputs, PagePlan(cuts, (), 0))[0]


def _same_drawings(taken, fresh) -> None:
    """Two `build_sheet_pieces` results are the same drawing."""
    (pieces_a, glue_a, stats_a), (pieces_b, glue_b, stats_b) = taken, fresh
    assert glue_a == glue_b and stats_a == stats_b
    for p, q in zip(pieces_a, pieces_b, strict=True):
        assert p.outline.equals_exact(q.outline, 0.0) and p.footprint.equals_exact(q.footprint, 0.0)
        assert p.texts == q.texts
        assert len(p.tabs) == len(q.tabs) and all(np.array_equal(a, b) for a, b in zip(p.tabs, q.tabs))
        assert np.array_equal(p.leaders, q.leaders) and np.array_equal(p.tab_folds, q.tab_folds)


def test_drawings_that_take_tabs_and_labels_found_before_are_the_drawings_made_afresh(models_dir):
    """split_for_pages draws a model's pieces again after cutting some, with one memo: what it
    takes from the memo (a pair's tab, a piece's labels, outline and footprint) is what drawing
    afresh gives."""
    from polyfold.pipeline.sheets import part_piece_inputs

    mesh, opts, scale, w, h, fitted = fitted_parts(models_dir, "bunny-348")
    before = part_piece_inputs(mesh, fitted)
    memo: dict = {}
    first, _, _ = build_sheet_pieces(before, scale, memo=memo)
    # cut the last piece (the pieces before it keep their names and glue numbers: their labels can
    # be taken again)
    after = part_piece_inputs(mesh, _piece_cut(mesh, fitted))
    assert len(after) == len(before) + 1
    tabs_before, labels_before, outlines_before = len(memo["tabs"]), len(memo["labels"]), len(memo["outlines"])
    taken = build_sheet_pieces(after, scale, memo=memo)
    fresh = build_sheet_pieces(after, scale)
    # the memo was used: fewer new entries than pairs and pieces drawn
    assert len(memo["tabs"]) - tabs_before < fresh[2].glue_edges
    assert len(memo["labels"]) - labels_before < len(after)
    assert len(memo["outlines"]) - outlines_before < len(after)
    _same_drawings(taken, fresh)


def test_labels_found_before_are_taken_again_renamed_where_a_cut_renumbered_them(models_dir, monkeypatch):
    """A cut in an early piece renames the pieces after it and renumbers the glue edges after its
    new one: a piece whose labels were placed before with texts as wide (`labels.width_key`) takes
    them again, renamed, and the drawing is the one made afresh."""
    import polyfold.fabricate.pieces as pieces_module
    from polyfold.pipeline.sheets import part_piece_inputs

    mesh, opts, scale, w, h, fitted = fitted_parts(models_dir, "bunny-348")
    memo: dict = {}
    build_sheet_pieces(part_piece_inputs(mesh, fitted), scale, memo=memo)
    after = part_piece_inputs(mesh, _piece_cut(mesh, fitted, 2))
    renamed = []
    original = pieces_module._renamed

    def counted(texts_then, placed, texts):
        got = original(texts_then, placed, texts)
        if got is not None and texts != texts_then:
            renamed.append((texts_then, texts))
        return got

    monkeypatch.setattr(pieces_module, "_renamed", counted)
    taken = build_sheet_pieces(after, scale, memo=memo)
    assert renamed  # (bunny-348's third piece cut: two pieces' labels are taken again under new texts)
    _same_drawings(taken, build_sheet_pieces(after, scale))
