"""unfold/tabroom.py: edge swaps open the narrow notches of a net (corners too narrow for a glue
tab) while the net stays one overlap-free piece; the result is re-checked by the independent
tests/fold_checker.py against the mesh file."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from conftest import assert_flat_regions_whole
from fold_checker import check_fold
from polyfold.formats.fold import net_to_fold, write_fold
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import corner_angles
from polyfold.mesh.mesh import Mesh
from polyfold.unfold.search import unfold
from polyfold.unfold.tabroom import NOTCH_DEG, open_notches


def _free_angles(net) -> list[float]:
    """Free angle (degrees) of every outline corner of a single-piece net, counted here again."""
    return [a for v in range(net.mesh.n_vertices) for a in _free_angles_at(net.mesh, net.crease_mask, v)]


def _free_angles_at(mesh, crease, v) -> list[float]:
    """The free angles (degrees) of the outline corners at vertex v: 360 minus the face angles
    held between a cut edge and the next one."""
    angles = corner_angles(mesh.vertices, mesh.faces)
    topo = mesh.topology
    out = []
    fan = [(f, int(np.flatnonzero(mesh.faces[f] == v)[0])) for f in np.flatnonzero((mesh.faces == v).any(axis=1))]
    cut_in = [(f, j) for f, j in fan if not crease[topo.face_edges[f, (j + 2) % 3]]]
    for f, j in cut_in:  # turn around v through creases to the next cut edge
        held = 0.0
        for _ in range(len(fan)):
            held += angles[f, j]
            e = topo.face_edges[f, j]
            if not crease[e]:
                break
            a, b = topo.edge_faces[e]
            f = b if a == f else a
            j = int(np.flatnonzero(mesh.faces[f] == v)[0])
        out.append(360.0 - math.degrees(held))
    return out


def test_corner_penalties_and_swap_gains_match_a_recount(models_dir) -> None:
    """The compiled corner walk (`_Fans.penalties`, `_Fans.swap_gains`) against the free angles
    counted here: each vertex's penalty is the sum of max(0, 1 - free / NOTCH_DEG) over its
    corners, on a net's creases and on random crease masks; a swap's gain is the change of the
    recounted penalties of the four end vertices, and the mask comes back unchanged."""
    from polyfold.unfold.tabroom import _Fans

    mesh = load_mesh(models_dir / "bunny-128.obj").components[0]
    net, _ = unfold(mesh, seed=3)
    fans = _Fans(net)
    edges = mesh.topology.edges

    def recount(crease, v):
        return sum(max(0.0, 1.0 - a / NOTCH_DEG) for a in _free_angles_at(mesh, crease, v))

    rng = np.random.default_rng(0)
    for crease in (net.crease_mask.copy(), rng.random(mesh.topology.n_edges) < 0.7):
        pen = fans.penalties(np.arange(mesh.n_vertices), crease)
        want = np.array([recount(crease, v) for v in range(mesh.n_vertices)])
        assert np.allclose(pen, want, atol=1e-9) and want.max() > 0
        e2 = int(rng.choice(np.flatnonzero(crease)))
        cand = np.flatnonzero(~crease)[:40]
        kept = crease.copy()
        delta, touched, after = fans.swap_gains(e2, cand, crease, edges, pen)
        assert np.array_equal(crease, kept)
        for c, g in enumerate(cand):
            swapped = crease.copy()
            swapped[e2], swapped[g] = False, True
            verts = sorted({*edges[e2].tolist(), *edges[g].tolist()})
            assert sorted(u for u in touched[c] if u >= 0) == verts
            gain = sum(recount(swapped, u) - recount(crease, u) for u in verts)
            assert delta[c] == pytest.approx(gain, abs=1e-9)
            assert all(after[c][k] == pytest.approx(recount(swapped, touched[c][k]), abs=1e-9)
                       for k in range(4) if touched[c][k] >= 0)


@pytest.mark.parametrize("name", ["fish-472", "bunny-128"])
def test_open_notches_keeps_one_overlap_free_piece_with_fewer_notches(models_dir, tmp_path, name):
    path = models_dir / f"{name}.obj"
    mesh = load_mesh(path).mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    opened, stats = open_notches(net)
    narrow_before = sum(a < NOTCH_DEG for a in _free_angles(net))
    narrow_after = sum(a < NOTCH_DEG for a in _free_angles(opened))
    assert stats.notches_before == narrow_before and stats.notches_after == narrow_after
    assert stats.swaps > 0 and narrow_after < 0.5 * narrow_before
    assert opened.n_pieces == 1 and np.count_nonzero(opened.crease_mask) == mesh.n_faces - 1
    fold = tmp_path / "opened.fold"
    write_fold(fold, net_to_fold([opened]))
    report = check_fold(str(fold), str(path))
    assert report.ok, report.problems[:3]


def test_kept_creases_are_never_cut(models_dir):
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    keep = net.crease_mask.copy()
    opened, stats = open_notches(net, keep=keep)
    assert stats.swaps == 0 and np.array_equal(opened.crease_mask, net.crease_mask)


@pytest.mark.parametrize("name", ["fish-472", "l-prism-div-44", "cylinder"])
def test_flat_regions_are_never_cut(models_dir, name):
    # issue 18: the merged edges of flat regions stay creases whatever `keep` says
    if name == "cylinder":
        cyl = trimesh.creation.cylinder(radius=0.5, height=1.2, sections=24)
        mesh = Mesh(cyl.vertices, cyl.faces)
    else:
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=20, max_pieces=1)
    opened, stats = open_notches(net)
    assert opened.n_pieces == 1
    assert_flat_regions_whole(opened)


def test_the_moved_faces_alone_give_the_full_layouts_verdict(models_dir):
    # `_moved_clear` lays out only the faces a swap moves (the rest keep their corners): on random
    # swaps of a net's tree (cut a crease, glue a cut edge across its subtree's border) its verdict
    # is that of laying the whole swapped tree out from its root and testing the moved faces
    # against the others; both verdicts occur
    from polyfold.collide.flat import face_bounds, overlapping_pairs_between
    from polyfold.unfold import kernels as K
    from polyfold.unfold.net import _dfs_intervals
    from polyfold.unfold.problem import UnfoldProblem
    from polyfold.unfold.tabroom import _laid, _moved_clear

    mesh = load_mesh(models_dir / "fish-472.obj").mesh
    net, _ = unfold(mesh, seed=2, time_limit=20, max_pieces=1)
    problem = UnfoldProblem.from_mesh(mesh, base=int(net.order[0]))
    laid = _laid(net, problem)
    assert np.array_equal(laid.coords, net.coords)  # (the search lays its nets out the same way)
    topo = mesh.topology
    inner = (topo.edge_faces >= 0).all(axis=1)
    tin, tout = _dfs_intervals(net.parent)
    rng = np.random.default_rng(7)
    verdicts = []
    for _ in range(300):
        crease = net.crease_mask.copy()
        e2 = int(rng.choice(np.flatnonzero(crease)))
        a, b = topo.edge_faces[e2]
        child = a if net.parent[a] == b else b
        moved = (tin >= tin[child]) & (tin < tout[child])
        fa, fb = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
        across = np.flatnonzero(inner & ~crease & (moved[np.maximum(fa, 0)] != moved[np.maximum(fb, 0)]))
        if not len(across):
            continue
        g = int(rng.choice(across))
        crease[e2], crease[g] = False, True
        n = mesh.n_faces
        parent, parent_edge, order = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
        assert K.tree_from_creases(crease, int(net.order[0]), problem.adj_ptr, problem.adj_face, problem.adj_edge,
                                   parent, parent_edge, order) == n
        coords = np.empty((n, 3, 2))
        K.layout_tree(order, parent, parent_edge, mesh.faces, topo.face_edges, problem.local, coords)
        bounds = [np.empty(n) for _ in range(4)]
        face_bounds(coords, order, *bounds)
        full = not len(overlapping_pairs_between(coords, parent, np.flatnonzero(moved), np.flatnonzero(~moved),
                                                 *bounds, problem.tol, np.int64(1)))
        assert np.array_equal(coords[~moved], laid.coords[~moved])  # the others keep their corners
        assert _moved_clear(net, laid, problem, crease, moved, np.flatnonzero(moved), np.flatnonzero(~moved),
                            g) == full
        verdicts.append(full)
    assert len(verdicts) > 200 and any(verdicts) and not all(verdicts)
