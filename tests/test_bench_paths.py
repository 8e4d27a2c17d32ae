"""A sample of bench/bench_paths.py in CI: make on a few shared models at no thickness and at the
default paper thickness, every written path re-checked by tests/path_checker.py and by
polyfold.verify.paths; not one may be invalid, and every piece must have a verified path."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

from bench_paths import run  # noqa: E402

SAMPLE = ("periscope2-44", "star-24", "torus-8x4-64", "stellated-octahedron-kleetope-24")


@pytest.mark.parametrize("thickness", [0.0, 0.2])
def test_every_written_path_is_valid(models_dir, tmp_path, thickness):
    for name in SAMPLE:
        row = run(models_dir / f"{name}.obj", [1], thickness, tmp_path, 60.0)
        assert not row.errors, row.errors
        assert row.written == row.pieces == row.verified > 0, (name, row)
        assert row.invalid_tests == 0 and row.invalid_verify == 0, (name, row.first_invalid)
