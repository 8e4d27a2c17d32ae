"""formats/files.py: atomic_write (a new file moved into place, the old one kept on failure),
StagedFolder (all files or none; only what polyfold wrote is ever replaced or removed, never the
input; a commit cut short is finished by the next run; two runs take turns), check_outputs /
check_folder, and the SVG / PDF / DXF page writers leaving no file, or the old one, when writing
fails."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import pytest

from polyfold.fabricate.page import Page
from polyfold.formats.dxf import write_dxf_page
from polyfold.errors import PolyfoldError
from polyfold.formats.files import JOURNAL, LOCK, MANIFEST, StagedFolder, atomic_write, check_folder, check_outputs
from polyfold.formats.pdf import write_pdf
from polyfold.formats.svg import write_svg_page


# ----------------------------------------------------------------------------------------------
# atomic_write


def test_atomic_write_replaces_and_leaves_no_temp(tmp_path: Path) -> None:
    target = tmp_path / "out.fold"
    atomic_write(target, "first")
    assert target.read_text() == "first"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask
    inode = target.stat().st_ino
    atomic_write(str(target), b"second \xff")
    assert target.read_bytes() == b"second \xff"
    assert target.stat().st_ino != inode  # a new file was moved into place, not rewritten
    assert os.listdir(tmp_path) == ["out.fold"]


def test_atomic_write_failure_keeps_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "out.svg"
    target.write_text("old")

    def broken_replace(src, dst):
        raise OSError("disk on fire")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk on fire"):
        atomic_write(target, "new")
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["out.svg"]


# ----------------------------------------------------------------------------------------------
# StagedFolder


def _visible(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))


def _run(folder: Path, files: dict[str, str], inputs=()) -> tuple[str, ...]:
    with StagedFolder(folder, "test", inputs=inputs) as stage:
        for name, text in files.items():
            stage.write(name, text)
        return stage.commit()


def test_commit_moves_every_file_in_and_removes_only_what_the_last_run_wrote(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "part-9.obj").write_text("mine too")  # named like an output, but not polyfold's
    assert _run(tmp_path, {"part-0.obj": "a", "part-7.obj": "a"}) == ("part-0.obj", "part-7.obj")
    with StagedFolder(tmp_path, "test") as stage:
        stage.write("part-0.obj", "b")
        stage.write("data.bin", b"\x00\x01")
        stage.path("late.txt").write_text("x")
        names = stage.commit()
    assert names == ("part-0.obj", "data.bin", "late.txt")
    # part-7.obj (the last run's, not this one's) is gone; the user's files stay
    assert _visible(tmp_path) == ["data.bin", "late.txt", "notes.txt", "part-0.obj", "part-9.obj"]
    assert (tmp_path / "data.bin").read_bytes() == b"\x00\x01"
    assert (tmp_path / "part-9.obj").read_text() == "mine too"
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == list(names)


def test_a_file_polyfold_did_not_write_is_never_replaced(tmp_path):
    (tmp_path / "sheet-01.svg").write_text("my drawing")
    with pytest.raises(PolyfoldError, match="sheet-01.svg: exists and was not written by polyfold"):
        _run(tmp_path, {"report.json": "{}", "sheet-01.svg": "<svg/>"})
    assert _visible(tmp_path) == ["sheet-01.svg"] and (tmp_path / "sheet-01.svg").read_text() == "my drawing"


def test_the_input_is_never_replaced_or_removed(tmp_path):
    _run(tmp_path, {"part-0.obj": "a", "part-1.obj": "a"})
    for files in ({"part-0.obj": "b"}, {"part-1.obj": "b", "part-0.obj": "b"}):  # removed, replaced
        with pytest.raises(PolyfoldError, match="input"):
            _run(tmp_path, files, inputs=[tmp_path / "part-1.obj"])
        assert [(tmp_path / n).read_text() for n in ("part-0.obj", "part-1.obj")] == ["a", "a"]


def test_an_error_before_commit_leaves_the_folder_as_it_was(tmp_path):
    (tmp_path / "part-0.obj").write_text("old")
    with pytest.raises(RuntimeError):
        with StagedFolder(tmp_path, "test") as stage:
            stage.write("part-0.obj", "new")
            raise RuntimeError("boom")
    assert _visible(tmp_path) == ["part-0.obj"] and (tmp_path / "part-0.obj").read_text() == "old"
    assert not [p for p in tmp_path.iterdir() if p.is_dir()]  # no temporary folder left


def test_a_run_stopped_before_its_commit_takes_away_the_folders_it_made(tmp_path):
    """An error or Ctrl-C (KeyboardInterrupt) between making a new output folder (and the folders
    above it) and the commit removes them again: they held nothing but the lock. A folder that
    was there stays, and so does one that holds anything else."""
    for exc in (RuntimeError, KeyboardInterrupt):
        with pytest.raises(exc):
            with StagedFolder(tmp_path / "new" / exc.__name__ / "out", "test") as stage:
                stage.write("report.json", "{}")
                raise exc()
        assert list(tmp_path.iterdir()) == []
    (tmp_path / "kept").mkdir()
    with pytest.raises(RuntimeError):
        with StagedFolder(tmp_path / "kept", "test"):
            raise RuntimeError()
    assert (tmp_path / "kept").is_dir() and list((tmp_path / "kept").iterdir()) == [tmp_path / "kept" / LOCK]
    with pytest.raises(RuntimeError):
        with StagedFolder(tmp_path / "other", "test"):
            (tmp_path / "other" / "notes.txt").write_text("mine")  # (not polyfold's: the folder stays)
            raise RuntimeError()
    assert (tmp_path / "other" / "notes.txt").read_text() == "mine"


def test_a_run_waiting_for_one_that_takes_its_folder_away_makes_it_again(tmp_path):
    """A second run into a new folder, waiting for the lock of the run that made it: that run
    stops before its commit and removes the folder; the second finds its lock file gone, makes
    the folder again and commits into it."""
    import threading
    import time

    folder = tmp_path / "out"
    entered, go_on, done = threading.Event(), threading.Event(), []

    def first() -> None:
        with pytest.raises(RuntimeError):
            with StagedFolder(folder, "test"):
                entered.set()
                go_on.wait(10)
                raise RuntimeError("given up")

    runs = [threading.Thread(target=first), threading.Thread(target=lambda: done.append(_run(folder, {"a.txt": "b"})))]
    runs[0].start()
    assert entered.wait(10)
    runs[1].start()
    time.sleep(0.3)  # (the second run waits for the lock)
    go_on.set()
    for run in runs:
        run.join(10)
    assert done == [("a.txt",)] and _visible(folder) == ["a.txt"] and (folder / "a.txt").read_text() == "b"


def test_a_commit_cut_short_is_finished_by_the_next_run(tmp_path, monkeypatch):
    old = {f"piece-{k}.fold": "old" for k in range(4)}
    _run(tmp_path, old)
    real = os.replace
    moves = []

    def dies_on_third_move(src, dst):
        if Path(dst).parent == tmp_path and not Path(dst).name.startswith("."):
            moves.append(dst)
            if len(moves) == 3:
                raise KeyboardInterrupt  # the process dies here
        real(src, dst)

    monkeypatch.setattr(os, "replace", dies_on_third_move)
    new = {f"piece-{k}.fold": "new" for k in range(3)} | {"report.json": "new"}
    with pytest.raises(KeyboardInterrupt):
        # (the context manager's exit removes the staged folder: a kill would not, so keep it)
        stage = StagedFolder(tmp_path, "test").__enter__()
        for name, text in new.items():
            stage.write(name, text)
        stage.commit()
    monkeypatch.setattr(os, "replace", real)
    os.close(stage._lock_fd)  # the kill releases the lock
    assert (tmp_path / JOURNAL).exists()  # a mix on disk, marked as a commit under way
    with StagedFolder(tmp_path, "test") as later:  # any later run finishes it first
        assert later.previous == set(new)
    assert _visible(tmp_path) == sorted(new) and all((tmp_path / n).read_text() == "new" for n in new)
    assert not (tmp_path / JOURNAL).exists() and not [p for p in tmp_path.iterdir() if p.is_dir()]


KILLED = """
import os, sys, time
from polyfold.formats.files import StagedFolder
real = os.replace
def slow(src, dst):
    time.sleep(0.01)
    real(src, dst)
os.replace = slow
with StagedFolder(sys.argv[1], "test") as stage:
    for k in range(40):
        stage.write(f"piece-{k}.fold", sys.argv[2])
    stage.write("report.json", sys.argv[2])
    stage.commit()
"""


def test_a_kill_at_any_instant_leaves_one_whole_set_after_the_next_run(tmp_path):
    import random
    import signal
    import subprocess
    import sys
    import time

    script = tmp_path / "killed.py"
    script.write_text(KILLED)
    rng = random.Random(5)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, str(script), str(tmp_path / "timed"), "old"], check=True)
    whole = time.perf_counter() - t0  # start-up, staging, then 41 moves of 10 ms each
    mixed = 0
    for trial in range(8):
        folder = tmp_path / f"out{trial}"
        subprocess.run([sys.executable, str(script), str(folder), "old"], check=True)
        proc = subprocess.Popen([sys.executable, str(script), str(folder), "new"])
        time.sleep(rng.uniform(0.3, 1.0) * whole)  # mostly somewhere in the moves
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        mixed += len({(folder / n).read_text() for n in _visible(folder)}) > 1
        with StagedFolder(folder, "test"):
            pass  # the next run into the folder
        texts = {(folder / n).read_text() for n in _visible(folder)}
        assert len(texts) == 1 and len(_visible(folder)) == 41  # all old or all new
        assert not [p for p in folder.iterdir() if p.is_dir()]
    assert mixed  # some kills did land between two moves


CONCURRENT = """
import sys, time
from polyfold.formats.files import StagedFolder
with StagedFolder(sys.argv[1], "test") as stage:
    n = int(sys.argv[3])
    for k in range(n):
        stage.write(f"sheet-{k:02d}.svg", sys.argv[2])
        time.sleep(0.01)
    stage.write("report.json", sys.argv[2])
    stage.commit()
"""


def test_two_runs_into_one_folder_take_turns(tmp_path):
    import subprocess
    import sys

    script = tmp_path / "run.py"
    script.write_text(CONCURRENT)
    folder = tmp_path / "out"
    procs = [subprocess.Popen([sys.executable, str(script), str(folder), tag, n]) for tag, n in (("a", "6"), ("b", "3"))]
    assert [p.wait() for p in procs] == [0, 0]
    names = _visible(folder)
    texts = {(folder / n).read_text() for n in names}
    assert len(texts) == 1  # one run's set, not a mix
    assert len(names) == (7 if texts == {"a"} else 4)
    assert json.loads((folder / MANIFEST).read_text())["files"] == sorted(names, key=lambda n: (n == "report.json", n))


def test_check_outputs_refuses_what_cannot_be_written_before_any_work(tmp_path):
    mesh = tmp_path / "c.obj"
    mesh.write_text("v 0 0 0")
    (tmp_path / "dir").mkdir()
    for outs, words in (([mesh], "is the input file"), ([tmp_path / "dir"], "is a folder"),
                        ([tmp_path / "missing" / "a.svg"], "does not exist"),
                        ([tmp_path / "a.fold", tmp_path / "a.fold"], "two outputs")):
        with pytest.raises(PolyfoldError, match=words):
            check_outputs(outs, [mesh])
    check_outputs([tmp_path / "a.fold", None], [mesh])
    with pytest.raises(PolyfoldError, match="named like one of its outputs"):
        check_folder(tmp_path, ("c.*",), [mesh])
    with pytest.raises(PolyfoldError, match="is a file"):
        check_folder(mesh, ("x",), [])


# ----------------------------------------------------------------------------------------------
# the page writers write atomically (the `page` fixture)


WRITERS = {
    "svg": lambda p, path: write_svg_page(p, path),
    "pdf": lambda p, path: write_pdf([p], path),
    "dxf": lambda p, path: write_dxf_page(p, path),
}


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_failed_write_leaves_no_file(page: Page, tmp_path, monkeypatch, fmt: str) -> None:
    def boom(*_args, **_kwargs):
        raise OSError("disk full")

    # Fails after the bytes went into the temp file, before it replaces the target.
    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(OSError, match="disk full"):
        WRITERS[fmt](page, tmp_path / f"out.{fmt}")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_failed_write_keeps_old_file(page: Page, tmp_path, monkeypatch, fmt: str) -> None:
    target = tmp_path / f"out.{fmt}"
    target.write_bytes(b"old")

    def boom(*_args, **_kwargs):
        raise RuntimeError("interrupted")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(RuntimeError):
        WRITERS[fmt](page, target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
