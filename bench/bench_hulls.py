"""Convex approximation benchmark (not a test): `approximate.hulls.approximate_hulls` on the closed
shared models after `segment` at several tau.

    .venv/bin/python bench/bench_hulls.py [--tau 0.02 0.05 0.1] [--planes]

Table 1 (markdown): parts, triangles per part before/after the facet simplification (mean/max),
Hausdorff distances approx -> part patch / patch -> approx / symmetric (max over parts, % of the
bbox diagonal), the largest growth from dropping facets (%), the volume ratio (sum of
approximations / model), the largest pairwise intersection volume by manifold3d over the model
volume, the number of cuts, seconds (approximate_hulls only, after one warm-up run).
--planes, table 2: the volume removed by all cuts (% of the model volume) at tau 0.02 and the
default with each set of plane candidates (the comparison in hulls.py's docstring); "error" where a
restricted set cannot separate a pair without cutting a hull below MIN_KEEP.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from polyfold.approximate.error import overlap_volumes
from polyfold.mesh.geometry import signed_volume
from polyfold.approximate.hulls import approximate_hulls, hull_meshes
from polyfold.errors import PolyfoldError
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.mesh import Mesh
from polyfold.segment.segment import DEFAULT_TAU, segment

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
CLOSED = ["bunny-128", "bunny-348", "horse-302", "fish-472", "sphere-deformed-320", "bumpy-528", "periscope-28",
          "star-24", "moneybox-128"]
PLANE_SETS = [("shared",), ("centroids",), ("overlap",), ("shared", "centroids", "overlap"),
              ("shared", "centroids", "overlap", "refine")]


def load(name: str) -> Mesh:
    return load_mesh(MODELS / f"{name}.obj").mesh


def table(taus: list[float]) -> None:
    approximate_hulls(load("star-24"), segment(load("star-24")))  # warm-up: numba kernels
    print("| model | tau | parts | faces before mean/max | faces after mean/max | H out % | H in % | H sym % "
          "| growth % | volume ratio | overlap / volume | cuts | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in CLOSED:
        mesh = load(name)
        for tau in taus:
            seg = segment(mesh, tau=tau)
            r = approximate_hulls(mesh, seg)
            vol = overlap_volumes(r.parts)
            off = (vol - np.diag(np.diag(vol))).max() / (r.volume.sum() / r.volume_ratio)
            print(f"| {name} | {tau:g} | {r.n_parts} | {r.faces_before.mean():.1f} / {r.faces_before.max()} "
                  f"| {r.faces_after.mean():.1f} / {r.faces_after.max()} | {100 * r.hausdorff_out_max:.2f} "
                  f"| {100 * r.hausdorff_in_max:.2f} | {100 * r.hausdorff_max:.2f} | {100 * r.simplify_error.max():.2f} "
                  f"| {r.volume_ratio:.3f} | {off:.1e} | {len(r.planes)} | {r.seconds:.2f} |")


def planes_table(taus: list[float]) -> None:
    print("| model | tau | parts | " + " | ".join("+".join(s) for s in PLANE_SETS) + " |")
    print("|---|---|---|" + "---|" * len(PLANE_SETS))
    for name in CLOSED:
        mesh = load(name)
        model_vol = signed_volume(mesh.vertices, mesh.faces)
        for tau in taus:
            seg = segment(mesh, tau=tau)
            if seg.n_parts < 2:
                continue
            row = []
            for methods in PLANE_SETS:
                t0 = time.perf_counter()
                try:
                    _, _, _, _, cuts, (_, scale) = hull_meshes(mesh, seg, methods=methods)
                except PolyfoldError as exc:  # a hull cut down to MIN_KEEP
                    row.append(f"error ({exc})"[:40])
                    continue
                removed = sum(c[4] for c in cuts) * scale ** 3
                row.append(f"{100 * removed / model_vol:.2f} ({time.perf_counter() - t0:.1f} s)")
            print(f"| {name} | {tau:g} | {seg.n_parts} | " + " | ".join(row) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tau", type=float, nargs="+", default=[0.02, 0.05, 0.1])
    ap.add_argument("--planes", action="store_true", help="also compare the plane candidates")
    args = ap.parse_args()
    table(args.tau)
    if args.planes:
        print()
        planes_table([0.02, DEFAULT_TAU])


if __name__ == "__main__":
    main()
