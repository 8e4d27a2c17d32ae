"""Build quality of `polyfold make` (issue 18), measured from the files it writes (not a test).

    .venv/bin/python bench/bench_build.py [--quick] [--markdown] [--no-generated] [--keep DIR]
                                          [--only NAME ...] [--time-limit 60]

Runs `polyfold.make` (API, defaults: A4, 150 mm) on every closed shared model
(../shared/models/*.obj or $POLYFOLD_MODELS) and on generated meshes (noisy icospheres and
Loop-subdivided shared models of 500-2000 faces, seeded, built here with trimesh), then measures
every folder with the tests' own readers (tests/sheet_reader.py: SVG, DXF with ezdxf, PDF with
pypdf; tests/build_metrics.py: the measures, against the mesh loaded with trimesh): pieces,
pages, paper utilisation, glue edges, untabbed edges, reduced tabs, labels under 2 mm cap
height, label overlaps (pairs of boxes / labels crossing a line), flat regions cut, wrong-way
tab fold marks (SVG, also checked in DXF and PDF), smallest printed edge and make's seconds.
Then the issue's targets, PASS or FAIL. `--quick`: the five models with Blender page counts.
Without pypdf (`pip install -e '.[test]'`) the PDF is not measured.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the independent readers live with the tests

from build_metrics import Measures, measure_folder  # noqa: E402

MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
# A4 pages of Blender's paper-model export at 150 mm (issue 18): make should need no more
BLENDER_PAGES = {"bunny-128": 3, "horse-302": 3, "fish-472": 2, "bunny-348": 5, "bumpy-528": 5}
UTILISATION_TARGET = 0.45


# ----------------------------------------------------------------------------------------------
# Generated meshes


def _obj_text(vertices: np.ndarray, faces: np.ndarray, comment: str) -> str:
    return (f"# {comment}\n" + "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
            + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces.tolist()))


def noisy_icosphere(subdivisions: int, sigma: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere with every vertex moved along its radius by a factor 1 + N(0, sigma)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = np.asarray(sphere.vertices, dtype=float)
    r = 1.0 + np.random.default_rng(seed).normal(0.0, sigma, len(v))
    return v * np.clip(r, 0.5, 1.5)[:, None], np.asarray(sphere.faces)


def loop_subdivided(path: Path, iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """A shared model smoothed by Loop subdivision (each pass: 4 times the faces, none coplanar)."""
    import trimesh

    mesh = trimesh.load(str(path), process=False, maintain_order=True, force="mesh")
    v, f = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces)
    for _ in range(iterations):
        v, f = trimesh.remesh.subdivide_loop(v, f)
    return np.asarray(v, dtype=float), np.asarray(f)


def decimated(path: Path, faces: int) -> tuple[np.ndarray, np.ndarray]:
    """A shared model Loop-subdivided twice (16 times its faces; more where that is under 3 times
    `faces`) and collapsed back to about `faces` faces by quadric edge collapse
    (fast-simplification, polyfold's own simplifier's): faces of every size and shape, as a scan
    decimated for papercraft has."""
    import fast_simplification
    import trimesh

    v, f = loop_subdivided(path, 2)
    while len(f) < 3 * faces:
        v, f = trimesh.remesh.subdivide_loop(v, f)
    out_v, out_f = fast_simplification.simplify(v.astype(np.float32), f.astype(np.int32), 1.0 - faces / len(f))
    return np.asarray(out_v, dtype=float), np.asarray(out_f, dtype=np.int64)


def hull_of_points(n: int, seed: int, stretch: float = 1.6) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of n random points on a sphere stretched `stretch` times along x: 2n - 4
    faces, many of them slivers."""
    import trimesh

    p = np.random.default_rng(seed).normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    p[:, 0] *= stretch
    hull = trimesh.convex.convex_hull(p)
    return np.asarray(hull.vertices, dtype=float), np.asarray(hull.faces)


def torus(around: int, across: int, r_tube: float = 0.35) -> tuple[np.ndarray, np.ndarray]:
    """A torus (radius 1, tube r_tube) of around x across quads, each two triangles."""
    u, w = np.meshgrid(2 * np.pi * np.arange(around) / around, 2 * np.pi * np.arange(across) / across, indexing="ij")
    v = np.stack([(1 + r_tube * np.cos(w)) * np.cos(u), (1 + r_tube * np.cos(w)) * np.sin(u), r_tube * np.sin(w)],
                 axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(around), np.arange(across), indexing="ij")
    a, b = i * across + j, (i + 1) % around * across + j
    c, d = (i + 1) % around * across + (j + 1) % across, i * across + (j + 1) % across
    f = np.concatenate([np.stack([a, b, c], axis=-1).reshape(-1, 3), np.stack([a, c, d], axis=-1).reshape(-1, 3)])
    return v, f


GENERATED = (  # name, builder (seeded)
    ("noisy-ico3-s03", lambda: noisy_icosphere(3, 0.03, 1)),
    ("noisy-ico3-s08", lambda: noisy_icosphere(3, 0.08, 2)),
    ("bunny-128-loop1", lambda: loop_subdivided(MODELS / "bunny-128.obj", 1)),
    ("horse-302-loop1", lambda: loop_subdivided(MODELS / "horse-302.obj", 1)),
    ("bunny-348-loop1", lambda: loop_subdivided(MODELS / "bunny-348.obj", 1)),
    ("star-4split-96-loop2", lambda: loop_subdivided(MODELS / "star-4split-96.obj", 2)),
)


def write_generated(folder: Path, generated=None, by: str = "bench/bench_build.py") -> list[Path]:
    """The generated meshes ((name, builder) pairs; default GENERATED) as OBJ files in folder."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, build in generated or GENERATED:
        v, f = build()
        path = folder / f"{name}.obj"
        path.write_text(_obj_text(v, f, f"{name}: generated by {by} ({len(f)} faces)"))
        out.append(path)
    return out


# ----------------------------------------------------------------------------------------------
# Running and measuring


@dataclass
class Row:
    name: str
    faces: int
    generated: bool
    seconds: float
    measures: Measures | None = None
    error: str = ""


def run_one(path: Path, out: Path, time_limit: float, generated: bool) -> Row:
    """make (defaults) on one mesh into out, then its measures."""
    from polyfold.errors import PolyfoldError
    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    n_faces = sum(1 for line in path.read_text().splitlines() if line.startswith("f "))
    t0 = time.perf_counter()
    try:
        make(path, out, MakeOptions(time_limit=time_limit))
    except PolyfoldError as exc:
        return Row(path.stem, n_faces, generated, time.perf_counter() - t0, error=str(exc))
    seconds = time.perf_counter() - t0
    return Row(path.stem, n_faces, generated, seconds, measure_folder(out, path))


COLUMNS = ("model", "faces", "pieces", "pages", "util", "glue", "untabbed", "reduced", "small lbl", "lbl overlap",
           "flat cut", "wrong way", "min edge", "s")


def cells(row: Row) -> list[str]:
    m = row.measures
    if m is None:
        return [row.name, str(row.faces)] + [""] * (len(COLUMNS) - 3) + [f"{row.seconds:.1f}"]
    pages = f"{m.pages}" + (f" ({BLENDER_PAGES[row.name]})" if row.name in BLENDER_PAGES else "")
    ways = sorted(set(m.wrong_way.values()))
    wrong = str(m.wrong_way["svg"]) if len(ways) == 1 else "/".join(f"{f} {n}" for f, n in m.wrong_way.items())
    return [row.name, str(row.faces), str(m.pieces), pages, f"{m.utilisation:.2f}", str(m.glue_edges), str(m.untabbed),
            str(m.reduced_tabs), f"{m.small_labels}/{m.labels}", f"{m.label_pairs}/{m.label_lines}", str(m.flat_cut),
            wrong, f"{m.smallest_edge_mm:.1f}", f"{row.seconds:.1f}"]


def print_table(rows: list[Row], markdown: bool) -> None:
    table = [list(COLUMNS)] + [cells(r) for r in rows]
    if markdown:
        print("| " + " | ".join(table[0]) + " |")
        print("|" + "|".join("---" if k == 0 else "---:" for k in range(len(COLUMNS))) + "|")
        for line in table[1:]:
            print("| " + " | ".join(line) + " |")
    else:
        widths = [max(len(line[k]) for line in table) for k in range(len(COLUMNS))]
        for line in table:
            print("  ".join(c.ljust(w) if k == 0 else c.rjust(w) for k, (c, w) in enumerate(zip(line, widths))))
    for r in rows:
        if r.error:
            print(f"{r.name}: make failed: {r.error}")
        elif r.measures.notes:
            print(f"{r.name}: {'; '.join(r.measures.notes)}")


def targets(rows: list[Row]) -> list[tuple[str, bool, str]]:
    """(target, passed, detail) for the issue's targets over the measured rows."""
    done = [r for r in rows if r.measures is not None]

    def zero(what: str, value) -> tuple[str, bool, str]:
        bad = [(r.name, value(r.measures)) for r in done if value(r.measures)]
        total = sum(v for _, v in bad)
        detail = f"{total} over {len(bad)} of {len(done)} models" + (
            f" (most: {max(bad, key=lambda b: b[1])[0]} {max(v for _, v in bad)})" if bad else "")
        return what, not bad, detail

    out = [
        zero("untabbed glue edges = 0", lambda m: m.untabbed),
        zero("label overlaps (pairs + labels on a line) = 0", lambda m: m.label_pairs + m.label_lines),
        zero("wrong-way tab fold marks = 0 (SVG, DXF, PDF)", lambda m: max(m.wrong_way.values())),
        zero("flat regions cut = 0", lambda m: m.flat_cut),
    ]
    page_rows = [r for r in done if r.name in BLENDER_PAGES]
    over = [f"{r.name} {r.measures.pages} > {BLENDER_PAGES[r.name]}" for r in page_rows
            if r.measures.pages > BLENDER_PAGES[r.name]]
    out.append(("pages <= Blender's", bool(page_rows) and not over,
                ", ".join(over) if over else f"{len(page_rows)} models within"))
    if done:
        mean = statistics.fmean(r.measures.utilisation for r in done)
        out.append((f"mean utilisation >= {UTILISATION_TARGET}", mean >= UTILISATION_TARGET,
                    f"{mean:.3f} over {len(done)} models"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only the five models with Blender page counts")
    ap.add_argument("--markdown", action="store_true", help="print the table as markdown")
    ap.add_argument("--no-generated", action="store_true", help="only the shared models")
    ap.add_argument("--only", nargs="+", default=None, help="only these models (file stems)")
    ap.add_argument("--keep", type=Path, default=None, help="keep the make folders (and generated meshes) here")
    ap.add_argument("--time-limit", type=float, default=60.0)
    args = ap.parse_args()
    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp)
        make(MODELS / "tetrahedron-4.obj", Path(tmp) / "warm", MakeOptions(size=50.0))  # compile / load caches
        shared = sorted(MODELS.glob("*.obj"))
        generated = [] if args.no_generated or args.quick else write_generated(work / "generated")
        todo = [(p, False) for p in shared] + [(p, True) for p in generated]
        if args.quick:
            todo = [(p, g) for p, g in todo if p.stem in BLENDER_PAGES]
        if args.only:
            todo = [(p, g) for p, g in todo if p.stem in args.only]
        rows = []
        t0 = time.perf_counter()
        for path, gen in todo:
            rows.append(run_one(path, work / "made" / path.stem, args.time_limit, gen))
            print(f"[{len(rows)}/{len(todo)}] {path.stem}: {rows[-1].seconds:.1f} s", file=sys.stderr, flush=True)
        print_table(rows, args.markdown)
        print()
        for what, ok, detail in targets(rows):
            print(f"{'PASS' if ok else 'FAIL'}  {what}: {detail}")
        print(f"\n{len(rows)} models, {time.perf_counter() - t0:.0f} s (make + measures); pages in brackets: "
              "Blender's; small lbl: labels under 2 mm cap height / labels; lbl overlap: overlapping pairs / "
              "labels crossing a line")


if __name__ == "__main__":
    main()
