"""apps/cli/mesh_commands.py: `polyfold info` (JSON and plain, bad inputs), `polyfold inflate`
(output mesh and log as the API gives them, guard trips, bad arguments) and `polyfold segment`
(every output file, --parts, errors; the horse's parts unfold and fold, checked independently)."""

from __future__ import annotations

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from conftest import CLI, bad_cases, one_line, run_cli
from fold_checker import check_fold
from path_checker import check_path
from polyfold.formats.meshes import load_mesh
from polyfold.inflate.inflate import inflate


# ----------------------------------------------------------------------------------------------
# polyfold info


INFO_FIELDS = ("faces", "vertices", "edges", "components", "boundary_loops", "genus", "closed", "manifold",
               "oriented", "hyperbolic_vertices", "concavity")


@pytest.mark.parametrize(
    "rel,expected",
    [
        ("cube-12.obj", {"faces": 12, "vertices": 8, "edges": 18, "components": 1, "genus": 0, "closed": True,
                         "boundary_loops": 0, "hyperbolic_vertices": 0}),
        ("torus-50.obj", {"faces": 50, "vertices": 25, "edges": 75, "genus": 1, "closed": True,
                          "hyperbolic_vertices": 10}),
        ("bunny-128.obj", {"faces": 128, "vertices": 66, "genus": 0, "closed": True, "hyperbolic_vertices": 24}),
        ("open/cube-no-bottom-40.obj", {"faces": 40, "closed": False, "boundary_loops": 1}),
        ("bad/two-cubes.obj", {"components": 2, "closed": True}),
    ],
)
def test_info_json(models_dir: Path, rel: str, expected: dict) -> None:
    proc = run_cli("info", models_dir / rel, "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    for key in INFO_FIELDS:
        assert key in report, key
    assert isinstance(report["concavity"], float)
    for key, value in expected.items():
        assert report[key] == value, (key, report[key], value)


def test_info_plain(models_dir: Path) -> None:
    proc = run_cli("info", models_dir / "cube-12.obj")
    assert proc.returncode == 0, proc.stderr
    assert "genus" in proc.stdout


def test_info_into_a_pipe_nobody_reads_stops_quietly(models_dir: Path) -> None:
    """`polyfold info M --json | head -1` where head has gone before info writes: no "internal
    error" line, the status a process killed by SIGPIPE has in the shell (141)."""
    import os

    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        proc = subprocess.run([*CLI, "info", str(models_dir / "bunny-128.obj"), "--json"], stdout=write_end,
                              stderr=subprocess.PIPE, text=True, timeout=120, env={**os.environ, "POLYFOLD_SERVER": "off"})
    finally:
        os.close(write_end)
    assert proc.returncode == 141 and proc.stderr == "", (proc.returncode, proc.stderr)


def test_info_imports_no_numba(models_dir: Path, tmp_path: Path) -> None:
    """`info` starts fast (issue 23): it compiles nothing, so numba (about 0.35 s to import and
    start loading kernels) is not imported, on a plain mesh, a textured one or an STL file (read
    without trimesh: about a second to import). With the kernels compiled ahead of time (`make
    setup`) it imports no scipy either for a mesh of up to MESH_HULL_COMPILED_POINTS vertices
    (scipy.spatial: 0.36-0.8 s, most of its time), and reports what it reports without them."""
    import json
    import os

    import trimesh

    from polyfold.jit import ahead_ready

    stl = tmp_path / "bunny.stl"
    trimesh.load(models_dir / "bunny-128.obj", force="mesh", process=False).export(stl)
    probe = ("import atexit, sys, runpy; sys.argv = ['polyfold'] + sys.argv[1:]\n"
             "atexit.register(lambda: print(*[m for m in ('numba', 'scipy', 'trimesh') if m in sys.modules] or ['none']))\n"
             "runpy.run_module('polyfold', run_name='__main__')\n")
    for path in (models_dir / "bunny-128.obj", models_dir / "textured/spot/spot_triangulated.obj", stl):  # 66, 2,930, 66 vertices
        reports = []
        for switch in ("on", "off"):
            proc = subprocess.run([CLI[0], "-c", probe, "info", str(path), "--json"], capture_output=True,
                                  text=True, timeout=120, env={**os.environ, "POLYFOLD_AHEAD": switch})
            assert proc.returncode == 0, (path.name, proc.stderr[-500:])
            *report, loaded = proc.stdout.strip().splitlines()
            assert "numba" not in loaded.split() and "trimesh" not in loaded.split(), (path.name, switch, loaded)
            if switch == "on" and ahead_ready():
                assert loaded == "none", (path.name, loaded)
            reports.append(json.loads("\n".join(report)))
        on, off = reports
        assert abs(on.pop("concavity") - off.pop("concavity")) <= 1e-9 and on == off, (path.name, on, off)


def test_info_rejects(models_dir: Path) -> None:
    for name, spec in bad_cases():
        if spec["expect"] != "reject":
            continue
        proc = run_cli("info", models_dir / "bad" / name, "--json")
        assert proc.returncode == 2, f"{name}: exit {proc.returncode}\n{proc.stderr}"
        assert name in one_line(proc.stderr)
        assert proc.stdout.strip() == ""


# ----------------------------------------------------------------------------------------------
# polyfold inflate


def test_cli(models_dir: Path, tmp_path: Path) -> None:
    src = models_dir / "sphere-deformed-320.obj"
    out, log = tmp_path / "out.obj", tmp_path / "log.csv"
    proc = subprocess.run([*CLI, "inflate", str(src), "-o", str(out), "--log", str(log)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    line = proc.stderr.strip().splitlines()[-1]
    assert "target-hv" in line and "HV 44 -> 0" in line and "steps" in line
    loaded = load_mesh(out)
    original = load_mesh(src)
    assert loaded.warnings == ()
    assert np.array_equal(loaded.mesh.faces, original.mesh.faces)
    assert int(loaded.mesh.hyperbolic.sum()) == 0
    api = inflate(original.mesh)
    np.testing.assert_array_equal(loaded.mesh.vertices, api.mesh.vertices)  # full precision
    with open(log, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["step", "IF", "HV", "volume_change"]
    steps = [int(r[0]) for r in rows[1:]]
    assert steps[0] == 0 and all(b > a for a, b in zip(steps, steps[1:]))
    assert int(rows[-1][2]) == 0


def test_cli_guard_and_errors(models_dir: Path, tmp_path: Path) -> None:
    src = models_dir / "sphere-deformed-320.obj"
    out = tmp_path / "out.obj"
    proc = subprocess.run([*CLI, "inflate", str(src), "-o", str(out), "--pressure", "100000"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "guard: face" in proc.stderr and out.exists()
    bad = subprocess.run([*CLI, "inflate", str(tmp_path / "missing.obj"), "-o", str(tmp_path / "x.obj")],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x.obj").exists()
    mode = subprocess.run([*CLI, "inflate", str(src), "-o", str(tmp_path / "y.obj"), "--mode", "balloon"],
                          capture_output=True, text=True, timeout=300)
    assert mode.returncode == 2 and "--mode" in mode.stderr


# ----------------------------------------------------------------------------------------------
# polyfold segment: the parts go straight into the unfolder and the planner


def test_horse_parts_unfold_and_fold(models_dir, tmp_path):
    out = tmp_path / "seg"
    proc = run_cli("segment", models_dir / "horse-302.obj", "-o", out, "--parts", 7, "--no-png")
    assert proc.returncode == 0, proc.stderr
    parts = sorted(out.glob("part-*.obj"))
    assert len(parts) == 7
    for part in parts:
        fold = tmp_path / f"{part.stem}.fold"
        proc = run_cli("unfold", part, "-o", fold, "--fold", "--max-pieces", 1, "--seed", 1, "--time-limit", 60)
        assert proc.returncode == 0, f"{part.name}: {proc.stderr}"
        report = check_fold(str(fold), str(part))
        assert report.ok and report.pieces == 1, f"{part.name}:\n{report}"
        path_report = check_path(fold)
        assert path_report.ok, f"{part.name}:\n{path_report}"


# ----------------------------------------------------------------------------------------------
# polyfold segment: outputs and errors


def test_segment_cli_writes_every_output(models_dir, tmp_path):
    src = models_dir / "bunny-128.obj"
    out = tmp_path / "out"
    out.mkdir()
    (out / "part-99.obj").write_text("stale\n")
    (out / ".polyfold-manifest.json").write_text('{"files": ["part-99.obj"]}')  # an earlier run's
    proc = run_cli("segment", src, "-o", out, "--tau", 0.05)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((out / "labels.json").read_text())
    assert set(doc) >= {"labels", "tau", "concavity"}
    labels = np.array(doc["labels"])
    n_parts = len(doc["concavity"])
    assert doc["tau"] == 0.05 and max(doc["concavity"]) <= 0.05
    assert len(labels) == 128 and labels.min() == 0 and labels.max() == n_parts - 1
    assert not (out / "part-99.obj").exists()
    assert sorted(p.name for p in out.glob("part-*.obj")) == sorted(f"part-{k}.obj" for k in range(n_parts))
    assert not [p for p in out.iterdir() if p.is_dir()]  # no staged folder left
    # the parts, in the whole mesh's frame, are exactly the labelled faces of the input
    whole = load_mesh(src).mesh
    centroids = whole.vertices[whole.faces].mean(axis=1)
    for k in range(n_parts):
        part = load_mesh(out / f"part-{k}.obj").mesh
        dist, idx = cKDTree(centroids).query(part.vertices[part.faces].mean(axis=1))
        assert dist.max() < 1e-12
        assert sorted(idx.tolist()) == np.flatnonzero(labels == k).tolist()
    # coloured whole mesh: one colour per part, faces in input order
    ply = trimesh.load(out / "segments.ply", process=False)
    assert len(ply.faces) == 128
    colors = np.asarray(ply.visual.face_colors)[:, :3]
    by_part = {tuple(c) for c in colors[labels == 0]}
    assert len(by_part) == 1 and len({tuple(c) for c in colors}) == n_parts
    glb = trimesh.load(out / "segments.glb", force="mesh", process=False)
    assert len(glb.faces) == 128
    png = (out / "segments.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 5000
    assert "parts" in proc.stderr and "Traceback" not in proc.stderr


def test_segment_cli_parts_and_errors(models_dir, tmp_path):
    proc = run_cli("segment", models_dir / "fish-472.obj", "-o", tmp_path / "f", "--parts", 5, "--no-png")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((tmp_path / "f" / "labels.json").read_text())
    assert len(doc["concavity"]) == 5 and not (tmp_path / "f" / "segments.png").exists()
    proc = run_cli("segment", models_dir / "fish-472.obj", "-o", tmp_path / "g", "--parts", 5, "--tau", 0.1)
    assert proc.returncode == 2 and "--tau or --parts" in one_line(proc.stderr)
    assert not (tmp_path / "g").exists()
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    proc = run_cli("segment", bad, "-o", tmp_path / "h")
    assert proc.returncode == 2 and "bad.obj" in one_line(proc.stderr)
    assert not (tmp_path / "h").exists()
