"""Big inputs against the time limit (issue 20), measured through the CLI (not a test).

    .venv/bin/python bench/bench_big.py [--time-limit 60] [--markdown] [--keep DIR]

Builds closed meshes of 20,000-100,000 faces here (noisy icospheres and a Loop-subdivided shared
model, seeded, with trimesh), then runs `polyfold info` and `polyfold make --time-limit T` on each
as a user would (one process each) and prints: faces, make's exit code and wall seconds (the limit
holds when make finishes or stops by T plus the interpreter's start), what the one line said,
`info`'s seconds, and each process's peak memory (from wait4). Target: every make done or stopped
within T + 5 s, with exit 0 or a one-line "stopped at --time-limit" (exit 1).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("POLYFOLD_MODELS", ROOT.parent / "shared" / "models"))
CLI = [sys.executable, "-m", "polyfold"]
SLACK_S = 5.0  # the interpreter's start and the mesh's loading come before make's clock starts


def meshes(work: Path) -> list[Path]:
    """The generated inputs: noisy icospheres of 20,480 and 81,920 faces and bunny-348 Loop-subdivided
    to 22,272 and 89,088 faces (or what of it the shared models hold)."""
    import trimesh

    out = []
    rng = np.random.default_rng(20)
    for level in (5, 6):
        sphere = trimesh.creation.icosphere(subdivisions=level)
        sphere.vertices *= 1.0 + 0.01 * rng.standard_normal((len(sphere.vertices), 1))
        path = work / f"noisy-ico{level}-{len(sphere.faces)}.obj"
        sphere.export(path)
        out.append(path)
    src = MODELS / "bunny-348.obj"
    if src.exists():
        bunny = trimesh.load(src, force="mesh", process=False)
        for times in (3, 4):
            sub = bunny.subdivide_loop(iterations=times)
            path = work / f"bunny-348-loop{times}-{len(sub.faces)}.obj"
            sub.export(path)
            out.append(path)
    return out


def run(args: list[str]) -> tuple[int, float, float, str]:
    """(exit code, wall seconds, peak memory in MB, last line of stderr) of one CLI process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([*CLI, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    lines = err.strip().splitlines()
    return proc.returncode, time.perf_counter() - t0, usage.ru_maxrss / 1024, lines[-1] if lines else ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--keep", type=Path, default=None, help="Keep the meshes and outputs here.")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="polyfold-bench-big-"))
    work.mkdir(parents=True, exist_ok=True)
    rows, ok = [], True
    for path in meshes(work):
        faces = sum(1 for line in path.read_text().splitlines() if line.startswith("f "))
        icode, isec, imem, _ = run(["info", str(path)])
        code, sec, mem, line = run(["make", str(path), "-o", str(work / path.stem), "-q",
                                    "--time-limit", f"{args.time_limit:g}"])
        held = sec <= args.time_limit + SLACK_S and (code == 0 or (code == 1 and "stopped at --time-limit" in line))
        ok &= held and icode == 0
        said = "made" if code == 0 else line.split(" while ", 1)[-1].split(": its", 1)[0][:60]
        rows.append((path.stem, faces, code, sec, mem, isec, imem, said, held))
    head = ("mesh", "faces", "make exit", "make s", "make MB", "info s", "info MB", "make stopped while", "limit held")
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print(f"| {r[0]} | {r[1]:,} | {r[2]} | {r[3]:.1f} | {r[4]:.0f} | {r[5]:.1f} | {r[6]:.0f} | {r[7]} | "
                  f"{'yes' if r[8] else 'NO'} |")
    else:
        for r in rows:
            print(f"{r[0]:28s} {r[1]:7,d} exit {r[2]} {r[3]:6.1f} s {r[4]:6.0f} MB | info {r[5]:5.1f} s "
                  f"{r[6]:5.0f} MB | {r[7]} | {'held' if r[8] else 'NOT HELD'}")
    print(f"\n{'PASS' if ok else 'FAIL'}  make done or stopped within --time-limit {args.time_limit:g} s "
          f"(+{SLACK_S:g} s start-up) on {len(rows)} meshes of 20k-100k faces; info exit 0")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
