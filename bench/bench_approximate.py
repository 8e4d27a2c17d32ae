"""`make --approximate hulls` on every closed shared model (issue 24), not a test: does every
convex part become one net with a verified folding path, and what does the builder get?

    .venv/bin/python bench/bench_approximate.py [--tau 0.05] [--size 150] [--out DIR]

One make per model (defaults: A4, 150 mm, fold on, seed 1; in this process, after one warm-up
make so that no row pays for compiling). Columns: parts; triangles per part of the clipped hulls
before the simplification and of the pieces built (mean / max); nets with one piece of all parts
(before any cut to fit the page); pieces and pages on the sheets; folding paths verified by the
independent check, and how many of them are straight lines (all creases together); the largest
Hausdorff distance (symmetric, % of the bbox diagonal); the volume of the parts over the model's;
the shortest printed edge (mm); make's seconds.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
CLOSED = ["bunny-128", "bunny-348", "horse-302", "fish-472", "sphere-deformed-320", "bumpy-528", "periscope-28",
          "star-24", "moneybox-128", "cube-12"]


def row(name: str, opts: MakeOptions, out: Path) -> str:
    loaded = load_mesh(MODELS / f"{name}.obj")
    t0 = time.perf_counter()
    rep = make(loaded, out / name, opts, name=name).report
    seconds = time.perf_counter() - t0
    a = rep.stages.approximate
    single = sum(n.pieces == 1 for n in rep.stages.unfold.nets)
    verified = sum(p.path_verified for p in rep.pieces)
    linear = sum(bool(p.linear) for p in rep.pieces if p.path_verified)
    before, after = a.faces_before, a.faces_after
    return (f"| {name} | {a.parts} | {sum(before) / len(before):.0f} / {max(before)} | "
            f"{sum(after) / len(after):.0f} / {max(after)} | {single}/{len(rep.stages.unfold.nets)} | "
            f"{len(rep.pieces)} | {rep.stages.layout.pages} | {verified}/{len(rep.pieces)} | {linear} | "
            f"{a.hausdorff_max:.1%} | {a.volume_ratio:.2f} | {len(a.contacts)} | "
            f"{rep.stages.layout.smallest_edge_mm:.1f} | {seconds:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tau", type=float, default=None, help="concavity bound of the parts (default: segment's)")
    ap.add_argument("--size", type=float, default=150.0)
    ap.add_argument("--out", type=Path, default=None, help="keep the make folders here")
    a = ap.parse_args()
    opts = MakeOptions(approximate="hulls", tau=a.tau, size=a.size)
    out = a.out or Path(tempfile.mkdtemp(prefix="bench-approximate-"))
    make(load_mesh(MODELS / "cube-12.obj"), out / "warm-up", opts, name="warm-up")  # compile (or load) first
    print("| model | parts | triangles per part before (mean / max) | after | one-piece nets | pieces | pages | "
          "paths verified | straight | Hausdorff | volume | glued pairs | shortest edge mm | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in CLOSED:
        print(row(name, opts, out), flush=True)


if __name__ == "__main__":
    main()
