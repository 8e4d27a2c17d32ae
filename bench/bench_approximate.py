"""`make --approximate hulls` on every closed shared model (issue 24), not a test: does every
convex part become one net with a verified folding path, and what does the builder get?

    .venv/bin/python bench/bench_approximate.py [--tau 0.05] [--size 150] [--out DIR] [--png-dir docs/approximate]

One make per model (defaults: A4, 150 mm, fold on, seed 1; in this process, after one warm-up
make so that no row pays for compiling). Columns: parts; triangles per part of the clipped hulls
before the simplification and of the pieces built (mean / max); nets with one piece of all parts
(before any cut to fit the page); pieces and pages on the sheets; folding paths verified by the
independent check, and how many of them are straight lines (all creases together); the largest
Hausdorff distance (symmetric, % of the bbox diagonal); the volume of the parts over the model's;
the shortest printed edge (mm); make's seconds. --png-dir: for the bunny and the horse, the model
in its parts' colours, its convex approximation in the same colours and the first sheet (pdftoppm).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from polyfold.formats.meshes import load_mesh, read_mesh_as_is
from polyfold.formats.png import write_mesh_png
from polyfold.formats.raster import part_colors
from polyfold.pipeline.approximate import joined
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions
from polyfold.segment.segment import DEFAULT_TAU, segment

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
PICTURED = ("bunny-128", "horse-302")
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


def pictures(name: str, folder: Path, tau: float | None, png_dir: Path) -> None:
    """png_dir/NAME-model.png (the model, coloured by part), NAME-hulls.png (the parts as built, same
    colours, same view) and NAME-sheet-1.png (the first page of sheets.pdf, when pdftoppm is there)."""
    png_dir.mkdir(parents=True, exist_ok=True)
    mesh = load_mesh(MODELS / f"{name}.obj").mesh
    seg = segment(mesh, tau=DEFAULT_TAU if tau is None else tau, seed=0)  # make's segmentation (seeded)
    colors = part_colors(seg.n_parts)
    write_mesh_png(png_dir / f"{name}-model.png", mesh.vertices, mesh.faces, colors[seg.labels], width=600, height=450)
    parts = [read_mesh_as_is(folder / f"part-{k}.obj") for k in range(seg.n_parts)]
    model = joined(parts)
    c = colors[np.repeat(np.arange(len(parts)), [p.n_faces for p in parts])]
    # the same view as the model: the model's own middle axis up (the hulls' extents differ a little)
    up = int(np.argsort(np.ptp(mesh.vertices, axis=0))[1])
    write_mesh_png(png_dir / f"{name}-hulls.png", model.vertices, model.faces, c, width=600, height=450, up_axis=up)
    if shutil.which("pdftoppm"):
        subprocess.run(["pdftoppm", "-png", "-r", "50", "-f", "1", "-l", "1", "-singlefile", str(folder / "sheets.pdf"),
                        str(png_dir / f"{name}-sheet-1")], check=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tau", type=float, default=None, help="concavity bound of the parts (default: segment's)")
    ap.add_argument("--size", type=float, default=150.0)
    ap.add_argument("--out", type=Path, default=None, help="keep the make folders here")
    ap.add_argument("--png-dir", type=Path, default=None, help="pictures of the bunny and the horse here")
    a = ap.parse_args()
    opts = MakeOptions(approximate="hulls", tau=a.tau, size=a.size)
    out = a.out or Path(tempfile.mkdtemp(prefix="bench-approximate-"))
    make(load_mesh(MODELS / "cube-12.obj"), out / "warm-up", opts, name="warm-up")  # compile (or load) first
    print("| model | parts | triangles per part before (mean / max) | after | one-piece nets | pieces | pages | "
          "paths verified | straight | Hausdorff | volume | glued pairs | shortest edge mm | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in CLOSED:
        print(row(name, opts, out), flush=True)
        if a.png_dir is not None and name in PICTURED:
            pictures(name, out / name, a.tau, a.png_dir)


if __name__ == "__main__":
    main()
