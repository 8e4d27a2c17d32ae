"""`polyfold make` on every closed benchmark mesh (not a test): parts, pieces, pages, tabs, paths.

    .venv/bin/python bench/bench_make.py [--paper a4] [--size 150] [--time-limit 60] [--no-fold]

Wall seconds per model are in one process with the numba kernels already compiled; every sheet
passed make's own checks (make raises otherwise).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from polyfold.errors import PolyfoldError
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paper", default="a4")
    ap.add_argument("--size", type=float, default=150.0)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--no-fold", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        make(MODELS / "tetrahedron-4.obj", Path(tmp) / "warm", MakeOptions(size=50.0))  # compile / load caches
        print(f"{'model':<34} {'faces':>5} {'parts':>5} {'pieces':>6} {'pages':>5} {'util':>5} {'tabs':>9} "
              f"{'no tab':>6} {'paths':>7} {'seconds':>7}")
        for path in sorted(MODELS.glob("*.obj")):
            opts = MakeOptions(paper=args.paper, size=args.size, time_limit=args.time_limit, fold=not args.no_fold)
            t0 = time.perf_counter()
            try:
                rep = make(path, Path(tmp) / path.stem, opts).report
            except PolyfoldError as exc:
                print(f"{path.stem:<34} {str(exc)[:100]}")
                continue
            dt = time.perf_counter() - t0
            lay = rep.stages.layout
            n = len(rep.pieces)
            print(f"{path.stem:<34} {rep.input.faces:>5} {rep.stages.segment.parts:>5} {n:>6} "
                  f"{lay.pages:>5} {lay.utilisation:>5.2f} {lay.tabs:>4}/{lay.glue_edges:<4} "
                  f"{len(lay.untabbed_edges):>6} {rep.checks.paths_verified:>3}/{n:<3} {dt:>7.2f}", flush=True)


if __name__ == "__main__":
    main()
