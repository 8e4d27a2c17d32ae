"""StagedFolder: all files or none, stale outputs of an earlier run removed."""

from __future__ import annotations

import pytest

from polyfold.formats.files import StagedFolder


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
