"""`polyfold bench paper`: the paper's Tables 1-2 and Figs. 3 and 5, regenerated next to the
paper's own numbers (ALGORITHMS.md 8).

In: the benchmark models folder (../shared/models), a number of runs, time limits. Out (into a
folder): report.md (tables: ours as mean ± standard deviation over the runs, the paper's value,
paper / ours), report.json (every run), fig3.png and fig5.png. Needs matplotlib for the figures
(the `bench` extra); the tables do not.

Every time is wall-clock seconds in this process with the numba kernels already compiled. A
"path" is a collision-free folding path found by `fold.plan.plan_fold` ("auto": straight line first =
LC, then the sequential planner, then Lazy PRM); whole meshes are also run with the paper's own
planner (straight line, then Lazy PRM) on a few seeds. A run without a path within the time limit
counts the time limit as its path time and is marked. Paths are planned at the default material
thickness of `polyfold fold` (THICKNESS_REL of the model size; README "Paper thickness"); Fig. 5
samples without thickness, as the paper.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..collide.tolerance import CONTACT_TOL, THICKNESS_REL

# ALGORITHMS.md 8.1: (DOF, LC, finding net s, path planning s) per horse patch
PAPER_TABLE1 = [(17, True, 0.00, 0.01), (17, True, 0.00, 0.02), (21, False, 0.00, 2.69), (42, False, 0.56, 1.39),
                (37, False, 0.02, 0.73), (86, True, 4.84, 0.31), (75, False, 0.58, 1.60)]
# ALGORITHMS.md 8.2 (+ the horse of 8.1): model -> whole (net, path, total), parts (k, seg, net, path, total)
PAPER_TABLE2 = {
    "periscope-28": {"whole": (0.08, 7.05, 7.13), "parts": (2, 0.00, 0.00, 0.12, 0.12)},
    "periscope2-44": {"whole": (0.21, 12.40, 12.61), "parts": (3, 0.00, 0.09, 0.17, 0.26)},
    "bunny-128": {"whole": (8.09, 482.57, 490.66), "parts": (3, 0.02, 2.90, 23.15, 26.07)},
    "fish-472": {"whole": (69.66, 1848.86, 1918.52), "parts": (5, 0.92, 13.19, 105.82, 119.01)},
    "fish-472 inflated": {"whole": None, "parts": (5, 0.92, 0.88, 9.93, 11.73)},
    "horse-302": {"whole": (219.87, math.inf, math.inf), "parts": (7, None, 6.00, 6.75, 12.75)},
}
# fish-472 folds into a shape that intersects itself by ~2.4e-4 of its size (MODELS.md): at the
# default contact tolerance no path can exist, so the fish rows use the paper's thickness scale.
CONTACT = {"fish-472": 1e-3, "fish-472 inflated": 1e-3}
# ... and since its folded shape is closer to itself than any material thickness, those rows fold
# without thickness; every other row plans at fold's default (THICKNESS_REL of the model size)
THICKNESS = {"fish-472": 0.0, "fish-472 inflated": 0.0}
STRATEGIES = ("discrete", "continuous", "continuous-full")
STRATEGY_STYLE = {"discrete": ("o", "tab:red"), "continuous": ("^", "tab:blue"), "continuous-full": ("s", "tab:green")}
FIG3_PAPER = {
    "uniform": [(0.0, 44), (0.0918, 48), (0.1726, 36), (0.2371, 20), (0.2681, 14), (0.3182, 0)],
    "constrained": [(0.0, 44), (0.0539, 38), (0.0705, 28), (0.0807, 20), (0.0830, 6), (0.0839, 0)],
}


@dataclass(frozen=True)
class BenchSettings:
    runs: int = 20
    time_limit: float = 60.0  # per search (one unfold, one path), whole meshes and parts alike
    samples: int = 1000  # Fig. 5 samples per net and strategy (ALGORITHMS.md 6.6)
    quick: bool = False


def quick_settings() -> BenchSettings:
    return BenchSettings(runs=3, time_limit=5.0, samples=200, quick=True)


# ----------------------------------------------------------------------------------------------
# Measurements


PAPER_PLANNER_RUNS = 5  # whole meshes with the paper's planner: it mostly runs into the time limit


def net_and_path(mesh, seed: int, time_limit: float, contact_tol: float, planner: str = "auto",
                 thickness: float = THICKNESS_REL) -> dict:
    """Unfold `mesh` (one component) and plan a folding path for the net; seconds and facts.

    planner: a `plan_fold` planner, or "paper": the straight line, then Lazy PRM for the time left.
    thickness: of the material, relative to the model size (default: fold's; the paper's model
    has none, Fig. 5 samples without).
    """
    from ..errors import PolyfoldError
    from ..fold.plan import plan_fold
    from ..fold.tree import FoldTree
    from ..unfold.search import unfold

    t0 = time.perf_counter()
    net, st = unfold(mesh, seed=seed, time_limit=time_limit)
    t1 = time.perf_counter()
    tree = FoldTree.from_net(net, contact_tol)
    tree = tree.with_thickness(thickness * tree.scale)
    row = {"dof": int(len(tree.creases)), "pieces": int(net.n_pieces), "net_s": t1 - t0, "path": False,
           "lc": None, "path_s": float(time_limit), "note": "", "tree": tree, "planner": None}
    if net.n_pieces > 1:
        row["note"] = "no single net in time"
        return row
    try:  # (plan_fold checks the goal first: a goal that self-intersects is its PolyfoldError)
        if planner == "paper":
            path = plan_fold(tree, planner="linear", time_limit=time_limit, seed=seed)
            if path is None:
                left = max(0.0, time_limit - (time.perf_counter() - t1))
                path = plan_fold(tree, planner="lazy-prm", time_limit=left, seed=seed)
        else:
            path = plan_fold(tree, planner=planner, time_limit=time_limit, seed=seed)
    except PolyfoldError as exc:
        row["note"] = str(exc)
        return row
    t2 = time.perf_counter()
    if path is None:
        row["note"] = "no path in time"
        row["path_s"] = max(t2 - t1, float(time_limit))
    else:
        row.update(path=True, lc=bool(path.linear), path_s=t2 - t1, planner=path.planner)
    return row


def _planner_counts(rows: list[dict], counts: dict[str, int] | None = None) -> dict[str, int]:
    """How many of the `net_and_path` rows each planner found the path of (added to counts)."""
    counts = {} if counts is None else counts
    for r in rows:
        if r["planner"]:
            counts[r["planner"]] = counts.get(r["planner"], 0) + 1
    return counts


def _whole_row(mesh, seeds, time_limit: float, tol: float, planner: str, thickness: float) -> dict:
    """Runs of one whole mesh: seconds per run, paths found, LC count, planners that found them."""
    rows = [net_and_path(mesh, seed, time_limit, tol, planner, thickness) for seed in seeds]
    return {"dof": rows[0]["dof"], "net_s": [r["net_s"] for r in rows], "path_s": [r["path_s"] for r in rows],
            "runs": len(rows), "paths": sum(r["path"] for r in rows), "lc": sum(bool(r["lc"]) for r in rows),
            "planners": _planner_counts(rows), "notes": sorted({r["note"] for r in rows if r["note"]}), "rows": rows}


def _parts_row(parts: list, runs: int, time_limit: float, tol: float, seg_s: list[float] | None,
               thickness: float) -> dict:
    """Runs over a list of part meshes: per run the sums of net and path seconds."""
    per_run, dofs, ok = [], [], True
    trees = []
    planners: dict[str, int] = {}
    for seed in range(1, runs + 1):
        rows = [net_and_path(p, seed, time_limit, tol, thickness=thickness) for p in parts]
        net_s = sum(r["net_s"] for r in rows)
        path_s = sum(r["path_s"] for r in rows)
        ok &= all(r["path"] for r in rows)
        per_run.append({"net_s": net_s, "path_s": path_s, "paths": [r["path"] for r in rows],
                        "lc": [r["lc"] for r in rows], "notes": [r["note"] for r in rows],
                        "part_net_s": [r["net_s"] for r in rows], "part_path_s": [r["path_s"] for r in rows]})
        _planner_counts(rows, planners)
        if seed == 1:
            dofs = [r["dof"] for r in rows]
            trees = [r["tree"] for r in rows]
    seg = seg_s or [0.0] * runs
    totals = [s + r["net_s"] + r["path_s"] for s, r in zip(seg, per_run)]
    return {"dofs": dofs, "runs": per_run, "seg_s": seg, "totals": totals, "all_paths": ok, "trees": trees,
            "planners": planners}


# ----------------------------------------------------------------------------------------------
# Tables


def table1(models: Path, st: BenchSettings, say) -> dict:
    """Horse: the paper's 7 patches and our own 7-part segmentation of horse-302."""
    from ..formats.meshes import load_mesh
    from ..segment.segment import segment

    say("table 1: the paper's horse patches")
    paper_parts = [load_mesh(p).components[0] for p in sorted((models / "paper-parts" / "horse").glob("part-*.obj"))]
    per_part = []
    for k, part in enumerate(paper_parts):
        rows = [net_and_path(part, seed, st.time_limit, CONTACT_TOL) for seed in range(1, st.runs + 1)]
        per_part.append({"dof": rows[0]["dof"], "lc": sum(bool(r["lc"]) for r in rows), "paths": sum(r["path"] for r in rows),
                         "net_s": [r["net_s"] for r in rows], "path_s": [r["path_s"] for r in rows]})
    say("table 1: our segmentation of horse-302")
    whole = load_mesh(models / "horse-302.obj").mesh
    seg_s, seg = [], None
    for _ in range(st.runs):
        t0 = time.perf_counter()
        seg = segment(whole, parts=7)
        seg_s.append(time.perf_counter() - t0)
    ours = []
    for k, part in enumerate(seg.parts):
        rows = [net_and_path(part, seed, st.time_limit, CONTACT_TOL) for seed in range(1, st.runs + 1)]
        ours.append({"dof": rows[0]["dof"], "lc": sum(bool(r["lc"]) for r in rows), "paths": sum(r["path"] for r in rows),
                     "net_s": [r["net_s"] for r in rows], "path_s": [r["path_s"] for r in rows]})
    return {"paper_patches": per_part, "our_parts": ours, "our_seg_s": seg_s}


def table2(models: Path, st: BenchSettings, say) -> tuple[dict, list]:
    """Whole mesh vs segmented, per model; also the nets for Fig. 5 (DOF, tree, whole/part)."""
    from ..inflate.inflate import inflate
    from ..formats.meshes import load_mesh
    from ..segment.segment import segment

    out, fig5_trees = {}, []
    fish_labels = None
    for name, paper in PAPER_TABLE2.items():
        tol = CONTACT.get(name, CONTACT_TOL)
        thick = THICKNESS.get(name, THICKNESS_REL)
        k = paper["parts"][0]
        if name == "fish-472 inflated":
            say(f"table 2: {name} (constrained inflation, the fish's own parts)")
            fish = load_mesh(models / "fish-472.obj").mesh
            t0 = time.perf_counter()
            res = inflate(fish, mode="constrained")
            inflate_s = time.perf_counter() - t0
            mesh = res.mesh
            parts = [mesh.submesh(np.flatnonzero(fish_labels == p)) for p in range(k)]
            seg_s = None
            extra = {"inflate_s": inflate_s, "inflate_stop": res.stop_reason,
                     "hv": [int(res.hyperbolic_start), int(res.hyperbolic)]}
        else:
            say(f"table 2: {name}")
            mesh = load_mesh(models / f"{name}.obj").mesh
            seg_s = []
            for _ in range(st.runs):
                t0 = time.perf_counter()
                seg = segment(mesh, parts=k)
                seg_s.append(time.perf_counter() - t0)
            parts = list(seg.parts)
            if name == "fish-472":
                fish_labels = seg.labels
            extra = {"tau": seg.tau}
        whole = None
        if paper["whole"] is not None:
            whole = _whole_row(mesh, range(1, st.runs + 1), st.time_limit, tol, "auto", thick)
            say(f"table 2: {name} whole, the paper's planner")
            whole["paper_planner"] = _whole_row(mesh, range(1, min(st.runs, PAPER_PLANNER_RUNS) + 1),
                                                st.time_limit, tol, "paper", thick)
            rows = whole.pop("rows")
            whole["paper_planner"].pop("rows")
            fig5_trees.append((name, "whole", rows[0]["tree"]))
        pr = _parts_row(parts, st.runs, st.time_limit, tol, seg_s, thick)
        fig5_trees += [(name, "parts", t) for t in pr.pop("trees")]
        out[name] = {"whole": whole, "parts": pr, "contact_tol": tol, "thickness": thick, **extra}
    return out, fig5_trees


# ----------------------------------------------------------------------------------------------
# Figures


def fig5(trees: list, st: BenchSettings, say) -> list[dict]:
    from ..fold.cspace import sample_ratio

    say(f"fig. 5: valid configuration ratios ({st.samples} samples per net and strategy)")
    rows = []
    for name, kind, tree in trees:
        tree = tree.with_thickness(0.0)  # the paper's zero-thickness valid ratio
        dof = int(len(tree.creases))
        m = st.samples * (10 if dof < 20 and not st.quick else 1)
        r = {"model": name, "kind": kind, "dof": dof, "samples": m}
        for strategy in STRATEGIES:
            valid, n = sample_ratio(tree, samples=m, strategy=strategy, seed=0)
            r[strategy] = valid / n
        rows.append(r)
    return rows


def fig3(models: Path, say) -> dict:
    from ..inflate.inflate import inflate
    from ..formats.meshes import load_mesh

    say("fig. 3: inflation of sphere-deformed-320, both modes")
    mesh = load_mesh(models / "sphere-deformed-320.obj").mesh
    out = {}
    for mode in ("uniform", "constrained"):
        t0 = time.perf_counter()
        res = inflate(mesh, mode=mode, log_every=10)
        hist = res.history
        hit = np.flatnonzero(hist[:, 2] <= 0)
        out[mode] = {"seconds": time.perf_counter() - t0, "steps": res.steps, "stop": res.stop_reason,
                     "if_at_hv0": float(hist[hit[0], 1]) if len(hit) else None,
                     "history": hist[:, :3].tolist()}
    return out


# ----------------------------------------------------------------------------------------------
# Report


def kernel_signatures() -> dict[str, set[str]]:
    """The type signatures each numba kernel of the polyfold modules imported so far holds in
    this process (compiled or loaded from the cache): a signature that appears while the clock
    runs means timed compilation."""
    import sys

    from ..jit import Kernel

    root = __package__.partition(".")[0]  # polyfold (this module is in polyfold.apps)
    out: dict[str, set[str]] = {}
    for module_name, module in list(sys.modules.items()):
        if module is None or not module_name.startswith(f"{root}."):
            continue
        for name, obj in vars(module).items():
            if isinstance(obj, Kernel) and obj.py_func.__module__ == module_name:
                out[f"{module_name.removeprefix(root + '.')}.{name}"] = {str(s) for s in obj.jit_signatures()}
    return out


def _warm_up(models: Path) -> None:
    """Call every timed stage once on small models, so numba compiles (fresh checkout) or loads
    its caches before the clock runs: without it the first timed run of a stage carries seconds
    of compilation (a cold checkout put 35 s into one horse segmentation)."""
    from ..collide.self_intersect import crossing_pairs
    from ..fold.cspace import sample_ratio
    from ..inflate.inflate import inflate
    from ..formats.meshes import load_mesh
    from ..segment.segment import segment

    small = load_mesh(models / "periscope-28.obj").mesh
    inflate(small, mode="constrained", max_steps=20)
    inflate(small, mode="uniform", max_steps=20)
    # inflation's self-intersection guard with pairs to skip (a mesh that crosses itself at the
    # start, as the fish): its own compiled variant
    crossing_pairs(small.vertices, small.faces, 1e-9, 1, np.array([1], dtype=np.int64))
    # the bunny reaches the segmentation's concavity kernels and the unfolder's local search;
    # a horse patch the planners' kernels for a net that does not fold along a straight line
    bunny = load_mesh(models / "bunny-128.obj").mesh
    segment(bunny, parts=3)
    patch = load_mesh(models / "paper-parts" / "horse" / "part-3.obj").mesh
    for mesh in (small, bunny, patch):
        for planner in ("linear", "two-phase", "sequential", "lazy-prm"):
            tree = net_and_path(mesh, 0, 1.0, CONTACT_TOL, planner)["tree"]
    for strategy in STRATEGIES:
        sample_ratio(tree, samples=10, strategy=strategy, seed=0)


def run(models: Path, out_dir: Path, st: BenchSettings, progress: Callable[[str], None] | None = None) -> dict:
    """Run everything, write out_dir/report.md, report.json, fig3.png, fig5.png; return the data."""
    from ..formats.files import atomic_write

    say = progress or (lambda s: None)
    if not (models / "horse-302.obj").exists():
        from ..errors import PolyfoldError

        raise PolyfoldError(f"benchmark models not found in {models} (set POLYFOLD_MODELS)")
    out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    _warm_up(models)
    before = kernel_signatures()
    t1 = table1(models, st, say)
    t2, trees = table2(models, st, say)
    f5 = fig5(trees, st, say)
    f3 = fig3(models, say)
    after = kernel_signatures()
    compiled = sorted(f"{name} {sig}" for name, sigs in after.items() for sig in sigs - before.get(name, set()))
    from .benchpaper_report import markdown, plots

    figs = plots(out_dir, f3, f5)
    seconds = time.perf_counter() - t0
    data = {"settings": st.__dict__, "seconds": seconds, "table1": t1, "table2": t2, "fig3": f3, "fig5": f5,
            "figures": figs, "compiled_while_timed": compiled}
    atomic_write(out_dir / "report.json", json.dumps(data, indent=1, default=float) + "\n")
    atomic_write(out_dir / "report.md", markdown(t1, t2, f3, f5, st, seconds, figs, compiled))
    return data
