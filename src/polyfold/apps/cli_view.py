"""`polyfold view`: the browser viewer (issue 7).

Only typer is imported at module level: `polyfold --help` must stay fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer


def register(app, guard, say, fail) -> None:
    """Add the command to the typer `app`. guard: wraps a command body (one-line errors, exit
    codes); say(line): one line on stderr; fail(message, code): one error line and exit."""

    @app.command(name="view")
    @guard
    def view(
        path: Path = typer.Argument(..., help="Output folder of `polyfold make`, or a mesh file (made into a folder first)."),
        port: int = typer.Option(8080, "--port", min=0, max=65535, help="Port; 0 = any free port (a taken port moves to the next free one)."),
        host: Optional[str] = typer.Option(None, "--host", help="Address to listen on. Default 127.0.0.1 (this machine only); other addresses (e.g. 0.0.0.0) only when given here."),
        output: Optional[Path] = typer.Option(None, "-o", "--output", help="With a mesh: keep the make output in this folder (default: a temporary folder, removed on exit)."),
        parts: Optional[int] = typer.Option(None, "--parts", min=1, help="With a mesh: segment into this many parts."),
        time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="With a mesh: seconds for make's searches."),
    ) -> None:
        """Show a make folder (or a mesh, made first) in the browser: parts, nets, folding animation, inflation."""
        import shutil
        import sys
        import tempfile

        from ..pipeline.folder import load_folder, make_folder
        from .view import DEFAULT_HOST, check_host, serve, wait

        # Check the address before any slow work: a refused --host should fail at once.
        check_host(host if host is not None else DEFAULT_HOST, explicit=host is not None)
        if not path.exists():
            fail(f"{path}: no such file or folder", 2)
        temp_dir: Optional[Path] = None
        try:
            source = source_path = None
            if path.is_dir():
                if output is not None or parts is not None:
                    say("warning: -o/--output and --parts apply to a mesh file only; showing the folder as it is")
                folder = load_folder(path)
            else:
                from ..formats.meshes import load_mesh
                from ..pipeline.options import MakeOptions

                loaded = load_mesh(path)
                for w in loaded.warnings:
                    say(f"warning: {path.name}: {w}")
                if output is None:
                    temp_dir = Path(tempfile.mkdtemp(prefix="polyfold-view-"))
                out_dir = output if output is not None else temp_dir
                opts = MakeOptions(parts=parts, time_limit=time_limit)
                folder = _make_with_progress(path, out_dir, opts, make_folder, say)
                source, source_path = loaded.mesh, path
            viewer = serve(folder, host if host is not None else DEFAULT_HOST, port,
                           allow_remote=host is not None, source=source, source_path=source_path)
            if host is not None and not _is_loopback(viewer.server.get_host()):
                say(f"warning: listening on {host}: anyone who can reach this machine can view the model "
                    f"and run make into {folder.path}")
            say(f"viewer at {viewer.url}")
            sys.stderr.flush()
            wait(viewer)
        finally:
            if temp_dir is not None:
                shutil.rmtree(temp_dir, ignore_errors=True)


def _is_loopback(host: str) -> bool:
    import ipaddress

    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _make_with_progress(mesh: Path, out_dir: Path, opts, make_folder, say):
    """Run make with a live status line on a terminal, else one line per stage on stderr."""
    from rich.console import Console

    console = Console(stderr=True)
    if console.is_terminal:
        with console.status(f"polyfold make {mesh.name}") as status:
            return make_folder(mesh, out_dir, opts, lambda stage, msg: status.update(f"[bold]{stage}[/bold]: {msg}"))
    last = [None]

    def progress(stage: str, msg: str) -> None:
        if stage != last[0]:
            say(f"{stage}: {msg}")
            last[0] = stage

    return make_folder(mesh, out_dir, opts, progress)
