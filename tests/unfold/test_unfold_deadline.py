"""unfold()'s optional Deadline: used instead of time_limit when given, same nets for the same seed
while it is not reached, and a spent one stops the search at once (with a net all the same)."""

from __future__ import annotations

import time

import numpy as np

from polyfold.deadline import Deadline
from polyfold.formats.meshes import load_mesh
from polyfold.unfold.search import unfold


def _same_net(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("parent", "parent_edge", "order", "coords", "piece"))


def test_a_deadline_not_reached_gives_the_time_limits_nets(models_dir):
    mesh = load_mesh(models_dir / "bunny-128.obj").components[0]
    for method in ("auto", "ga", "steepest-edge"):
        for seed in (0, 3):
            net, st = unfold(mesh, method=method, seed=seed, time_limit=600, max_generations=50)
            net_d, st_d = unfold(mesh, method=method, seed=seed, deadline=Deadline.after(600), max_generations=50)
            assert _same_net(net, net_d)
            assert (st.generations, st.evaluations, st.method, st.pieces) == (st_d.generations, st_d.evaluations,
                                                                              st_d.method, st_d.pieces)


def test_a_spent_deadline_stops_the_search(models_dir):
    mesh = load_mesh(models_dir / "bumpy-528.obj").components[0]
    unfold(mesh, seed=0, time_limit=0.0)  # compile / load the kernels first
    t0 = time.perf_counter()
    net, st = unfold(mesh, method="ga", seed=0, time_limit=600, deadline=Deadline.after(0.0))
    assert st.generations == 0  # the deadline wins over time_limit
    assert time.perf_counter() - t0 < 30
    assert net.n_pieces == st.pieces >= 1
