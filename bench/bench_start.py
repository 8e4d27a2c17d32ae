"""Where a user waits (issue 23), not a test: the first run, start-up, and peak memory.

    .venv/bin/python bench/bench_start.py [--skip-cold] [--sizes 128,1500,5000] [--no-server]

Every row is a fresh `polyfold` process (the CLI as a user runs it), timed wall-clock, with the
peak memory of it and the processes it starts (PSS, sampled: pages they share counted once) from
a second run of the same command (sampling costs CPU time: the timed run is not sampled; the cold
rows and `server start`, which cannot run twice alike, are timed while sampled).
Cold rows use an empty numba cache of their own ($NUMBA_CACHE_DIR in a temporary folder, so the
project's cache is left alone):

- cold make: `polyfold make` of bunny-128 with nothing compiled (a bare `pip install`), as it
  runs (two or more cores: the fold stage's kernels compile in a second process, `warmup.Beside`)
  and on one core (`taskset -c 0`: everything in one process);
- warm-up: `polyfold warm-up` into an empty cache (what `make setup` adds), then make after it;
- warm: `--help`, `info` (of the bunny, of the bunny as STL and of a noisy sphere of 5,120
  faces), `make` with the kernels cached (every later run; ahead of time where
  `polyfold warm-up` built them, `polyfold.jit`), the make again just in time (POLYFOLD_AHEAD=off:
  numba's dispatchers from its cache), and where the warm make's time goes: until its first
  progress line (start-up: imports; it reads the mesh next), until its summary line, and until
  the process has ended;
- served (`--server`, on by default): the same warm rows and make rows through `polyfold server`
  (`apps.server`: a resident process that forks a warm child per command), started in a runtime
  folder of its own; memory there is the server's process tree (the server, the child and its
  workers) less nothing: the server's own pages count too;
- make at N faces: generated closed meshes (bunny-128 itself; noisy icospheres refined to about N
  faces, one per noise seed of --sphere-seeds; shared models Loop-subdivided (--dense: bunny-348
  once, 1,392 faces, horse-302 once, 1,208, fish-472 once, 1,888, moneybox-128 twice, 2,048,
  bumpy-528 once, 2,112: models whose small faces crowd their labels at 150 mm; --decimated:
  bumpy-528, bunny-348, fish-472 and horse-302 Loop-subdivided twice and decimated to 1,500
  faces, faces of every size and shape; the convex hull of 752 random points, 1,500 faces, many
  slivers; a 50 x 15 torus, 1,500 faces), warm cache, fold on, A4 at 150 mm: seconds and peak
  memory.
Prints a table; compile seconds per stage are the cold make's own (report.json "compile_seconds"),
and the machine's speed before and after the rows (`machine_probe.py`: the host's hours differ).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CLI = [str(ROOT / ".venv" / "bin" / "polyfold")] if (ROOT / ".venv" / "bin" / "polyfold").exists() else [sys.executable, "-m", "polyfold"]
BUNNY = ROOT / "examples" / "bunny-128.obj"
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
DENSE = "bunny-348:1,horse-302:1,fish-472:1,moneybox-128:2,bumpy-528:1"  # (--dense) name:Loop subdivisions
DECIMATED = "bumpy-528,bunny-348,fish-472,horse-302"  # (--decimated) Loop-subdivided twice, then to 1,500 faces
sys.path.insert(0, str(ROOT / "bench"))
from machine_probe import kernels_ahead, probe_seconds  # noqa: E402


def _tree_pss_mb(pid: int) -> float:
    """Proportional set size (MB) of process `pid` and its descendants (Linux /proc; 0 elsewhere):
    pages the forked workers share with make count once, split between them."""
    def tree(p: int) -> list[int]:
        try:
            kids = open(f"/proc/{p}/task/{p}/children").read().split()
        except OSError:
            return [p]
        return [p] + [q for k in kids for q in tree(int(k))]

    total = 0.0
    for p in tree(pid):
        try:
            with open(f"/proc/{p}/smaps_rollup") as f:
                total += next(int(line.split()[1]) for line in f if line.startswith("Pss:")) / 1024.0
        except (OSError, StopIteration):
            pass
    return total


OWN = dict(os.environ, POLYFOLD_SERVER="off")  # every row in a process of its own, server or not


def run(args: list[str], env: dict | None = None, prefix: list[str] = [], server: int | None = None
        ) -> tuple[float, float, int]:
    """(wall seconds, peak memory MB, exit code) of a CLI command (run under `prefix`, e.g.
    taskset), run twice: timed alone, then with its memory sampled (reading /proc costs CPU
    time: tens of ms a sample for a process of hundreds of MB, and a served command has two
    process trees to read). Memory: the peak of its process tree's PSS (make's forked workers
    included), sampled every 0.1 s, plus that of the process tree of the `server` that runs its
    command; where /proc cannot say, the process's own peak RSS."""
    t0 = time.perf_counter()
    proc = subprocess.run(prefix + CLI + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                          env=OWN if env is None else env)
    wall = time.perf_counter() - t0
    _, mb, code = _sampled(args, env, prefix, server)
    return wall, mb, code if proc.returncode == 0 else proc.returncode


def _sampled(args: list[str], env: dict | None, prefix: list[str], server: int | None) -> tuple[float, float, int]:
    import threading

    t0 = time.perf_counter()
    proc = subprocess.Popen(prefix + CLI + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env=OWN if env is None else env)
    peak, done = [0.0], threading.Event()

    def sample() -> None:
        while not done.wait(0.1):  # (reading smaps costs: rarer samples keep it out of the times)
            mb = _tree_pss_mb(proc.pid) + (_tree_pss_mb(server) if server else 0.0)
            peak[0] = max(peak[0], mb)

    watcher = threading.Thread(target=sample, daemon=True)
    watcher.start()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    done.set()
    watcher.join()
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read().decode() if proc.stderr else ""
    if proc.returncode != 0:
        print(f"  ! {' '.join(args)}: exit {proc.returncode}: {err.strip().splitlines()[-1:]}", file=sys.stderr)
    return wall, peak[0] or usage.ru_maxrss / 1024.0, proc.returncode


def timeline(args: list[str], env: dict | None = None) -> tuple[float, float, float]:
    """(first progress line, last line, exit) in seconds from the start of a CLI command run with
    its progress on: how long it starts (imports, until it reads the mesh), works, and ends."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(CLI + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=OWN if env is None else env)
    assert proc.stderr is not None
    stamps = [time.perf_counter() - t0 for _line in proc.stderr]
    proc.wait()
    end = time.perf_counter() - t0
    return (stamps[0], stamps[-1], end) if stamps else (end, end, end)


def stages(out: Path) -> dict[str, float]:
    report = json.loads((out / "report.json").read_text())
    return {k: float(v["seconds"]) for k, v in report.get("stages", {}).items()
            if isinstance(v, dict) and v.get("seconds")}


def sphere_obj(path: Path, faces: int, seed: int = 1) -> int:
    """A noisy icosphere of about `faces` faces (refined by subdivision), written as OBJ."""
    import trimesh

    sub = max(1, int(round(np.log(faces / 20) / np.log(4))))
    sphere = trimesh.creation.icosphere(subdivisions=sub)
    v = np.asarray(sphere.vertices, dtype=float)
    v = v * np.clip(1 + np.random.default_rng(seed).normal(0, 0.03, len(v)), 0.8, 1.2)[:, None]
    f = np.asarray(sphere.faces)
    path.write_text("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f))
    return len(f)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-cold", action="store_true", help="no cold rows (each compiles for about a minute)")
    ap.add_argument("--sizes", default="128,1500,5000", help="face counts of the make rows")
    ap.add_argument("--sphere-seeds", default="1,2,3", help="noise draws of each size's sphere (a sphere each)")
    ap.add_argument("--dense", default=DENSE, help="shared models to Loop-subdivide, name:times,...")
    ap.add_argument("--no-dense", action="store_true", help="leave out the Loop-subdivided models")
    ap.add_argument("--decimated", default=DECIMATED,
                    help="shared models to subdivide and decimate to 1,500 faces (with a 1,500-face hull and torus)")
    ap.add_argument("--no-decimated", action="store_true", help="leave out the decimated models, hull and torus")
    ap.add_argument("--no-server", action="store_true", help="no rows through `polyfold server`")
    a = ap.parse_args()
    rows: list[tuple[str, float, float, str]] = []
    probe_before = probe_seconds()
    tmp = Path(tempfile.mkdtemp(prefix="bench-start-"))
    if not a.skip_cold:
        env = dict(OWN, NUMBA_CACHE_DIR=str(tmp / "cache-cold"))
        wall, mb, _ = _sampled(["make", str(BUNNY), "-o", str(tmp / "cold"), "-q"], env, [], None)
        cold_report = json.loads((tmp / "cold" / "report.json").read_text())
        rows.append(("cold make bunny-128 (bare pip install)", wall, mb,
                     "the fold stage's kernels compile in a second process meanwhile (its memory counted)"))
        if shutil.which("taskset"):  # the same on one core: one process compiles everything
            env1 = dict(OWN, NUMBA_CACHE_DIR=str(tmp / "cache-cold-1"))
            wall, mb, _ = _sampled(["make", str(BUNNY), "-o", str(tmp / "cold1"), "-q"], env1, ["taskset", "-c", "0"],
                                   None)
            rows.append(("  the same on one core (taskset -c 0)", wall, mb, "one process"))
        env = dict(OWN, NUMBA_CACHE_DIR=str(tmp / "cache-setup"))
        wall, mb, _ = _sampled(["warm-up"], env, [], None)
        rows.append(("warm-up (make setup adds it)", wall, mb, ""))
        wall, mb, _ = run(["make", str(BUNNY), "-o", str(tmp / "after"), "-q"], env)
        rows.append(("make bunny-128 after warm-up", wall, mb, ""))
        compile_s = {c["stage"]: c["seconds"] for c in cold_report["compile_seconds"]}
        rows.append(("  of it compiling, by stage (report.json)", sum(compile_s.values()), 0.0,
                     ", ".join(f"{k} {v:.1f}" for k, v in compile_s.items())))
    run(["make", str(BUNNY), "-o", str(tmp / "prime"), "-q"])  # the project's cache, as after setup
    warm = (("info bunny-128", ["info", str(BUNNY)]),
            ("make bunny-128 (warm)", ["make", str(BUNNY), "-o", str(tmp / "warm"), "-q"]))
    # `info` of other inputs: an STL (read by polyfold, not trimesh) and a mesh of 5,120 faces (its
    # hull compiled: no scipy)
    from bench_build import _obj_text, noisy_icosphere
    from polyfold.formats.meshes import load_mesh, write_mesh

    bunny = load_mesh(BUNNY).mesh
    write_mesh(tmp / "bunny-128.stl", bunny.vertices, bunny.faces)
    (tmp / "sphere-5120.obj").write_text(_obj_text(*noisy_icosphere(4, 0.02, 1), "bench_start"))
    infos = (("info bunny-128 as STL", ["info", str(tmp / "bunny-128.stl")]),
             ("info noisy sphere, 5,120 faces", ["info", str(tmp / "sphere-5120.obj")]))
    ahead = kernels_ahead(OWN)
    for label, args in (("--help", ["--help"]), warm[0], *infos, warm[1]):
        best = min((run(args) for _ in range(3)), key=lambda r: r[0])
        how = "" if label == "--help" else ("; kernels ahead of time (no numba)" if ahead
                                            else "; no ahead-of-time kernels for this code: run `polyfold warm-up`")
        rows.append((label, best[0], best[1], "three runs: the fastest" + how))
    best = min((run(warm[1][1], dict(OWN, POLYFOLD_AHEAD="off")) for _ in range(3)), key=lambda r: r[0])
    rows.append(("  the same just in time (POLYFOLD_AHEAD=off)", best[0], best[1],
                 "numba imported, kernels loaded from its cache; three runs: the fastest"))
    first, last, end = min((timeline(["make", str(BUNNY), "-o", str(tmp / "timeline")]) for _ in range(3)),
                           key=lambda t: t[2])
    rows.append(("  of it: start-up, make, end", end, 0.0,
                 f"{first:.2f} until the mesh is read, {last - first:.2f} making it, {end - last:.2f} after the summary"
                 " (progress lines stamped; fastest of three)"))
    served, server = None, None
    if not a.no_server:
        runtime = Path(tempfile.mkdtemp(prefix="pfb"))  # (short: a Unix socket's path)
        served = dict(os.environ, XDG_RUNTIME_DIR=str(runtime), POLYFOLD_SERVER="require")
        wall, mb, code = _sampled(["server", "start"], served, [], None)
        status = subprocess.run([*CLI, "server", "status"], env=served, capture_output=True, text=True).stdout
        server = int(status.split("pid ")[1].split(",")[0]) if code == 0 else None
        rows.append(("server start (once)", wall, _tree_pss_mb(server) if server else mb,
                     "imports and loads every kernel; memory: the server"))
        for label, args in warm:
            best = min((run(args, served, server=server) for _ in range(3)), key=lambda r: r[0])
            rows.append((f"{label}, served", best[0], best[1], "three runs: the fastest"))
    meshes = []  # (label, path)
    for n in (int(s) for s in a.sizes.split(",")):
        if n == 128:
            continue
        for seed in (int(s) for s in a.sphere_seeds.split(",")):
            mesh = tmp / f"sphere-{n}-{seed}.obj"
            got = sphere_obj(mesh, n, seed)
            meshes.append((f"make noisy sphere, {got} faces, noise seed {seed}", mesh))
    for name, times in ([] if a.no_dense else [item.split(":") for item in a.dense.split(",")]):
        if not (MODELS / f"{name}.obj").exists():
            continue
        sys.path.insert(0, str(ROOT / "bench"))
        from bench_build import loop_subdivided

        v, f = loop_subdivided(MODELS / f"{name}.obj", int(times))
        mesh = tmp / f"{name}-loop{times}.obj"
        mesh.write_text("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
                        + "".join(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in f))
        meshes.append((f"make {name} Loop-subdivided{' twice' if times == '2' else ''}, {len(f)} faces", mesh))
    if not a.no_decimated:
        sys.path.insert(0, str(ROOT / "bench"))
        from bench_build import decimated, hull_of_points, torus

        built = [(f"{name} decimated", lambda name=name: decimated(MODELS / f"{name}.obj", 1500))
                 for name in a.decimated.split(",") if name and (MODELS / f"{name}.obj").exists()]
        built += [("hull of 752 random points", lambda: hull_of_points(752, 7)), ("torus 50 x 15", lambda: torus(50, 15))]
        for label, build in built:
            v, f = build()
            mesh = tmp / f"{label.split()[0]}-{len(meshes)}.obj"
            mesh.write_text("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
                            + "".join(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in f))
            meshes.append((f"make {label}, {len(f)} faces", mesh))
    for k, (label, mesh) in enumerate(meshes):
        for how, env in (("", None), (", served", served)):
            if how and served is None:
                continue
            wall, mb, code = run(["make", str(mesh), "-o", str(tmp / f"make-{k}{how}"), "-q"], env,
                                 server=server if how else None)
            note = "" if code == 0 else f"exit {code}"
            if code == 0:
                st = stages(tmp / f"make-{k}{how}")
                note = ", ".join(f"{k} {v:.1f}" for k, v in st.items() if v > 0.05)
            rows.append((label + how, wall, mb, note))
    if served is not None:
        subprocess.run([*CLI, "server", "stop"], env=served, capture_output=True)
    print(f"{'what':52s} {'wall s':>8s} {'peak MB':>8s}  notes")
    for label, wall, mb, note in rows:
        print(f"{label:52s} {wall:8.2f} {mb:8.0f}  {note}")
    print(f"machine probe (bench/machine_probe.py): {probe_before:.3f} s before the rows, {probe_seconds():.3f} s after")


if __name__ == "__main__":
    main()
