"""pipeline/folding.py (make's fold stage): a piece whose faces clash at the goal within the
paper's thickness is split at once (`fold.plan.plan_fold` says no path can exist), not searched
for a path no planner finds."""

from __future__ import annotations

import math

from conftest import single_component

import polyfold.pipeline.folding as folding
from polyfold.deadline import Deadline
from polyfold.fabricate.fit import model_scale
from polyfold.fold.checker import ValidityChecker
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.parts import make_parts


def test_a_goal_clashing_within_the_thickness_is_split_without_planning(models_dir, monkeypatch):
    """hull-ellipsoid-rand-236 has two vertices 0.25 mm apart (at 150 mm) that the mesh does not
    join: at 0.2 mm paper, faces there clash just before the goal. Every planner failed on such
    pieces (12.6 s), which were then halved until the two faces fell apart; now they are halved
    at once, and every piece that is searched has a goal clear at the thickness."""
    planned = []
    plan = folding.plan_fold

    def recorded(tree, **kwargs):
        path = plan(tree, **kwargs)  # (a piece whose goal clashes raises here, before any search)
        planned.append(tree)
        return path

    monkeypatch.setattr(folding, "plan_fold", recorded)
    mesh = single_component(models_dir, "hull-ellipsoid-rand-236")
    opts = MakeOptions()
    parts, _, _ = make_parts(mesh, opts, Deadline.after(30.0), lambda stage, message: None)
    said = []
    results, report = folding.fold_pieces(parts, opts, Deadline.after(30.0), lambda stage, m: said.append(m),
                                          model_scale([mesh], opts.size))
    assert report.splits_for_folding >= 1 and any("clash at the goal" in m for m in said)
    assert report.verified == report.pieces == len(results)
    for tree in planned:
        assert ValidityChecker(tree, math.radians(opts.resolution_deg)).valid(tree.goal)
    # and the test that decides it (plan_fold's check of the goal) sees the clash on the whole piece
    import pytest

    from polyfold.errors import PolyfoldError
    from polyfold.fold.plan import plan_fold

    whole = folding.FoldTree.from_pattern(folding.crease_pattern([parts[0].net]), opts.contact_tol).with_thickness(
        opts.thickness / model_scale([mesh], opts.size))
    with pytest.raises(PolyfoldError, match=r"clash at the goal: net faces (\d+) and (?!\1)\d+ come closer"):
        plan_fold(whole, resolution_deg=opts.resolution_deg, time_limit=30.0)


def test_pieces_planned_side_by_side_get_the_paths_planned_one_by_one(models_dir, monkeypatch):
    """With two cores (and PARALLEL_FOLD_FACES) the pieces are planned in forked processes
    (`processes.fork_map`, the largest first) and put back in order: the same pieces, paths
    (every frame), reports and counts as planning them one by one in this process."""
    import numpy as np

    import polyfold.processes as processes

    from polyfold.pipeline.options import paper_size
    from polyfold.pipeline.sheets import fit_parts, pack_box

    mesh = single_component(models_dir, "fish-472")
    opts = MakeOptions()
    parts, _, _ = make_parts(mesh, opts, Deadline.after(30.0), lambda stage, message: None)
    scale = model_scale([mesh], opts.size)
    parts, _ = fit_parts(parts, scale, opts, pack_box(*paper_size(opts.paper), opts), "fish-472")  # as make
    runs, asked = {}, []
    real = processes.fork_map

    def recorded(fn, items, workers):
        asked.append(workers)
        return real(fn, items, workers)

    monkeypatch.setattr(processes, "fork_map", recorded)
    for cores in (1, 2):
        monkeypatch.setattr(processes, "usable_cores", lambda cores=cores: cores)
        runs[cores] = folding.fold_pieces(parts, opts, Deadline.after(60.0), lambda stage, m: None, scale)
    assert asked == [1, 2]
    (one, one_report), (two, two_report) = runs[1], runs[2]
    assert len(one) == len(two) > 2 and one_report.verified >= 2
    if one_report.splits_for_folding == 0:  # in the order of the parts' pieces
        expected = [np.flatnonzero(p.net.piece == k) for p in parts for k in range(p.net.n_pieces)]
        assert all(np.array_equal(fp.fids, want) for fp, want in zip(one, expected))
    for a, b in zip(one, two):
        facts = [(x.part, x.info.path, x.info.planner, x.info.frames) for x in (a, b)]
        assert facts[0] == facts[1]
        assert np.array_equal(a.mesh_faces, b.mesh_faces) and np.array_equal(a.net.coords, b.net.coords)
        assert (a.path is None) == (b.path is None) and a.info.note == b.info.note
        if a.path is not None:
            assert a.path.frames.shape == b.path.frames.shape and np.array_equal(a.path.frames, b.path.frames)
    assert (one_report.splits_for_folding, one_report.rejected_paths) == (two_report.splits_for_folding,
                                                                        two_report.rejected_paths)
