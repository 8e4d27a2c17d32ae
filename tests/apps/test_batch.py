"""apps/batch.py with apps/isolation.py and apps/study.py, `polyfold batch` (issue 9): one isolated
process per mesh, statuses, resume, summary files, the CLI, the same batch on a Dask LocalCluster,
and the two studies. (One file: the tests share the input folder and the first batch's results.)

Crashes and hangs come from the test hook POLYFOLD_BATCH_FAULT (see polyfold/apps/isolation.py): the task
of crash-me.obj calls os._exit(1), segv-me.obj segfaults, hang-me.obj sleeps until killed."""

from __future__ import annotations

import csv
import importlib
import json
import os
import shutil
import time
import xml.etree.ElementTree as ET
from dataclasses import fields
from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import one_line, run_cli
from polyfold.apps.batch import BatchRow, expand, out_names, run_batch
from polyfold.apps.isolation import FAULT_ENV, PRELOAD
from polyfold.apps.study import run_study
from polyfold.errors import PolyfoldError
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

GOOD = ("cube-12", "icosahedron-20", "octahedron-8")
FAULTS = "crash:crash-me.obj,segv:segv-me.obj,hang:hang-me.obj"
EXPECTED = {"crash-me": "crashed", "cube-12": "ok", "hang-me": "timeout", "icosahedron-20": "ok",
            "nan-vertex": "error", "octahedron-8": "ok", "segv-me": "crashed"}
OPTS = MakeOptions(fold=False, size=100.0, guide=False)  # short runs; folding and the guide are tested elsewhere
HARD = 12.0  # hard limit of the runs with hang-me: far above a small make (~1-3 s)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, models_dir) -> Path:
    """3 small closed meshes, one bad file (rejected), three copies of the octahedron for the hook."""
    d = tmp_path_factory.mktemp("batch") / "in"
    d.mkdir()
    for name in GOOD:
        shutil.copy(models_dir / f"{name}.obj", d)
    shutil.copy(models_dir / "bad" / "nan-vertex.obj", d)
    for fault in ("crash", "segv", "hang"):
        shutil.copy(models_dir / "octahedron-8.obj", d / f"{fault}-me.obj")
    # One make in this process first: on a fresh clone it compiles the numba kernels into their
    # on-disk cache (~10 s), which the batch's task processes then load. Otherwise the first
    # tasks, compiling at once, can run into HARD and the statuses would measure the compiler.
    make(models_dir / "cube-12.obj", d.parent / "warm-up", OPTS)
    return d


def _batch(inputs: Path, out: Path, **kw) -> SimpleNamespace:
    """run_batch over every input with the fault hook on; the summary files as read right after."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(FAULT_ENV, FAULTS)
        t0 = time.perf_counter()
        result = run_batch(str(inputs / "*.obj"), out, OPTS, hard_limit=HARD, **kw)
        wall = time.perf_counter() - t0
    return SimpleNamespace(result=result, wall=wall, out=out, csv=(out / "summary.csv").read_text(),
                           jsonl=(out / "summary.jsonl").read_text())


@pytest.fixture(scope="module")
def local(inputs, tmp_path_factory) -> SimpleNamespace:
    return _batch(inputs, tmp_path_factory.mktemp("local") / "out", workers=2)


def _statuses(rows) -> dict[str, str]:
    return {r.out: r.status for r in rows}


def _check_rows(run: SimpleNamespace) -> None:
    rows = run.result.rows
    assert _statuses(rows) == EXPECTED
    assert [r.out for r in rows] == sorted(EXPECTED)  # mesh order, not completion order
    by = {r.out: r for r in rows}
    for name in GOOD:
        r = by[name]
        report = json.loads((run.out / name / "report.json").read_text())
        assert r.faces == report["input"]["faces"] == int(name.rsplit("-", 1)[1])
        assert r.pieces == len(report["pieces"]) >= 1 and r.parts >= 1 and r.pages >= 1
        assert r.error == ""
        for stage in ("load", "inflate", "segment", "unfold", "fold", "layout", "export"):
            assert getattr(r, f"{stage}_s") == pytest.approx(report["stages"][stage]["seconds"])
        assert r.total_s >= report["seconds"]
    err = by["nan-vertex"].error
    assert "non-finite" in err and "nan-vertex.obj" in err and "\n" not in err
    assert not (run.out / "nan-vertex" / "report.json").exists()
    assert "exit code 1" in by["crash-me"].error
    assert "SIGSEGV" in by["segv-me"].error
    assert by["hang-me"].error.startswith("killed at the hard limit") and HARD <= by["hang-me"].total_s < HARD + 5
    for name in ("nan-vertex", "crash-me", "segv-me", "hang-me"):
        assert by[name].faces is None and by[name].pieces is None
    assert {r.out for r in run.result.failed} == {"nan-vertex", "crash-me", "segv-me", "hang-me"}
    # the hang held one of two workers; everything else ran beside it
    assert run.wall < HARD + 20


def test_local_pool_statuses(local) -> None:
    _check_rows(local)
    assert local.result.counts() == {"ok": 3, "skipped": 0, "error": 1, "timeout": 1, "crashed": 2}


def test_summary_files(local) -> None:
    rows = list(csv.DictReader(local.csv.splitlines()))
    header = local.csv.splitlines()[0].split(",")
    assert header == [f.name for f in fields(BatchRow)]
    assert header[:6] == ["mesh", "out", "faces", "parts", "pieces", "pages"]
    assert [r["out"] for r in rows] == sorted(EXPECTED)
    assert {r["out"]: r["status"] for r in rows} == EXPECTED
    jrows = [json.loads(line) for line in local.jsonl.splitlines()]
    assert len(jrows) == len(rows) == 7
    for c, j, r in zip(rows, jrows, local.result.rows):
        assert j["mesh"] == c["mesh"] == r.mesh and j["status"] == c["status"] == r.status
        assert j["error"] == c["error"] == r.error
        assert j["faces"] == r.faces and (c["faces"] == "" if r.faces is None else int(c["faces"]) == r.faces)
        assert float(c["total_s"]) == pytest.approx(j["total_s"], rel=1e-4)
        if r.status == "ok":
            assert float(c["unfold_s"]) == pytest.approx(j["unfold_s"], rel=1e-4, abs=1e-6)
        else:
            assert c["unfold_s"] == "" and j["unfold_s"] is None
    assert not list(local.out.glob(".summary*"))  # atomic writes left no temp file


def test_resume(inputs, local, tmp_path) -> None:
    first = {r.out: r for r in local.result.rows}
    pattern = [str(inputs / f"{n}.obj") for n in GOOD]
    t0 = time.perf_counter()
    again = run_batch(pattern, local.out, OPTS, workers=2)
    assert time.perf_counter() - t0 < 5  # nothing ran
    assert [r.status for r in again.rows] == ["skipped"] * 3
    for r in again.rows:
        assert (r.faces, r.pieces, r.pages) == (first[r.out].faces, first[r.out].pieces, first[r.out].pages)
    assert "skipped" in (local.out / "summary.csv").read_text()
    # --force, other options, or a mesh newer than its report: made again
    assert run_batch(pattern[:1], local.out, OPTS, force=True).rows[0].status == "ok"
    assert run_batch(pattern[1:2], local.out, MakeOptions(fold=False, size=90.0, guide=False)).rows[0].status == "ok"
    st = os.stat(pattern[2])
    later = time.time() + 60
    os.utime(pattern[2], (later, later))
    try:
        assert run_batch(pattern[2:], local.out, OPTS).rows[0].status == "ok"
    finally:  # the other tests share the input folder
        os.utime(pattern[2], (st.st_atime, st.st_mtime))


def test_hard_limit_kills_a_real_make(models_dir, tmp_path) -> None:
    t0 = time.perf_counter()
    res = run_batch(str(models_dir / "bunny-128.obj"), tmp_path / "out", MakeOptions(), hard_limit=0.3)
    assert time.perf_counter() - t0 < 5
    (row,) = res.rows
    assert row.status == "timeout" and row.faces is None
    assert not (tmp_path / "out" / "bunny-128" / "report.json").exists()


def test_preload_modules_exist() -> None:
    # the forkserver skips a preload name it cannot import without a word (a stale module path)
    for name in PRELOAD:
        importlib.import_module(name)


def test_inputs_and_names(tmp_path, models_dir) -> None:
    for sub in ("a", "b"):
        (tmp_path / sub).mkdir()
        shutil.copy(models_dir / "cube-12.obj", tmp_path / sub / "cube.obj")
    (tmp_path / "a" / "notes.txt").write_text("not a mesh")
    meshes = expand(str(tmp_path / "**" / "*"))
    assert [p.relative_to(tmp_path).as_posix() for p in meshes] == ["a/cube.obj", "b/cube.obj"]
    names = out_names(meshes)
    assert len(set(names)) == 2 and all(n.startswith("cube-") for n in names)
    assert out_names(meshes[::-1]) == names[::-1]  # stable: depends on the file, not the order
    assert out_names(meshes[:1]) == ["cube"]
    with pytest.raises(PolyfoldError, match="no mesh files"):
        expand(str(tmp_path / "*.obj"))
    with pytest.raises(PolyfoldError, match="paper"):
        run_batch(str(tmp_path / "a" / "*.obj"), tmp_path / "out", MakeOptions(paper="b5"))


def test_cli(inputs, tmp_path) -> None:
    out = tmp_path / "out"
    good = str(inputs / "[ico][cuc][bot]*.obj")  # cube-12, icosahedron-20, octahedron-8
    proc = run_cli("batch", good, "-o", out, "--no-fold", "--size", "100", "--workers", "2", timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 4 and all(f"[{k}/3]" in lines[k - 1] for k in (1, 2, 3))
    assert "3 ok" in lines[-1] and "summary.csv" in lines[-1]
    for name in GOOD:
        assert name in proc.stdout  # the table
    # the good ones are skipped now; the bad file fails -> exit 1, one line with -q
    proc = run_cli("batch", good, inputs / "nan-vertex.obj", "-o", out, "--no-fold", "--size", "100", "-q")
    assert proc.returncode == 1
    line = one_line(proc.stderr)
    assert "3 skipped" in line and "1 error" in line and proc.stdout == ""
    statuses = {r["out"]: r["status"] for r in csv.DictReader((out / "summary.csv").read_text().splitlines())}
    assert statuses == {"cube-12": "skipped", "icosahedron-20": "skipped", "octahedron-8": "skipped",
                        "nan-vertex": "error"}
    proc = run_cli("batch", str(tmp_path / "none-*.obj"), "-o", out)
    assert proc.returncode == 2 and "no mesh files" in one_line(proc.stderr)


def test_dask_local_cluster(inputs, local, tmp_path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        run = _batch(inputs, tmp_path / "out", scheduler=cluster.scheduler_address)
    _check_rows(run)
    assert _statuses(run.result.rows) == _statuses(local.result.rows)
    assert run.csv.splitlines()[0] == local.csv.splitlines()[0]


def _svg_texts(path: Path) -> str:
    root = ET.parse(path).getroot()
    return " ".join(t.text or "" for t in root.iter("{http://www.w3.org/2000/svg}text"))


def test_study_unfold(inputs, tmp_path) -> None:
    files = [inputs / f"{n}.obj" for n in GOOD] + [inputs / "nan-vertex.obj"]
    res = run_study("unfold", [str(f) for f in files], tmp_path, runs=3, time_limit=10.0, workers=2)
    assert res.files == (tmp_path / "study-unfold.csv", tmp_path / "study-unfold.svg")
    rows = {Path(r["mesh"]).stem: r for r in csv.DictReader((tmp_path / "study-unfold.csv").read_text().splitlines())}
    assert rows["nan-vertex"]["status"] == "error" and "non-finite" in rows["nan-vertex"]["error"]
    for name in GOOD:
        r = rows[name]
        assert r["status"] == "ok" and int(r["faces"]) == int(name.rsplit("-", 1)[1])
        assert int(r["runs"]) == 3 and 0 <= int(r["successes"]) <= 3
        assert 0.0 <= float(r["success_rate"]) <= 1.0
        assert 0.0 <= float(r["median_s"]) <= float(r["max_s"]) < 10.0
        assert float(r["success_rate"]) == 1.0  # small convex polyhedra always unfold into one piece
    text = _svg_texts(tmp_path / "study-unfold.svg")
    assert "faces" in text and "success rate" in text and "median seconds" in text


def test_study_cspace_cli(inputs, tmp_path, models_dir) -> None:
    shutil.copy(models_dir / "torus-8x4-64.obj", inputs.parent / "torus-8x4-64.obj")
    pattern = [str(inputs / f"{n}.obj") for n in GOOD] + [str(inputs.parent / "torus-8x4-64.obj")]
    proc = run_cli("batch", *pattern, "-o", tmp_path, "--study", "cspace", "--samples", "200", "-q", timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "study cspace: 4 mesh(es): 4 ok" in one_line(proc.stderr)
    rows = list(csv.DictReader((tmp_path / "study-cspace.csv").read_text().splitlines()))
    assert len(rows) == 4
    for r in rows:
        assert r["status"] == "ok" and int(r["samples"]) == 200
        # a single-piece net of F faces is a spanning tree: F - 1 creases
        assert int(r["pieces"]) == 1 and int(r["dof"]) == int(r["faces"]) - 1
        for s in ("discrete", "continuous"):
            assert 0.0 <= float(r[f"{s}_ratio"]) <= 1.0
            assert float(r[f"{s}_ratio"]) == pytest.approx(int(r[f"{s}_valid"]) / 200)
    torus = next(r for r in rows if "torus" in r["mesh"])
    assert float(torus["discrete_ratio"]) < 1.0  # a non-convex net collides in some configurations
    text = _svg_texts(tmp_path / "study-cspace.svg")
    assert "DOF" in text and "discrete" in text and "continuous" in text


def _marked(marker: str) -> list[int]:
    """Live processes whose environment holds marker (a batch, its forkserver, its tasks)."""
    pids = []
    for env in Path("/proc").glob("[0-9]*/environ"):
        try:
            if marker.encode() in env.read_bytes():
                stat = (env.parent / "stat").read_text()
                if stat.rsplit(")", 1)[1].split()[0] != "Z":  # not a zombie
                    pids.append(int(env.parent.name))
        except OSError:
            continue
    return pids


@pytest.mark.serial  # (under a pytest-xdist worker its batch never shows up in /proc: run alone)
@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="needs /proc")
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_a_killed_batch_leaves_no_process_and_no_temp_folder(inputs, tmp_path, sig) -> None:
    """What `timeout`, schedulers and the OOM killer send: the hanging task, the forkserver and the
    resource tracker all go with the batch; its temporary folder too (after SIGKILL: at the next
    batch)."""
    import signal
    import subprocess
    import sys
    import uuid

    marker = f"POLYFOLD_TEST_MARKER={uuid.uuid4().hex}"
    temp = tmp_path / "tmp"
    temp.mkdir()
    env = {**os.environ, FAULT_ENV: FAULTS, "TMPDIR": str(temp), marker.split("=")[0]: marker.split("=")[1]}
    proc = subprocess.Popen([sys.executable, "-m", "polyfold", "batch", str(inputs / "hang-me.obj"), "-o",
                             str(tmp_path / "out"), "--no-fold", "--workers", "1", "-q"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    end = time.monotonic() + 60
    while not list(temp.glob("polyfold-batch-*/0.log")) and time.monotonic() < end:  # the task is running
        time.sleep(0.2)
    assert len(_marked(marker)) >= 3  # batch, forkserver, the task (and the resource tracker)
    proc.send_signal(getattr(signal, sig))
    proc.wait(timeout=30)
    end = time.monotonic() + 15
    while _marked(marker) and time.monotonic() < end:
        time.sleep(0.2)
    assert _marked(marker) == []  # nothing survives the batch
    if sig == "SIGTERM":
        assert proc.returncode != 0 and "Traceback" not in proc.stderr.read().decode()
    else:  # the next batch removes the dead one's folder
        run = subprocess.run([sys.executable, "-m", "polyfold", "batch", str(inputs / "cube-12.obj"), "-o",
                              str(tmp_path / "out2"), "--no-fold", "-q"], env={**env, FAULT_ENV: ""},
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr
    assert not list(temp.glob("polyfold-batch-*"))


def test_the_output_folder_is_never_an_input(inputs, tmp_path) -> None:
    root = tmp_path / "tree"
    shutil.copytree(inputs, root / "in")
    pattern = str(root / "**" / "cube-12.obj")
    out = root / "out"  # inside the '**' glob: its part-K.obj and the like must not come back in
    first = run_batch(pattern, out, OPTS)
    shutil.copy(inputs / "cube-12.obj", out / "cube-12.obj")  # even a mesh named like an input
    again = run_batch(pattern, out, OPTS, force=True)
    assert [Path(r.mesh) for r in first.rows] == [Path(r.mesh) for r in again.rows] == [root / "in" / "cube-12.obj"]
