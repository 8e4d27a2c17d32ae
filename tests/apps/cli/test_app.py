"""apps/cli/app.py: the `polyfold` command line as a whole: startup cost, bad inputs
(bad/expected.json) and unreadable files rejected with one line and exit code 2, nothing left
behind. (The commands: test_mesh_commands.py, test_net_commands.py, test_make_commands.py.)"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import CLI, bad_cases, one_line, run_cli
from fold_checker import check_fold


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


def test_a_command_imports_no_pydantic(models_dir: Path) -> None:
    """typer 0.29 made pydantic a requirement and imports it in every command (0.05 s of each
    start); polyfold pins typer below it (pyproject.toml): a command runs without it."""
    probe = ("import atexit, sys, runpy; sys.argv = ['polyfold'] + sys.argv[1:]\n"
             "atexit.register(lambda: print('pydantic' if 'pydantic' in sys.modules else 'no pydantic'))\n"
             "runpy.run_module('polyfold', run_name='__main__')\n")
    proc = subprocess.run([CLI[0], "-c", probe, "info", str(models_dir / "bunny-128.obj"), "--json"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip().splitlines()[-1] == "no pydantic", proc.stderr[-500:]


def test_a_line_on_stderr_is_one_write(monkeypatch) -> None:
    """`say` writes its line and newline at once: a Ctrl-C between print's two writes left the
    "interrupted" line on the end of the progress line before it."""
    from polyfold.apps.cli.app import say

    writes: list[str] = []

    class Recorder:
        def write(self, text: str) -> int:
            writes.append(text)
            return len(text)

        def flush(self) -> None:
            pass

    monkeypatch.setattr(sys, "stderr", Recorder())
    say("layout: fitting pieces to the page")
    assert writes == ["polyfold: layout: fitting pieces to the page\n"]


def test_progress_uses_rich_on_a_terminal_only(monkeypatch, tmp_path: Path) -> None:
    """The live status line (rich) where rich would call stderr a terminal; elsewhere plain lines,
    and rich is not even imported (it was, 11-22 ms of every make's start, to learn that)."""
    from polyfold.apps.cli.app import terminal_console

    monkeypatch.delenv("FORCE_COLOR", raising=False)
    monkeypatch.delenv("TTY_COMPATIBLE", raising=False)
    assert not sys.stderr.isatty() and terminal_console() is None  # (pytest's captured stderr)
    monkeypatch.setenv("FORCE_COLOR", "1")
    console = terminal_console()
    assert console is not None and console.is_terminal
    monkeypatch.setenv("TTY_COMPATIBLE", "0")  # (rich's own rule decides once rich is asked)
    assert terminal_console() is None

    probe = ("import atexit, sys, runpy; sys.argv = ['polyfold'] + sys.argv[1:]\n"
             "atexit.register(lambda: print('rich' if 'rich' in sys.modules else 'no rich'))\n"
             "runpy.run_module('polyfold', run_name='__main__')\n")
    bunny = Path(__file__).resolve().parents[3] / "examples" / "bunny-128.obj"
    env = {k: v for k, v in os.environ.items() if k not in ("FORCE_COLOR", "TTY_COMPATIBLE")}
    proc = subprocess.run([CLI[0], "-c", probe, "make", str(bunny), "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0 and proc.stdout.strip().splitlines()[-1] == "no rich", proc.stderr[-500:]
    assert "polyfold: layout: " in proc.stderr  # the plain progress lines


# ----------------------------------------------------------------------------------------------
# Bad inputs, as bad/expected.json says


def test_bad_cases_found(models_dir: Path) -> None:
    names = {name for name, _ in bad_cases()}
    assert len(names) >= 15
    for name in names:
        assert (models_dir / "bad" / name).is_file(), name


@pytest.mark.parametrize("name,spec", bad_cases(), ids=[n for n, _ in bad_cases()])
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
