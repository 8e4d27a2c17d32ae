"""apps/warmup.py (`polyfold warm-up`, run by `make setup`): it reaches the kernels a first
`polyfold make` needs, so numba has them in its cache before the user's first run."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import bumpy_sphere, compile_bytecode, kernels_cached, warm_up
from polyfold.jit import SWITCH

# a first run's process has no ahead-of-time kernels (`jit`): the signature tests below run without them
JUST_IN_TIME = {**os.environ, SWITCH: "off"}


def test_warm_up_reaches_the_kernels_of_every_stage():
    seconds = warm_up(processes=1, ahead=False)  # all here, so this process holds every signature
    assert set(seconds) == {"bytecode", "make", "fold", "segment", "inflate"} and all(s >= 0 for s in seconds.values())
    sigs = kernel_signatures()  # (entry points: a kernel called only from compiled code is linked into its caller)
    for kernel in ("unfold.kernels.local_search", "unfold.kernels.evaluate_batch", "fold.checker.segment_free",
                   "segment.merge_kernels.merge_run", "fabricate.pack._scan", "inflate.kernels.run_steps",
                   "unfold.tabroom._swap_gains", "fabricate.labels._clear_near", "fabricate.labels._grid_bfs",
                   "fabricate.overlap_kernels.blocked_by", "fabricate.overlap_kernels.grown_box_meets",
                   "fabricate.overlap_kernels.first_clear_box", "fabricate.overlap_kernels.first_box_in_triangle",
                   "fabricate.overlap_kernels.first_leader_spot",
                   "fabricate.overlap_kernels.first_unblocked", "fabricate.overlap_kernels.overlap_area",
                   "fabricate.labels._path_back", "fabricate.labels._path_turns", "fabricate.labels._refresh_free",
                   "fabricate.pack.mark_edges", "fabricate.overlap_kernels.grown_box_apart",
                   "unfold.kernels.crease_bfs", "unfold.kernels.place_children", "fabricate.labels._dilated",
                   "fabricate.labels._enclosed"):
        assert sigs.get(kernel), f"{kernel} was not compiled (or loaded from the cache) by the warm-up"


def test_warm_up_in_two_processes_runs_every_section():
    """`make setup` on two cores: the sections split between this process and a second one, which
    between them run every section one process runs (the entry point `python -m
    polyfold.apps.warmup SECTION...` prints their seconds as JSON)."""
    import json

    from polyfold.apps.warmup import HERE, SECOND_PROCESS, WARM_UP

    assert set(warm_up(processes=2, ahead=False)) == {"bytecode", *HERE, *SECOND_PROCESS}
    # what one process runs, the two run between them
    assert set(WARM_UP) <= set(HERE) | set(SECOND_PROCESS) and not set(HERE) & set(SECOND_PROCESS)
    proc = subprocess.run([sys.executable, "-m", "polyfold.apps.warmup", "segment", "inflate"], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert set(json.loads(proc.stdout.splitlines()[-1])) == {"segment", "inflate"}


@pytest.mark.serial  # (it removes the package's bytecode: a warm-up in another worker would write it back)
def test_warm_up_writes_the_bytecode_of_every_module_even_where_python_would_not():
    """An editable install under PYTHONDONTWRITEBYTECODE (as on this machine) never gets
    `__pycache__/*.pyc` for polyfold's modules; after compile_bytecode a fresh process under that
    setting loads every polyfold module `make` imports from its bytecode (`python -v` says which
    file each code object came from)."""
    from pathlib import Path

    import polyfold

    package = Path(polyfold.__file__).parent
    for pyc in package.rglob("__pycache__/*.pyc"):  # as a fresh editable install has them: none
        pyc.unlink()

    def code_objects_from() -> list[str]:
        run = subprocess.run([sys.executable, "-v", "-c", "import polyfold.pipeline.make"], capture_output=True,
                             text=True, timeout=120, env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
        assert run.returncode == 0, run.stderr[-2000:]
        return [line.split("code object from ")[1].strip("'") for line in run.stderr.splitlines()
                if "code object from" in line and str(package) in line]

    before = code_objects_from()
    assert len(before) > 50 and all(f.endswith(".py") for f in before)  # compiled from source, every time
    assert compile_bytecode() is True
    after = code_objects_from()
    assert len(after) == len(before) and all(f.endswith(".pyc") for f in after), [f for f in after if f.endswith(".py")]


def test_bumpy_sphere_is_closed_and_seeded():
    v, f = bumpy_sphere()
    assert v.shape == (42, 3) and f.shape == (80, 3)
    v2, _ = bumpy_sphere()
    assert (v == v2).all()


def test_cli_warm_up_says_what_it_did():
    """...and builds make's kernels ahead of time (`jit`; this machine has a C compiler): a fresh
    process then finds them."""
    proc = subprocess.run([sys.executable, "-m", "polyfold", "warm-up"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "kernels compiled and cached" in proc.stderr
    ahead = [line for line in proc.stderr.splitlines() if "warm-up: ahead of time: " in line]
    assert len(ahead) == 1 and " kernels compiled, " in ahead[0], proc.stderr
    ready = subprocess.run([sys.executable, "-c", "from polyfold.jit import ahead_ready; print(ahead_ready())"],
                           capture_output=True, text=True, timeout=120)
    assert ready.stdout.strip() == "True", ready.stderr


def test_kernels_cached_tells_a_cold_cache_from_a_warm_one(tmp_path):
    warm_up(ahead=False)
    assert kernels_cached() is True
    cold = subprocess.run([sys.executable, "-c", "from polyfold.apps.warmup import kernels_cached; print(kernels_cached())"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty")})
    assert cold.returncode == 0 and cold.stdout.strip() == "False", cold.stderr


# a first run's make compiles its fold stage in a second process (`Beside`) -----------------------

_FOLD_STAGE_SIGNATURES = r"""
import json, os, sys
from pathlib import Path
from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import SECTIONS
from polyfold.deadline import Deadline
from polyfold.fabricate.fit import model_scale
from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.folding import fold_pieces
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.parts import make_parts

opts = MakeOptions()
mesh = load_mesh(Path(sys.argv[1])).mesh
parts, _, _ = make_parts(mesh, opts, Deadline.after(30.0), lambda stage, message: None)
for name in ("fold-plan", "fold-check"):
    SECTIONS[name][1](None)
# on one core fold_pieces plans every piece here, not in forked processes: their kernels are this one's
os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
before = kernel_signatures()
folded, report = fold_pieces(parts, opts, Deadline.after(30.0), lambda stage, message: None,
                             model_scale([mesh], opts.size))
after = kernel_signatures()
new = {k: sorted(v - before.get(k, set())) for k, v in after.items() if v - before.get(k, set())}
print(json.dumps({"new": new, "verified": report.verified, "pieces": report.pieces}))
"""


def test_the_sections_beside_compile_every_kernel_of_makes_fold_stage():
    """What a first run waits for instead of compiling: after the sections `fold-plan` and
    `fold-check` (on the hand-made tetrahedron net), folding the bunny's real pieces as make does
    calls no kernel signature they did not (a fresh process; cached or compiled, the same)."""
    import json
    from pathlib import Path

    bunny = Path(__file__).resolve().parents[2] / "examples" / "bunny-128.obj"
    proc = subprocess.run([sys.executable, "-c", _FOLD_STAGE_SIGNATURES, str(bunny)], capture_output=True, text=True,
                          timeout=600, env=JUST_IN_TIME)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout.splitlines()[-1])
    assert got["pieces"] >= 1 and got["verified"] == got["pieces"]
    assert got["new"] == {}, f"make's fold stage compiles beyond the first run's sections: {got['new']}"


_UNFOLD_STAGE_SIGNATURES = r"""
import json, sys
from pathlib import Path
from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import SECTIONS
from polyfold.deadline import Deadline
from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.options import MakeOptions
from polyfold.pipeline.parts import make_parts

SECTIONS["unfold"][1](None)
before = kernel_signatures()
mesh = load_mesh(Path(sys.argv[1])).mesh
parts, _, report = make_parts(mesh, MakeOptions(parts=4), Deadline.after(60.0), lambda stage, message: None)
after = kernel_signatures()
new = {k: sorted(v - before.get(k, set())) for k, v in after.items()
       if k.startswith("unfold.") and v - before.get(k, set())}
print(json.dumps({"new": new, "parts": len(parts), "local": [n.method for n in report.nets]}))
"""


def test_the_unfold_section_compiles_the_unfold_stage_of_a_segmented_make(models_dir):
    """What a first run's `make --parts` (or `--inflate`) has the second process compile while it
    segments: after the section `unfold` (a closed bumpy sphere), unfolding the horse's four parts
    (open patches) as make does calls no unfolder kernel signature the section did not."""
    import json

    proc = subprocess.run([sys.executable, "-c", _UNFOLD_STAGE_SIGNATURES, str(models_dir / "horse-302.obj")], capture_output=True,
                          text=True, timeout=600, env=JUST_IN_TIME)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout.splitlines()[-1])
    assert got["parts"] == 4
    assert got["new"] == {}, f"make's unfold stage compiles beyond the section: {got['new']}"


_AFTER_THE_WAIT = r"""
import json, sys, tempfile
from pathlib import Path
from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import SECTIONS
from polyfold.pipeline.make import make
from polyfold.pipeline.options import MakeOptions

for name in ("fold-plan", "fold-check", "guide"):
    SECTIONS[name][1](None)
before = kernel_signatures()
with tempfile.TemporaryDirectory() as out:
    make(Path(sys.argv[1]), out, MakeOptions())
after = kernel_signatures()
late = ("fold.", "verify.", "guide.", "formats.", "graphs.")  # what make calls from its fold stage on
new = {k: sorted(v - before.get(k, set())) for k, v in after.items()
       if k.startswith(late) and v - before.get(k, set())}
print(json.dumps(new))
"""


def test_what_make_compiles_after_its_wait_is_in_the_sections_of_the_wait():
    """A first run's make compiles nothing from its fold stage on that `Beside`'s sections (the
    second process's `fold-plan`, this one's `fold-check` and `guide`) did not: the bunny's make
    after them calls no new signature of a fold, path check, guide or file-format kernel."""
    import json
    from pathlib import Path

    bunny = Path(__file__).resolve().parents[2] / "examples" / "bunny-128.obj"
    proc = subprocess.run([sys.executable, "-c", _AFTER_THE_WAIT, str(bunny)], capture_output=True, text=True,
                          timeout=600, env=JUST_IN_TIME)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.splitlines()[-1]) == {}


def test_star_net_is_a_flat_net_that_folds_to_its_tetrahedron():
    from shapely.geometry import Polygon

    from polyfold.apps.warmup import star_net
    from polyfold.deadline import Deadline
    from polyfold.fabricate.fit import model_scale
    from polyfold.pipeline.folding import fold_pieces
    from polyfold.pipeline.options import MakeOptions

    part = star_net()
    net = part.net
    a, b, c = net.coords[:, 0], net.coords[:, 1], net.coords[:, 2]
    signed = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    assert (signed > 0).all()  # every face CCW, outer side up
    # every face keeps its 3D side lengths on paper
    v, f = net.mesh.vertices, net.mesh.faces
    for k in range(3):
        flat = np.linalg.norm(net.coords[:, (k + 1) % 3] - net.coords[:, k], axis=1)
        assert np.allclose(flat, np.linalg.norm(v[f[:, (k + 1) % 3]] - v[f[:, k]], axis=1))
    # no two faces overlap on paper (shapely, not the unfolder's test)
    tris = [Polygon(t) for t in net.coords]
    assert all(tris[i].intersection(tris[j]).area < 1e-12 for i in range(4) for j in range(i + 1, 4))
    # and it folds: make's fold stage finds a path the independent check accepts
    opts = MakeOptions()
    _, report = fold_pieces([part], opts, Deadline.after(30.0), lambda stage, message: None,
                            model_scale([net.mesh], opts.size))
    assert report.pieces == 1 and report.verified == 1


@pytest.mark.parametrize("forked", [True, False])
def test_beside_waits_for_its_stage_only_and_stops_a_process_left_over(forked, monkeypatch):
    from polyfold.apps import warmup
    from polyfold.apps.warmup import Beside

    monkeypatch.setattr(warmup, "can_fork", lambda: forked)  # (False: a fresh Python, as on macOS)

    with Beside(("fold-check",), (), "fold") as beside:
        beside.ready("layout")
        assert beside.proc is not None  # not its stage: no wait
        beside.ready("fold")
        assert beside.proc is None  # waited for it
    with Beside(("make",), (), "fold") as beside:
        proc = beside.proc
    assert proc.returncode is not None and proc.returncode != 0  # never waited for: stopped on the way out


def test_make_calls_ready_once_per_stage_before_its_work(tmp_path):
    from pathlib import Path

    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    calls: list[str] = []
    seen: list[tuple[str, str]] = []
    bunny = Path(__file__).resolve().parents[2] / "examples" / "bunny-128.obj"
    make(bunny, tmp_path / "out", MakeOptions(guide=False), lambda stage, message: seen.append((stage, message)),
         ready=calls.append)
    assert len(calls) == len(set(calls)) and {"load", "unfold", "layout", "fold", "export"} <= set(calls)
    assert calls.index("fold") < calls.index("export")
    # the fold stage's first message comes before any piece is planned (the first run waits there)
    fold_messages = [m for s, m in seen if s == "fold"]
    assert fold_messages[0].startswith("planning folding paths for")


_CROWDED_LABEL_SIGNATURES = r"""
import json, sys
from pathlib import Path
import polyfold.fabricate.labels as L
from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import SECTIONS, _warm_crowded_labels
from polyfold.deadline import Deadline
from polyfold.fabricate import pieces as P
from polyfold.fabricate.fit import model_scale
from polyfold.formats.meshes import load_mesh
from polyfold.pipeline.options import MakeOptions, paper_size
from polyfold.pipeline.parts import make_parts
from polyfold.pipeline.sheets import fit_parts, pack_box, part_piece_inputs

_warm_crowded_labels()
SECTIONS["tabs"][1](None)  # (a first run's second process compiles it)
import polyfold.fabricate.overlap_kernels as K
overlap = {"calls": 0}
def counted_overlap(*a, _f=K.blocked_by):
    overlap["calls"] += 1
    return _f(*a)
K.blocked_by = counted_overlap
before = kernel_signatures()
calls = {"free_near": 0, "routed_near": 0}
for name in calls:
    def counted(*a, _f=getattr(L._Taken, name), _n=name, **k):
        calls[_n] += 1
        return _f(*a, **k)
    setattr(L._Taken, name, counted)
mesh = load_mesh(Path(sys.argv[1])).mesh
opts = MakeOptions(size=60.0, paper="80x80mm")
parts, _, _ = make_parts(mesh, opts, Deadline.after(60), lambda *a: None)
scale = model_scale([mesh], opts.size)
fitted, _ = fit_parts(parts, scale, opts, pack_box(*paper_size(opts.paper), opts), "fish")
P.PARALLEL_LABELS = 10**9  # (every piece here, in this process)
P.build_sheet_pieces(part_piece_inputs(mesh, fitted), scale)
after = kernel_signatures()
new = {k: sorted(v - before.get(k, set())) for k, v in after.items() if v - before.get(k, set()) and k.startswith(("fabricate.labels", "fabricate.overlap_kernels"))}
print(json.dumps({"new": new, "calls": calls, "overlap_calls": overlap["calls"]}))
"""


def test_the_warm_up_compiles_the_kernels_of_crowded_labels(models_dir):
    """Crowded pieces (the fish at 60 mm on 80 mm pages: labels by seam run, far from their edges)
    call the label kernels with the signatures the warm-up compiled, and their tabs and labels the
    overlap test with those of the `tabs` section (a fresh process)."""
    import json

    proc = subprocess.run([sys.executable, "-c", _CROWDED_LABEL_SIGNATURES, str(models_dir / "fish-472.obj")],
                          capture_output=True, text=True, timeout=600, env=JUST_IN_TIME)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout.splitlines()[-1])
    assert got["calls"]["free_near"] > 0 and got["calls"]["routed_near"] > 0
    assert got["new"] == {}, f"crowded labels compile beyond the warm-up: {got['new']}"
    assert got["overlap_calls"] > 0
