"""Folding paths you can trust (issue 19): every path `polyfold make` writes, re-checked (not a test).

    .venv/bin/python bench/bench_paths.py [--quick] [--seeds 1-5] [--thickness 0,0.2]
                                          [--no-generated] [--only NAME ...] [--markdown]

Runs `polyfold.make` (API, defaults: A4, 150 mm, fold on) on every closed shared model
(../shared/models/*.obj or $POLYFOLD_MODELS) for each seed and each paper thickness (mm), and on
generated meshes of 500-2000 faces (random convex hulls, noisy icospheres, Loop-subdivided shared
models; seeded, built here with trimesh) for the first seed. Every piece's FOLD file that holds a
path is re-checked twice, as written: by tests/path_checker.py (the tests' standalone checker,
numpy + shapely, no polyfold import; zero thickness: crossing, and coplanar overlap within its
tolerance) and by polyfold.verify.paths at the thickness the file states. Prints per model (over
its seeds): pieces, paths written, paths make reported verified, invalid paths by each checker,
paths the check rejected inside make (re-planned by splitting), splits for folding, pieces
without a path, fold seconds, make seconds. Target: 0 invalid paths at every thickness.
`--quick`: six shared models, seed 1, no generated meshes (what CI runs, tests/bench/).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the standalone path checker lives with the tests
sys.path.insert(0, str(ROOT / "bench"))

import bench_build  # noqa: E402
from bench_build import loop_subdivided, noisy_icosphere  # noqa: E402
from path_checker import check_path  # noqa: E402

MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
QUICK = ("bunny-128", "horse-302", "periscope2-44", "star-24", "torus-8x4-64", "stellated-octahedron-kleetope-24")


def convex_hull(n_points: int, axes: tuple[float, float, float], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of n points on an ellipsoid (about 2 n faces)."""
    import trimesh

    p = np.random.default_rng(seed).normal(size=(n_points, 3))
    p = p / np.linalg.norm(p, axis=1)[:, None] * np.asarray(axes)
    hull = trimesh.convex.convex_hull(p)
    return np.asarray(hull.vertices, dtype=float), np.asarray(hull.faces)


GENERATED = (  # name, builder (seeded): 20 meshes of 500-2000 faces
    ("hull-ellipsoid-300", lambda: convex_hull(300, (1.0, 0.7, 0.5), 11)),
    ("hull-ellipsoid-500", lambda: convex_hull(500, (1.0, 0.9, 0.5), 12)),
    ("hull-ellipsoid-700", lambda: convex_hull(700, (1.0, 1.1, 0.5), 13)),
    ("hull-ball-900", lambda: convex_hull(900, (1.0, 1.0, 1.0), 14)),
    ("hull-disc-400", lambda: convex_hull(400, (1.0, 1.0, 0.2), 15)),
    ("noisy-ico3-s02", lambda: noisy_icosphere(3, 0.02, 21)),
    ("noisy-ico3-s05", lambda: noisy_icosphere(3, 0.05, 22)),
    ("noisy-ico3-s08", lambda: noisy_icosphere(3, 0.08, 23)),
    ("noisy-ico3-s12", lambda: noisy_icosphere(3, 0.12, 24)),
    ("bunny-128-loop1", lambda: loop_subdivided(MODELS / "bunny-128.obj", 1)),
    ("bunny-348-loop1", lambda: loop_subdivided(MODELS / "bunny-348.obj", 1)),
    ("horse-302-loop1", lambda: loop_subdivided(MODELS / "horse-302.obj", 1)),
    ("fish-472-loop1", lambda: loop_subdivided(MODELS / "fish-472.obj", 1)),
    ("moneybox-128-loop2", lambda: loop_subdivided(MODELS / "moneybox-128.obj", 2)),
    ("torus-12x6-144-loop2", lambda: loop_subdivided(MODELS / "torus-12x6-144.obj", 2)),
    ("sphere-deformed-320-loop1", lambda: loop_subdivided(MODELS / "sphere-deformed-320.obj", 1)),
    ("icosphere-l2-320-loop1", lambda: loop_subdivided(MODELS / "icosphere-l2-320.obj", 1)),
    ("star-4split-96-loop2", lambda: loop_subdivided(MODELS / "star-4split-96.obj", 2)),
    ("spiky-icosahedron-60-loop2", lambda: loop_subdivided(MODELS / "spiky-icosahedron-60.obj", 2)),
    ("torus-twisted-10x3-60-loop2", lambda: loop_subdivided(MODELS / "torus-twisted-10x3-60.obj", 2)),
)


@dataclass
class Row:
    name: str
    thickness: float
    faces: int = 0
    runs: int = 0
    pieces: int = 0
    written: int = 0
    verified: int = 0
    invalid_tests: int = 0  # rejected by tests/path_checker.py (zero thickness)
    invalid_verify: int = 0  # rejected by polyfold.verify.paths at the stated thickness
    rejected: int = 0
    splits: int = 0
    without: int = 0
    fold_s: float = 0.0
    make_s: float = 0.0
    errors: list[str] = field(default_factory=list)
    first_invalid: str = ""


def check_folder(out: Path, row: Row) -> None:
    """Re-check every written path of a make folder with both checkers."""
    from polyfold.verify.paths import check_fold_path

    for f in sorted(out.glob("piece-*.fold")):
        fold = json.loads(f.read_text())
        if not fold.get("polyfold:path"):
            continue
        row.written += 1
        theirs = check_path(fold)
        folded = np.asarray(fold["file_frames"][0]["vertices_coords"], dtype=float)
        diag = float(np.linalg.norm(folded.max(axis=0) - folded.min(axis=0)))
        mine = check_fold_path(fold, thickness=fold.get("polyfold:path_thicknessRel", 0.0) * diag)
        if not theirs.ok:
            row.invalid_tests += 1
            row.first_invalid = row.first_invalid or f"{f.name}: tests checker: {theirs.first_collision} {theirs.problems[:1]}"
        if not mine.ok:
            row.invalid_verify += 1
            row.first_invalid = row.first_invalid or f"{f.name}: verify.paths: {mine.why()}"


def run(path: Path, seeds: list[int], thickness: float, work: Path, time_limit: float) -> Row:
    from polyfold.errors import PolyfoldError
    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    row = Row(path.stem, thickness, sum(1 for line in path.read_text().splitlines() if line.startswith("f ")))
    for seed in seeds:
        out = work / f"{path.stem}-t{thickness:g}-s{seed}"
        t0 = time.perf_counter()
        try:
            rep = make(path, out, MakeOptions(seed=seed, thickness=thickness, time_limit=time_limit)).report
        except PolyfoldError as exc:
            row.errors.append(f"seed {seed}: {exc}")
            continue
        row.make_s += time.perf_counter() - t0
        row.runs += 1
        fr = rep.stages.fold
        row.pieces += fr.pieces
        row.verified += fr.verified
        row.rejected += fr.rejected_paths
        row.splits += fr.splits_for_folding
        row.without += fr.pieces - fr.verified
        row.fold_s += fr.seconds
        check_folder(out, row)
    return row


COLUMNS = ("model", "faces", "t mm", "runs", "pieces", "paths", "verified", "invalid (tests)", "invalid (verify)",
           "rejected in make", "splits", "no path", "fold s", "make s")


def cells(r: Row) -> list[str]:
    return [r.name, str(r.faces), f"{r.thickness:g}", str(r.runs), str(r.pieces), str(r.written), str(r.verified),
            str(r.invalid_tests), str(r.invalid_verify), str(r.rejected), str(r.splits), str(r.without),
            f"{r.fold_s:.1f}", f"{r.make_s:.1f}"]


def print_table(rows: list[Row], markdown: bool) -> None:
    table = [list(COLUMNS)] + [cells(r) for r in rows]
    if markdown:
        print("| " + " | ".join(COLUMNS) + " |")
        print("|---|" + "---:|" * (len(COLUMNS) - 1))
        for c in table[1:]:
            print("| " + " | ".join(c) + " |")
        return
    widths = [max(len(c[i]) for c in table) for i in range(len(COLUMNS))]
    for c in table:
        print("  ".join(x.ljust(w) if i == 0 else x.rjust(w) for i, (x, w) in enumerate(zip(c, widths))))


def parse_seeds(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="six shared models, seed 1, no generated meshes")
    ap.add_argument("--seeds", default="1-5", help="seeds of the shared models (generated meshes: the first)")
    ap.add_argument("--thickness", default="0,0.2", help="paper thicknesses, mm")
    ap.add_argument("--no-generated", action="store_true")
    ap.add_argument("--only", nargs="+", default=None, help="only these models (file stems)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--time-limit", type=float, default=60.0)
    args = ap.parse_args()
    seeds = [1] if args.quick else parse_seeds(args.seeds)
    thicknesses = [float(t) for t in args.thickness.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        shared = [p for p in sorted(MODELS.glob("*.obj")) if p.stem != "tetrahedron-4"]  # no page fits it at 150 mm
        if args.quick:
            shared = [p for p in shared if p.stem in QUICK]
        todo = [(p, seeds) for p in shared]
        if not (args.quick or args.no_generated):
            todo += [(p, seeds[:1]) for p in bench_build.write_generated(work / "generated", GENERATED, "bench/bench_paths.py")]
        if args.only:
            todo = [(p, s) for p, s in todo if p.stem in args.only]
        rows: list[Row] = []
        t0 = time.perf_counter()
        for thickness in thicknesses:
            for path, s in todo:
                rows.append(run(path, s, thickness, work / "made", args.time_limit))
                r = rows[-1]
                print(f"[{len(rows)}/{len(todo) * len(thicknesses)}] {path.stem} t={thickness:g}: {r.written} paths, "
                      f"{r.invalid_tests + r.invalid_verify} invalid, {r.make_s:.1f} s", file=sys.stderr, flush=True)
        print_table(rows, args.markdown)
        print()
        for r in rows:
            for e in r.errors:
                print(f"{r.name} (t {r.thickness:g}): make failed: {e}")
            if r.first_invalid:
                print(f"{r.name} (t {r.thickness:g}): first invalid path: {r.first_invalid}")
        for thickness in thicknesses:
            sel = [r for r in rows if r.thickness == thickness]
            bad = sum(r.invalid_tests + r.invalid_verify for r in sel)
            print(f"{'PASS' if bad == 0 else 'FAIL'}  invalid paths = 0 at {thickness:g} mm: {bad} among "
                  f"{sum(r.written for r in sel)} written paths ({sum(r.pieces for r in sel)} pieces, "
                  f"{sum(r.without for r in sel)} without a verified path, {sum(r.rejected for r in sel)} rejected "
                  f"and re-planned, {sum(r.splits for r in sel)} splits for folding)")
        print(f"\n{len(rows)} rows, {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
