"""verify/paths.py, the independent re-check of written folding paths: its physical model on
hand-made strips (paper sliding on paper collides at any tiny gap, a crease folded flat does
not, a glued seam closing at the goal does not), agreement with tests/path_checker.py on real
paths, paths it must reject, and its independence from the planners' code."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

from path_checker import check_path
from polyfold.fold.plan import plan_fold
from polyfold.fold.tree import FoldTree
from polyfold.formats.fold import pattern_fold, with_path
from polyfold.formats.meshes import load_mesh
from polyfold.unfold.pattern import crease_pattern
from polyfold.unfold.search import unfold
from polyfold.verify.paths import check_fold_path, faces_collide

SRC = Path(__file__).resolve().parents[2] / "src" / "polyfold"


def _strip(frames_deg: list[list[float]], mesh_vertex: list[int] | None = None) -> dict:
    """Three unit right triangles in a row, A = (0, 1, 2), B = (1, 3, 2), C = (2, 3, 4): creases
    A-B (edge 1) and B-C (edge 3); A and C share only net vertex 2."""
    coords = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.0, 2.0]]
    faces = [[0, 1, 2], [1, 3, 2], [2, 3, 4]]
    edges = [[0, 1], [1, 2], [2, 0], [1, 3], [3, 2], [3, 4], [4, 2]]
    assignment = ["B", "V", "B", "B", "V", "B", "B"]
    fold = {"vertices_coords": coords, "faces_vertices": faces, "edges_vertices": edges,
            "edges_assignment": assignment, "edges_foldAngle": frames_deg[-1], "polyfold:path": frames_deg}
    if mesh_vertex is not None:
        fold["polyfold:vertices_meshVertex"] = mesh_vertex
    return fold


def _frames(*angles: tuple[float, float]) -> list[list[float]]:
    """Frames of the strip from (A-B angle, B-C angle) pairs, FOLD degrees."""
    return [[0.0, a, 0.0, 0.0, b, 0.0, 0.0] for a, b in angles]


def test_two_faces_sliding_on_each_other_collide_whatever_the_gap():
    a = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    for gap in (1e-6, 1e-4):
        b = a + [0.3, 0.3, gap]  # nearly coplanar, overlapping in projection
        assert not faces_collide(a, b, tol=1e-7)  # a zero-thickness test lets them pass
        assert faces_collide(a, b, tol=1e-7, thickness=1e-3)
        assert faces_collide(a, b, tol=1e-7, thickness=0.0) is False
    side = a + [1.2, 0.0, 1e-6]  # side by side: closer than the thickness, no overlap
    assert not faces_collide(a, side, tol=1e-7, thickness=1e-3)
    tilted = np.array([[0.2, 0.2, 1e-4], [0.8, 0.2, 0.3], [0.2, 0.6, 0.5]])  # near at one corner only
    assert faces_collide(a, tilted, tol=1e-7, thickness=1e-3) and not faces_collide(a, tilted, tol=1e-7)


def test_paper_folding_onto_paper_collides_at_any_thickness():
    # B folds onto A, then C (hinged on B) back down onto A: a three-layer stack, C ends 2e-6 rad
    # from A's plane over it (a zero-thickness test with a contact tolerance lets that pass)
    almost = 180.0 - 1e-4
    fold = _strip(_frames((0.0, 0.0), (almost, 0.0), (almost, -almost)))
    thin = check_fold_path(fold, thickness=0.0)
    assert thin.ok, thin.why()  # apart by more than the tolerance: no crossing
    assert check_path(fold).first_collision is None  # the tests' checker agrees at that tolerance ...
    assert check_path(fold, tol_rel=1e-5).first_collision is not None  # ... and sees it within 1e-5
    thick = check_fold_path(fold, thickness=1e-3)
    assert not thick.ok and thick.first_collision is not None
    seg, t, i, j = thick.first_collision
    assert (seg, {i, j}) == (1, {0, 2}) and 0 < t <= 1
    # the other way round C folds through A: a crossing at any thickness, where both checkers see it
    through = _strip(_frames((0.0, 0.0), (almost, 0.0), (almost, almost)))
    hit = check_fold_path(through).first_collision
    assert hit is not None and hit[:2] == check_path(through).first_collision[:2]


def test_a_crease_folded_flat_is_no_collision():
    fold = _strip(_frames((0.0, 0.0), (180.0, 0.0)))
    check = check_fold_path(fold, thickness=0.01)
    assert check.ok, check.why()
    assert check.configs == 1 + 180  # the flat frame, then every degree


def test_faces_sharing_a_net_vertex_may_touch_at_it():
    # A and C fold towards each other about the shared corner 2, stopping apart
    fold = _strip(_frames((0.0, 0.0), (60.0, -60.0)))
    assert check_fold_path(fold, thickness=0.01).ok


def test_glued_seams_closing_at_the_goal_are_no_collision(models_dir):
    """star-24's spikes close along seams whose faces are a few degrees apart (well within 1 % of
    its size of each other near the seam): the planner's path at that thickness is accepted, and
    only because the seams are known as seams (without the mesh vertices the closing spikes are
    paper on paper)."""
    mesh = load_mesh(models_dir / "star-24.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=10)
    pattern = crease_pattern([net])
    tree = FoldTree.from_pattern(pattern)
    thickness = 0.01 * tree.scale
    path = plan_fold(tree.with_thickness(thickness), time_limit=20, seed=1)
    assert path is not None
    fold = with_path(pattern_fold(pattern), path, 1.0, 1e-7, thickness)
    check = check_fold_path(fold, thickness=thickness)
    assert check.ok, check.why()
    assert check_path(fold).ok  # and at no thickness by the tests' checker
    del fold["polyfold:vertices_meshVertex"]
    assert not check_fold_path(fold, thickness=thickness).ok


def test_rejects_what_is_not_the_written_goal_or_folds_a_cut():
    fold = _strip(_frames((0.0, 0.0), (90.0, 0.0)))
    fold["edges_foldAngle"] = [0.0, 91.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    assert "goal" in check_fold_path(fold).why()
    fold = _strip(_frames((0.0, 0.0), (90.0, 0.0)))
    fold["polyfold:path"][1][0] = 5.0  # a cut edge
    assert "cut" in check_fold_path(_strip(fold["polyfold:path"])).why()
    fold = _strip(_frames((0.0, 0.0), (90.0, 0.0)))
    fold["polyfold:path"][0][1] = 3.0
    assert "flat" in check_fold_path(fold).why()


def test_agrees_with_the_tests_checker_on_a_colliding_straight_line(lazy_case):
    """The l-prism net whose straight fold collides: both checkers find the collision on the
    straight line, and both accept the Lazy PRM's path around it."""
    _, _, fold, _, path = lazy_case
    straight = dict(fold, **{"polyfold:path": [[0.0] * len(fold["edges_foldAngle"]), list(fold["edges_foldAngle"])]})
    mine = check_fold_path(straight, step_deg=0.5)
    theirs = check_path(straight, step_deg=0.5)
    assert not mine.ok and theirs.first_collision is not None
    written = with_path(fold, path, 1.0, 1e-7)
    assert check_fold_path(written).ok and check_path(written).ok


def test_make_pieces_are_verified_as_written(tmp_path, models_dir):
    """Every piece make calls verified says so in its FOLD file, at the thickness it states, and
    both the package's check and the tests' checker accept the file as written (mm)."""
    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    rep = make(models_dir / "bunny-128.obj", tmp_path, MakeOptions(thickness=0.3, guide=False)).report
    assert rep.stages.fold.thickness_mm == 0.3 and rep.checks.paths_verified == len(rep.pieces)
    for f in sorted(tmp_path.glob("piece-*.fold")):
        fold = json.loads(f.read_text())
        assert fold["polyfold:path_verified"] is True
        folded = np.asarray(fold["file_frames"][0]["vertices_coords"])
        diag = float(np.linalg.norm(folded.max(axis=0) - folded.min(axis=0)))
        assert fold["polyfold:path_thicknessRel"] * diag == pytest.approx(0.3)
        check = check_fold_path(fold, thickness=0.3)
        assert check.ok, f"{f.name}: {check.why()}"
        assert check_path(fold).ok, f.name


def test_shares_no_code_with_the_planners():
    """verify/ imports nothing of polyfold (its own kinematics and triangle tests) but the kernel
    decorator, `polyfold.jit.njit`: numba's njit, run ahead of time where `polyfold warm-up` built
    the kernels (a compiler, like numba itself, not code that checks anything)."""
    for path in (SRC / "verify").glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                if node.level == 2 and node.module == "jit":
                    assert [a.name for a in node.names] == ["njit"], path.name
                    continue
                assert node.level == 0 and not (node.module or "").startswith("polyfold"), (path.name, node.module)
            if isinstance(node, ast.Import):
                assert not any(a.name.startswith("polyfold") for a in node.names), path.name


def test_periscope2_seed_1_gets_a_path_both_checkers_accept(models_dir):
    """`polyfold unfold periscope2-44.obj --fold --seed 1` (issue 19: a path of it once slid the two
    halves of a flat quad across each other 1e-6 apart): its path now passes the independent
    check at the default thickness, the tests' checker, and the tests' checker with a contact
    tolerance of 1e-5 (paper on paper within 1e-5 of the model size would show there)."""
    from polyfold.deadline import Deadline
    from polyfold.pipeline.nets import NetsOptions, unfold_nets

    loaded = load_mesh(models_dir / "periscope2-44.obj")
    result = unfold_nets(loaded, "periscope2-44", NetsOptions(fold=True, seed=1), Deadline.after(60))
    fold = result.fold
    assert result.path_error is None and fold["polyfold:path_verified"] is True
    folded = np.asarray(fold["file_frames"][0]["vertices_coords"])
    diag = float(np.linalg.norm(folded.max(axis=0) - folded.min(axis=0)))
    assert fold["polyfold:path_thicknessRel"] == pytest.approx(1e-3)
    check = check_fold_path(fold, thickness=1e-3 * diag)
    assert check.ok, check.why()
    assert check_path(fold).ok
    assert check_path(fold, tol_rel=1e-5).first_collision is None


@pytest.mark.parametrize("moves", [
    [(30.0, 0.0), (60.0, 0.0), (120.0, 0.0), (179.9999, 0.0), (179.9999, -179.9999)],  # collides last
    [(179.9999, 0.0), (179.9999, -179.9999), (179.9999, -90.0), (179.9999, -30.0), (179.9999, 0.0)],  # first
    [(30.0, -20.0), (60.0, -40.0), (90.0, -60.0), (60.0, -30.0), (0.0, 0.0)],  # no collision
])
def test_a_path_checked_in_two_processes_gets_the_same_verdict(monkeypatch, moves):
    import polyfold.verify.paths as paths
    from polyfold.processes import beside

    fold = _strip(_frames((0.0, 0.0), *moves))
    fold["edges_foldAngle"] = fold["polyfold:path"][-1]
    alone = check_fold_path(fold, thickness=1e-3)
    monkeypatch.setattr(paths, "PARALLEL_CHECK_WORK", 0)  # (any path is long enough to split)
    split = check_fold_path(fold, thickness=1e-3, side_by_side=beside)
    assert split == alone
    assert split.configs > 1


def test_testing_only_pairs_of_different_rigid_bodies_finds_what_testing_every_pair_finds(models_dir):
    """`_segment` tests only pairs of faces in different rigid bodies along a segment (`_bodies`:
    the others keep their relative pose, checked at its start). On random walks of bunny-128's
    net, one to three creases turning per segment by up to 120 degrees, at a thickness of 1 % of
    its size: every two corners of one body keep their distance from start to end, each turning
    crease makes one body more, and from every start free of collision the first colliding
    sample and pair are those of a test of every pair (many segments collide)."""
    import polyfold.verify.paths as paths

    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    net, _ = unfold(mesh, seed=1, time_limit=10)
    fold = pattern_fold(crease_pattern([net]))
    faces = np.asarray(fold["faces_vertices"], dtype=np.int64)
    assignment = [str(a).upper() for a in fold["edges_assignment"]]
    tree = paths._tree(np.asarray(fold["vertices_coords"], dtype=float), faces,
                       np.asarray(fold["edges_vertices"], dtype=np.int64), assignment)
    creases = np.flatnonzero([a not in paths.CUT for a in assignment])
    folded = np.asarray(fold["file_frames"][0]["vertices_coords"])
    scale = float(np.linalg.norm(folded.max(axis=0) - folded.min(axis=0)))
    args = (tree.order, tree.parent, tree.edge, tree.hinge, tree.flat, np.ascontiguousarray(folded[faces]), tree.piece,
            faces, np.full_like(faces, -1), 1e-7 * scale, 0.01 * scale, 0.1 * scale)

    def corners(q):
        return paths._fold(q, tree.order, tree.parent, tree.edge, tree.hinge, tree.flat,
                           np.empty((len(faces), 3, 3))).reshape(-1, 3)

    rng = np.random.default_rng(5)
    colliding = free = 0
    for _walk in range(12):
        q = np.zeros(len(assignment))
        for _step in range(12):
            nxt = q.copy()
            turn = rng.choice(creases, size=int(rng.integers(1, 4)), replace=False)
            nxt[turn] = np.clip(nxt[turn] + rng.uniform(-120.0, 120.0, len(turn)), -180.0, 180.0)
            body = np.repeat(paths._bodies(q, nxt, False, tree.order, tree.parent, tree.edge), 3)
            assert len(np.unique(body)) == 1 + np.count_nonzero(nxt != q)
            a, b = corners(q), corners(nxt)
            same = body[:, None] == body[None, :]
            moved = np.abs(np.linalg.norm(a[:, None] - a[None], axis=2) - np.linalg.norm(b[:, None] - b[None], axis=2))
            assert moved[same].max() < 1e-9 * scale
            m = int(np.ceil(np.abs(nxt - q).max()))
            whole = paths._segment(q, nxt, m, 1, False, True, *args)
            rigid = paths._segment(q, nxt, m, 1, False, False, *args)
            assert rigid[:3] == whole[:3]
            if whole[0] >= 0:
                colliding += 1
                break  # (a walk goes on from configurations free of collision only)
            free += 1
            q = nxt
    assert colliding >= 5 and free >= 20, (colliding, free)
