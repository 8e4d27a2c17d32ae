"""Issue 20, part 1: no file polyfold did not write is ever deleted or overwritten, through the CLI.
make and segment touch only what their last run into the folder wrote (its manifest), refuse an
input named like an output in the output folder, and `-o` equal to the input, a missing folder or
a folder given for a file stop with one line and exit 2 before anything is written."""

from __future__ import annotations

import shutil
from pathlib import Path

from conftest import one_line, run_cli


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


def test_make_keeps_the_users_files_and_never_replaces_its_input(models_dir: Path, tmp_path: Path) -> None:
    d = tmp_path / "d"
    d.mkdir()
    shutil.copy(models_dir / "bunny-128.obj", d / "part-3.obj")
    (d / "sheet-notes.svg").write_text("x")
    before = _snapshot(d)
    proc = run_cli("make", d / "part-3.obj", "-o", d)
    assert proc.returncode == 2 and "part-3.obj" in one_line(proc.stderr)
    assert _snapshot(d) == before  # nothing written, nothing removed
    # a mesh from elsewhere: make writes beside the user's files and removes none of them
    proc = run_cli("make", models_dir / "cube-12.obj", "-o", d)
    assert proc.returncode == 0, proc.stderr
    after = _snapshot(d)
    assert after["part-3.obj"] == before["part-3.obj"] and after["sheet-notes.svg"] == b"x"
    assert "report.json" in after and "sheets.pdf" in after


def test_segment_into_the_folder_of_its_input_part_is_refused(models_dir: Path, tmp_path: Path) -> None:
    p = tmp_path / "p"
    assert run_cli("segment", models_dir / "horse-302.obj", "-o", p, "--parts", "4").returncode == 0
    before = _snapshot(p)
    proc = run_cli("segment", p / "part-3.obj", "-o", p)
    assert proc.returncode == 2 and "part-3.obj" in one_line(proc.stderr)
    assert _snapshot(p) == before


def test_single_file_outputs_that_cannot_be_written_stop_before_any_work(models_dir: Path, tmp_path: Path) -> None:
    mesh = tmp_path / "c.obj"
    shutil.copy(models_dir / "cube-12.obj", mesh)
    original = mesh.read_bytes()
    cases = [
        (("unfold", mesh, "-o", mesh), "is the input file"),
        (("inflate", mesh, "-o", mesh), "is the input file"),
        (("unfold", mesh, "-o", tmp_path / "a.fold", "--svg", tmp_path / "nodir" / "a.svg"), "does not exist"),
        (("inflate", mesh, "-o", tmp_path / "i.obj", "--log", tmp_path / "nodir" / "log.csv"), "does not exist"),
        (("unfold", mesh, "-o", tmp_path), "is a folder"),
    ]
    for args, words in cases:
        proc = run_cli(*args)
        assert proc.returncode == 2 and words in one_line(proc.stderr), (args, proc.stderr)
        assert mesh.read_bytes() == original
        assert sorted(p.name for p in tmp_path.iterdir()) == ["c.obj"]  # no first output left behind
