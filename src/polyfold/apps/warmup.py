"""`polyfold warm-up`: compile polyfold's numba kernels now, into numba's cache, so that the first
real command does not wait for them.

numba compiles a kernel the first time a process calls it and keeps the machine code in its cache
(`__pycache__` beside the sources, or $NUMBA_CACHE_DIR); later processes load it in milliseconds.
Without this step a fresh install spends its first `polyfold make` compiling: about 16.5 s of a
bunny's 18 s on a 2-core machine (33 s of compiling shared by two processes, `Beside`). `make
setup` runs it once (README "Set-up").

It also writes the bytecode of polyfold's own modules (`compile_bytecode`): pip writes it for a
regular install, but an editable one (`make setup`) leaves it to the first import, and where
PYTHONDONTWRITEBYTECODE is set nothing ever writes it, so every command compiled polyfold's
Python from source, 0.2 s of a warm `make`.

In: nothing (generated bumpy spheres of 80 and 320 faces, seeded, so no file is needed). Out:
seconds per stage. Every stage of `make` runs once (load, check, segment, unfold, fold, sheets,
guide), then the unfolder's local search (on a sphere whose heuristic nets overlap), every folding
planner at zero and at the default thickness, segmentation into parts (`make --parts`, `segment`)
and both inflation modes (`make --inflate`).
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from typing import TYPE_CHECKING, Callable

import numpy as np

from ..processes import Forked, can_fork, usable_cores

if TYPE_CHECKING:
    import subprocess

    from ..mesh.mesh import Mesh


def compile_bytecode() -> bool:
    """Write the bytecode (`__pycache__/*.pyc`) of every module of the installed polyfold package,
    whatever PYTHONDONTWRITEBYTECODE says; False where its folder is read-only (nothing is lost:
    Python then compiles the sources as it imports them)."""
    import compileall
    from pathlib import Path

    return bool(compileall.compile_dir(str(Path(__file__).resolve().parents[1]), quiet=2))


def kernels_cached() -> bool | None:
    """Whether numba's cache holds the planners' main kernel (a first run compiles when not):
    True or False, or None when this numba keeps its cache where this cannot look. True without
    looking when the kernels run ahead of time (`jit.ahead_ready`: numba is not imported)."""
    from ..jit import ahead_ready

    if ahead_ready():
        return True
    try:
        from ..fold.checker import segment_free

        return os.path.exists(segment_free._cache._cache_file._index_path)
    except Exception:  # numba's cache layout is its own: no hint rather than a wrong one
        return None


def bumpy_sphere(subdivisions: int = 1, sigma: float = 0.12, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)): an icosphere (80 faces at 1 subdivision, 320 at 2) with
    every vertex moved along its radius by a factor 1 + N(0, sigma) (within 0.6-1.4): dents
    (hyperbolic vertices) and a few nearly convex parts."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = np.asarray(sphere.vertices, dtype=float)
    r = np.clip(1.0 + np.random.default_rng(seed).normal(0.0, sigma, len(v)), 0.6, 1.4)
    return v * r[:, None], np.asarray(sphere.faces, dtype=np.int64)


def height_grid(n: int, height: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)): an n x n grid of unit squares centred on the origin, over
    z = height(x, y) (arrays of the grid's x and y in, of z out), each square split along one
    diagonal: for z = x^2 - y^2 a saddle, every interior vertex hyperbolic (no single net)."""
    x, y = (a.ravel() for a in np.meshgrid(np.arange(n + 1.0) - n / 2, np.arange(n + 1.0) - n / 2, indexing="ij"))
    corner = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    faces = np.concatenate([np.column_stack([corner, corner + n + 1, corner + n + 2]),
                            np.column_stack([corner, corner + n + 2, corner + 1])])
    return np.column_stack([x, y, height(x, y)]), faces


def _warm_make(mesh) -> None:
    import trimesh

    from ..mesh.mesh import Mesh
    from ..pipeline.make import make
    from ..pipeline.options import MakeOptions
    from ..unfold.problem import UnfoldProblem

    with tempfile.TemporaryDirectory() as tmp:
        make(mesh, tmp, MakeOptions(), name="warm-up")
    _warm_crowded_labels()
    # a mesh with flat edges (the sphere has none): the unfolder's set-up counts cut candidates anew
    box = trimesh.creation.box()
    UnfoldProblem.from_mesh(Mesh(np.asarray(box.vertices, dtype=float), np.asarray(box.faces, dtype=np.int64)))


def _warm_crowded_labels() -> None:
    """The label kernels that only crowded pieces reach (the warm-up's sphere has room for every
    label beside its edge), with the argument types `labels._Taken` gives them."""
    from ..fabricate.labels import (_RINGS2, _box_free, _clear_near, _dilated, _enclosed, _grid_bfs, _path_back,
                                    _path_turns, _refresh_free)
    from ..fabricate.pack import mark_edges

    free = np.ones((8, 8), dtype=bool)
    _clear_near(free, free, free, 0, 7, 0, 7, np.zeros(2), np.ones(2), 0.2, _RINGS2, 0, np.zeros(3, dtype=np.int64),
                np.zeros(1, dtype=np.int64), np.empty((4, 64, 3)), np.zeros(4, dtype=np.int64),
                np.zeros((4, len(_RINGS2)), dtype=np.int64), 3, ~free, np.linspace(0.0, 1.0, 5), 2)
    dist, _found = _grid_bfs(free, 1, 1, 5, np.ones((1, 8, 8), dtype=bool), 2)
    _path_back(dist, 3, 3)
    _path_turns(np.ones((3, 2)), ~free, np.zeros(2), 5.0, 0.4)
    _box_free(~free, 1, 1)
    _enclosed(_dilated(~free, np.ones((3, 3), dtype=bool)))
    window = mark_edges(~free, ~free, np.zeros((3, 2)), np.ones((3, 2)), np.array([0, 3]),
                        np.array([[0.0, 0.0, 1.0, 1.0]]), np.zeros(1, dtype=bool), np.zeros(2), 5.0)
    _refresh_free(free.copy(), ~free, window, 1, 1)
    # a label box near another across its corner: `_grown_box_hits` asks the distance test
    from ..fabricate.overlap_kernels import grown_box_apart

    box = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]])
    grown_box_apart(box, 0.25, box + 4.5, np.array([0, 4], dtype=np.int64))
    _warm_label_sides()


def _warm_label_sides() -> None:
    """The tests of spots beside an edge (`labels.PieceLabels._nearest_to`: nearer it than the
    piece's other cut sides; `_outside`'s compiled test of its spots; `_hits`), on a triangle
    too small for its labels; the screen of spots farther off (`_leader_spots`)."""
    from shapely.geometry import Polygon

    from ..fabricate.labels import PieceLabels, _Taken, text_box, text_boxes
    from ..fabricate.tabs import CutSide, Room

    tri = np.array([[0.0, 0.0], [10.0, 0.0], [5.0, 8.0]])
    side = CutSide(0, 0, 0, tri[0], tri[1], tri)
    labels = PieceLabels(Room(np.array([Polygon(tri)], dtype=object)), 2.0,
                         np.stack([tri, np.roll(tri, -1, axis=0)], axis=1))
    labels._nearest_to(tri - [0.0, 1.0], side)
    for text in ("12345", "12345"):  # beside the edge (there is no room in the face), then next to that
        labels.edge(side, text)
    labels._hits(text_box(np.array([5.0, -1.0]), np.array([1.0, 0.0]), "1", 2.0))
    labels._taken = _Taken(labels)
    spots = text_boxes(np.array([[5.0, -6.0], [5.0, 3.0]]), np.array([1.0, 0.0]), "1", 2.0)
    list(labels._leader_spots(spots, tri[0] + [5.0, 0.0]))


def _warm_fold(mesh) -> None:
    from ..collide.tolerance import THICKNESS_REL
    from ..fold.plan import PLANNERS, plan_fold
    from ..fold.tree import FoldTree
    from ..unfold.search import unfold

    bumpy = _bumpier_sphere()
    for seed in range(1, 6):
        _, stats = unfold(bumpy, seed=seed, time_limit=10.0)
        if "local-search" in stats.method:
            break
    _warm_no_single_net()
    net, _ = unfold(mesh, seed=1, time_limit=10.0)
    tree = FoldTree.from_net(net)
    for thickness in (0.0, THICKNESS_REL):
        t = tree.with_thickness(thickness * tree.scale)
        for planner in PLANNERS:
            plan_fold(t, planner=planner, time_limit=0.5, seed=1)


def star_net():
    """A regular tetrahedron (edge 2 sqrt 2) as one Part: face 0 with the other three hinged to its
    sides, laid out by numpy alone (each hinged face is face 0's far corner mirrored across their
    shared side), so that the fold stage's kernels compile on it without the unfolder's."""
    from ..mesh.mesh import Mesh
    from ..pipeline.parts import Part
    from ..unfold.net import Net

    v = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])
    f = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], dtype=np.int64)  # outward (CCW from outside)
    mesh = Mesh(v, f)
    corner = {0: np.array([0.0, 0.0]), 1: np.array([2.0 * math.sqrt(2.0), 0.0])}
    corner[2] = np.array([math.sqrt(2.0), math.sqrt(6.0)])  # face 0 flat, CCW
    coords = np.zeros((4, 3, 2))
    coords[0] = [corner[i] for i in f[0]]
    parent = np.array([-1, 0, 0, 0], dtype=np.int64)
    parent_edge = np.full(4, -1, dtype=np.int64)
    fe = mesh.topology.face_edges
    for g in (1, 2, 3):
        shared = [int(a) for a in f[g] if a in f[0]]
        far = next(int(a) for a in f[0] if a not in shared)
        mirrored = corner[shared[0]] + corner[shared[1]] - corner[far]  # equilateral faces
        coords[g] = [corner[int(a)] if int(a) in shared else mirrored for a in f[g]]
        parent_edge[g] = int(np.intersect1d(fe[0], fe[g])[0])
    net = Net(mesh=mesh, parent=parent, parent_edge=parent_edge, order=np.arange(4, dtype=np.int64),
              coords=coords, piece=np.zeros(4, dtype=np.int64))
    return Part(np.arange(4, dtype=np.int64), net)


def _star_tree():
    """(the crease pattern of `star_net`, the paper's thickness in its model units, the options)
    as make's fold stage has them (default options, a 150 mm model)."""
    from ..fabricate.fit import model_scale
    from ..pipeline.options import MakeOptions
    from ..unfold.pattern import crease_pattern

    net = star_net().net
    opts = MakeOptions()
    thickness = opts.thickness / model_scale([net.mesh], opts.size)
    pattern = crease_pattern([net])
    return pattern, thickness, opts


def _warm_tabs(mesh) -> None:
    """The layout's overlap kernels, with the argument types tabs and labels give them: a tab
    beside a face, its corner discs kept free (`tabs.Room.blocked`) and a label box beside another
    (`labels._Boxes.hits`): what every make calls (a first run compiles them beside; the bunny's
    labels all fit in their faces, so `_warm_label_sides` is left to a make that needs it)."""
    from shapely.geometry import Polygon

    from ..fabricate.labels import PieceLabels, _Boxes, text_box
    from ..fabricate.tabs import TAB_CLEAR_MM, CutSide, Room, choose_tab

    boxes = _Boxes()
    boxes.add(text_box(np.zeros(2), np.array([1.0, 0.0]), "12", 2.0))
    boxes.hits(text_box(np.array([0.0, 1.0]), np.array([0.0, 1.0]), "3", 2.0))

    tri = np.array([[0.0, 0.0], [10.0, 0.0], [5.0, 8.0]])
    room = Room(np.array([Polygon(tri), Polygon(tri * [1.0, -1.0] + [0.0, -7.0])], dtype=object))
    side = CutSide(0, 0, 0, tri[0], tri[1], tri)
    choose_tab((side, side), [room])
    room.blocked(Polygon(tri + [0.0, -1.0]), None, TAB_CLEAR_MM)
    # a face in the tab's way: a clipped tab (`tabs._clipped`), then a label in the face
    spike = np.array([[4.5, -0.5], [5.5, -0.5], [5.0, -15.0]])
    choose_tab((side, side), [Room(np.array([Polygon(tri), Polygon(spike)], dtype=object))])
    PieceLabels(room, 2.0, np.stack([tri, np.roll(tri, -1, axis=0)], axis=1)).edge(side, "1")


def _bumpier_sphere() -> "Mesh":
    """A bumpier sphere of 320 faces, whose heuristic nets overlap: the memetic search's local
    search runs on it (within seeds 1-5)."""
    from ..mesh.mesh import Mesh

    return Mesh(*bumpy_sphere(subdivisions=2, sigma=0.15, seed=1))


def _warm_no_single_net() -> None:
    """The unfolder on a mesh with no single net (a 3 x 3 grid on the saddle z = (x^2 - y^2) / 3, whose
    interior vertices are all hyperbolic): `fewest_pieces` and the fallback's set cover, which the
    sphere's nets never reach (a first blocked part paid 1 s of loading numba for them)."""
    from ..mesh.mesh import Mesh
    from ..unfold.search import unfold

    unfold(Mesh(*height_grid(3, lambda x, y: (x * x - y * y) / 3)), seed=1, time_limit=1.0)


def _warm_unfold(mesh) -> None:
    """make's unfold stage (`pipeline.parts.make_parts`: the net search, its local search, the
    moves that make room for tabs) on a bumpier sphere whose heuristic nets overlap, so that the
    local search runs: a first run's `Beside` compiles it while a make that inflates or segments
    compiles those stages first."""
    from ..deadline import Deadline
    from ..pipeline.options import MakeOptions
    from ..pipeline.parts import make_parts

    bumpy = _bumpier_sphere()
    for seed in range(1, 6):
        _, _, report = make_parts(bumpy, MakeOptions(seed=seed), Deadline.after(10.0), lambda stage, message: None)
        if any("local-search" in net.method for net in report.nets):
            break
    _warm_no_single_net()


def _warm_fold_plan(mesh) -> None:
    """make's fold stage without the check of the paths: the tree, the collision test, a plan."""
    from ..fold.plan import plan_fold
    from ..fold.tree import FoldTree, collides

    pattern, thickness, opts = _star_tree()
    tree = FoldTree.from_pattern(pattern, opts.contact_tol).with_thickness(thickness)
    collides(tree, tree.goal)
    plan_fold(tree, resolution_deg=opts.resolution_deg, time_limit=10.0, seed=opts.seed)


def _warm_fold_check(mesh) -> None:
    """make's independent check of a path (`pipeline.folding.verify_written`), on the straight path
    of `star_net` (made without the planners: it runs while they compile beside)."""
    from ..fold.plan import FoldPath
    from ..mesh.geometry import fold_deg_to_rho
    from ..pipeline.folding import verify_written

    pattern, thickness, opts = _star_tree()
    goal = fold_deg_to_rho(np.asarray(pattern.fold_deg, dtype=np.float64))
    path = FoldPath(frames=np.stack([np.zeros_like(goal), goal]), linear=True, planner="linear", seconds=0.0,
                    edges_checked=0, configs_checked=0, nodes=0)
    verify_written(pattern, path, opts, thickness)


def _warm_guide(mesh) -> None:
    """make's assembly guide: a folded pose (`fold_positions`), a face-id picture (`face_ids`) of
    `star_net`'s crease tree (whose kernels the fold stage compiled before) and its label spots
    (`label_spots`), and the distances along the surface that order the build steps and the
    openings left as they are glued (`heaviest_component`)."""
    from ..fold.tree import FoldTree, fold_positions
    from ..graphs import heaviest_component, shortest_distances
    from ..guide.pictures import face_ids, fit_camera, label_spots

    pattern, _, opts = _star_tree()
    tree = FoldTree.from_pattern(pattern, opts.contact_tol)
    tris = fold_positions(tree, np.zeros(tree.n_edges))
    ids, _ = face_ids(fit_camera(tris, np.eye(3), 8, 8), tris)
    label_spots(ids, [0], min_px=1)
    shortest_distances(3, np.array([0, 1]), np.array([1, 2]), np.ones(2), 0)
    heaviest_component(3, np.array([0, 1]), np.array([1, 2]), np.ones(2))


def _warm_segment(mesh) -> None:
    from ..segment.segment import part_concavity, segment

    segment(mesh, parts=3)
    part_concavity(mesh, np.arange(mesh.n_faces))  # (a part's concavity from Python: make --parts reports it)


def _warm_inflate(mesh) -> None:
    from ..collide.self_intersect import crossing_pairs
    from ..inflate.inflate import inflate

    for mode in ("uniform", "constrained"):
        inflate(mesh, mode=mode, max_steps=5)
    # the self-intersection guard with pairs to skip (a mesh that crosses itself at the start), and none
    crossing_pairs(mesh.vertices, mesh.faces, 1e-9, 1, np.array([1], dtype=np.int64))
    crossing_pairs(mesh.vertices, mesh.faces, 1e-9, 1)


# name: (what it compiles, how); in this order in one process
SECTIONS: dict[str, tuple[str, Callable]] = {
    "make": ("make (every stage of the main job)", _warm_make),
    "fold": ("the unfolder's local search and fallback, and the folding planners", _warm_fold),
    "segment": ("segmentation", _warm_segment),
    "inflate": ("inflation", _warm_inflate),
    # (make's own: a `polyfold server` makes its sphere through the command line instead)
    "labels": ("make's label kernels for crowded pieces", lambda mesh: _warm_crowded_labels()),
    # a first run's `Beside` (make has them all; `unfold` only where inflation or segmentation
    # comes first)
    "unfold": ("make's unfold stage: the net search", _warm_unfold),
    "tabs": ("make's layout: the overlap tests of tabs and labels", _warm_tabs),
    "fold-plan": ("make's fold stage: the planners", _warm_fold_plan),
    "fold-check": ("make's fold stage: the path check", _warm_fold_check),
    "guide": ("make's assembly guide: folded poses and pictures", _warm_guide),
}
WARM_UP = ("make", "fold", "segment", "inflate")  # what `polyfold warm-up` runs (the rest: in make's)
# with two cores, the same kernels in two processes at once: make's own sections split between
# them, each taking about half the compiling (seconds of each section on an empty cache, one
# process, the twenty-ninth session's slow machine: fold-plan 53, fold-check 15, segment 42 there;
# unfold 33, tabs 14, labels 24, guide 6, inflate 15, then make and fold mostly from the cache,
# here). The fold stage's sections go first there, so they are in the cache by the time this
# process's make reaches them (it would otherwise compile them too). Before: make and fold here
# (136 s), segmentation and inflation there (57 s), idle for the last 80 s.
HERE = ("unfold", "tabs", "labels", "guide", "inflate", "make", "fold")
SECOND_PROCESS = ("fold-plan", "fold-check", "segment")
BESIDE_WAIT_S = 300.0  # the longest a first run waits for `Beside` (its sections take 15-17 s here)


class Beside:
    """Warm-up sections compiled in a second Python process while this one works on, for the
    stage that needs them: a first run's `make` (nothing in numba's cache) starts the layout's
    overlap tests of tabs and labels (`tabs`: 5 s, in the cache long before this process lays
    out) and the fold stage's planners (`fold-plan`) at once; when its own fold stage begins
    (`ready`) it compiles the path check (`fold-check`) and the guide's kernels (`guide`) itself
    if the second process is still compiling, then waits for it, and loads the rest from the
    cache instead of compiling it. The fold stage's kernels are the largest share of a first run's compiling (about half of the
    bunny's 33 s here) and share little with the stages before it, which this process compiles
    meanwhile: the two processes end within half a second of each other. If the second process
    fails, this one compiles what it needs as usual. Use as a context manager (the process is
    stopped on the way out)."""

    def __init__(self, beside: tuple[str, ...], here: tuple[str, ...], stage: str) -> None:
        self.stage, self.here = stage, here
        # forked where it may be (it starts with polyfold, numba and numpy imported, where a fresh
        # interpreter spends 0.5-0.7 s importing them), else a fresh Python (macOS)
        self.proc: "Forked | subprocess.Popen | None" = (
            Forked(lambda: _quiet_sections(beside)) if can_fork() else start_sections(beside, capture=False))

    def ready(self, stage: str) -> None:
        """Called as `stage` starts (make's `ready`): when the second process compiles for it, do
        `here` meanwhile and wait for it."""
        if stage != self.stage or self.proc is None:
            return
        import subprocess

        from ..deadline import compiling_elsewhere

        if self.proc.poll() is None:
            for name in self.here:
                SECTIONS[name][1](None)
        with compiling_elsewhere():  # (no deadline runs on while the kernels are made)
            try:
                self.proc.wait(timeout=BESIDE_WAIT_S)
            except subprocess.TimeoutExpired:  # stuck: this process compiles what it needs itself
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def __enter__(self) -> "Beside":
        return self

    def __exit__(self, *exc) -> None:
        if self.proc is not None and self.proc.poll() is None:  # its stage never came (--no-fold, an error)
            self.proc.kill()
            self.proc.wait()
        self.proc = None


def _quiet_sections(names: tuple[str, ...]) -> None:
    """`run_sections` with stdout and stderr to /dev/null (in `Beside`'s forked process: numba's
    warnings would land among the parent's progress lines)."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    run_sections(list(names))


def compile_beside(stages_first: bool = False) -> "Beside | None":
    """With two or more cores, a `Beside` for make's fold stage (for a first run:
    `kernels_cached()` False); else None. stages_first: the make inflates or segments before it
    unfolds, and the second process compiles the unfold stage first, while this one compiles
    those (horse-302 with --parts 4 --inflate constrained: this one compiled 33 s, mostly before
    its unfold stage, the other 20 s, idle from then on)."""
    if usable_cores() >= 2:  # (on one core the two processes would only take turns)
        if can_fork():  # (numba's set-up once, here: the forked process inherits it)
            from ..jit import start_compiler

            start_compiler()
        # the guide's kernels here, with the path check, while the second process compiles the
        # planners: its `tabs` section grew by 2 s with the compiled tests of tabs and labels (the
        # thirteenth session), and with the guide there too this process waited for it (cold make
        # of the bunny, alternating: 18.6-19.2 s with the guide there, 17.6-18.3 s here; the
        # eleventh session had put it there when `tabs` took 3 s)
        first = ("unfold",) if stages_first else ()
        return Beside(first + ("tabs", "fold-plan"), ("fold-check", "guide"), "fold")
    return None


def start_sections(names: tuple[str, ...] | list[str], capture: bool) -> "subprocess.Popen":
    """A second Python process running the named SECTIONS (`python -m polyfold.apps.warmup`); its
    last stdout line, when `capture`, is their seconds as JSON."""
    import subprocess
    import sys

    out = subprocess.PIPE if capture else subprocess.DEVNULL
    return subprocess.Popen([sys.executable, "-m", "polyfold.apps.warmup", *names], stdout=out, stderr=out,
                            text=True)


def run_sections(names: list[str], progress: Callable[[str], None] | None = None) -> dict[str, float]:
    """Run the named SECTIONS in this process, in order; seconds of each."""
    from ..mesh.mesh import Mesh

    say = progress or (lambda line: None)
    # (make's fold-stage sections bring their own net: no trimesh sphere to build for them)
    mesh = Mesh(*bumpy_sphere()) if set(names) - {"unfold", "tabs", "fold-plan", "fold-check", "guide", "labels"} else None
    seconds: dict[str, float] = {}
    for name in names:
        what, run = SECTIONS[name]
        say(f"warm-up: {what}")
        t0 = time.perf_counter()
        run(mesh)
        seconds[name] = time.perf_counter() - t0
    return seconds


def warm_up(progress: Callable[[str], None] | None = None, processes: int | None = None,
            ahead: bool = True) -> dict[str, float]:
    """Call every compiled kernel a command can reach once, just in time (into numba's cache);
    then, with `ahead`, compile the kernel calls of those sections ahead of time (`compile_ahead`);
    seconds per section ("ahead": that step). processes: 1 runs every section here; 2 (the default
    with two or more cores) runs SECOND_PROCESS in a second Python process and HERE in this one at
    the same time (numba compiles in one thread; its cache is written file by file, a temporary
    file renamed, so two processes may fill it together)."""
    import json

    from ..jit import just_in_time

    t0 = time.perf_counter()
    compiled = compile_bytecode()
    if progress:
        progress("warm-up: Python bytecode of polyfold's modules " + ("written" if compiled else "not written (read-only)"))
    bytecode_s = time.perf_counter() - t0
    processes = processes or (2 if usable_cores() >= 2 else 1)
    beside = None
    if processes >= 2:
        beside = start_sections(SECOND_PROCESS, capture=True)
        if progress:
            what = [SECTIONS[n][0] for n in SECOND_PROCESS]
            progress(f"warm-up: {'; '.join(what[:-1])} and {what[-1]}, in a second process")
    here = list(WARM_UP if beside is None else HERE)
    with just_in_time():
        seconds = run_sections(here, progress)
        if beside is not None:
            out, err = beside.communicate()
            if beside.returncode == 0:
                seconds.update(json.loads(out.splitlines()[-1]))
            else:  # whatever went wrong there, compile them here
                seconds.update(run_sections(list(SECOND_PROCESS), progress))
    seconds = {"bytecode": bytecode_s, **seconds}
    if ahead:
        t0 = time.perf_counter()
        said = compile_ahead(progress)
        if progress:
            progress(f"warm-up: ahead of time: {said}")
        seconds["ahead"] = time.perf_counter() - t0
    return seconds


def compile_ahead(progress: Callable[[str], None] | None = None) -> str:
    """Compile the kernels the WARM_UP sections call from Python ahead of time (`jit.build_ahead`), in
    a Python process of its own: it runs them just in time (from numba's cache, which the
    sections before filled), on one core so that no forked worker makes a call unrecorded. Returns
    its one-line account."""
    import json
    import subprocess
    import sys

    from ..jit import SWITCH

    if progress:
        progress("warm-up: the sections again, their kernel calls recorded and compiled ahead of time (a warm "
                 "command then starts without numba)")
    proc = subprocess.run([sys.executable, "-m", "polyfold.apps.warmup", "--ahead", *WARM_UP],
                          capture_output=True, text=True, env={**os.environ, SWITCH: "off"})
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or not lines:
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return f"not built: its process ended with {proc.returncode} ({last})"
    return json.loads(lines[-1])["ahead"]


def _record_and_build(names: list[str]) -> str:
    """The process of `compile_ahead`: the sections with their kernel calls recorded, then the build."""
    from ..jit import build_ahead, record_calls

    cores = os.sched_getaffinity(0) if hasattr(os, "sched_setaffinity") else None
    if cores:
        os.sched_setaffinity(0, {min(cores)})  # (usable_cores() 1: nothing forked)
    calls = record_calls()
    run_sections(names)
    if cores:
        os.sched_setaffinity(0, cores)
    return build_ahead(calls, processes=usable_cores())


if __name__ == "__main__":  # the second process of warm_up: sections named on the command line
    import json
    import sys

    from ..processes import collect_less, in_roomy_stack

    collect_less()
    from ..jit import just_in_time

    def run() -> None:
        if sys.argv[1:2] == ["--ahead"]:
            print(json.dumps({"ahead": _record_and_build(sys.argv[2:])}))
        else:
            with just_in_time():
                print(json.dumps(run_sections(sys.argv[1:])))

    in_roomy_stack(run)
