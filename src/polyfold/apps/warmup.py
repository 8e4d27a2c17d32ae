"""`polyfold warm-up`: compile polyfold's numba kernels now, into numba's cache, so that the first
real command does not wait for them.

numba compiles a kernel the first time a process calls it and keeps the machine code in its cache
(`__pycache__` beside the sources, or $NUMBA_CACHE_DIR); later processes load it in milliseconds.
Without this step a fresh install spends its first `polyfold make` compiling: about 45 s of a
bunny's 47 s on a 2-core machine. `make setup` runs it once (README "Set-up").

In: nothing (generated bumpy spheres of 80 and 320 faces, seeded, so no file is needed). Out:
seconds per stage. Every stage of `make` runs once (load, check, segment, unfold, fold, sheets,
guide), then the unfolder's local search (on a sphere whose heuristic nets overlap), every folding
planner at zero and at the default thickness, segmentation into parts (`make --parts`, `segment`)
and both inflation modes (`make --inflate`).
"""

from __future__ import annotations

import tempfile
import time
from typing import Callable

import numpy as np


def kernels_cached() -> bool | None:
    """Whether numba's cache holds the planners' main kernel (a first run compiles when not):
    True or False, or None when this numba keeps its cache where this cannot look."""
    import os

    try:
        from ..fold.checker import segment_free

        return os.path.exists(segment_free._cache._cache_file._index_path)
    except Exception:  # numba's cache layout is its own: no hint rather than a wrong one
        return None


def bumpy_sphere(subdivisions: int = 1, sigma: float = 0.12, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)): an icosphere (80 faces at 1 subdivision, 320 at 2) with
    every vertex moved along its radius by a factor 1 + N(0, sigma) (within 0.6-1.4): dents
    (hyperbolic vertices) and a few nearly convex parts."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = np.asarray(sphere.vertices, dtype=float)
    r = np.clip(1.0 + np.random.default_rng(seed).normal(0.0, sigma, len(v)), 0.6, 1.4)
    return v * r[:, None], np.asarray(sphere.faces, dtype=np.int64)


def _warm_make(mesh) -> None:
    from ..pipeline.make import make
    from ..pipeline.options import MakeOptions

    with tempfile.TemporaryDirectory() as tmp:
        make(mesh, tmp, MakeOptions(), name="warm-up")


def _warm_fold(mesh) -> None:
    from ..collide.tolerance import THICKNESS_REL
    from ..fold.plan import PLANNERS, plan_fold
    from ..fold.tree import FoldTree
    from ..mesh.mesh import Mesh
    from ..unfold.search import unfold

    # a bumpier sphere, whose heuristic nets overlap: the memetic search's local search runs
    bumpy = Mesh(*bumpy_sphere(subdivisions=2, sigma=0.15, seed=1))
    for seed in range(1, 6):
        _, stats = unfold(bumpy, seed=seed, time_limit=10.0)
        if "local-search" in stats.method:
            break
    net, _ = unfold(mesh, seed=1, time_limit=10.0)
    tree = FoldTree.from_net(net)
    for thickness in (0.0, THICKNESS_REL):
        t = tree.with_thickness(thickness * tree.scale)
        for planner in PLANNERS:
            plan_fold(t, planner=planner, time_limit=0.5, seed=1)


def _warm_segment(mesh) -> None:
    from ..segment.segment import segment

    segment(mesh, parts=3)


def _warm_inflate(mesh) -> None:
    from ..collide.self_intersect import crossing_pairs
    from ..inflate.inflate import inflate

    for mode in ("uniform", "constrained"):
        inflate(mesh, mode=mode, max_steps=5)
    # the self-intersection guard with pairs to skip (a mesh that crosses itself at the start)
    crossing_pairs(mesh.vertices, mesh.faces, 1e-9, 1, np.array([1], dtype=np.int64))


# name: (what it compiles, how); in this order in one process
SECTIONS: dict[str, tuple[str, Callable]] = {
    "make": ("make (every stage of the main job)", _warm_make),
    "fold": ("the unfolder's local search and the folding planners", _warm_fold),
    "segment": ("segmentation", _warm_segment),
    "inflate": ("inflation", _warm_inflate),
}
# run beside the others in a second process when there are two cores: segmentation's and
# inflation's kernels share little with make's, so the two halves take about as long (a fresh
# machine: 61 + 10 s against 32 + 7 s; 110 s in one process)
BESIDE = ("segment", "inflate")


def run_sections(names: list[str], progress: Callable[[str], None] | None = None) -> dict[str, float]:
    """Run the named SECTIONS in this process, in order; seconds of each."""
    from ..mesh.mesh import Mesh

    say = progress or (lambda line: None)
    mesh = Mesh(*bumpy_sphere())
    seconds: dict[str, float] = {}
    for name in names:
        what, run = SECTIONS[name]
        say(f"warm-up: {what}")
        t0 = time.perf_counter()
        run(mesh)
        seconds[name] = time.perf_counter() - t0
    return seconds


def warm_up(progress: Callable[[str], None] | None = None, processes: int | None = None) -> dict[str, float]:
    """Call every compiled kernel a command can reach once; seconds per section. processes: 1 runs
    every section here; 2 (the default with two or more cores) runs BESIDE in a second Python
    process at the same time (numba compiles in one thread; its cache is written file by file, a
    temporary file renamed, so two processes may fill it together)."""
    import json
    import os
    import subprocess
    import sys

    processes = processes or (2 if (os.cpu_count() or 1) >= 2 else 1)
    beside = None
    if processes >= 2:
        beside = subprocess.Popen([sys.executable, "-m", "polyfold.apps.warmup", *BESIDE], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        if progress:
            progress(f"warm-up: {' and '.join(SECTIONS[n][0] for n in BESIDE)}, in a second process")
    here = [n for n in SECTIONS if beside is None or n not in BESIDE]
    seconds = run_sections(here, progress)
    if beside is not None:
        out, err = beside.communicate()
        if beside.returncode == 0:
            seconds.update(json.loads(out.splitlines()[-1]))
        else:  # whatever went wrong there, compile them here
            seconds.update(run_sections(list(BESIDE), progress))
    return seconds


if __name__ == "__main__":  # the second process of warm_up: sections named on the command line
    import json
    import sys

    print(json.dumps(run_sections(sys.argv[1:])))
