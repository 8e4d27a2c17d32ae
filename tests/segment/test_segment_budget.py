"""segment()'s time budget: the parts=K search stops when its Deadline passes, returns the closest
count found so far and says so; without a deadline (or with one never reached) nothing changes."""

from __future__ import annotations

import numpy as np

from polyfold.deadline import Deadline
from polyfold.formats.meshes import load_mesh
from polyfold.segment.segment import DEFAULT_TAU, segment


def _same(a, b) -> bool:
    return (np.array_equal(a.labels, b.labels) and a.tau == b.tau and np.array_equal(a.concavity, b.concavity)
            and a.timed_out == b.timed_out)


def test_a_spent_budget_stops_the_parts_search_after_one_run(models_dir, monkeypatch):
    import polyfold.segment.segment as S

    mesh = load_mesh(models_dir / "horse-302.obj").mesh
    calls = []
    merge_run = S.merge_run

    def counting_run(*args):
        calls.append(args[0])
        return merge_run(*args)

    monkeypatch.setattr(S, "merge_run", counting_run)
    full = segment(mesh, parts=6)
    assert full.n_parts == 6 and not full.timed_out
    runs_in_full = len(calls)
    assert runs_in_full > 2  # the default tau does not give 6 parts: a bisection

    calls.clear()
    cut = segment(mesh, parts=6, deadline=Deadline.after(0.0))
    assert len(calls) == 1  # the run at the default tau, then the search stops
    assert cut.timed_out
    assert cut.tau == DEFAULT_TAU and cut.n_parts != 6
    plain = segment(mesh, tau=DEFAULT_TAU)  # what that one run gives
    assert np.array_equal(cut.labels, plain.labels) and np.array_equal(cut.concavity, plain.concavity)
    assert (cut.concavity <= cut.tau).all()


def test_a_budget_not_reached_changes_nothing(models_dir):
    for name, k in (("bunny-128", 3), ("horse-302", 6), ("periscope2-44", 9)):
        mesh = load_mesh(models_dir / f"{name}.obj").mesh
        want = segment(mesh, parts=k)
        assert not want.timed_out
        assert _same(want, segment(mesh, parts=k, deadline=Deadline.after(600.0)))
        assert _same(want, segment(mesh, parts=k, deadline=Deadline.never()))
    # a single tau is one run: a spent deadline does not cut it
    mesh = load_mesh(models_dir / "bunny-128.obj").mesh
    assert _same(segment(mesh), segment(mesh, deadline=Deadline.after(0.0)))


def test_the_closest_count_so_far_is_returned(models_dir, monkeypatch):
    """A deadline that passes mid-bisection: the answer is the run whose count was closest to K."""
    import polyfold.segment.segment as S

    mesh = load_mesh(models_dir / "horse-302.obj").mesh
    seen = []
    merge_run = S.merge_run

    def recording_run(*args):
        label, n, memo = merge_run(*args)
        seen.append(n)
        return label, n, memo

    class FourRuns:  # expires after the fourth merging run
        def expired(self) -> bool:
            return len(seen) >= 4

    monkeypatch.setattr(S, "merge_run", recording_run)
    cut = segment(mesh, parts=6, deadline=FourRuns())
    assert cut.timed_out and len(seen) == 4
    assert abs(cut.n_parts - 6) == min(abs(n - 6) for n in seen)
    assert (cut.concavity <= cut.tau).all()
