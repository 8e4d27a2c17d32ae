"""`polyfold server start | stop | status | run`: the resident process that runs the compute verbs
without a fresh process's start-up (`apps.server`)."""

from __future__ import annotations

import time

import typer

from .app import app, fail, guard, say

server_app = typer.Typer(no_args_is_help=True, help="A resident process that runs info, inflate, segment, "
                         "unfold, fold, cspace and make without start-up time (this user only, no network).")
app.add_typer(server_app, name="server")

IDLE = typer.Option(30.0, "--idle-minutes", min=0.1, help="Stop after this many minutes without a command.")


def _describe(status: dict) -> str:
    return (f"pid {status['pid']}, up {time.time() - status['started']:.0f} s, {status['served']} command(s) served, "
            f"{status['running']} running; stops when idle {status['idle_minutes']:g} min; socket {status['socket']}")


@server_app.command("start")
@guard
def start(idle_minutes: float = IDLE) -> None:
    """Start the server in the background (once its kernels are loaded: a few seconds, or about a
    minute the first time, when it compiles them); later commands use it."""
    from ..server import ServerError, start as run

    t0 = time.perf_counter()
    try:
        status, new = run(idle_minutes)
    except ServerError as exc:
        fail(f"server: {exc}", 3)
    if new:
        say(f"server ready in {time.perf_counter() - t0:.1f} s: {_describe(status)}")
    else:
        say(f"server already running: {_describe(status)}")


def _ask(op: str) -> dict | None:
    """The server's answer to `op` (`apps.server.request`), None when none runs; one line and
    exit 3 when the socket's directory is not private."""
    from ..server import ServerError, request

    try:
        return request(op)
    except ServerError as exc:
        fail(f"server: {exc}", 3)


@server_app.command("stop")
@guard
def stop() -> None:
    """Stop this installation's server (commands it runs finish first)."""
    status = _ask("stop")
    say("no server running" if status is None else f"server stopping: {_describe(status)}")


@server_app.command("status")
@guard
def status() -> None:
    """Whether this installation's server runs (exit 1 when not), and what it has done."""
    answer = _ask("status")
    if answer is None:
        fail("no server running (`polyfold server start`)", 1)
    print(f"polyfold server: {_describe(answer)}")


@server_app.command("run")
@guard
def run(idle_minutes: float = IDLE) -> None:
    """Run the server in this process, in the foreground (Ctrl-C stops it)."""
    from ..server import ServerError, serve

    if _ask("status") is not None:
        fail("a server already runs for this installation (`polyfold server status`)", 1)
    try:
        say("server: loading kernels ...")
        serve(idle_minutes, ready=lambda path: say(f"server ready, listening on {path} (Ctrl-C stops it)"))
    except ServerError as exc:
        fail(f"server: {exc}", 3)
