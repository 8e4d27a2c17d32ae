"""How fast this machine runs right now: a fixed piece of work that does not depend on polyfold's
code, timed, so that the benchmarks' seconds from different hours can be compared (issue 23:
"as ratios where the machine is noisy"). Not a test.

    .venv/bin/python bench/machine_probe.py [--repeat 5]

The work is a make's mix in small: a CPython loop over a dict, a numpy sort, a GEOS union of
buffered triangles (shapely), 200 MB of fresh memory touched (page faults: a make's rasters and
forked workers fault in pages by the hundred thousand) and 20 forks of this process, one core,
seeded. `probe_seconds` is the fastest of `repeat`
runs; a slower hour (the host's other guests) reads higher. bench_make_many.py and
bench_start.py print it before and after their rows. It read 0.38-0.40 s on 2026-12-07 at
17:45-18:30 UTC, an evening when the code of 2026-12-06 (75af39f) made the 1,500-face meshes of
bench_make_many 1.6-2.7 times as slowly (median 1.9) as that day's README table says.
"""

from __future__ import annotations

import argparse
import os
import time


def _work() -> float:
    """The fixed work; returns a number from it (so that nothing is optimised away)."""
    import numpy as np
    import shapely

    rng = np.random.default_rng(0)
    counts: dict[int, int] = {}
    for i in range(400_000):
        counts[i % 997] = counts.get(i % 997, 0) + i
    a = rng.random(1_000_000)
    s = float(np.sort(a)[::1000].sum())
    tri = rng.random((3_000, 3, 2)) * 100.0 + rng.random((3_000, 1, 2)) * 400.0
    area = float(shapely.area(shapely.union_all(shapely.buffer(shapely.polygons(tri), 0.2, quad_segs=2))))
    fresh = np.ones(25_000_000)  # (200 MB: every page faulted in)
    s += float(fresh[::4096].sum())
    del fresh
    for _ in range(20):
        pid = os.fork()
        if pid == 0:
            os._exit(0)
        os.waitpid(pid, 0)
    return s + area + sum(counts.values())


def kernels_ahead(env: dict | None = None) -> bool:
    """Whether a polyfold process (with `env`) finds its kernels compiled ahead of time for this
    very code (`polyfold.jit.ahead_ready`): any edit of its sources, a revert too, makes them
    stale until `polyfold warm-up` runs, and makes then run numba's slower dispatchers."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", "from polyfold.jit import ahead_ready; print(ahead_ready())"],
                          env=env, capture_output=True, text=True)
    return done.stdout.strip() == "True"


def probe_seconds(repeat: int = 5) -> float:
    """The fastest of `repeat` timings of the fixed work (seconds, wall, this process)."""
    _work()  # (imports and first-touch allocations out of the timings)
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        _work()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    print(f"machine probe: {probe_seconds(ap.parse_args().repeat):.3f} s")


if __name__ == "__main__":
    main()
