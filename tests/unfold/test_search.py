"""unfold/search.py (`unfold`): verified single nets of closed, genus-one and open meshes, two cuts
at hyperbolic vertices, every method, the same net for the same seed, the multi-piece fallback and
the time budget (time_limit or a Deadline), flat regions (coplanar faces, input polygons) whole in
every net."""

import itertools
import time

import numpy as np
import pytest
from shapely.geometry import Polygon

from conftest import (NO_SINGLE_NET, assert_flat_regions_whole, closed_meshes, single_component, sorted_side_lengths,
                      subdivided_box, torus_inside)
from polyfold.collide.flat import find_overlaps
from polyfold.deadline import Deadline
from polyfold.errors import NoNetFound
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import merged_edges
from polyfold.unfold.problem import HEURISTICS, UnfoldProblem
from polyfold.unfold import kernels as K
from polyfold.unfold.search import split_into_pieces, unfold

PLATONIC = ["tetrahedron-4", "cube-12", "octahedron-8", "dodecahedron-36", "icosahedron-20"]
# torus-12x6-144 is not here: its top and bottom rings are flat annuli, each kept whole (flat regions,
# below), and no single net around them is known (see test_no_single_net_with_flat_regions_whole)
GENUS_ONE = ["torus-50", "torus-8x4-64", "torus-twisted-10x3-60"]


def assert_valid_net(net, n_pieces=1):
    mesh = net.mesh
    # every face congruent to its 3D triangle, CCW seen from +z (outer side up)
    np.testing.assert_allclose(sorted_side_lengths(net.coords), sorted_side_lengths(mesh.vertices[mesh.faces]),
                               atol=1e-9 * mesh.bbox_diagonal)
    c = net.coords
    area2 = (c[:, 1, 0] - c[:, 0, 0]) * (c[:, 2, 1] - c[:, 0, 1]) - (c[:, 1, 1] - c[:, 0, 1]) * (c[:, 2, 0] - c[:, 0, 0])
    assert (area2 > 0).all()
    # a crease joins the two faces that share that mesh edge, and they share its two corners in 2D
    for f in np.flatnonzero(net.parent >= 0):
        p, e = net.parent[f], net.parent_edge[f]
        assert e in mesh.topology.face_edges[f] and e in mesh.topology.face_edges[p]
        for v in mesh.topology.edges[e]:
            np.testing.assert_allclose(c[f][mesh.faces[f] == v], c[p][mesh.faces[p] == v], atol=1e-12 * mesh.bbox_diagonal)
    # no two faces of one piece overlap (all pairs, crease pairs included)
    for piece in range(net.n_pieces):
        idx = np.flatnonzero(net.piece == piece)
        assert len(find_overlaps(c[idx], None, 1e-9 * mesh.bbox_diagonal)) == 0
    assert net.n_pieces == n_pieces


def _tree_path(parent: np.ndarray, order: np.ndarray, f: int, g: int) -> list[int]:
    """The faces whose crease to their parent lies on the tree path between faces f and g."""
    depth = np.zeros(len(parent), int)
    for x in order[1:]:
        depth[x] = depth[parent[x]] + 1
    on_path = []
    while f != g:
        if depth[f] >= depth[g]:
            on_path.append(f)
            f = parent[f]
        else:
            on_path.append(g)
            g = parent[g]
    return on_path


@pytest.mark.parametrize("name", PLATONIC)
def test_platonic_solids_single_net(models_dir, name):
    net, stats = unfold(single_component(models_dir, name), seed=1)
    assert_valid_net(net)
    assert stats.pieces == 1 and not stats.timed_out
    # closed genus 0: cut edges form a spanning tree of the vertex graph (|V| - 1 edges)
    cuts = ~net.crease_mask
    assert cuts.sum() == net.mesh.n_vertices - 1


@pytest.mark.parametrize("name", GENUS_ONE)
def test_genus_one_single_net(models_dir, name):
    net, _ = unfold(single_component(models_dir, name), seed=2)
    assert_valid_net(net)
    # genus g: cuts = |V| - 1 + 2g (the cut graph carries the 2g handle loops)
    assert (~net.crease_mask).sum() == net.mesh.n_vertices - 1 + 2


@pytest.mark.parametrize("name", ["open/hemisphere-152", "open/cube-no-bottom-40",
                                  "paper-parts/horse/part-6", "paper-parts/bunny-128/part-0"])
def test_open_patches_single_net(models_dir, name):
    net, _ = unfold(single_component(models_dir, name), seed=1)
    assert_valid_net(net)


@pytest.mark.parametrize("name", ["bunny-128", "star-prism-36", "spiky-icosahedron-60"])
def test_hyperbolic_vertices_get_two_cuts(models_dir, name):
    # ALGORITHMS.md 2: a vertex with angle sum > 2 pi and only one cut would overlap itself.
    net, _ = unfold(single_component(models_dir, name), seed=3)
    assert_valid_net(net)
    topo = net.mesh.topology
    cut_edges = topo.edges[~net.crease_mask]
    cuts_per_vertex = np.bincount(cut_edges.ravel(), minlength=net.mesh.n_vertices)
    hyper = np.flatnonzero(net.mesh.hyperbolic)
    assert len(hyper) > 0 and (cuts_per_vertex[hyper] >= 2).all()


def test_same_seed_same_net(models_dir):
    mesh = single_component(models_dir, "bunny-128")
    a, _ = unfold(mesh, seed=5)
    b, _ = unfold(mesh, seed=5)
    assert np.array_equal(a.parent, b.parent) and np.array_equal(a.coords, b.coords)


@pytest.mark.parametrize("method", sorted(set(HEURISTICS) - {"unsteepest-edge", "random-edge"}) + ["ga"])
def test_every_method_gives_a_verified_net(models_dir, method):
    mesh = single_component(models_dir, "icosahedron-20")
    net, stats = unfold(mesh, method=method, seed=1, time_limit=20)
    assert_valid_net(net, n_pieces=stats.pieces)


def test_fallback_splits_into_overlap_free_pieces(models_dir):
    mesh = single_component(models_dir, "bumpy-528")
    problem = UnfoldProblem.from_mesh(mesh)
    rng = np.random.default_rng(0)
    parent, parent_edge, order, coords = problem.decode(HEURISTICS["flat-tree"](problem, rng))
    pairs = problem.overlaps(coords, parent)
    assert len(pairs) > 0  # a plain flat tree of this bumpy mesh overlaps
    cut = split_into_pieces(parent, parent_edge, order, pairs)
    # every overlapping pair is separated: some crease on its tree path is cut
    for f, g in pairs:
        assert cut[_tree_path(parent, order, f, g)].any()


def test_fallback_in_blocks_still_separates_every_pair(models_dir, monkeypatch):
    # a net of tens of thousands of faces has ~1e9 creases on its overlap paths: it is cut into
    # blocks first; made to happen here on a small instance by lowering the cap
    import polyfold.unfold.search as search

    mesh = single_component(models_dir, "bumpy-528")
    problem = UnfoldProblem.from_mesh(mesh)
    parent, parent_edge, order, coords = problem.decode(HEURISTICS["flat-tree"](problem, np.random.default_rng(0)))
    pairs = problem.overlaps(coords, parent)
    whole = split_into_pieces(parent, parent_edge, order, pairs)
    monkeypatch.setattr(search, "MAX_PATH_CREASES", 50)
    monkeypatch.setattr(search, "PATH_BLOCK_FACES", 64)
    cut = split_into_pieces(parent, parent_edge, order, pairs)
    for f, g in pairs:
        assert cut[_tree_path(parent, order, f, g)].any()
    pieces = K.piece_labels(order, np.where(cut, -1, parent))
    sizes = np.bincount(pieces)
    assert cut.sum() > whole.sum() and sizes.max() < 3 * 64 + 1  # blocks, each under 3 blocks' faces


def test_dfs_intervals_and_subtree_areas_match_a_plain_walk():
    from polyfold.unfold.net import _dfs_intervals

    rng = np.random.default_rng(3)
    for _ in range(50):
        n = int(rng.integers(1, 200))
        perm = rng.permutation(n)
        parent = np.full(n, -1, dtype=np.int64)
        for k in range(1, n):
            if rng.random() > 0.1:
                parent[perm[k]] = perm[rng.integers(0, k)]
        tin, tout = _dfs_intervals(parent)
        assert sorted(tin.tolist()) == list(range(n))
        for f in range(n):  # g in f's subtree iff f is g or an ancestor of g
            for g in range(n):
                a, up = g, False
                while a >= 0 and not up:
                    up, a = a == f, parent[a]
                assert (tin[f] <= tin[g] < tout[f]) == up


def test_time_limit_fallback_and_max_pieces(models_dir):
    mesh = single_component(models_dir, "bumpy-528")
    net, stats = unfold(mesh, method="flat-tree", seed=0, time_limit=0.0)
    if stats.timed_out:
        assert stats.pieces > 1
        assert_valid_net(net, n_pieces=stats.pieces)
        with pytest.raises(NoNetFound):
            unfold(mesh, method="flat-tree", seed=0, time_limit=0.0, max_pieces=1)


# ----------------------------------------------------------------------------------------------
# unfold()'s optional Deadline: used instead of time_limit when given, same nets for the same seed
# while it is not reached, and a spent one stops the search at once (with a net all the same)


def _same_net(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("parent", "parent_edge", "order", "coords", "piece"))


def test_a_deadline_not_reached_gives_the_time_limits_nets(models_dir):
    mesh = load_mesh(models_dir / "bunny-128.obj").components[0]
    for method in ("auto", "ga", "steepest-edge"):
        for seed in (0, 3):
            net, st = unfold(mesh, method=method, seed=seed, time_limit=600, max_generations=50)
            net_d, st_d = unfold(mesh, method=method, seed=seed, deadline=Deadline.after(600), max_generations=50)
            assert _same_net(net, net_d)
            assert (st.generations, st.evaluations, st.method, st.pieces) == (st_d.generations, st_d.evaluations,
                                                                              st_d.method, st_d.pieces)


def test_a_spent_deadline_stops_the_search(models_dir):
    mesh = load_mesh(models_dir / "bumpy-528.obj").components[0]
    unfold(mesh, seed=0, time_limit=0.0)  # compile / load the kernels first
    t0 = time.perf_counter()
    net, st = unfold(mesh, method="ga", seed=0, time_limit=600, deadline=Deadline.after(0.0))
    assert st.generations == 0  # the deadline wins over time_limit
    assert time.perf_counter() - t0 < 30
    assert net.n_pieces == st.pieces >= 1


# ----------------------------------------------------------------------------------------------
# Flat regions (issue 18): coplanar faces and the triangles of one input polygon are one polygon of
# every net: their merged edges are creases (`assert_flat_regions_whole`), whatever finds the net;
# NO_SINGLE_NET (conftest): the meshes where that leaves no single net


@pytest.mark.parametrize("path", closed_meshes(), ids=lambda p: p.stem)
def test_every_closed_mesh_keeps_its_flat_regions_whole(path):
    (mesh,) = load_mesh(path).components
    hopeless = path.stem in NO_SINGLE_NET
    net, stats = unfold(mesh, seed=1, time_limit=2.0 if hopeless else 60.0)
    assert_valid_net(net, n_pieces=stats.pieces)
    assert_flat_regions_whole(net)
    assert stats.pieces == 1 or hopeless  # no other model needs more than one piece


@pytest.mark.parametrize("name", ["cube-12", "bad/quad-cube", "dodecahedron-36", "truncated-octahedron-44"])
@pytest.mark.parametrize("method", ["auto", "ga", "flat-tree", "steepest-edge", "random"])
def test_every_merged_edge_is_a_crease(models_dir, name, method):
    mesh = single_component(models_dir, name)
    merged = merged_edges(mesh)
    assert merged.any()
    net, stats = unfold(mesh, method=method, seed=2, time_limit=20)
    assert_valid_net(net, n_pieces=stats.pieces)
    assert (net.crease_mask[merged]).all()  # polygons without interior vertices: no flat edge is cut


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_subdivided_box_unfolds_with_whole_sides(seed):
    mesh = subdivided_box(2)
    net, stats = unfold(mesh, seed=seed, time_limit=20)
    assert_valid_net(net)
    assert_flat_regions_whole(net)
    # a side is 32 triangles around 9 interior vertices: 9 flat edges per side are left out of the tree
    merged = merged_edges(mesh)
    assert (merged & ~net.crease_mask).sum() == 6 * 9


@pytest.mark.parametrize("name", sorted(NO_SINGLE_NET))
def test_no_single_net_with_flat_regions_whole(models_dir, name):
    # the memetic search's local search and the multi-piece fallback under the same rule
    net, stats = unfold(single_component(models_dir, name), seed=1, time_limit=3.0)
    assert stats.timed_out and stats.pieces > 1
    assert_valid_net(net, n_pieces=stats.pieces)
    assert_flat_regions_whole(net)


def test_a_blocked_single_net_is_refused_at_once(models_dir):
    # star-4split-96: the cuts forced at its hyperbolic midpoints split the dual graph (NO_SINGLE_NET)
    mesh = single_component(models_dir, "star-4split-96")
    assert UnfoldProblem.from_mesh(mesh).single_net_blocked()
    t0 = time.perf_counter()
    with pytest.raises(NoNetFound, match="flat regions"):
        unfold(mesh, seed=1, time_limit=60, max_pieces=1)
    assert time.perf_counter() - t0 < 5
    for name in ("cube-12", "l-prism-div-44", "torus-8x4-64", "bunny-128"):  # single nets exist
        assert not UnfoldProblem.from_mesh(single_component(models_dir, name)).single_net_blocked()


def test_a_blocked_mesh_is_unfolded_into_pieces_after_a_short_search(models_dir, monkeypatch):
    # without max_pieces=1 the search can only trade overlaps for pieces: it gets BLOCKED_SEARCH_S,
    # not the time limit (make spent 51 s of star-4split-96's 53 s on such searches)
    import polyfold.unfold.search as S

    given = []
    searches = {"run_memetic": S.run_memetic, "fewest_pieces": S.fewest_pieces}

    def recorded(name):
        def run(problem, rng, deadline, *args, **kwargs):
            given.append((name, deadline.left()))
            return searches[name](problem, rng, deadline, *args, **kwargs)
        return run

    for name in searches:
        monkeypatch.setattr(S, name, recorded(name))
    mesh = single_component(models_dir, "star-4split-96")
    net, stats = unfold(mesh, seed=1, time_limit=60)
    assert len(given) == 1 and given[0][0] == "fewest_pieces" and given[0][1] <= S.BLOCKED_SEARCH_S
    assert stats.timed_out and stats.pieces > 1 and stats.method == "fewest-pieces"
    assert_valid_net(net, n_pieces=stats.pieces)
    assert_flat_regions_whole(net)
    given.clear()
    unfold(single_component(models_dir, "bunny-128"), seed=1, time_limit=60)  # not blocked: its time limit
    assert len(given) == 1 and given[0][0] == "run_memetic" and given[0][1] > 50


def test_fallback_cuts_only_cuttable_creases(models_dir):
    mesh = single_component(models_dir, "bumpy-528")
    problem = UnfoldProblem.from_mesh(mesh)
    rng = np.random.default_rng(0)
    parent, parent_edge, order, coords = problem.decode(HEURISTICS["flat-tree"](problem, rng))
    pairs = problem.overlaps(coords, parent)
    cuttable = (parent >= 0) & (rng.random(len(parent)) < 0.5)
    cut = split_into_pieces(parent, parent_edge, order, pairs, cuttable=cuttable)
    allowed = cuttable.copy()
    for f, g in pairs:
        on_path = _tree_path(parent, order, f, g)
        assert cut[on_path].any()  # still separated
        if not cuttable[on_path].any():
            allowed[on_path] = True  # the only way to separate this pair
    assert cut.any() and not (cut & ~allowed).any()


def test_luby_sequence() -> None:
    """The restart lengths: t_i = 2^(k-1) when i = 2^k - 1, else t_(i - 2^(k-1) + 1) for
    2^(k-1) <= i < 2^k - 1 (Luby, Sinclair and Zuckerman 1993)."""
    from polyfold.unfold.search import luby

    def reference(i: int) -> int:
        k = 1
        while (1 << k) - 1 < i:
            k += 1
        return 1 << (k - 1) if i == (1 << k) - 1 else reference(i - (1 << (k - 1)) + 1)

    assert [luby(i) for i in range(1, 16)] == [1, 1, 2, 1, 1, 2, 4, 1, 1, 2, 1, 1, 2, 4, 8]
    assert all(luby(i) == reference(i) for i in range(1, 2000))


def test_memetic_restarts_are_deterministic_and_find_nets(models_dir) -> None:
    """A search cut into restarts after 1, 1, 2, ... generations (restart unit 1): on horse-302,
    seed 29 finds its net in the third generation, after two restarts, the same net every time,
    and the net has no overlap (one search: no race)."""
    import polyfold.unfold.search as search

    mesh = load_mesh(models_dir / "horse-302.obj").components[0]
    problem = UnfoldProblem.from_mesh(mesh)
    kept = search.RESTART_GENERATIONS
    search.RESTART_GENERATIONS = 1
    try:
        runs = [search.run_memetic(problem, np.random.default_rng(29), Deadline.never(), 4, population=50, race=False)
                for _ in range(2)]
    finally:
        search.RESTART_GENERATIONS = kept
    (w1, f1, g1, _, _), (w2, f2, g2, _, _) = runs
    assert (f1, g1) == (0.0, 3) and np.array_equal(w1, w2) and (f2, g2) == (f1, g1)
    G, L = problem.evaluate(w1[None, :])
    assert float(search._fitness(G, L)[0]) == 0.0


def test_no_single_net_carries_the_searched_net_in_pieces(models_dir) -> None:
    """max_pieces=1 without success raises NoNetFound whose `pieces` gives the net the same search
    returns without the request (several pieces, valid), so `make` need not search again; the
    blocked case, where no search runs, carries none."""
    mesh = single_component(models_dir, "torus-12x6-144")
    with pytest.raises(NoNetFound) as caught:
        unfold(mesh, seed=3, time_limit=600, max_generations=2, max_pieces=1)
    net, stats = caught.value.pieces()
    plain, plain_stats = unfold(mesh, seed=3, time_limit=600, max_generations=2)
    assert net.n_pieces > 1 and stats.pieces == net.n_pieces and stats.timed_out
    assert _same_net(net, plain) and plain_stats.pieces == stats.pieces
    assert_valid_net(net, n_pieces=net.n_pieces)
    with pytest.raises(NoNetFound) as blocked:
        unfold(single_component(models_dir, "star-4split-96"), seed=1, time_limit=60, max_pieces=1)
    assert blocked.value.pieces is None


@pytest.mark.parametrize("name", ["horse-302", "bunny-348"])
def test_a_kick_draws_afresh_only_the_edges_near_the_overlaps(models_dir, name) -> None:
    """`kick` (the memetic search's child): the edges of the faces within `rings` edge-steps of
    an overlapping face get fresh weights, every other edge keeps its crease (light) or cut
    (heavy) weight, so Prim's tree away from the overlaps is the tree kicked; a valid tree comes
    back as its own genome."""
    from polyfold.unfold.search import kick

    mesh = single_component(models_dir, name)
    topo = mesh.topology
    problem = UnfoldProblem.from_mesh(mesh)
    for seed in range(3):
        genome = HEURISTICS["random-edge"](problem, np.random.default_rng(seed))
        parent, parent_edge, _, coords = problem.decode(genome)
        pairs = find_overlaps(coords, parent, problem.tol)
        assert len(pairs)
        crease = np.zeros(topo.n_edges, dtype=bool)
        crease[parent_edge[parent_edge >= 0]] = True
        for rings in (0, 2):
            near = set(pairs.ravel().tolist())  # faces within `rings` steps, by a plain BFS
            for _ in range(rings):
                near |= {int(g) for f in near for e in topo.face_edges[f] for g in topo.edge_faces[e] if g >= 0}
            redrawn = np.zeros(topo.n_edges, dtype=bool)
            redrawn[topo.face_edges[sorted(near)].ravel()] = True
            w = kick(problem, genome, np.random.default_rng(seed), rings)
            assert ((w >= 0) & (w <= 1)).all()
            assert (w[~redrawn & crease] == 0).all() and (w[~redrawn & ~crease] >= 0.5).all()
            assert (w[redrawn] < 0.5).any() and (w[redrawn & ~crease] < 0.5).any()  # drawn anew
            _, kicked_edge, _, _ = problem.decode(w)
            kept = np.zeros(topo.n_edges, dtype=bool)
            kept[kicked_edge[kicked_edge >= 0]] = True
            assert (kept[~redrawn & crease]).all()  # the creases away from the overlaps stay
        valid = unfold(mesh, seed=seed, time_limit=60)[0]
        plain = np.zeros(topo.n_edges, dtype=bool)
        plain[valid.parent_edge[valid.parent_edge >= 0]] = True
        w = kick(problem, np.where(plain, 0.0, 1.0), np.random.default_rng(0), 2)
        assert np.array_equal(w == 0, plain)


@pytest.mark.parametrize("name", ["horse-302", "bunny-348"])
def test_local_search_score_is_a_full_recount_of_its_tree(models_dir, name) -> None:
    """The local search keeps its overlapping pairs across moves (re-testing only pairs across
    the moved subtree): the score it reports must equal G + 100 L counted afresh, by the plain
    sweep over every pair, on the tree it returns, for runs of several lengths from random and
    steepest-edge trees. A move that meets many new pairs is turned down without testing them
    all (`SURE_REJECT`): the runs end on the same tree and score as runs that test every pair."""
    from polyfold.unfold.problem import random_weights, steepest_edge_weights
    from polyfold.unfold.search import _genome_of_tree

    mesh = single_component(models_dir, name)
    topo = mesh.topology
    problem = UnfoldProblem.from_mesh(mesh)
    scores = []
    for seed in range(4):
        weights = (steepest_edge_weights if seed % 2 else random_weights)(problem, np.random.default_rng(seed))
        _, parent_edge, _, _ = problem.decode(weights)
        crease = np.zeros(topo.n_edges, dtype=np.bool_)
        crease[parent_edge[parent_edge >= 0]] = True
        for iterations in (20, 200, 1000):
            runs = []
            for sure_reject in (K.SURE_REJECT, 1, 2**62):  # (1: often tests every pair after all; 2**62: always)
                tried = crease.copy()
                runs.append((K.local_search(tried, problem.merged, problem.base, problem.adj_ptr, problem.adj_face,
                                            problem.adj_edge, topo.edge_faces, mesh.faces, topo.face_edges, topo.edges,
                                            problem.hyperbolic, problem.local, problem.tol, iterations, seed, 0.5,
                                            sure_reject), tried))
            # moves judged on a lower bound of their score: the same moves, trees and scores
            assert all(r[0] == runs[0][0] and np.array_equal(r[1], runs[0][1]) for r in runs), (seed, iterations)
            (score, _), crease = runs[0]
            parent, _, _, tris = problem.decode(_genome_of_tree(crease, np.random.default_rng(0)))
            pairs = find_overlaps(tris, parent, problem.tol)
            G, L = len(pairs), K.local_overlaps(pairs.astype(np.int64), topo.face_edges, topo.edges, problem.hyperbolic)
            assert score == G + 100 * L, (seed, iterations)
            scores.append(score)
    assert max(scores) > 0 and len(set(scores)) > 4  # overlapping trees and moves that changed them


@pytest.mark.parametrize("seed", [4, 65, 86])
def test_two_racing_searches_give_the_earlier_rounds_net_on_one_core_or_two(models_dir, monkeypatch, seed) -> None:
    """When the first search's first batch and generation find no net, a second search (its own
    random stream) races it in rounds of a generation: the net found in the earlier round wins,
    the first search's on a tie. On horse-302, seed 4 ties (both in round 2), seed 65 is won by
    the second and seed 86 by the first; the winner is the one each search finds alone, and the
    net, generations and evaluations are the same on one core (turns) as on two (a fork)."""
    import polyfold.processes as processes
    import polyfold.unfold.search as search

    mesh = load_mesh(models_dir / "horse-302.obj").components[0]
    problem = UnfoldProblem.from_mesh(mesh)
    args = (Deadline.never(), 40, 400, 7, 0.4, 0.5, None, None)  # (unfold's population at 302 faces)

    def alone(rng, offset: int):
        """The round a search finds its net in, numbered on from offset, and the net (or None)."""
        s = search._Stream(problem, rng, *args)
        while not s.over():
            s.step()
        return (s.counts[-1][0] + offset, s.answer[0]) if s.answer is not None else (search.NEVER, None)

    rng = np.random.default_rng(seed)
    first = search._Stream(problem, rng, *args)
    while first.steps < search.SOLO_STEPS:
        first.step()
    assert first.answer is None  # the race is run
    solo = first.generation
    rounds = [alone(np.random.default_rng(seed), 0), alone(np.random.default_rng(seed).spawn(1)[0], solo)]
    expected = min((r, k) for k, (r, _) in enumerate(rounds))
    assert expected[0] < search.NEVER
    runs = []
    for cores in (1, 2):
        monkeypatch.setattr(processes, "usable_cores", lambda cores=cores: cores)
        runs.append(search.run_memetic(problem, np.random.default_rng(seed), Deadline.never(), 40, population=400))
    (w1, f1, g1, e1, _), (w2, f2, g2, e2, _) = runs
    assert f1 == f2 == 0.0 and (g1, e1) == (g2, e2) and np.array_equal(w1, w2)
    assert np.array_equal(w1, rounds[expected[1]][1])  # the winner's net: the one it finds alone
    G, L = problem.evaluate(w1[None, :])
    assert float(search._fitness(G, L)[0]) == 0.0
    assert {4: (2, 0), 65: (2, 1), 86: (2, 0)}[seed] == expected


@pytest.mark.parametrize("major", [2, 3])
def test_a_disk_with_no_single_net_is_cut_into_the_fewest_pieces(major):
    # 2 x 4 and 3 x 4 quads of a torus's inside have no single net (every interior vertex is a
    # saddle, tests/unfold/test_problem.py) and two pieces suffice (strips along the minor circle);
    # the GA this search replaced cut its fewest-overlaps tree into 3 and 4. Each piece is checked
    # apart from polyfold's overlap test: no two of its faces overlap by more than a sliver (shapely).
    mesh = torus_inside(major)
    assert mesh.n_faces == 8 * major
    for seed in (1, 2, 3):
        net, stats = unfold(mesh, seed=seed, time_limit=60)
        assert stats.pieces == net.n_pieces == 2 and stats.method == "fewest-pieces"
        assert_valid_net(net, n_pieces=2)
        assert_flat_regions_whole(net)
        faces = [Polygon(c) for c in net.coords]
        sliver = 1e-9 * min(f.area for f in faces)
        for f, g in itertools.combinations(range(mesh.n_faces), 2):
            if net.piece[f] == net.piece[g]:
                assert faces[f].intersection(faces[g]).area <= sliver
