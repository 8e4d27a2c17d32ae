"""Issue 18's build checks on what make writes, re-read by the tests' own readers
(tests/sheet_reader.py, tests/build_metrics.py; never polyfold's code): every glue edge tabbed (or
joined by a glue strip), every tab fold marked as its seam folds in SVG, DXF and PDF, no label
under 2 mm or overlapping another label or a line, no flat region cut, no outline side of a
micrometre. On shared models chosen
for what makes these hard (a fish of slivers and fans, bunnies and a horse crowded with labels, a
cube and an L-prism of flat polygons), on a generated noisy sphere and on a Loop-subdivided bunny
at 60 mm and fish-472 at 65 mm, too dense for a label per glue edge (labelled by seam run), the
fish with one label that has no readable place until its piece is cut
(`splits_for_labels`); bench/bench_build.py runs
all of them (hull-ellipsoid-rand-236 is left out here: the reader cannot find one edge among its
0.1 mm slivers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from build_metrics import measure_folder
from sheet_reader import read_svg

from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

MODELS = ("fish-472", "bunny-348", "horse-302", "cube-12", "l-prism-div-44")


def _noisy_sphere(path: Path) -> Path:
    """An icosphere of 320 faces, every vertex moved along its radius by 1 + N(0, 0.05) (seeded)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=2)
    r = 1.0 + np.random.default_rng(7).normal(0.0, 0.05, len(sphere.vertices))
    trimesh.Trimesh(sphere.vertices * r[:, None], sphere.faces, process=False).export(path)
    return path


def _loop_bunny(path: Path, models_dir: Path) -> Path:
    """bunny-128 after one pass of Loop subdivision (512 faces, none coplanar)."""
    import trimesh

    mesh = trimesh.load(models_dir / "bunny-128.obj", process=False, maintain_order=True, force="mesh")
    v, f = trimesh.remesh.subdivide_loop(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    trimesh.Trimesh(v, f, process=False).export(path)
    return path


CASES = [(name, 150.0) for name in MODELS] + [("noisy-sphere-320", 150.0), ("bunny-128-loop1", 60.0), ("fish-472", 65.0)]
# too dense for a label beside every glue edge: labelled by seam run
SEAM_RUNS = {("bunny-128-loop1", 60.0), ("fish-472", 65.0)}
# and one label without a place on the first drawing, until its piece is cut (the nets of seed 1).
# horse-302 at 60 mm was this case until the unfolder's search changed (2026-12-04): its nets now
# need no cut for labels, and this reader does not find one of its seam runs (label 45, 8 edges
# ending at a needle's tip), an open question, so it is not a case here.
CUT_FOR_LABELS = {("fish-472", 65.0)}


@pytest.mark.parametrize(("name", "size"), CASES)
def test_sheets_pass_the_build_checks(name: str, size: float, models_dir: Path, tmp_path: Path) -> None:
    if name.startswith("noisy"):
        mesh = _noisy_sphere(tmp_path / f"{name}.obj")
    elif name.endswith("loop1"):
        # edges of 1.4-2 mm at 60 mm: no room for a label per glue edge, one per seam run
        mesh = _loop_bunny(tmp_path / f"{name}.obj", models_dir)
    else:
        mesh = models_dir / f"{name}.obj"
    result = make(mesh, tmp_path / "out", MakeOptions(size=size, time_limit=30, guide=False))
    m = measure_folder(tmp_path / "out", mesh)
    lay = result.report.stages.layout
    runs = lay.seam_runs
    assert (runs > 0) == ((name, size) in SEAM_RUNS)
    assert lay.small_labels == 0
    assert (lay.splits_for_labels > 0) == ((name, size) in CUT_FOR_LABELS)
    expected = {f"{runs} seam runs printed with one label"} if runs else set()
    assert set(m.notes) - {"pypdf not installed: PDF not measured"} == expected  # every copy found
    assert m.untabbed_labels == []
    assert m.tabs + m.glue_strips == m.glue_edges
    assert {f: v for f, v in m.wrong_way_labels.items() if v} == {}
    assert len(m.wrong_way) == 3 or "pypdf" in " ".join(m.notes)
    assert (m.small_labels, m.label_pairs, m.label_lines) == (0, 0, 0)
    assert m.flat_cut_labels == []
    # both copies of every glue edge found from their label (their own, or their seam run's)
    assert len(m.copies) == m.glue_edges and all(len(c) == 2 for c in m.copies.values())
    # no cut a blade cannot make: outline sides of a micrometre (left by joining tabs to faces)
    for sheet in sorted((tmp_path / "out").glob("sheet-*.svg")):
        for ring in read_svg(sheet).outlines:
            assert np.linalg.norm(ring - np.roll(ring, 1, axis=0), axis=1).min() >= 1e-3
