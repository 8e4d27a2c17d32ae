"""Folding benchmark (not a test): nets + collision-free folding paths for the paper's parts.

For every part in ../shared/models/paper-parts and for periscope-28, periscope2-44 and bunny-128
(whole meshes): DOF, linearly foldable?, net seconds, path seconds, frames. Targets (issue 3):
every paper part gets a verified path; the 7 horse parts <= 0.25 s total net + path (paper:
12.75 s); bunny-128 whole net + path <= 10 s (paper: 490 s); fish parts <= 2.5 s total (paper:
119 s). Times are wall-clock seconds in one process with the numba kernels already compiled.

    .venv/bin/python bench/bench_fold.py [--seeds 1] [--time-limit 60] [--prefer-linear] [--contact-tol 1e-7]
    .venv/bin/python bench/bench_fold.py --collision   # the collision test alone, us per configuration

--collision: microseconds per configuration of the planners' collision test, thread time, best of
15: "line" = the 0.5 degree samples of the straight line flat -> goal in order, up to the first
that collides (`kinematics.segment_collides`); "path" = the segments of plan_fold's own path
checked at 0.5 degree as the planners do (`fold.segment_free`: bisection order, rigid groups).
Target (perf-coll): at least 2x faster than 057cf99 on small and mid nets, no slower on big ones;
the 057cf99 columns hold that commit's times measured the same way on the development machine
(2 shared cores, so compare runs made at the same time).

fish/part-4 (from the paper's own data) intersects itself in its folded goal shape by ~2.4e-4 of the
model size, so no path exists at the default contact tolerance; `--contact-tol 1e-3` (0.15 mm on a
150 mm model, about the paper's thickness) treats that as contact.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from polyfold.errors import PolyfoldError
from polyfold.fold.plan import is_linearly_foldable, plan_fold
from polyfold.formats.meshes import load_mesh
from polyfold.fold.tree import FoldTree, collides
from polyfold.unfold.search import unfold

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))


def cases() -> list[tuple[str, str, Path]]:
    out = []
    for group in ("horse", "fish", "bunny-128"):
        for p in sorted((MODELS / "paper-parts" / group).glob("part-*.obj")):
            out.append((group, f"{group}/{p.stem}", p))
    for name in ("periscope-28", "periscope2-44", "bunny-128"):
        out.append(("whole", name, MODELS / f"{name}.obj"))
    return out


def run(path: Path, seed: int, time_limit: float, prefer_linear: bool, contact_tol: float = 1e-7) -> dict:
    (mesh,) = load_mesh(path).components
    def accept(net) -> bool:
        tree = FoldTree.from_net(net, contact_tol)
        return collides(tree, tree.goal) or is_linearly_foldable(tree)  # hopeless shapes: stop looking

    accept = accept if prefer_linear else None
    t0 = time.perf_counter()
    net, st = unfold(mesh, seed=seed, time_limit=time_limit, accept=accept)
    t1 = time.perf_counter()
    tree = FoldTree.from_net(net, contact_tol)
    row = {"dof": len(tree.creases), "pieces": net.n_pieces, "net_s": t1 - t0}
    if collides(tree, tree.goal):
        row.update(path_s=float("nan"), frames=0, lc=None, note="goal shape itself self-intersects (input data)")
        return row
    try:
        path = plan_fold(tree, resolution_deg=1.0, time_limit=time_limit, seed=seed)
    except PolyfoldError as exc:
        row.update(path_s=float("nan"), frames=0, lc=None, note=str(exc))
        return row
    t2 = time.perf_counter()
    if path is None:
        row.update(path_s=t2 - t1, frames=0, lc=False, note="no path within the time limit")
    else:
        row.update(path_s=t2 - t1, frames=len(path.frames), lc=path.linear, note=path.planner)
    return row


# us per configuration at 057cf99 (line, path) on the dev machine, measured as collision_table does
# (057cf99 checked a segment with one config_collides_moving call per sample)
COLLISION_BEFORE = {
    "periscope-28 part 0": (2.48, 2.22), "periscope-28 part 1": (1.70, None), "periscope2-44 part 0": (3.6, 2.4),
    "horse-302 part 1": (24.3, None), "horse-302 part 3": (19.0, 10.3), "bunny-128": (33.3, 14.2),
    "horse-302": (99.5, 38.4), "fish-472": (160.0, None),
}


def collision_table() -> None:
    """Print us per configuration of the collision test (see the module docstring)."""
    import math

    from polyfold.fold.checker import segment_free
    from polyfold.fold.checker import collision_work, segment_collides
    from polyfold.segment.segment import segment

    def best_of(fn) -> float:
        fn()
        best = math.inf
        for _ in range(15):
            t = time.thread_time()
            fn()
            best = min(best, time.thread_time() - t)
        return best

    def line_us(tree) -> float | None:
        """The straight line's 0.5 degree samples in order, up to the first that collides, in one
        call (as a segment)."""
        m = int(math.ceil(np.abs(tree.goal).max() / math.radians(0.5) - 1e-12))
        zero, ks = np.zeros(tree.n_edges), np.arange(1, m)
        work = collision_work(tree.n_faces)
        args = (zero, tree.goal, ks, m, tree.order, tree.parent, tree.crease, tree.axis, tree.flat, tree.piece,
                np.arange(tree.n_faces), tree.tol, work, np.empty(tree.n_edges))
        checked = segment_collides(*args)[1]
        if checked == 0:  # a goal within half a degree of flat: no sample to time
            return None
        return best_of(lambda: segment_collides(*args)) / checked * 1e6

    def path_us(tree, frames) -> float:
        """The path's segments at 0.5 degree, as the planner checks them (one call per segment)."""
        work = collision_work(tree.n_faces)
        q = np.empty(tree.n_edges)
        t = tree
        segments = [(a, b, max(1, int(math.ceil(np.abs(b - a).max() / math.radians(0.5) - 1e-12))))
                    for a, b in zip(frames[:-1], frames[1:])]
        checked = sum(segment_free(a, b, m, t.order, t.parent, t.crease, t.axis, t.flat, t.piece,
                                   t.tol, q, 1 << 40, work, False)[1] for a, b, m in segments)

        def run():
            for a, b, m in segments:
                segment_free(a, b, m, t.order, t.parent, t.crease, t.axis, t.flat, t.piece, t.tol, q, 1 << 40, work, False)
        return best_of(run) / checked * 1e6

    nets = []
    for name, parts, keep in (("periscope-28", 2, None), ("periscope2-44", 3, (0,)), ("horse-302", 7, (1, 3)),
                              ("bunny-128", None, None), ("horse-302", None, None), ("fish-472", None, None)):
        mesh = load_mesh(MODELS / f"{name}.obj").mesh
        if parts is None:
            nets.append((name, mesh))
            continue
        for i, part in enumerate(segment(mesh, parts=parts).parts):
            if keep is None or i in keep:
                nets.append((f"{name} part {i}", part))
    print(f"{'net':<22} {'faces':>5} {'line us':>8} {'057cf99':>8} {'path us':>8} {'057cf99':>8}  path planner")
    for label, mesh in nets:
        net, _ = unfold(mesh, seed=1, time_limit=20)
        tree = FoldTree.from_net(net)
        us_path, planner = None, "-"
        if not collides(tree, tree.goal):
            path = plan_fold(tree, seed=1)
            if path is not None:
                planner = path.planner
                if len(path.frames) > 2:
                    us_path = path_us(tree, path.frames)
        before = COLLISION_BEFORE.get(label, (None, None))
        cells = " ".join(f"{v:>8.2f}" if v is not None else f"{'-':>8}" for v in (line_us(tree), before[0], us_path, before[1]))
        print(f"{label:<22} {tree.n_faces:>5} {cells}  {planner}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--prefer-linear", action="store_true")
    ap.add_argument("--contact-tol", type=float, default=1e-7, help="contact tolerance, fraction of the model size")
    ap.add_argument("--collision", action="store_true", help="only the table of the collision test's cost")
    args = ap.parse_args()
    if args.collision:
        collision_table()
        return
    run(MODELS / "tetrahedron-4.obj", 0, 10, False)  # compile / load the numba caches first
    print(f"{'part':<22} {'seed':>4} {'DOF':>4} {'pcs':>3} {'LC':>5} {'net s':>7} {'path s':>7} {'total':>7} {'frames':>6}  planner / note")
    totals: dict[tuple[str, int], float] = {}
    failures = 0
    for group, name, path in cases():
        for seed in range(1, args.seeds + 1):
            r = run(path, seed, args.time_limit, args.prefer_linear, args.contact_tol)
            total = r["net_s"] + (0.0 if np.isnan(r["path_s"]) else r["path_s"])
            key = (f"{name} (whole)" if group == "whole" else f"{group} parts", seed)
            totals[key] = totals.get(key, 0.0) + total
            failures += r["frames"] == 0
            lc = "-" if r["lc"] is None else ("yes" if r["lc"] else "no")
            print(f"{name:<22} {seed:>4} {r['dof']:>4} {r['pieces']:>3} {lc:>5} {r['net_s']:>7.3f} {r['path_s']:>7.3f} "
                  f"{total:>7.3f} {r['frames']:>6}  {r['note']}", flush=True)
    print()
    targets = {"horse parts": 0.25, "fish parts": 2.5, "bunny-128 (whole)": 10.0}
    print(f"{'group':<22} {'seed':>4} {'net+path s':>10}  target")
    for (group, seed), total in totals.items():
        t = targets.get(group)
        verdict = f"<= {t:g} s: {'MET' if total <= t else 'MISSED'}" if t else ""
        print(f"{group:<22} {seed:>4} {total:>10.3f}  {verdict}")
    print(f"\nparts without a verified path: {failures}")


if __name__ == "__main__":
    main()
