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
would fold through each other"). Self-intersection (two faces sharing no edge cross, by
`collide.triangles.triangles_collide` with its touching semantics, so faces meeting at a shared vertex
count only if they really cross; tolerance 1e-7 of the bounding-box diagonal) is checked by a
sort-and-sweep over face boxes at the start, every ``log_every`` steps and at the end; when it
trips, the state of the last passed check is returned ("faces i and j would intersect"). Pairs that
already cross in the input (and their one-ring neighbours) are reported in ``notes`` and exempt.

Open meshes: boundary vertices move under the same forces (pressure over their partial fan,
springs, rest spring) but are not counted as hyperbolic (their angle sum is not a curvature, as in
`io.describe`), are never boosted and count as elliptic for the paper rule; boundary edges have
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
from numba import njit

from ..collide.sweep import face_boxes
from ..collide.tolerance import CONTACT_TOL
from ..collide.triangles import triangles_collide
from ..errors import PolyfoldError
from ..mesh.geometry import HYPERBOLIC_EPS
from ..mesh.mesh import Mesh

TWO_PI = 2.0 * math.pi
HV_EPS = HYPERBOLIC_EPS  # hyperbolic: S_v > 2 pi + HV_EPS
STALL_DISP = 1e-3  # stop when the summed step displacement falls below this
COLLAPSE = 1e-8  # a face collapses when its area drops below this * the initial mean area
CONTACT = CONTACT_TOL  # self-intersection tolerance, fraction of the bounding-box diagonal

# chunk status codes
_RUNNING, _TARGET, _STALL, _FLIP, _COLLAPSE, _FOLD = 0, 1, 2, 3, 4, 5


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


# --------------------------------------------------------------------------------------------------
# numba kernels
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def _geometry(X, F, edges, efaces, counted, normals, area2, phi, S, rho):
    """Unit normals, doubled areas, corner angles, angle sums and fold angles of X; returns HV."""
    m = F.shape[0]
    n = X.shape[0]
    for v in range(n):
        S[v] = 0.0
    for f in range(m):
        a = F[f, 0]
        b = F[f, 1]
        c = F[f, 2]
        ux = X[b, 0] - X[a, 0]
        uy = X[b, 1] - X[a, 1]
        uz = X[b, 2] - X[a, 2]
        wx = X[c, 0] - X[a, 0]
        wy = X[c, 1] - X[a, 1]
        wz = X[c, 2] - X[a, 2]
        nx = uy * wz - uz * wy
        ny = uz * wx - ux * wz
        nz = ux * wy - uy * wx
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        area2[f] = nn
        if nn > 0.0:
            normals[f, 0] = nx / nn
            normals[f, 1] = ny / nn
            normals[f, 2] = nz / nn
        else:
            normals[f, 0] = 0.0
            normals[f, 1] = 0.0
            normals[f, 2] = 0.0
        for k in range(3):
            p = F[f, k]
            q = F[f, (k + 1) % 3]
            r = F[f, (k + 2) % 3]
            ax = X[q, 0] - X[p, 0]
            ay = X[q, 1] - X[p, 1]
            az = X[q, 2] - X[p, 2]
            bx = X[r, 0] - X[p, 0]
            by = X[r, 1] - X[p, 1]
            bz = X[r, 2] - X[p, 2]
            cx = ay * bz - az * by
            cy = az * bx - ax * bz
            cz = ax * by - ay * bx
            ang = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)
            phi[f, k] = ang
            S[p] += ang
    for e in range(edges.shape[0]):
        f0 = efaces[e, 0]
        f1 = efaces[e, 1]
        if f0 < 0 or f1 < 0:
            rho[e] = 0.0
            continue
        a = edges[e, 0]
        b = edges[e, 1]
        ux = X[b, 0] - X[a, 0]
        uy = X[b, 1] - X[a, 1]
        uz = X[b, 2] - X[a, 2]
        n0x = normals[f0, 0]
        n0y = normals[f0, 1]
        n0z = normals[f0, 2]
        n1x = normals[f1, 0]
        n1y = normals[f1, 1]
        n1z = normals[f1, 2]
        cx = n0y * n1z - n0z * n1y
        cy = n0z * n1x - n0x * n1z
        cz = n0x * n1y - n0y * n1x
        lu = math.sqrt(ux * ux + uy * uy + uz * uz)
        s = (cx * ux + cy * uy + cz * uz) / lu if lu > 0.0 else 0.0
        rho[e] = math.atan2(s, n0x * n1x + n0y * n1y + n0z * n1z)
    hv = 0
    for v in range(n):
        if counted[v] and S[v] > TWO_PI + HV_EPS:
            hv += 1
    return hv


@njit(cache=True)
def _forces(X, P, F, L0, fedge, edges, phi, S, rho, normals, pv, E, stiff, thr, vbase, vrule, counted, lam, force):
    """Total force per vertex (pressure + stretch-only edge springs + rest springs) into `force`.

    pv: per-vertex pressure; stiff: k_e of stiff edges (1 in uniform mode); thr: deep-concave
    threshold (radians); vbase: vertex_stiffness (0 disables the rest springs); vrule 0 = js, 1 = paper;
    lam: (n,) scratch buffer.
    """
    n = X.shape[0]
    m = F.shape[0]
    for v in range(n):
        force[v, 0] = 0.0
        force[v, 1] = 0.0
        force[v, 2] = 0.0
    for f in range(m):
        for k in range(3):
            v = F[f, k]
            if S[v] > 0.0:
                w = pv[v] * phi[f, k] / S[v]
                force[v, 0] += w * normals[f, 0]
                force[v, 1] += w * normals[f, 1]
                force[v, 2] += w * normals[f, 2]
    for f in range(m):
        for k in range(3):
            a = F[f, k]
            b = F[f, (k + 1) % 3]
            dx = X[b, 0] - X[a, 0]
            dy = X[b, 1] - X[a, 1]
            dz = X[b, 2] - X[a, 2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            dl = length - L0[f, k]
            if dl <= 0.0 or length == 0.0:
                continue
            r = rho[fedge[f, k]]
            ke = stiff if (r > 0.0 or -r > thr) else 1.0
            g = E * ke * dl / length
            force[a, 0] += g * dx
            force[a, 1] += g * dy
            force[a, 2] += g * dz
            force[b, 0] -= g * dx
            force[b, 1] -= g * dy
            force[b, 2] -= g * dz
    if vbase > 0.0:
        if vrule == 0:
            for v in range(n):
                lam[v] = stiff
            for e in range(edges.shape[0]):
                if rho[e] < 0.0:
                    lam[edges[e, 0]] = 1.0
                    lam[edges[e, 1]] = 1.0
        else:
            for v in range(n):
                lam[v] = 1.0 if (counted[v] and S[v] > TWO_PI + HV_EPS) else stiff
        for v in range(n):
            k = E * vbase * lam[v]
            force[v, 0] -= k * (X[v, 0] - P[v, 0])
            force[v, 1] -= k * (X[v, 1] - P[v, 1])
            force[v, 2] -= k * (X[v, 2] - P[v, 2])


@njit(cache=True)
def _run(X, P, F, L0, fedge, edges, efaces, counted, pv, boost, pcap, p, E, stiff, thr, vbase, vrule, dt,
         until_hv, n_steps, min_area2, normals, area2, phi, S, rho, Xn, normals_n, area2_n, phi_n, S_n, rho_n,
         lam, force, out):
    """Run up to n_steps steps from X (whose geometry is in normals..rho). Updates X, the geometry
    buffers and the per-vertex pressures pv (raised by p * boost per step on hyperbolic vertices, up
    to pcap) in place. out[0] = steps done, out[1] = HV of X, out[2], out[3] = detail
    (face / faces / edge). Returns the status code."""
    n = X.shape[0]
    m = F.shape[0]
    hv = 0
    for v in range(n):
        if counted[v] and S[v] > TWO_PI + HV_EPS:
            hv += 1
    done = 0
    status = _RUNNING
    while True:
        out[1] = hv
        if hv <= until_hv:
            status = _TARGET
            break
        if done >= n_steps:
            break
        _forces(X, P, F, L0, fedge, edges, phi, S, rho, normals, pv, E, stiff, thr, vbase, vrule, counted, lam, force)
        total = 0.0
        for v in range(n):
            dx = dt * force[v, 0]
            dy = dt * force[v, 1]
            dz = dt * force[v, 2]
            total += math.sqrt(dx * dx + dy * dy + dz * dz)
            Xn[v, 0] = X[v, 0] + dx
            Xn[v, 1] = X[v, 1] + dy
            Xn[v, 2] = X[v, 2] + dz
        if total < STALL_DISP:
            rising = False  # a still-hyperbolic vertex whose pressure is still being raised
            if boost > 0.0:
                for v in range(n):
                    if counted[v] and S[v] > TWO_PI + HV_EPS and pv[v] < pcap:
                        rising = True
                        break
            if not rising:
                status = _STALL
                break
        hv_n = _geometry(Xn, F, edges, efaces, counted, normals_n, area2_n, phi_n, S_n, rho_n)
        for f in range(m):
            if area2_n[f] < min_area2:
                status = _COLLAPSE
                out[2] = f
                break
            if (normals[f, 0] * normals_n[f, 0] + normals[f, 1] * normals_n[f, 1]
                    + normals[f, 2] * normals_n[f, 2]) < 0.0:
                status = _FLIP
                out[2] = f
                break
        if status != _RUNNING:
            break
        for e in range(edges.shape[0]):
            a = rho[e]
            b = rho_n[e]
            if (a > 0.5 * math.pi and b < -0.5 * math.pi) or (a < -0.5 * math.pi and b > 0.5 * math.pi):
                status = _FOLD
                out[2] = efaces[e, 0]
                out[3] = efaces[e, 1]
                break
        if status != _RUNNING:
            break
        X[:] = Xn
        normals[:] = normals_n
        area2[:] = area2_n
        phi[:] = phi_n
        S[:] = S_n
        rho[:] = rho_n
        hv = hv_n
        done += 1
        if boost > 0.0:
            for v in range(n):
                if counted[v] and S[v] > TWO_PI + HV_EPS:
                    pv[v] = min(pv[v] + p * boost, pcap)
    out[0] = done
    return status


@njit(cache=True)
def _intersections(X, F, tol, skip_keys, max_pairs, pairs):
    """Sort-and-sweep over face AABBs; exact test (triangles_collide) on pairs sharing no edge and
    not listed in skip_keys (sorted i * m + j, i < j). Returns the number of crossing pairs
    (the first max_pairs written to pairs)."""
    m = F.shape[0]
    tris = np.empty((m, 3, 3))
    for f in range(m):
        for k in range(3):
            for i in range(3):
                tris[f, k, i] = X[F[f, k], i]
    lo, hi = face_boxes(tris)
    xs = np.argsort(lo[:, 0])
    count = 0
    for ii in range(m):
        i = xs[ii]
        for jj in range(ii + 1, m):
            j = xs[jj]
            if lo[j, 0] - hi[i, 0] > tol:
                break
            if lo[j, 1] - hi[i, 1] > tol or lo[i, 1] - hi[j, 1] > tol:
                continue
            if lo[j, 2] - hi[i, 2] > tol or lo[i, 2] - hi[j, 2] > tol:
                continue
            shared = 0
            for a in range(3):
                for b in range(3):
                    if F[i, a] == F[j, b]:
                        shared += 1
            if shared >= 2:
                continue  # edge neighbours: handled by the fold-through guard
            lo_ij = min(i, j)
            hi_ij = max(i, j)
            if skip_keys.shape[0] > 0:
                key = lo_ij * m + hi_ij
                k = np.searchsorted(skip_keys, key)
                if k < skip_keys.shape[0] and skip_keys[k] == key:
                    continue
            if triangles_collide(tris[i], tris[j], tol):
                if count < max_pairs:
                    pairs[count, 0] = lo_ij
                    pairs[count, 1] = hi_ij
                count += 1
    return count


# --------------------------------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------------------------------


def _signed_volume(X: np.ndarray, F: np.ndarray) -> float:
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _crossing_pairs(X: np.ndarray, F: np.ndarray, tol: float, skip: np.ndarray, max_pairs: int = 64) -> tuple[int, np.ndarray]:
    pairs = np.empty((max(max_pairs, 1), 2), dtype=np.int64)
    count = _intersections(X, F, tol, skip, max_pairs, pairs)
    return int(count), pairs[: min(count, max_pairs)]


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


def self_intersections(mesh: Mesh, tol: float = CONTACT) -> np.ndarray:
    """Pairs (k, 2), i < j, of faces that cross each other (faces sharing an edge are not tested;
    faces touching at a shared vertex or resting on each other do not count). tol: fraction of the
    bounding-box diagonal."""
    X, F = mesh.vertices, mesh.faces
    if len(F) == 0:
        return np.empty((0, 2), dtype=np.int64)
    diag = float(np.linalg.norm(X.max(0) - X.min(0))) if len(X) else 0.0
    empty = np.empty(0, dtype=np.int64)
    count, _ = _crossing_pairs(X, F, tol * diag, empty, 0)
    if count == 0:
        return np.empty((0, 2), dtype=np.int64)
    return _crossing_pairs(X, F, tol * diag, empty, count)[1]


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
    if mode not in ("constrained", "uniform"):
        raise PolyfoldError(f"unknown inflation mode {mode!r} (use 'constrained' or 'uniform')")
    if vertex_rule not in ("js", "paper"):
        raise PolyfoldError(f"unknown vertex rule {vertex_rule!r} (use 'js' or 'paper')")
    checks = {"pressure": pressure, "modulus": modulus, "stiffness_ratio": stiffness_ratio,
              "vertex_stiffness": vertex_stiffness, "hv_boost": hv_boost, "max_boost": max_boost,
              "concave_threshold_deg": concave_threshold_deg}
    for name, value in checks.items():
        if not (math.isfinite(value) and value >= 0):
            raise PolyfoldError(f"{name} must be a finite number >= 0, not {value!r}")
    if not (math.isfinite(step) and step > 0.9):
        raise PolyfoldError(f"step must be > 0.9 (dt = ln(step + 0.1) / 1000 > 0), not {step!r}")
    if max_steps < 0 or log_every < 1 or stall_window < 0:
        raise PolyfoldError("max_steps and stall_window must be >= 0 and log_every >= 1")
    if mesh.n_faces == 0:
        raise PolyfoldError("cannot inflate a mesh without faces")
    if mode == "uniform":
        stiffness_ratio, vertex_stiffness, hv_boost = 1.0, 0.0, 0.0
    dt = math.log(step + 0.1) / 1000.0

    F = mesh.faces
    topo = mesh.topology
    edges = np.ascontiguousarray(topo.edges)
    efaces = np.ascontiguousarray(topo.edge_faces)
    fedge = np.ascontiguousarray(topo.face_edges)
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
    normals, area2, phi, S, rho = np.empty((m, 3)), np.empty(m), np.empty((m, 3)), np.empty(n), np.empty(len(edges))
    bufs_n = (np.empty((n, 3)), np.empty((m, 3)), np.empty(m), np.empty((m, 3)), np.empty(n), np.empty(len(edges)))
    force, lam = np.empty((n, 3)), np.empty(n)
    out = np.zeros(4, dtype=np.int64)
    hv = int(_geometry(X, F, edges, efaces, counted, normals, area2, phi, S, rho))
    hv_start = hv
    min_area2 = COLLAPSE * float(area2.mean())
    pv = np.full(n, float(pressure))
    pcap = float(pressure) * (1.0 + max_boost)
    rule = 0 if vertex_rule == "js" else 1
    v0 = _signed_volume(P, F)
    tol = CONTACT * float(np.linalg.norm(P[used].max(0) - P[used].min(0)))

    notes: list[str] = []
    count, pairs = _crossing_pairs(X, F, tol, np.empty(0, dtype=np.int64), 0)
    if count:
        count, pairs = _crossing_pairs(X, F, tol, np.empty(0, dtype=np.int64), count)
        notes.append(f"the input already self-intersects ({count} crossing face pair{'s' if count != 1 else ''}, "
                     f"e.g. faces {pairs[0, 0]} and {pairs[0, 1]}); those pairs and their neighbours are not checked")
    skip = _near_pairs(F, pairs, n) if count else np.empty(0, dtype=np.int64)

    snaps_wanted = sorted({int(s) for s in snapshot_steps if 0 <= int(s) <= max_steps})
    snapshots: dict[int, np.ndarray] = {}
    history: list[tuple[float, float, float, float]] = []

    def mean_disp(state: np.ndarray) -> float:
        return float(np.linalg.norm(state[used] - P[used], axis=1).mean())

    def record(k: int, state: np.ndarray, hv_k: int) -> None:
        IF = mean_disp(state)
        vol = _signed_volume(state, F)
        dv = vol / v0 - 1.0 if v0 != 0 else float("nan")
        if history and history[-1][0] == k:
            history[-1] = (k, IF, hv_k, dv)
        else:
            history.append((k, IF, hv_k, dv))
        if progress is not None:
            progress(k, IF, hv_k)

    def snap(k: int, state: np.ndarray) -> None:
        if k in snaps_wanted:
            snapshots[k] = state * scale + center

    snap(0, X)
    record(0, X, hv)
    good = (0, X.copy(), hv)  # last state that passed the intersection check
    done = 0
    reason = ""
    best_hv, best_at, if_at_best = hv, 0, 0.0
    while not reason:
        target = min(max_steps, (done // log_every + 1) * log_every)
        later = [s for s in snaps_wanted if s > done]
        if later:
            target = min(target, later[0])
        status = _run(X, P, F, L0, fedge, edges, efaces, counted, pv, float(hv_boost), pcap, float(pressure),
                      float(modulus), float(stiffness_ratio), math.radians(concave_threshold_deg),
                      float(vertex_stiffness), rule, dt, int(until_hv), target - done, min_area2,
                      normals, area2, phi, S, rho, *bufs_n, lam, force, out)
        done += int(out[0])
        hv = int(out[1])
        if status == _TARGET:
            reason = "target-hv"
        elif status == _STALL:
            reason = "stalled"
        elif status == _FLIP:
            reason = f"guard: face {int(out[2])} would flip"
        elif status == _COLLAPSE:
            reason = f"guard: face {int(out[2])} would collapse"
        elif status == _FOLD:
            reason = f"guard: faces {int(out[2])} and {int(out[3])} would fold through each other"
        elif done >= max_steps:
            reason = "max-steps"
        snap(done, X)
        if done % log_every == 0 or reason:
            c, pr = _crossing_pairs(X, F, tol, skip, 1) if check_intersections else (0, None)
            if c:
                k, Xg, hv_g = good
                X[:] = Xg
                hv = hv_g
                done = k
                for s in [s for s in snapshots if s > k]:
                    del snapshots[s]
                while history and history[-1][0] > k:
                    history.pop()
                reason = f"guard: faces {int(pr[0, 0])} and {int(pr[0, 1])} would intersect"
                break
            good = (done, X.copy(), hv)
            record(done, X, hv)
            if not reason and stall_window:
                IF = history[-1][1]
                if hv < best_hv:
                    best_hv, best_at, if_at_best = hv, done, IF
                elif done - best_at >= stall_window:
                    if abs(IF - if_at_best) < 1e-4:
                        reason = "stalled"
                    else:
                        best_at, if_at_best = done, IF
    IF = mean_disp(X)
    out_mesh = Mesh(X * scale + center, F.copy(), mesh.face_source.copy())
    if not history or history[-1][0] != done:
        record(done, X, hv)
    return InflateResult(
        mesh=out_mesh,
        stop_reason=reason,
        steps=done,
        inflation_rate=IF,
        hyperbolic=hv,
        history=np.array(history, dtype=np.float64).reshape(-1, 4),
        snapshots=snapshots,
        hyperbolic_start=hv_start,
        notes=tuple(notes),
    )
