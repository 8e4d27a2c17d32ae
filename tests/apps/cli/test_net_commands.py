"""apps/cli/net_commands.py, end to end: `polyfold unfold` on every model (every net it writes is
verified by the independent checker in fold_checker.py: structure, congruence with the mesh, no
overlaps, pieces, folding), its methods, time limits and sheet options; `unfold --fold` and
`polyfold fold` with their folding paths judged by the independent path checker (path_checker.py).
(`polyfold cspace`: fold/test_cspace.py.)"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import (NO_SINGLE_NET, PARTS, by_class, closed_meshes, models_path, one_line, read_png, run_cli,
                      straight, torus_inside, unfold_cli)
from fold_checker import check_fold
from path_checker import check_path

METHODS = ["steepest-edge", "flat-tree", "unflat-tree", "min-perimeter", "max-perimeter", "random", "ga"]
TESTS = Path(__file__).resolve().parents[2]  # tests/, where path_checker.py is


def assert_single_net(mesh: Path, out: Path, proc: subprocess.CompletedProcess, single: bool = True) -> None:
    assert proc.returncode == 0, f"{mesh.name}: exit {proc.returncode}\n{proc.stderr}"
    assert "Traceback" not in proc.stderr
    report = check_fold(out, mesh)
    assert report.ok, f"{mesh.name}:\n{report}"
    assert report.overlaps == []
    assert (report.pieces == 1) == single, f"{mesh.name}: {report.pieces} pieces\n{proc.stderr}"


def _open_meshes() -> list[Path]:
    root = models_path()
    if root is None:
        return []
    return sorted(p for sub in ("open", "paper-parts") for p in (root / sub).rglob("*.obj"))


def _id(path: Path) -> str:
    root = models_path()
    return str(path.relative_to(root)) if root else path.name


# ----------------------------------------------------------------------------------------------
# Every benchmark mesh gets one verified net


def _unfold_every_mesh(mesh: Path, out: Path) -> None:
    """One verified net; several pieces (within 3 s) where whole flat regions leave no single one."""
    if _id(mesh).removesuffix(".obj") in NO_SINGLE_NET:
        assert_single_net(mesh, out, unfold_cli(mesh, out, time_limit=3), single=False)
    else:
        assert_single_net(mesh, out, unfold_cli(mesh, out))


@pytest.mark.parametrize("mesh", closed_meshes(), ids=_id)
def test_closed_mesh_single_net(mesh: Path, tmp_path: Path) -> None:
    _unfold_every_mesh(mesh, tmp_path / "net.fold")


@pytest.mark.parametrize("mesh", _open_meshes(), ids=_id)
def test_open_mesh_single_net(mesh: Path, tmp_path: Path) -> None:
    _unfold_every_mesh(mesh, tmp_path / "net.fold")


def test_models_found(models_dir: Path) -> None:
    # Guard against the parametrized tests silently collecting nothing.
    assert len(closed_meshes()) >= 30
    assert len(_open_meshes()) >= 10


# ----------------------------------------------------------------------------------------------
# Seeds and determinism


def test_seeds_and_determinism(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "bunny-128.obj"
    paths = {}
    for name, seed in (("a", 1), ("b", 1), ("c", 2)):
        paths[name] = tmp_path / f"{name}.fold"
        proc = unfold_cli(mesh, paths[name], seed=seed)
        assert_single_net(mesh, paths[name], proc)
    assert paths["a"].read_bytes() == paths["b"].read_bytes(), "same seed, different FOLD files"


# ----------------------------------------------------------------------------------------------
# Sheet outputs


def test_svg_and_png(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "cube-12.obj"
    out, svg, png = tmp_path / "cube.fold", tmp_path / "cube.svg", tmp_path / "cube.png"
    proc = unfold_cli(mesh, out, "--svg", svg, "--png", png)
    assert_single_net(mesh, out, proc)
    assert svg.stat().st_size > 0 and png.stat().st_size > 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import xml.etree.ElementTree as ET

    root = ET.parse(svg).getroot()
    assert root.tag.endswith("svg")
    assert root.get("width", "").endswith("mm") and root.get("height", "").endswith("mm")


def _drawn_segments(svg: Path) -> np.ndarray:
    """Every straight segment (k, 2, 2) of the cut, mountain and valley layers of an SVG (paths of
    absolute M / L / Z commands), read with a parser of its own."""
    segs = []
    for group in ET.parse(svg).getroot().iter("{http://www.w3.org/2000/svg}g"):
        if group.get("id") not in ("cut", "mountain", "valley"):
            continue
        for path in group.iter("{http://www.w3.org/2000/svg}path"):
            for sub in re.findall(r"M[^M]*", path.get("d")):
                pts = np.array([float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", sub)]).reshape(-1, 2)
                if sub.rstrip().endswith("Z"):
                    pts = np.vstack([pts, pts[:1]])
                segs.extend(np.stack([pts[:-1], pts[1:]], axis=1))
    return np.array(segs).reshape(-1, 2, 2)


def test_quads_stay_whole(models_dir: Path, tmp_path: Path) -> None:
    # issue 18: each quad of the input file (two triangles after loading) is one polygon of the net
    mesh = models_dir / "bad" / "quad-cube.obj"
    out, svg = tmp_path / "quads.fold", tmp_path / "quads.svg"
    proc = unfold_cli(mesh, out, "--svg", svg, "--size", 100, "--fold")
    assert_single_net(mesh, out, proc)
    fold = json.loads(out.read_text())
    source = fold["polyfold:faces_meshFace"]
    kind = {frozenset(e): a for e, a in zip(fold["edges_vertices"], fold["edges_assignment"])}
    for quad in range(6):
        t0, t1 = (set(fold["faces_vertices"][f]) for f in range(len(source)) if source[f] == quad)
        assert kind[frozenset(t0 & t1)] == "F"  # joined by their flat diagonal, not cut along it
    # no line of the sheet is a diagonal of a 100 mm square (sides, tabs and creases are shorter)
    lengths = np.linalg.norm(np.diff(_drawn_segments(svg), axis=1)[:, 0], axis=1)
    assert len(lengths) > 0 and np.allclose(lengths.max(), 100.0)


def test_cli_sheet_options_and_oversize_warning(models_dir: Path, tmp_path: Path):
    mesh = models_dir / "tetrahedron-4.obj"
    svg, png = tmp_path / "t.svg", tmp_path / "t.png"
    proc = subprocess.run([sys.executable, "-m", "polyfold", "unfold", str(mesh), "-o", str(tmp_path / "t.fold"),
                           "--svg", str(svg), "--png", str(png), "--size", "400", "--no-labels", "--no-tabs"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "larger than 300 x 300 mm" in proc.stderr
    root = ET.parse(svg).getroot()
    assert not by_class(root, "edge-label") and not by_class(root, "tab") and by_class(root, "cut")
    assert read_png(png).shape[1] == 1200


# ----------------------------------------------------------------------------------------------
# Every search method gives a valid net (heuristics may need several pieces)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ["icosahedron-20", "bunny-128"])
def test_methods(models_dir: Path, tmp_path: Path, method: str, name: str) -> None:
    mesh = models_dir / f"{name}.obj"
    out = tmp_path / "net.fold"
    proc = unfold_cli(mesh, out, "--method", method, time_limit=20)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = check_fold(out, mesh)
    assert report.ok, f"{method} on {name}:\n{report}"
    assert report.overlaps == []
    assert report.pieces >= 1
    if report.pieces > 1:
        assert "fell back" in proc.stderr


# ----------------------------------------------------------------------------------------------
# Running out of time, bad options


def test_tiny_time_limit_falls_back_to_pieces(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "bumpy-528.obj"
    out = tmp_path / "net.fold"
    proc = unfold_cli(mesh, out, "--method", "ga", time_limit=0.05)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = check_fold(out, mesh)
    assert report.ok, str(report)
    assert report.overlaps == []
    if report.pieces > 1:
        assert "fell back" in proc.stderr, proc.stderr


def test_tiny_time_limit_max_pieces_1(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "bumpy-528.obj"
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = out_dir / "net.fold"
    proc = unfold_cli(mesh, out, "--method", "ga", "--max-pieces", "1", time_limit=0.05)
    assert "Traceback" not in proc.stderr
    if proc.returncode == 0:
        assert_single_net(mesh, out, proc)
    else:
        assert proc.returncode == 1, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        assert "bumpy-528" in proc.stderr
        assert list(out_dir.iterdir()) == []


def test_a_mesh_without_a_single_net_is_told_so(tmp_path: Path) -> None:
    # a patch of a torus's inside (every interior vertex a saddle) has no single net: --max-pieces 1
    # fails at once naming why, and without it the net comes in the fewest pieces (two), which the
    # independent checker passes
    import trimesh

    mesh = torus_inside(2)
    obj = tmp_path / "inside.obj"
    trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(obj)
    out = tmp_path / "net.fold"
    proc = unfold_cli(obj, out, "--max-pieces", "1")
    assert proc.returncode == 1
    assert "interior vertices are all hyperbolic" in one_line(proc.stderr)
    assert not out.exists()
    proc = unfold_cli(obj, out)
    assert_single_net(obj, out, proc, single=False)
    assert check_fold(out, obj).pieces == 2
    assert "2 pieces" in proc.stderr and "no single-piece net exists" in proc.stderr


def test_bad_max_pieces(models_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "net.fold"
    proc = run_cli("unfold", models_dir / "cube-12.obj", "-o", out, "--max-pieces", "7")
    assert proc.returncode == 2
    one_line(proc.stderr)
    assert not out.exists()


# ----------------------------------------------------------------------------------------------
# unfold --fold on the horse's paper parts and the periscope


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
    assert fold["polyfold:path_planner"] in ("linear", "two-phase", "sequential", "sequential-rrt", "lazy-prm")
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
# polyfold fold on a net whose straight-line fold collides (the `lazy_case` fixture)


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
# polyfold fold on a whole mesh: the sequential planner


def test_fold_cli_uses_the_sequential_planner_when_the_line_collides(whole_bunny, tmp_path):
    _, net = whole_bunny
    out = tmp_path / "bunny-path.fold"
    proc = run_cli("fold", net, "-o", out, "--seed", 1, "--time-limit", 60)
    assert proc.returncode == 0, proc.stderr
    assert "sequential" in one_line(proc.stderr)
    fold = json.loads(out.read_text())
    assert fold["polyfold:path_planner"] == "sequential" and fold["polyfold:path_linear"] is False
    assert check_path(out).ok
