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
