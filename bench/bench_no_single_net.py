"""Meshes with no single net (not a test): the tree cut into the fewest pieces, against the GA.

    .venv/bin/python bench/bench_no_single_net.py [--seeds 3] [--markdown]

Every mesh here is one that `UnfoldProblem.single_net_blocked` says has no single net: the blocked
parts that segmentation makes of two trimesh tori (24 x 10 and 40 x 14: patches of their inside,
every interior vertex a saddle) and of star-4split-96 (../shared/models or $POLYFOLD_MODELS), that
star whole (flat regions whose hyperbolic vertices force cuts), and grids on the saddle
z = (x^2 - y^2) / (n / 1.5) of n x n squares. Each is searched for BLOCKED_SEARCH_S per seed, as
`unfold` does, by `fewest_pieces` (what "auto" runs there now) and by the memetic GA (what it ran
before: the tree with the fewest overlapping pairs); both trees are then cut by the same exact set
cover. Prints per mesh the pieces per seed and the mean seconds of each, then the totals.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import trimesh

from polyfold.apps.warmup import height_grid
from polyfold.deadline import Deadline
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh
from polyfold.segment.segment import DEFAULT_TAU, segment
from polyfold.unfold.problem import UnfoldProblem
from polyfold.unfold.search import BLOCKED_SEARCH_S, fewest_pieces, pieces_of, run_memetic

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))


def saddle(n: int) -> Mesh:
    """n x n unit squares over z = (x^2 - y^2) / (n / 1.5), each split along one diagonal."""
    return Mesh(*height_grid(n, lambda x, y: (x * x - y * y) / (n / 1.5)))


def blocked_parts(name: str, mesh: Mesh) -> list[tuple[str, Mesh]]:
    """(name, part) of every part of the mesh's segmentation (default tau) with no single net."""
    seg = segment(mesh, tau=DEFAULT_TAU, seed=0)
    parts = [mesh.submesh(f) for f in seg.face_ids]
    return [(f"{name} part {k}", p) for k, p in enumerate(parts) if UnfoldProblem.from_mesh(p).single_net_blocked()]


def meshes() -> list[tuple[str, Mesh]]:
    out: list[tuple[str, Mesh]] = []
    for major, minor, r in ((24, 10, 0.35), (40, 14, 0.3)):
        t = trimesh.creation.torus(1.0, r, major_sections=major, minor_sections=minor)
        out += blocked_parts(f"torus {major} x {minor}", Mesh(np.asarray(t.vertices, dtype=float),
                                                              np.asarray(t.faces, dtype=np.int64)))
    star = MODELS / "star-4split-96.obj"
    if star.exists():
        whole = load_mesh(star).mesh
        out += blocked_parts("star-4split-96", whole) + [("star-4split-96 whole", whole)]
    out += [(f"saddle {n} x {n}", saddle(n)) for n in (4, 6, 10, 14)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args()
    todo = meshes()
    searches = {
        "GA": lambda p, rng: run_memetic(p, rng, Deadline.after(BLOCKED_SEARCH_S), 15000, population=400)[0],
        "fewest": lambda p, rng: fewest_pieces(p, rng, Deadline.after(BLOCKED_SEARCH_S))[0],
    }
    for search in searches.values():  # numba's kernels loaded before the first timing
        search(UnfoldProblem.from_mesh(todo[0][1]), np.random.default_rng(0))
    if a.markdown:
        print("| mesh | faces | GA: pieces | GA: s | fewest pieces: pieces | s |\n|---|---|---|---|---|---|")
    else:
        print(f"{'mesh':28s} {'faces':>5s} {'GA pieces':>12s} {'s':>5s} {'fewest':>12s} {'s':>5s}")
    total = {k: [0, 0.0] for k in searches}
    for name, mesh in todo:
        problem = UnfoldProblem.from_mesh(mesh)
        cells = []
        for key, search in searches.items():
            got, seconds = [], []
            for seed in range(1, a.seeds + 1):
                t = time.perf_counter()
                genome = search(problem, np.random.default_rng(seed))
                seconds.append(time.perf_counter() - t)
                got.append(pieces_of(problem, genome, exact_seconds=min(5.0, 0.05 * BLOCKED_SEARCH_S + 0.5))[0])
            total[key][0] += sum(got)
            total[key][1] += sum(seconds)
            cells.append((" ".join(map(str, got)), float(np.mean(seconds))))
        (g, gs), (f, fs) = cells
        if a.markdown:
            print(f"| {name} | {mesh.n_faces} | {g} | {gs:.2f} | {f} | {fs:.2f} |", flush=True)
        else:
            print(f"{name:28s} {mesh.n_faces:5d} {g:>12s} {gs:5.2f} {f:>12s} {fs:5.2f}", flush=True)
    runs = len(todo) * a.seeds
    print(f"\n{len(todo)} meshes, seeds 1-{a.seeds}: the GA {total['GA'][0]} pieces ({total['GA'][1] / runs:.2f} s a "
          f"search), fewest_pieces {total['fewest'][0]} ({total['fewest'][1] / runs:.2f} s)")


if __name__ == "__main__":
    main()
