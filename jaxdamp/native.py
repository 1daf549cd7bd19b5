"""A compiled CPU engine (numba) for forward runs: the step of :mod:`jaxdamp.integrate`, fast.

XLA's CPU backend runs the pure-JAX step at ~150–200 µs per system-step for a 250-grain bed
(``benchmarks/RESULTS.md``): it splits the contact law into many loop passes. This module
implements *the same* step — same contact law, same velocity-Verlet scheme with predicted
velocities, same wall geometry, same energy channels — as plain loops compiled by numba:

* grain pairs come from a half neighbour list (each pair once, Newton's third law applied)
  built inside the kernel on a cell grid from box-frame positions, holding the pairs closer
  than ``R_i + R_j + skin``, and rebuilt whenever a grain moved more than ``skin / 2``; the
  list is rebuilt at the start of every call,
  so a call's result is a pure function of its inputs (resume stays bit-identical);
* the batch of independent systems is spread over the CPU cores (``prange``).

It is called from JAX through :func:`jax.pure_callback` once per sampling interval (every
``record_every`` steps), inside the same ``lax.scan`` as the JAX engine, so records, runner,
checkpoints and sweeps are shared. It is forward-only: gradients use the JAX engine, which
stays the reference; ``tests/test_native.py`` checks that both agree.
"""

from __future__ import annotations

import math

import numpy as np

try:
    from numba import njit, prange

    AVAILABLE = True
except ImportError:  # pragma: no cover - numba is a dependency; keep the JAX engine usable
    AVAILABLE = False

SYSTEMS = {"primary": 0, "driven": 1}

#: LLVM fast-math flags of the kernels: contraction into FMAs, reassociation, reciprocals and
#: signed zeros. Not ``nnan``/``ninf``: the kernel tests for non-finite states and must keep
#: those tests (with them the compiler may assume every value finite and drop the checks).
FASTMATH = {"contract", "reassoc", "arcp", "nsz"}
MIXING = {"arithmetic": 0, "harmonic": 1, "geometric": 2}

if AVAILABLE:

    @njit(cache=True, inline="always", error_model="numpy", fastmath=FASTMATH)
    def _mix(a, b, rule):
        if rule == 0:
            return 0.5 * (a + b)
        if rule == 2:
            return math.sqrt(a * b)
        s = a + b
        return 2.0 * a * b / s if s > 0 else 0.0

    @njit(cache=True, inline="always", error_model="numpy", fastmath=FASTMATH)
    def _contact(xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, k_n, g_n, g_s, mu):
        """Contact law of :func:`jaxdamp.contact.contact_force` for one touching contact.

        Returns force on i (fx, fy, fz), tangential force (tx, ty, tz), elastic energy,
        normal loss, friction loss. Written without data-dependent branches where a
        ``min``/``max`` does (branch mispredictions dominated the dense-bed cost), and with
        the one division of the Coulomb cap only where the cap applies."""
        sq = math.sqrt(xi)
        xi_dot = -(vx * nx + vy * ny + vz * nz)
        f_el = k_n * xi * sq
        f_n = max(f_el + g_n * sq * xi_dot, 0.0)
        # contact-point relative velocity v_rel - spin × n, and its tangential part
        cx = vx - (sy * nz - sz * ny)
        cy = vy - (sz * nx - sx * nz)
        cz = vz - (sx * ny - sy * nx)
        cn = cx * nx + cy * ny + cz * nz
        tx = cx - cn * nx
        ty = cy - cn * ny
        tz = cz - cn * nz
        sp2 = tx * tx + ty * ty + tz * tz
        # |F_t| = min(γ_s sqrt(ξ) |v_s|, μ F_n): drag = |F_t| / |v_s|
        drag = g_s * sq
        cap = mu * f_n
        if drag * drag * sp2 > cap * cap:
            drag = cap / math.sqrt(sp2)
        ftx, fty, ftz = -drag * tx, -drag * ty, -drag * tz
        return (
            f_n * nx + ftx, f_n * ny + fty, f_n * nz + ftz, ftx, fty, ftz,
            0.4 * k_n * xi * xi * sq, (f_n - f_el) * xi_dot, drag * sp2,
        )

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _build_pairs(r, z_box, cutoff, pi, pj, pc, ref, R, comp, A, gn, gs, mu, mixing):
        """Half list of the pairs whose surfaces are closer than the skin, ``|r_i - r_j| < R_i +
        R_j + cutoff - 2 R_max`` (box frame; size-aware, as :mod:`jaxdamp.neighbors`), via a
        cell grid of side ``cutoff``, with the pairs' constants ``pc[k] = (R_i + R_j, k_n, γ_n,
        γ_s, μ)`` (they depend on the pair only); stores the reference positions. Returns the
        number of pairs, or minus the number needed when the arrays are too small."""
        n = r.shape[0]
        extra = cutoff - 2.0 * R.max()
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for i in range(n):
            ref[i, 0] = r[i, 0]
            ref[i, 1] = r[i, 1]
            ref[i, 2] = r[i, 2] - z_box
            for k in range(3):
                if not math.isfinite(ref[i, k]):
                    return 0  # non-finite state: no pairs; the runner stops on it
                lo[k] = min(lo[k], ref[i, k])
                hi[k] = max(hi[k], ref[i, k])
        for k in range(3):
            if not (hi[k] - lo[k] < 1e3):  # exploded (or non-finite) state: no pairs; the
                return 0                    # runner stops on the non-finite state it leads to
        side = cutoff
        dims = np.empty(3, np.int64)
        while True:  # cap the grid at ~4 cells per grain (tall, sparse boxes)
            for k in range(3):
                dims[k] = int((hi[k] - lo[k]) / side) + 1
            if float(dims[0]) * float(dims[1]) * float(dims[2]) <= 4 * n + 64:
                break
            side *= 1.5
        ncell = dims[0] * dims[1] * dims[2]
        cell = np.empty(n, np.int64)
        count = np.zeros(ncell + 1, np.int64)
        for i in range(n):
            cx = int((ref[i, 0] - lo[0]) / side)
            cy = int((ref[i, 1] - lo[1]) / side)
            cz = int((ref[i, 2] - lo[2]) / side)
            c = (cx * dims[1] + cy) * dims[2] + cz
            cell[i] = c
            count[c + 1] += 1
        for c in range(ncell):
            count[c + 1] += count[c]
        fill = count[:-1].copy()
        order = np.empty(n, np.int64)
        for i in range(n):
            order[fill[cell[i]]] = i
            fill[cell[i]] += 1
        k = 0
        cap = pi.shape[0]
        for i in range(n):
            c = cell[i]
            cz = c % dims[2]
            cy = (c // dims[2]) % dims[1]
            cx = c // (dims[1] * dims[2])
            for ax in range(max(cx - 1, 0), min(cx + 2, dims[0])):
                for ay in range(max(cy - 1, 0), min(cy + 2, dims[1])):
                    for az in range(max(cz - 1, 0), min(cz + 2, dims[2])):
                        cc = (ax * dims[1] + ay) * dims[2] + az
                        for s in range(count[cc], count[cc + 1]):
                            j = order[s]
                            if j <= i:
                                continue
                            dx = ref[i, 0] - ref[j, 0]
                            dy = ref[i, 1] - ref[j, 1]
                            dz = ref[i, 2] - ref[j, 2]
                            lim = R[i] + R[j] + extra
                            if dx * dx + dy * dy + dz * dz < lim * lim:
                                if k < cap:
                                    pi[k] = i
                                    pj[k] = j
                                    rs = R[i] + R[j]
                                    k_n = (4.0 / 3.0) * math.sqrt(R[i] * R[j] / rs) / (comp[i] + comp[j])
                                    pc[k, 0] = rs
                                    pc[k, 1] = k_n
                                    pc[k, 2] = _mix(gn[i], gn[j], mixing) + 1.5 * _mix(A[i], A[j], mixing) * k_n
                                    pc[k, 3] = _mix(gs[i], gs[j], mixing)
                                    pc[k, 4] = _mix(mu[i], mu[j], mixing)
                                k += 1
        return k if k <= cap else -k

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _pairs(r, z_box, cutoff, pi, pj, pc, ref, R, comp, A, gn, gs, mu, mixing):
        """:func:`_build_pairs`, growing the pair arrays when they are too small."""
        k = _build_pairs(r, z_box, cutoff, pi, pj, pc, ref, R, comp, A, gn, gs, mu, mixing)
        if k < 0:
            pi = np.empty(2 * (-k), np.int64)
            pj = np.empty(2 * (-k), np.int64)
            pc = np.empty((2 * (-k), 5))
            k = _build_pairs(r, z_box, cutoff, pi, pj, pc, ref, R, comp, A, gn, gs, mu, mixing)
        return k, pi, pj, pc

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _moved_too_far(r, z_box, ref, half_skin2):
        for i in range(r.shape[0]):
            dx = r[i, 0] - ref[i, 0]
            dy = r[i, 1] - ref[i, 1]
            dz = r[i, 2] - z_box - ref[i, 2]
            if dx * dx + dy * dy + dz * dz > half_skin2:
                return True
        return False

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _wall_constants(R, comp, A, gn, gs, mu, wc, wA, wgn, wgs, wmu, mixing):
        """Per grain, the constants of its contact with any wall: ``(N, 4)`` array of
        ``(k_n, γ_n, γ_s, μ)`` (they depend on the grain and the wall material only)."""
        n = R.shape[0]
        wk = np.empty((n, 4))
        for i in range(n):
            k_n = (4.0 / 3.0) * math.sqrt(R[i]) / (comp[i] + wc)
            wk[i, 0] = k_n
            wk[i, 1] = _mix(gn[i], wgn, mixing) + 1.5 * _mix(A[i], wA, mixing) * k_n
            wk[i, 2] = _mix(gs[i], wgs, mixing)
            wk[i, 3] = _mix(mu[i], wmu, mixing)
        return wk

    @njit(cache=True, inline="always", error_model="numpy", fastmath=FASTMATH)
    def _wall(i, xi, nx, ny, nz, v, w, R, zd_box, wk, F, T, out):
        """Contact of grain ``i`` with a wall of inward normal ``n`` at overlap ``xi > 0``:
        adds to ``F``, ``T`` and the energy channels; returns the force's z component."""
        fx, fy, fz, tx, ty, tz, e, ln, lf = _contact(
            xi, nx, ny, nz, v[i, 0], v[i, 1], v[i, 2] - zd_box,
            R[i] * w[i, 0], R[i] * w[i, 1], R[i] * w[i, 2],
            wk[i, 0], wk[i, 1], wk[i, 2], wk[i, 3])
        F[i, 0] += fx
        F[i, 1] += fy
        F[i, 2] += fz
        T[i, 0] -= R[i] * (ny * tz - nz * ty)
        T[i, 1] -= R[i] * (nz * tx - nx * tz)
        T[i, 2] -= R[i] * (nx * ty - ny * tx)
        out[4] += e
        out[7] += ln
        out[8] += lf
        return fz

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _forces(r, v, w, z_box, zd_box, R, m, wk, Lx, Ly, Lz, grav, drag,
                pi, pj, pc, npairs, F, T, out):
        """Forces (F, T filled in place) and scalars ``out`` = [box_z, floor_lid_z, n_floor,
        n_lid, e_elastic, pp_normal, pp_friction, pw_normal, pw_friction]. ``wk``: the
        grains' wall constants (:func:`_wall_constants`)."""
        n = r.shape[0]
        for i in range(n):
            F[i, 0] = -m[i] * drag * v[i, 0]
            F[i, 1] = -m[i] * drag * v[i, 1]
            F[i, 2] = m[i] * (-grav - drag * v[i, 2])
            T[i, 0] = 0.0
            T[i, 1] = 0.0
            T[i, 2] = 0.0
        for k in range(9):
            out[k] = 0.0
        # energy sums in registers: F, T and out may alias as far as the compiler knows, so
        # accumulating into out[...] would force a store and reload per contact
        e_sum = 0.0
        ln_sum = 0.0
        lf_sum = 0.0
        for p in range(npairs):
            i = pi[p]
            j = pj[p]
            dx = r[i, 0] - r[j, 0]
            dy = r[i, 1] - r[j, 1]
            dz = r[i, 2] - r[j, 2]
            d2 = dx * dx + dy * dy + dz * dz
            rs = pc[p, 0]
            if d2 >= rs * rs:
                continue
            d = math.sqrt(d2)
            xi = rs - d
            inv = 1.0 / d
            nx, ny, nz = dx * inv, dy * inv, dz * inv
            sx = R[i] * w[i, 0] + R[j] * w[j, 0]
            sy = R[i] * w[i, 1] + R[j] * w[j, 1]
            sz = R[i] * w[i, 2] + R[j] * w[j, 2]
            fx, fy, fz, tx, ty, tz, e, ln, lf = _contact(
                xi, nx, ny, nz, v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2],
                sx, sy, sz, pc[p, 1], pc[p, 2], pc[p, 3], pc[p, 4])
            F[i, 0] += fx
            F[i, 1] += fy
            F[i, 2] += fz
            F[j, 0] -= fx
            F[j, 1] -= fy
            F[j, 2] -= fz
            # torque -R_k (n × F_t) on both grains of the pair
            cx = ny * tz - nz * ty
            cy = nz * tx - nx * tz
            cz = nx * ty - ny * tx
            T[i, 0] -= R[i] * cx
            T[i, 1] -= R[i] * cy
            T[i, 2] -= R[i] * cz
            T[j, 0] -= R[j] * cx
            T[j, 1] -= R[j] * cy
            T[j, 2] -= R[j] * cz
            e_sum += e
            ln_sum += ln
            lf_sum += lf
        out[4] = e_sum
        out[5] = ln_sum
        out[6] = lf_sum
        # walls: floor, lid, x = 0, x = Lx, y = 0, y = Ly (inward normals), unrolled: most
        # grains touch none, so the common path is six compares
        for i in range(n):
            Ri = R[i]
            floor = r[i, 2] - z_box
            if floor < Ri:
                fz = _wall(i, Ri - floor, 0.0, 0.0, 1.0, v, w, R, zd_box, wk, F, T, out)
                out[0] -= fz
                out[1] -= fz
                out[2] += 1.0
            if Lz - floor < Ri:
                fz = _wall(i, Ri - (Lz - floor), 0.0, 0.0, -1.0, v, w, R, zd_box, wk, F, T, out)
                out[0] -= fz
                out[1] -= fz
                out[3] += 1.0
            if r[i, 0] < Ri:
                out[0] -= _wall(i, Ri - r[i, 0], 1.0, 0.0, 0.0, v, w, R, zd_box, wk, F, T, out)
            if Lx - r[i, 0] < Ri:
                out[0] -= _wall(i, Ri - (Lx - r[i, 0]), -1.0, 0.0, 0.0, v, w, R, zd_box, wk, F, T, out)
            if r[i, 1] < Ri:
                out[0] -= _wall(i, Ri - r[i, 1], 0.0, 1.0, 0.0, v, w, R, zd_box, wk, F, T, out)
            if Ly - r[i, 1] < Ri:
                out[0] -= _wall(i, Ri - (Ly - r[i, 1]), 0.0, -1.0, 0.0, v, w, R, zd_box, wk, F, T, out)

    @njit(cache=True, error_model="numpy", fastmath=FASTMATH)
    def _advance_one(b, n_steps, system, mixing, cutoff, skin,
                     r, v, w, q, a, al, zs, work, power, diag,
                     R, m, I, comp, A, gn, gs, mu, sc, impulse):
        """Advance system ``b`` by ``n_steps``. ``zs`` = [z, zd, zdd, t, z_max, z_min, step];
        ``diag`` = [e_elastic, f_floor_lid, f_box, n_floor, n_lid]; ``sc`` the scalar params."""
        (wc, wA, wgn, wgs, wmu, Lx, Ly, Lz, grav, M, K, C, U, amp, om, z_off, dt, drag,
         t_win) = (sc[b, 0], sc[b, 1], sc[b, 2], sc[b, 3], sc[b, 4], sc[b, 5], sc[b, 6],
                   sc[b, 7], sc[b, 8], sc[b, 9], sc[b, 10], sc[b, 11], sc[b, 12], sc[b, 13],
                   sc[b, 14], sc[b, 15], sc[b, 16], sc[b, 17], sc[b, 18])
        n = r.shape[1]
        rb, vb, wb, qb, ab, alb = r[b], v[b], w[b], q[b], a[b], al[b]
        Rb, mb, Ib = R[b], m[b], I[b]
        pi = np.empty(16 * n + 16, np.int64)
        pj = np.empty(16 * n + 16, np.int64)
        pc = np.empty((16 * n + 16, 5))
        cb, Ab, gnb, gsb, mub = comp[b], A[b], gn[b], gs[b], mu[b]
        wk = _wall_constants(Rb, cb, Ab, gnb, gsb, mub, wc, wA, wgn, wgs, wmu, mixing)
        ref = np.empty((n, 3))
        z, zd, zdd, t, zmax, zmin, step = zs[b, 0], zs[b, 1], zs[b, 2], zs[b, 3], zs[b, 4], zs[b, 5], zs[b, 6]
        npairs = 0
        if n > 1:
            npairs, pi, pj, pc = _pairs(rb, z, cutoff, pi, pj, pc, ref, Rb, cb, Ab, gnb, gsb, mub, mixing)
        half_skin2 = 0.25 * skin * skin
        r1 = np.empty((n, 3))
        vp = np.empty((n, 3))
        wp = np.empty((n, 3))
        F = np.empty((n, 3))
        T = np.empty((n, 3))
        out = np.empty(9)
        pw = np.empty(7)
        imp0 = 0.0
        imp1 = 0.0
        for _ in range(n_steps):
            if n > 1 and _moved_too_far(rb, z, ref, half_skin2):
                npairs, pi, pj, pc = _pairs(rb, z, cutoff, pi, pj, pc, ref, Rb, cb, Ab, gnb, gsb, mub, mixing)
            t1 = t + dt
            for i in range(n):
                for k in range(3):
                    r1[i, k] = rb[i, k] + dt * vb[i, k] + 0.5 * dt * dt * ab[i, k]
                    vp[i, k] = vb[i, k] + dt * ab[i, k]
                    wp[i, k] = wb[i, k] + dt * alb[i, k]
            ph = om * t1
            if system == 0:
                z1 = z + dt * zd + 0.5 * dt * dt * zdd
                zdp = zd + dt * zdd
            else:
                z1 = z_off + amp * math.cos(ph)
                zdp = -amp * om * math.sin(ph)
                zdd1 = -amp * om * om * math.cos(ph)
            _forces(r1, vp, wp, z1, zdp, Rb, mb, wk, Lx, Ly, Lz, grav, drag,
                    pi, pj, pc, npairs, F, T, out)
            health = out[0] + out[4] + out[5] + out[6] + out[7] + out[8] + z1 + zdp
            for i in range(n):
                health += F[i, 0] + F[i, 1] + F[i, 2] + T[i, 0] + T[i, 1] + T[i, 2]
            if not math.isfinite(health):
                # the state blew up: mark it non-finite and stop; the runner reports it
                for i in range(n):
                    for k in range(3):
                        rb[i, k] = np.nan
                        vb[i, k] = np.nan
                zd = np.nan
                break
            if system == 0:
                u1 = U * math.cos(ph)
                ud1 = -U * om * math.sin(ph)
                zdd1 = (-C * (zdp - ud1) - K * (z1 - u1) + out[0]) / M
                zd1 = zd + 0.5 * dt * (zdd + zdd1)
                pw[0] = -ud1 * (K * (z1 - u1) + C * (zdp - ud1))
                pw[1] = C * (zdp - ud1) ** 2
            else:
                zd1 = zdp
                pw[0] = -out[0] * zdp
                pw[1] = 0.0
            pw[2], pw[3], pw[4], pw[5] = out[5], out[6], out[7], out[8]
            pdrag = 0.0
            for i in range(n):
                pdrag += mb[i] * (vp[i, 0] ** 2 + vp[i, 1] ** 2 + vp[i, 2] ** 2)
            pw[6] = drag * pdrag
            for i in range(n):
                # rotation by the mid-step angular velocity ω + α dt/2 (exact axis-angle)
                ox = wb[i, 0] + 0.5 * dt * alb[i, 0]
                oy = wb[i, 1] + 0.5 * dt * alb[i, 1]
                oz = wb[i, 2] + 0.5 * dt * alb[i, 2]
                h2 = 0.25 * dt * dt * (ox * ox + oy * oy + oz * oz)  # (half angle)^2
                if h2 < 1e-4:
                    # cos h and sin(h)/|ω| by their series: exact in float64 for h < 0.01
                    # (next terms < 3e-21), and free of sin/cos/sqrt calls per grain and step
                    cw = 1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 / 720.0))
                    s = 0.5 * dt * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 / 5040.0)))
                else:
                    speed = math.sqrt(ox * ox + oy * oy + oz * oz)
                    cw = math.cos(0.5 * speed * dt)
                    s = math.sin(0.5 * speed * dt) / speed
                dw, dx, dy, dz = cw, s * ox, s * oy, s * oz
                qw, qx, qy, qz = qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3]
                nw = dw * qw - (dx * qx + dy * qy + dz * qz)
                nx = dw * qx + qw * dx + (dy * qz - dz * qy)
                ny = dw * qy + qw * dy + (dz * qx - dx * qz)
                nz = dw * qz + qw * dz + (dx * qy - dy * qx)
                nrm = math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
                qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3] = nw / nrm, nx / nrm, ny / nrm, nz / nrm
                for k in range(3):
                    a1 = F[i, k] / mb[i]
                    al1 = T[i, k] / Ib[i]
                    vb[i, k] = vb[i, k] + 0.5 * dt * (ab[i, k] + a1)
                    wb[i, k] = wb[i, k] + 0.5 * dt * (alb[i, k] + al1)
                    ab[i, k] = a1
                    alb[i, k] = al1
                    rb[i, k] = r1[i, k]
            for c in range(7):
                work[b, c] = work[b, c] + 0.5 * dt * (power[b, c] + pw[c])
                power[b, c] = pw[c]
            z, zd, zdd, t = z1, zd1, zdd1, t1
            if t1 >= t_win:
                zmax = max(zmax, z1)
                zmin = min(zmin, z1)
            step += 1
            imp0 += out[1]
            imp1 += out[0]
        zs[b, 0], zs[b, 1], zs[b, 2], zs[b, 3], zs[b, 4], zs[b, 5], zs[b, 6] = z, zd, zdd, t, zmax, zmin, step
        diag[b, 0], diag[b, 1], diag[b, 2], diag[b, 3], diag[b, 4] = out[4], out[1], out[0], out[2], out[3]
        impulse[b, 0] = imp0 / n_steps
        impulse[b, 1] = imp1 / n_steps

    @njit(cache=True, parallel=True, error_model="numpy", fastmath=FASTMATH)
    def _advance(n_steps, system, mixing, cutoff, skin, r, v, w, q, a, al, zs, work, power,
                 diag, R, m, I, comp, A, gn, gs, mu, sc, impulse):
        for b in prange(r.shape[0]):
            _advance_one(b, n_steps, system, mixing, cutoff, skin, r, v, w, q, a, al, zs, work,
                         power, diag, R, m, I, comp, A, gn, gs, mu, sc, impulse)


#: Scalar parameters passed to the kernel, in order.
SCALARS = ("wall_compliance", "wall_A", "wall_gamma_n", "wall_gamma_s", "wall_mu", "Lx", "Ly",
           "Lz", "gravity", "M", "K", "C", "U", "amplitude", "omega", "z_offset", "dt", "drag",
           "t_window")


# -- packing of pytrees (one float64 array per call across the JAX/Python boundary) ---------


def layout(tree):
    """``[(field, shape without batch axis, dtype)]`` of a batched pytree dataclass."""
    import dataclasses

    return [(f.name, tuple(getattr(tree, f.name).shape[1:]), getattr(tree, f.name).dtype)
            for f in dataclasses.fields(tree)]


def pack(tree):
    """Batched pytree dataclass -> ``(B, total)`` float64 JAX array (integers exactly < 2^53)."""
    import dataclasses

    import jax.numpy as jnp

    leaves = [getattr(tree, f.name) for f in dataclasses.fields(tree)]
    b = leaves[0].shape[0]
    return jnp.concatenate([jnp.reshape(x, (b, -1)).astype(jnp.float64) for x in leaves], axis=1)


def unpack_like(packed, tree):
    """Inverse of :func:`pack` in JAX, with ``tree`` giving shapes and dtypes."""
    import dataclasses

    import jax.numpy as jnp

    out, k = {}, 0
    for f in dataclasses.fields(tree):
        x = getattr(tree, f.name)
        size = int(np.prod(x.shape[1:], dtype=np.int64))
        out[f.name] = jnp.reshape(packed[:, k:k + size], x.shape).astype(x.dtype)
        k += size
    return type(tree)(**out)


def unpack(packed, lay):
    """Packed numpy array -> dict of numpy arrays (float64 views/copies per :func:`layout`)."""
    out, k = {}, 0
    b = packed.shape[0]
    for name, shape, dtype in lay:
        size = int(np.prod(shape, dtype=np.int64))
        out[name] = packed[:, k:k + size].reshape((b,) + shape)
        k += size
    return out


def pack_numpy(d, lay):
    b = next(iter(d.values())).shape[0]
    return np.concatenate([np.asarray(d[name], np.float64).reshape(b, -1) for name, _, _ in lay], axis=1)


def advance_numpy(model, state: dict, params: dict, n_steps: int):
    """Advance a batch given as numpy dicts (fields of ``State`` / ``Params``, leading batch
    axis). Returns ``(new_state_dict, mean_forces (B, 2))``; inputs are not modified."""
    f64 = lambda x: np.ascontiguousarray(x, dtype=np.float64)  # noqa: E731
    r, v, w, q = (f64(state[k]).copy() for k in ("r", "v", "w", "q"))
    a, al = f64(state["a"]).copy(), f64(state["alpha"]).copy()
    zs = np.stack([f64(state[k]) for k in ("z", "zd", "zdd", "t", "z_max", "z_min")]
                  + [np.asarray(state["step"], np.float64)], axis=1)
    work = f64(state["work"]).copy()
    power = f64(state["power"]).copy()
    B = r.shape[0]
    diag = np.zeros((B, 5))
    impulse = np.zeros((B, 2))
    sc = np.stack([np.broadcast_to(f64(params[k]), (B,)) for k in SCALARS], axis=1)
    _advance(int(n_steps), SYSTEMS[model.system], MIXING[model.mixing], model.cutoff, model.skin,
             r, v, w, q, a, al, zs, work, power, diag,
             f64(params["radius"]), f64(params["mass"]), f64(params["inertia"]),
             f64(params["compliance"]), f64(params["A"]), f64(params["gamma_n"]),
             f64(params["gamma_s"]), f64(params["mu"]), sc, impulse)
    new = dict(state)
    new.update(r=r, v=v, w=w, q=q, a=a, alpha=al, work=work, power=power,
               z=zs[:, 0], zd=zs[:, 1], zdd=zs[:, 2], t=zs[:, 3], z_max=zs[:, 4], z_min=zs[:, 5],
               step=zs[:, 6],
               e_elastic=diag[:, 0], f_floor_lid=diag[:, 1], f_box=diag[:, 2],
               n_floor=diag[:, 3], n_lid=diag[:, 4])
    return new, impulse
