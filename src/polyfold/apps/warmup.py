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


def warm_up(progress: Callable[[str], None] | None = None) -> dict[str, float]:
    """Call every compiled kernel a command can reach once; seconds per stage."""
    from ..collide.self_intersect import crossing_pairs
    from ..collide.tolerance import THICKNESS_REL
    from ..fold.plan import PLANNERS, plan_fold
    from ..fold.tree import FoldTree
    from ..inflate.inflate import inflate
    from ..mesh.mesh import Mesh
    from ..pipeline.make import make
    from ..pipeline.options import MakeOptions
    from ..segment.segment import segment
    from ..unfold.search import unfold

    say = progress or (lambda line: None)
    seconds: dict[str, float] = {}
    v, f = bumpy_sphere()
    mesh = Mesh(v, f)

    t0 = time.perf_counter()
    say("warm-up: make (every stage of the main job)")
    with tempfile.TemporaryDirectory() as tmp:
        make(mesh, tmp, MakeOptions(), name="warm-up")
    seconds["make"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say("warm-up: the unfolder's local search and the folding planners")
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
    seconds["fold"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say("warm-up: segmentation")
    segment(mesh, parts=3)
    seconds["segment"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say("warm-up: inflation")
    for mode in ("uniform", "constrained"):
        inflate(mesh, mode=mode, max_steps=5)
    # the self-intersection guard with pairs to skip (a mesh that crosses itself at the start)
    crossing_pairs(mesh.vertices, mesh.faces, 1e-9, 1, np.array([1], dtype=np.int64))
    seconds["inflate"] = time.perf_counter() - t0
    return seconds
