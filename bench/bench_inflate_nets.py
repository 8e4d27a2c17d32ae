"""Inflation vs net finding (not a test): unfold the original and the constrained-inflated mesh.

For each model (default bunny-128, bunny-348, fish-472) the mesh is inflated once in constrained
mode with the default parameters (`polyfold.inflate.inflate`; its stop reason, HV before / after
and IF are printed as they come, including a guard stop), then the original and the inflated mesh
are unfolded with seeds 1..N (`polyfold.unfold.unfold`, --time-limit seconds each). Every piece of
every net is re-checked with the exact overlap test before it is counted.

Prints the inflation results, then model | variant | HV | median s | max s | single nets | median
generations, and per model the speed-up of the medians (original / inflated). Times are wall-clock
seconds of `unfold` (search + layout + fallback), numba kernels already compiled.

    .venv/bin/python bench/bench_inflate_nets.py [--seeds 10] [--time-limit 60] [--models a,b,...]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from polyfold.inflate.inflate import inflate
from polyfold.formats.meshes import load_mesh
from polyfold.collide.flat import find_overlaps
from polyfold.unfold.search import unfold

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
DEFAULT_MODELS = "bunny-128,bunny-348,fish-472"


def run_seeds(mesh, seeds: int, time_limit: float) -> tuple[list[float], int, list[int]]:
    """Unfold `mesh` with seeds 1..seeds; returns (seconds per seed, single nets, generations)."""
    times, singles, gens = [], 0, []
    for seed in range(1, seeds + 1):
        t0 = time.perf_counter()
        net, st = unfold(mesh, seed=seed, time_limit=time_limit)
        times.append(time.perf_counter() - t0)
        # re-check every piece with the exact test before counting it
        for p in range(net.n_pieces):
            idx = np.flatnonzero(net.piece == p)
            assert len(find_overlaps(net.coords[idx], None, 1e-9 * mesh.bbox_diagonal)) == 0
        singles += st.pieces == 1
        gens.append(st.generations)
    return times, singles, gens


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--models", default=DEFAULT_MODELS, help=f"comma-separated model names (default {DEFAULT_MODELS})")
    args = ap.parse_args()
    names = args.models.split(",")

    # warm up the numba caches so the first model is not charged for loading them
    tet = load_mesh(MODELS / "tetrahedron-4.obj").components[0]
    unfold(tet, seed=0)
    inflate(tet, max_steps=5, log_every=1)

    print(f"{'model':<12} {'faces':>5} {'steps':>6} {'seconds':>8} {'HV before':>9} {'HV after':>8} {'IF':>7}  stop reason")
    meshes = {}
    for name in names:
        (mesh,) = load_mesh(MODELS / f"{name}.obj").components
        t0 = time.perf_counter()
        res = inflate(mesh, mode="constrained")
        secs = time.perf_counter() - t0
        meshes[name] = (mesh, res.mesh)
        print(f"{name:<12} {mesh.n_faces:>5} {res.steps:>6} {secs:>8.3f} {res.hyperbolic_start:>9} {res.hyperbolic:>8} "
              f"{res.inflation_rate:>7.4f}  {res.stop_reason}", flush=True)
        for note in res.notes:
            print(f"{'':<12} note: {note}")
    print()

    print(f"{'model':<12} {'variant':<9} {'HV':>4} {'median s':>9} {'max s':>8} {'single nets':>12} {'median gens':>12}")
    summary = []
    for name in names:
        medians = {}
        for variant, mesh in zip(("original", "inflated"), meshes[name]):
            times, singles, gens = run_seeds(mesh, args.seeds, args.time_limit)
            medians[variant] = float(np.median(times))
            hv = int(mesh.hyperbolic.sum())
            print(f"{name:<12} {variant:<9} {hv:>4} {medians[variant]:>9.3f} {max(times):>8.3f} "
                  f"{singles:>5}/{args.seeds:<6} {float(np.median(gens)):>12g}", flush=True)
        summary.append((name, medians["original"], medians["inflated"]))
    print()
    for name, orig, infl in summary:
        print(f"{name:<12} median {orig:.3f} s -> {infl:.3f} s: speed-up x{orig / infl:.2f}")


if __name__ == "__main__":
    main()
