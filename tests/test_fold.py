"""Folding paths: `polyfold unfold --fold`, `polyfold fold`, `polyfold cspace` and the fold API,
judged by the independent path checker (tests/path_checker.py, which does not import polyfold)."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from fold_checker import check_fold
from path_checker import FoldNet, check_path, triangles_cross
from polyfold.fold.plan import is_linearly_foldable, plan_fold
from polyfold.formats.fold import with_path
from polyfold.formats.fold import dumps, net_to_fold
from polyfold.formats.meshes import load_mesh
from polyfold.fold.tree import fold_positions
from polyfold.formats.fold import fold_tree
from polyfold.unfold.search import unfold

CLI = [sys.executable, "-m", "polyfold"]
TESTS = Path(__file__).resolve().parent
PARTS = [f"paper-parts/horse/part-{i}" for i in range(7)] + ["periscope-28"]


def run_cli(*args, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout)


def one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got:\n{stderr}"
    assert "Traceback" not in stderr
    return lines[0]


def straight(fold: dict) -> dict:
    """The FOLD with its path replaced by the straight line flat -> goal."""
    out = dict(fold)
    goal = [float(a) for a in fold["edges_foldAngle"]]
    out["polyfold:path"] = [[0.0] * len(goal), goal]
    return out


def api_net(mesh: Path, method: str = "auto", seed: int = 1) -> dict:
    comps = load_mesh(mesh).components
    return net_to_fold([unfold(c, method=method, seed=seed + i, time_limit=10)[0] for i, c in enumerate(comps)])


# ----------------------------------------------------------------------------------------------
# unfold --fold on the horse's paper parts and the periscope


@pytest.fixture(scope="module")
def folded_parts(models_dir, tmp_path_factory) -> dict:
    """name -> (mesh, FOLD file written by `polyfold unfold --fold`, completed process)."""
    root = tmp_path_factory.mktemp("parts")
    out = {}
    for name in PARTS:
        mesh = models_dir / f"{name}.obj"
        net = root / f"{name.replace('/', '_')}.fold"
        proc = run_cli("unfold", mesh, "-o", net, "--fold", "--seed", 1, "--time-limit", 30)
        out[name] = (mesh, net, proc)
    return out


@pytest.mark.parametrize("name", PARTS)
def test_unfold_fold_gives_a_checked_path(folded_parts, name):
    mesh, net, proc = folded_parts[name]
    assert proc.returncode == 0, proc.stderr
    assert "folding path" in one_line(proc.stderr)
    net_report = check_fold(net, mesh)
    assert net_report.ok, str(net_report)
    fold = json.loads(net.read_text())
    assert fold["polyfold:path_resolutionDeg"] == 1.0
    assert fold.get("polyfold:path_contactTol", 1e-7) == 1e-7
    assert fold["polyfold:path_planner"] in ("linear", "sequential", "sequential-rrt", "lazy-prm")
    assert fold["polyfold:path_linear"] == (len(fold["polyfold:path"]) == 2)
    report = check_path(net)
    assert report.ok, str(report)
    assert report.frames == len(fold["polyfold:path"]) >= 2
    assert report.configs_checked >= report.segments + 1
    assert report.fold_error < 1e-9


def test_horse_parts_need_more_than_the_straight_line(folded_parts):
    """Some horse parts' nets do not fold along the straight line; the checker sees why."""
    bent = []
    for name in PARTS[:7]:
        _, net, proc = folded_parts[name]
        assert proc.returncode == 0, proc.stderr
        fold = json.loads(net.read_text())
        if fold["polyfold:path_planner"] != "linear":
            assert len(fold["polyfold:path"]) > 2
            bent.append(name)
            assert check_path(straight(fold), step_deg=0.5).first_collision is not None, name
    assert bent, "every horse part folded along the straight line"


# ----------------------------------------------------------------------------------------------
# A net whose straight-line fold collides: the Lazy PRM for real


L_OUTLINE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # an L, star-shaped from corner 0
L_CAP = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]


def prism_obj(outline, cap, height: float) -> str:
    """Closed prism over a CCW outline (cap: triangles of it), outward faces, as OBJ text."""
    n = len(outline)
    lines = [f"v {x} {y} 0" for x, y in outline] + [f"v {x} {y} {height}" for x, y in outline]
    for i in range(n):
        j = (i + 1) % n
        lines += [f"f {i + 1} {j + 1} {j + n + 1}", f"f {i + 1} {j + n + 1} {i + n + 1}"]
    for a, b, c in cap:
        lines += [f"f {a + 1} {c + 1} {b + 1}", f"f {a + n + 1} {b + n + 1} {c + n + 1}"]
    return "\n".join(lines) + "\n"


SEARCH = [(m, s) for m in ("auto", "random", "unflat-tree", "steepest-edge", "flat-tree") for s in (1, 2, 3)]


@pytest.fixture(scope="module")
def lazy_case(tmp_path_factory):
    """(name, mesh, FOLD dict, net file, FoldPath): the first net, in a fixed search order, that is not
    linearly foldable but for which the planner finds a Lazy PRM path with an intermediate frame.
    First a hand-made L-shaped prism (written here), then benchmark meshes if they are around."""
    from conftest import models_path

    root = tmp_path_factory.mktemp("lazy")
    hand = root / "l-prism-hand.obj"
    hand.write_text(prism_obj(L_OUTLINE, L_CAP, 1.5))
    meshes = [hand]
    models = models_path()
    if models is not None:
        meshes += [models / f"{n}.obj" for n in ("l-prism-20", "u-prism-28", "periscope-28")]
    for mesh in meshes:
        for method, seed in SEARCH:
            fold = api_net(mesh, method, seed)
            tree = fold_tree(fold)
            if plan_fold(tree, planner="linear") is not None:
                continue
            path = plan_fold(tree, planner="lazy-prm", time_limit=20, seed=1)
            if path is not None and len(path.frames) > 2:
                net = root / f"{mesh.stem}-{method}-{seed}.fold"
                net.write_text(dumps(fold))
                return f"{mesh.name} --method {method} --seed {seed}", mesh, fold, net, path
    pytest.fail("no net needing the Lazy PRM found")


def test_lazy_prm_path_where_the_straight_line_collides(lazy_case):
    name, mesh, fold, net, path = lazy_case
    assert name.startswith("l-prism-hand.obj"), name  # the hand-made mesh suffices
    net_report = check_fold(net, mesh)
    assert net_report.ok, str(net_report)
    tree = fold_tree(fold)
    assert plan_fold(tree, planner="linear") is None
    assert not is_linearly_foldable(tree)
    # the straight line really collides (the planner checks it at 1 deg and 0.5 deg)
    hit = check_path(straight(fold), step_deg=0.5).first_collision
    assert hit is not None and 0 < hit[1] <= 1, hit
    # ... and the Lazy PRM path around it is accepted
    assert path.planner == "lazy-prm" and not path.linear and len(path.frames) > 2
    report = check_path(with_path(fold, path, 1.0, 1e-7))
    assert report.ok, f"{name}:\n{report}"
    finer = check_path(with_path(fold, path, 1.0, 1e-7), step_deg=0.25)
    assert finer.ok, f"{name}:\n{finer}"


def test_fold_cli_plans_around_the_collision(lazy_case, tmp_path):
    name, _, _, net, _ = lazy_case
    out = tmp_path / "out.fold"
    proc = run_cli("fold", net, "-o", out, "--planner", "lazy-prm", "--seed", 1, "--time-limit", 30)
    assert proc.returncode == 0, proc.stderr
    line = one_line(proc.stderr)
    assert "not linearly foldable" in line and "lazy-prm" in line
    fold = json.loads(out.read_text())
    assert fold["polyfold:path_planner"] == "lazy-prm" and fold["polyfold:path_linear"] is False
    assert len(fold["polyfold:path"]) > 2
    report = check_path(out)
    assert report.ok, f"{name}:\n{report}"
    # the checker's command line: 0 on the path, 1 on the straight line (which collides)
    main = subprocess.run([sys.executable, str(TESTS / "path_checker.py"), str(out)], capture_output=True, text=True)
    assert main.returncode == 0 and "ok: True" in main.stdout, main.stdout + main.stderr
    bad = tmp_path / "straight.fold"
    bad.write_text(json.dumps(straight(fold)))
    main = subprocess.run([sys.executable, str(TESTS / "path_checker.py"), str(bad), "--step-deg", "0.5"],
                          capture_output=True, text=True)
    assert main.returncode == 1 and "first collision: segment 0" in main.stdout, main.stdout + main.stderr


def test_linear_planner_fails_cleanly_when_the_straight_line_collides(lazy_case, tmp_path):
    _, _, _, net, _ = lazy_case
    out = tmp_path / "out.fold"
    proc = run_cli("fold", net, "-o", out, "--planner", "linear", "--time-limit", 30)
    assert proc.returncode == 1, proc.stderr
    assert "no folding path" in one_line(proc.stderr)
    assert proc.stdout == ""
    assert not out.exists()


def test_same_seed_same_path(lazy_case, tmp_path):
    _, _, _, net, _ = lazy_case
    paths = []
    for k in range(2):
        out = tmp_path / f"out{k}.fold"
        proc = run_cli("fold", net, "-o", out, "--planner", "lazy-prm", "--seed", 7, "--time-limit", 30)
        assert proc.returncode == 0, proc.stderr
        paths.append(json.loads(out.read_text())["polyfold:path"])
    assert paths[0] == paths[1]
    assert check_path(tmp_path / "out0.fold").ok


# ----------------------------------------------------------------------------------------------
# Whole meshes: the sequential planner (crease-by-crease unfolding of the folded shape)


def _whole_net(models_dir: Path, name: str, seed: int, n_faces: int) -> dict:
    fold = api_net(models_dir / f"{name}.obj", "auto", seed)
    assert len(fold["faces_vertices"]) == n_faces
    return fold


def _assert_monotone_discrete(tree, path) -> None:
    """Every frame is a discrete state of the paper's sampling domain (each crease flat or at its
    goal), and the frames only fold creases, from all flat to all folded."""
    goal = tree.goal[tree.creases]
    cr = path.frames[:, tree.creases]
    assert np.all(np.isclose(cr, 0.0) | np.isclose(cr, goal))
    folded = np.isclose(cr, goal).sum(axis=1)
    assert folded[0] == 0 and folded[-1] == len(goal) and np.all(np.diff(folded) > 0)


def test_sequential_planner_folds_the_whole_horse(models_dir):
    """The paper found no path for the whole horse (301 DOF) in an hour, and the Lazy PRM alone
    finds none here in seconds; crease-by-crease unfolding of the folded shape does. (The
    independent checker re-checks a whole-mesh path below, on the smaller bunny: on the horse
    it takes minutes.)"""
    tree = fold_tree(_whole_net(models_dir, "horse-302", 3, 302))
    assert plan_fold(tree, planner="linear") is None
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=1)
    assert path is not None, "no sequential path for the whole horse"
    assert path.planner == "sequential" and not path.linear
    _assert_monotone_discrete(tree, path)
    assert plan_fold(tree, planner="lazy-prm", time_limit=3, seed=1) is None


def test_sequential_planner_unlocks_stuck_creases_by_a_continuous_search(models_dir):
    """Horse net 13: nine creases of a curled strip carrying a 67-face flap can open neither alone,
    nor first, nor together in the discrete domain (this seed had no path before). The
    RRT-Connect search over those creases opens them; its frames (the path's first ones, off the
    discrete domain) are re-checked by the independent checker, the rest is discrete."""
    fold = _whole_net(models_dir, "horse-302", 13, 302)
    tree = fold_tree(fold)
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=13)
    assert path is not None and path.planner == "sequential-rrt"
    goal = tree.goal[tree.creases]
    cr = path.frames[:, tree.creases]
    discrete = np.all(np.isclose(cr, 0.0) | np.isclose(cr, goal), axis=1)
    k = int(np.argmax(discrete[1:])) + 1  # the stuck state: where the discrete frames begin
    assert k > 1 and not discrete[1:k].any() and discrete[k:].all()
    folded = np.isclose(cr[k:], goal).sum(axis=1)
    assert folded[-1] == len(goal) and np.all(np.diff(folded) > 0)
    # only the stuck creases move in the continuous part, and they end where the discrete part starts
    moving = np.flatnonzero(np.ptp(cr[:k + 1], axis=0) > 0)
    assert 0 < len(moving) <= 32
    net = FoldNet(fold, 1e-7)
    deg = np.asarray(path.degrees_fold())
    for s in range(k):
        _, hit = net.segment_collision(deg[s], deg[s + 1], 0.5, skip_start=s > 0)
        assert hit is None, f"segment {s} collides at {hit}"


@pytest.mark.parametrize("planner", ["auto", "linear", "sequential", "lazy-prm"])
def test_every_planner_handles_a_net_without_creases(models_dir, planner):
    mesh = load_mesh(models_dir / "tetrahedron-4.obj").mesh.submesh(np.array([0]))
    net, _ = unfold(mesh)
    tree = fold_tree(net_to_fold([net]))
    assert len(tree.creases) == 0
    path = plan_fold(tree, planner=planner)
    assert path is not None and path.linear and path.frames.shape == (2, tree.n_edges)
    assert np.allclose(path.frames, 0.0)


@pytest.fixture(scope="module")
def whole_bunny(models_dir, tmp_path_factory) -> tuple[dict, Path]:
    """A one-piece net of the whole bunny (127 DOF) as a FOLD dict and file."""
    fold = _whole_net(models_dir, "bunny-128", 1, 128)
    net = tmp_path_factory.mktemp("whole") / "bunny.fold"
    net.write_text(dumps(fold))
    return fold, net


def test_sequential_path_of_a_whole_mesh_passes_the_independent_checker(whole_bunny):
    fold, _ = whole_bunny
    tree = fold_tree(fold)
    assert plan_fold(tree, planner="linear") is None
    path = plan_fold(tree, planner="sequential", time_limit=60, seed=1)
    assert path is not None and path.planner == "sequential"
    _assert_monotone_discrete(tree, path)
    report = check_path(with_path(fold, path, 1.0, 1e-7), step_deg=0.5)
    assert report.ok, str(report)
    assert report.frames == len(path.frames) > 2


def test_fold_cli_uses_the_sequential_planner_when_the_line_collides(whole_bunny, tmp_path):
    _, net = whole_bunny
    out = tmp_path / "bunny-path.fold"
    proc = run_cli("fold", net, "-o", out, "--seed", 1, "--time-limit", 60)
    assert proc.returncode == 0, proc.stderr
    assert "sequential" in one_line(proc.stderr)
    fold = json.loads(out.read_text())
    assert fold["polyfold:path_planner"] == "sequential" and fold["polyfold:path_linear"] is False
    assert check_path(out).ok


# ----------------------------------------------------------------------------------------------
# Two implementations of the kinematics agree (hypothesis)


@pytest.fixture(scope="module")
def nets(models_dir) -> list[tuple[dict, FoldNet]]:
    """A one-piece and a five-piece net of horse parts, and a two-piece torus net."""
    out = []
    for name, method in (("paper-parts/horse/part-3", "auto"), ("paper-parts/horse/part-5", "steepest-edge"),
                         ("torus-8x4-64", "steepest-edge")):
        fold = api_net(models_dir / f"{name}.obj", method)
        out.append((fold, FoldNet(fold)))
    assert out[1][1].n_pieces > 1 and out[2][1].n_pieces > 1
    return out


def _angles(net: FoldNet, values: np.ndarray) -> np.ndarray:
    assert len(values) >= len(net.edges)
    return np.where(net.cut, 0.0, values[: len(net.edges)])


ANGLES = hnp.arrays(np.float64, 300, elements=st.floats(-180.0, 180.0, allow_nan=False))


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 2), values=ANGLES)
def test_independent_folding_preserves_edge_lengths(nets, which, values):
    fold, net = nets[which]
    q = _angles(net, values)
    pos = net.fold(q)  # (F, 3, 3)
    flat = np.zeros((len(net.xy), 3))
    flat[:, :2] = net.xy
    flat = flat[net.faces]
    side = lambda t: np.linalg.norm(t - np.roll(t, -1, axis=-2), axis=-1)
    assert np.abs(side(pos) - side(flat)).max() < 1e-9 * net.scale
    # every net vertex lands at one point: faces joined by creases stay joined
    for v in range(len(net.xy)):
        pts = pos[net.faces == v]
        assert np.abs(pts - pts[0]).max() < 1e-9 * net.scale
    # faces stay proper (no reflection): folded normals agree with the rigid motion of each face
    n = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    area = 0.5 * np.linalg.norm(n, axis=1)
    flat_area = 0.5 * np.cross(flat[:, 1] - flat[:, 0], flat[:, 2] - flat[:, 0])[:, 2]
    assert np.allclose(area, flat_area, rtol=1e-9, atol=1e-12 * net.scale ** 2)


def _kabsch_error(P: np.ndarray, Q: np.ndarray) -> float:
    pc, qc = P.mean(axis=0), Q.mean(axis=0)
    U, _, Vt = np.linalg.svd((P - pc).T @ (Q - qc))
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    rot = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return float(np.linalg.norm((P - pc) @ rot.T + qc - Q, axis=1).max())


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 2), values=ANGLES)
def test_fold_positions_agrees_with_independent_folding(nets, which, values):
    fold, net = nets[which]
    q = _angles(net, values)
    tree = fold_tree(fold)
    theirs = fold_positions(tree, -np.radians(q))
    mine = net.fold(q)
    for k in range(net.n_pieces):
        members = np.flatnonzero(net.piece == k)
        err = _kabsch_error(theirs[members].reshape(-1, 3), mine[members].reshape(-1, 3))
        assert err < 1e-9 * net.scale, (k, err)


def test_mountain_goes_below_in_both_implementations():
    """One crease, two triangles: a negative (mountain) FOLD angle turns the child below z = 0."""
    fold = {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3]],
        "edges_vertices": [[0, 1], [1, 2], [2, 0], [2, 3], [3, 0]],
        "edges_assignment": ["B", "B", "M", "B", "B"],
        "edges_foldAngle": [0, 0, -90.0, 0, 0],
    }
    net = FoldNet(fold)
    pos = net.fold(np.array([0, 0, -90.0, 0, 0]))
    assert np.allclose(pos[0, :, 2], 0) and pos[1, 2, 2] < -0.5  # vertex 3 of face 1 went down
    theirs = fold_positions(fold_tree(fold), -np.radians([0, 0, -90.0, 0, 0]))
    assert np.allclose(theirs, pos)


# ----------------------------------------------------------------------------------------------
# The checker's own geometry and endpoint checks


def test_triangle_crossing_cases():
    T = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], float)
    cases = {
        "pierced": ([[0.5, 0.5, -1], [0.5, 0.5, 1], [3, 3, 0.5]], True),
        "corner resting on interior": ([[0.5, 0.5, 0], [0.5, 0.5, 1], [1, 0.2, 1]], False),
        "shared edge, folded": ([[0, 0, 0], [2, 0, 0], [1, -1, 1]], False),
        "shared edge, folded flat onto it": ([[0, 0, 0], [2, 0, 0], [0.5, 1, 0]], True),
        "coplanar side by side": ([[2, 0, 0], [0, 2, 0], [2, 2, 0]], False),
        "shared corner, crossing through it": ([[0, 0, 0], [1, 1, 1], [1, 1, -1]], True),
        "shared corner, both straddle, apart": ([[0, 0, 0], [-1, -1, 1], [-1, -1, -1]], False),
        "shared corner, one side": ([[0, 0, 0], [-1, -1, 1], [-1, 1, -1]], False),
        "far above": ([[0, 0, 1], [2, 0, 1], [0, 2, 1]], False),
    }
    A = np.repeat(T[None], len(cases), axis=0)
    B = np.array([c[0] for c in cases.values()], float)
    got = triangles_cross(A, B, 1e-9)
    assert dict(zip(cases, got.tolist())) == {k: v[1] for k, v in cases.items()}
    assert (triangles_cross(B, A, 1e-9) == got).all()  # symmetric


def test_checker_rejects_bad_endpoints(folded_parts):
    _, net, proc = folded_parts["paper-parts/horse/part-0"]
    assert proc.returncode == 0, proc.stderr
    fold = json.loads(net.read_text())
    cut = [e for e, a in enumerate(fold["edges_assignment"]) if a == "B"][0]
    crease = int(np.argmax(np.abs(fold["edges_foldAngle"])))

    def mutated(edit):
        f = json.loads(json.dumps(fold))
        edit(f["polyfold:path"])
        return check_path(f)

    assert not mutated(lambda p: p[0].__setitem__(crease, 1.0)).ok
    assert not mutated(lambda p: p[-1].__setitem__(crease, p[-1][crease] * 0.5)).ok
    assert not mutated(lambda p: p[1].__setitem__(cut, 3.0)).ok
    assert not mutated(lambda p: p.pop()).ok  # stops short of the goal
    f = json.loads(json.dumps(fold))
    f["edges_foldAngle"][crease] *= 0.5  # the goal no longer folds into the foldedForm
    f["polyfold:path"][-1][crease] *= 0.5
    report = check_path(f)
    assert any("foldedForm" in p for p in report.problems), str(report)


# ----------------------------------------------------------------------------------------------
# cspace


def _cspace(net: Path, strategy: str, samples: int = 1000) -> tuple[int, int, float]:
    proc = run_cli("cspace", net, "--samples", samples, "--strategy", strategy, "--seed", 1)
    assert proc.returncode == 0, proc.stderr
    m = re.search(r"valid (\d+) / (\d+) = ([0-9.eE+-]+)", proc.stdout)
    assert m, proc.stdout
    return int(m.group(1)), int(m.group(2)), float(m.group(3))


def test_cspace_ratio_matches_an_independent_estimate(folded_parts):
    """`polyfold cspace` on horse part 0: ratios in [0, 1], and each agrees with an estimate by
    the independent checker from its own samples of the same distribution (within 5 sigma).

    (The paper's Fig. 5 has discrete >= continuous; on these horse-part nets it is the other way
    round: about 0.76 discrete vs 0.94 continuous, so that is not asserted.)"""
    _, net, proc = folded_parts["paper-parts/horse/part-0"]
    assert proc.returncode == 0, proc.stderr
    fold = json.loads(net.read_text())
    checker = FoldNet(fold)
    goal = checker.angles
    rng = np.random.default_rng(2024)
    n_mine = 1000
    ratios = {}
    for strategy in ("discrete", "continuous"):
        valid, total, ratio = _cspace(net, strategy)
        assert total == 1000 and 0.0 <= ratio <= 1.0 and math.isclose(ratio, valid / total, rel_tol=1e-5)
        u = (rng.random((n_mine, len(goal))) < 0.5) if strategy == "discrete" else rng.random((n_mine, len(goal)))
        q = u * goal
        mine = sum(h is None for h in checker.collisions(checker.fold(q))) / n_mine
        p = (valid + mine * n_mine) / (total + n_mine)
        sigma = math.sqrt(max(p * (1 - p), 1e-4) * (1 / total + 1 / n_mine))
        assert abs(ratio - mine) <= 5 * sigma, (strategy, ratio, mine)
        ratios[strategy] = ratio
    # the part needs the Lazy PRM: some of its discrete configurations self-intersect, not all
    assert 0.0 < ratios["discrete"] < 1.0
    assert ratios["continuous"] > 0.0
