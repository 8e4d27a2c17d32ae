"""numba kernels of inflation (`inflate.py`; the model is in its docstring, ALGORITHMS.md 3.1-3.4).

    surface_geometry  normals, doubled areas, corner angles, angle sums, fold angles; the HV count
    run_steps         up to n steps of the explicit update with the per-step guards (flip,
                      collapse, fold-through) and the stall rule; returns a status code
"""

from __future__ import annotations

import math

from ..arrays import copy_flat
from ..jit import njit

from ..mesh.geometry import HYPERBOLIC_EPS

TWO_PI = 2.0 * math.pi
HV_EPS = HYPERBOLIC_EPS  # hyperbolic: S_v > 2 pi + HV_EPS
STALL_DISP = 1e-3  # stop when the summed step displacement falls below this

# status codes of run_steps
RUNNING, AT_TARGET, STALLED, FLIPPED, COLLAPSED, FOLDED_THROUGH = 0, 1, 2, 3, 4, 5


@njit(cache=True)
def surface_geometry(X, F, edges, efaces, counted, normals, area2, phi, S, rho):
    """Unit normals, doubled areas, corner angles, angle sums and fold angles of X; returns HV."""
    m = F.shape[0]
    n = X.shape[0]
    for v in range(n):
        S[v] = 0.0
    for f in range(m):
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
            cn = math.sqrt(cx * cx + cy * cy + cz * cz)
            if k == 0:  # the face's normal is the cross product at its first corner; |c| = 2 area
                area2[f] = cn
                if cn > 0.0:
                    normals[f, 0] = cx / cn
                    normals[f, 1] = cy / cn
                    normals[f, 2] = cz / cn
                else:
                    normals[f, 0] = 0.0
                    normals[f, 1] = 0.0
                    normals[f, 2] = 0.0
            ang = math.atan2(cn, ax * bx + ay * by + az * bz)
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
def run_steps(X, P, F, L0, fedge, edges, efaces, counted, pv, boost, pcap, p, E, stiff, thr, vbase, vrule, dt,
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
    status = RUNNING
    while True:
        out[1] = hv
        if hv <= until_hv:
            status = AT_TARGET
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
                status = STALLED
                break
        hv_n = surface_geometry(Xn, F, edges, efaces, counted, normals_n, area2_n, phi_n, S_n, rho_n)
        for f in range(m):
            if area2_n[f] < min_area2:
                status = COLLAPSED
                out[2] = f
                break
            if (normals[f, 0] * normals_n[f, 0] + normals[f, 1] * normals_n[f, 1]
                    + normals[f, 2] * normals_n[f, 2]) < 0.0:
                status = FLIPPED
                out[2] = f
                break
        if status != RUNNING:
            break
        for e in range(edges.shape[0]):
            a = rho[e]
            b = rho_n[e]
            if (a > 0.5 * math.pi and b < -0.5 * math.pi) or (a < -0.5 * math.pi and b > 0.5 * math.pi):
                status = FOLDED_THROUGH
                out[2] = efaces[e, 0]
                out[3] = efaces[e, 1]
                break
        if status != RUNNING:
            break
        copy_flat(X, Xn, Xn.size)
        copy_flat(normals, normals_n, normals_n.size)
        copy_flat(area2, area2_n, area2_n.size)
        copy_flat(phi, phi_n, phi_n.size)
        copy_flat(S, S_n, S_n.size)
        copy_flat(rho, rho_n, rho_n.size)
        hv = hv_n
        done += 1
        if boost > 0.0:
            for v in range(n):
                if counted[v] and S[v] > TWO_PI + HV_EPS:
                    pv[v] = min(pv[v] + p * boost, pcap)
    out[0] = done
    return status

