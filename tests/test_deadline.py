"""deadline.py: Deadline, the one "time is up" type."""

from __future__ import annotations

import math
import time

from polyfold.deadline import CompileTally, Deadline, clock, compiled_seconds


def test_left_expired_and_shares():
    d = Deadline.after(0.2)
    assert 0.0 < d.left() <= 0.2 and not d.expired()
    assert d.within(0.05).at <= d.at and d.within(10).at == d.at
    assert abs(d.share(4).left() - d.left() / 4) < 0.01
    past = Deadline(clock() - 1.0)
    assert past.expired() and past.left() == 0.0 and past.share(3).expired()
    never = Deadline.never()
    assert never.at == math.inf and not never.expired() and never.within(1.0).at < math.inf


def test_or_when_is_up_once_its_test_says_so_and_shares_keep_the_test():
    stopped = []
    d = Deadline.after(100).or_when(lambda: bool(stopped))
    assert not d.expired() and d.left() > 90 and not d.within(5).expired() and not d.share(2).expired()
    stopped.append(True)
    for made in (d, d.within(5), d.share(2), d.before(1)):
        assert made.expired() and made.left() == 0.0
    assert Deadline(clock() - 1).or_when(lambda: False).expired()  # the clock still counts
    outer = []
    both = Deadline.after(100).or_when(lambda: bool(outer)).or_when(lambda: False)
    assert not both.expired()
    outer.append(True)
    assert both.expired()  # the first test is kept


def test_check_raises_out_of_time_only_when_expired():
    import pytest

    from polyfold.errors import OutOfTime

    Deadline.never().check("anything")
    Deadline.after(10).check("anything")
    with pytest.raises(OutOfTime, match="while drawing") as err:
        Deadline(clock() - 1e-3).check("drawing")
    assert err.value.doing == "drawing" and err.value.exit_code == 1
    d = Deadline.after(5.0)
    assert abs((d.at - d.before(2.0).at) - 2.0) < 1e-9


def test_clock_stops_while_numba_compiles():
    """A time limit is the work's: the minute a first run spends compiling kernels must not run a
    search out of its budget (a fresh install's first `make` of the bunny did, at 60 s)."""
    import numpy as np
    from numba import njit

    d = Deadline.after(60.0)
    tally = CompileTally()
    tally.enter("before")
    left0, compiled0, wall0 = d.left(), compiled_seconds(), time.perf_counter()
    tally.enter("compiling")

    @njit  # defined here: always compiled, never from a cache
    def sum_sines(x):
        s = 0.0
        for i in range(x.shape[0]):
            s += np.sin(x[i]) * np.cos(x[i])
        return s

    assert abs(sum_sines(np.ones(3)) - 3 * math.sin(1.0) * math.cos(1.0)) < 1e-12
    wall = time.perf_counter() - wall0
    compiled = compiled_seconds() - compiled0
    # the call was mostly compiling (20-200 ms, by the machine), ten times the tolerance below...
    assert 0.5 * wall < compiled <= wall and compiled > 0.01
    assert left0 - d.left() <= wall - compiled + 1e-3  # ...and the deadline did not count it
    assert clock() <= time.perf_counter() - compiled
    by_stage = tally.by_stage()
    assert "before" not in by_stage and abs(by_stage["compiling"] - compiled) < 1e-3
    sum_sines(np.ones(4))  # compiled already: no more compile seconds
    assert tally.by_stage() == by_stage
