"""Segmentation benchmark (not a test): part counts, agreement with the paper, speed, and the
paper's Table 2 shape (whole mesh vs segmented route: net seconds, path seconds, pieces).

    .venv/bin/python bench/bench_segment.py [--seeds 3] [--time-limit 30] [--png-dir docs/segment] [--sweep]

Tables:
1. parts at the default tau (0.05) vs the paper's counts, seconds;
2. Rand index vs ../shared/models/paper-parts at the paper's part count (horse 7, fish 5);
3. speed on ~500 and ~2000 face meshes (default tau and --parts 5);
4. whole vs parts: unfold + fold every part of `segment(parts=K)` vs the whole mesh.
fish-472 and its paper parts self-intersect in the folded shape by ~2.4e-4 of the model size (see
MODELS.md), so the fish rows use a contact tolerance of 1e-3 (0.15 mm on a 150 mm model).
--sweep: the weight sweep behind segment.W_SEAM / SEED_ANGLE_DEG / W_COMPACT.
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from polyfold.segment import segment as S
from polyfold.errors import PolyfoldError
from polyfold.fold.plan import plan_fold
from polyfold.formats.meshes import load_mesh
from polyfold.fold.tree import FoldTree, collides
from polyfold.mesh.mesh import Mesh
from polyfold.formats.png import write_mesh_png
from polyfold.formats.raster import part_colors
from polyfold.unfold.search import unfold

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
PAPER = [("periscope-28", 2), ("periscope2-44", 3), ("bunny-128", 3), ("fish-472", 5), ("horse-302", 7)]
CONTACT = {"fish-472": 1e-3}


def load(name: str) -> Mesh:
    return load_mesh(MODELS / f"{name}.obj").mesh


def paper_labels(mesh: Mesh, group: str) -> np.ndarray:
    tree = cKDTree(mesh.vertices[mesh.faces].mean(axis=1))
    labels = np.full(mesh.n_faces, -1)
    for k, p in enumerate(sorted((MODELS / "paper-parts" / group).glob("part-*.obj"))):
        part = trimesh.load(p, process=False, force="mesh")
        labels[tree.query(np.asarray(part.triangles_center))[1]] = k
    return labels


def net_and_path(mesh: Mesh, seed: int, time_limit: float, contact_tol: float) -> dict:
    t0 = time.perf_counter()
    net, _ = unfold(mesh, seed=seed, time_limit=time_limit)
    t1 = time.perf_counter()
    tree = FoldTree.from_net(net, contact_tol)
    out = {"pieces": net.n_pieces, "net_s": t1 - t0, "dof": len(tree.creases), "path": False, "path_s": float("nan")}
    if net.n_pieces > 1 or collides(tree, tree.goal):
        return out
    try:
        path = plan_fold(tree, time_limit=time_limit, seed=seed)
    except PolyfoldError:
        return out
    out.update(path=path is not None, path_s=time.perf_counter() - t1)
    return out


def subdivided(mesh: Mesh) -> Mesh:
    v, f = trimesh.remesh.subdivide(mesh.vertices, mesh.faces)
    return Mesh(np.asarray(v, float), np.asarray(f, np.int64))


def noisy_sphere(subdivisions: int) -> Mesh:
    s = trimesh.creation.icosphere(subdivisions=subdivisions)
    rng = np.random.default_rng(0)
    return Mesh(s.vertices * (1 + 0.03 * rng.standard_normal((len(s.vertices), 1))), np.asarray(s.faces, np.int64))


def table_counts(png_dir: Path | None) -> None:
    print(f"\n1. parts at the default tau = {S.DEFAULT_TAU}")
    print(f"{'model':<16} {'faces':>5} {'paper':>5} {'ours':>5} {'max conc':>8} {'seconds':>7}")
    for name, k in PAPER:
        mesh = load(name)
        t0 = time.perf_counter()
        seg = S.segment(mesh)
        dt = time.perf_counter() - t0
        print(f"{name:<16} {mesh.n_faces:>5} {k:>5} {seg.n_parts:>5} {seg.concavity.max():>8.4f} {dt:>7.3f}")
        if png_dir is not None:
            png_dir.mkdir(parents=True, exist_ok=True)
            write_mesh_png(png_dir / f"{name}.png", mesh.vertices, mesh.faces, part_colors(seg.n_parts)[seg.labels],
                           width=480, height=360)
            segk = S.segment(mesh, parts=k)
            write_mesh_png(png_dir / f"{name}-{k}parts.png", mesh.vertices, mesh.faces,
                           part_colors(segk.n_parts)[segk.labels], width=480, height=360)


def table_rand() -> None:
    print("\n2. Rand index vs the paper's decomposition (same part count)")
    print(f"{'model':<16} {'parts':>5} {'RI':>6} {'tau':>7}  target")
    for name, group, k in (("horse-302", "horse", 7), ("fish-472", "fish", 5)):
        mesh = load(name)
        seg = S.segment(mesh, parts=k)
        ri = S.rand_index(seg.labels, paper_labels(mesh, group))
        print(f"{name:<16} {seg.n_parts:>5} {ri:>6.3f} {seg.tau:>7.4f}  {'>= 0.85' if group == 'horse' else ''}")


def table_speed() -> None:
    print("\n3. speed (targets: <= 1 s at ~500 faces, <= 10 s at ~2000 faces)")
    print(f"{'mesh':<24} {'faces':>5} {'default s':>9} {'parts':>5} {'--parts 5 s':>11}")
    cases = [("bumpy-528", load("bumpy-528")), ("fish-472", load("fish-472")),
             ("noisy sphere", noisy_sphere(3)), ("horse-302 subdivided", subdivided(load("horse-302"))),
             ("fish-472 subdivided", subdivided(load("fish-472"))),
             ("bumpy-528 subdivided", subdivided(load("bumpy-528"))), ("noisy sphere", noisy_sphere(4))]
    for name, mesh in cases:
        t0 = time.perf_counter()
        seg = S.segment(mesh)
        t1 = time.perf_counter()
        S.segment(mesh, parts=5)
        t2 = time.perf_counter()
        print(f"{name:<24} {mesh.n_faces:>5} {t1 - t0:>9.3f} {seg.n_parts:>5} {t2 - t1:>11.3f}")


def table_whole_vs_parts(seeds: int, time_limit: float) -> None:
    print(f"\n4. whole mesh vs segmented (parts = paper count); mean over {seeds} seeds, time limit {time_limit:g} s per search")
    print(f"{'model':<14} {'route':<6} {'parts':>5} {'DOF/part':<22} {'seg s':>6} {'net s':>7} {'path s':>7} "
          f"{'total':>7} {'pieces':>6} {'paths':>6} {'speedup':>7}")
    for name, k in PAPER:
        mesh = load(name)
        tol = CONTACT.get(name, 1e-7)
        whole, parts = [], []
        for seed in range(1, seeds + 1):
            whole.append(net_and_path(mesh, seed, time_limit, tol))
            t0 = time.perf_counter()
            seg = S.segment(mesh, parts=k)
            seg_s = time.perf_counter() - t0
            rows = [net_and_path(p, seed, time_limit, tol) for p in seg.parts]
            parts.append({"seg_s": seg_s, "rows": rows})
        w_net = np.mean([r["net_s"] for r in whole])
        w_path_ok = all(r["path"] for r in whole)
        w_path = np.mean([r["path_s"] for r in whole]) if w_path_ok else float("nan")
        w_total = w_net + (w_path if w_path_ok else time_limit)
        print(f"{name:<14} {'whole':<6} {1:>5} {whole[0]['dof']:<22} {'-':>6} {w_net:>7.3f} "
              f"{w_path if w_path_ok else float('nan'):>7.3f} {w_total:>7.3f}{'' if w_path_ok else '+'} "
              f"{np.mean([r['pieces'] for r in whole]):>6.1f} {sum(r['path'] for r in whole):>3}/{seeds:<2}")
        seg_s = np.mean([p["seg_s"] for p in parts])
        net_s = np.mean([sum(r["net_s"] for r in p["rows"]) for p in parts])
        ok = all(r["path"] for p in parts for r in p["rows"])
        path_s = np.mean([sum(r["path_s"] for r in p["rows"]) for p in parts]) if ok else float("nan")
        total = seg_s + net_s + (path_s if ok else 0.0)
        dofs = ",".join(str(r["dof"]) for r in parts[0]["rows"])
        n_paths = sum(all(r["path"] for r in p["rows"]) for p in parts)
        print(f"{'':<14} {'parts':<6} {len(parts[0]['rows']):>5} {dofs:<22} {seg_s:>6.3f} {net_s:>7.3f} {path_s:>7.3f} "
              f"{total:>7.3f} {np.mean([sum(r['pieces'] for r in p['rows']) for p in parts]):>6.1f} "
              f"{n_paths:>3}/{seeds:<2} {w_total / total:>6.1f}x")
    print("('+': no path within the time limit for some seed; the limit is counted as its path time.)")


def sweep() -> None:
    print("\nweight sweep: Rand index (horse 7, fish 5) and default-tau part counts (periscope, periscope2, bunny, fish, horse)")
    hm, fm = load("horse-302"), load("fish-472")
    hp, fp = paper_labels(hm, "horse"), paper_labels(fm, "fish")
    others = [load(n) for n, _ in PAPER]
    orig = S._run
    for wc, ws, ang in itertools.product([0.0, 0.05, 0.1], [0.5, 1.0, 2.0, 4.0, 6.0], [5.0, 10.0, 12.0, 15.0]):
        S._run = lambda m, tau, target, seeds, **kw: orig(m, tau, target, seeds, w_compact=wc, w_seam=ws)
        S.SEED_ANGLE_DEG = ang
        try:
            ri_h = S.rand_index(S.segment(hm, parts=7).labels, hp)
            ri_f = S.rand_index(S.segment(fm, parts=5).labels, fp)
            counts = [S.segment(m).n_parts for m in others]
        finally:
            S._run = orig
        print(f"w_compact {wc:<4} w_seam {ws:<4} angle {ang:<4}  horse {ri_h:.3f}  fish {ri_f:.3f}  counts {counts}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--time-limit", type=float, default=30.0)
    ap.add_argument("--png-dir", type=Path, default=None, help="write a picture of each segmentation here")
    ap.add_argument("--sweep", action="store_true", help="only run the weight sweep")
    args = ap.parse_args()
    S.segment(load("tetrahedron-4"))  # compile / load the numba caches first
    net_and_path(load("tetrahedron-4"), 0, 10, 1e-7)
    if args.sweep:
        sweep()
        return
    table_counts(args.png_dir)
    table_rand()
    table_speed()
    table_whole_vs_parts(args.seeds, args.time_limit)


if __name__ == "__main__":
    main()
