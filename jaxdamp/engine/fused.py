"""The fused device step (``numerics.engine = "fused"``): the native kernel's step on a CUDA
device, one thread block per system, every step of a chunk in one launch.

The XLA step on a device runs ~45 kernels per step, each a pass over the batch in memory, and
launches them again every step (issue 32: 0.82–1.06 µs per system-step on an H200, 82 µs per
step for one system). This module advances a whole chunk in **one** kernel launch written with
``numba-cuda``:

* a **block per system**, a **thread per grain** (grains ``tid, tid + T, …`` when the bed has
  more grains than the block has threads, ``T ≤`` :data:`THREADS`); the block loops over the
  chunk's steps itself, so nothing returns to the host between steps;
* each grain keeps a **full** neighbour list (its own row, ``j`` ascending) and computes the
  forces on itself only: no atomics, no second pass. The pair's force is odd in the separation
  and the relative velocity (:func:`jaxdamp.engine.native.pair_contact`), so grain ``j`` gets
  exactly ``−F``: the same forces as the CPU's half list with Newton's third law. The lists
  hold the pairs closer than ``R_i + R_j + skin`` (box frame, size-aware, as the CPU kernel)
  and are rebuilt, by every grain against all others, at a chunk's first step and whenever a
  grain moved more than ``skin / 2``; the skin is widened for fast grains as on the CPU;
* per step: thread 0 predicts the mount, every thread predicts its grains, the lists are
  rebuilt if needed, every thread adds its grains' walls (:func:`~jaxdamp.engine.native.
  grain_walls`) and pairs and applies the velocity-Verlet corrector and the rotation to
  them; the block sums the energy channels and the force on the box (a tree in shared memory,
  the same order every run, so a resumed run repeats itself bit for bit), and thread 0 moves
  the mount and writes the samples (:func:`jaxdamp.physics.energy.record_row`).

**One definition of the physics.** Nothing of the physics is retyped here: the contact laws,
the walls of every container, the mounts, the body force, the rotation and the sample are the
numba scalar forms the CPU kernel inlines (:mod:`jaxdamp.engine.native`'s ``grain_walls``,
``pair_constants``, ``pair_contact``, ``wall_constants`` and the forms they call); numba-cuda
compiles the same functions for the device. State, parameters and samples are the CPU
kernel's packed rows (:func:`jaxdamp.engine.native.pack`, :func:`~jaxdamp.engine.native.
kernel_args`), so the runner, checkpoints and sweeps are shared with the other engines.

It is forward-only and float64, like the native kernel; ``"jax"`` stays the differentiable
reference. ``tests/test_fused.py`` checks it against the JAX and native engines on the CPU in
numba-cuda's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``: the kernel's Python runs thread by
thread, so on small beds only), and that it compiles to PTX for the device
(:func:`compile_ptx`) without one. ``benchmarks/device_check.py`` compares it with the CPU on
a device and times it.

Example (on a machine with a CUDA device and ``pip install "jaxdamp[cuda]"``)::

    jaxdamp sweep --preset sanchez2012-optimal --set numerics.engine=fused
"""

from __future__ import annotations

import functools
import math
import os
from collections import namedtuple

import numpy as np

from jaxdamp.engine import native
from jaxdamp.physics.containers import section_scalar, side_curvature_scalar
from jaxdamp.physics.energy import record_row
from jaxdamp.physics.integrate import rotate_scalar, rotate_series_scalar
from jaxdamp.physics.model import CH, N_CHANNELS
from jaxdamp.physics.mounts import DRIVEN, energy_scalar, predict_scalar, respond_scalar

try:  # a module global: numba-cuda's simulator swaps it for its own in the kernel's globals
    from numba import cuda
except ImportError:  # the cuda extra is not installed: available() says so
    cuda = None

#: Most threads in a block (one per grain; more grains are strided over them). A power of two:
#: the block's sums are a tree.
THREADS = 256
#: Smallest block on a device (a warp); the simulator runs one thread per grain.
WARP = 32
#: Neighbours a grain's list holds at first; a chunk whose lists overflow is run again from
#: its inputs with room for the most any grain needed (a pure function of its inputs).
NEIGHBOURS = 16
#: The values the block sums per step (a tree in shared memory).
_SUMS = ("e_walls", "pw_n", "pw_f", "box_z", "floor_lid", "n_floor", "n_lid", "drag",
         "pp_e", "pp_n", "pp_f", "health")
N_SUMS = len(_SUMS)
_DRIVEN = DRIVEN.id
_IN, _PRIM, _PPN, _PPF, _PWN, _PWF, _DRAG = (
    CH[k] for k in ("input", "primary_damping", "pp_normal", "pp_friction", "pw_normal",
                    "pw_friction", "drag"))
#: Per-system scratch in device memory: per-grain rows ``(3, n)`` / ``(n, 4)`` and the
#: structure's vectors.
_SCRATCH = ("r1", "vp", "rw", "ref", "wk", "wks", "y1", "ydp", "xs", "xds", "acc", "tmp")
Scratch = namedtuple("Scratch", _SCRATCH)


def simulated() -> bool:
    """Whether numba-cuda runs kernels in its CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, read
    when ``numba.cuda`` is first imported): the CPU tests' mode."""
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def available() -> tuple[bool, str]:
    """``(usable, why not)``: numba-cuda installed and a CUDA device visible to it (or the
    simulator on)."""
    if cuda is None:
        return False, ("numba-cuda is not installed: pip install \"jaxdamp[cuda]\" "
                       "(README, On a GPU)")
    if simulated():
        return True, ""
    try:
        if cuda.is_available():
            return True, ""
    except Exception as err:  # noqa: BLE001 - a driver that fails to load says why here
        return False, f"numba-cuda finds no usable CUDA device ({err})"
    return False, "numba-cuda finds no CUDA device (the fused engine runs on NVIDIA GPUs)"


def scratch_layout(n: int, ndof: int) -> tuple[Scratch, int]:
    """Offsets of :data:`_SCRATCH` in a system's scratch row and the row's length."""
    sizes = {"r1": 3 * n, "vp": 3 * n, "rw": 3 * n, "ref": 3 * n, "wk": 4 * n, "wks": 4 * n,
             "y1": ndof - 1, "ydp": ndof - 1, "xs": ndof, "xds": ndof, "acc": ndof,
             "tmp": ndof}
    off, k = {}, 0
    for name in _SCRATCH:
        off[name] = k
        k += sizes[name]
    return Scratch(**off), max(k, 1)


def threads_per_block(n: int) -> int:
    """One thread per grain, rounded up to a power of two, at most :data:`THREADS` (at least a
    warp on a device)."""
    t = 1
    while t < min(n, THREADS):
        t *= 2
    return t if simulated() else max(t, WARP)


@functools.lru_cache(maxsize=1)
def _kernel():
    """The kernel, compiled by numba-cuda on first use (for the device, or run in the
    simulator)."""
    from numba import float64, njit

    grain_walls = native.grain_walls
    pair_constants = native.pair_constants
    pair_contact = native.pair_contact
    wall_constants = native.wall_constants
    rebuild_steps = native.REBUILD_STEPS

    if simulated():
        def plain(a):  # the simulator wraps arrays; the scalar forms take numpy arrays
            return getattr(a, "_ary", a)
    else:
        @njit(inline="always")
        def plain(a):
            return a

    @cuda.jit(device=True, inline="always")
    def block_sum(red, tid, nt, k_max, use_max):
        """The tree over the block's threads of ``red[k, :]`` for ``k < k_max`` (sums, or
        maxima when ``use_max``) into ``red[k, 0]``; ends synchronised."""
        cuda.syncthreads()
        s = nt // 2
        while s > 0:
            if tid < s:
                for k in range(k_max):
                    if use_max:
                        red[k, tid] = max(red[k, tid], red[k, tid + s])
                    else:
                        red[k, tid] = red[k, tid] + red[k, tid + s]
            cuda.syncthreads()
            s //= 2

    @cuda.jit
    def advance(n_records, record_every, dims, skin0, st, pm, so, po, sid, bounds, rec, scr, sc,
                nbr, cnt, status):
        st, pm, sid, bounds, rec = plain(st), plain(pm), plain(sid), plain(bounds), plain(rec)
        scr, nbr, cnt, status = plain(scr), plain(nbr), plain(cnt), plain(status)
        b = cuda.blockIdx.x
        tid = cuda.threadIdx.x
        nt = cuda.blockDim.x
        n = sid.shape[0]
        cap = nbr.shape[1]
        row = st[b]
        prow = pm[b]
        s = scr[b]
        nb = nbr[b]
        nc = cnt[b]
        mount, law, shape = dims.mount, dims.law, dims.shape
        prescribed = mount == _DRIVEN
        S, F, n_lines, ndof, n_section = (dims.n_species, dims.n_cols, dims.n_lines, dims.ndof,
                                          dims.n_section)
        rb = row[so.r:so.r + 3 * n].reshape((n, 3))
        vb = row[so.v:so.v + 3 * n].reshape((n, 3))
        wb = row[so.w:so.w + 3 * n].reshape((n, 3))
        qb = row[so.q:so.q + 4 * n].reshape((n, 4))
        ab = row[so.a:so.a + 3 * n].reshape((n, 3))
        alb = row[so.alpha:so.alpha + 3 * n].reshape((n, 3))
        work = row[so.work:so.work + N_CHANNELS]
        power = row[so.power:so.power + N_CHANNELS]
        Rb = prow[po.radius:po.radius + n]
        mb = prow[po.mass:po.mass + n]
        Ib = prow[po.inertia:po.inertia + n]
        tab = prow[po.pair_table:po.pair_table + S * S * F].reshape((S, S, F))
        wtab = prow[po.wall_table:po.wall_table + S * F].reshape((S, F))
        Lz, grav = prow[po.Lz], prow[po.gravity]
        section = prow[po.section:po.section + n_section]
        dt = prow[po.dt]
        drag, t_win = prow[po.drag], prow[po.t_window]
        ex, ey, ez = prow[po.ex], prow[po.ey], prow[po.ez]
        ny = ndof - 1
        yv = row[so.y:so.y + ny]
        ydv = row[so.yd:so.yd + ny]
        yddv = row[so.ydd:so.ydd + ny]
        r1 = s[sc.r1:sc.r1 + 3 * n].reshape((3, n))
        vp = s[sc.vp:sc.vp + 3 * n].reshape((3, n))
        rw = s[sc.rw:sc.rw + 3 * n].reshape((3, n))
        ref = s[sc.ref:sc.ref + 3 * n].reshape((3, n))
        wk = s[sc.wk:sc.wk + 4 * n].reshape((n, 4))
        wks = s[sc.wks:sc.wks + 4 * n].reshape((n, 4))
        y1 = s[sc.y1:sc.y1 + ny]
        ydp = s[sc.ydp:sc.ydp + ny]
        xs = s[sc.xs:sc.xs + ndof]
        xds = s[sc.xds:sc.xds + ndof]
        acc = s[sc.acc:sc.acc + ndof]
        tmp = s[sc.tmp:sc.tmp + ndof]
        red = cuda.shared.array((N_SUMS, THREADS), float64)
        sh = cuda.shared.array(4, float64)  # t1, z1, z'1 of the step; 1 once it blew up
        pw = cuda.local.array(N_CHANNELS, float64)
        parts = cuda.local.array(N_SUMS, float64)
        ft = cuda.local.array(6, float64)  # a grain's force and torque

        # once per launch: the walls' constants of each grain, the skin from the fastest grain
        kappa = side_curvature_scalar(shape, section)
        sec = section_scalar(section)
        z, zd, zdd, t = row[so.z], row[so.zd], row[so.zdd], row[so.t]
        v2 = 0.0
        r_max = 0.0
        for i in range(tid, n, nt):
            wk[i, 0], wk[i, 1], wk[i, 2], wk[i, 3] = wall_constants(law, wtab[sid[i]], Rb[i],
                                                                    mb[i], 0.0)
            wks[i, 0], wks[i, 1], wks[i, 2], wks[i, 3] = wall_constants(law, wtab[sid[i]],
                                                                        Rb[i], mb[i], kappa)
            v2 = max(v2, (vb[i, 0] - ex * zd) ** 2 + (vb[i, 1] - ey * zd) ** 2
                     + (vb[i, 2] - ez * zd) ** 2)
            r_max = max(r_max, Rb[i])
            for c in range(3):
                ref[c, i] = 0.0  # set at the first step's build
        red[0, tid] = v2
        red[1, tid] = r_max
        block_sum(red, tid, nt, 2, True)
        v2 = red[0, 0]
        r_max = red[1, 0]
        skin = max(skin0, min(2.0 * rebuild_steps * math.sqrt(v2) * dt, 2.0 * r_max))
        extra = (2.0 * r_max + skin) - 2.0 * r_max
        half_skin2 = 0.25 * skin * skin
        hdt2 = 0.5 * dt * dt
        e_start = row[so.e_start]
        zmax, zmin, step = row[so.z_max], row[so.z_min], row[so.step]
        e_el = 0.0
        floor_lid = 0.0
        box_z = 0.0
        n_floor = 0.0
        n_lid = 0.0
        first = True
        if tid == 0:
            sh[3] = 0.0  # set once the state blows up (read by all after a barrier)
        cuda.syncthreads()
        for k_rec in range(n_records):
            imp0 = 0.0
            imp1 = 0.0
            for _ in range(record_every):
                if tid == 0:  # the mount's prediction
                    t1 = t + dt
                    z1, zdp = predict_scalar(mount, t1, dt, z, zd, zdd, prow, po)
                    for j in range(ny):
                        y1[j] = yv[j] + dt * ydv[j] + hdt2 * yddv[j]
                        ydp[j] = ydv[j] + dt * yddv[j]
                    sh[0], sh[1], sh[2] = t1, z1, zdp
                cuda.syncthreads()
                z1, zdp = sh[1], sh[2]
                # the predictor of this thread's grains, and whether one moved skin/2
                far = 0
                for i in range(tid, n, nt):
                    for c in range(3):
                        r1[c, i] = rb[i, c] + dt * vb[i, c] + hdt2 * ab[i, c]
                        vp[c, i] = vb[i, c] + dt * ab[i, c]
                        rw[c, i] = Rb[i] * (wb[i, c] + dt * alb[i, c])
                    ddx = r1[0, i] - ex * z1 - ref[0, i]
                    ddy = r1[1, i] - ey * z1 - ref[1, i]
                    ddz = r1[2, i] - ez * z1 - ref[2, i]
                    if ddx * ddx + ddy * ddy + ddz * ddz > half_skin2:
                        far = 1
                if cuda.syncthreads_or(far) or first:
                    # the lists anew, from the predicted positions in the box frame
                    first = False
                    for i in range(tid, n, nt):
                        ref[0, i] = r1[0, i] - ex * z1
                        ref[1, i] = r1[1, i] - ey * z1
                        ref[2, i] = r1[2, i] - ez * z1
                    cuda.syncthreads()
                    for i in range(tid, n, nt):
                        m = 0
                        for j in range(n):
                            dx = ref[0, i] - ref[0, j]
                            dy = ref[1, i] - ref[1, j]
                            dz = ref[2, i] - ref[2, j]
                            lim = Rb[i] + Rb[j] + extra
                            if j != i and dx * dx + dy * dy + dz * dz < lim * lim:
                                if m < cap:
                                    nb[m, i] = j
                                m += 1
                        nc[i] = m
                        if m > cap:
                            cuda.atomic.max(status, b, m)
                    cuda.syncthreads()
                # this thread's grains: walls, pairs, corrector, rotation
                for k in range(N_SUMS):
                    parts[k] = 0.0
                for i in range(tid, n, nt):
                    ux, uy, uz = vp[0, i], vp[1, i], vp[2, i]
                    f, sums, _ = grain_walls(
                        shape, law, r1[0, i], r1[1, i], r1[2, i], ux, uy, uz, rw[0, i], rw[1, i],
                        rw[2, i], Rb[i], mb[i], wk, wks, i, sec, ex, ey, ez, z1, zdp, Lz, grav,
                        drag, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
                    for k in range(7):
                        parts[k] += sums[k]
                    parts[7] += mb[i] * (ux * ux + uy * uy + uz * uz)
                    fx, fy, fz, tx, ty, tz = f
                    for k in range(min(nc[i], cap)):
                        j = nb[k, i]
                        dx = r1[0, i] - r1[0, j]
                        dy = r1[1, i] - r1[1, j]
                        dz = r1[2, i] - r1[2, j]
                        d2 = dx * dx + dy * dy + dz * dz
                        rs = Rb[i] + Rb[j]
                        if d2 < rs * rs:
                            _, kk, gg, gs, mu = pair_constants(law, tab, sid[i], sid[j], Rb[i],
                                                               Rb[j], mb[i], mb[j])
                            gx, gy, gz, cx, cy, cz, e, ln, lf = pair_contact(
                                law, dx, dy, dz, d2, rs, ux - vp[0, j], uy - vp[1, j],
                                uz - vp[2, j], rw[0, i] + rw[0, j], rw[1, i] + rw[1, j],
                                rw[2, i] + rw[2, j], kk, gg, gs, mu)
                            fx += gx
                            fy += gy
                            fz += gz
                            tx -= Rb[i] * cx
                            ty -= Rb[i] * cy
                            tz -= Rb[i] * cz
                            parts[8] += e
                            parts[9] += ln
                            parts[10] += lf
                    # the velocity-Verlet corrector and the rotation by the mid-step spin
                    im = 1.0 / mb[i]
                    iI = 1.0 / Ib[i]
                    ox = wb[i, 0] + 0.5 * dt * alb[i, 0]
                    oy = wb[i, 1] + 0.5 * dt * alb[i, 1]
                    oz = wb[i, 2] + 0.5 * dt * alb[i, 2]
                    ft[0], ft[1], ft[2], ft[3], ft[4], ft[5] = fx, fy, fz, tx, ty, tz
                    h = 0.0
                    for c in range(3):
                        a1 = ft[c] * im
                        al1 = ft[3 + c] * iI
                        h += a1 + al1
                        vb[i, c] = vb[i, c] + 0.5 * dt * (ab[i, c] + a1)
                        ab[i, c] = a1
                        wb[i, c] = wb[i, c] + 0.5 * dt * (alb[i, c] + al1)
                        alb[i, c] = al1
                        rb[i, c] = r1[c, i]
                    parts[11] += h
                    qw, qx, qy, qz, ok = rotate_series_scalar(qb[i, 0], qb[i, 1], qb[i, 2],
                                                              qb[i, 3], ox, oy, oz, dt)
                    if not ok:
                        qw, qx, qy, qz = rotate_scalar(qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3],
                                                       ox, oy, oz, dt)
                    qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3] = qw, qx, qy, qz
                for k in range(N_SUMS):
                    red[k, tid] = parts[k]
                block_sum(red, tid, nt, N_SUMS, False)
                if tid == 0:  # the mount's response, the energy channels, the finite check
                    t1 = sh[0]
                    e_el = red[0, 0] + 0.5 * red[8, 0]
                    pw_n, pw_f, box_z, floor_lid = red[1, 0], red[2, 0], red[3, 0], red[4, 0]
                    n_floor, n_lid = red[5, 0], red[6, 0]
                    pp_n, pp_f = 0.5 * red[9, 0], 0.5 * red[10, 0]
                    zdd1, pw[_IN], pw[_PRIM] = respond_scalar(mount, t1, z1, zdp, y1, ydp,
                                                              box_z, prow, po, n_lines, xs,
                                                              xds, acc, tmp)
                    zd1 = zdp if prescribed else zd + 0.5 * dt * (zdd + zdd1)
                    pw[_PPN], pw[_PPF], pw[_PWN], pw[_PWF] = pp_n, pp_f, pw_n, pw_f
                    pw[_DRAG] = drag * red[7, 0]
                    health = box_z + e_el + pp_n + pp_f + pw_n + pw_f + z1 + zdp + zdd1
                    health += red[11, 0]
                    if not math.isfinite(health):
                        zd = math.nan
                        sh[3] = 1.0
                    else:
                        for c in range(N_CHANNELS):
                            work[c] = work[c] + 0.5 * dt * (power[c] + pw[c])
                            power[c] = pw[c]
                        for j in range(ny):
                            ydv[j] = ydv[j] + 0.5 * dt * (yddv[j] + acc[j + 1])
                            yddv[j] = acc[j + 1]
                            yv[j] = y1[j]
                        z, zd, zdd, t = z1, zd1, zdd1, t1
                        if t1 >= t_win:
                            zmax = max(zmax, z1)
                            zmin = min(zmin, z1)
                        step += 1
                        imp0 += floor_lid
                        imp1 += box_z
                cuda.syncthreads()
                if sh[3] != 0.0:
                    # the state blew up: mark it non-finite and stop; the runner reports it
                    for i in range(tid, n, nt):
                        for c in range(3):
                            rb[i, c] = math.nan
                            vb[i, c] = math.nan
                    cuda.syncthreads()
                    break
            if tid == 0:
                e_prim = energy_scalar(mount, t, z, zd, yv, ydv, prow, po, n_lines, xs, xds)
                record_row(rec[b, k_rec], t, z, zd, yv, e_prim, rb, vb, wb, mb, Ib, Rb, grav, Lz,
                           ez, e_el, e_start, imp0 / record_every, imp1 / record_every, n_floor,
                           n_lid, work, bounds)
            cuda.syncthreads()
        if tid == 0:
            row[so.z], row[so.zd], row[so.zdd], row[so.t] = z, zd, zdd, t
            row[so.z_max], row[so.z_min], row[so.step] = zmax, zmin, step
            row[so.e_elastic], row[so.f_floor_lid], row[so.f_box] = e_el, floor_lid, box_z
            row[so.n_floor], row[so.n_lid] = n_floor, n_lid

    return advance


def advance_packed(model, state_packed, params_packed, state_layout, param_layout,
                   n_records: int, record_every: int, device: int | None = None):
    """:func:`jaxdamp.engine.native.advance_packed` on the CUDA device: the same packed rows
    in and out, the same samples. The rows travel to the device and back once per call (a
    chunk of thousands of steps: the copies are milliseconds beside seconds of compute).
    ``device``: the CUDA ordinal to run on (default: numba's current device). In the
    simulator (the CPU tests) the threads hand over the interpreter every 0.1 ms instead of
    every 5 ms, or its barriers cost milliseconds each."""
    import contextlib
    import sys

    if simulated():
        old = sys.getswitchinterval()
        sys.setswitchinterval(1e-4)
        try:
            return _advance_packed(model, state_packed, params_packed, state_layout,
                                   param_layout, n_records, record_every)
        finally:
            sys.setswitchinterval(old)
    with cuda.gpus[device] if device is not None else contextlib.nullcontext():
        return _advance_packed(model, state_packed, params_packed, state_layout, param_layout,
                               n_records, record_every)


def _advance_packed(model, state_packed, params_packed, state_layout, param_layout, n_records,
                    record_every):
    ok, why = available()
    if not ok:
        raise RuntimeError(f"numerics.engine = 'fused': {why}")
    st = np.array(state_packed, dtype=np.float64, order="C", copy=True)
    pm = np.ascontiguousarray(params_packed, dtype=np.float64)
    dims, so, po, sid, bounds, width = native.kernel_args(model, state_layout, param_layout)
    n, batch = model.n, st.shape[0]
    sc, size = scratch_layout(n, dims.ndof)
    kernel = _kernel()
    cap = NEIGHBOURS
    while True:
        d_st = cuda.to_device(st)
        d_rec = cuda.device_array((batch, int(n_records), width))
        status = cuda.to_device(np.zeros(batch, np.int64))
        kernel[batch, threads_per_block(n)](
            int(n_records), int(record_every), dims, float(model.skin), d_st, cuda.to_device(pm),
            so, po, cuda.to_device(sid), cuda.to_device(bounds), d_rec,
            cuda.device_array((batch, size)), sc, cuda.device_array((batch, cap, n), np.int32),
            cuda.device_array((batch, n), np.int32), status)
        need = int(status.copy_to_host().max())
        if need <= cap:
            return d_st.copy_to_host(), d_rec.copy_to_host()
        cap = need + need // 4  # room for the most any grain needed, and some


def compile_ptx(model, states, params, cc: tuple[int, int] = (9, 0)) -> str:
    """The kernel compiled to PTX for compute capability ``cc`` (default 9.0: H100, H200) for
    ``model``'s packed rows (``states``, ``params``: a batch of them, for their layouts),
    without a device: the CPU check that the device gets code that compiles (the simulator
    runs the kernel's Python, not its lowering). Needs numba-cuda's compiler (libNVVM, in
    the ``cuda`` extra), not a GPU."""
    import numba

    if simulated():
        raise RuntimeError("compile_ptx needs numba-cuda's compiler: unset NUMBA_ENABLE_CUDASIM")
    dims, so, po, _, _, _ = native.kernel_args(model, native.layout(states),
                                               native.layout(params))
    sc, _ = scratch_layout(model.n, dims.ndof)
    f2 = numba.float64[:, ::1]
    sig = (numba.int64, numba.int64, numba.typeof(dims), numba.float64, f2, f2,
           numba.typeof(so), numba.typeof(po), numba.int64[::1], numba.int64[::1],
           numba.float64[:, :, ::1], f2, numba.typeof(sc), numba.int32[:, :, ::1],
           numba.int32[:, ::1], numba.int64[::1])
    ptx, _ = cuda.compile_ptx(_kernel().py_func, sig, cc=cc)
    return ptx
