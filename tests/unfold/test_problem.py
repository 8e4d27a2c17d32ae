"""unfold/problem.py: the faces' local frames keep their side lengths; the single nets ruled out
without a search (`single_net_blocked`) are ruled out by brute force too."""

import itertools
import math
import time

import networkx as nx
import numpy as np
import pytest
from shapely.geometry import Polygon

from conftest import height_grid, single_component, sorted_side_lengths, torus_inside
from polyfold.errors import NoNetFound
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh
from polyfold.segment.segment import DEFAULT_TAU, segment
from polyfold.unfold.problem import UnfoldProblem, local_frames
from polyfold.unfold.search import unfold


def test_local_frames_keep_side_lengths(models_dir):
    mesh = single_component(models_dir, "bunny-128")
    loc = local_frames(mesh.vertices, mesh.faces)
    np.testing.assert_allclose(sorted_side_lengths(loc), sorted_side_lengths(mesh.vertices[mesh.faces]), rtol=1e-12)
    assert (loc[:, 2, 1] > 0).all()


def _single_nets(mesh: Mesh) -> int:
    """Overlap-free single-piece edge unfoldings of a small mesh, by brute force and apart from
    polyfold's unfolder: every spanning tree of the dual graph (all sets of interior edges whose
    removal leaves one) laid out face by face, any two faces overlapping by more than a sliver
    (shapely) rejected. Flat regions are not kept whole here (more trees than polyfold allows)."""
    topo = mesh.topology
    inner = np.flatnonzero(topo.interior)
    n, p = mesh.n_faces, mesh.vertices
    found = 0
    for cut in itertools.combinations(range(len(inner)), len(inner) - (n - 1)):
        kept = np.delete(inner, list(cut))
        tree = nx.Graph([tuple(topo.edge_faces[e]) for e in kept])
        if tree.number_of_nodes() != n or not nx.is_tree(tree):
            continue
        flat = {0: {v: q for v, q in zip(mesh.faces[0], _place_triangle(p[mesh.faces[0]]))}}
        for parent, child in nx.bfs_edges(tree, 0):
            shared = set(mesh.faces[parent]) & set(mesh.faces[child])
            (tip,) = set(mesh.faces[child]) - shared
            (away,) = set(mesh.faces[parent]) - shared
            a, b = sorted(shared)
            flat[child] = {a: flat[parent][a], b: flat[parent][b],
                           tip: _apex(flat[parent][a], flat[parent][b], flat[parent][away], p[a], p[b], p[tip])}
        polygons = [Polygon([flat[f][v] for v in mesh.faces[f]]) for f in range(n)]
        sliver = 1e-9 * min(poly.area for poly in polygons)
        if all(polygons[f].intersection(polygons[g]).area <= sliver for f in range(n) for g in range(f + 1, n)):
            found += 1
    return found


def _place_triangle(corners: np.ndarray) -> list[np.ndarray]:
    a, b, c = corners
    ab = np.linalg.norm(b - a)
    x = np.dot(c - a, b - a) / ab
    return [np.zeros(2), np.array([ab, 0.0]), np.array([x, np.sqrt(max(np.dot(c - a, c - a) - x * x, 0.0))])]


def _apex(a2, b2, away2, a3, b3, tip3) -> np.ndarray:
    """The flat position of tip3 beside the flat edge a2-b2, on the side away from away2."""
    ab = b2 - a2
    u = ab / np.linalg.norm(ab)
    normal = np.array([-u[1], u[0]])
    if np.dot(away2 - a2, normal) > 0:
        normal = -normal
    along = np.dot(tip3 - a3, b3 - a3) / np.linalg.norm(b3 - a3)
    up = np.sqrt(max(np.dot(tip3 - a3, tip3 - a3) - along * along, 0.0))
    return a2 + along * u + up * normal


@pytest.mark.parametrize("name, mesh, blocked, nets", [
    ("torus inside, 2 x 4 quads", torus_inside(2), True, False),
    ("saddle z = (x^2 - y^2) / 3, 3 x 3", height_grid(3, lambda x, y: (x * x - y * y) / 3), True, False),
    ("bowl z = (x^2 + y^2) / 3, 3 x 3", height_grid(3, lambda x, y: (x * x + y * y) / 3), False, True),
    # the rule only rules nets out: here a cut may end at the peak, and it is overlaps farther from
    # the vertices that leave no single net, which only a search (or brute force) finds
    ("saddle with one vertex raised to a peak",
     height_grid(3, lambda x, y: (x * x - y * y) / 3 + 0.6 * (x == 0.5) * (y == 0.5)), False, False),
])
def test_a_disk_of_saddle_vertices_has_no_single_net(name, mesh, blocked, nets):
    # "no single net" is checked against every spanning tree the mesh has
    problem = UnfoldProblem.from_mesh(mesh)
    interior = np.setdiff1d(np.arange(mesh.n_vertices), mesh.topology.edges[~mesh.topology.interior])
    assert len(interior) >= 2
    assert bool(problem.single_net_blocked()) == blocked
    assert (_single_nets(mesh) > 0) == nets
    if blocked:
        assert problem.hyperbolic[interior].all()
        assert "interior vertices are all hyperbolic" in problem.single_net_blocked()
        t0 = time.perf_counter()
        with pytest.raises(NoNetFound, match="interior vertices are all hyperbolic"):
            unfold(mesh, seed=1, time_limit=60, max_pieces=1)
        assert time.perf_counter() - t0 < 5


@pytest.mark.parametrize("name, how", [("torus-8x4-64", {"tau": DEFAULT_TAU}), ("torus-12x6-144", {"parts": 6}),
                                       ("open/tube-132", {"parts": 6})])
def test_the_disk_rule_on_the_parts_of_shared_models(models_dir, name, how):
    # the parts segmentation makes of the shared models that the disk rule says have no single net
    # (patches of a torus's or a tube's inside), checked by brute force where their spanning trees
    # are few enough to enumerate
    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    parts = [mesh.submesh(f) for f in segment(mesh, seed=0, **how).face_ids]
    ruled_out = [p for p in parts
                 if "interior vertices are all hyperbolic" in (UnfoldProblem.from_mesh(p).single_net_blocked() or "")]
    small = [p for p in ruled_out
             if math.comb(int(p.topology.interior.sum()), int(p.topology.interior.sum()) - p.n_faces + 1) <= 1000]
    assert small
    for part in small:
        assert _single_nets(part) == 0


def test_a_vertex_inside_a_flat_region_may_end_a_cut():
    # a saddle grid whose middle is flat: every interior vertex is hyperbolic but the middle one,
    # whose edges are all merged (its region is kept whole); a tree cannot hold every merged edge
    # around it, so a net slits the region there and a cut may end at it: the disk rule claims nothing
    def height(x, y):
        return np.where((np.abs(x) <= 1) & (np.abs(y) <= 1) & (np.abs(x - y) <= 1), 0.0, (x * x - y * y) / 3)

    mesh = height_grid(4, height)
    problem = UnfoldProblem.from_mesh(mesh)
    middle = int(np.flatnonzero((np.abs(mesh.vertices[:, :2]).sum(axis=1) == 0))[0])
    interior = np.setdiff1d(np.arange(mesh.n_vertices), mesh.topology.edges[~mesh.topology.interior])
    assert problem.hyperbolic[np.setdiff1d(interior, [middle])].all() and not problem.hyperbolic[middle]
    assert middle not in mesh.topology.edges[problem.cut_candidates]
    assert problem.single_net_blocked() is None
