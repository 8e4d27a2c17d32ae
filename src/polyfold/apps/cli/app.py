"""The typer app behind `polyfold`: one-line errors, exit codes, and the entry point `main`."""

from __future__ import annotations

import sys
from functools import wraps
from pathlib import Path

import typer

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Turn 3D triangle meshes into verified paper nets (FOLD, SVG, PNG).",
)
bench_app = typer.Typer(no_args_is_help=True, help="Benchmarks against the paper.")
app.add_typer(bench_app, name="bench")


def say(line: str) -> None:
    """One line on stderr, prefixed `polyfold:`, in one write: print writes the text and its
    newline apart, and a Ctrl-C between the two left the next line (the "interrupted") on the end
    of this one."""
    sys.stderr.write(f"polyfold: {line}\n")
    sys.stderr.flush()


def terminal_console():
    """A rich Console on stderr when stderr is a terminal (rich's own test), else None, without
    importing rich (11-22 ms of a command's start) when it plainly is not one: not a tty, and none
    of the settings rich reads to say otherwise (TTY_COMPATIBLE, FORCE_COLOR)."""
    import os

    if not sys.stderr.isatty() and os.environ.get("TTY_COMPATIBLE", "") != "1" and "FORCE_COLOR" not in os.environ:
        return None
    from rich.console import Console

    console = Console(stderr=True)
    return console if console.is_terminal else None


def fail(message: str, code: int) -> None:
    """One error line on stderr, then exit with `code`."""
    say(f"error: {message}")
    raise typer.Exit(code)


def _stdout_gone() -> bool:
    """Whether stdout is a pipe whose reading end is closed (poll says POLLERR)."""
    import select

    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), 0)
        return any(events & select.POLLERR for _fd, events in poller.poll(0))
    except (OSError, ValueError, AttributeError):  # no poll here, or no stdout to ask
        return False


def guard(func):
    """Run a command body; turn known errors into one line + exit code, never a traceback."""

    @wraps(func)
    def wrapper(*args, **kwargs):
        from ...errors import PolyfoldError, one_line

        try:
            return func(*args, **kwargs)
        except PolyfoldError as exc:
            fail(one_line(exc), exc.exit_code)
        except KeyboardInterrupt:  # (said by `main`, which also sees those outside a command's body)
            raise typer.Exit(130) from None
        except typer.Exit:
            raise
        except BrokenPipeError as exc:
            if not _stdout_gone():
                fail(one_line(exc), 3)
            # what it printed is read no more (`polyfold info M --json | head -1`): stop quietly,
            # as `cat` would, killed by SIGPIPE (the shell's 141); nothing left to flush there
            import os

            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise typer.Exit(141) from None
        except OSError as exc:
            if exc.filename is None:
                fail(one_line(exc), 3)
            # the file system said no (full, read-only, no permission, vanished folder): the
            # user's to fix, like bad input; every writer stages its files, so nothing half-written
            fail(f"{exc.filename}: {exc.strerror or exc}", 2)
        except Exception as exc:  # last resort: still one line, no traceback
            fail(one_line(exc), 3)

    return wrapper


def load(path: Path, quiet: bool = False, faces: str = "none", size: float = 150.0):
    """The mesh file, loaded and repaired; a warning line per repair unless quiet. `faces`: the
    --faces of `mesh.simplify.face_target` (at `size` mm for auto), said on a line when it acts."""
    from ...formats.meshes import load_mesh
    from ...mesh.simplify import face_target, simplify, summary

    loaded = load_mesh(path)
    if not quiet:
        for w in loaded.warnings:
            say(f"warning: {path.name}: {w}")
    target = face_target(faces, loaded.mesh, size)
    if target is not None:
        done = simplify(loaded, target)
        if not quiet:
            say(f"{path.name}: {summary(faces, done.faces_before, done.faces_after, done.hausdorff, done.min_angle_deg)}; "
                "face numbers from here on are the simplified mesh's")
        loaded = done.loaded
    return loaded


def main() -> None:
    """The `polyfold` command: a usage error (unknown option, bad or missing value) is one line
    and exit 2, like every other error, not click's box."""
    try:
        from typer._click import exceptions as click_errors  # typer 0.2x carries its own click
    except ImportError:  # pragma: no cover - older typer on the plain click package
        from click import exceptions as click_errors

    try:
        code = app(standalone_mode=False)
    except click_errors.NoArgsIsHelpError as exc:  # `polyfold` or `polyfold bench` alone: the help
        exc.show()
        code = exc.exit_code
    except click_errors.UsageError as exc:
        where = exc.ctx.command_path if exc.ctx is not None else "polyfold"
        say(f"error: {where}: {exc.format_message()} (see {where} --help)")
        code = 2
    except (click_errors.Abort if hasattr(click_errors, "Abort") else typer.Abort, typer.Abort):
        code = 130
    if code == 130:  # Ctrl-C: in a command (`guard`) or while typer parsed its options (typer says nothing)
        say("error: interrupted")
    sys.exit(code if isinstance(code, int) else 0)


# The verbs register themselves on `app` when imported, in this order: --help lists them in the
# order of the pipeline.
from . import mesh_commands  # noqa: E402,F401,I001
from . import net_commands  # noqa: E402,F401,I001
from . import make_commands  # noqa: E402,F401,I001
from . import server_commands  # noqa: E402,F401,I001
