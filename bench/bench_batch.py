"""`polyfold batch` throughput (not a test): meshes per minute with 1 and with 2 worker processes.

    .venv/bin/python bench/bench_batch.py [--workers 1,2] [--no-fold] [--size 100] [--time-limit 60]
                                          [--scheduler tcp://host:8786] [--pattern 'DIR/*.obj']

Runs `run_batch` (the API behind `polyfold batch`, with --force so nothing is skipped) over every
closed benchmark mesh (../shared/models/*.obj or $POLYFOLD_MODELS) into a temporary folder, once
per worker count. Wall-clock seconds include starting one process per mesh; the forkserver that
forks them is started (and polyfold preloaded into it) by a one-mesh warm-up batch first, and the
numba kernels come from their on-disk cache. Meshes that fail (e.g. a face too large for the
page) count as processed: the rate is meshes handled per minute.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from polyfold.apps.batch import run_batch
from polyfold.pipeline.options import MakeOptions

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    ap.add_argument("--no-fold", action="store_true", help="skip folding-path planning (make --no-fold)")
    ap.add_argument("--size", type=float, default=150.0)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--scheduler", default=None, help="Dask scheduler address (workers then ignored)")
    ap.add_argument("--pattern", default=str(MODELS / "*.obj"))
    args = ap.parse_args()
    opts = MakeOptions(size=args.size, time_limit=args.time_limit, fold=not args.no_fold)
    print(f"make options: size {opts.size:g} mm, fold {opts.fold}, time limit {opts.time_limit:g} s; "
          f"meshes: {args.pattern}; CPUs: {os.cpu_count()}")
    with tempfile.TemporaryDirectory() as tmp:
        run_batch(str(MODELS / "octahedron-8.obj"), Path(tmp) / "warm", opts, workers=1)
        print(f"{'workers':>7} {'meshes':>6} {'ok':>4} {'failed':>6} {'seconds':>8} {'meshes/min':>10} {'speedup':>7}")
        base = None
        for n in [int(w) for w in args.workers.split(",")]:
            t0 = time.perf_counter()
            res = run_batch(args.pattern, Path(tmp) / f"w{n}", opts, workers=n, scheduler=args.scheduler, force=True)
            dt = time.perf_counter() - t0
            rate = len(res.rows) / (dt / 60)
            base = base or rate
            print(f"{n:>7} {len(res.rows):>6} {res.counts()['ok']:>4} {len(res.failed):>6} {dt:>8.1f} {rate:>10.1f} "
                  f"{rate / base:>7.2f}", flush=True)
            for r in res.failed:
                print(f"        {r.out}: {r.status}: {r.error[:100]}")


if __name__ == "__main__":
    main()
