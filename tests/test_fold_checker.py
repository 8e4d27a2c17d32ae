"""The independent net checker (tests/fold_checker.py) itself: it accepts a real multi-piece net
of `polyfold unfold` and catches broken ones (overlapping pieces, a wrong fold angle, a mirrored
net, distortion, bad face sources); otherwise the net tests prove nothing."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import models_path, unfold_cli
from fold_checker import check_fold


@pytest.fixture(scope="module")
def multi_piece_net(tmp_path_factory) -> tuple[Path, dict]:
    root = models_path()
    if root is None:
        pytest.skip("benchmark models not found")
    mesh = root / "bunny-128.obj"
    out = tmp_path_factory.mktemp("checker") / "bunny.fold"
    proc = unfold_cli(mesh, out, "--method", "max-perimeter", time_limit=20)
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
