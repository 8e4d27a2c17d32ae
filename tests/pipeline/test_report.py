"""pipeline/report.py: report.json and assembly.json as types: exact round trips, clear errors on other layouts."""

from __future__ import annotations

import json

import pytest

from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.report import Assembly, MakeReport


@pytest.fixture(scope="module")
def made(models_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("made")
    result = make(models_dir / "bunny-128.obj", out, MakeOptions(inflate="constrained", parts=2, time_limit=30))
    return out, result


def test_files_round_trip_byte_for_byte(made):
    out, result = made
    text = (out / "report.json").read_text()
    assert MakeReport.from_dict(json.loads(text)).to_json() == text == result.report.to_json()
    asm = (out / "assembly.json").read_text()
    assert Assembly.from_dict(json.loads(asm)).to_json() == asm


def test_report_fields_are_typed(made):
    _, result = made
    rep = result.report
    assert rep.options == MakeOptions(inflate="constrained", parts=2, time_limit=30)
    assert rep.stages.inflate.mode == "constrained" and rep.stages.inflate.steps > 0
    assert rep.stages.segment.parts == len(rep.stages.unfold.nets) == 2
    assert [p.fold_file for p in rep.pieces] == [f"piece-{p.piece}.fold" for p in rep.pieces]
    assert rep.outputs[-1] == "report.json"


def test_inflate_none_writes_only_mode_and_seconds(models_dir, tmp_path):
    result = make(models_dir / "tetrahedron-4.obj", tmp_path, MakeOptions(size=100))
    assert set(json.loads((tmp_path / "report.json").read_text())["stages"]["inflate"]) == {"mode", "seconds"}
    assert result.report.stages.inflate.steps is None


@pytest.mark.parametrize("edit, key", [
    (lambda d: d.pop("stages"), "stages"),
    (lambda d: d["input"].update(faces="many"), "faces"),
    (lambda d: d["pieces"][0].pop("fold_file"), "fold_file"),
    (lambda d: d.update(polyfold_report=99), "version"),
])
def test_other_layouts_are_refused_naming_the_key(made, edit, key):
    out, _ = made
    data = json.loads((out / "report.json").read_text())
    edit(data)
    with pytest.raises(ValueError, match=key):
        MakeReport.from_dict(data)
