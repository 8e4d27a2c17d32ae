"""The one way to say "time is up": a `Deadline` (a point on the `time.perf_counter` clock).

Every search that runs against a time budget (unfold, segment, fold's planners, make, batch)
takes a Deadline, checks `expired()` between steps, and reports when it ran out rather than
hanging; a part of the work gets a share of what is left (`within`, `share`, `before`). Work that
must be done whatever the time (make's drawing and fitting) calls `check`, which raises OutOfTime
past a hard deadline. The pattern of
OMPL's PlannerTerminationCondition: callers decide when to stop, the work only asks.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from .errors import OutOfTime


@dataclass(frozen=True)
class Deadline:
    """at: the `time.perf_counter()` value at which time is up (math.inf: never)."""

    at: float

    @classmethod
    def after(cls, seconds: float) -> Deadline:
        """The deadline `seconds` from now (math.inf: never)."""
        return cls(time.perf_counter() + seconds)

    @classmethod
    def never(cls) -> Deadline:
        return cls(math.inf)

    def left(self) -> float:
        """Seconds left, never negative."""
        return max(0.0, self.at - time.perf_counter())

    def expired(self) -> bool:
        return time.perf_counter() >= self.at

    def check(self, doing: str) -> None:
        """Raise OutOfTime("... while <doing>") when time is up: the check between steps of work
        that has no cheaper fallback (drawing the pieces, fitting them to the page), so a run on a
        mesh far too large for its time limit stops instead of running on."""
        if self.expired():
            raise OutOfTime(f"time limit reached while {doing}", doing)

    def before(self, seconds: float) -> Deadline:
        """The deadline `seconds` earlier than this one (a share kept back for the work after)."""
        return Deadline(self.at - seconds)

    def within(self, seconds: float) -> Deadline:
        """The earlier of this deadline and `seconds` from now."""
        return Deadline(min(self.at, time.perf_counter() + seconds))

    def share(self, parts: int) -> Deadline:
        """A deadline for one of `parts` equal shares of the time left (the first of them)."""
        return self.within(self.left() / max(1, parts))
