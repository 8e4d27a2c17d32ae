"""--faces on meshes with sharp edges and flat sides, and on curved ones (issue 21), through the API
(not a test).

    .venv/bin/python bench/bench_simplify.py [--markdown]

CAD-like shared models (cube, stars, prisms, the periscope, a torus) midpoint-subdivided to
6,000-12,000 faces (flat sides of many triangles, sharp edges), a cylinder, and curved meshes
(bunny-348 Loop-subdivided to 22,272 faces, a noisy 20,480-face icosphere) simplified to 4x the
original face count and to 300 faces: faces after, the exact Hausdorff distance to the input over
its bounding-box diagonal, the smallest face angle, the faces under 5 degrees, seconds. For each,
the collapse alone (fast-simplification at its default aggressiveness) beside it: what making the
flat regions whole first (`mesh.flat`) and the tries of `mesh.simplify` change.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))


def meshes():
    import trimesh

    from polyfold.mesh.mesh import Mesh

    for name in ("cube-12", "star-24", "l-prism-div-44", "u-prism-28", "periscope-28", "star-prism-36",
                 "torus-12x6-144"):
        path = MODELS / f"{name}.obj"
        if not path.exists():
            continue
        tm = trimesh.load(path, process=False, force="mesh")
        n = len(tm.faces)
        while len(tm.faces) < 6000:
            tm = tm.subdivide()
        yield f"{name} (subdivided)", Mesh(tm.vertices, tm.faces), n
    cyl = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=64).subdivide().subdivide()
    yield "cylinder-64 (subdivided)", Mesh(cyl.vertices, cyl.faces), 252
    if (MODELS / "bunny-348.obj").exists():
        bunny = trimesh.load(MODELS / "bunny-348.obj", process=False, force="mesh").subdivide_loop(iterations=3)
        yield "bunny-348 loop3", Mesh(bunny.vertices, bunny.faces), 348
    sphere = trimesh.creation.icosphere(subdivisions=5)
    sphere.vertices *= 1.0 + 0.01 * np.random.default_rng(20).standard_normal((len(sphere.vertices), 1))
    yield "noisy-ico5", Mesh(sphere.vertices, sphere.faces), 320


def main() -> int:
    import fast_simplification

    from polyfold.mesh.mesh import Mesh
    from polyfold.mesh.repair import LoadedMesh
    from polyfold.mesh.simplify import hausdorff, min_angles_deg, simplify

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    head = ("mesh", "faces", "asked", "faces after", "surface moved", "min angle", "< 5°", "s",
            "collapse alone: moved", "min angle", "< 5°")
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|---|" + "---:|" * (len(head) - 1))
    else:
        print("  ".join(head))
    for name, mesh, n_orig in meshes():
        diag = mesh.bbox_diagonal
        for target in (4 * n_orig, 300):
            t0 = time.perf_counter()
            done = simplify(LoadedMesh(name, mesh, (mesh,), ()), target)
            seconds = time.perf_counter() - t0
            out = done.loaded.mesh
            angles = min_angles_deg(out.vertices, out.faces)
            p, f = fast_simplification.simplify(mesh.vertices, mesh.faces.astype(np.int32), target_count=target)
            alone = Mesh(np.asarray(p, dtype=np.float64), np.asarray(f, dtype=np.int64))
            alone_angles = min_angles_deg(alone.vertices, alone.faces)
            row = (name, f"{mesh.n_faces:,}", f"{target:,}", f"{out.n_faces:,}", f"{done.hausdorff:.2g}",
                   f"{angles.min():.1f}°", str(int((angles < 5).sum())), f"{seconds:.2f}",
                   f"{hausdorff(mesh, alone) / diag:.2g}", f"{alone_angles.min():.1f}°",
                   str(int((alone_angles < 5).sum())))
            print(("| " + " | ".join(row) + " |") if args.markdown else "  ".join(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
