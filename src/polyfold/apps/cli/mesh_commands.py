"""The verbs on meshes: info, inflate, segment."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Optional

import typer

from . import options
from .app import app, fail, guard, load, say


@app.command()
@guard
def info(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    json_out: bool = typer.Option(False, "--json", help="Print the report as JSON."),
) -> None:
    """Load and check a mesh; report its topology, hyperbolic vertices and concavity."""
    import json

    from ...mesh.repair import describe

    loaded = load(mesh)
    report = describe(loaded)
    if json_out:
        print(json.dumps(report, indent=2))
        return
    width = max(len(k) for k in report)
    for key, value in report.items():
        if key == "warnings":
            continue
        if isinstance(value, float):
            value = f"{value:.6g}"
        print(f"{key:<{width}}  {value}")


@app.command()
@guard
def inflate(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Inflated mesh (.obj, .ply, .off, .stl, .glb by suffix; same faces, same order, input units)."),
    mode: str = typer.Option("constrained", "--mode", help="constrained (keeps convex and deep concave features) or uniform (plain balloon)."),
    pressure: float = typer.Option(0.5, "--pressure", min=0.0, help="Pressure p (UI range 0.1-1)."),
    stiffness_ratio: float = typer.Option(10.0, "--stiffness-ratio", min=0.0, help="Stiff-edge multiplier (constrained mode)."),
    vertex_stiffness: float = typer.Option(1.0, "--vertex-stiffness", min=0.0, help="Rest-spring factor (constrained mode)."),
    until_hv: int = typer.Option(0, "--until-hv", min=0, help="Stop once at most this many hyperbolic vertices remain."),
    max_steps: int = typer.Option(20000, "--max-steps", min=0, help="Stop after this many steps."),
    log: Optional[Path] = typer.Option(None, "--log", help="Write step,IF,HV,volume_change every 50 steps to this CSV."),
) -> None:
    """Inflate a mesh to remove hyperbolic (saddle) vertices while keeping its faces (paper Sec. 3)."""
    if mode not in ("constrained", "uniform"):
        fail(f"--mode must be 'constrained' or 'uniform', not {mode!r}", 2)
    from ...formats.files import atomic_write, check_outputs
    from ...formats.meshes import write_mesh
    from ...inflate.inflate import inflate as inflate_mesh

    check_outputs([output, log], [mesh])
    t0 = time.perf_counter()
    loaded = load(mesh)
    show = sys.stderr.isatty()

    def progress(step: int, rate: float, hv: int) -> None:
        if show:
            print(f"\rpolyfold: step {step}, IF {rate:.4f}, HV {hv}   ", end="", file=sys.stderr, flush=True)

    res = inflate_mesh(loaded.mesh, mode=mode, pressure=pressure, stiffness_ratio=stiffness_ratio,
                       vertex_stiffness=vertex_stiffness, until_hv=until_hv, max_steps=max_steps, progress=progress)
    if show:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    for note in res.notes:
        say(f"warning: {mesh.name}: {note}")
    write_mesh(output, res.mesh.vertices, res.mesh.faces,
               header=f"{mesh.name} inflated by polyfold ({mode}): {res.steps} steps, {res.stop_reason}")
    if log is not None:
        rows = ["step,IF,HV,volume_change"]
        rows += [f"{int(s)},{r!r},{int(h)},{v!r}" for s, r, h, v in res.history.tolist()]
        atomic_write(log, "\n".join(rows) + "\n")
    seconds = time.perf_counter() - t0
    say(f"{mesh.name}: {res.steps} steps, {seconds:.2f} s, stopped: {res.stop_reason}, "
         f"HV {res.hyperbolic_start} -> {res.hyperbolic}, IF {res.inflation_rate:.4f}")


@app.command()
@guard
def segment(
    mesh: Path = typer.Argument(..., help="Mesh file (OBJ, OFF, STL, PLY, GLB)."),
    output: Path = typer.Option(..., "-o", "--output", help="Folder for part-K.obj, labels.json, segments.ply/.glb/.png."),
    tau: Optional[float] = typer.Option(None, "--tau", min=0.0, help="Concavity bound per part, fraction of the bounding-box diagonal (default 0.05)."),
    parts: Optional[int] = typer.Option(None, "--parts", min=1, help="Pick tau so that there are this many parts (instead of --tau)."),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the surface samples of the concavity measure."),
    time_limit: float = typer.Option(60.0, "--time-limit", min=0.0, help="With --parts: seconds for the search of tau (then the closest count found)."),
    png: bool = typer.Option(True, "--png/--no-png", help="Also draw segments.png."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No warnings or table, only errors."),
    faces: str = options.FACES,
) -> None:
    """Split a mesh into few connected, nearly convex parts (concavity <= tau each), ready to unfold."""
    if tau is not None and parts is not None:
        fail("give --tau or --parts, not both", 2)
    from ...deadline import Deadline
    from ...formats.segmentation import check_segmentation_folder, write_segmentation
    from ...mesh.simplify import check_faces_spec
    from ...segment.segment import DEFAULT_TAU, segment as segment_mesh

    check_segmentation_folder(output, (mesh,))
    check_faces_spec(faces)
    t0 = time.perf_counter()
    deadline = Deadline.after(time_limit)
    loaded = load(mesh, quiet, faces)
    seg = segment_mesh(loaded.mesh, tau=DEFAULT_TAU if tau is None else tau, parts=parts, seed=seed, deadline=deadline)
    seconds = time.perf_counter() - t0
    if parts is not None and seg.n_parts != parts and not quiet:
        why = (f"the search of tau ran out of time after {time_limit:g} s: the closest count found" if seg.timed_out
               else "even tau 0 gives fewer: the parts are already convex" if seg.n_parts < parts
               else "the mesh has that many separate components")
        say(f"warning: {mesh.name}: {seg.n_parts} parts instead of {parts} ({why})")
    write_segmentation(seg, loaded.mesh, output, n_input_faces=loaded.n_input_faces, source_name=mesh.name, png=png,
                       inputs=(mesh,))
    if not quiet:
        print(f"{'part':>4} {'faces':>6} {'concavity':>10}")
        for k, (p, c) in enumerate(zip(seg.parts, seg.concavity)):
            print(f"{k:>4} {p.n_faces:>6} {c:>10.4f}")
        say(f"{mesh.name}: {seg.n_parts} parts, tau {seg.tau:.4g}, {seconds:.2f} s -> {output}")
