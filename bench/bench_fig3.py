"""Fig. 3 of the paper (not a test): IF against hyperbolic vertices, uniform vs constrained inflation.

Inflates sphere-deformed-320 (162 vertices, 44 hyperbolic) in both modes with the default
parameters until HV = 0 (or the run's own stop), logging (step, IF, HV, volume change) every
--log-every steps. Prints one row per mode (steps, seconds, stop reason, IF at HV = 0 and the
constrained / uniform IF ratio), then, for each point the paper gives, our HV at the paper's IF
(the logged row nearest that IF) and the IF at which our run first gets to the paper's HV (first
row with HV <= the paper's, or >= for the uniform rise above the start).

Writes to --out (default out/fig3/):
  fig3_hv_vs_if.png       HV against IF, our runs as lines, the paper's points as markers
  fig3_snapshots.png      2 x 6 renders (rows = modes) at the logged states where HV first gets to
                          the paper's HV values, hyperbolic vertices on the visible side as red dots
  fig3_history_<mode>.csv the history rows (step, IF, HV, volume_change)

Times are wall-clock seconds of `polyfold.inflate.inflate`, numba kernels already compiled. Needs
matplotlib (the `bench` extra: pip install -e .[bench]); the runtime package does not.

    .venv/bin/python bench/bench_fig3.py [--log-every 10] [--out out/fig3] [--model sphere-deformed-320]
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from pathlib import Path

import numpy as np

from polyfold.inflate.inflate import inflate
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
MODES = ("uniform", "constrained")
# ALGORITHMS.md 8.3 (paper Fig. 3): (IF, HV) pairs per mode
PAPER = {
    "uniform": [(0.0, 44), (0.0918, 48), (0.1726, 36), (0.2371, 20), (0.2681, 14), (0.3182, 0)],
    "constrained": [(0.0, 44), (0.0539, 38), (0.0705, 28), (0.0807, 20), (0.0830, 6), (0.0839, 0)],
}
COLORS = {"uniform": "tab:blue", "constrained": "tab:orange"}
ELEV, AZIM = 20.0, -60.0  # camera (degrees), the same for every panel


def row_at_if(hist: np.ndarray, target: float) -> int:
    """Index of the logged row whose IF is nearest `target` (first such row)."""
    return int(np.argmin(np.abs(hist[:, 1] - target)))


def row_reaching(hist: np.ndarray, hv: int) -> int:
    """Index of the first logged row whose HV gets to `hv` coming from the start: HV >= hv when hv
    is above the starting HV (the uniform rise), else HV <= hv; -1 if the run never gets there."""
    rows = np.flatnonzero(hist[:, 2] >= hv if hv > hist[0, 2] else hist[:, 2] <= hv)
    return int(rows[0]) if len(rows) else -1


def first_if_reaching(hist: np.ndarray, hv: int) -> float:
    """IF of `row_reaching` (nan if never)."""
    i = row_reaching(hist, hv)
    return float(hist[i, 1]) if i >= 0 else float("nan")


def camera() -> np.ndarray:
    """Rows: screen x, screen y, towards the viewer (orthographic, z up in the model frame)."""
    e, a = np.radians(ELEV), np.radians(AZIM)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])  # towards the viewer
    right = np.cross([0.0, 0.0, 1.0], view)
    right /= np.linalg.norm(right)
    up = np.cross(view, right)
    return np.array([right, up, view])


def render(ax, X: np.ndarray, F: np.ndarray, center: np.ndarray, half: float, title: str) -> None:
    """Painter's-algorithm render: back faces culled, light-gray Lambert shading, hyperbolic
    vertices whose normal faces the camera as red dots."""
    from matplotlib.collections import PolyCollection

    R = camera()
    Y = (X - center) @ R.T
    mesh = Mesh(X, F)
    n = mesh.face_normals
    facing = n @ R[2]
    light = np.array([-0.4, 0.5, 0.75])
    light /= np.linalg.norm(light)
    shade = 0.45 + 0.5 * np.clip((n @ R.T) @ light, 0.0, 1.0)
    front = np.flatnonzero(facing > 0)
    order = front[np.argsort(Y[F[front], 2].mean(1))]  # far to near
    colors = np.repeat(0.86 * shade[order, None], 3, axis=1)
    colors = np.clip(colors, 0, 1)
    pc = PolyCollection(Y[F[order]][:, :, :2], facecolors=colors, edgecolors=(0.35, 0.35, 0.35),
                        linewidths=0.25)
    ax.add_collection(pc)
    # vertex normals (area weighted) to keep only the hyperbolic vertices on the visible side
    vn = np.zeros_like(X)
    raw = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    for k in range(3):
        np.add.at(vn, F[:, k], raw)
    hyp = mesh.hyperbolic
    seen = hyp & (vn @ R[2] > 0)
    ax.scatter(Y[seen, 0], Y[seen, 1], s=9, c="red", edgecolors="darkred", linewidths=0.3, zorder=3)
    ax.set_xlim(-half, half)
    ax.set_ylim(-half, half)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for s in ax.spines.values():
        s.set_visible(False)
    ax.set_title(title, fontsize=8)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="sphere-deformed-320")
    ap.add_argument("--log-every", type=int, default=10)
    ap.add_argument("--max-steps", type=int, default=20000)
    ap.add_argument("--out", default="out/fig3")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (mesh,) = load_mesh(MODELS / f"{args.model}.obj").components
    # warm up the numba caches so the first run is not charged for loading them
    inflate(load_mesh(MODELS / "tetrahedron-4.obj").components[0], max_steps=5, log_every=1)

    runs = {}
    for mode in MODES:
        t0 = time.perf_counter()
        res = inflate(mesh, mode=mode, log_every=args.log_every, max_steps=args.max_steps)
        runs[mode] = (res, time.perf_counter() - t0)

    # ---------------------------------------------------------------- tables
    print(f"{args.model}: {mesh.n_vertices} vertices, {mesh.n_faces} faces, "
          f"{int(mesh.hyperbolic.sum())} hyperbolic; defaults, log every {args.log_every} steps")
    print()
    if0 = {}
    for mode in MODES:
        res = runs[mode][0]
        if0[mode] = first_if_reaching(res.history, 0)
    ratio = if0["constrained"] / if0["uniform"]
    print(f"{'mode':<12} {'steps':>6} {'seconds':>8} {'stop reason':<28} {'IF at HV=0':>10} {'paper IF':>8} "
          f"{'vol. change':>11}")
    for mode in MODES:
        res, secs = runs[mode]
        print(f"{mode:<12} {res.steps:>6} {secs:>8.3f} {res.stop_reason:<28} {if0[mode]:>10.4f} "
              f"{PAPER[mode][-1][0]:>8.4f} {res.history[-1, 3]:>+11.3f}")
    paper_ratio = PAPER["constrained"][-1][0] / PAPER["uniform"][-1][0]
    print(f"IF ratio constrained / uniform at HV=0: ours {ratio:.3f}, paper {paper_ratio:.3f}")
    print()
    print(f"{'mode':<12} {'paper IF':>8} {'paper HV':>8} {'our HV at that IF':>17} {'(step)':>7} "
          f"{'our IF when HV first reaches paper HV':>37}")
    for mode in MODES:
        hist = runs[mode][0].history
        for p_if, p_hv in PAPER[mode]:
            i = row_at_if(hist, p_if)
            beyond = "*" if p_if > hist[-1, 1] else " "
            print(f"{mode:<12} {p_if:>8.4f} {p_hv:>8d} {int(hist[i, 2]):>16d}{beyond} {int(hist[i, 0]):>7d} "
                  f"{first_if_reaching(hist, p_hv):>37.4f}")
    if any(p[-1][0] > runs[m][0].history[-1, 1] for m, p in PAPER.items()):
        print("* the paper's IF is beyond the end of our run (HV 0 reached earlier): last row shown")

    # ---------------------------------------------------------------- CSV
    files = []
    for mode in MODES:
        path = out / f"fig3_history_{mode}.csv"
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["step", "IF", "HV", "volume_change"])
            for step, IF, hv, dv in runs[mode][0].history:
                w.writerow([int(step), f"{IF:.6f}", int(hv), f"{dv:.6f}"])
        files.append(path)

    # ---------------------------------------------------------------- HV vs IF
    fig, ax = plt.subplots(figsize=(7, 4.6), dpi=150)
    for mode in MODES:
        hist = runs[mode][0].history
        ax.plot(hist[:, 1], hist[:, 2], color=COLORS[mode], lw=1.3, label=f"{mode} (ours)")
        pts = np.array(PAPER[mode])
        ax.plot(pts[:, 0], pts[:, 1], ls="none", marker="o" if mode == "uniform" else "s", ms=7,
                mfc="white", mec=COLORS[mode], mew=1.6, label=f"{mode} (paper)")
    ax.set_xlabel("inflation rate IF (mean vertex displacement, bounding-sphere radius = 1)")
    ax.set_ylabel("hyperbolic vertices HV")
    ax.set_title(f"Fig. 3: HV vs IF, {args.model} (uniform vs constrained inflation)")
    ax.set_xlim(left=-0.005)
    ax.set_ylim(bottom=-1)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = out / "fig3_hv_vs_if.png"
    fig.savefig(path)
    plt.close(fig)
    files.append(path)

    # ---------------------------------------------------------------- snapshots
    # second pass per mode with snapshots at the logged steps where HV first gets to the paper's values
    # (deterministic: the history must match the first pass)
    chosen = {}
    for mode in MODES:
        hist = runs[mode][0].history
        rows = [row_reaching(hist, p_hv) for _, p_hv in PAPER[mode]]
        # never reached (e.g. the uniform rise to 48 does not happen): the row with the nearest HV
        rows = [i if i >= 0 else int(np.argmin(np.abs(hist[:, 2] - p_hv))) for i, (_, p_hv) in zip(rows, PAPER[mode])]
        steps = [int(hist[i, 0]) for i in rows]
        res2 = inflate(mesh, mode=mode, log_every=args.log_every, max_steps=args.max_steps, snapshot_steps=steps)
        assert np.array_equal(res2.history[:, :3], hist[:, :3]), "second pass diverged"
        chosen[mode] = [(res2.snapshots[s], hist[i]) for s, i in zip(steps, rows)]
    V0 = mesh.vertices
    center = (V0.max(0) + V0.min(0)) / 2.0
    R = camera()
    half = 1.04 * max(np.abs((X - center) @ R[:2].T).max() for m in MODES for X, _ in chosen[m])
    ncol = max(len(v) for v in chosen.values())
    fig, axes = plt.subplots(len(MODES), ncol, figsize=(2.2 * ncol, 2.45 * len(MODES)), dpi=150)
    for r, mode in enumerate(MODES):
        for c, (X, row) in enumerate(chosen[mode]):
            render(axes[r, c], X, mesh.faces, center, half,
                   f"{mode} IF={row[1]:.4f} HV={int(row[2])}\n(step {int(row[0])}, paper HV {PAPER[mode][c][1]})")
    fig.suptitle(f"{args.model}: snapshots where HV first reaches the paper's HV values (red: hyperbolic vertices, visible side)",
                 fontsize=10)
    fig.tight_layout()
    path = out / "fig3_snapshots.png"
    fig.savefig(path)
    plt.close(fig)
    files.append(path)

    print()
    for p in files:
        print(f"wrote {p}")


if __name__ == "__main__":
    main()
