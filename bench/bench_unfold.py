"""Unfolding benchmark (not a test): every closed mesh in ../shared/models, seeds 1-10.

Prints model | faces | seed | seconds | pieces | generations, then a per-model summary with the
issue's targets (bunny-128 median <= 0.2 s, bunny-348 <= 2 s, bumpy-528 <= 10 s, 10/10 seeds a
single net; fish-472 and horse-302 a single net in <= 30 s). Times are wall-clock seconds of
`polyfold.unfold.unfold` (search + layout + fallback), numba kernels already compiled.

    .venv/bin/python bench/bench_unfold.py [--seeds 10] [--time-limit 60] [--models a,b,...]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from polyfold.formats.meshes import load_mesh
from polyfold.collide.flat import find_overlaps
from polyfold.unfold.search import unfold

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
TARGETS = {"bunny-128": 0.2, "bunny-348": 2.0, "bumpy-528": 10.0, "fish-472": 30.0, "horse-302": 30.0}
FIRST = ["bunny-128", "bunny-348", "bumpy-528"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--models", default="", help="comma-separated model names (default: all closed meshes)")
    args = ap.parse_args()
    names = [p.stem for p in sorted(MODELS.glob("*.obj"))]
    names = FIRST + [n for n in names if n not in FIRST]
    if args.models:
        names = args.models.split(",")
    # warm up the numba caches so the first model is not charged for loading them
    unfold(load_mesh(MODELS / "tetrahedron-4.obj").components[0], seed=0)
    print(f"{'model':<36} {'faces':>5} {'seed':>4} {'seconds':>8} {'pieces':>6} {'generations':>11}  method")
    summary = []
    for name in names:
        loaded = load_mesh(MODELS / f"{name}.obj")
        (mesh,) = loaded.components
        times, singles = [], 0
        for seed in range(1, args.seeds + 1):
            t0 = time.perf_counter()
            net, st = unfold(mesh, seed=seed, time_limit=args.time_limit)
            dt = time.perf_counter() - t0
            # re-check every piece with the exact test before counting it
            for p in range(net.n_pieces):
                idx = np.flatnonzero(net.piece == p)
                assert len(find_overlaps(net.coords[idx], None, 1e-9 * mesh.bbox_diagonal)) == 0
            times.append(dt)
            singles += st.pieces == 1
            print(f"{name:<36} {mesh.n_faces:>5} {seed:>4} {dt:>8.3f} {st.pieces:>6} {st.generations:>11}  {st.method}", flush=True)
        summary.append((name, mesh.n_faces, float(np.median(times)), max(times), singles))
    print()
    print(f"{'model':<36} {'faces':>5} {'median s':>9} {'max s':>8} {'single nets':>12}  target")
    for name, faces, med, worst, singles in summary:
        target = TARGETS.get(name)
        verdict = ""
        if target is not None:
            met = (med if name in FIRST else worst) <= target and singles == args.seeds
            verdict = f"{'median' if name in FIRST else 'max'} <= {target:g} s, all single: {'MET' if met else 'MISSED'}"
        print(f"{name:<36} {faces:>5} {med:>9.3f} {worst:>8.3f} {singles:>5}/{args.seeds:<6}  {verdict}")


if __name__ == "__main__":
    main()
