"""`polyfold server`: a resident process that runs the command line's compute verbs at once.

Every fresh `polyfold` process imports what its command needs (numpy, shapely, reportlab...;
numba too where no kernel was compiled ahead of time, `jit`) and loads its kernels before it
does any work, and its first calls build what later ones reuse: about half of a warm `make` of
the bunny on a 2-core machine. A server pays that once: it imports everything and runs the
warm-up's sections (every kernel loaded, ahead of time and just in time), then waits on a Unix
socket.
`polyfold info | inflate | segment | unfold | fold | cspace | make` (SERVED) looks for it first
(`forward`): it hands over its arguments, working directory, environment, umask, CPU affinity and
its stdin, stdout and stderr themselves (file descriptors, SCM_RIGHTS), and the server forks a
child that runs the command as the client would have, writing straight to the same terminal,
pipe or file. The child's exit code (128 + N when signal N ended it) comes back on the socket.
SIGINT, SIGTERM and SIGHUP sent to the client are sent on to the child; a client that goes away
interrupts its child. Without a server (or with POLYFOLD_SERVER=off) the command runs in its own
process, as before.

Forked, not served in-process: every command starts from the same warm state, and whatever one
command leaves in memory (caches, globals, garbage) never reaches the next.

Safety: no network. The socket lives in a directory only this user may enter
(`$XDG_RUNTIME_DIR/polyfold`, else `/tmp/polyfold-UID`; made 0700, refused when another user owns
it or others may enter it), the socket itself is 0600, and the server checks every caller's user
id (SO_PEERCRED). It runs the SERVED verbs and nothing else. Staleness: the socket's name hashes
the Python interpreter, polyfold's source files (paths, sizes, mtimes) and the environment
settings read at import time (NUMBA_*, OMP_*, PYTHON*...), so an edited or reinstalled polyfold,
or a client with other such settings, never gets an answer from the wrong code: it runs in its
own process, and the old server stops within a minute, when no command of its runs.

Linux only (fork, SO_PEERCRED, pidfd). This module imports only the standard library at the top:
the client side runs before anything else in every `polyfold` process.
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import struct
import sys
import time
from pathlib import Path
from typing import Callable

SERVED = frozenset({"info", "inflate", "segment", "unfold", "fold", "cspace", "make"})
SWITCH = "POLYFOLD_SERVER"  # "off": never use a server; "require": fail when none answers
IDLE_MINUTES = 30.0  # a server with no command to run for this long stops
# environment variables read when modules are imported (numba's config, the BLAS thread pools,
# Python's own): a client whose values differ from the server's gets a server of its own
_IMPORT_TIME_ENV = ("NUMBA_", "OMP_", "OPENBLAS_", "MKL_", "PYTHON")
_FORWARDED = ("SIGINT", "SIGTERM", "SIGHUP")
_ACCEPTED = b"\x01"
_HEADER = struct.Struct("!I")
_CODE = struct.Struct("!i")
_LONGEST = 1 << 24  # bytes of a request: arguments and environment (a longer one is turned down)
START_WAIT_S = 900.0  # `server start` waits this long for a server that compiles its kernels first


class ServerError(Exception):
    """The server cannot be used or started (unsafe directory, start failed): one line."""


def _fingerprint() -> str:
    """Hash of what a server's answers depend on besides the request (see the module docstring)."""
    # the interpreter and the environment (a venv's python and python3 are one interpreter)
    from ..sources import hash_sources

    h = hashlib.sha256(f"{os.path.realpath(sys.executable)}\n{sys.prefix}\n".encode())
    hash_sources(h)
    for key in sorted(os.environ):
        if key.startswith(_IMPORT_TIME_ENV) and key != SWITCH:
            h.update(f"{key}={os.environ[key]}\n".encode())
    return h.hexdigest()[:16]


def runtime_dir(create: bool = True) -> Path | None:
    """This user's private directory for server sockets (see the module docstring), made when
    missing (else None: no server was ever started there, and a command's start-up writes
    nothing); ServerError when it is not private, or not on Linux."""
    if not sys.platform.startswith("linux"):
        raise ServerError("the server needs Linux (fork, SO_PEERCRED, pidfd); every command runs in its own process")
    base = os.environ.get("XDG_RUNTIME_DIR")
    uid = os.getuid()
    # (a Unix socket's path holds at most 107 bytes: the socket's name and a temporary suffix fit)
    if base and os.path.isdir(base) and os.stat(base).st_uid == uid and len(base) < 60:
        d = Path(base) / "polyfold"
    else:
        d = Path("/tmp") / f"polyfold-{uid}"
    try:
        if create:
            d.mkdir(mode=0o700, exist_ok=True)
        elif not os.path.lexists(d):
            return None
        st = os.lstat(d)
    except OSError as exc:
        raise ServerError(f"{d}: {exc.strerror or exc}") from None
    import stat

    if not stat.S_ISDIR(st.st_mode) or st.st_uid != uid or st.st_mode & 0o077:
        raise ServerError(f"{d}: not a directory of this user's alone (mode {st.st_mode & 0o777:o}); "
                          "no server is used or started")
    return d


def socket_path(create: bool = True) -> Path | None:
    """Where the server for this polyfold and these settings listens (None: see `runtime_dir`)."""
    d = runtime_dir(create)
    return None if d is None else d / f"{_fingerprint()}.sock"


def _connect(path: Path | None) -> socket.socket | None:
    """A connection to the server at `path`; None when none listens there (a socket left by a
    server that died is removed)."""
    if path is None:
        return None
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(str(path))
        return sock
    except (FileNotFoundError, ConnectionRefusedError) as exc:
        sock.close()
        if isinstance(exc, ConnectionRefusedError):
            try:
                path.unlink()
            except OSError:
                pass
        return None
    except OSError:
        sock.close()
        return None


def _send(sock: socket.socket, message: dict, fds: list[int] = ()) -> None:
    data = json.dumps(message).encode()
    socket.send_fds(sock, [_HEADER.pack(len(data))], list(fds)) if fds else sock.sendall(_HEADER.pack(len(data)))
    sock.sendall(data)


def _recv_exact(sock: socket.socket, n: int) -> bytes:
    out = b""
    while len(out) < n:
        chunk = sock.recv(n - len(out))
        if not chunk:
            break
        out += chunk
    return out


def _recv(sock: socket.socket, max_fds: int = 0) -> tuple[dict | None, list[int]]:
    """A message (None when the peer closed first) and the file descriptors sent with it."""
    fds: list[int] = []
    if max_fds:
        head, fds, _flags, _addr = socket.recv_fds(sock, _HEADER.size, max_fds)
    else:
        head = sock.recv(_HEADER.size)
    head += _recv_exact(sock, _HEADER.size - len(head)) if head else b""
    if len(head) < _HEADER.size or _HEADER.unpack(head)[0] > _LONGEST:
        return None, fds
    data = _recv_exact(sock, _HEADER.unpack(head)[0])
    return json.loads(data.decode()), fds


def _stdio() -> tuple[list[int], list[int]]:
    """This process's fds 0, 1, 2 to hand over, /dev/null for any that is closed; the /dev/null
    fds opened (to close after)."""
    fds, opened = [], []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
            fds.append(fd)
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
            fds.append(null)
            opened.append(null)
    return fds, opened


def forward(argv: list[str]) -> int | None:
    """Run `polyfold ARGV` in a running server and return its exit code; None when it is to run in
    this process (not a SERVED verb, not Linux, POLYFOLD_SERVER=off, no server for this polyfold).
    With POLYFOLD_SERVER=require, no server is an error (exit 3)."""
    switch = os.environ.get(SWITCH, "")
    if not argv or argv[0] not in SERVED or switch == "off" or not sys.platform.startswith("linux"):
        return None
    try:
        sock = _connect(socket_path(create=False))
    except ServerError as exc:
        print(f"polyfold: warning: {exc}", file=sys.stderr)
        sock = None
    if sock is None:
        if switch == "require":
            print("polyfold: error: no polyfold server runs for this installation (POLYFOLD_SERVER=require; "
                  "start one with `polyfold server start`)", file=sys.stderr)
            return 3
        return None
    try:
        return _run_there(sock, argv)
    except KeyboardInterrupt:  # before the server took the command: nothing ran
        print("polyfold: error: interrupted", file=sys.stderr)
        return 130


def _run_there(sock: socket.socket, argv: list[str]) -> int | None:
    """`forward`'s conversation on a connected socket."""
    import signal

    with sock:
        fds, opened = _stdio()
        try:
            affinity = sorted(os.sched_getaffinity(0))
            umask = os.umask(0o022)
            os.umask(umask)
            _send(sock, {"op": "run", "argv": argv, "cwd": os.getcwd(), "env": dict(os.environ), "umask": umask,
                         "affinity": affinity}, fds)
        except OSError:
            return None  # the server went away meanwhile: run here
        finally:
            for fd in opened:
                os.close(fd)
        try:
            accepted = sock.recv(1)
        except OSError:
            accepted = b""
        if accepted != _ACCEPTED:  # turned down before anything ran (or gone): run here
            return None

        def send_on(signum: int, _frame) -> None:
            try:
                sock.send(bytes([signum]))
            except OSError:
                pass

        for name in _FORWARDED:
            signal.signal(getattr(signal, name), send_on)
        try:
            code = _recv_exact(sock, _CODE.size)
        except OSError:
            code = b""
        if len(code) < _CODE.size:
            print("polyfold: error: the polyfold server stopped while it ran this command", file=sys.stderr)
            return 3
        return _CODE.unpack(code)[0]


def request(op: str) -> dict | None:
    """Ask this polyfold's server `op` ("status" or "stop"); its answer, or None when none runs."""
    sock = _connect(socket_path(create=False))
    if sock is None:
        return None
    with sock:
        try:
            _send(sock, {"op": op})
            answer, _ = _recv(sock)
        except OSError:
            return None
    return answer


def start(idle_minutes: float = IDLE_MINUTES, wait_s: float = START_WAIT_S) -> tuple[dict, bool]:
    """Start a server in the background unless one runs; (its status, whether it was started
    now). It is ready when this returns: its kernels loaded (compiled first when numba's cache
    is empty, as `polyfold warm-up` would). Its log: the socket's path with .log. ServerError
    when it does not come up."""
    import subprocess

    status = request("status")
    if status is not None:
        return status, False
    path = socket_path()
    log = path.with_suffix(".log")
    with open(log, "wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "polyfold.apps.server", "--idle-minutes", str(idle_minutes)],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err,
                                start_new_session=True, cwd="/")  # (holds no directory of the caller's)
    t0 = time.monotonic()
    while time.monotonic() - t0 < wait_s:
        if proc.poll() is not None:
            tail = log.read_text(errors="replace").strip().splitlines()[-1:] or ["no message"]
            raise ServerError(f"the server stopped as it started (exit {proc.returncode}): {tail[0]}")
        status = request("status")
        if status is not None:
            return status, True
        time.sleep(0.05)
    proc.kill()
    raise ServerError(f"the server was not ready after {wait_s:.0f} s (log: {log})")


# ---- the server side ----------------------------------------------------------------------------

# each served verb once, quietly, through the command line itself, on the warm-up's bumpy sphere
# ({mesh}) in a temporary folder ({tmp}): what a command loads on its first call (its modules, typer's
# command tree) is then loaded in the server, not in every child
_FIRST_CALLS = (("info", "{mesh}"), ("make", "{mesh}", "-o", "{tmp}/make", "-q"),
                ("unfold", "{mesh}", "-o", "{tmp}/net.fold", "-q"), ("fold", "{tmp}/net.fold", "-o", "{tmp}/path.fold"),
                ("cspace", "{tmp}/net.fold", "--samples", "20"), ("segment", "{mesh}", "-o", "{tmp}/seg", "-q"),
                ("inflate", "{mesh}", "-o", "{tmp}/inflated.obj", "--max-steps", "5"))


def _preload() -> None:
    """Import what the commands import and load every kernel they call (compiling them first when
    numba's cache is empty): `_FIRST_CALLS`, then the warm-up's sections and make's label kernels
    for crowded pieces just in time."""
    import contextlib
    import io
    import tempfile

    from ..formats.meshes import obj_text
    from ..jit import just_in_time
    from .cli.app import app
    from .warmup import WARM_UP, bumpy_sphere, run_sections

    with tempfile.TemporaryDirectory() as tmp:
        mesh = os.path.join(tmp, "warm-up.obj")
        with open(mesh, "w") as out:
            out.write(obj_text(*bumpy_sphere()))
        for call in _FIRST_CALLS:
            argv = [a.format(mesh=mesh, tmp=tmp) for a in call]
            quiet = io.StringIO()
            with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
                try:
                    app(argv, standalone_mode=False)
                except SystemExit:
                    pass
    # and numba's dispatchers too (the calls above ran ahead of time where `polyfold warm-up` built
    # them): loaded here once, not in each child whose call has types the ahead-of-time module lacks
    with just_in_time():
        run_sections(list(WARM_UP) + ["labels"])


def _child(conn: socket.socket, fds: list[int], req: dict) -> None:
    """In the forked child: become the client's process (stdio, directory, environment, umask,
    affinity), run the command and exit with its code (the server reports it)."""
    import io
    import signal
    import threading

    from ..processes import exit_status

    signal.signal(signal.SIGINT, signal.default_int_handler)
    for name in ("SIGTERM", "SIGHUP", "SIGCHLD"):
        signal.signal(getattr(signal, name), signal.SIG_DFL)
    for target, fd in enumerate(fds):
        os.dup2(fd, target)
    for fd in set(fds) - {0, 1, 2}:
        os.close(fd)
    encoding = "utf-8"
    sys.stdin = sys.__stdin__ = io.TextIOWrapper(io.FileIO(0, "r", closefd=False), encoding=encoding)
    sys.stdout = sys.__stdout__ = io.TextIOWrapper(io.FileIO(1, "w", closefd=False), encoding=encoding,
                                                   line_buffering=os.isatty(1))
    sys.stderr = sys.__stderr__ = io.TextIOWrapper(io.FileIO(2, "w", closefd=False), encoding=encoding,
                                                   errors="backslashreplace", write_through=True)
    code = 3
    try:
        os.chdir(req["cwd"])
        os.environ.clear()
        os.environ.update(req["env"])
        from ..formats.files import use_umask

        use_umask(int(req["umask"]))
        try:
            os.sched_setaffinity(0, req["affinity"])
        except (OSError, ValueError):
            pass

        passed_on = {int(getattr(signal, name)) for name in _FORWARDED}

        def listen() -> None:  # signals the client was sent; its going away interrupts the command
            while True:
                try:
                    b = conn.recv(1)
                except OSError:
                    b = b""
                if not b:
                    os.kill(os.getpid(), signal.SIGINT)
                    return
                if b[0] in passed_on:
                    os.kill(os.getpid(), b[0])

        sys.argv = ["polyfold", *req["argv"]]
        from .cli.app import main

        # (a signal the client passed on before this thread ran waits in the socket: it lands at
        # once, maybe before main's own handling begins, and is an interrupt all the same)
        threading.Thread(target=listen, daemon=True).start()
        main()
        code = 0
    except SystemExit as exc:
        code = exit_status(exc)
    except KeyboardInterrupt:
        print("polyfold: error: interrupted", file=sys.stderr)
        code = 130
    except BaseException as exc:  # (the command's own errors are one line already: this is the server's)
        try:
            print(f"polyfold: error: server: {type(exc).__name__}: {exc}", file=sys.stderr)
        except Exception:
            pass
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:
                pass
        os._exit(code)


class _Server:
    """The listening socket, the children running commands and the counts `status` reports."""

    def __init__(self, path: Path, idle_minutes: float) -> None:
        import selectors

        self.path, self.idle_s = path, idle_minutes * 60.0
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp")
        self.listener.bind(str(tmp))
        os.chmod(tmp, 0o600)
        self.listener.listen(16)
        os.replace(tmp, path)  # ready: clients find it only now
        self.inode = os.stat(path).st_ino
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.listener, selectors.EVENT_READ)
        self.running: dict[int, tuple[int, socket.socket]] = {}  # pidfd: (pid, its client's connection)
        self.started, self.served, self.last, self.stop = time.time(), 0, time.monotonic(), False

    def ours(self) -> bool:
        """Whether the socket's name is still this server's (not removed, not taken by another)."""
        try:
            return os.stat(self.path).st_ino == self.inode
        except OSError:
            return False

    def current(self) -> bool:
        """Whether this server's code is still polyfold's: its sources unchanged since it started
        (a client of edited or reinstalled sources looks for another socket's name)."""
        return _fingerprint() == self.path.stem

    def loop(self) -> None:
        import selectors

        while True:
            idle = time.monotonic() - self.last
            if self.stop and self.listener.fileno() >= 0:  # no new commands; the running ones finish
                self.sel.unregister(self.listener)
                self.close()
            if not self.running and (self.stop or idle >= self.idle_s or not self.ours() or not self.current()):
                return  # (asked to, idle, or of no use: its name taken, or its sources changed)
            timeout = None if self.running else max(0.0, min(self.idle_s - idle, 60.0))
            for key, _ in self.sel.select(timeout):
                if key.fileobj is self.listener:
                    try:
                        conn, _ = self.listener.accept()
                    except OSError:
                        continue
                    child = self.take(conn)
                    if child is not None:
                        self.running[child[0]] = (child[1], conn)
                        self.sel.register(child[0], selectors.EVENT_READ)
                        self.served += 1
                else:
                    self.reap(key.fileobj)

    def reap(self, pidfd: int) -> None:
        """A child ended: its exit code (128 + N for signal N) to its client."""
        pid, conn = self.running.pop(pidfd)
        self.sel.unregister(pidfd)
        os.close(pidfd)
        _, status = os.waitpid(pid, 0)
        code = os.waitstatus_to_exitcode(status)
        try:
            conn.sendall(_CODE.pack(code if code >= 0 else 128 - code))
        except OSError:
            pass
        conn.close()
        self.last = time.monotonic()

    def status(self) -> dict:
        return {"pid": os.getpid(), "started": self.started, "served": self.served, "running": len(self.running),
                "socket": str(self.path), "idle_minutes": self.idle_s / 60.0}

    def take(self, conn: socket.socket) -> tuple[int, int] | None:
        """Answer one connection: (pidfd, pid) of the child forked to run its command, or None
        (answered and closed, or turned down)."""
        fds: list[int] = []
        try:
            uid = struct.unpack("3i", conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED,
                                                      struct.calcsize("3i")))[1]
            if uid != os.getuid():
                conn.close()
                return None
            conn.settimeout(10.0)  # a client that connects and says nothing does not hold the server
            req, fds = _recv(conn, 3)
            op = None if req is None else req.get("op")
            if op in ("status", "stop"):
                self.stop |= op == "stop"
                _send(conn, self.status())
                conn.close()
                return None
            if op != "run" or len(fds) != 3 or not req.get("argv") or req["argv"][0] not in SERVED:
                conn.close()
                return None
            conn.settimeout(None)
            pid = os.fork()
            if pid == 0:
                # nothing of the server's but this client's connection stays open in the child
                for fd in (self.listener, self.sel, *(c for _, c in self.running.values())):
                    fd.close()
                for pidfd in self.running:
                    os.close(pidfd)
                _child(conn, fds, req)
            pidfd = os.pidfd_open(pid)
            conn.sendall(_ACCEPTED)
            return pidfd, pid
        except (OSError, ValueError, KeyError, TypeError):
            conn.close()
            return None
        finally:
            for fd in fds:
                os.close(fd)

    def close(self) -> None:
        """Stop listening (the socket's name removed while it is this server's)."""
        if self.ours():
            self.path.unlink()
        self.listener.close()


def serve(idle_minutes: float = IDLE_MINUTES, ready: Callable[[str], None] | None = None) -> None:
    """Run a server in this process (see the module docstring) until it has been idle for
    `idle_minutes`, is asked to stop (`request("stop")`, SIGTERM, SIGINT), or another server has
    taken its socket's name. Commands running then finish; their clients get their exit codes."""
    import gc
    import signal

    path = socket_path()
    _preload()
    gc.collect()
    gc.freeze()  # (the children's collections skip what every one of them inherits)
    server = _Server(path, idle_minutes)
    if ready is not None:
        ready(str(path))

    def stop(*_) -> None:
        server.stop = True
        if not server.running:
            raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    try:
        server.loop()
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
    try:  # a clean end: the log `start` made for it says nothing worth keeping
        path.with_suffix(".log").unlink()
    except OSError:
        pass


if __name__ == "__main__":  # `polyfold server start` runs this in the background
    import argparse

    parser = argparse.ArgumentParser(prog="python -m polyfold.apps.server")
    parser.add_argument("--idle-minutes", type=float, default=IDLE_MINUTES)
    idle = parser.parse_args().idle_minutes
    from ..processes import in_roomy_stack

    in_roomy_stack(lambda: serve(idle))
