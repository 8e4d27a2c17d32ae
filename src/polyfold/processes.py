"""Work spread over this machine's cores (standard library only): how many cores this process may
use; `fork_map`, which runs independent pieces of work in processes forked from this one,
`beside`, which runs one piece of work in a forked process while this one does another,
`Forked`, a forked process to poll, wait for or kill, as `subprocess.Popen` would a spawned one,
`ForkedStream`, the values of a generator made in a forked process and read as they come,
`Standby`, a process forked early that loads libraries and then runs the calls it is sent, and
the command line's process settings (`collect_less`, `in_roomy_stack`, `exit_status`, `leave`).

Forked, not spawned: a child starts as a copy of this process (its modules, kernels and data), so
little but the results is pickled and a fork costs milliseconds, not the second of a fresh
interpreter. Linux only (fork is unsafe on macOS); elsewhere the work runs here.
"""

from __future__ import annotations

import contextlib
import gc
import os
import sys
import types
from typing import Any, Callable, Sequence, TypeVar

T = TypeVar("T")


@contextlib.contextmanager
def _interrupt_after_fork():
    """Around a fork in the main thread: a Ctrl-C that comes while it forks is taken after it,
    in this process. (Python runs a signal's handler at the next line of Python code, and a fork
    runs some, the at-fork hooks (logging's lock); KeyboardInterrupt raised in one of them is
    printed as "Exception ignored" and lost, and the interrupted command ran on to its end.) The
    interrupt is only noted while forking, then handed to the handler that was there before."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():  # (only there may handlers change)
        yield
        return
    caught: list[int] = []
    here = os.getpid()
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)  # (in the child too, as it was forked from)
        if caught and callable(previous) and os.getpid() == here:
            previous(signal.SIGINT, None)


def usable_cores() -> int:
    """The cores this process may run on (its affinity, as `taskset` sets it, where the OS says)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


# The collector's first threshold for polyfold's own processes (the default is 700): numba's
# compiler allocates millions of short-lived objects in reference cycles (its IR, types and
# templates), and with the default the collector runs thousands of times over them, 5-10 % of a
# first run's compiling. Ten thousand allocations between collections hold a few MB more at most.
GC_THRESHOLD = (10_000, 10, 10)


def collect_less() -> None:
    """Set `GC_THRESHOLD` for this process: for the command line and its helper processes, never
    on import (a program that imports polyfold keeps its own settings)."""
    gc.set_threshold(*GC_THRESHOLD)


# CPython (3.11 on) keeps its frames on a data stack of chunks mapped from the OS, 16 KB unless a
# frame needs more, each unmapped the moment the call that needed it returns: code whose call depth
# goes up and down across a chunk's end maps and unmaps 16 KB at every call. numba's compiler is
# such code: the bunny's first make mapped 16 KB 410,000 times, 3.4 s of its system time (0.7 s
# in room), about 1 s of its wall time. A frame of ROOMY_FRAME_SLOTS slots (8 bytes each) gets a
# chunk of its own, 1 MB (16 KB doubled until it holds the frame and 1,000 slots more), and every
# call under it runs in the 0.5 MB left above it: no chunk ends there.
ROOMY_FRAME_SLOTS = 66_000


def _call(fn: Callable[[], T]) -> T:
    return fn()


try:  # the same function, its frame made ROOMY_FRAME_SLOTS slots large (stack slots it never uses)
    _roomy_call = types.FunctionType(_call.__code__.replace(co_stacksize=ROOMY_FRAME_SLOTS), globals(),
                                     "in_roomy_stack")
except (AttributeError, TypeError, ValueError):  # (an interpreter whose code objects are not CPython's)
    _roomy_call = _call


def in_roomy_stack(fn: Callable[[], T]) -> T:
    """fn(), with room on the interpreter's frame stack for every call under it (see
    ROOMY_FRAME_SLOTS): for a process's main function, once (each call maps its own 1 MB)."""
    return _roomy_call(fn)


def exit_status(done: SystemExit) -> int:
    """The exit status a process ending with `done` has: its code, 0 for None, 1 for a message."""
    return done.code if isinstance(done.code, int) else (0 if done.code is None else 1)


def leave(code: int) -> None:
    """End this process now with exit status `code`, as `sys.exit` would but without the
    interpreter's teardown: the exit handlers run (they end pools, remove temporary folders), the
    standard streams are flushed, then `os._exit`. For the command line when its command is done:
    tearing down what a make loaded (hundreds of modules, its kernels' machine code) costs 0.2-0.4 s
    that nobody waits for. While a thread other than this one and not a daemon still runs, or
    where the exit handlers cannot be run from here, it is a plain `sys.exit` (which waits)."""
    import atexit
    import threading

    run_handlers = getattr(atexit, "_run_exitfuncs", None)  # CPython's; what interpreter exit calls
    others = [t for t in threading.enumerate() if t is not threading.current_thread() and not t.daemon]
    if others or run_handlers is None:
        sys.exit(code)
    run_handlers()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):  # closed, or a pipe whose reader has gone
            pass
    os._exit(code)


def can_fork() -> bool:
    """Whether work may go to processes forked from this one: on Linux (fork is unsafe on macOS),
    outside daemonic processes (which may not have children)."""
    import multiprocessing as mp

    return sys.platform.startswith("linux") and not mp.current_process().daemon


def _results_file():
    """An anonymous file for a forked worker's results: in memory (memfd) where the OS has it."""
    import tempfile

    if hasattr(os, "memfd_create"):
        try:
            return os.fdopen(os.memfd_create("polyfold-results"), "w+b")
        except OSError:
            pass
    return tempfile.TemporaryFile()


def _kill_and_reap(pid: int) -> None:
    """End a forked child now (SIGKILL) and reap it; nothing when it is gone already."""
    import signal

    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except OSError:
        pass


def fork_map(fn: Callable[[Any], Any], items: Sequence[Any], workers: int) -> list[Any]:
    """[fn(x) for x in items], in that order, run by up to `workers` processes forked from this
    one, which take the items one at a time (put the longest first). fn, the items and whatever
    they read are inherited by the fork, not pickled; each result is pickled. fn must not depend on
    side effects of other calls (each child changes only its own copy of memory; this process's
    stays as it was). An exception raised by fn is raised here (the first item's that raised).
    Runs here, in order, when workers or items are fewer than two, on other systems than Linux,
    or in a daemonic process (which may not have children); when a worker dies (killed, out of
    memory) its items are done here instead of waiting for it forever.

    Plain forks (3-4 ms each for a make's process), not a pool (concurrent.futures' took 11-17 ms,
    its queues, threads and pickled items): the items' numbers are handed out through a pipe
    written before the fork (a read of one number from it is atomic), and each worker writes
    its results to a file of its own in memory, read here when it has ended. Workers ignore
    Ctrl-C (this process reports it and kills them) and take no more items once this process has
    gone (killed: nobody would read them)."""
    import pickle
    import signal

    workers = min(workers, len(items))
    if workers < 2 or not can_fork():
        return [fn(x) for x in items]
    # the numbers: one per item, or per run of items where they are more than the pipe holds
    per = -(-len(items) // 8192)
    starts = list(range(0, len(items), per))
    numbers, rest = os.pipe()
    with os.fdopen(rest, "wb") as pipe:
        pipe.write(b"".join(k.to_bytes(4, sys.byteorder, signed=True) for k in starts))  # (closed before the fork)
    files, pids, parent = [], [], os.getpid()
    # what this process holds is no garbage the workers need look at: frozen, their collections
    # skip it (a full collection over make's objects costs each worker tens of ms, and touches
    # pages it shares with this process); thawed here when they are forked
    gc.freeze()
    try:
        for _ in range(workers):
            out = _results_file()
            try:
                with _interrupt_after_fork():
                    pid = os.fork()
            except OSError:  # no more processes to be had: those forked do the work
                out.close()
                break
            if pid == 0:  # a worker: never returns into the caller's code
                try:
                    signal.signal(signal.SIGINT, signal.SIG_IGN)  # (this process reports Ctrl-C and ends it)
                    # (a worker whose parent has gone, killed, takes no more items: nobody reads them)
                    while os.getppid() == parent and len(got := os.read(numbers, 4)) == 4:
                        first = int.from_bytes(got, sys.byteorder, signed=True)
                        for i in range(first, min(first + per, len(items))):
                            try:
                                pickle.dump((i, True, fn(items[i])), out, protocol=pickle.HIGHEST_PROTOCOL)
                            except BaseException as exc:  # (raised here instead; the worker stops)
                                pickle.dump((i, False, exc), out, protocol=pickle.HIGHEST_PROTOCOL)
                                raise
                finally:
                    try:
                        out.flush()
                    finally:
                        os._exit(0)
            files.append(out)
            pids.append(pid)
    finally:
        gc.unfreeze()
        os.close(numbers)
    done: dict[int, tuple[bool, Any]] = {}
    try:
        for pid, out in zip(pids, files):
            os.waitpid(pid, 0)
            out.seek(0)
            while True:
                try:
                    i, ok, value = pickle.load(out)
                except Exception:  # the end (or a worker killed mid-write: its items are done here)
                    break
                done[i] = (ok, value)
    finally:
        for pid in pids:  # (left running only when this process was interrupted)
            _kill_and_reap(pid)
        for out in files:
            out.close()
    results = []
    for i, x in enumerate(items):
        ok, value = done[i] if i in done else (True, fn(x))
        if not ok:
            raise value
        results.append(value)
    return results


class Forked:
    """fn() in a process forked from this one (check `can_fork` first), with the part of
    `subprocess.Popen`'s interface that waits for a process: poll(), wait(timeout), kill(),
    returncode (0 when fn returned, 1 when it raised, -signal when a signal ended it). For long
    work whose result goes elsewhere (a file, a cache); nothing comes back. Forked by os.fork
    itself: a multiprocessing Process forked the same way took 1.3-3 s more system time for a
    first run's compiling (0.81 M page faults against 0.22 M; not found why). The child holds a
    pipe's write end, so the read end shows its end without polling."""

    def __init__(self, fn: Callable[[], Any]) -> None:
        self.returncode: int | None = None
        self._ended, ending = os.pipe()
        with _interrupt_after_fork():
            pid = os.fork()
        if pid == 0:  # the child: never returns into the caller's code
            code = 1
            try:
                os.close(self._ended)
                fn()
                code = 0
            finally:
                os._exit(code)
        os.close(ending)
        self.pid = pid

    def poll(self) -> int | None:
        return self._reap(0.0)

    def wait(self, timeout: float | None = None) -> int:
        """Its return code; subprocess.TimeoutExpired when it runs on after timeout seconds."""
        code = self._reap(timeout)
        if code is None:
            import subprocess

            raise subprocess.TimeoutExpired(f"forked process {self.pid}", timeout)
        return code

    def kill(self) -> None:
        if self.returncode is None:
            import signal

            os.kill(self.pid, signal.SIGKILL)  # (a child that ended but is not reaped yet: no error)

    def _reap(self, timeout: float | None) -> int | None:
        import select

        if self.returncode is None and select.select([self._ended], [], [], timeout)[0]:
            self.returncode = os.waitstatus_to_exitcode(os.waitpid(self.pid, 0)[1])
            os.close(self._ended)
        return self.returncode


class ForkedStream:
    """The values a generator yields, made in a process forked from this one (check `can_fork`
    first) and read here one at a time as they come: for work done ahead of its need, while this
    process does other work. `next()` waits for the next value and returns (True, value), or
    (False, None) once there are no more: the generator ended or raised, or its process died (a
    caller that needs the rest makes it itself). Each value is pickled through a pipe (made 1 MB
    where the OS allows, so the process rarely waits for this one to read). The process ignores
    Ctrl-C (this one reports it), stops once this one has gone, and `close` (or leaving a `with`
    block) kills it."""

    PIPE_BYTES = 1 << 20

    def __init__(self, gen: Callable[[], Any]) -> None:
        import signal

        readable, writable = os.pipe()
        try:
            import fcntl

            fcntl.fcntl(writable, fcntl.F_SETPIPE_SZ, self.PIPE_BYTES)
        except (ImportError, AttributeError, OSError):  # (the OS's own size: the process waits more)
            pass
        parent = os.getpid()
        gc.freeze()  # (see fork_map)
        try:
            with _interrupt_after_fork():
                pid = os.fork()
        except OSError:
            pid = -1
        finally:
            gc.unfreeze()
        if pid == 0:  # the child: never returns into the caller's code
            try:
                import pickle

                signal.signal(signal.SIGINT, signal.SIG_IGN)  # (this process reports Ctrl-C and ends it)
                os.close(readable)
                with os.fdopen(writable, "wb") as out:
                    for value in gen():
                        if os.getppid() != parent:  # (killed: nobody reads them)
                            break
                        pickle.dump(value, out, protocol=pickle.HIGHEST_PROTOCOL)
                        out.flush()
            finally:
                os._exit(0)
        os.close(writable)
        self.pid = pid
        self._in: Any = os.fdopen(readable, "rb")
        if pid < 0:  # no process to be had: no values
            self.close()

    def next(self) -> tuple[bool, Any]:
        import pickle

        if self._in is None:
            return False, None
        try:
            return True, pickle.load(self._in)
        except Exception:  # the end (or the process killed mid-write)
            self.close()
            return False, None

    def close(self) -> None:
        if self._in is not None:
            self._in.close()
            self._in = None
        if self.pid > 0:
            _kill_and_reap(self.pid)
            self.pid = 0

    def __enter__(self) -> ForkedStream:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def beside(here: Callable[[], Any], there: Callable[[], Any]) -> tuple[Any, Any]:
    """(here(), there()): there() in a process forked from this one, here() in this one
    meanwhile (so here() may show progress; a forked child must stay quiet). As with `fork_map`,
    there() and what it reads are inherited and its result pickled; an exception raised by
    there() is raised here, one raised by here() (an interrupt too) ends the forked process at
    once. Both run here, here() first, where fork_map would run its items here, and there() is
    run here when its process dies."""
    import multiprocessing as mp

    if not can_fork():
        return here(), there()
    ctx = mp.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)

    def child() -> None:
        try:
            out = (True, there())
        except BaseException as exc:  # (raised in the parent instead)
            out = (False, exc)
        send.send(out)

    gc.freeze()  # (see fork_map)
    try:
        proc = ctx.Process(target=child)
        try:
            with _interrupt_after_fork():
                proc.start()
        except OSError:
            return here(), there()
        send.close()  # (the child's copy stays open: its end tells this one the child is gone)
        answered = False
        try:
            near = here()
            try:
                ok, far = receive.recv()
            except EOFError:  # the child died (killed, out of memory) before it answered
                ok, far = True, there()
            answered = True
        finally:
            if not answered:  # here() raised: the child's work is not wanted
                proc.terminate()
            proc.join()
            receive.close()
    finally:
        gc.unfreeze()
    if not ok:
        raise far
    return near, far


class Standby:
    """A process forked now that runs prepare() at once (imports the work it will be given needs)
    while this one goes on, then the calls it is sent, one at a time in the order sent:
    `submit(fn, *args)` pickles fn (a module-level function) and its arguments to it and returns
    a ticket, `result(ticket)` waits for fn(*args) (pickled back; what fn raised is raised here).
    For work whose libraries take long to import next to the data it needs: they load on a core
    this process leaves idle, and a process forked later (`beside`) would load them again.
    A call the process cannot answer (it died: killed, out of memory) is run here. It ignores
    Ctrl-C (this process reports it and ends it); `close` ends it, as does this process ending
    (its pipe closes). Check `can_fork` first."""

    def __init__(self, prepare: Callable[[], Any]) -> None:
        import multiprocessing as mp

        ctx = mp.get_context("fork")
        self._conn, theirs = ctx.Pipe()
        self._sent: list[tuple[Callable[..., Any], tuple]] = []  # every call submitted, by ticket
        self._answers: dict[int, tuple[bool, Any]] = {}
        self._received = 0  # answers read from the pipe (they come in the order sent)
        self._sender: Any = None  # the thread sending the last call (the next one waits for it)
        self._gone = False

        def serve() -> None:
            import signal

            signal.signal(signal.SIGINT, signal.SIG_IGN)
            self._conn.close()
            try:
                prepare()
            except Exception:  # (what it failed to load, the calls load themselves or fail there)
                pass
            while True:
                try:
                    call = theirs.recv()
                except (EOFError, OSError):  # the parent is gone
                    return
                fn, args = call
                try:
                    answer = (True, fn(*args))
                except BaseException as exc:  # (raised in the parent instead)
                    answer = (False, exc)
                try:
                    theirs.send(answer)
                except (OSError, ValueError):  # the parent is gone
                    return

        gc.freeze()  # (see fork_map)
        try:
            self._proc: Any = ctx.Process(target=serve, daemon=True)
            with _interrupt_after_fork():
                self._proc.start()
        except OSError:
            self._proc, self._gone = None, True
        finally:
            gc.unfreeze()
        theirs.close()

    def submit(self, fn: Callable[..., Any], *args: Any) -> int:
        """Send fn(*args) to the process (from a thread of this one: a large call waits for the
        pipe while the process finishes the one before) and return its ticket."""
        import threading

        self._sent.append((fn, args))
        if not self._gone:
            sender = threading.Thread(target=self._send, args=((fn, args), self._sender), daemon=True)
            sender.start()
            self._sender = sender
        return len(self._sent) - 1

    def _send(self, call: tuple, before: Any) -> None:
        if before is not None:
            before.join()
        if self._gone:
            return
        try:
            self._conn.send(call)
        except Exception:  # the process is gone, or the call does not pickle: `result` runs it here
            self.close()

    def answered(self, ticket: int) -> bool:
        """Whether the call with this ticket has been answered (or will be run here), without
        waiting: the process is free for the next call when every call sent so far is."""
        try:
            while ticket not in self._answers and not self._gone and self._conn.poll(0):
                self._answers[self._received] = self._conn.recv()
                self._received += 1
        except (EOFError, OSError):
            self._gone = True
        return ticket in self._answers or self._gone

    def result(self, ticket: int) -> Any:
        """fn(*args) of the call with this ticket (waits for it and for the calls before it; reads
        while a sender may still be writing: the process may be sending an answer as large)."""
        while ticket not in self._answers:
            if self._gone:
                fn, args = self._sent[ticket]
                return fn(*args)
            try:
                self._answers[self._received] = self._conn.recv()
                self._received += 1
            except (EOFError, OSError):
                self._gone = True
        ok, value = self._answers.pop(ticket)
        if not ok:
            raise value
        return value

    def close(self) -> None:
        """End the process (at once: calls not yet answered are run here if asked for)."""
        self._gone = True
        proc, self._proc = self._proc, None
        if proc is not None:
            try:
                proc.kill()  # (one that ended already: no error)
                proc.join()
            except (OSError, ValueError, AssertionError):
                pass
