"""Mesh inflation: reduce the hyperbolic (saddle) vertices of a mesh (ALGORITHMS.md 3).

Model (ALGORITHMS.md 3.1-3.4). The mesh is normalised once (bounding-box centre to the origin,
largest vertex distance 1); `P` are the rest positions, `X` the current ones. Every step recomputes
on the current mesh the face normals `n_f`, corner angles `phi`, angle sums `S_v` and signed fold
angles `rho_e`, then moves every vertex by `dt * f(v)` (first order, unit mass, no damping),
`dt = ln(step + 0.1) / 1000`, with

* pressure      f_p(v) = p_v * sum_{f ∋ v} (phi_{f,v} / S_v) * n_f
* edge springs  for every face and each of its directed edges a->b (an interior edge is visited
                twice): dL = |X_b - X_a| - |P_b - P_a|; if dL > 0, g = E * k_e * dL * unit(X_b - X_a)
                is added to a and subtracted from b (stretch only). k_e = stiffness_ratio on convex
                (rho > 0) and deep concave (rho < -concave_threshold) edges, 1 otherwise.
* rest springs  f_v(v) = -E * lambda_v * (X_v - P_v) (constrained mode only).
                vertex_rule "js" (default): lambda_v = vertex_stiffness * (stiffness_ratio if v has
                no incident concave edge, else 1); "paper": lambda_v = vertex_stiffness * (1 if v is
                hyperbolic, else stiffness_ratio).

Uniform mode forces stiffness_ratio = 1, vertex_stiffness = 0 and hv_boost = 0 (the plain balloon
of the paper, the baseline the constrained IF is compared with).

Why a straight port stalls
--------------------------
With the defaults, the rules above (``hv_boost=0``) stop making progress on sphere-deformed-320
(the Fig. 3 mesh) at HV 18-20, IF ~0.066 (other ports report 14-17 at ~0.078). Two things happen:

1. The remaining saddles are at a true equilibrium, not oscillating: |f| ~ 1e-4 at those vertices
   against |f_p| ~ 0.49. The pressure on a vertex is bounded (the weights phi/S_v sum to 1, so
   |f_p| <= p), while the springs holding it grow linearly with the displacement; the saddles of
   that mesh have convex and *deep* concave edges (rho ~ -25 deg), so most or all of their edges
   are stiff (k_e = 10) and the rest spring adds E * lambda_v. S_v depends on the edge lengths of
   the star only, so lowering it needs the star to stretch, and at p = 0.5 the stiff springs
   (~0.29) plus the rest spring (~0.19) balance the pressure while S_v is still 2 pi + 0.02..0.13.
2. Elsewhere the mesh never settles: edges with rho ~ 0 in the flat parts toggle k_e between 1
   and 10 (58 edges), and with them lambda_v of their vertices (74 vertices), every few steps. This
   limit cycle (amplitude ~2e-3) keeps the summed step displacement near 1e-2, so the JS stall
   rule (< 1e-3) never fires, and two vertices near 2 pi make the HV count flicker 18 <-> 20.
   The paper vertex rule is worse (it pins every elliptic vertex with lambda = 10: HV stays 44).

The rule used here
------------------
A local pressure continuation (``hv_boost``, default 1e-4): every vertex has its own pressure
p_v, starting at p; after each step, p_v grows by hv_boost * p while v is hyperbolic, up to
p * (1 + max_boost) (default 4 p), and is kept (not reset) when v turns elliptic. This is the
"raise p slightly" remedy of ALGORITHMS.md 3.6, applied only where the equilibrium leaves a saddle
and only as much as needed: elliptic vertices never feel more than the base pressure (flat and
convex regions are preserved, IF stays small), while a stuck saddle is pushed out until its
stretched spokes bring S_v below 2 pi. Keeping p_v is a hysteresis: a popped vertex does not fall
back across 2 pi. The growth is slow (p_v doubles after 10 000 hyperbolic steps) so the mesh stays
close to equilibrium (quasi-static): faster rates reach HV 0 in fewer steps but with more IF
(sphere-deformed-320: 1e-4 -> IF 0.0835 in 5 406 steps, 3e-4 -> 0.0865, 1e-3 -> 0.092,
5e-3 -> 0.119; the paper reports 0.0839; uniform mode needs 0.384). The cap keeps a mesh whose
saddles cannot be removed (a torus must keep some) from being blown up: once every remaining
saddle is at the cap the ordinary stall rules end the run.

Stopping, first of: HV <= ``until_hv`` ("target-hv"; a negative until_hv never stops on HV); a
stall ("stalled": the summed step displacement sum_v |dt f(v)| < 1e-3 while no saddle's pressure
is still rising, or, for the limit cycle above, no new lowest HV and IF moving less than 1e-4
over ``stall_window`` steps); ``max_steps`` ("max-steps"); a guard ("guard: ...").

Guards. A step is rejected, and the state before it returned, when a face normal turns by more
than 90 degrees in one step ("face N would flip"), a face area drops below 1e-8 of the initial
mean ("would collapse"), or an edge's fold angle passes through +-180 degrees ("faces i and j
would fold through each other"); these run in the step kernel (`kernels.run_steps`).
Self-intersection (two faces sharing no edge cross, `collide.self_intersect.crossing_pairs` with the
touching semantics of `collide.triangles.triangles_collide`, so faces meeting at a shared vertex
count only if they really cross; tolerance 1e-7 of the bounding-box diagonal) is checked at the
start, every ``log_every`` steps and at the end; when it trips, the state of the last passed check
is returned ("faces i and j would intersect"). Pairs that already cross in the input (and their
one-ring neighbours) are reported in ``notes`` and exempt.

Open meshes: boundary vertices move under the same forces (pressure over their partial fan,
springs, rest spring) but are not counted as hyperbolic (their angle sum is not a curvature, as in
`mesh.repair.describe`), are never boosted and count as elliptic for the paper rule; boundary edges have
rho = 0 (k_e = 1).

IF (ALGORITHMS.md 3.5) = mean |X_v - P_v| over the vertices of the faces, in units of the
normalised mesh (bounding-sphere radius 1). volume_change = V / V_0 - 1 of the signed volume about
the bounding-box centre (nan when V_0 = 0). The output is mapped back to the input's frame and
units; faces, face order and face_source are the input's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Iterable, Optional

import numpy as np

from ..collide.self_intersect import crossing_pairs
from ..collide.tolerance import CONTACT_TOL
from ..errors import PolyfoldError
from ..mesh.geometry import signed_volume
from ..mesh.mesh import Mesh
from .kernels import AT_TARGET, COLLAPSED, FLIPPED, FOLDED_THROUGH, STALLED, run_steps, surface_geometry

COLLAPSE = 1e-8  # a face collapses when its area drops below this * the initial mean area
CONTACT = CONTACT_TOL  # self-intersection tolerance, fraction of the bounding-box diagonal
STALL_IF = 1e-4  # stall window: IF moving less than this since the window opened


@dataclass(frozen=True)
class InflateResult:
    """Result of `inflate`.

    mesh: the inflated mesh in the input's frame and units (same faces, face order, face_source).
    stop_reason: "target-hv", "stalled", "max-steps", or "guard: ..." (the state is the last good
    one). steps: updates applied. inflation_rate: IF at the end. hyperbolic: HV at the end
    (hyperbolic_start: at the start). history: rows (step, IF, HV, volume_change) every log_every
    steps plus the final state. snapshots: {step: (n, 3) vertex positions in the input frame}.
    notes: facts worth reporting (e.g. the input already self-intersects).
    """

    mesh: Mesh
    stop_reason: str
    steps: int
    inflation_rate: float
    hyperbolic: int
    history: np.ndarray
    snapshots: dict = field(default_factory=dict)
    hyperbolic_start: int = 0
    notes: tuple = ()


def inflate(
    mesh: Mesh,
    mode: str = "constrained",
    pressure: float = 0.5,
    modulus: float = 2.0,
    step: float = 1.2,
    stiffness_ratio: float = 10.0,
    concave_threshold_deg: float = 15.0,
    vertex_stiffness: float = 1.0,
    until_hv: int = 0,
    max_steps: int = 20000,
    log_every: int = 50,
    snapshot_steps: Iterable[int] = (),
    vertex_rule: str = "js",
    hv_boost: float = 1e-4,
    max_boost: float = 3.0,
    stall_window: int = 2000,
    check_intersections: bool = True,
    progress: Optional[Callable[[int, float, int], None]] = None,
) -> InflateResult:
    """Inflate `mesh` until at most `until_hv` hyperbolic vertices remain (ALGORITHMS.md 3).

    mode "constrained" (paper Eqs. 6-8) or "uniform" (stiffness_ratio 1, vertex_stiffness 0
    forced). hv_boost: per-step growth of the pressure on still-hyperbolic vertices, relative to
    `pressure` (0 = the straight port, see the module docstring). stall_window: steps without a
    new best HV and with IF moving less than 1e-4 that count as a stall (0 disables).
    check_intersections=False drops the self-intersection guard (the input is still checked and
    reported in notes); the flip, collapse and fold-through guards always run.
    progress(step, IF, HV) is called every log_every steps. Raises PolyfoldError on bad arguments.
    """
    _check_arguments(mesh, mode, vertex_rule, step, max_steps, log_every, stall_window, {
        "pressure": pressure, "modulus": modulus, "stiffness_ratio": stiffness_ratio,
        "vertex_stiffness": vertex_stiffness, "hv_boost": hv_boost, "max_boost": max_boost,
        "concave_threshold_deg": concave_threshold_deg})
    if mode == "uniform":
        stiffness_ratio, vertex_stiffness, hv_boost = 1.0, 0.0, 0.0
    surface = _normalised_surface(mesh)
    model = _Model(
        pressures=np.full(surface.n_vertices, float(pressure)), boost=float(hv_boost),
        cap=float(pressure) * (1.0 + max_boost), pressure=float(pressure), modulus=float(modulus),
        stiffness=float(stiffness_ratio), threshold=math.radians(concave_threshold_deg),
        vertex_stiffness=float(vertex_stiffness), rule=0 if vertex_rule == "js" else 1,
        dt=math.log(step + 0.1) / 1000.0, until_hv=int(until_hv),
        min_area2=COLLAPSE * float(surface.area2.mean()))
    guard = _IntersectionGuard(surface, check_intersections)
    log = _Log(surface, snapshot_steps, max_steps, progress)
    log.snap(0, surface.X)
    log.record(0, surface.X, surface.hv_start)
    reason, done, hv = _step_loop(surface, model, guard, log, max_steps, log_every, stall_window)
    return _result(mesh, surface, log, guard.notes, reason, done, hv)


MAX_PARAMETER = 1e6  # pressures, moduli and stiffnesses above this are typing errors (the UI range is 0.1-10)


def _check_arguments(mesh: Mesh, mode: str, vertex_rule: str, step: float, max_steps: int, log_every: int,
                     stall_window: int, nonnegative: dict[str, float]) -> None:
    """Raise PolyfoldError on an argument `inflate` cannot run with (nonnegative: name -> value of
    the parameters that must be finite and >= 0)."""
    if mode not in ("constrained", "uniform"):
        raise PolyfoldError(f"unknown inflation mode {mode!r} (use 'constrained' or 'uniform')")
    if vertex_rule not in ("js", "paper"):
        raise PolyfoldError(f"unknown vertex rule {vertex_rule!r} (use 'js' or 'paper')")
    for name, value in nonnegative.items():
        if not (math.isfinite(value) and value >= 0):
            raise PolyfoldError(f"{name} must be a finite number >= 0, not {value!r}")
        if value > MAX_PARAMETER:
            raise PolyfoldError(f"{name} must be at most {MAX_PARAMETER:g} (forces that large overflow), not {value!r}")
    if not (math.isfinite(step) and step > 0.9):
        raise PolyfoldError(f"step must be > 0.9 (dt = ln(step + 0.1) / 1000 > 0), not {step!r}")
    if max_steps < 0 or log_every < 1 or stall_window < 0:
        raise PolyfoldError("max_steps and stall_window must be >= 0 and log_every >= 1")
    if mesh.n_faces == 0:
        raise PolyfoldError("cannot inflate a mesh without faces")


@dataclass(frozen=True)
class _Surface:
    """The mesh being inflated, normalised (bounding-box centre of the used vertices at the
    origin, largest distance 1), with the arrays of `run_steps`. P: rest positions; X: current
    positions (updated in place); used: vertices of some face; counted: used and not on the
    boundary (their angle sum is a curvature); L0 (m, 3): rest length of edge k -> k+1 of each
    face; geometry: normals, area2, phi, S, rho of X; scratch: the buffers of a step's state
    (Xn, normals, area2, phi, S, rho), lam, force; out: what `run_steps` reports (steps done, HV,
    the face / faces of a guard's stop)."""

    F: np.ndarray
    edges: np.ndarray
    efaces: np.ndarray
    fedge: np.ndarray
    used: np.ndarray
    counted: np.ndarray
    center: np.ndarray
    scale: float
    P: np.ndarray
    X: np.ndarray
    L0: np.ndarray
    geometry: tuple
    scratch: tuple
    out: np.ndarray
    hv_start: int

    @property
    def n_vertices(self) -> int:
        return len(self.P)

    @property
    def area2(self) -> np.ndarray:
        """Doubled face areas of X as of the last `surface_geometry` (set-up or step)."""
        return self.geometry[1]

    def inflation_rate(self, state: np.ndarray) -> float:
        """IF: mean |state_v - P_v| over the used vertices."""
        return float(np.linalg.norm(state[self.used] - self.P[self.used], axis=1).mean())


def _normalised_surface(mesh: Mesh) -> _Surface:
    """`_Surface` of mesh, its geometry computed; PolyfoldError if its used vertices coincide."""
    F = mesh.faces
    topo = mesh.topology
    edges = np.ascontiguousarray(topo.edges)
    efaces = np.ascontiguousarray(topo.edge_faces)
    V = mesh.vertices
    used = np.zeros(len(V), dtype=bool)
    used[F.reshape(-1)] = True
    center = (V[used].max(0) + V[used].min(0)) / 2.0
    scale = float(np.linalg.norm(V[used] - center, axis=1).max())
    if not scale > 0:
        raise PolyfoldError("cannot inflate a mesh whose vertices all coincide")
    P = np.ascontiguousarray((V - center) / scale)
    X = P.copy()
    counted = used.copy()
    counted[edges[topo.boundary].reshape(-1)] = False  # boundary vertices: not curvature
    L0 = np.linalg.norm(P[np.roll(F, -1, axis=1)] - P[F], axis=2)
    m, n = len(F), len(V)
    geometry = (np.empty((m, 3)), np.empty(m), np.empty((m, 3)), np.empty(n), np.empty(len(edges)))
    scratch = (np.empty((n, 3)), np.empty((m, 3)), np.empty(m), np.empty((m, 3)), np.empty(n), np.empty(len(edges)),
               np.empty(n), np.empty((n, 3)))
    hv = int(surface_geometry(X, F, edges, efaces, counted, *geometry))
    return _Surface(F, edges, efaces, np.ascontiguousarray(topo.face_edges), used, counted, center, scale, P, X, L0,
                    geometry, scratch, np.zeros(4, dtype=np.int64), hv)


@dataclass(frozen=True)
class _Model:
    """The force model's parameters as `run_steps` takes them (after the uniform-mode
    overrides). pressures (n,): p_v, raised in place on hyperbolic vertices by boost * pressure
    per step up to cap; threshold: deep-concave threshold (radians); rule: 0 js, 1 paper."""

    pressures: np.ndarray
    boost: float
    cap: float
    pressure: float
    modulus: float
    stiffness: float
    threshold: float
    vertex_stiffness: float
    rule: int
    dt: float
    until_hv: int
    min_area2: float

    def run(self, s: _Surface, n_steps: int) -> int:
        """Up to n_steps steps of s.X (`run_steps`); returns its status, s.out its counts."""
        return run_steps(s.X, s.P, s.F, s.L0, s.fedge, s.edges, s.efaces, s.counted, self.pressures, self.boost,
                         self.cap, self.pressure, self.modulus, self.stiffness, self.threshold,
                         self.vertex_stiffness, self.rule, self.dt, self.until_hv, n_steps, self.min_area2,
                         *s.geometry, *s.scratch, s.out)


class _Log:
    """What a run records: history rows (step, IF, HV, volume_change), snapshots in the input's
    frame at the wanted steps, the progress callback."""

    def __init__(self, surface: _Surface, snapshot_steps: Iterable[int], max_steps: int,
                 progress: Optional[Callable[[int, float, int], None]]) -> None:
        self.surface = surface
        self.snaps_wanted = sorted({int(s) for s in snapshot_steps if 0 <= int(s) <= max_steps})
        self.snapshots: dict[int, np.ndarray] = {}
        self.history: list[tuple[float, float, float, float]] = []
        self.progress = progress
        self.v0 = signed_volume(surface.P, surface.F)

    def record(self, k: int, state: np.ndarray, hv: int) -> float:
        """Log (or replace) the row of step k; returns its IF."""
        IF = self.surface.inflation_rate(state)
        vol = signed_volume(state, self.surface.F)
        dv = vol / self.v0 - 1.0 if self.v0 != 0 else float("nan")
        if self.history and self.history[-1][0] == k:
            self.history[-1] = (k, IF, hv, dv)
        else:
            self.history.append((k, IF, hv, dv))
        if self.progress is not None:
            self.progress(k, IF, hv)
        return IF

    def snap(self, k: int, state: np.ndarray) -> None:
        if k in self.snaps_wanted:
            self.snapshots[k] = state * self.surface.scale + self.surface.center

    def rewind(self, k: int) -> None:
        """Forget the rows and snapshots after step k."""
        for s in [s for s in self.snapshots if s > k]:
            del self.snapshots[s]
        while self.history and self.history[-1][0] > k:
            self.history.pop()


def _result(mesh: Mesh, surface: _Surface, log: _Log, notes: tuple, reason: str, done: int, hv: int) -> InflateResult:
    """The InflateResult of a run that stopped for `reason` after `done` steps at HV hv (the state
    in surface.X); logs that state if it is not the last row yet."""
    if not np.isfinite(surface.X).all():  # (the guards compare positions: NaN slips past them)
        raise PolyfoldError(f"inflation diverged by step {done} (positions no longer finite): lower the pressure "
                            "or the stiffness ratio")
    IF = surface.inflation_rate(surface.X)
    out_mesh = Mesh(surface.X * surface.scale + surface.center, surface.F.copy(), mesh.face_source.copy())
    if not log.history or log.history[-1][0] != done:
        log.record(done, surface.X, hv)
    return InflateResult(
        mesh=out_mesh,
        stop_reason=reason,
        steps=done,
        inflation_rate=IF,
        hyperbolic=hv,
        history=np.array(log.history, dtype=np.float64).reshape(-1, 4),
        snapshots=log.snapshots,
        hyperbolic_start=surface.hv_start,
        notes=notes,
    )


def _near_pairs(F: np.ndarray, pairs: np.ndarray, n: int) -> np.ndarray:
    """Sorted keys i * m + j (i < j) of the face pairs exempt from the intersection guard because the
    input already crosses there: both faces within one vertex ring of the two faces of an input
    crossing pair (the crossing line slides onto neighbouring faces as the surfaces move)."""
    m = len(F)
    vert_faces = [[] for _ in range(n)]
    for f, tri in enumerate(F.tolist()):
        for v in tri:
            vert_faces[v].append(f)
    keys = set()
    for i, j in pairs.tolist():
        near_i = sorted({g for v in F[i] for g in vert_faces[v]})
        near_j = sorted({g for v in F[j] for g in vert_faces[v]})
        for a in near_i:
            for b in near_j:
                if a != b:
                    keys.add(min(a, b) * m + max(a, b))
    return np.array(sorted(keys), dtype=np.int64)


class _IntersectionGuard:
    """The self-intersection guard: the input's crossing pairs (a note; they and their neighbours
    are exempt, `_near_pairs`) and the last state that passed a check (step, X, HV)."""

    def __init__(self, surface: _Surface, enabled: bool) -> None:
        X, F, used = surface.X, surface.F, surface.used
        self.surface = surface
        self.enabled = enabled
        self.tol = CONTACT * float(np.linalg.norm(surface.P[used].max(0) - surface.P[used].min(0)))
        count, pairs = crossing_pairs(X, F, self.tol, 0)
        notes = []
        if count:
            count, pairs = crossing_pairs(X, F, self.tol, count)
            notes.append(f"the input already self-intersects ({count} crossing face pair{'s' if count != 1 else ''}, "
                         f"e.g. faces {pairs[0, 0]} and {pairs[0, 1]}); those pairs and their neighbours are not checked")
        self.notes = tuple(notes)
        self.skip = _near_pairs(F, pairs, surface.n_vertices) if count else None
        self.good = (0, X.copy(), surface.hv_start)

    def crossing(self) -> Optional[tuple[int, int]]:
        """A face pair of the current state that crosses (not exempt), or None (also when off)."""
        if not self.enabled:
            return None
        count, pairs = crossing_pairs(self.surface.X, self.surface.F, self.tol, 1, self.skip)
        return (int(pairs[0, 0]), int(pairs[0, 1])) if count else None

    def passed(self, k: int, hv: int) -> None:
        """The current state (step k, HV hv) passed a check."""
        if self.enabled:
            self.good = (k, self.surface.X.copy(), hv)

    def restore(self) -> tuple[int, int]:
        """Put the last state that passed back into the surface; returns its (step, HV)."""
        k, X, hv = self.good
        self.surface.X[:] = X
        return k, hv


class _StallWindow:
    """The stall rule for the limit cycle (module docstring): no new lowest HV and IF moving
    less than STALL_IF over `window` steps (window 0: never)."""

    def __init__(self, window: int, hv: int) -> None:
        self.window = window
        self.best_hv, self.best_at, self.if_at_best = hv, 0, 0.0

    def stalled(self, k: int, hv: int, IF: float) -> bool:
        """Update with the logged state of step k; True when the run has stalled."""
        if not self.window:
            return False
        if hv < self.best_hv:
            self.best_hv, self.best_at, self.if_at_best = hv, k, IF
        elif k - self.best_at >= self.window:
            if abs(IF - self.if_at_best) < STALL_IF:
                return True
            self.best_at, self.if_at_best = k, IF
        return False


def _stop_reason(status: int, out: np.ndarray, at_max_steps: bool) -> str:
    """The stop reason for a `run_steps` status ("" to go on)."""
    if status == AT_TARGET:
        return "target-hv"
    if status == STALLED:
        return "stalled"
    if status == FLIPPED:
        return f"guard: face {int(out[2])} would flip"
    if status == COLLAPSED:
        return f"guard: face {int(out[2])} would collapse"
    if status == FOLDED_THROUGH:
        return f"guard: faces {int(out[2])} and {int(out[3])} would fold through each other"
    return "max-steps" if at_max_steps else ""


def _step_loop(surface: _Surface, model: _Model, guard: _IntersectionGuard, log: _Log, max_steps: int,
               log_every: int, stall_window: int) -> tuple[str, int, int]:
    """Run the steps in chunks up to the next log step or snapshot, until a stop rule fires; the
    intersection guard and the log at every log step and at the end. Returns (stop reason, steps
    done, HV) of the state left in surface.X."""
    done = 0
    hv = surface.hv_start
    reason = ""
    stall = _StallWindow(stall_window, hv)
    while not reason:
        target = min(max_steps, (done // log_every + 1) * log_every)
        later = [s for s in log.snaps_wanted if s > done]
        if later:
            target = min(target, later[0])
        status = model.run(surface, target - done)
        done += int(surface.out[0])
        hv = int(surface.out[1])
        reason = _stop_reason(status, surface.out, done >= max_steps)
        log.snap(done, surface.X)
        if done % log_every == 0 or reason:
            hit = guard.crossing()
            if hit is not None:
                done, hv = guard.restore()
                log.rewind(done)
                return f"guard: faces {hit[0]} and {hit[1]} would intersect", done, hv
            guard.passed(done, hv)
            IF = log.record(done, surface.X, hv)
            if not reason and stall.stalled(done, hv, IF):
                reason = "stalled"
    return reason, done, hv
