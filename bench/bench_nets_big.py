"""Single nets of bigger closed meshes (issue 23, item 3), measured (not a test).

    .venv/bin/python bench/bench_nets_big.py [--seeds 5] [--time-limit 30] [--only NAME ...] [--markdown]

Builds closed meshes of 1,000-2,000 faces here (noisy icospheres, random convex hulls and
Loop-subdivided shared models, seeded) and two of about 5,000, then unfolds each with
`polyfold.unfold.unfold` for seeds 1..N (numba kernels loaded before the clock starts). Every net is
re-checked for overlaps by the exact flat test before it counts. Prints per seed the seconds,
pieces and GA generations, then per mesh the median and maximum seconds, the single nets and the
median generations, against the issue's targets (1,000-2,000 faces: median <= 1 s, max <= 3 s;
5,000 faces: median <= 10 s; a single net on every seed).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from bench_build import loop_subdivided, noisy_icosphere  # noqa: E402
from bench_paths import convex_hull  # noqa: E402

MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))

MESHES = (  # name, builder (seeded), size class
    ("noisy-ico3-s02", lambda: noisy_icosphere(3, 0.02, 31), "1-2k"),
    ("noisy-ico3-s05", lambda: noisy_icosphere(3, 0.05, 22), "1-2k"),
    ("noisy-ico3-s08", lambda: noisy_icosphere(3, 0.08, 23), "1-2k"),
    ("noisy-ico3-s12", lambda: noisy_icosphere(3, 0.12, 24), "1-2k"),
    ("hull-ball-600", lambda: convex_hull(600, (1.0, 1.0, 1.0), 41), "1-2k"),
    ("hull-ellipsoid-950", lambda: convex_hull(950, (1.0, 0.6, 0.3), 42), "1-2k"),
    ("bunny-348-loop1", lambda: loop_subdivided(MODELS / "bunny-348.obj", 1), "1-2k"),
    ("horse-302-loop1", lambda: loop_subdivided(MODELS / "horse-302.obj", 1), "1-2k"),
    ("fish-472-loop1", lambda: loop_subdivided(MODELS / "fish-472.obj", 1), "1-2k"),
    ("sphere-deformed-320-loop1", lambda: loop_subdivided(MODELS / "sphere-deformed-320.obj", 1), "1-2k"),
    ("bumpy-528-loop1", lambda: loop_subdivided(MODELS / "bumpy-528.obj", 1), "1-2k"),
    ("noisy-ico4-s03", lambda: noisy_icosphere(4, 0.03, 51), "5k"),
    ("bunny-348-loop2", lambda: loop_subdivided(MODELS / "bunny-348.obj", 2), "5k"),
)
TARGETS = {"1-2k": (1.0, 3.0), "5k": (10.0, None)}  # (median, max) seconds


def main() -> None:
    from polyfold.collide.flat import find_overlaps
    from polyfold.formats.meshes import load_mesh
    from polyfold.mesh.mesh import Mesh
    from polyfold.unfold.search import unfold

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--only", nargs="*", default=None, help="only these meshes (names above)")
    ap.add_argument("--markdown", action="store_true", help="the summary as a Markdown table")
    args = ap.parse_args()

    unfold(load_mesh(MODELS / "bunny-128.obj").components[0], seed=0)  # kernels loaded off the clock
    print(f"{'mesh':<28} {'faces':>5} {'seed':>4} {'seconds':>8} {'pieces':>6} {'generations':>11}  method")
    summary = []
    for name, build, size in MESHES:
        if args.only and name not in args.only:
            continue
        v, f = build()
        mesh = Mesh(np.asarray(v, dtype=float), np.asarray(f, dtype=np.int64))
        times, gens, singles = [], [], 0
        for seed in range(1, args.seeds + 1):
            t0 = time.perf_counter()
            net, st = unfold(mesh, seed=seed, time_limit=args.time_limit)
            dt = time.perf_counter() - t0
            for p in range(net.n_pieces):  # the exact flat test, not the search's own
                idx = np.flatnonzero(net.piece == p)
                assert len(find_overlaps(net.coords[idx], None, 1e-9 * mesh.bbox_diagonal)) == 0, (name, seed)
            times.append(dt)
            gens.append(st.generations)
            singles += st.pieces == 1
            print(f"{name:<28} {mesh.n_faces:>5} {seed:>4} {dt:>8.2f} {st.pieces:>6} {st.generations:>11}  {st.method}",
                  flush=True)
        summary.append((name, mesh.n_faces, size, float(np.median(times)), max(times), singles, len(times),
                        float(np.median(gens))))
    print()
    head = ["mesh", "faces", "median s", "max s", "single nets", "median generations", "target"]
    rows = []
    for name, faces, size, med, mx, singles, runs, gen in summary:
        t_med, t_max = TARGETS[size]
        ok = med <= t_med and (t_max is None or mx <= t_max) and singles == runs
        target = f"median <= {t_med:g}" + (f", max <= {t_max:g}" if t_max else "") + (": met" if ok else ": not met")
        rows.append([name, f"{faces:,}", f"{med:.2f}", f"{mx:.2f}", f"{singles}/{runs}", f"{gen:g}", target])
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print("| " + " | ".join(r) + " |")
    else:
        widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)] if rows else []
        print("  ".join(h.ljust(w) for h, w in zip(head, widths)))
        for r in rows:
            print("  ".join(c.ljust(w) for c, w in zip(r, widths)))


if __name__ == "__main__":
    main()
