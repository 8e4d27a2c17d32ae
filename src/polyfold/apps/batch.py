"""Batch jobs (issue 9): `make` over many meshes, one isolated process per mesh.

In: glob patterns (or paths), an output folder, `MakeOptions`. Out of `run_batch`: DIR/<stem>/ per
mesh (what `make` writes) and DIR/summary.csv + DIR/summary.jsonl, one `BatchRow` per mesh. Also
what every batch job shares (the studies of study.py too): the inputs (`expand`), rows out of
task outcomes, `BatchResult`, the CSV text. Each mesh runs in its own process (isolation.py); a
hard wall-clock limit per task (default 2 x time limit + 30 s) kills a task that hangs.

Only the standard library (and isolation.py, which imports only it) is imported at module level:
the task processes import this module, and `polyfold --help` must stay fast.
"""

from __future__ import annotations

import csv
import glob
import io
import json
import os
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence, TypeAlias

from .isolation import faults, hard_limit_for, run_tasks, task_spec

if TYPE_CHECKING:
    from ..pipeline.options import MakeOptions
    from ..pipeline.report import MakeReport
    from .study import CspaceStudyRow, UnfoldStudyRow

MESH_SUFFIXES = {".obj", ".off", ".stl", ".ply", ".glb", ".gltf"}
STAGES = ("load", "inflate", "segment", "unfold", "fold", "layout", "export")
FAILED = ("error", "timeout", "crashed")
STATUSES = ("ok", "skipped", *FAILED)


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


Row: TypeAlias = "BatchRow | UnfoldStudyRow | CspaceStudyRow"  # the study rows are study.py's
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
# Inputs and rows


def expand(patterns: str | os.PathLike | Sequence[str | os.PathLike], exclude: str | os.PathLike | None = None
           ) -> list[Path]:
    """Glob patterns (expanded here, '**' allowed) or plain paths -> mesh files, sorted, no
    duplicates, none inside the folder `exclude` (a batch's own output folder: its part-K.obj are
    not inputs). Raises PolyfoldError when nothing matches."""
    from ..errors import PolyfoldError

    if isinstance(patterns, (str, os.PathLike)):
        patterns = [patterns]
    found: dict[str, Path] = {}
    skip = os.path.join(os.path.realpath(exclude), "") if exclude is not None else None
    for pat in patterns:
        # an existing file is taken as named, even when its name holds glob characters ([, *, ?)
        hits = [os.fspath(pat)] if os.path.isfile(pat) else glob.glob(os.fspath(pat), recursive=True)
        for hit in hits:
            p = Path(hit)
            real = os.path.realpath(p)
            if p.is_file() and p.suffix.lower() in MESH_SUFFIXES and not (skip and real.startswith(skip)):
                found.setdefault(real, p)
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


def outcome_row(cls: type, mesh: str, outcome: dict, **extra) -> Row:
    """A row of `cls` from a task outcome {status, error, seconds, values}."""
    names = {f.name for f in fields(cls)}
    values = {k: v for k, v in outcome.get("values", {}).items() if k in names}
    return cls(mesh=mesh, **values, **extra, total_s=float(outcome.get("seconds", 0.0)),
               status=outcome["status"], error=outcome.get("error", ""))


def row_collector(total: int, progress: Progress | None) -> tuple[list[Row | None], Callable[[int, Row], None]]:
    """(rows, finish): `total` empty rows in mesh order, and finish(i, row), which fills row i and
    calls progress(row, rows done, total)."""
    rows: list[Row | None] = [None] * total
    done = [0]

    def finish(i: int, row: Row) -> None:
        rows[i] = row
        done[0] += 1
        if progress:
            progress(row, done[0], total)

    return rows, finish


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


# ----------------------------------------------------------------------------------------------
# Batch make


def finished_report(mesh: Path, out: Path, opts: MakeOptions) -> MakeReport | None:
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


def make_values(report: MakeReport) -> dict:
    """BatchRow fields out of a make report."""
    stages = report.stages
    values = {f"{s}_s": getattr(stages, s).seconds for s in STAGES}
    return {**values, "faces": report.input.faces, "parts": stages.segment.parts, "pieces": len(report.pieces),
            "pages": stages.layout.pages}


def make_task(spec: dict) -> dict:
    """The task of one mesh (in its own process): make it into spec["out"]; -> BatchRow values."""
    from ..pipeline.make import make
    from ..pipeline.options import MakeOptions

    result = make(spec["mesh"], spec["out"], MakeOptions(**spec["options"]))
    return make_values(result.report)


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
    meshes = expand(patterns, exclude=out_dir)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = out_names(meshes)
    limit = hard_limit_for(opts.time_limit, hard_limit)
    hook = faults()
    rows, finish = row_collector(len(meshes), progress)
    specs, index = [], []
    for i, (mesh, name) in enumerate(zip(meshes, names)):
        report = None if force else finished_report(mesh, out / name, opts)
        if report is not None:
            finish(i, outcome_row(BatchRow, str(mesh), {"status": "skipped", "values": make_values(report),
                                                        "seconds": report.seconds}, out=name))
            continue
        specs.append(task_spec(make_task, mesh, limit, hook.get(mesh.name), out=os.path.abspath(out / name),
                               options=asdict(opts)))
        index.append(i)
    run_tasks(specs, workers, scheduler,
              lambda k, outcome: finish(index[k], outcome_row(BatchRow, str(meshes[index[k]]), outcome,
                                                              out=names[index[k]])))
    files = write_summary([r for r in rows if r is not None], out)
    return BatchResult(out_dir=out, rows=tuple(rows), files=files, seconds=time.perf_counter() - t0)


def write_summary(rows: Sequence[Row], out_dir: Path) -> tuple[Path, ...]:
    """out_dir/summary.csv and summary.jsonl (one JSON object per row), each written atomically."""
    from ..formats.files import atomic_write

    csv_path, jsonl_path = out_dir / "summary.csv", out_dir / "summary.jsonl"
    atomic_write(csv_path, rows_csv(rows))
    atomic_write(jsonl_path, "".join(json.dumps(asdict(r)) + "\n" for r in rows))
    return csv_path, jsonl_path
