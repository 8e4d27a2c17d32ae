"""Process isolation for batch jobs (issue 9): every task in its own process, locally or on Dask.

In: task specs (JSON-able dicts, made by `task_spec`: which function runs, on which mesh, its
hard limit) and a callback. Out: one outcome dict per task, {status, error, seconds, values},
status ok | error (the task raised) | crashed (the process died) | timeout (killed at the limit).

Isolation: a task runs in its own process -- a forkserver child locally, a subprocess
`python -m polyfold.apps.isolation SPEC RESULT LOG` inside the task on Dask -- so a crash
(segfault, os._exit) or a hang in one task becomes that task's status and never stops the others.
A hard wall-clock limit per task kills a task that hangs.

Nothing outlives the batch: every task process leads its own process group (whatever it starts
is killed with it, `_kill`), exits when the batch process is gone (even by SIGKILL; then the
forkserver and the resource tracker, whose pipes only the batch and its tasks hold, exit too), asks
the kernel to kill it when the process that forked it dies (PR_SET_PDEATHSIG) and sets an alarm a
little past its hard limit (in case nobody is left to kill it). SIGTERM to the
batch process ends it like Ctrl+C: its tasks are killed and its temporary folder removed; a
temporary folder left by a batch that was SIGKILLed is removed by the next batch
(`_remove_stale_temps`: the folder names its process id).

Test hook (tests/apps/test_batch.py only): POLYFOLD_BATCH_FAULT="crash:NAME,segv:NAME,hang:NAME"
makes the task of the mesh file named NAME call os._exit(1), segfault, or sleep forever. The
parent reads it when a batch starts (`faults`) and puts it into the task spec, so it also reaches
forkserver children (started with an older environment) and Dask workers.

Only the standard library (and polyfold.deadline, errors and formats.files, which import only
it) is imported at module level: Dask workers and the task processes import this module, and `polyfold --help` must stay fast.
"""

from __future__ import annotations

import importlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import deque
from pathlib import Path
from typing import Callable, Sequence

from ..errors import one_line
from ..formats.files import atomic_write

FAULT_ENV = "POLYFOLD_BATCH_FAULT"
SCHEDULER_ENV = "POLYFOLD_SCHEDULER"
# imported once by the forkserver, so each task process starts with them loaded (saves ~1 s each):
# the task modules and what make, unfold and the studies import lazily (make's own imports bring
# in every stage). The forkserver skips a name it cannot import without a word, so
# tests/apps/test_batch.py checks them.
PRELOAD = ("polyfold.apps.isolation", "polyfold.apps.batch", "polyfold.apps.study", "polyfold.pipeline.make",
           "polyfold.formats.meshes", "polyfold.inflate.inflate", "polyfold.fold.cspace")

WATCH_S = 0.5  # a task process looks this often whether its batch process is still there
ALARM_GRACE_S = 10.0  # a task's own alarm rings this long after its hard limit (the parent kills first)
TEMP_PREFIX = "polyfold-batch-"  # + the batch process id + "-": its temporary folder
ENTRY = "polyfold.apps.isolation"  # `python -m ENTRY SPEC RESULT LOG` runs one task (the Dask path)
OnDone = Callable[[int, dict], None]  # (index of the spec, its outcome)


# ----------------------------------------------------------------------------------------------
# Task specs


def faults() -> dict[str, str]:
    """The test hook: mesh file name -> crash | segv | hang."""
    out = {}
    for item in os.environ.get(FAULT_ENV, "").split(","):
        kind, _, name = item.strip().partition(":")
        if kind in ("crash", "segv", "hang") and name:
            out[name] = kind
    return out


def task_spec(task: Callable[[dict], dict], mesh: Path, hard_limit: float, fault: str | None, **args) -> dict:
    """The spec of one task: `task(spec)` -> values (a module-level function: a fresh process
    imports it by name) on `mesh` (made absolute), killed after hard_limit seconds; fault: the
    test hook's fault for this mesh (None: none); args: what the task reads besides."""
    return {"task": f"{task.__module__}:{task.__qualname__}", "mesh": os.path.abspath(mesh), **args,
            "hard_limit": hard_limit, "fault": fault}


def hard_limit_for(budget: float, hard_limit: float | None) -> float:
    """The hard limit of a task whose searches may take `budget` seconds: hard_limit when given,
    else 2 x budget + 30 s."""
    return hard_limit if hard_limit is not None else 2 * budget + 30


# ----------------------------------------------------------------------------------------------
# Inside the task process


def run_task(spec: dict) -> dict:
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
        module, _, name = spec["task"].partition(":")
        values = getattr(importlib.import_module(module), name)(spec)
        return {"status": "ok", "error": "", "values": values}
    except Exception as exc:
        return {"status": "error", "error": one_line(exc), "values": {}}


def _leash(hard_limit: float, batch_pid: int | None) -> None:
    """In a task process: lead its own process group, die with the process that forked it
    (Linux: the Dask worker's subprocess), die by SIGALRM a little past the hard limit, and exit
    within WATCH_S of the batch process (batch_pid) going (a forkserver child: the forkserver
    stays while its children hold its pipe, so it is the batch that is watched)."""
    import math
    import signal

    try:
        os.setpgid(0, 0)
    except OSError:
        pass  # already a group leader (the Dask path's subprocess may be)
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    signal.alarm(max(1, math.ceil(hard_limit + ALARM_GRACE_S)))
    if batch_pid is not None:  # the forkserver outlives the batch while a task runs: watch the batch itself
        import threading

        def watch() -> None:
            while True:
                try:
                    os.kill(batch_pid, 0)
                except ProcessLookupError:
                    os._exit(1)
                except PermissionError:
                    return
                time.sleep(WATCH_S)

        threading.Thread(target=watch, name="polyfold-batch-watch", daemon=True).start()


def child_main(spec: dict, result_path: str, log_path: str) -> None:
    """Entry of a task process: on a leash (`_leash`), output to the log (not the parent's
    terminal), a traceback of every fatal signal into it (faulthandler), the outcome as JSON into
    result_path."""
    import faulthandler

    _leash(float(spec.get("hard_limit", 3600.0)), spec.get("batch_pid"))
    log = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    sys.stdout.flush()
    sys.stderr.flush()
    os.dup2(log, 1)
    os.dup2(log, 2)
    faulthandler.enable()
    atomic_write(result_path, json.dumps(run_task(spec)))  # the parent never reads half a result


# ----------------------------------------------------------------------------------------------
# Outcomes


def process_outcome(exitcode: int | None, result_path: str, log_path: str, seconds: float) -> dict:
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


def timeout_outcome(limit: float, seconds: float) -> dict:
    return {"status": "timeout", "error": f"killed at the hard limit of {limit:g} s", "seconds": seconds}


# ----------------------------------------------------------------------------------------------
# Running tasks: local processes or Dask


def run_tasks(specs: Sequence[dict], workers: int | None, scheduler: str | None, on_done: OnDone) -> None:
    """Every spec in its own process: the local pool (at most `workers` at once, default: CPUs),
    or Dask when a scheduler address is given (argument, else $POLYFOLD_SCHEDULER); call
    on_done(index, outcome) as each finishes."""
    scheduler = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if not specs:
        return
    if scheduler:
        _run_dask(list(specs), scheduler, on_done)
    else:
        _run_local(list(specs), max(1, workers or default_workers()), on_done)


def default_workers() -> int:
    """CPUs this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _mp_context():
    """forkserver (a clean, single-threaded parent with polyfold preloaded; fork from a process that
    runs a progress-bar thread is unsafe) where it exists, else spawn."""
    import multiprocessing as mp

    if "forkserver" in mp.get_all_start_methods():
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(list(PRELOAD))
        return ctx
    return mp.get_context("spawn")


def _run_local(specs: list[dict], workers: int, on_done: OnDone) -> None:
    """Run every spec in its own process, at most `workers` at once; call on_done(index, outcome)
    as each finishes. A process past its spec's hard_limit is killed (status timeout)."""
    from multiprocessing.connection import wait

    import signal
    import threading

    ctx = _mp_context()
    _remove_stale_temps()
    tmp = tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{os.getpid()}-")
    todo = deque(enumerate(specs))
    running: dict = {}  # sentinel -> (index, process, start, hard deadline, result path, log path)

    def on_term(signum, frame):  # noqa: ARG001 - SIGTERM (timeout, schedulers) ends the batch like Ctrl+C
        raise KeyboardInterrupt

    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, on_term) if main else None
    try:
        while todo or running:
            while todo and len(running) < workers:
                i, spec = todo.popleft()
                res, log = os.path.join(tmp, f"{i}.json"), os.path.join(tmp, f"{i}.log")
                proc = ctx.Process(target=child_main, args=({**spec, "batch_pid": os.getpid()}, res, log), daemon=True,
                                   name=f"polyfold-batch-{i}")
                proc.start()
                t0 = time.perf_counter()
                running[proc.sentinel] = (i, proc, t0, t0 + spec["hard_limit"], res, log)  # wall clock: kills hung children
            first = min(hard for _, _, _, hard, _, _ in running.values())
            ready = set(wait(list(running), timeout=max(0.0, first - time.perf_counter())))
            now = time.perf_counter()
            for sentinel, (i, proc, t0, hard, res, log) in list(running.items()):
                if sentinel in ready:
                    proc.join()
                    outcome = process_outcome(proc.exitcode, res, log, now - t0)
                elif now >= hard:
                    _kill(proc)
                    outcome = timeout_outcome(specs[i]["hard_limit"], now - t0)
                else:
                    continue
                del running[sentinel]
                on_done(i, outcome)
    finally:  # interrupted: leave no task process behind
        for _, proc, _, _, _, _ in running.values():
            _kill(proc)
        shutil.rmtree(tmp, ignore_errors=True)
        if main:
            signal.signal(signal.SIGTERM, previous)


def _kill(proc) -> None:
    """Kill a task process and everything in its process group; wait for it."""
    import signal

    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (OSError, TypeError):
        pass  # not (yet) a group leader, or gone
    proc.kill()
    proc.join()


def _remove_stale_temps() -> None:
    """Remove the temporary folders of batches whose process is gone (killed with SIGKILL)."""
    root = Path(tempfile.gettempdir())
    for folder in root.glob(f"{TEMP_PREFIX}*-*"):
        pid = folder.name[len(TEMP_PREFIX):].split("-", 1)[0]
        if not pid.isdigit() or not folder.is_dir() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(folder, ignore_errors=True)
        except PermissionError:
            pass  # another user's live process


def dask_task(spec: dict) -> dict:
    """Body of one Dask task: the job runs in a subprocess, so a crash or hang costs that
    subprocess and not the Dask worker; -> the same outcome dict as the local pool."""
    with tempfile.TemporaryDirectory(prefix="polyfold-task-") as tmp:
        spec_path, res, log = (os.path.join(tmp, n) for n in ("spec.json", "result.json", "task.log"))
        with open(spec_path, "w") as fh:
            json.dump(spec, fh)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([sys.executable, "-m", ENTRY, spec_path, res, log],
                                  stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  timeout=spec["hard_limit"])
        except subprocess.TimeoutExpired:  # run() has killed it
            return timeout_outcome(spec["hard_limit"], time.perf_counter() - t0)
        return process_outcome(proc.returncode, res, log, time.perf_counter() - t0)


def _run_dask(specs: list[dict], address: str, on_done: OnDone) -> None:
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
        raise PolyfoldError(f"cannot reach the Dask scheduler at {address}: {one_line(exc)}") from None
    with client:
        token = os.urandom(4).hex()
        futures = {client.submit(dask_task, spec, key=f"polyfold-batch-{token}-{i}", pure=False, retries=0): i
                   for i, spec in enumerate(specs)}
        for fut in as_completed(futures):
            try:
                outcome = fut.result()
            except Exception as exc:  # the Dask worker itself died (e.g. KilledWorker) or similar
                outcome = {"status": "crashed", "error": f"dask task failed: {one_line(exc)}", "seconds": 0.0}
            on_done(futures[fut], outcome)


def main(argv: Sequence[str] | None = None) -> int:
    """`python -m polyfold.apps.isolation SPEC.json RESULT.json LOG`: run one task (the Dask path)."""
    spec_path, result_path, log_path = (argv if argv is not None else sys.argv[1:])[:3]
    with open(spec_path) as fh:
        spec = json.load(fh)
    child_main(spec, result_path, log_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
