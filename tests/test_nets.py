"""End-to-end tests of `polyfold unfold`: every net the CLI writes is verified by the independent
checker in fold_checker.py (structure, congruence with the mesh, no overlaps, pieces, folding)."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import closed_meshes, models_path
from fold_checker import check_fold

CLI = [sys.executable, "-m", "polyfold"]
METHODS = ["steepest-edge", "flat-tree", "unflat-tree", "min-perimeter", "max-perimeter", "random", "ga"]


def run_cli(*args, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout)


def unfold(mesh: Path, out: Path, *extra, seed: int = 1, time_limit: float = 60) -> subprocess.CompletedProcess:
    return run_cli("unfold", mesh, "-o", out, "--seed", seed, "--time-limit", time_limit, *extra)


def assert_single_net(mesh: Path, out: Path, proc: subprocess.CompletedProcess) -> None:
    assert proc.returncode == 0, f"{mesh.name}: exit {proc.returncode}\n{proc.stderr}"
    assert "Traceback" not in proc.stderr
    report = check_fold(out, mesh)
    assert report.ok, f"{mesh.name}:\n{report}"
    assert report.overlaps == []
    assert report.pieces == 1, f"{mesh.name}: {report.pieces} pieces\n{proc.stderr}"


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


@pytest.mark.parametrize("mesh", closed_meshes(), ids=_id)
def test_closed_mesh_single_net(mesh: Path, tmp_path: Path) -> None:
    out = tmp_path / "net.fold"
    assert_single_net(mesh, out, unfold(mesh, out))


@pytest.mark.parametrize("mesh", _open_meshes(), ids=_id)
def test_open_mesh_single_net(mesh: Path, tmp_path: Path) -> None:
    out = tmp_path / "net.fold"
    assert_single_net(mesh, out, unfold(mesh, out))


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
        proc = unfold(mesh, paths[name], seed=seed)
        assert_single_net(mesh, paths[name], proc)
    assert paths["a"].read_bytes() == paths["b"].read_bytes(), "same seed, different FOLD files"


# ----------------------------------------------------------------------------------------------
# Sheet outputs


def test_svg_and_png(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "cube-12.obj"
    out, svg, png = tmp_path / "cube.fold", tmp_path / "cube.svg", tmp_path / "cube.png"
    proc = unfold(mesh, out, "--svg", svg, "--png", png)
    assert_single_net(mesh, out, proc)
    assert svg.stat().st_size > 0 and png.stat().st_size > 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import xml.etree.ElementTree as ET

    root = ET.parse(svg).getroot()
    assert root.tag.endswith("svg")
    assert root.get("width", "").endswith("mm") and root.get("height", "").endswith("mm")


# ----------------------------------------------------------------------------------------------
# Every search method gives a valid net (heuristics may need several pieces)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ["icosahedron-20", "bunny-128"])
def test_methods(models_dir: Path, tmp_path: Path, method: str, name: str) -> None:
    mesh = models_dir / f"{name}.obj"
    out = tmp_path / "net.fold"
    proc = unfold(mesh, out, "--method", method, time_limit=20)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = check_fold(out, mesh)
    assert report.ok, f"{method} on {name}:\n{report}"
    assert report.overlaps == []
    assert report.pieces >= 1
    if report.pieces > 1:
        assert "fell back" in proc.stderr


# ----------------------------------------------------------------------------------------------
# Running out of time


def test_tiny_time_limit_falls_back_to_pieces(models_dir: Path, tmp_path: Path) -> None:
    mesh = models_dir / "bumpy-528.obj"
    out = tmp_path / "net.fold"
    proc = unfold(mesh, out, "--method", "ga", time_limit=0.05)
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
    proc = unfold(mesh, out, "--method", "ga", "--max-pieces", "1", time_limit=0.05)
    assert "Traceback" not in proc.stderr
    if proc.returncode == 0:
        assert_single_net(mesh, out, proc)
    else:
        assert proc.returncode == 1, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        assert "bumpy-528" in proc.stderr
        assert list(out_dir.iterdir()) == []


# ----------------------------------------------------------------------------------------------
# The checker itself must catch broken nets (otherwise the tests above prove nothing)


@pytest.fixture(scope="module")
def multi_piece_net(tmp_path_factory) -> tuple[Path, dict]:
    root = models_path()
    if root is None:
        pytest.skip("benchmark models not found")
    mesh = root / "bunny-128.obj"
    out = tmp_path_factory.mktemp("checker") / "bunny.fold"
    proc = unfold(mesh, out, "--method", "max-perimeter", time_limit=20)
    assert proc.returncode == 0, proc.stderr
    fold = json.loads(out.read_text())
    if max(fold["polyfold:faces_piece"]) < 1:
        pytest.skip("max-perimeter gave a single piece: no multi-piece net to mutate")
    return mesh, fold


def _mutated(tmp_path: Path, fold: dict, mutate) -> Path:
    fold = copy.deepcopy(fold)
    mutate(fold)
    path = tmp_path / "mutated.fold"
    path.write_text(json.dumps(fold))
    return path


def _first_crease(fold: dict) -> int:
    return next(e for e, a in enumerate(fold["edges_assignment"]) if a in ("M", "V"))


def test_checker_accepts_the_net(multi_piece_net, tmp_path: Path) -> None:
    mesh, fold = multi_piece_net
    report = check_fold(_mutated(tmp_path, fold, lambda f: None), mesh)
    assert report.ok, str(report)
    assert report.pieces == max(fold["polyfold:faces_piece"]) + 1


def test_checker_catches_overlapping_pieces(multi_piece_net, tmp_path: Path) -> None:
    mesh, fold = multi_piece_net

    def stack(f):
        xy = np.array(f["vertices_coords"])
        faces = np.array(f["faces_vertices"])
        piece = np.array(f["polyfold:faces_piece"])
        v0, v1 = np.unique(faces[piece == 0]), np.unique(faces[piece == 1])
        xy[v1] += xy[v0].mean(axis=0) - xy[v1].mean(axis=0)
        f["vertices_coords"] = xy.tolist()

    report = check_fold(_mutated(tmp_path, fold, stack), mesh)
    assert report.overlaps and not report.ok


def test_checker_catches_wrong_fold_angle(multi_piece_net, tmp_path: Path) -> None:
    mesh, fold = multi_piece_net

    def bend(f):
        f["edges_foldAngle"][_first_crease(f)] *= 1.01

    report = check_fold(_mutated(tmp_path, fold, bend), mesh)
    assert not report.ok and report.fold_error > 1e-6


def test_checker_catches_mirrored_net(multi_piece_net, tmp_path: Path) -> None:
    mesh, fold = multi_piece_net

    def mirror(f):  # a mirror image, kept CCW and with the folds reversed: inside out
        f["vertices_coords"] = [[-x, y] for x, y in f["vertices_coords"]]
        f["faces_vertices"] = [t[::-1] for t in f["faces_vertices"]]
        f["edges_foldAngle"] = [-a for a in f["edges_foldAngle"]]
        f["edges_assignment"] = [{"M": "V", "V": "M"}.get(a, a) for a in f["edges_assignment"]]

    path = _mutated(tmp_path, fold, mirror)
    assert not check_fold(path, mesh).ok
    assert not check_fold(path, mesh, orientation="outward").ok


def test_checker_catches_distortion_and_bad_sources(multi_piece_net, tmp_path: Path) -> None:
    mesh, fold = multi_piece_net

    def stretch(f):
        f["vertices_coords"][0][0] += 1e-3

    def swap(f):
        s = f["polyfold:faces_meshFace"]
        s[0], s[1] = s[1], s[0]

    def drop(f):
        for key in ("faces_vertices", "polyfold:faces_meshFace", "polyfold:faces_piece"):
            f[key] = f[key][:-1]

    def cut(f):
        f["edges_assignment"][_first_crease(f)] = "B"

    for mutate in (stretch, swap, drop, cut):
        report = check_fold(_mutated(tmp_path, fold, mutate), mesh)
        assert not report.ok, mutate.__name__
