"""apps/server.py: `polyfold server` and the commands it runs for the command line: the same
files, output and exit codes as a command run in its own process, signals passed on, nothing
left running, and no answer for another user or from a directory others may enter."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from conftest import CLI, REPO_ROOT, one_line

BUNNY = REPO_ROOT / "examples" / "bunny-128.obj"


def _env(runtime: Path, switch: str) -> dict:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime), POLYFOLD_SERVER=switch)
    return env


def _cli(env: dict, *args, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout, env=env, cwd=cwd)


def _status(env: dict) -> dict | None:
    """The server's answer to "status" for a client with environment `env`, asked from here with
    `env` in place of this process's (the socket's name hashes it): in milliseconds, where a fresh
    Python took seconds under a full parallel run's load, long enough for a command a test means
    to stop mid-work to finish first."""
    from polyfold.apps.server import request

    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(env)
    try:
        return request("status")
    finally:
        os.environ.clear()
        os.environ.update(saved)


def _wait_running(env: dict, count: int, what: str, seconds: float = 10.0) -> None:
    """Until the server runs `count` commands; fails saying `what` after `seconds`."""
    end = time.monotonic() + seconds
    while _status(env)["running"] != count:
        if time.monotonic() > end:
            pytest.fail(what)
        time.sleep(0.02)


@pytest.fixture(scope="module")
def runtime():
    """A private runtime directory (short: a Unix socket's path is at most 107 bytes) with a
    server started in it; stopped and checked gone afterwards."""
    d = Path(tempfile.mkdtemp(prefix="pfs"))
    os.chmod(d, 0o700)
    env = _env(d, "require")
    proc = _cli(env, "server", "start", "--idle-minutes", "10")
    assert proc.returncode == 0, proc.stderr
    assert "server ready" in proc.stderr
    pid = _status(env)["pid"]
    yield d
    stop = _cli(env, "server", "stop")
    assert stop.returncode == 0 and "server stopping" in stop.stderr, stop.stderr
    for _ in range(100):  # gone, its socket removed
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        pytest.fail("the server did not stop")
    assert not list((d / "polyfold").glob("*.sock"))
    shutil.rmtree(d, ignore_errors=True)


def _tree(folder: Path) -> dict[str, str]:
    """Hash of every file but report.json (its seconds); of a DXF, its entities (its header holds
    the time of writing and fresh ids, whichever process writes it)."""

    def content(p: Path) -> bytes:
        data = p.read_bytes()
        if p.suffix == ".dxf":
            start = data.index(b"\nENTITIES\n")
            return data[start:data.index(b"\nENDSEC\n", start)]
        return data

    return {p.relative_to(folder).as_posix(): hashlib.sha256(content(p)).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name != "report.json"}


def test_a_served_make_writes_what_its_own_process_writes(runtime: Path, tmp_path: Path) -> None:
    shutil.copy(BUNNY, tmp_path / "bunny.obj")
    before = _status(_env(runtime, "require"))["served"]
    # a relative mesh and output: the command runs in the client's working directory
    served = _cli(_env(runtime, "require"), "make", "bunny.obj", "-o", "served", cwd=tmp_path)
    here = _cli(_env(runtime, "off"), "make", "bunny.obj", "-o", "here", cwd=tmp_path)
    assert served.returncode == 0 and here.returncode == 0, served.stderr + here.stderr
    assert _status(_env(runtime, "require"))["served"] == before + 1
    assert _tree(tmp_path / "served") == _tree(tmp_path / "here")
    assert len(_tree(tmp_path / "served")) > 10
    assert served.stdout == here.stdout
    # progress and summary lines (no terminal: one line per stage), but for the seconds and folder
    def lines(err: str, folder: str) -> str:
        return re.sub(r"\d+\.\d\d s", "T s", err).replace(folder, "OUT")

    assert lines(served.stderr, "served") == lines(here.stderr, "here")


def test_output_errors_and_exit_codes_come_back(runtime: Path, tmp_path: Path) -> None:
    env = _env(runtime, "require")
    info = _cli(env, "info", BUNNY, "--json")
    assert info.returncode == 0 and info.stdout == _cli(_env(runtime, "off"), "info", BUNNY, "--json").stdout
    missing = _cli(env, "info", tmp_path / "missing.obj")
    assert missing.returncode == 2
    assert "missing.obj" in one_line(missing.stderr)
    usage = _cli(env, "make", BUNNY)  # no -o: a usage error, as in its own process
    assert usage.returncode == 2 and "Traceback" not in usage.stderr
    # the client's umask holds for what the command writes
    out = tmp_path / "net.fold"
    proc = subprocess.run(["sh", "-c", f"umask 077 && {' '.join(map(str, CLI))} unfold {BUNNY} -o {out} -q"],
                          capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_mode & 0o777 == 0o600


_INTERRUPT_AT_ONCE = r"""
import os, sys
from polyfold.apps import server
out, err_path, mesh = sys.argv[1:]
sock = server._connect(server.socket_path(create=False))
null = os.open(os.devnull, os.O_RDWR)
err = os.open(err_path, os.O_WRONLY | os.O_CREAT)
server._send(sock, {"op": "run", "argv": ["make", mesh, "-o", out], "cwd": os.getcwd(), "env": dict(os.environ),
                    "umask": 0o022, "affinity": sorted(os.sched_getaffinity(0))}, [null, null, err])
assert sock.recv(1) == server._ACCEPTED
sock.send(bytes([2]))  # SIGINT passed on at once: it waits in the socket until the child listens
print(server._CODE.unpack(server._recv_exact(sock, server._CODE.size))[0])
"""


def test_an_interrupt_passed_on_before_the_command_listens_is_an_interrupt(runtime: Path, tmp_path: Path) -> None:
    """A signal the client passes on as soon as the server takes the command lands in the child
    at once, before or after the command's own handling begins: exit 130 and "interrupted"
    either way (not a server error), nothing written."""
    env = _env(runtime, "require")
    out, err = tmp_path / "out", tmp_path / "stderr"
    for _ in range(5):  # (where it lands varies)
        proc = subprocess.run([sys.executable, "-c", _INTERRUPT_AT_ONCE, str(out), str(err), str(BUNNY)],
                              capture_output=True, text=True, timeout=120, env=env)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip() == "130", err.read_text()
        assert err.read_text().strip().splitlines()[-1] == "polyfold: error: interrupted"
        assert not out.exists()
        err.unlink()
    _wait_running(env, 0, "an interrupted command still runs in the server")


def test_an_interrupt_reaches_the_command(runtime: Path, tmp_path: Path, models_dir: Path) -> None:
    env = _env(runtime, "require")
    before = _status(env)
    out = tmp_path / "out"
    # long enough to be interrupted (bunny-348 at 400 mm: dozens of pieces, seconds of work)
    proc = subprocess.Popen([*CLI, "make", str(models_dir / "bunny-348.obj"), "-o", str(out), "--size", "400",
                             "--faces", "none", "--seed", "3"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    _wait_running(env, before["running"] + 1, "the command never ran in the server")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "polyfold: error: interrupted" and "Traceback" not in err
    assert not out.exists()
    _wait_running(env, before["running"], "the interrupted command still runs in the server")


def test_a_client_that_goes_away_stops_its_command(runtime: Path, tmp_path: Path, models_dir: Path) -> None:
    env = _env(runtime, "require")
    before = _status(env)
    # long enough that the kill lands mid-work on a loaded machine too (bumpy-528 at 400 mm: 8 s
    # alone here; with bunny-348's 3.7 s a full parallel run failed once with the output folder
    # made: most likely the kill landed in its export, the status polls being slow under load)
    proc = subprocess.Popen([*CLI, "make", str(models_dir / "bumpy-528.obj"), "-o", str(tmp_path / "out"),
                             "--size", "400", "--faces", "none"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _wait_running(env, before["running"] + 1, "the command never ran in the server")
    proc.kill()
    proc.wait()
    _wait_running(env, before["running"], "the command of a killed client still runs")
    out = tmp_path / "out"  # (what is there, if anything, says how far the command got)
    assert not out.exists(), sorted(p.name for p in out.iterdir())


@pytest.mark.skipif(os.getuid() != 0, reason="needs root to run a client as another user")
def test_another_user_gets_no_answer(runtime: Path) -> None:
    path = next((runtime / "polyfold").glob("*.sock"))
    code = ("import socket, sys\n"
            "s = socket.socket(socket.AF_UNIX)\n"
            "try:\n    s.connect(sys.argv[1]); s.sendall(b'x'); print('answer', s.recv(10))\n"
            "except OSError as e: print('refused', e.errno)\n")
    python = "/usr/bin/python3"  # (the test's own may sit where that user cannot go)
    if not os.access(python, os.X_OK):
        pytest.skip("no system python3 to run as another user")
    proc = subprocess.run([python, "-c", code, str(path)], capture_output=True, text=True, timeout=60, user=65534)
    assert proc.stdout.startswith("refused 13"), proc.stdout + proc.stderr  # EACCES: not even the directory
    # and were both opened to them, the server itself turns them down (SO_PEERCRED): no answer
    for d in (runtime, runtime / "polyfold"):
        os.chmod(d, 0o711)
    os.chmod(path, 0o666)
    try:
        status = json.dumps({"op": "status"}).encode()
        asking = code.replace("b'x'", repr(struct.pack("!I", len(status)) + status))
        proc = subprocess.run([python, "-c", asking, str(path)], capture_output=True, text=True, timeout=60,
                              user=65534)
    finally:
        for d in (runtime, runtime / "polyfold"):
            os.chmod(d, 0o700)
        os.chmod(path, 0o600)
    # (closed with the request unread: the end of the stream, a reset or a broken pipe)
    assert proc.stdout.strip() in ("answer b''", "refused 104", "refused 32"), proc.stdout + proc.stderr
    assert os.stat(path).st_mode & 0o777 == 0o600
    assert os.stat(runtime / "polyfold").st_mode & 0o777 == 0o700


def test_a_directory_others_may_enter_is_refused(tmp_path_factory) -> None:
    d = Path(tempfile.mkdtemp(prefix="pfo"))
    try:
        (d / "polyfold").mkdir(mode=0o755)
        os.chmod(d / "polyfold", 0o755)
        start = _cli(_env(d, "on"), "server", "start")
        assert start.returncode == 3
        assert "not a directory of this user's alone" in one_line(start.stderr)
        # a command still runs, in its own process, and says why no server is used
        info = _cli(_env(d, "on"), "info", BUNNY)
        assert info.returncode == 0 and "bunny-128.obj" in info.stdout
        assert "not a directory of this user's alone" in info.stderr
        assert not list((d / "polyfold").iterdir())
    finally:
        shutil.rmtree(d, ignore_errors=True)


def test_a_dead_servers_socket_is_cleared(monkeypatch) -> None:
    d = Path(tempfile.mkdtemp(prefix="pfd"))
    try:
        os.chmod(d, 0o700)
        monkeypatch.setenv("XDG_RUNTIME_DIR", str(d))
        from polyfold.apps.server import socket_path

        path = socket_path()
        left = socket.socket(socket.AF_UNIX)
        left.bind(str(path))  # bound, never listening: what a killed server leaves
        left.close()
        proc = _cli(_env(d, "on"), "info", BUNNY)
        assert proc.returncode == 0 and "bunny-128.obj" in proc.stdout, proc.stderr
        assert not path.exists()
        required = _cli(_env(d, "require"), "info", BUNNY)
        assert required.returncode == 3 and "no polyfold server runs" in one_line(required.stderr)
        stopped = _cli(_env(d, "on"), "server", "status")
        assert stopped.returncode == 1
    finally:
        shutil.rmtree(d, ignore_errors=True)


def test_settings_read_at_import_get_a_server_of_their_own(monkeypatch) -> None:
    from polyfold.apps import server

    monkeypatch.delenv("NUMBA_OPT", raising=False)
    plain = server._fingerprint()
    monkeypatch.setenv("NUMBA_OPT", "1")
    assert server._fingerprint() != plain
    monkeypatch.setenv("POLYFOLD_SERVER", "require")  # the switch itself is not such a setting
    monkeypatch.setenv("NUMBA_OPT", "1")
    other = server._fingerprint()
    monkeypatch.setenv("POLYFOLD_SERVER", "off")
    assert server._fingerprint() == other


def test_only_the_compute_verbs_are_served() -> None:
    from polyfold.apps.server import SERVED, forward

    assert SERVED == {"info", "inflate", "segment", "unfold", "fold", "cspace", "make"}
    for argv in (["view", "x"], ["batch", "x"], ["server", "status"], ["warm-up"], []):
        assert forward(argv) is None  # run in the client's own process, server or not


def test_a_client_with_other_import_time_settings_runs_in_its_own_process(runtime: Path) -> None:
    """NUMBA_* (and the like) are read when modules are imported: a server started without the
    client's setting must not answer it; the command runs in the client's process."""
    env = _env(runtime, "on")
    before = _status(env)["served"]
    other = dict(env, NUMBA_OPT="0")
    proc = _cli(other, "info", BUNNY)
    assert proc.returncode == 0 and "bunny-128.obj" in proc.stdout, proc.stderr
    assert _status(env)["served"] == before
    required = _cli(dict(other, POLYFOLD_SERVER="require"), "info", BUNNY)
    assert required.returncode == 3 and "no polyfold server runs" in one_line(required.stderr)


def test_without_a_server_a_command_writes_nothing_for_one() -> None:
    """A user who never starts a server: the commands look for one without making its folder."""
    d = Path(tempfile.mkdtemp(prefix="pfn"))
    try:
        os.chmod(d, 0o700)
        info = _cli(_env(d, "on"), "info", BUNNY)
        status = _cli(_env(d, "on"), "server", "status")
        assert info.returncode == 0 and info.stderr == "", info.stderr
        assert status.returncode == 1 and "no server running" in one_line(status.stderr)
        assert list(d.iterdir()) == []
    finally:
        shutil.rmtree(d, ignore_errors=True)
