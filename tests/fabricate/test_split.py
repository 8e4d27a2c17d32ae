"""fabricate/split.py: cutting creases so that the pieces of a real net fill fewer pages."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely import Polygon

from polyfold.deadline import Deadline, clock
from polyfold.fabricate.fit import model_scale
from polyfold.fabricate.pack import pack_outlines
from polyfold.fabricate.paper import GAP_MM
from polyfold.fabricate.pieces import build_sheet_pieces
from polyfold.fabricate.split import LABEL_SPLIT_LEAST, MIN_PART, MIN_PART_FACES, _Tree, plan_label_cuts, plan_pages
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import merged_edges
from polyfold.pipeline.options import MakeOptions, paper_size
from polyfold.pipeline.parts import make_parts
from polyfold.pipeline.sheets import _packer_page, fit_parts, pack_box, part_piece_inputs
from polyfold.unfold.net import cut_creases, piece_net

MARGIN = 10.0


def drawn(models_dir, name: str, seed: int = 1) -> dict:
    """A model at the defaults (A4, 150 mm; the unfolder's `seed`): its pieces as make draws them
    before folding."""
    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    opts = MakeOptions(seed=seed)
    parts, _, _ = make_parts(mesh, opts, Deadline.after(60), lambda *a: None)
    scale = model_scale([mesh], opts.size)
    box = pack_box(*paper_size(opts.paper), opts)
    fitted, _ = fit_parts(parts, scale, opts, box, name)
    inputs = part_piece_inputs(mesh, fitted)
    pieces, _, _ = build_sheet_pieces(inputs, scale)
    page, margin = _packer_page(box)  # the page the packer is given: `box` inside its margins
    assert margin == MARGIN
    return {"mesh": mesh, "inputs": inputs, "pieces": pieces, "page": page, "scale": scale}


@pytest.fixture(scope="module")
def bunny(models_dir):
    return drawn(models_dir, "bunny-128")


def plan(bunny, n_pages, **kw):
    return plan_pages(bunny["pieces"], [inp.net for inp in bunny["inputs"]], bunny["page"], MARGIN, GAP_MM, n_pages,
                      clock() + 60, seed=1, **kw)


def printable_area(page) -> float:
    return (page[0] - 2 * MARGIN) * (page[1] - 2 * MARGIN)


def test_bunny_needs_more_than_two_pages_uncut_and_the_plan_fits_two(bunny):
    pieces, page = bunny["pieces"], bunny["page"]
    whole = pack_outlines([p.footprint for p in pieces], page, MARGIN, GAP_MM, seed=1)
    area = sum(p.footprint.area for p in pieces)
    assert whole.n_pages >= 3 and 1 < area / printable_area(page) < 2
    p = plan(bunny, 2)
    assert p is not None and p.pages == 2
    assert sum(len(c) for c in p.cuts) > 0


def test_plan_cuts_only_creases_and_names_every_part_once(bunny):
    p = plan(bunny, 2)
    lo = MIN_PART * printable_area(bunny["page"])
    n_parts = 0
    for inp, cuts, piece in zip(bunny["inputs"], p.cuts, bunny["pieces"]):
        net = inp.net
        assert (net.parent_edge[cuts] >= 0).all()  # a crease of the piece: never through a face
        cut = cut_creases(net, cuts)
        np.testing.assert_array_equal(cut.coords, net.coords)  # no face moves
        roots = {root for t, root in p.order if bunny["inputs"][t] is inp}
        assert roots == set(np.flatnonzero(cut.parent < 0).tolist())  # each part placed once, by its root
        n_parts += cut.n_pieces
        for k in range(cut.n_pieces):  # no sliver: every part at least MIN_PART of a page (faces and
            faces = piece_net(cut, k)[1]  # tabs), and at least two faces
            assert faces_area(piece, faces) >= lo * (1 - 1e-9) and len(faces) >= MIN_PART_FACES
    assert n_parts == len(p.order) == len(bunny["pieces"]) + sum(len(c) for c in p.cuts)


def test_a_crowded_spot_is_cut_through_by_a_crease_that_leaves_two_real_parts(bunny):
    pieces, nets = bunny["pieces"], [inp.net for inp in bunny["inputs"]]
    big = int(np.argmax([len(p.faces_xy) for p in pieces]))
    piece = pieces[big]
    # the spot: the face nearest the middle of the piece (a label with no place, at its centroid)
    centroids = piece.faces_xy.mean(axis=1)
    mid = int(np.argmin(np.linalg.norm(centroids - centroids.mean(axis=0), axis=1)))
    spot = centroids[mid]
    size = np.linalg.norm(piece.faces_xy[mid] - np.roll(piece.faces_xy[mid], 1, axis=0), axis=1).max()
    cuts = plan_label_cuts(pieces, nets, [(big, float(spot[0]), float(spot[1]))])
    assert [len(c) for c in cuts] == [1 if i == big else 0 for i in range(len(pieces))]
    (f,) = cuts[big]
    net = nets[big]
    assert net.parent_edge[f] >= 0  # a crease
    # it runs past the spot: one of the spot's face's sides or a crease within a face's size of it
    k = int(np.argmax(net.mesh.topology.face_edges[f] == net.parent_edge[f]))
    a, b = piece.faces_xy[f, k], piece.faces_xy[f, (k + 1) % 3]
    t = np.clip(np.dot(spot - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    assert np.linalg.norm(a + t * (b - a) - spot) < size
    cut = cut_creases(net, cuts[big])
    assert cut.n_pieces == 2
    whole = faces_area(piece, np.arange(len(piece.faces_xy)))
    for part in range(2):
        faces = piece_net(cut, part)[1]
        assert len(faces) >= MIN_PART_FACES
        assert faces_area(piece, faces) >= 0.5 * LABEL_SPLIT_LEAST * whole  # (tab room and labels aside)


def faces_area(piece, faces) -> float:
    """Area (mm^2) of the piece's faces `faces` with the tabs the whole piece has on their sides."""
    tri = piece.faces_xy[faces]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    area = float(np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum() / 2)
    mids = ((tri + np.roll(tri, -1, axis=1)) / 2).reshape(-1, 2)
    for tab, fold in zip(piece.tabs, piece.tab_folds):
        if np.linalg.norm(mids - fold.mean(axis=0), axis=1).min() < 1e-6:
            area += Polygon(tab).area
    return area


def test_plan_is_deterministic_and_fails_below_the_area_bound(bunny):
    a, b = plan(bunny, 2), plan(bunny, 2)
    assert a.order == b.order and all(np.array_equal(x, y) for x, y in zip(a.cuts, b.cuts))
    area = sum(p.footprint.area for p in bunny["pieces"]) / printable_area(bunny["page"])
    assert math.ceil(area) == 2
    assert plan(bunny, 1) is None  # more outline than one page holds


def test_plan_with_room_cuts_nothing_and_is_the_packers_first_fit(bunny):
    pieces, page = bunny["pieces"], bunny["page"]
    whole = pack_outlines([q.footprint for q in pieces], page, MARGIN, GAP_MM, seed=1)
    p = plan(bunny, whole.n_pages)
    assert p is not None and not any(len(c) for c in p.cuts)
    order = [t for t, _ in p.order]
    assert sorted(order) == list(range(len(pieces)))
    packing = pack_outlines([q.footprint for q in pieces], page, MARGIN, GAP_MM, seed=1, hint=order, tries=1)
    assert packing.n_pages <= whole.n_pages and list(packing.order) == order


def test_plan_gives_up_at_its_deadline(bunny):
    assert plan_pages(bunny["pieces"], [inp.net for inp in bunny["inputs"]], bunny["page"], MARGIN, GAP_MM, 2,
                      clock() - 1.0) is None


def test_flat_polygons_are_never_cut(models_dir):
    # torus-12x6-144's quads are flat polygons of two triangles each: their diagonals are merged
    # creases, which the plan must leave alone however it cuts
    torus = drawn(models_dir, "torus-12x6-144")
    whole = pack_outlines([q.footprint for q in torus["pieces"]], torus["page"], MARGIN, GAP_MM, seed=1)
    p = plan(torus, whole.n_pages - 1)
    assert p is not None and sum(len(c) for c in p.cuts) > 0
    for inp, cuts in zip(torus["inputs"], p.cuts):
        merged = merged_edges(inp.net.mesh)
        assert merged.any() and not merged[inp.net.parent_edge[cuts]].any()
    # nor offered: no cut a plan weighs is a merged crease (there are some to offer without the rule)
    offered, merged_creases = set(), set()
    for piece, inp in zip(torus["pieces"], torus["inputs"]):
        net = inp.net
        tree = _Tree(piece, net)
        sides = tree.sides(np.ones(len(net.parent), dtype=bool), 0.0, np.inf)
        offered |= {(inp.face_ids[f], below) for _, f, below in sides}
        is_merged = (net.parent_edge >= 0) & merged_edges(net.mesh)[net.parent_edge]
        merged_creases |= {(inp.face_ids[f], below) for f in np.flatnonzero(is_merged) for below in (True, False)}
    assert offered and merged_creases and not offered & merged_creases


def test_a_cap_cuts_sprawling_pieces_into_compact_parts_that_fill_one_page(models_dir):
    # star-24's two nets (seed 3) cover 0.59 of a page, but their spikes enclose gaps that the
    # bottom-left fill cannot use: however the plan cuts them they need two pages, cut into parts
    # whose convex hulls are at most 0.2 of a page they fit one. (Which nets a seed gives follows
    # the unfolder's search: on seeds 1-12, 3 and 5 give such nets now; 8 others fit one page
    # uncapped or do not fit with the cap either.)
    star = drawn(models_dir, "star-24", seed=3)
    area = sum(p.footprint.area for p in star["pieces"]) / printable_area(star["page"])
    assert 0.5 < area < 0.65
    assert plan(star, 1) is None
    p = plan(star, 1, cap=0.2)
    assert p is not None and p.pages == 1 and sum(len(c) for c in p.cuts) > 0
    cap = 0.2 * printable_area(star["page"])
    for piece, inp, cuts in zip(star["pieces"], star["inputs"], p.cuts):
        tree, cut = _Tree(piece, inp.net), cut_creases(inp.net, cuts)
        for k in range(cut.n_pieces):  # every part is compact: its hull (tabs and labels) within the cap
            mask = np.zeros(len(inp.net.parent), dtype=bool)
            mask[piece_net(cut, k)[1]] = True
            assert tree.hull(mask) <= cap
    assert plan(star, 1, cap=0.2).order == p.order  # deterministic
