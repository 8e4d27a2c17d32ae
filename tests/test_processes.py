"""processes.py: `fork_map` runs a function over items in forked processes, in order, and raises
what it raises; `beside` runs one function in a forked process while another runs here;
`Forked` waits for, polls and kills a forked process as Popen does a spawned one; `ForkedStream`
reads a generator's values made in a forked process as they come; `Standby`
prepares in a forked process and then runs the calls it is sent there; `usable_cores` counts
this process's cores."""

from __future__ import annotations

import os

import numpy as np
import pytest

from polyfold.errors import OutOfTime
from polyfold.processes import Standby, beside, fork_map, usable_cores

BIG = np.arange(1_000_000)  # read by the children through the fork, never pickled


def test_results_in_order_computed_in_other_processes() -> None:
    got = fork_map(lambda i: (i, int(BIG[i * 1000]), os.getpid()), list(range(12)), 3)
    assert [g[:2] for g in got] == [(i, i * 1000) for i in range(12)]
    if os.uname().sysname == "Linux":
        assert os.getpid() not in {g[2] for g in got}  # forked workers did the work


def test_serial_when_one_worker_or_one_item() -> None:
    for items, workers in (([1, 2, 3], 1), ([5], 4), ([], 4)):
        assert [g[1] for g in fork_map(lambda x: (x, os.getpid()), items, workers)] == [os.getpid()] * len(items)


def test_an_exception_in_a_worker_is_raised_here() -> None:
    def fn(x):
        if x == 3:
            raise OutOfTime("out of time", "placing labels")
        return x

    with pytest.raises(OutOfTime) as err:
        fork_map(fn, list(range(6)), 2)
    assert err.value.doing == "placing labels"


def test_usable_cores() -> None:
    n = usable_cores()
    assert 1 <= n <= (os.cpu_count() or 1)


def test_a_dead_worker_does_not_hang_the_work() -> None:
    """A worker killed mid-item (here: os._exit in a child) breaks the pool; the items are then
    done in this process, and nothing waits for the dead one."""
    parent = os.getpid()

    def fn(x):
        if x == 2 and os.getpid() != parent:
            os._exit(1)
        return x * x

    assert fork_map(fn, list(range(5)), 2) == [0, 1, 4, 9, 16]


def test_the_workers_see_this_process_frozen_and_it_is_thawed_after() -> None:
    """fork_map freezes this process's objects for the workers' collections (gc.freeze) and thaws
    them when the work is done, so nothing this process holds stays out of its own collections."""
    import gc

    assert gc.get_freeze_count() == 0
    counts = fork_map(lambda i: gc.get_freeze_count(), list(range(4)), 2)
    if os.uname().sysname == "Linux":
        assert min(counts) > 0  # the workers inherited the frozen objects
    assert gc.get_freeze_count() == 0


def test_beside_runs_one_here_and_one_in_a_fork_at_once() -> None:
    """The two run at the same time (each waits for the other's mark in shared memory), there()
    in another process, reading this process's data through the fork; an exception from either
    is raised here; where no process can be forked both run here, here() first."""
    import time
    from multiprocessing import RawArray

    marks = RawArray("b", [0, 0])

    def meet(k: int) -> tuple[int, int]:
        marks[k] = 1
        t0 = time.monotonic()
        while not marks[1 - k] and time.monotonic() - t0 < 20:
            time.sleep(0.001)
        return int(marks[1 - k]), os.getpid()

    (met_here, pid_here), (met_there, pid_there) = beside(lambda: meet(0), lambda: meet(1))
    if os.uname().sysname == "Linux":
        assert met_here == met_there == 1 and pid_here == os.getpid() != pid_there
    assert beside(lambda: int(BIG[7]), lambda: int(BIG[999_999])) == (7, 999_999)

    def fail():
        raise OutOfTime("out of time", "racing")

    for here, there in ((fail, lambda: 1), (lambda: 1, fail)):
        with pytest.raises(OutOfTime):
            beside(here, there)


def test_beside_ends_the_forked_work_when_here_raises() -> None:
    """An interrupt (or any exception) here does not wait for there() to finish."""
    import time

    def slow():
        time.sleep(60)
        return 1

    def interrupted():
        time.sleep(0.2)
        raise KeyboardInterrupt

    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        beside(interrupted, slow)
    assert time.monotonic() - t0 < 10


def test_forked_reports_how_its_work_ended_as_popen_would(tmp_path) -> None:
    import subprocess
    import time

    from polyfold.processes import Forked

    mark = tmp_path / "ran"
    done = Forked(lambda: mark.write_text("yes"))
    assert done.wait(timeout=30) == 0 and done.returncode == 0
    assert mark.read_text() == "yes"  # (the work ran in the child, which shares this file system)

    def fail() -> None:
        raise RuntimeError("in the child")

    assert Forked(fail).wait(timeout=30) == 1

    slow = Forked(lambda: time.sleep(60))
    assert slow.poll() is None
    with pytest.raises(subprocess.TimeoutExpired):
        slow.wait(timeout=0.05)
    slow.kill()
    assert slow.wait(timeout=30) == -9 and slow.poll() == -9
    slow.kill()  # (ended and reaped: nothing to do)


_LEAVE = r"""
import atexit, sys, tempfile, threading, time, pathlib
from polyfold.processes import leave
folder = tempfile.TemporaryDirectory()  # removed by an exit handler (weakref.finalize)
pathlib.Path(sys.argv[1]).write_text(folder.name)
atexit.register(lambda: print("exit handlers ran"))
print("buffered output")  # (stdout is a pipe: block-buffered, written only when flushed)
if sys.argv[2] == "thread":
    threading.Thread(target=lambda: (time.sleep(0.5), print("the thread finished"))).start()
leave(3)
print("never")
"""


@pytest.mark.parametrize("with_thread", [False, True])
def test_leave_ends_the_process_as_an_exit_would(tmp_path, with_thread) -> None:
    """`leave` (the command line's end): the exit status, what was printed, the exit handlers (a
    temporary folder removed), and a running thread that is not a daemon finished, as sys.exit."""
    import subprocess
    import sys

    where = tmp_path / "folder.txt"
    run = subprocess.run([sys.executable, "-c", _LEAVE, str(where), "thread" if with_thread else "-"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 3, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0] == "buffered output" and "exit handlers ran" in lines and "never" not in lines
    assert ("the thread finished" in lines) == with_thread
    assert not os.path.exists(where.read_text())


def test_exit_status_is_the_interpreters() -> None:
    """`exit_status`: the status `sys.exit(code)` gives a process (None 0, an int itself, a
    message 1), for the command line's `leave` and the server's children."""
    import subprocess
    import sys

    from polyfold.processes import exit_status

    for code in (None, 0, 3, 141, "a message"):
        run = subprocess.run([sys.executable, "-c", f"import sys; sys.exit({code!r})"], capture_output=True, timeout=60)
        assert exit_status(SystemExit(code)) == run.returncode, code


def _down(n: int) -> int:
    return 0 if n == 0 else _down(n - 1) + 1


def _up_and_down() -> None:
    """Calls 0-400 deep, again and again: across the end of a 16 KB frame chunk or two."""
    for _ in range(100):
        for depth in range(0, 400, 7):
            _down(depth)


def _page_faults(fn) -> int:
    import resource

    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    fn()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def test_calls_in_the_roomy_stack_map_no_frame_chunks() -> None:
    """Outside `in_roomy_stack`, calls going up and down across a chunk's end map a fresh chunk
    each time (its pages fault in anew: thousands of faults); inside, they reuse its one chunk
    (a handful). And the function's value comes back."""
    from polyfold.processes import in_roomy_stack

    outside = _page_faults(_up_and_down)
    inside = _page_faults(lambda: in_roomy_stack(_up_and_down))
    assert outside > 1000, outside  # (the churn this guards against, as CPython 3.11 has it)
    assert inside < outside / 20, (inside, outside)
    assert in_roomy_stack(lambda: _down(50)) == 50


# module-level: a Standby's calls are pickled by reference
_PREPARED: list[int] = []


def _prepare() -> None:
    _PREPARED.append(os.getpid())


def _prepared_where(big: np.ndarray) -> tuple[list[int], int, int, np.ndarray]:
    """What prepare() did in this process, this process, the argument's sum, a large answer."""
    return list(_PREPARED), os.getpid(), int(big.sum()), np.ones(2_000_000)


def _fail(why: str) -> None:
    raise OutOfTime("out of time", why)


def _exit_there(parent: int) -> int:
    """Ends the process it runs in unless that is `parent` (a standby dying mid-call)."""
    if os.getpid() != parent:
        os._exit(3)
    return parent


def _pid() -> int:
    return os.getpid()


def test_standby_prepares_then_runs_the_calls_sent_in_order_with_large_data_both_ways() -> None:
    """prepare() ran in the standby process before its calls; several calls sent at once, each
    with megabytes going there and coming back (the process answers one while the next is still
    being sent: nothing waits for the other side), answered in order whichever is asked first."""
    if os.uname().sysname != "Linux":
        pytest.skip("forking is Linux only")
    standby = Standby(_prepare)
    try:
        big = np.arange(3_000_000)
        tickets = [standby.submit(_prepared_where, big + k) for k in range(3)]
        last = standby.result(tickets[2])
        firsts = [standby.result(t) for t in tickets[:2]]
        for k, (prepared, pid, total, answer) in enumerate([*firsts, last]):
            assert pid != os.getpid() and prepared == [pid]
            assert total == int(big.sum()) + k * len(big) and answer.sum() == 2_000_000
        assert _PREPARED == []  # prepare() never ran here
    finally:
        standby.close()


def _sleep(seconds: float) -> float:
    import time

    time.sleep(seconds)
    return seconds


def test_standby_says_whether_a_call_is_answered_without_waiting() -> None:
    import time

    standby = Standby(_prepare)
    try:
        slow = standby.submit(_sleep, 1.0)
        t0 = time.monotonic()
        assert not standby.answered(slow) and time.monotonic() - t0 < 0.5
        assert standby.result(slow) == 1.0
        quick = standby.submit(_sleep, 0.0)
        t0 = time.monotonic()
        while not standby.answered(quick) and time.monotonic() - t0 < 20:
            time.sleep(0.01)
        assert standby.result(quick) == 0.0
    finally:
        standby.close()


def test_standby_raises_here_what_a_call_raised_there_and_goes_on() -> None:
    standby = Standby(_prepare)
    try:
        with pytest.raises(OutOfTime) as err:
            standby.result(standby.submit(_fail, "writing"))
        assert err.value.doing == "writing"
        assert standby.result(standby.submit(_pid)) != os.getpid() or os.uname().sysname != "Linux"
    finally:
        standby.close()


def test_standby_runs_here_what_it_cannot_send_or_answer() -> None:
    """A call that does not pickle (a lambda), or one sent to a process that died (killed, out of
    memory: here it exits mid-call), is run in this process; nothing waits for ever."""
    standby = Standby(_prepare)
    try:
        assert standby.result(standby.submit(lambda: os.getpid())) == os.getpid()
        assert standby.result(standby.submit(_pid)) == os.getpid()  # (the process was ended: all here)
    finally:
        standby.close()
    standby = Standby(_prepare)
    try:
        died = standby.submit(_exit_there, os.getpid())
        after = standby.submit(_pid)
        assert standby.result(after) == os.getpid()
        assert standby.result(died) == os.getpid()
    finally:
        standby.close()


def test_large_results_come_back_whole_and_in_order() -> None:
    """Results larger than a pipe holds (each worker writes them to a file of its own) and more
    items than workers: every result whole, in the items' order, from several processes."""
    got = fork_map(lambda i: (os.getpid(), np.full(300_000, i, dtype=np.int64)), list(range(9)), 2)
    assert [int(a[0]) for _pid, a in got] == list(range(9))
    assert all(len(a) == 300_000 and (a == i).all() for i, (_pid, a) in enumerate(got))
    if os.uname().sysname == "Linux":
        assert os.getpid() not in {pid for pid, _a in got}


def test_workers_stop_taking_items_when_this_process_is_killed() -> None:
    """A make killed mid-work (SIGKILL, or SIGTERM from a served client's end) leaves no worker
    working on: each takes no more items once its parent is gone."""
    import signal
    import subprocess
    import sys
    import textwrap
    import time

    code = textwrap.dedent("""
        import os, sys, time
        from polyfold.processes import fork_map
        def slow(i):
            os.write(1, f"{os.getpid()}\\n".encode())
            time.sleep(0.3)
            return i
        fork_map(slow, list(range(40)), 2)
    """)
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    workers: set[int] = set()
    while len(workers) < 2:  # (each worker says its pid at each item it takes)
        workers.add(int(proc.stdout.readline()))
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    def running(pid: int) -> bool:  # (an ended worker nobody has reaped yet is a zombie: gone)
        try:
            with open(f"/proc/{pid}/stat") as f:
                return f.read().rsplit(")", 1)[1].split()[0] != "Z"
        except OSError:
            return False

    deadline = time.monotonic() + 5.0  # (40 items of 0.3 s on two workers would take 6 s)
    while time.monotonic() < deadline and any(running(pid) for pid in workers):
        time.sleep(0.05)
    assert not any(running(pid) for pid in workers)  # each stopped after its item


def test_a_forked_stream_gives_the_generators_values_in_order_as_they_come() -> None:
    """Values made in a forked process (larger in all than a pipe holds), read one at a time:
    (True, value) in the generator's order, then (False, None) for good."""
    from polyfold.processes import ForkedStream

    here = os.getpid()

    def values():
        for i in range(12):
            yield i, os.getpid(), np.full(200_000, i, dtype=np.int64)  # (19 MB in all)

    with ForkedStream(values) as stream:
        got = [stream.next() for _ in range(12)]
        assert stream.next() == (False, None) and stream.next() == (False, None)
    assert all(ok for ok, _v in got)
    assert [v[0] for _ok, v in got] == list(range(12))
    assert all(len(v[2]) == 200_000 and (v[2] == v[0]).all() for _ok, v in got)
    if os.uname().sysname == "Linux":
        assert {v[1] for _ok, v in got} != {here}


def test_a_forked_stream_ends_where_its_generator_raises_and_close_ends_its_process() -> None:
    import time

    from polyfold.processes import ForkedStream

    def two_then_raise():
        yield 1
        yield 2
        raise ValueError("no more")

    with ForkedStream(two_then_raise) as stream:
        assert [stream.next() for _ in range(3)] == [(True, 1), (True, 2), (False, None)]

    def forever():
        while True:
            time.sleep(0.01)
            yield 0

    stream = ForkedStream(forever)
    pid = stream.pid
    assert stream.next() == (True, 0)
    stream.close()
    with pytest.raises(ChildProcessError):  # (killed and reaped)
        os.waitpid(pid, 0)
    assert stream.next() == (False, None)


def test_an_interrupt_while_forking_is_taken_after_the_fork() -> None:
    """A Ctrl-C that lands while a process forks (here sent from an at-fork hook, where logging's
    lock is released after every fork) raises KeyboardInterrupt in this process after the fork,
    for each way of forking; before, Python printed "Exception ignored" and the command ran on.
    (In a process of its own: at-fork hooks cannot be taken back.)"""
    import subprocess
    import sys
    import textwrap

    script = textwrap.dedent("""
        import os, signal, sys
        # (Python's own handler, whatever this test's process was started with: a command started in
        # the background by a shell without job control, as `.ci/run ... &`, inherits SIGINT ignored)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        from polyfold import processes as P
        armed = [False]
        def interrupt_me():
            if armed[0]:
                armed[0] = False
                os.kill(os.getpid(), signal.SIGINT)
        os.register_at_fork(after_in_parent=interrupt_me)
        ways = {
            "fork_map": lambda: P.fork_map(lambda x: x, [1, 2, 3], 2),
            "beside": lambda: P.beside(lambda: 1, lambda: 2),
            "Forked": lambda: P.Forked(lambda: None).wait(10),
            "ForkedStream": lambda: P.ForkedStream(lambda: iter([1])).close(),
            "Standby": lambda: P.Standby(lambda: None).close(),
        }
        for name, fork in ways.items():
            armed[0] = True
            try:
                fork()
                print(name, "ran on")
            except KeyboardInterrupt:
                print(name, "interrupted")
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:-1] == [f"{name} interrupted" for name in
                                            ("fork_map", "beside", "Forked", "ForkedStream", "Standby")], done.stderr
