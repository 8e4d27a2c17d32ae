"""Batch jobs (issue 9): `make`, or a study, over many meshes, one isolated process per mesh.

In: glob patterns (or paths), an output folder, `MakeOptions`. Out of `run_batch`: DIR/<stem>/ per
mesh (what `make` writes) and DIR/summary.csv + DIR/summary.jsonl, one `BatchRow` per mesh. Out of
`run_study`: DIR/study-<name>.csv and DIR/study-<name>.svg, one row per mesh.

Isolation: every mesh runs in its own process -- a forkserver child locally, a subprocess
`python -m polyfold.apps.batch SPEC RESULT LOG` inside the task on Dask -- so a crash (segfault,
os._exit) or a hang in one mesh becomes that mesh's status and never stops the others. A hard
wall-clock limit per task (default 2 x time limit + 30 s) kills a task that hangs.

Test hook (tests/test_batch.py only): POLYFOLD_BATCH_FAULT="crash:NAME,segv:NAME,hang:NAME"
makes the task of the mesh file named NAME call os._exit(1), segfault, or sleep forever. The
parent reads it when a batch starts and puts it into the task spec, so it also reaches forkserver
children (started with an older environment) and Dask workers.

Only the standard library is imported at module level: Dask workers and the task processes
import this module, and `polyfold --help` must stay fast.
"""

from __future__ import annotations

import csv
import glob
import io
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections import deque
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

if TYPE_CHECKING:
    from ..pipeline.options import MakeOptions
    from ..pipeline.report import MakeReport

MESH_SUFFIXES = {".obj", ".off", ".stl", ".ply", ".glb", ".gltf"}
STAGES = ("load", "inflate", "segment", "unfold", "fold", "layout", "export")
FAILED = ("error", "timeout", "crashed")
STATUSES = ("ok", "skipped", *FAILED)
STUDIES = ("unfold", "cspace")
FAULT_ENV = "POLYFOLD_BATCH_FAULT"
SCHEDULER_ENV = "POLYFOLD_SCHEDULER"
# imported once by the forkserver, so each task process starts with them loaded (saves ~1 s each)
PRELOAD = ("polyfold.apps.batch", "polyfold.pipeline.make", "polyfold.formats.meshes", "polyfold.unfold.search",
           "polyfold.fold.plan", "polyfold.fold.tree", "polyfold.formats.fold", "polyfold.fabricate.pieces",
           "polyfold.fabricate.fit", "polyfold.fabricate.check", "polyfold.fabricate.pack", "polyfold.formats.svg",
           "polyfold.formats.pdf", "polyfold.formats.dxf", "polyfold.segment.segment", "polyfold.formats.raster",
           "polyfold.formats.png")


@dataclass(frozen=True)
class BatchRow:
    """One mesh of a make batch. Counts and stage seconds come from its report.json (None when
    make did not finish). total_s: wall-clock seconds of the task, process start to exit (for
    skipped meshes: the finished run's make seconds). error: one line, empty when ok/skipped."""

    mesh: str
    out: str = ""
    faces: int | None = None
    parts: int | None = None
    pieces: int | None = None
    pages: int | None = None
    load_s: float | None = None
    inflate_s: float | None = None
    segment_s: float | None = None
    unfold_s: float | None = None
    fold_s: float | None = None
    layout_s: float | None = None
    export_s: float | None = None
    total_s: float = 0.0
    status: str = "ok"
    error: str = ""


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


Row = BatchRow | UnfoldStudyRow | CspaceStudyRow
Progress = Callable[[Row, int, int], None]  # (finished row, rows done, rows in all)


@dataclass(frozen=True)
class BatchResult:
    """What a batch or study produced: rows in mesh order, the files written, wall seconds."""

    out_dir: Path
    rows: tuple[Row, ...]
    files: tuple[Path, ...]
    seconds: float

    @property
    def failed(self) -> tuple[Row, ...]:
        return tuple(r for r in self.rows if r.status in FAILED)

    def counts(self) -> dict[str, int]:
        """Rows per status, every status present (zeros included)."""
        return {s: sum(r.status == s for r in self.rows) for s in STATUSES}


# ----------------------------------------------------------------------------------------------
# Inputs


def expand(patterns: str | os.PathLike | Sequence[str | os.PathLike]) -> list[Path]:
    """Glob patterns (expanded here, '**' allowed) or plain paths -> mesh files, sorted, no
    duplicates. Raises PolyfoldError when nothing matches."""
    from ..errors import PolyfoldError

    if isinstance(patterns, (str, os.PathLike)):
        patterns = [patterns]
    found: dict[str, Path] = {}
    for pat in patterns:
        # an existing file is taken as named, even when its name holds glob characters ([, *, ?)
        hits = [os.fspath(pat)] if os.path.isfile(pat) else glob.glob(os.fspath(pat), recursive=True)
        for hit in hits:
            p = Path(hit)
            if p.is_file() and p.suffix.lower() in MESH_SUFFIXES:
                found.setdefault(os.path.realpath(p), p)
    if not found:
        raise PolyfoldError(f"no mesh files ({', '.join(sorted(MESH_SUFFIXES))}) match {' '.join(map(str, patterns))}")
    return sorted(found.values(), key=lambda p: str(p))


def out_names(meshes: Sequence[Path]) -> list[str]:
    """Folder name per mesh: its stem; stems that occur more than once get a short hash of the
    real path (stable whatever else is in the batch, so a rerun finds its earlier output)."""
    import hashlib

    stems = [p.stem for p in meshes]
    return [s if stems.count(s) == 1 else f"{s}-{hashlib.sha1(os.path.realpath(p).encode()).hexdigest()[:8]}"
            for s, p in zip(stems, meshes)]


def _faults() -> dict[str, str]:
    """The test hook: mesh file name -> crash | segv | hang."""
    out = {}
    for item in os.environ.get(FAULT_ENV, "").split(","):
        kind, _, name = item.strip().partition(":")
        if kind in ("crash", "segv", "hang") and name:
            out[name] = kind
    return out


def _finished_report(mesh: Path, out: Path, opts: MakeOptions) -> MakeReport | None:
    """The report.json in `out` if it is from a finished make of this mesh file with these options
    and newer than the mesh, else None. make moves report.json in last, so it marks a finished run."""
    from ..pipeline.report import MakeReport

    path = out / "report.json"
    try:
        if path.stat().st_mtime < mesh.stat().st_mtime:
            return None
        # a report of another layout (older version) is redone, not trusted
        report = MakeReport.from_dict(json.loads(path.read_text()))
    except (OSError, ValueError):
        return None
    return report if report.options == opts and report.input.file == mesh.name else None


def _make_values(report: MakeReport) -> dict:
    """BatchRow fields out of a make report."""
    stages = report.stages
    values = {f"{s}_s": getattr(stages, s).seconds for s in STAGES}
    return {**values, "faces": report.input.faces, "parts": stages.segment.parts, "pieces": len(report.pieces),
            "pages": stages.layout.pages}


def _row(cls: type, mesh: str, outcome: dict, **extra) -> Row:
    """A row of `cls` from a task outcome {status, error, seconds, values}."""
    names = {f.name for f in fields(cls)}
    values = {k: v for k, v in outcome.get("values", {}).items() if k in names}
    return cls(mesh=mesh, **values, **extra, total_s=float(outcome.get("seconds", 0.0)),
               status=outcome["status"], error=outcome.get("error", ""))


# ----------------------------------------------------------------------------------------------
# Inside the task process


def _one_line(exc: BaseException) -> str:
    from ..errors import PolyfoldError

    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, PolyfoldError):
        return text or type(exc).__name__
    return f"internal error ({type(exc).__name__}): {text}".rstrip(": ")


def _run_task(spec: dict) -> dict:
    """Run one task spec; -> {status: ok | error, error, values}."""
    fault = spec.get("fault")
    if fault == "crash":
        os._exit(1)
    if fault == "segv":
        import ctypes

        ctypes.string_at(0)  # reads address 0: a real segfault
    if fault == "hang":
        while True:
            time.sleep(3600)
    try:
        values = {"make": _task_make, "unfold": _task_unfold, "cspace": _task_cspace}[spec["kind"]](spec)
        return {"status": "ok", "error": "", "values": values}
    except Exception as exc:
        return {"status": "error", "error": _one_line(exc), "values": {}}


def _task_make(spec: dict) -> dict:
    from ..pipeline.make import make
    from ..pipeline.options import MakeOptions

    result = make(spec["mesh"], spec["out"], MakeOptions(**spec["options"]))
    return _make_values(result.report)


def _task_unfold(spec: dict) -> dict:
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


def _task_cspace(spec: dict) -> dict:
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


def _child_main(spec: dict, result_path: str, log_path: str) -> None:
    """Entry of a task process: output to the log (not the parent's terminal), a traceback of
    every fatal signal into it (faulthandler), the outcome as JSON into result_path."""
    import faulthandler

    log = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    sys.stdout.flush()
    sys.stderr.flush()
    os.dup2(log, 1)
    os.dup2(log, 2)
    faulthandler.enable()
    outcome = _run_task(spec)
    tmp = result_path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(outcome, fh)
    os.replace(tmp, result_path)  # the parent never reads half a result


def _outcome(exitcode: int | None, result_path: str, log_path: str, seconds: float) -> dict:
    """What a finished task process left: its result, else a 'crashed' outcome naming the exit
    code or signal (and the log's last line, e.g. faulthandler's 'Fatal Python error: ...')."""
    try:
        with open(result_path) as fh:
            return {**json.load(fh), "seconds": seconds}
    except (OSError, ValueError):
        pass
    if exitcode is not None and exitcode < 0:
        import signal

        try:
            why = f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            why = f"killed by signal {-exitcode}"
    else:
        why = f"exit code {exitcode}"
    try:
        with open(log_path, errors="replace") as fh:
            lines = [ln.strip() for ln in fh.read().splitlines() if ln.strip()]
    except OSError:
        lines = []
    fatal = [ln for ln in lines if ln.startswith("Fatal Python error")]
    last = fatal[0] if fatal else (lines[-1] if lines else "")
    return {"status": "crashed", "error": f"task process died ({why})" + (f": {last[:200]}" if last else ""),
            "seconds": seconds}


def _timeout(limit: float, seconds: float) -> dict:
    return {"status": "timeout", "error": f"killed at the hard limit of {limit:g} s", "seconds": seconds}


# ----------------------------------------------------------------------------------------------
# Running tasks: local processes or Dask


def _mp_context():
    """forkserver (a clean, single-threaded parent with polyfold preloaded; fork from a process that
    runs a progress-bar thread is unsafe) where it exists, else spawn."""
    import multiprocessing as mp

    if "forkserver" in mp.get_all_start_methods():
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(list(PRELOAD))
        return ctx
    return mp.get_context("spawn")


def _run_local(specs: list[dict], workers: int, on_done: Callable[[int, dict], None]) -> None:
    """Run every spec in its own process, at most `workers` at once; call on_done(index, outcome)
    as each finishes. A process past its spec's hard_limit is killed (status timeout)."""
    from multiprocessing.connection import wait

    ctx = _mp_context()
    tmp = tempfile.mkdtemp(prefix="polyfold-batch-")
    todo = deque(enumerate(specs))
    running: dict = {}  # sentinel -> (index, process, start, result path, log path)
    try:
        while todo or running:
            while todo and len(running) < workers:
                i, spec = todo.popleft()
                res, log = os.path.join(tmp, f"{i}.json"), os.path.join(tmp, f"{i}.log")
                proc = ctx.Process(target=_child_main, args=(spec, res, log), daemon=True,
                                   name=f"polyfold-batch-{i}")
                proc.start()
                running[proc.sentinel] = (i, proc, time.perf_counter(), res, log)
            deadline = min(t0 + specs[i]["hard_limit"] for i, _, t0, _, _ in running.values())
            ready = set(wait(list(running), timeout=max(0.0, deadline - time.perf_counter())))
            now = time.perf_counter()
            for sentinel, (i, proc, t0, res, log) in list(running.items()):
                if sentinel in ready:
                    proc.join()
                    outcome = _outcome(proc.exitcode, res, log, now - t0)
                elif now - t0 >= specs[i]["hard_limit"]:
                    proc.kill()
                    proc.join()
                    outcome = _timeout(specs[i]["hard_limit"], now - t0)
                else:
                    continue
                del running[sentinel]
                on_done(i, outcome)
    finally:  # interrupted: leave no task process behind
        for _, proc, _, _, _ in running.values():
            proc.kill()
            proc.join()
        shutil.rmtree(tmp, ignore_errors=True)


def _dask_task(spec: dict) -> dict:
    """Body of one Dask task: the job runs in a subprocess, so a crash or hang costs that
    subprocess and not the Dask worker; -> the same outcome dict as the local pool."""
    with tempfile.TemporaryDirectory(prefix="polyfold-task-") as tmp:
        spec_path, res, log = (os.path.join(tmp, n) for n in ("spec.json", "result.json", "task.log"))
        with open(spec_path, "w") as fh:
            json.dump(spec, fh)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([sys.executable, "-m", "polyfold.apps.batch", spec_path, res, log],
                                  stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  timeout=spec["hard_limit"])
        except subprocess.TimeoutExpired:  # run() has killed it
            return _timeout(spec["hard_limit"], time.perf_counter() - t0)
        return _outcome(proc.returncode, res, log, time.perf_counter() - t0)


def _run_dask(specs: list[dict], address: str, on_done: Callable[[int, dict], None]) -> None:
    """Submit every spec to the Dask scheduler at `address` (no retries: a task that failed is
    reported, not rerun); call on_done(index, outcome) as each finishes."""
    from ..errors import PolyfoldError

    try:
        from distributed import Client, as_completed
    except ImportError:
        raise PolyfoldError("--scheduler needs Dask: pip install 'dask[distributed]' "
                            "(the polyfold[batch] extra)") from None
    try:
        client = Client(address, timeout="15s")
    except (OSError, TimeoutError) as exc:
        raise PolyfoldError(f"cannot reach the Dask scheduler at {address}: {_one_line(exc)}") from None
    with client:
        token = os.urandom(4).hex()
        futures = {client.submit(_dask_task, spec, key=f"polyfold-batch-{token}-{i}", pure=False, retries=0): i
                   for i, spec in enumerate(specs)}
        for fut in as_completed(futures):
            try:
                outcome = fut.result()
            except Exception as exc:  # the Dask worker itself died (e.g. KilledWorker) or similar
                outcome = {"status": "crashed", "error": f"dask task failed: {_one_line(exc)}", "seconds": 0.0}
            on_done(futures[fut], outcome)


def _run(specs: list[dict], workers: int | None, scheduler: str | None, on_done: Callable[[int, dict], None]) -> None:
    """Local pool, or Dask when a scheduler address is given (argument, else $POLYFOLD_SCHEDULER)."""
    scheduler = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if not specs:
        return
    if scheduler:
        _run_dask(specs, scheduler, on_done)
    else:
        _run_local(specs, max(1, workers or default_workers()), on_done)


def default_workers() -> int:
    """CPUs this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


# ----------------------------------------------------------------------------------------------
# Batch make


def run_batch(patterns: str | os.PathLike | Sequence[str | os.PathLike], out_dir: str | os.PathLike,
              opts: MakeOptions | None = None, *, workers: int | None = None, scheduler: str | None = None,
              hard_limit: float | None = None, force: bool = False, progress: Progress | None = None) -> BatchResult:
    """`make` every mesh matching `patterns` into out_dir/<stem>/, each in its own process.

    workers: local processes at once (default: CPUs); scheduler: Dask scheduler address (default
    $POLYFOLD_SCHEDULER; then workers is ignored). hard_limit: wall-clock seconds after which a
    task is killed (default 2 x opts.time_limit + 30). force: redo meshes that have a finished
    report.json with the same options (otherwise skipped). progress(row, done, total) after each
    mesh. Writes out_dir/summary.csv and summary.jsonl; -> BatchResult (rows in mesh order)."""
    from ..pipeline.options import MakeOptions, check_options

    opts = opts or MakeOptions()
    check_options(opts)  # one error for options make would reject on every mesh, not N
    t0 = time.perf_counter()
    meshes = expand(patterns)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = out_names(meshes)
    limit = hard_limit if hard_limit is not None else 2 * opts.time_limit + 30
    faults = _faults()
    rows: list[Row | None] = [None] * len(meshes)
    done = [0]

    def finish(i: int, row: Row) -> None:
        rows[i] = row
        done[0] += 1
        if progress:
            progress(row, done[0], len(meshes))

    specs, index = [], []
    for i, (mesh, name) in enumerate(zip(meshes, names)):
        report = None if force else _finished_report(mesh, out / name, opts)
        if report is not None:
            finish(i, _row(BatchRow, str(mesh), {"status": "skipped", "values": _make_values(report),
                                                 "seconds": report.seconds}, out=name))
            continue
        specs.append({"kind": "make", "mesh": os.path.abspath(mesh), "out": os.path.abspath(out / name),
                      "options": asdict(opts), "hard_limit": limit, "fault": faults.get(mesh.name)})
        index.append(i)
    _run(specs, workers, scheduler,
         lambda k, outcome: finish(index[k], _row(BatchRow, str(meshes[index[k]]), outcome, out=names[index[k]])))
    files = write_summary([r for r in rows if r is not None], out)
    return BatchResult(out_dir=out, rows=tuple(rows), files=files, seconds=time.perf_counter() - t0)


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def rows_csv(rows: Sequence[Row]) -> str:
    """CSV text: a header of the row dataclass's field names, then one line per row."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([f.name for f in fields(rows[0])] if rows else [f.name for f in fields(BatchRow)])
    for r in rows:
        w.writerow([_cell(getattr(r, f.name)) for f in fields(r)])
    return buf.getvalue()


def write_summary(rows: Sequence[Row], out_dir: Path) -> tuple[Path, ...]:
    """out_dir/summary.csv and summary.jsonl (one JSON object per row), each written atomically."""
    from ..formats.files import atomic_write

    csv_path, jsonl_path = out_dir / "summary.csv", out_dir / "summary.jsonl"
    atomic_write(csv_path, rows_csv(rows))
    atomic_write(jsonl_path, "".join(json.dumps(asdict(r)) + "\n" for r in rows))
    return csv_path, jsonl_path


# ----------------------------------------------------------------------------------------------
# Studies


def run_study(study: str, patterns: str | os.PathLike | Sequence[str | os.PathLike], out_dir: str | os.PathLike, *,
              runs: int = 5, samples: int = 1000, seed: int = 1, time_limit: float = 60.0, contact_tol: float = 1e-7,
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
    budget = time_limit * (runs if study == "unfold" else 1)
    limit = hard_limit if hard_limit is not None else 2 * budget + 30
    faults = _faults()
    cls = UnfoldStudyRow if study == "unfold" else CspaceStudyRow
    specs = [{"kind": study, "mesh": os.path.abspath(m), "runs": runs, "samples": samples, "seed": seed,
              "time_limit": time_limit, "contact_tol": contact_tol, "hard_limit": limit, "fault": faults.get(m.name)}
             for m in meshes]
    rows: list[Row | None] = [None] * len(meshes)
    done = [0]

    def finish(i: int, outcome: dict) -> None:
        rows[i] = _row(cls, str(meshes[i]), outcome)
        done[0] += 1
        if progress:
            progress(rows[i], done[0], len(meshes))

    _run(specs, workers, scheduler, finish)
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


def main(argv: Sequence[str] | None = None) -> int:
    """`python -m polyfold.apps.batch SPEC.json RESULT.json LOG`: run one task (the Dask path)."""
    spec_path, result_path, log_path = (argv if argv is not None else sys.argv[1:])[:3]
    with open(spec_path) as fh:
        spec = json.load(fh)
    _child_main(spec, result_path, log_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
