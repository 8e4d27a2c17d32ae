"""Tests of the `polyfold` command line: startup cost, bad inputs (bad/expected.json), `info`."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import models_path
from fold_checker import check_fold

CLI = [sys.executable, "-m", "polyfold"]
INFO_FIELDS = ("faces", "vertices", "edges", "components", "boundary_loops", "genus", "closed", "manifold",
               "oriented", "hyperbolic_vertices", "concavity")


def run_cli(*args, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout)


def one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got:\n{stderr}"
    assert "Traceback" not in stderr
    return lines[0]


def _bad_cases() -> list[tuple[str, dict]]:
    root = models_path()
    if root is None:
        return []
    table = json.loads((root / "bad" / "expected.json").read_text())
    return sorted((name, spec) for name, spec in table.items() if not name.startswith("_"))


# ----------------------------------------------------------------------------------------------
# Startup


def test_help() -> None:
    script = Path(sys.executable).with_name("polyfold")
    cmd = [str(script)] if script.exists() else CLI
    proc = subprocess.run([*cmd, "--help"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert "unfold" in proc.stdout and "info" in proc.stdout


def test_cli_import_is_light() -> None:
    code = "import sys, polyfold.apps.cli.app; print(any(m in sys.modules for m in ('numba', 'trimesh', 'scipy')))"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"


# ----------------------------------------------------------------------------------------------
# Bad inputs, as bad/expected.json says


def test_bad_cases_found(models_dir: Path) -> None:
    names = {name for name, _ in _bad_cases()}
    assert len(names) >= 15
    for name in names:
        assert (models_dir / "bad" / name).is_file(), name


@pytest.mark.parametrize("name,spec", _bad_cases(), ids=[n for n, _ in _bad_cases()])
def test_bad_input(models_dir: Path, tmp_path: Path, name: str, spec: dict) -> None:
    mesh = models_dir / "bad" / name
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = out_dir / "net.fold"
    proc = run_cli("unfold", mesh, "-o", out, "--seed", 1, "--time-limit", 20)
    assert "Traceback" not in proc.stderr, proc.stderr
    expect = spec["expect"]

    def assert_rejected():
        assert proc.returncode == 2, f"exit {proc.returncode}\n{proc.stderr}"
        assert name in one_line(proc.stderr)
        assert list(out_dir.iterdir()) == [], "output or temp files left behind"

    def assert_net(orientation: str):
        assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stderr}"
        assert list(out_dir.iterdir()) == [out], "temp files left behind"
        report = check_fold(out, mesh, orientation=orientation)
        assert report.ok, str(report)
        assert report.overlaps == []
        if "pieces" in spec:
            assert report.pieces == spec["pieces"], f"{report.pieces} pieces\n{proc.stderr}"

    if expect == "reject":
        assert_rejected()
    elif expect == "repair":
        warnings = [line for line in proc.stderr.splitlines() if "warning" in line]
        assert warnings, proc.stderr
        # A repair may flip faces, so the net follows the repaired orientation, not the file's.
        assert_net("outward")
    elif expect == "accept":
        assert_net("source")
    elif expect == "either":
        if proc.returncode == 0:
            assert_net("source")
        else:
            assert_rejected()
    else:
        pytest.fail(f"unknown expectation {expect!r}")


# ----------------------------------------------------------------------------------------------
# polyfold info


@pytest.mark.parametrize(
    "rel,expected",
    [
        ("cube-12.obj", {"faces": 12, "vertices": 8, "edges": 18, "components": 1, "genus": 0, "closed": True,
                         "boundary_loops": 0, "hyperbolic_vertices": 0}),
        ("torus-50.obj", {"faces": 50, "vertices": 25, "edges": 75, "genus": 1, "closed": True,
                          "hyperbolic_vertices": 10}),
        ("bunny-128.obj", {"faces": 128, "vertices": 66, "genus": 0, "closed": True, "hyperbolic_vertices": 24}),
        ("open/cube-no-bottom-40.obj", {"faces": 40, "closed": False, "boundary_loops": 1}),
        ("bad/two-cubes.obj", {"components": 2, "closed": True}),
    ],
)
def test_info_json(models_dir: Path, rel: str, expected: dict) -> None:
    proc = run_cli("info", models_dir / rel, "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    for key in INFO_FIELDS:
        assert key in report, key
    assert isinstance(report["concavity"], float)
    for key, value in expected.items():
        assert report[key] == value, (key, report[key], value)


def test_info_plain(models_dir: Path) -> None:
    proc = run_cli("info", models_dir / "cube-12.obj")
    assert proc.returncode == 0, proc.stderr
    assert "genus" in proc.stdout


def test_info_rejects(models_dir: Path) -> None:
    for name, spec in _bad_cases():
        if spec["expect"] != "reject":
            continue
        proc = run_cli("info", models_dir / "bad" / name, "--json")
        assert proc.returncode == 2, f"{name}: exit {proc.returncode}\n{proc.stderr}"
        assert name in one_line(proc.stderr)
        assert proc.stdout.strip() == ""


# ----------------------------------------------------------------------------------------------
# Unreadable files


def _unreadable(kind: str, tmp_path: Path) -> Path:
    if kind == "directory":
        path = tmp_path / "folder.obj"
        path.mkdir()
    elif kind == "garbage":
        path = tmp_path / "garbage.obj"
        path.write_bytes(bytes(range(256)) * 8 + b"\x00\xff\xfe v 1 2\x00 f 1 2 3\n")
    elif kind == "missing":
        path = tmp_path / "missing.obj"
    elif kind == "unknown-extension":
        path = tmp_path / "mesh.xyz"
        path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    else:
        raise AssertionError(kind)
    return path


@pytest.mark.parametrize("command", ["unfold", "info"])
@pytest.mark.parametrize("kind", ["directory", "garbage", "missing", "unknown-extension"])
def test_unreadable(tmp_path: Path, kind: str, command: str) -> None:
    path = _unreadable(kind, tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    args = ["unfold", path, "-o", out_dir / "net.fold", "--time-limit", 5] if command == "unfold" else ["info", path]
    proc = run_cli(*args)
    assert proc.returncode == 2, f"exit {proc.returncode}\n{proc.stderr}"
    assert path.name in one_line(proc.stderr)
    assert list(out_dir.iterdir()) == []


def test_bad_max_pieces(models_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "net.fold"
    proc = run_cli("unfold", models_dir / "cube-12.obj", "-o", out, "--max-pieces", "7")
    assert proc.returncode == 2
    one_line(proc.stderr)
    assert not out.exists()
