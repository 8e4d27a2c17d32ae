"""formats/files.py: atomic_write (a new file moved into place, the old one kept on failure),
StagedFolder (all files or none, stale outputs of an earlier run removed), and the SVG / PDF / DXF
page writers leaving no file, or the old one, when writing fails."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from polyfold.fabricate.page import Page
from polyfold.formats.dxf import write_dxf_page
from polyfold.formats.files import StagedFolder, atomic_write
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


def test_commit_moves_every_file_in_and_removes_stale_ones(tmp_path):
    (tmp_path / "part-7.obj").write_text("old")
    (tmp_path / "notes.txt").write_text("mine")
    with StagedFolder(tmp_path, "test") as stage:
        stage.write("part-0.obj", "v")
        stage.write("data.bin", b"\x00\x01")
        stage.path("late.txt").write_text("x")
        names = stage.commit(stale=["part-*.obj"])
    assert names == ("part-0.obj", "data.bin", "late.txt")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data.bin", "late.txt", "notes.txt", "part-0.obj"]
    assert (tmp_path / "data.bin").read_bytes() == b"\x00\x01"


def test_an_error_before_commit_leaves_the_folder_as_it_was(tmp_path):
    (tmp_path / "part-0.obj").write_text("old")
    with pytest.raises(RuntimeError):
        with StagedFolder(tmp_path, "test") as stage:
            stage.write("part-0.obj", "new")
            raise RuntimeError("boom")
    assert [p.name for p in tmp_path.iterdir()] == ["part-0.obj"]
    assert (tmp_path / "part-0.obj").read_text() == "old"


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
