"""pipeline/parts.py (make's segment + unfold stage): how long a component's single net is
searched for before it is segmented; a part with no single net says why."""

from __future__ import annotations

from conftest import single_component, torus_inside

import polyfold.pipeline.parts as parts_module
from polyfold.deadline import Deadline
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.parts import SINGLE_NET_S, SINGLE_NET_S_PER_FACE, make_parts


def test_a_single_net_is_searched_for_as_long_as_its_faces_warrant(models_dir, monkeypatch):
    """torus-12x6-144 has no single net the search finds (none in 20 s, seeds 1-3): make searched
    30 s for one before segmenting it; now SINGLE_NET_S + SINGLE_NET_S_PER_FACE x 144 faces, and the
    two parts it is segmented into get theirs from the same rule."""
    given: list[tuple[int, float]] = []
    unfold = parts_module.unfold

    def recorded(mesh, **kwargs):
        given.append((mesh.n_faces, kwargs["time_limit"]))
        return unfold(mesh, **kwargs)

    monkeypatch.setattr(parts_module, "unfold", recorded)
    mesh = single_component(models_dir, "torus-12x6-144")
    parts, seg, report = make_parts(mesh, MakeOptions(), Deadline.after(30.0), lambda stage, message: None)
    assert given[0] == (144, SINGLE_NET_S + SINGLE_NET_S_PER_FACE * 144)
    assert all(limit <= SINGLE_NET_S + SINGLE_NET_S_PER_FACE * n for n, limit in given)
    assert len(parts) >= 2 and seg.segmented_components == (0,)
    assert sum(len(p.faces) for p in parts) == 144 and all(p.net.n_pieces == 1 for p in parts)


def test_a_part_with_no_single_net_says_why():
    # a patch of a torus's inside has no single net (tests/unfold/test_problem.py): make's report
    # says why beside its pieces, and make says it once for all such parts
    said: list[tuple[str, str]] = []
    parts, seg, report = make_parts(torus_inside(2), MakeOptions(), Deadline.after(30.0),
                                    lambda stage, message: said.append((stage, message)))
    assert sum(p.net.n_pieces for p in parts) == sum(n.pieces for n in report.nets) == 2
    assert all("interior vertices are all hyperbolic" in n.no_single_net for n in report.nets)
    assert [m for s, m in said if "the fewest found" in m] == [
        f"{len(report.nets)} part(s) cut into 2 pieces, the fewest found: {report.nets[0].no_single_net}"]
