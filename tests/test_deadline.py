"""deadline.py: Deadline, the one "time is up" type."""

from __future__ import annotations

import math
import time

from polyfold.deadline import Deadline


def test_left_expired_and_shares():
    d = Deadline.after(0.2)
    assert 0.0 < d.left() <= 0.2 and not d.expired()
    assert d.within(0.05).at <= d.at and d.within(10).at == d.at
    assert abs(d.share(4).left() - d.left() / 4) < 0.01
    past = Deadline(time.perf_counter() - 1.0)
    assert past.expired() and past.left() == 0.0 and past.share(3).expired()
    never = Deadline.never()
    assert never.at == math.inf and not never.expired() and never.within(1.0).at < math.inf


def test_check_raises_out_of_time_only_when_expired():
    import pytest

    from polyfold.errors import OutOfTime

    Deadline.never().check("anything")
    Deadline.after(10).check("anything")
    with pytest.raises(OutOfTime, match="while drawing") as err:
        Deadline(time.perf_counter() - 1e-3).check("drawing")
    assert err.value.doing == "drawing" and err.value.exit_code == 1
    d = Deadline.after(5.0)
    assert abs((d.at - d.before(2.0).at) - 2.0) < 1e-9
