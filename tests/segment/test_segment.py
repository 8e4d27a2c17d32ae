"""segment/segment.py (issue 5): the guarantees on every closed benchmark mesh, part-awareness
against the paper's own decompositions, the part maps, the merging's arrays and memo, and the time
budget (the parts=K search stops at its Deadline).

Connectivity and concavity are re-measured here with code of the test's own (numpy/scipy, no
polyfold geometry), so a bug in the segmenter's bookkeeping cannot hide behind itself."""

from __future__ import annotations

from collections import defaultdict, deque
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from conftest import closed_meshes, depth_below_hull, subdivided_box
from polyfold.deadline import Deadline
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.geometry import merged_edges
from polyfold.mesh.mesh import Mesh, face_components
from polyfold.segment.segment import DEFAULT_TAU, rand_index, segment, surface_samples


# ----------------------------------------------------------------------------------------------
# Independent measures


def edge_connected(faces: np.ndarray) -> bool:
    """True when the triangles form one piece through shared edges (BFS over a dict of edges)."""
    by_edge = defaultdict(list)
    for f, (a, b, c) in enumerate(faces.tolist()):
        for u, v in ((a, b), (b, c), (c, a)):
            by_edge[(min(u, v), max(u, v))].append(f)
    nbrs = defaultdict(set)
    for fs in by_edge.values():
        for f in fs:
            nbrs[f].update(fs)
    seen, todo = {0}, deque([0])
    while todo:
        for g in nbrs[todo.popleft()]:
            if g not in seen:
                seen.add(g)
                todo.append(g)
    return len(seen) == len(faces)


def measured_concavity(mesh: Mesh, faces: np.ndarray, samples: np.ndarray) -> float:
    verts = mesh.vertices[np.unique(mesh.faces[faces])]
    pts = np.concatenate([verts, samples[faces].reshape(-1, 3)])
    return depth_below_hull(pts, verts) / np.linalg.norm(np.ptp(mesh.vertices, axis=0))


def check_segmentation(mesh: Mesh, seg, tau: float) -> None:
    assert seg.labels.shape == (mesh.n_faces,)
    assert seg.labels.min() == 0 and seg.labels.max() == seg.n_parts - 1
    # every face in exactly one part: the part face lists partition the faces
    all_faces = np.concatenate(seg.face_ids)
    assert np.array_equal(np.sort(all_faces), np.arange(mesh.n_faces))
    samples = surface_samples(mesh, seed=0)
    for k, (part, fids, vids) in enumerate(zip(seg.parts, seg.face_ids, seg.vertex_ids)):
        assert np.all(seg.labels[fids] == k)
        # maps: part vertex i is mesh vertex vids[i]; part face j is mesh face fids[j]
        assert np.array_equal(part.vertices, mesh.vertices[vids])
        assert np.array_equal(vids[part.faces], mesh.faces[fids])
        assert np.array_equal(part.face_source, mesh.face_source[fids])
        assert edge_connected(part.faces), f"part {k} is not edge-connected"
        conc = measured_concavity(mesh, fids, samples)
        assert conc == pytest.approx(seg.concavity[k], rel=1e-6, abs=1e-9)
        # (1e-12: rounding of the hull planes; the segmenter treats such depths as 0)
        assert conc <= tau * (1 + 1e-6) + 1e-12, f"part {k}: concavity {conc} > tau {tau}"


def paper_labels(mesh: Mesh, part_files: list[Path]) -> np.ndarray:
    """Face labels of the paper's decomposition: its part files are in the whole mesh's frame."""
    centroids = mesh.vertices[mesh.faces].mean(axis=1)
    tree = cKDTree(centroids)
    labels = np.full(mesh.n_faces, -1)
    for k, path in enumerate(part_files):
        part = trimesh.load(path, process=False, force="mesh")
        dist, idx = tree.query(np.asarray(part.triangles_center))
        assert dist.max() < 1e-4 * mesh.bbox_diagonal
        labels[idx] = k
    assert (labels >= 0).all()
    return labels


# ----------------------------------------------------------------------------------------------
# Guarantees


@pytest.mark.parametrize("path", closed_meshes(), ids=lambda p: p.stem)
def test_guarantees_on_every_closed_mesh(path):
    mesh = load_mesh(path).mesh
    seg = segment(mesh)
    assert seg.tau == DEFAULT_TAU
    check_segmentation(mesh, seg, DEFAULT_TAU)


@pytest.mark.parametrize("tau", [0.0, 0.01, 0.1, 1.0])
def test_guarantees_across_tau(models_dir, tau):
    for name in ("horse-302", "bunny-128", "u-prism-28"):
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
        seg = segment(mesh, tau=tau)
        check_segmentation(mesh, seg, tau)
    # a convex mesh is one part at any tau; tau 0 still allows flat or convex pieces
    cube = load_mesh(models_dir / "icosphere-l2-320.obj").mesh
    assert segment(cube, tau=tau).n_parts == 1


def test_fewer_parts_for_larger_tau(models_dir):
    mesh = load_mesh(models_dir / "horse-302.obj").mesh
    counts = [segment(mesh, tau=t).n_parts for t in (0.01, 0.03, 0.05, 0.1, 0.3)]
    assert counts == sorted(counts, reverse=True) and counts[0] > counts[-1]


@pytest.mark.parametrize("name,k", [("periscope-28", 2), ("periscope2-44", 3), ("bunny-128", 3),
                                    ("fish-472", 5), ("horse-302", 7)])
def test_parts_option_reaches_the_paper_counts(models_dir, name, k):
    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    seg = segment(mesh, parts=k)
    assert seg.n_parts == k
    check_segmentation(mesh, seg, seg.tau)


def test_parts_bounded_by_tau_zero_and_components(models_dir):
    mesh = load_mesh(models_dir / "tetrahedron-4.obj").mesh
    assert segment(mesh, parts=1).n_parts == 1
    # a convex mesh is one part even at tau 0: more parts would not be nearly convex "parts"
    assert segment(mesh, parts=9).n_parts == 1
    # two disjoint copies: never fewer parts than edge-connected components
    two = Mesh(np.concatenate([mesh.vertices, mesh.vertices + 5.0]), np.concatenate([mesh.faces, mesh.faces + 4]))
    seg = segment(two, parts=1)
    assert seg.n_parts == 2
    check_segmentation(two, seg, seg.tau)
    with pytest.raises(ValueError):
        segment(mesh, tau=-1.0)


def test_polygons_of_the_input_stay_whole(tmp_path):
    # an L-shaped prism written with quads and two hexagon caps: any split must follow polygon edges
    pts2 = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    v = [(x, y, 0.0) for x, y in pts2] + [(x, y, 1.0) for x, y in pts2]
    faces = ["f 6 5 4 3 2 1", "f 7 8 9 10 11 12"]
    faces += [f"f {i + 1} {(i + 1) % 6 + 1} {(i + 1) % 6 + 7} {i + 7}" for i in range(6)]
    path = tmp_path / "l.obj"
    path.write_text("\n".join(f"v {x} {y} {z}" for x, y, z in v) + "\n" + "\n".join(faces) + "\n")
    loaded = load_mesh(path)
    seg = segment(loaded.mesh, tau=0.0)
    assert seg.n_parts >= 2  # the L is not convex
    for src in np.unique(loaded.mesh.face_source):
        assert len(set(seg.labels[loaded.mesh.face_source == src].tolist())) == 1
    check_segmentation(loaded.mesh, seg, 0.0)


@pytest.mark.parametrize("name", ["torus-12x6-144", "l-prism-div-44", "star-4split-96", "subdivided-box", "cylinder"])
@pytest.mark.parametrize("how", [{"tau": 0.0}, {"tau": DEFAULT_TAU}, {"parts": 6}])
def test_flat_regions_stay_whole(models_dir, name, how):
    # coplanar faces (merged_edges), like input polygons, are never split between parts: no net cuts them
    if name == "subdivided-box":
        mesh = subdivided_box(2)
    elif name == "cylinder":
        cyl = trimesh.creation.cylinder(radius=0.5, height=1.2, sections=24)
        mesh = Mesh(cyl.vertices, cyl.faces)
    else:
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
    region = face_components(mesh.n_faces, mesh.topology, merged_edges(mesh))
    seg = segment(mesh, **how)
    assert len(np.unique(np.stack([region, seg.labels]), axis=1).T) == region.max() + 1
    # star-4split's triangles are flat to 8e-5 rad only: alone they are up to 1.1e-6 deep below their hull
    check_segmentation(mesh, seg, max(seg.tau, 2e-6))


# ----------------------------------------------------------------------------------------------
# Part-awareness


def test_merging_arrays_match_their_numpy_definitions(models_dir):
    """The per-mesh arrays of the merging come from numba kernels; bit for bit they are the numpy
    expressions they replaced (samples, areas, perimeters, inner edges and their concave weights),
    so costs and concavities do not move."""
    import math

    import polyfold.segment.segment as S
    from polyfold.mesh.geometry import face_areas

    for name in ("periscope-28", "bunny-128", "paper-parts/horse/part-6", "open/tube-132"):
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
        m = S._Merger(mesh, 0)
        topo = mesh.topology
        tri = mesh.vertices[mesh.faces]
        r = np.random.default_rng(0).random((mesh.n_faces, 3, 2))
        flip = r.sum(axis=2) > 1
        r[flip] = 1 - r[flip]
        samples = tri[:, None, 0] + r[..., :1] * (tri[:, None, 1] - tri[:, None, 0]) + r[..., 1:] * (tri[:, None, 2] - tri[:, None, 0])
        edge_len = np.linalg.norm(mesh.vertices[topo.edges[:, 1]] - mesh.vertices[topo.edges[:, 0]], axis=1)
        inner = np.flatnonzero(topo.interior)
        conc_w = edge_len[inner] * np.clip(-mesh.fold_angles[inner], 0.0, None) / (math.pi / 2)
        assert m.samples.tobytes() == samples.tobytes()
        assert m.areas.tobytes() == face_areas(mesh.vertices, mesh.faces).tobytes()
        assert m.face_perim.tobytes() == edge_len[topo.face_edges].sum(axis=1).tobytes()
        assert m.inner_len.tobytes() == edge_len[inner].tobytes() and m.inner_conc.tobytes() == conc_w.tobytes()
        assert np.array_equal(m.ef0, topo.edge_faces[inner, 0]) and np.array_equal(m.ef1, topo.edge_faces[inner, 1])
        assert (conc_w > 0).any() and (conc_w == 0).any()


def test_a_full_memo_is_regrown_and_the_run_redone(models_dir, monkeypatch):
    """merge_run stops when the memo of union concavities fills up and redoes the run on a larger
    one: starting from a memo with room for 2 unions gives the same segmentations."""
    import polyfold.segment.segment as S

    meshes = [load_mesh(models_dir / f"{n}.obj").mesh for n in ("periscope2-44", "bunny-128")]
    cases = [(m, k) for m in meshes for k in (None, 2, 5)]
    want = [segment(m) if k is None else segment(m, parts=k) for m, k in cases]

    def tiny_memo(n_faces):
        return (np.full(4, -1, dtype=np.int64), np.zeros((2, 2), dtype=np.uint64), np.zeros(2),
                np.zeros(2, dtype=bool), np.zeros((2, 2), dtype=np.int64), np.empty((4, 3)), np.zeros(2, dtype=np.int64))

    slots = []
    merge_run = S.merge_run

    def recording_run(*args):
        label, n, memo = merge_run(*args)
        slots.append(len(memo[1]))
        # each part of the memo grows only when short: at most 4x what is in use
        assert len(memo[1]) <= 4 * memo[6][0] + 8 and len(memo[5]) <= 4 * memo[6][1] + 8
        return label, n, memo

    monkeypatch.setattr(S, "new_memo", tiny_memo)
    monkeypatch.setattr(S, "merge_run", recording_run)
    got = [segment(m) if k is None else segment(m, parts=k) for m, k in cases]
    assert max(slots) >= 64  # the memo did grow, many times over
    for a, b in zip(want, got):
        assert np.array_equal(a.labels, b.labels) and a.tau == b.tau and np.array_equal(a.concavity, b.concavity)


def test_rand_index():
    a = np.array([0, 0, 1, 1, 2])
    assert rand_index(a, a) == 1.0
    assert rand_index(a, np.array([5, 5, 3, 3, 9])) == 1.0  # names of parts do not matter
    # pairs: 10; a and b = all-in-one agree only on the 2 pairs a keeps together
    assert rand_index(a, np.zeros(5)) == pytest.approx(2 / 10)
    rng = np.random.default_rng(0)
    x, y = rng.integers(0, 4, 60), rng.integers(0, 3, 60)
    brute = np.mean([(x[i] == x[j]) == (y[i] == y[j]) for i in range(60) for j in range(i + 1, 60)])
    assert rand_index(x, y) == pytest.approx(brute)


@pytest.mark.parametrize("name,group,k,target", [("horse-302", "horse", 7, 0.85), ("fish-472", "fish", 5, 0.95)])
def test_rand_index_against_the_paper(models_dir, name, group, k, target):
    mesh = load_mesh(models_dir / f"{name}.obj").mesh
    files = sorted((models_dir / "paper-parts" / group).glob("part-*.obj"))
    assert len(files) == k
    theirs = paper_labels(mesh, files)
    ours = segment(mesh, parts=k)
    assert ours.n_parts == k
    assert rand_index(ours.labels, theirs) >= target


# ----------------------------------------------------------------------------------------------
# The time budget: the parts=K search stops when its Deadline passes, returns the closest
# count found so far and says so; without a deadline (or with one never reached) nothing changes.


def _same(a, b) -> bool:
    return (np.array_equal(a.labels, b.labels) and a.tau == b.tau and np.array_equal(a.concavity, b.concavity)
            and a.timed_out == b.timed_out)


def test_a_spent_budget_stops_the_parts_search_after_one_run(models_dir, monkeypatch):
    import polyfold.segment.segment as S

    mesh = load_mesh(models_dir / "horse-302.obj").mesh
    calls = []
    merge_run = S.merge_run

    def counting_run(*args):
        calls.append(args[0])
        return merge_run(*args)

    monkeypatch.setattr(S, "merge_run", counting_run)
    full = segment(mesh, parts=6)
    assert full.n_parts == 6 and not full.timed_out
    runs_in_full = len(calls)
    assert runs_in_full > 2  # the default tau does not give 6 parts: a bisection

    calls.clear()
    cut = segment(mesh, parts=6, deadline=Deadline.after(0.0))
    assert len(calls) == 1  # the run at the default tau, then the search stops
    assert cut.timed_out
    assert cut.tau == DEFAULT_TAU and cut.n_parts != 6
    plain = segment(mesh, tau=DEFAULT_TAU)  # what that one run gives
    assert np.array_equal(cut.labels, plain.labels) and np.array_equal(cut.concavity, plain.concavity)
    assert (cut.concavity <= cut.tau).all()


def test_a_budget_not_reached_changes_nothing(models_dir):
    for name, k in (("bunny-128", 3), ("horse-302", 6), ("periscope2-44", 9)):
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
        want = segment(mesh, parts=k)
        assert not want.timed_out
        assert _same(want, segment(mesh, parts=k, deadline=Deadline.after(600.0)))
        assert _same(want, segment(mesh, parts=k, deadline=Deadline.never()))
    # a single tau is one run: a spent deadline does not cut it
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    assert _same(segment(mesh), segment(mesh, deadline=Deadline.after(0.0)))


def test_the_closest_count_so_far_is_returned(models_dir, monkeypatch):
    """A deadline that passes mid-bisection: the answer is the run whose count was closest to K."""
    import polyfold.segment.segment as S

    mesh = load_mesh(models_dir / "horse-302.obj").mesh
    seen = []
    merge_run = S.merge_run

    def recording_run(*args):
        label, n, memo = merge_run(*args)
        seen.append(n)
        return label, n, memo

    class FourRuns:  # expires after the fourth merging run
        def expired(self) -> bool:
            return len(seen) >= 4

    monkeypatch.setattr(S, "merge_run", recording_run)
    cut = segment(mesh, parts=6, deadline=FourRuns())
    assert cut.timed_out and len(seen) == 4
    assert abs(cut.n_parts - 6) == min(abs(n - 6) for n in seen)
    assert (cut.concavity <= cut.tau).all()
