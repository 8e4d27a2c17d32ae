"""fabricate/fit.py: the smallest printed edge and face of a model at its printed scale, and
(fabricate/paper.py) the --size that makes the smallest edge buildable; `split_to_fit` and
`join_pieces`: pieces split along creases until they fit the page, never through a flat region
(coplanar faces, an input polygon), and joined back where they fit together; a single face or flat
polygon too large for the page is a `PieceTooLarge` error with the largest scale that fits. (How
make splits nets to fit the page: test_sheet.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh

from conftest import assert_flat_regions_whole, single_component, sorted_side_lengths, subdivided_box
from polyfold.collide.flat import find_overlaps
from polyfold.fabricate.fit import PieceTooLarge, _encloses, join_pieces, model_scale, smallest_printed, split_to_fit
from polyfold.fabricate.pack import fits_page
from polyfold.fabricate.paper import BUILDABLE_EDGE_MM, size_for_edge
from polyfold.fabricate.tabs import TAB_MAX_MM
from polyfold.mesh.geometry import merged_edges
from polyfold.mesh.mesh import Mesh, face_components
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.sheets import pack_box
from polyfold.unfold.net import cut_creases
from polyfold.unfold.search import unfold


def test_smallest_printed_edge_and_face_height():
    # a right tetrahedron with legs 1, 2, 3: shortest edge 1; the narrowest face is the one with
    # legs 1 and 2 (height 2 / sqrt(5) over its hypotenuse sqrt(5))
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    edge, face = smallest_printed(Mesh(v, f), 10.0)
    assert edge == pytest.approx(10.0)
    heights = []
    for tri in v[f]:
        sides = np.linalg.norm(tri - np.roll(tri, -1, axis=0), axis=1)
        area = 0.5 * np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0]))
        heights.append(2 * area / sides.max())
    assert face == pytest.approx(10.0 * min(heights))
    assert face == pytest.approx(10.0 * 2 / math.sqrt(5))


def test_size_for_edge_rounds_up():
    assert size_for_edge(150.0, 4.9) == 154  # 150 * 5 / 4.9 = 153.06
    assert size_for_edge(100.0, 2.5) == 200 == 100.0 * BUILDABLE_EDGE_MM / 2.5
    assert size_for_edge(150.0, 1.0, edge_mm=3.0) == 450


# the A4 page and margin make fits pieces to (`pack_box` at the defaults: margins all round, footer)
MARGIN = MakeOptions().margin
A4 = tuple(float(x) + MARGIN for x in pack_box(210.0, 297.0, MakeOptions())[2:])


def _single_net(mesh: Mesh):
    net, stats = unfold(mesh, seed=1, time_limit=20)
    assert stats.pieces == 1
    return net


def test_cube_at_a4_150mm_is_six_whole_squares(models_dir):
    mesh = single_component(models_dir, "cube-12")
    net = _single_net(mesh)
    fitted, cuts = split_to_fit(net, model_scale([mesh], 150.0), A4, MARGIN)
    assert fitted.n_pieces == 6 and cuts == 5
    for p in range(6):
        f0, f1 = np.flatnonzero(fitted.piece == p)  # two faces a piece ...
        np.testing.assert_allclose(mesh.face_normals[f0], mesh.face_normals[f1], atol=1e-12)  # ... one square
    assert_flat_regions_whole(fitted)


def _cylinder() -> Mesh:
    cyl = trimesh.creation.cylinder(radius=0.5, height=1.2, sections=24)  # caps: flat fans around their centre
    return Mesh(cyl.vertices, cyl.faces)


def assert_pieces_fit(net, scale: float, page, margin: float) -> None:
    """A valid net whose every piece, with room for tabs all round, fits the page in a rotation the
    packer tries: each crease's two faces share its corners bit for bit (the sheet outlines are unions of
    faces), no two faces of a piece overlap, every face is congruent to its mesh triangle."""
    mesh = net.mesh
    c = net.coords
    np.testing.assert_allclose(sorted_side_lengths(c), sorted_side_lengths(mesh.vertices[mesh.faces]),
                               atol=1e-9 * mesh.bbox_diagonal)
    for f in np.flatnonzero(net.parent >= 0):
        p, e = net.parent[f], net.parent_edge[f]
        for v in mesh.topology.edges[e]:
            assert np.array_equal(c[f][mesh.faces[f] == v], c[p][mesh.faces[p] == v])
    for k in range(net.n_pieces):
        idx = np.flatnonzero(net.piece == k)
        assert len(find_overlaps(c[idx], None, 1e-9 * mesh.bbox_diagonal)) == 0
        room = shapely.convex_hull(shapely.multipoints(c[idx].reshape(-1, 2) * scale)).buffer(TAB_MAX_MM)  # any tab
        assert fits_page(room, page, margin, angles=8) >= 1.0


@pytest.mark.parametrize("name", ["subdivided-box", "cylinder", "dodecahedron-36", "l-prism-div-44", "bad/quad-cube"])
def test_splits_never_cut_a_merged_edge(models_dir, name):
    mesh = {"subdivided-box": subdivided_box, "cylinder": _cylinder}.get(name, lambda: single_component(models_dir, name))()
    net = _single_net(mesh)
    scale = model_scale([mesh], 150.0)
    fitted, added = split_to_fit(net, scale, A4, MARGIN)
    assert added > 0 and fitted.n_pieces == added + 1
    assert_flat_regions_whole(fitted)
    assert_pieces_fit(fitted, scale, A4, MARGIN)


@pytest.mark.parametrize("name", ["cylinder", "subdivided-box"])
def test_join_pieces_puts_pieces_back_together(name):
    # every flat region a piece of its own (the cylinder's 24 sides and 2 caps, the box's 6 sides),
    # then joined back along shared edges wherever the two pieces still fit the page, overlap-free
    mesh = _cylinder() if name == "cylinder" else subdivided_box(2)
    net = _single_net(mesh)
    apart = cut_creases(net, np.flatnonzero(net.cuttable))
    assert apart.n_pieces == face_components(mesh.n_faces, mesh.topology, merged_edges(mesh)).max() + 1
    scale = model_scale([mesh], 150.0)
    for page in (A4, (800.0, 800.0)):
        joined, joins = join_pieces(apart, scale, page, MARGIN)
        assert joins > 0 and joined.n_pieces == apart.n_pieces - joins
        assert joined.n_pieces == 1 or page == A4  # on a large page all of it is one piece again
        assert_flat_regions_whole(joined)
        assert_pieces_fit(joined, scale, page, MARGIN)
    joined, joins = join_pieces(apart, scale, A4, MARGIN, limit=2)
    assert joins == 2


@pytest.mark.parametrize("name, faces", [("cube-12", 2), ("bad/quad-cube", 1)])
def test_a_flat_polygon_too_large_is_an_error_not_a_cut(models_dir, name, faces):
    # 260 x 130 mm printable: a 150 mm square (with its tab room) does not fit, its two triangles
    # would (the hypotenuse along the page) -- the square is not cut in two
    mesh = single_component(models_dir, name)
    net = _single_net(mesh)
    page = (280.0, 150.0)
    scale = model_scale([mesh], 150.0)
    with pytest.raises(PieceTooLarge) as info:
        split_to_fit(net, scale, page, MARGIN)
    err = info.value
    assert len(err.faces) == faces and err.face == err.faces[0]
    polygon = np.flatnonzero(np.isin(mesh.face_source, err.faces))
    assert len(polygon) == 2 and np.allclose(mesh.face_normals[polygon[0]], mesh.face_normals[polygon[1]])
    assert ("flat polygon of faces" in str(err)) == (faces > 1)
    assert 0.5 < err.factor < 1.0
    fitted, _ = split_to_fit(net, scale * err.factor, page, MARGIN)  # the scale it names fits
    assert_flat_regions_whole(fitted)
    with pytest.raises(PieceTooLarge):  # and is the largest that does
        split_to_fit(net, scale * err.factor * 1.001, page, MARGIN)


def test_a_join_that_would_close_a_hole_is_refused():
    # a U of three unit squares (two triangles each) and a bar closing its mouth: joined, they would
    # enclose the square hole between the U's arms; the same bar beside the U encloses nothing
    def square(x, y):
        return [[(x, y), (x + 1, y), (x + 1, y + 1)], [(x, y), (x + 1, y + 1), (x, y + 1)]]

    u = np.array(square(0, 0) + square(1, 0) + square(2, 0) + square(0, 1) + square(2, 1), dtype=float) * 10
    closing = np.array(square(0, 2) + square(1, 2) + square(2, 2), dtype=float) * 10
    beside = np.array(square(3, 0) + square(4, 0), dtype=float) * 10
    assert _encloses(u, closing) and not _encloses(u, beside)
    nearly = closing + [0.0, 0.01]  # 0.01 mm off: still closes the loop for a cutter
    assert _encloses(u, nearly)


def test_hull_fits_decides_as_the_grown_hull_does():
    """`_hull_fits` answers from the points' extents where those decide it; it must say what the
    grown hull itself says (`_hull_scale` >= 1) on point sets of every shape at every distance from
    fitting, those within the pad's arcs of the page's edge included."""
    from polyfold.fabricate.fit import PACK_ANGLES, _hull_fits, _hull_scale
    from polyfold.fabricate.pack import _best_fit

    rng = np.random.default_rng(5)
    page, margin, pad = (210.0, 297.0), 10.0, 7.0
    decided = 0
    for k in range(3000):
        n = int(rng.integers(3, 40))
        pts = rng.normal(size=(n, 2)) * rng.uniform(0.05, 1.0, size=2)
        if k % 3 == 0:  # polygons: the extreme points are corners
            t = np.linspace(0, 2 * np.pi, n + 3)
            pts = np.stack([np.cos(t), rng.uniform(0.1, 1) * np.sin(t)], 1)
        pts = pts @ np.array([[math.cos(k), -math.sin(k)], [math.sin(k), math.cos(k)]])
        bare = _best_fit(pts, PACK_ANGLES, page[0] - 2 * margin, page[1] - 2 * margin)[0]  # the bare points just fit
        pts = pts * bare * rng.uniform(0.85, 1.0)  # from 2 pads short of fitting to just fitting
        want = _hull_scale(pts, page, margin, pad) >= 1.0
        assert _hull_fits(pts, page, margin, pad) == want
        decided += want
    assert 0 < decided < 3000  # both answers met
