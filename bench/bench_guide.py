"""What the assembly guide (issue 22) adds to make's time: `polyfold make` with and without
--no-guide, as a user runs it (wall time of the command, median of --runs after one warm-up
run each), and in-process, on bunny-128, horse-302 and generated meshes (a random convex hull and
a noisy sphere). Not a test.

    .venv/bin/python bench/bench_guide.py [--runs 3] [--markdown]

Columns: steps, pictures, guide.pdf pages, the guide's own build seconds (report.json), make's
wall time without and with the guide, and the share it adds (the issue's bound: 30 % on bunny-128
and horse-302).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
CLI = str(Path(sys.executable).with_name("polyfold"))


def generated(tmp: Path) -> list[tuple[str, Path]]:
    """A random convex hull (300 points) and a noisy icosphere (320 faces), as OBJ files."""
    import trimesh

    rng = np.random.default_rng(22)
    hull = trimesh.convex.convex_hull(rng.normal(size=(300, 3)) * [1.0, 0.8, 0.6])
    sphere = trimesh.creation.icosphere(subdivisions=2)
    sphere.vertices *= 1.0 + 0.04 * rng.standard_normal((len(sphere.vertices), 1))
    out = []
    for name, m in ((f"hull-{len(hull.faces)}", hull), ("noisy-ico2-320", sphere)):
        path = tmp / f"{name}.obj"
        m.export(path)
        out.append((name, path))
    return out


def run(mesh: Path, out: Path, guide: bool) -> tuple[float, dict]:
    t0 = time.perf_counter()
    subprocess.run([CLI, "make", str(mesh), "-o", str(out), "-q", "--guide" if guide else "--no-guide"], check=True)
    wall = time.perf_counter() - t0
    return wall, json.loads((out / "report.json").read_text())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cases = [(n, MODELS / f"{n}.obj") for n in ("bunny-128", "horse-302") if (MODELS / f"{n}.obj").exists()]
        cases += generated(tmp)
        for name, mesh in cases:
            times = {False: [], True: []}
            inproc = {False: [], True: []}
            rep = None
            for guide in (False, True):
                run(mesh, tmp / f"{name}-{guide}", guide)  # warm-up (numba cache, files)
            for _ in range(args.runs):
                for guide in (False, True):
                    wall, r = run(mesh, tmp / f"{name}-{guide}", guide)
                    times[guide].append(wall)
                    inproc[guide].append(r["seconds"])
                    if guide:
                        rep = r
            g = rep["stages"]["guide"]
            off, on = statistics.median(times[False]), statistics.median(times[True])
            ioff, ion = statistics.median(inproc[False]), statistics.median(inproc[True])
            rows.append((name, rep["input"]["faces"], len(rep["pieces"]), g["steps"], g["pictures"], g["pdf_pages"],
                         g["seconds"], off, on, 100 * (on - off) / off, ioff, ion, 100 * (ion - ioff) / ioff))
    head = ("mesh", "faces", "pieces", "steps", "pictures", "guide.pdf pages", "guide build s", "make wall s (no guide)",
            "make wall s (guide)", "added", "in-process s (no guide)", "in-process s (guide)", "added")
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]} | {r[5]} | {r[6]:.2f} | {r[7]:.2f} | {r[8]:.2f} | "
                  f"{r[9]:+.0f} % | {r[10]:.2f} | {r[11]:.2f} | {r[12]:+.0f} % |")
    else:
        for r in rows:
            print(f"{r[0]:<16} {r[1]:>5} faces {r[2]:>3} pieces {r[3]:>3} steps {r[4]:>3} pics {r[5]:>3} pages  "
                  f"guide {r[6]:.2f} s  wall {r[7]:.2f} -> {r[8]:.2f} s ({r[9]:+.0f} %)  "
                  f"in-process {r[10]:.2f} -> {r[11]:.2f} s ({r[12]:+.0f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
