"""inflate/inflate.py (`inflate`, over inflate/kernels.py): forces against a slow reference, the
Fig. 3 targets on sphere-deformed-320, guards, frame, determinism. (`polyfold inflate`:
apps/cli/test_mesh_commands.py.)"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

from polyfold.errors import PolyfoldError
from polyfold.collide.self_intersect import self_intersections
from polyfold.inflate.inflate import inflate
from polyfold.formats.meshes import load_mesh
from polyfold.mesh.repair import describe
from polyfold.mesh.mesh import Mesh

TWO_PI = 2 * math.pi


# ----------------------------------------------------------------------------------------------
# Slow reference (plain loops, straight from ALGORITHMS.md 3.1-3.4)


def _sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _norm(a):
    return math.sqrt(_dot(a, a))


def ref_geometry(X, F):
    """normals, corner angles, angle sums, fold angle per undirected edge {(a, b) sorted: rho}."""
    normals, phi = [], []
    S = [0.0] * len(X)
    for tri in F:
        n = _cross(_sub(X[tri[1]], X[tri[0]]), _sub(X[tri[2]], X[tri[0]]))
        length = _norm(n)
        normals.append([c / length for c in n])
        angles = []
        for k in range(3):
            p, q, r = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
            a, b = _sub(X[q], X[p]), _sub(X[r], X[p])
            ang = math.atan2(_norm(_cross(a, b)), _dot(a, b))
            angles.append(ang)
            S[p] += ang
        phi.append(angles)
    runs = {}
    for f, tri in enumerate(F):
        for k in range(3):
            a, b = tri[k], tri[(k + 1) % 3]
            runs.setdefault((min(a, b), max(a, b)), []).append((f, a, b))
    rho = {}
    for key, faces in runs.items():
        if len(faces) != 2:
            rho[key] = 0.0
            continue
        (f0, a, b), (f1, _, _) = faces
        u = _sub(X[b], X[a])
        u = [c / _norm(u) for c in u]
        n0, n1 = normals[f0], normals[f1]
        rho[key] = math.atan2(_dot(_cross(n0, n1), u), _dot(n0, n1))
    return normals, phi, S, rho


def ref_forces(X, P, F, pv, E, stiff, thr, vbase, rule):
    normals, phi, S, rho = ref_geometry(X, F)
    force = [[0.0, 0.0, 0.0] for _ in X]
    for f, tri in enumerate(F):  # pressure, angle weights phi / S_v
        for k in range(3):
            v = tri[k]
            for i in range(3):
                force[v][i] += pv[v] * phi[f][k] / S[v] * normals[f][i]
    for tri in F:  # stretch-only springs, each directed edge of each face
        for k in range(3):
            a, b = tri[k], tri[(k + 1) % 3]
            d = _sub(X[b], X[a])
            dl = _norm(d) - _norm(_sub(P[b], P[a]))
            if dl <= 0:
                continue
            r = rho[(min(a, b), max(a, b))]
            ke = stiff if (r > 0 or (r < 0 and abs(r) > thr)) else 1.0
            for i in range(3):
                g = E * ke * dl * d[i] / _norm(d)
                force[a][i] += g
                force[b][i] -= g
    if vbase > 0:  # rest springs
        for v in range(len(X)):
            if rule == "js":
                concave = any(r < 0 for (a, b), r in rho.items() if v in (a, b))
                lam = vbase * (1.0 if concave else stiff)
            else:
                lam = vbase * (1.0 if S[v] > TWO_PI + 1e-9 else stiff)
            for i in range(3):
                force[v][i] -= E * lam * (X[v][i] - P[v][i])
    return force, S


def ref_inflate(mesh: Mesh, steps: int, mode="constrained", p=0.5, E=2.0, step=1.2, stiff=10.0, thr_deg=15.0,
                vbase=1.0, rule="js", boost=0.0, max_boost=3.0):
    """Positions (input frame) after each of `steps` steps, by the formulas, plain loops."""
    V = mesh.vertices
    center = (V.max(0) + V.min(0)) / 2
    scale = np.linalg.norm(V - center, axis=1).max()
    P = ((V - center) / scale).tolist()
    X = [row[:] for row in P]
    F = mesh.faces.tolist()
    if mode == "uniform":
        stiff, vbase, boost = 1.0, 0.0, 0.0
    dt = math.log(step + 0.1) / 1000
    pv = [p] * len(X)
    out = [np.array(X) * scale + center]
    for _ in range(steps):
        force, _ = ref_forces(X, P, F, pv, E, stiff, math.radians(thr_deg), vbase, rule)
        X = [[X[v][i] + dt * force[v][i] for i in range(3)] for v in range(len(X))]
        _, _, S, _ = ref_geometry(X, F)
        for v in range(len(X)):
            if boost and S[v] > TWO_PI + 1e-9:
                pv[v] = min(pv[v] + p * boost, p * (1 + max_boost))
        out.append(np.array(X) * scale + center)
    return out


# ----------------------------------------------------------------------------------------------
# Independent self-intersection test: an edge of one face properly crossing the other face


def crossing_pairs(mesh: Mesh, eps: float = 1e-9) -> list[tuple[int, int]]:
    X, F = mesh.vertices, mesh.faces
    m = len(F)
    i, j = np.triu_indices(m, 1)
    shared = (F[i][:, :, None] == F[j][:, None, :]).sum(axis=(1, 2))
    keep = shared < 2  # edge neighbours cannot cross without a fold-through
    i, j = i[keep], j[keep]
    hit = np.zeros(len(i), dtype=bool)
    for a, b in ((i, j), (j, i)):
        tri = X[F[b]]  # (k, 3, 3)
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        for k in range(3):
            p = X[F[a, k]]
            q = X[F[a, (k + 1) % 3]]
            dp = np.einsum("ij,ij->i", p - tri[:, 0], n)
            dq = np.einsum("ij,ij->i", q - tri[:, 0], n)
            proper = dp * dq < 0
            t = np.where(proper, dp / np.where(proper, dp - dq, 1.0), 0.0)
            x = p + t[:, None] * (q - p)
            # barycentric coordinates of x in tri, by sub-areas along n
            nn = np.einsum("ij,ij->i", n, n)
            w0 = np.einsum("ij,ij->i", np.cross(tri[:, 1] - x, tri[:, 2] - x), n) / nn
            w1 = np.einsum("ij,ij->i", np.cross(tri[:, 2] - x, tri[:, 0] - x), n) / nn
            w2 = 1 - w0 - w1
            inside = (w0 > eps) & (w1 > eps) & (w2 > eps)
            hit |= proper & inside
    return list(zip(i[hit].tolist(), j[hit].tolist()))


# ----------------------------------------------------------------------------------------------
# Fixtures


def bumpy_sphere() -> Mesh:
    """icosphere-l1 (42 vertices) with seeded radial noise: convex, shallow and deep concave edges."""
    from conftest import models_path

    base = load_mesh(models_path() / "icosphere-l1-80.obj").mesh
    rng = np.random.default_rng(7)
    r = rng.uniform(0.8, 1.2, len(base.vertices))
    return Mesh(base.vertices * r[:, None] + np.array([3.0, -1.0, 0.5]), base.faces)


@pytest.fixture(scope="module")
def deformed(models_dir: Path) -> Mesh:
    return load_mesh(models_dir / "sphere-deformed-320.obj").mesh


@pytest.fixture(scope="module")
def runs(deformed: Mesh) -> dict:
    inflate(deformed, max_steps=60)  # warm the numba kernels
    out = {}
    for mode in ("constrained", "uniform"):
        t0 = time.perf_counter()
        res = inflate(deformed, mode=mode, snapshot_steps=(0, 100, 1000))
        out[mode] = (res, time.perf_counter() - t0)
    return out


# ----------------------------------------------------------------------------------------------
# Forces and update against the reference


@pytest.mark.parametrize("mode,rule,boost", [("constrained", "js", 0.0), ("constrained", "paper", 0.0),
                                             ("constrained", "js", 0.05), ("uniform", "js", 0.0)])
def test_matches_reference(models_dir: Path, mode: str, rule: str, boost: float) -> None:
    mesh = bumpy_sphere()
    rho = np.degrees(mesh.fold_angles)
    assert (rho > 0).any() and ((rho < 0) & (rho > -15)).any() and (rho < -15).any()
    assert mesh.hyperbolic.sum() > 0
    steps = 40
    ref = ref_inflate(mesh, steps, mode=mode, rule=rule, boost=boost)
    res = inflate(mesh, mode=mode, vertex_rule=rule, hv_boost=boost, max_steps=steps, until_hv=-1,
                  stall_window=0, snapshot_steps=range(steps + 1))
    assert res.steps == steps and res.stop_reason == "max-steps"
    for k in (1, 2, 10, steps):  # step 1: pressure only; later: springs and rest springs too
        np.testing.assert_allclose(res.snapshots[k], ref[k], rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.mesh.vertices, ref[-1], rtol=0, atol=1e-11)


def test_reference_sees_the_boost(models_dir: Path) -> None:
    mesh = bumpy_sphere()
    a = inflate(mesh, max_steps=40, until_hv=-1, hv_boost=0.0).mesh.vertices
    b = inflate(mesh, max_steps=40, until_hv=-1, hv_boost=0.05).mesh.vertices
    assert np.abs(a - b).max() > 1e-6


# ----------------------------------------------------------------------------------------------
# Fig. 3 targets


def test_constrained_reaches_hv0(runs: dict) -> None:
    con, seconds = runs["constrained"]
    uni, _ = runs["uniform"]
    assert con.stop_reason == "target-hv" and con.hyperbolic == 0 and con.hyperbolic_start == 44
    assert uni.stop_reason == "target-hv" and uni.hyperbolic == 0
    assert con.inflation_rate <= uni.inflation_rate / 3
    assert 0.05 < con.inflation_rate < 0.12  # paper: 0.0839
    assert 0.25 < uni.inflation_rate < 0.45  # paper: 0.3182
    assert seconds < 2.0
    assert runs["uniform"][1] < 2.0


def test_history_and_snapshots(runs: dict, deformed: Mesh) -> None:
    for mode in ("constrained", "uniform"):
        res, _ = runs[mode]
        h = res.history
        assert h.shape[1] == 4 and h[0, 0] == 0 and h[0, 2] == 44 and h[0, 1] == 0
        assert np.all(np.diff(h[:, 0]) > 0)
        assert np.all(h[:-1, 0] % 50 == 0) and h[-1, 0] == res.steps
        assert h[-1, 2] == res.hyperbolic and h[-1, 1] == pytest.approx(res.inflation_rate)
        assert set(res.snapshots) == {0, 100, 1000}
        np.testing.assert_allclose(res.snapshots[0], deformed.vertices, atol=1e-12)
        k = int(np.flatnonzero(h[:, 0] == 1000)[0])
        v = res.snapshots[1000]
        scale = np.linalg.norm(deformed.vertices - (deformed.vertices.max(0) + deformed.vertices.min(0)) / 2, axis=1).max()
        assert np.linalg.norm(v - deformed.vertices, axis=1).mean() / scale == pytest.approx(h[k, 1])
    uni = runs["uniform"][0].history
    assert uni[:, 2].max() > 44  # uniform HV first rises (paper: 48)
    assert uni[-1, 3] > 1.0  # uniform balloons (volume more than doubles)


def test_inflated_mesh_is_valid(runs: dict, deformed: Mesh) -> None:
    for mode in ("constrained", "uniform"):
        out = runs[mode][0].mesh
        assert np.array_equal(out.faces, deformed.faces)
        assert np.array_equal(out.face_source, deformed.face_source)
        # no face flipped against the input, none collapsed, HV recounted independently
        assert ((out.face_normals * deformed.face_normals).sum(1) > 0).all()
        assert out.angle_sums.max() <= TWO_PI + 1e-9
        from polyfold.mesh.geometry import face_areas

        assert face_areas(out.vertices, out.faces).min() > 1e-8 * face_areas(deformed.vertices, deformed.faces).mean()
        assert crossing_pairs(out) == []
        assert len(self_intersections(out)) == 0
        # input frame: centre kept, size comparable
        c0 = (deformed.vertices.max(0) + deformed.vertices.min(0)) / 2
        c1 = (out.vertices.max(0) + out.vertices.min(0)) / 2
        assert np.linalg.norm(c1 - c0) < 0.05 * deformed.bbox_diagonal
        assert 1.0 < out.bbox_diagonal / deformed.bbox_diagonal < (1.3 if mode == "constrained" else 2.0)


def test_straight_port_stalls(deformed: Mesh) -> None:
    res = inflate(deformed, hv_boost=0.0, max_steps=20000)
    assert res.stop_reason == "stalled" and res.hyperbolic > 0


def test_uniform_convex_grows(models_dir: Path) -> None:
    mesh = load_mesh(models_dir / "icosphere-l2-320.obj").mesh
    assert inflate(mesh, mode="uniform").stop_reason == "target-hv"  # HV 0 already: nothing to do
    res = inflate(mesh, mode="uniform", until_hv=-1, max_steps=600)
    assert res.stop_reason == "max-steps" and res.steps == 600
    assert np.all(res.history[:, 2] == 0)
    assert np.all(np.diff(res.history[:, 3]) > 0) and res.history[-1, 3] > 0.05
    assert res.mesh.bbox_diagonal > mesh.bbox_diagonal


def test_open_mesh(models_dir: Path) -> None:
    loaded = load_mesh(models_dir / "open" / "tube-132.obj")
    res = inflate(loaded.mesh, max_steps=300)
    assert res.hyperbolic_start == describe(loaded)["hyperbolic_vertices"]  # boundary not counted
    assert res.steps == 300 and res.stop_reason == "max-steps"
    assert np.array_equal(res.mesh.faces, loaded.mesh.faces)


# ----------------------------------------------------------------------------------------------
# Guards


@pytest.mark.parametrize("kwargs,word", [({"pressure": 1e5}, "flip"), ({"pressure": 1000.0}, "fold through")])
def test_guard_trip_is_clean(deformed: Mesh, kwargs: dict, word: str) -> None:
    res = inflate(deformed, **kwargs)
    assert res.stop_reason.startswith("guard: ") and word in res.stop_reason
    assert res.hyperbolic > 0
    assert ((res.mesh.face_normals * deformed.face_normals).sum(1) > 0).all()
    assert crossing_pairs(res.mesh) == []
    assert res.history[-1, 0] == res.steps


def test_intersection_guard(models_dir: Path) -> None:
    mesh = load_mesh(models_dir / "open" / "tube-132.obj").mesh
    res = inflate(mesh, mode="uniform", max_steps=12000)
    assert "would intersect" in res.stop_reason
    assert res.steps % 50 == 0  # the last state that passed the check
    assert crossing_pairs(res.mesh) == []
    # one more check interval would cross: the guard is not a false alarm
    worse = inflate(mesh, mode="uniform", max_steps=res.steps + 50, check_intersections=False)
    assert worse.steps == res.steps + 50
    assert len(crossing_pairs(worse.mesh)) > 0


def test_input_already_intersecting(models_dir: Path) -> None:
    mesh = load_mesh(models_dir / "fish-472.obj").mesh
    assert len(crossing_pairs(mesh)) > 0
    res = inflate(mesh, max_steps=0)
    assert res.notes and "already self-intersects" in res.notes[0]
    assert res.stop_reason == "max-steps"


def test_bad_arguments(deformed: Mesh) -> None:
    with pytest.raises(PolyfoldError):
        inflate(deformed, mode="balloon")
    with pytest.raises(PolyfoldError):
        inflate(deformed, vertex_rule="other")
    with pytest.raises(PolyfoldError):
        inflate(deformed, pressure=-1.0)
    with pytest.raises(PolyfoldError):
        inflate(deformed, step=0.5)


def test_deterministic(deformed: Mesh) -> None:
    a = inflate(deformed, max_steps=1500)
    b = inflate(deformed, max_steps=1500)
    assert np.array_equal(a.mesh.vertices, b.mesh.vertices)
    assert np.array_equal(a.history, b.history, equal_nan=True)
