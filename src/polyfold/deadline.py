"""The one way to say "time is up": a `Deadline` (a point on `clock()`, the
`time.perf_counter` clock less numba's compiling).

Every search that runs against a time budget (unfold, segment, fold's planners, make, batch)
takes a Deadline, checks `expired()` between steps, and reports when it ran out rather than
hanging; a part of the work gets a share of what is left (`within`, `share`, `before`). Work that
must be done whatever the time (make's drawing and fitting) calls `check`, which raises OutOfTime
past a hard deadline. The pattern of
OMPL's PlannerTerminationCondition: callers decide when to stop, the work only asks.

Deadlines run on `clock()`, a `time.perf_counter` that stops while numba compiles: a time limit
is the work's budget, and a first run after `pip install` spends most of a minute compiling
kernels (once; later runs load them from numba's cache). Counted, that minute ran a bunny's
`make` out of its 60 s on a fresh install; now its work gets the same time as
in every later run. `compiled_seconds()` says how long compiling took (the make report's
"compile_seconds", by stage).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from .errors import OutOfTime

_compiling = {"depth": 0, "since": 0.0, "total": 0.0, "watching": False}


def watch_compiles() -> None:
    """Listen to numba's compile events (once per process; `jit` calls it when it first needs
    numba): nested compiles (a kernel's callees) count once, in the outermost."""
    if _compiling["watching"]:
        return
    from numba.core import event

    class _Tally(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            if _compiling["depth"] == 0:
                _compiling["since"] = time.perf_counter()
            _compiling["depth"] += 1

        def on_end(self, ev: event.Event) -> None:
            _compiling["depth"] -= 1
            if _compiling["depth"] == 0:
                _compiling["total"] += time.perf_counter() - _compiling["since"]

    event.register("numba:compile", _Tally())
    _compiling["watching"] = True


def compiled_seconds() -> float:
    """Seconds this process has spent compiling numba kernels so far (those under way included);
    0 before the first Deadline."""
    if _compiling["depth"]:
        return _compiling["total"] + time.perf_counter() - _compiling["since"]
    return _compiling["total"]


@contextmanager
def compiling_elsewhere() -> Iterator[None]:
    """Count the time inside as compiling: waiting for kernels that another process compiles into
    the cache (a first run's `apps.warmup.Beside`) is not work either."""
    t0 = time.perf_counter()
    try:
        yield
    finally:
        _compiling["total"] += time.perf_counter() - t0


def clock() -> float:
    """`time.perf_counter()` less the seconds spent compiling: the clock every Deadline runs on.
    (Process-wide: while one thread compiles, every thread's deadlines wait.)"""
    if not _compiling["watching"] and "numba" in sys.modules:  # (numba not imported: nothing compiles)
        watch_compiles()
    return time.perf_counter() - compiled_seconds()


class CompileTally:
    """Seconds spent compiling, by stage of a run: call `enter(stage)` as each stage starts;
    `seconds` {stage: s} holds the stages that compiled anything (nothing on a warm cache)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._stage: str | None = None
        self._mark = compiled_seconds()

    def enter(self, stage: str) -> None:
        now = compiled_seconds()
        if self._stage is not None and now > self._mark:
            self.seconds[self._stage] = self.seconds.get(self._stage, 0.0) + now - self._mark
        self._stage, self._mark = stage, now

    def by_stage(self) -> dict[str, float]:
        """`seconds` up to now, the stage under way included."""
        if self._stage is not None:
            self.enter(self._stage)
        return dict(self.seconds)


@dataclass(frozen=True)
class Deadline:
    """at: the `clock()` value at which time is up (math.inf: never); stop: also up once this
    says so (`or_when`), whatever the clock."""

    at: float
    stop: Callable[[], bool] | None = field(default=None, compare=False)

    @classmethod
    def after(cls, seconds: float) -> Deadline:
        """The deadline `seconds` from now (math.inf: never)."""
        return cls(clock() + seconds)

    @classmethod
    def never(cls) -> Deadline:
        return cls(math.inf)

    def left(self) -> float:
        """Seconds left, never negative (none once stopped)."""
        if self.stop is not None and self.stop():
            return 0.0
        return max(0.0, self.at - clock())

    def expired(self) -> bool:
        return clock() >= self.at or (self.stop is not None and self.stop())

    def or_when(self, stop: Callable[[], bool]) -> Deadline:
        """This deadline, also up once stop() is true (a search that another has beaten; the
        deadlines made from it keep the test, and it keeps this one's)."""
        if self.stop is None:
            return Deadline(self.at, stop)
        before = self.stop
        return Deadline(self.at, lambda: before() or stop())

    def check(self, doing: str) -> None:
        """Raise OutOfTime("... while <doing>") when time is up: the check between steps of work
        that has no cheaper fallback (drawing the pieces, fitting them to the page), so a run on a
        mesh far too large for its time limit stops instead of running on."""
        if self.expired():
            raise OutOfTime(f"time limit reached while {doing}", doing)

    def before(self, seconds: float) -> Deadline:
        """The deadline `seconds` earlier than this one (a share kept back for the work after)."""
        return Deadline(self.at - seconds, self.stop)

    def within(self, seconds: float) -> Deadline:
        """The earlier of this deadline and `seconds` from now."""
        return Deadline(min(self.at, clock() + seconds), self.stop)

    def share(self, parts: int) -> Deadline:
        """A deadline for one of `parts` equal shares of the time left (the first of them)."""
        return self.within(self.left() / max(1, parts))
