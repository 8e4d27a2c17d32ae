"""Studies over many meshes (`polyfold batch --study`): each mesh an isolated task, as in a batch.

In: glob patterns (or paths), an output folder, the study's settings. Out of `run_study`:
DIR/study-<name>.csv (one row per mesh) and DIR/study-<name>.svg (plain SVG: matplotlib is not a
dependency). "unfold": single-piece rate and unfold seconds against faces; "cspace" (paper
Fig. 5): the valid configuration ratio per sampling strategy against DOF.

Only the standard library (and batch.py / isolation.py, which import only it) is imported at
module level: the task processes import this module.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ..collide.tolerance import CONTACT_TOL
from .batch import BatchResult, Progress, Row, expand, outcome_row, row_collector, rows_csv
from .isolation import faults, hard_limit_for, run_tasks, task_spec

STUDIES = ("unfold", "cspace")


@dataclass(frozen=True)
class UnfoldStudyRow:
    """One mesh of `--study unfold`: `runs` unfold calls (seeds 1..N per component), how many gave
    a single piece, and unfold's own seconds per call."""

    mesh: str
    faces: int | None = None
    components: int | None = None
    runs: int | None = None
    successes: int | None = None
    success_rate: float | None = None
    median_s: float | None = None
    mean_s: float | None = None
    max_s: float | None = None
    total_s: float = 0.0
    status: str = "ok"
    error: str = ""


@dataclass(frozen=True)
class CspaceStudyRow:
    """One mesh of `--study cspace` (paper Fig. 5): the net of its largest component (faces of that
    component, pieces, DOF = creases) and the valid configuration ratio per sampling strategy."""

    mesh: str
    faces: int | None = None
    pieces: int | None = None
    dof: int | None = None
    samples: int | None = None
    discrete_valid: int | None = None
    discrete_ratio: float | None = None
    continuous_valid: int | None = None
    continuous_ratio: float | None = None
    total_s: float = 0.0
    status: str = "ok"
    error: str = ""


# ----------------------------------------------------------------------------------------------
# The study tasks (each in its own process)


def unfold_task(spec: dict) -> dict:
    """Unfold every component of spec["mesh"] with seeds 1..runs; -> UnfoldStudyRow values."""
    from ..formats.meshes import load_mesh
    from ..unfold.search import unfold

    loaded = load_mesh(spec["mesh"])
    _warm_up()
    seconds, ok = [], 0
    for comp in loaded.components:
        for seed in range(1, spec["runs"] + 1):
            net, stats = unfold(comp, seed=seed, time_limit=spec["time_limit"])
            ok += net.n_pieces == 1
            seconds.append(stats.seconds)
    return {"faces": loaded.mesh.n_faces, "components": len(loaded.components), "runs": len(seconds),
            "successes": ok, "success_rate": ok / len(seconds), "median_s": statistics.median(seconds),
            "mean_s": statistics.fmean(seconds), "max_s": max(seconds)}


def _warm_up() -> None:
    """Unfold a tetrahedron once: the first unfold of a process loads the numba kernels from
    their cache (~0.3 s), which would otherwise count against the first timed run."""
    import numpy as np

    from ..mesh.mesh import Mesh
    from ..unfold.search import unfold

    tetra = Mesh(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
                 faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    unfold(tetra, seed=0, time_limit=5.0)


def cspace_task(spec: dict) -> dict:
    """One net (seed) of the largest component of spec["mesh"], its valid configuration ratio
    per strategy; -> CspaceStudyRow values."""
    from ..fold.cspace import sample_ratio
    from ..formats.meshes import load_mesh
    from ..fold.tree import FoldTree
    from ..unfold.search import unfold

    loaded = load_mesh(spec["mesh"])
    comp = max(loaded.components, key=lambda m: m.n_faces)
    net, _ = unfold(comp, seed=spec["seed"], time_limit=spec["time_limit"])
    tree = FoldTree.from_net(net, spec["contact_tol"])
    dv, n = sample_ratio(tree, spec["samples"], "discrete", spec["seed"])
    cv, _ = sample_ratio(tree, spec["samples"], "continuous", spec["seed"])
    return {"faces": comp.n_faces, "pieces": net.n_pieces, "dof": len(tree.creases), "samples": n,
            "discrete_valid": dv, "discrete_ratio": dv / n, "continuous_valid": cv, "continuous_ratio": cv / n}


# ----------------------------------------------------------------------------------------------
# Running a study


def run_study(study: str, patterns: str | os.PathLike | Sequence[str | os.PathLike], out_dir: str | os.PathLike, *,
              runs: int = 5, samples: int = 1000, seed: int = 1, time_limit: float = 60.0, contact_tol: float = CONTACT_TOL,
              workers: int | None = None, scheduler: str | None = None, hard_limit: float | None = None,
              progress: Progress | None = None) -> BatchResult:
    """A study over the meshes, each mesh an isolated task as in `run_batch`.

    "unfold": unfold every component with seeds 1..runs (time_limit each): single-piece rate and
    seconds -> success rate and median seconds against faces. "cspace" (paper Fig. 5): one net
    (seed) of the largest component, `samples` configurations per strategy (discrete, continuous)
    -> valid ratio (log scale) against DOF. Writes out_dir/study-<study>.csv and .svg. hard_limit
    default: 2 x the task's time budget + 30 s."""
    from ..errors import PolyfoldError

    if study not in STUDIES:
        raise PolyfoldError(f"--study must be {' or '.join(STUDIES)}, not {study!r}")
    if runs < 1 or samples < 1:
        raise PolyfoldError("--runs and --samples must be at least 1")
    t0 = time.perf_counter()
    meshes = expand(patterns)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    limit = hard_limit_for(time_limit * (runs if study == "unfold" else 1), hard_limit)
    hook = faults()
    task, cls = (unfold_task, UnfoldStudyRow) if study == "unfold" else (cspace_task, CspaceStudyRow)
    specs = [task_spec(task, m, limit, hook.get(m.name), runs=runs, samples=samples, seed=seed,
                       time_limit=time_limit, contact_tol=contact_tol) for m in meshes]
    rows, finish = row_collector(len(meshes), progress)
    run_tasks(specs, workers, scheduler, lambda i, outcome: finish(i, outcome_row(cls, str(meshes[i]), outcome)))
    from ..formats.files import atomic_write

    csv_path, svg_path = out / f"study-{study}.csv", out / f"study-{study}.svg"
    atomic_write(csv_path, rows_csv(rows))
    atomic_write(svg_path, study_svg(study, [r for r in rows if r.status == "ok"]))
    return BatchResult(out_dir=out, rows=tuple(rows), files=(csv_path, svg_path), seconds=time.perf_counter() - t0)


# ----------------------------------------------------------------------------------------------
# Plots: plain SVG (matplotlib is not a dependency)

PANEL_W, PANEL_H = 460, 340
PAD_L, PAD_R, PAD_T, PAD_B = 70, 20, 40, 50
COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c")


def _nice_ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About n round ticks (1, 2, 5 x 10^k steps) covering [lo, hi]."""
    span = hi - lo if hi > lo else 1.0
    raw = span / n
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = math.floor(lo / step) * step
    return [first + k * step for k in range(int(math.ceil((hi - first) / step - 1e-9)) + 1)]


def _fmt(v: float) -> str:
    return f"{v:g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.0e}"


def _panel(x0: float, series: list[tuple[str, list[float], list[float]]], title: str, xlabel: str,
           ylabel: str, log_y: bool, y_max: float | None = None) -> list[str]:
    """SVG elements of one scatter panel at horizontal offset x0. series: (label, xs, ys). On a
    log axis, values <= 0 are drawn hollow on the bottom edge."""
    xs = [x for _, sx, _ in series for x in sx]
    ys = [y for _, _, sy in series for y in sy]
    xt = _nice_ticks(0.0, max(xs, default=1.0) or 1.0)
    if log_y:
        pos = [y for y in ys if y > 0]
        lo = math.floor(math.log10(min(pos))) if pos else -3
        hi = math.ceil(math.log10(max(pos))) if pos else 0
        hi = max(hi, lo + 1)
        yt = [10.0 ** k for k in range(lo, hi + 1)]
        ymap = lambda y: (math.log10(y) - lo) / (hi - lo) if y > 0 else 0.0  # noqa: E731
    else:
        yt = _nice_ticks(0.0, y_max if y_max is not None else (max(ys, default=1.0) or 1.0))
        ymap = lambda y: (y - yt[0]) / (yt[-1] - yt[0])  # noqa: E731
    left, right, top, bottom = x0 + PAD_L, x0 + PANEL_W - PAD_R, PAD_T, PANEL_H - PAD_B
    px = lambda x: left + (x - xt[0]) / (xt[-1] - xt[0]) * (right - left)  # noqa: E731
    py = lambda y: bottom - ymap(y) * (bottom - top)  # noqa: E731
    el = [f'<text x="{(left + right) / 2:.1f}" y="{top - 16}" text-anchor="middle" font-size="14" '
          f'font-weight="bold">{title}</text>',
          f'<rect x="{left}" y="{top}" width="{right - left}" height="{bottom - top}" fill="none" stroke="#333"/>']
    for t in xt:
        el.append(f'<line x1="{px(t):.1f}" y1="{bottom}" x2="{px(t):.1f}" y2="{bottom + 5}" stroke="#333"/>'
                  f'<text x="{px(t):.1f}" y="{bottom + 18}" text-anchor="middle" font-size="11">{_fmt(t)}</text>')
    for t in yt:
        el.append(f'<line x1="{left}" y1="{py(t):.1f}" x2="{right}" y2="{py(t):.1f}" stroke="#ddd"/>'
                  f'<text x="{left - 6}" y="{py(t) + 4:.1f}" text-anchor="end" font-size="11">{_fmt(t)}</text>')
    el.append(f'<text x="{(left + right) / 2:.1f}" y="{bottom + 38}" text-anchor="middle" font-size="12">{xlabel}</text>')
    el.append(f'<text transform="translate({x0 + 18},{(top + bottom) / 2:.1f}) rotate(-90)" text-anchor="middle" '
              f'font-size="12">{ylabel}</text>')
    for k, (label, sx, sy) in enumerate(series):
        c = COLORS[k % len(COLORS)]
        for x, y in zip(sx, sy):
            fill = c if not (log_y and y <= 0) else "none"
            el.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="3.5" fill="{fill}" stroke="{c}" fill-opacity="0.75"/>')
        if len(series) > 1:
            ly = top + 16 + 16 * k
            el.append(f'<circle cx="{right - 110}" cy="{ly - 4}" r="4" fill="{c}"/>'
                      f'<text x="{right - 100}" y="{ly}" font-size="11">{label}</text>')
    return el


def study_svg(study: str, rows: Sequence[Row]) -> str:
    """The study's plot as an SVG document (rows with status ok)."""
    if study == "unfold":
        faces = [r.faces for r in rows]
        panels = [_panel(0, [("success", faces, [r.success_rate for r in rows])], "Single-piece nets",
                         "faces", "success rate (single piece)", False, 1.0),
                  _panel(PANEL_W, [("median", faces, [r.median_s for r in rows])], "Unfold time",
                         "faces", "median seconds (log)", True)]
        title = f"polyfold study unfold: {len(rows)} meshes"
    else:
        dof = [r.dof for r in rows]
        panels = [_panel(0, [("discrete", dof, [r.discrete_ratio for r in rows]),
                             ("continuous", dof, [r.continuous_ratio for r in rows])],
                         "Valid configurations (Fig. 5)", "DOF (creases)", "|C_valid| / |C_sampled| (log)", True)]
        title = f"polyfold study cspace: {len(rows)} meshes (hollow: no valid sample)"
    width = PANEL_W * len(panels)
    body = "\n".join(e for p in panels for e in p)
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{PANEL_H + 20}" '
            f'viewBox="0 0 {width} {PANEL_H + 20}" font-family="sans-serif">\n'
            f'<rect width="100%" height="100%" fill="white"/>\n{body}\n'
            f'<text x="{width / 2:.1f}" y="{PANEL_H + 12}" text-anchor="middle" font-size="11" fill="#555">'
            f'{title}</text>\n</svg>\n')
