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
* with tangential springs (``tangential_law = "mindlin"``) each grain keeps its own copy of
  a pair's spring beside its list (exactly the opposite of its partner's copy: the contact is
  odd), steps it with the native kernel's ``pair_spring`` and, at a rebuild, carries it from
  the old list to the new one through the state's rows (partners in increasing order, as the
  other engines keep them), by pair identity; a spring the rows have no room for is counted
  lost and the runner redoes the chunk with larger lists, as on the CPU;
* per step: thread 0 predicts the mount, every thread predicts its grains, the lists are
  rebuilt if needed, every thread adds its grains' walls (:func:`~jaxdamp.engine.native.
  grain walls`) and pairs and applies the velocity-Verlet corrector and the rotation to
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

    jaxdamp frf --preset sanchez2012-optimal --replicates 8 --set numerics.engine=fused
"""

from __future__ import annotations

import functools
import math
import os
import sys
import threading
from collections import namedtuple

import numpy as np

from jaxdamp.engine import native
from jaxdamp.physics.contact import G_STAR
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
#: Registers a thread may use (``None``: as many as the compiler wants, up to 255). The
#: kernel for the thesis bed takes all 255 and spills ~0.5 kB per thread, so one block of 256
#: threads fits an SM; capped at 128, two fit and it spills ~1.5 kB
#: (:func:`resources`, sm_90). Which is faster is for a device to measure
#: (``benchmarks/device_check.py --fused-registers``).
MAX_REGISTERS: int | None = None
#: Neighbours a grain's list holds at first; a chunk whose lists overflow is run again from
#: its inputs with room for the most any grain needed (a pure function of its inputs).
NEIGHBOURS = 16
#: The values the block sums per step (a tree in shared memory); with tangential springs
#: four more (:data:`_SPRING_SUMS`).
_SUMS = ("e_walls", "pw_n", "pw_f", "box_z", "floor_lid", "n_floor", "n_lid", "n_wall",
         "l_floor", "l_lid", "drag", "pp_e", "pp_n", "pp_f", "health")
N_SUMS = len(_SUMS)
#: The springs' sums of a step (:func:`jaxdamp.engine.native.pair_spring`'s ``tot``): the
#: turned energy, the pairs' and the walls' slip losses, the springs' energy. Each pair is
#: visited from both its grains (full lists): its part enters at half weight.
_SPRING_SUMS = ("turned", "pp_slip", "pw_slip", "e_spring")
#: Where the sums of the pair pass start (the grain pass fills the ones before).
_PAIR_SUMS = _SUMS.index("pp_e")
_DRIVEN = DRIVEN.id
_IN, _PRIM, _PPN, _PPF, _PWN, _PWF, _DRAG, _PW_FLOOR, _PW_LID, _PW_SIDE = (
    CH[k] for k in ("input", "primary_damping", "pp_normal", "pp_friction", "pw_normal",
                    "pw_friction", "drag", "pw_floor", "pw_lid", "pw_side"))
_PP_SLIP, _PW_SLIP, _STIFF = (CH[k] for k in ("pp_slip", "pw_slip", "spring_stiffness"))
#: Per-system scratch in device memory: per-grain rows ``(n, 3)`` / ``(n, 4)`` (the CPU
#: kernel's layout: its grain pass runs on them), the structure's vectors, and for several
#: cells each grain's loss power and force on its container (``grain`` ``(n, 2)``), each cell's
#: (``pwc``, ``bzc`` ``(cells,)``), the cells' containers' positions and velocities
#: (``frames`` ``(cells, 2)``) and the grains' forces on the degrees of freedom (``fdof``);
#: with tangential springs, the half-step velocities ``vh`` and spins ``sh = R ω`` ``(n, 3)``
#: with which they grow, per grain ``wg = (G*, R*`` of a plane, ``R*`` of the sides``)`` and
#: each cell's walls' mean velocity over the step ``zds`` ``(cells,)`` (sized 0 without).
_SCRATCH = ("r1", "vp", "rw", "ref", "F", "T", "wk", "wks", "y1", "ydp", "xs", "xds", "acc",
            "tmp", "grain", "pwc", "bzc", "frames", "fdof", "vh", "sh", "wg", "zds")
Scratch = namedtuple("Scratch", _SCRATCH)


def simulated() -> bool:
    """Whether numba-cuda runs kernels in its CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, read
    when ``numba.cuda`` is first imported): the CPU tests' mode."""
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def _simulator_shared_arrays_locked() -> None:
    """Make the CUDA simulator hand every thread of a block the same shared array.

    numba-cuda's simulator (``FakeCUDAShared.array``, numba-cuda 0.30.4) keys a block's shared
    arrays by the line that asks for them, and looks the key up and stores a new array
    without a lock: two threads that reach the line together get two arrays, and the block's
    sums then read memory no thread wrote. A loaded machine makes it likely (a CI run of the
    long suite went non-finite at the first sample of a chunk so). This replaces the method,
    once per process, with the same lookup under a lock; the key is the caller's frame
    (file, line), as before."""
    from numba.cuda.simulator import kernelapi

    cls = kernelapi.FakeCUDAShared
    if getattr(cls.array, "locked", False):
        return
    unlocked = cls.array
    lock = threading.Lock()

    def array(self, shape, dtype, alignment=None):
        if shape == 0 or alignment is not None:  # dynamic shared memory: one buffer, no key
            return unlocked(self, shape, dtype, alignment)
        frame = sys._getframe(1)
        key = (frame.f_code.co_filename, frame.f_lineno)
        with lock:
            res = self._allocations.get(key)
            if res is None:
                if isinstance(dtype, kernelapi.types.Type):
                    dtype = kernelapi.numpy_support.as_dtype(dtype)
                res = self._allocations[key] = np.empty(shape, dtype)
        return res

    array.locked = True
    cls.array = array


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


def scratch_layout(n: int, ndof: int, cells: int, springs: bool = False
                   ) -> tuple[Scratch, int]:
    """Offsets of :data:`_SCRATCH` in a system's scratch row and the row's length."""
    ns = n if springs else 0
    sizes = {"r1": 3 * n, "vp": 3 * n, "rw": 3 * n, "ref": 3 * n, "F": 3 * n, "T": 3 * n,
             "wk": 4 * n, "wks": 4 * n,
             "y1": ndof - 1, "ydp": ndof - 1, "xs": ndof, "xds": ndof, "acc": ndof,
             "tmp": ndof, "grain": 2 * n, "pwc": cells, "bzc": cells, "frames": 2 * cells,
             "fdof": ndof, "vh": 3 * ns, "sh": 3 * ns, "wg": 3 * ns,
             "zds": cells if springs else 0}
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


def compile_note() -> str | None:
    """A one-line note before this process first launches the fused kernel (numba-cuda
    compiles it for the device at its first launch, once per process and kind of bed: mount,
    contact law, container; there is no on-disk cache), else ``None``."""
    if _kernel.cache_info().currsize:
        return None
    return ("compiling the fused CUDA kernel for this bed (once per process) — the first "
            "progress bar starts after it")


@functools.lru_cache(maxsize=16)
def _kernel(mount: int, law: int, shape: int, max_registers: int | None = None,
            springs: bool = False):
    """The kernel for the mount, contact law and container numbered ``mount``, ``law``,
    ``shape`` (``Dims``), compiled by numba-cuda on first use (for the device, or run in the
    simulator). The three are constants of the compiled code, so the paths of the others
    fold away: with every path in one kernel the thread spilled twice as much (1080 B of
    stores instead of 508 at 255 registers, sm_90: :func:`resources`,
    ``benchmarks/RESULTS.md``). ``springs``: the tangential springs with history
    (``tangential_law = "mindlin"``, :func:`_springs_to_list`), a constant too: the viscous
    kernel has none of their code."""
    from numba import float64, njit

    grain_walls = native.grain_walls
    pair_constants = native.pair_constants
    pair_contact = native.pair_contact
    pair_spring = native.pair_spring
    held_pair = native.held_pair
    cell_steps = native._cell_steps
    increment_of = native._INCREMENT_OF
    g_star = G_STAR
    n_sums = N_SUMS + (len(_SPRING_SUMS) if springs else 0)
    wall_constants = native.wall_constants
    cell_sums = native.cell_sums
    cell_frames = native.cell_frames
    dof_loads = native.dof_loads
    rebuild_steps = native.REBUILD_STEPS

    if simulated():
        _simulator_shared_arrays_locked()

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

    @njit(inline="always")  # (a CPU form: numba-cuda compiles it into the kernel)
    def springs_to_rows(i, n, nb, nc, cap, hsb, spq, spp):
        """Grain ``i``'s springs from its list (``hsb[k, i]``, the spring of its ``k``-th
        neighbour ``nb[k, i]``) into its state rows (``spq[i]``, ``spp[i]``: partners in
        increasing order, padded with ``n``; the JAX engine's and the native kernel's form,
        :mod:`jaxdamp.engine.history`); returns how many had no room (lost)."""
        KS = spq.shape[1]
        c = 0
        lost = 0
        for k in range(min(nc[i], cap)):
            if hsb[k, i, 0] != 0.0 or hsb[k, i, 1] != 0.0 or hsb[k, i, 2] != 0.0:
                if c < KS:
                    spq[i, c] = nb[k, i]
                    spp[i, c, 0], spp[i, c, 1], spp[i, c, 2] = (hsb[k, i, 0], hsb[k, i, 1],
                                                                hsb[k, i, 2])
                    c += 1
                else:
                    lost += 1
        for m in range(c, KS):
            spq[i, m] = n
            spp[i, m, 0], spp[i, m, 1], spp[i, m, 2] = 0.0, 0.0, 0.0
        return lost

    @njit(inline="always")  # (a CPU form: numba-cuda compiles it into the kernel)
    def springs_to_list(i, n, nb, nc, cap, hsb, spq, spp):
        """Grain ``i``'s springs from its state rows onto its list, by pair identity (both in
        increasing partner order: one merge); returns how many springs found no listed pair
        (lost: a touching pair is always listed, so none unless a list overflowed)."""
        KS = spq.shape[1]
        c = 0
        lost = 0
        for k in range(min(nc[i], cap)):
            j = nb[k, i]
            while c < KS and spq[i, c] < j:
                if spp[i, c, 0] != 0.0 or spp[i, c, 1] != 0.0 or spp[i, c, 2] != 0.0:
                    lost += 1
                c += 1
            if c < KS and spq[i, c] == j:
                hsb[k, i, 0], hsb[k, i, 1], hsb[k, i, 2] = spp[i, c, 0], spp[i, c, 1], spp[i, c, 2]
                c += 1
            else:
                hsb[k, i, 0], hsb[k, i, 1], hsb[k, i, 2] = 0.0, 0.0, 0.0
        while c < KS and spq[i, c] < n:
            if spp[i, c, 0] != 0.0 or spp[i, c, 1] != 0.0 or spp[i, c, 2] != 0.0:
                lost += 1
            c += 1
        return lost

    @cuda.jit(**({} if simulated() or max_registers is None else
                  {"max_registers": max_registers}))
    def advance(n_records, record_every, dims, skin0, st, pm, so, po, sid, bounds, cg, cdof, rec,
                scr, sc, nbr, cnt, status, hs, lostd):
        st, pm, sid, bounds, rec = plain(st), plain(pm), plain(sid), plain(bounds), plain(rec)
        cg, cdof = plain(cg), plain(cdof)
        scr, nbr, cnt, status = plain(scr), plain(nbr), plain(cnt), plain(status)
        hs, lostd = plain(hs), plain(lostd)
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
        K = dims.cells
        cells = K > 1
        work_cell = row[so.work_cell:so.work_cell + K]
        power_cell = row[so.power_cell:so.power_cell + K]
        Rb = prow[po.radius:po.radius + n]
        mb = prow[po.mass:po.mass + n]
        Ib = prow[po.inertia:po.inertia + n]
        tab = prow[po.pair_table:po.pair_table + S * S * F].reshape((S, S, F))
        wtab = prow[po.wall_table:po.wall_table + S * F].reshape((S, F))
        Lz, grav = prow[po.Lz], prow[po.gravity]
        section = prow[po.section:po.section + n_section]
        og = prow[po.origin:po.origin + 2 * n].reshape((n, 2))  # the grains' cells' corners
        dt = prow[po.dt]
        drag, t_win = prow[po.drag], prow[po.t_window]
        ex, ey, ez = prow[po.ex], prow[po.ey], prow[po.ez]
        ny = ndof - 1
        yv = row[so.y:so.y + ny]
        ydv = row[so.yd:so.yd + ny]
        yddv = row[so.ydd:so.ydd + ny]
        r1 = s[sc.r1:sc.r1 + 3 * n].reshape((n, 3))
        vp = s[sc.vp:sc.vp + 3 * n].reshape((n, 3))
        rw = s[sc.rw:sc.rw + 3 * n].reshape((n, 3))
        ref = s[sc.ref:sc.ref + 3 * n].reshape((n, 3))
        Fs = s[sc.F:sc.F + 3 * n].reshape((n, 3))
        Ts = s[sc.T:sc.T + 3 * n].reshape((n, 3))
        wk = s[sc.wk:sc.wk + 4 * n].reshape((n, 4))
        wks = s[sc.wks:sc.wks + 4 * n].reshape((n, 4))
        y1 = s[sc.y1:sc.y1 + ny]
        ydp = s[sc.ydp:sc.ydp + ny]
        xs = s[sc.xs:sc.xs + ndof]
        xds = s[sc.xds:sc.xds + ndof]
        acc = s[sc.acc:sc.acc + ndof]
        tmp = s[sc.tmp:sc.tmp + ndof]
        grain = s[sc.grain:sc.grain + 2 * n].reshape((n, 2))
        pwc = s[sc.pwc:sc.pwc + K]
        bzc = s[sc.bzc:sc.bzc + K]
        frames = s[sc.frames:sc.frames + 2 * K].reshape((K, 2))
        fdof = s[sc.fdof:sc.fdof + ndof]
        # the tangential springs (sized 0 without): the pairs' in the state's rows between
        # launches and on the lists (hsb, a spring per slot) within one, the walls' in the rows
        KS, NW = dims.slots, dims.walls
        spq = row[so.spring_partner:so.spring_partner + n * KS].reshape((n, KS))
        spp = row[so.spring_pair:so.spring_pair + 3 * n * KS].reshape((n, KS, 3))
        hw = row[so.spring_wall:so.spring_wall + 3 * n * NW].reshape((n, NW, 3))
        ns = n if springs else 0
        vhs = s[sc.vh:sc.vh + 3 * ns].reshape((ns, 3))
        shs = s[sc.sh:sc.sh + 3 * ns].reshape((ns, 3))
        wg = s[sc.wg:sc.wg + 3 * ns].reshape((ns, 3))
        zds = s[sc.zds:sc.zds + (K if springs else 0)]
        hsb = hs[b]
        wtot = cuda.local.array(4, float64)  # a step's spring sums: the walls', the pairs'
        ptot = cuda.local.array(4, float64)
        lost = 0
        e_spring = row[so.e_spring] if springs else 0.0
        spread = False  # cells on several degrees of freedom (else all on the box's)
        for c in range(K):
            spread = spread | (cdof[c] != 0)
        red = cuda.shared.array((n_sums, THREADS), float64)
        sh = cuda.shared.array(4, float64)  # t1, z1, z'1 of the step; 1 once it blew up
        pw = cuda.local.array(N_CHANNELS, float64)
        for c in range(N_CHANNELS):  # the channels the step never sets (springs) stay 0
            pw[c] = 0.0
        inc = cuda.local.array(N_CHANNELS, float64)
        parts = cuda.local.array(n_sums, float64)
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
                ref[i, c] = 0.0  # set at the first step's build
            if springs:
                wg[i, 0] = wtab[sid[i], g_star]
                wg[i, 1] = Rb[i]
                wg[i, 2] = Rb[i] / (1.0 - Rb[i] * kappa)
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
        n_side = 0.0
        first = True
        if tid == 0:
            sh[3] = 0.0  # set once the state blows up (read by all after a barrier)
            for j in range(ndof):  # scratch comes uninitialised; the box's entry is set per step
                fdof[j] = 0.0
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
                    if cells:
                        cell_frames(cdof, z1, zdp, y1, ydp, frames)
                    if springs:
                        cell_steps(cdof, z, z1, yv, y1, dt, zds)
                    sh[0], sh[1], sh[2] = t1, z1, zdp
                cuda.syncthreads()
                z1, zdp = sh[1], sh[2]
                # the predictor of this thread's grains, then their body force and walls
                # (the CPU kernel's grain pass over this thread's grains) and whether one
                # moved skin/2 since the lists were built
                for i in range(tid, n, nt):
                    for c in range(3):
                        r1[i, c] = rb[i, c] + dt * vb[i, c] + hdt2 * ab[i, c]
                        vp[i, c] = vb[i, c] + dt * ab[i, c]
                        rw[i, c] = Rb[i] * (wb[i, c] + dt * alb[i, c])
                    if springs:  # the half-step velocities and R ω, with which they grow
                        for c in range(3):
                            vhs[i, c] = vb[i, c] + 0.5 * dt * ab[i, c]
                            shs[i, c] = Rb[i] * (wb[i, c] + 0.5 * dt * alb[i, c])
                for c in range(4):
                    wtot[c] = 0.0
                    ptot[c] = 0.0
                if springs:
                    (parts[0], parts[1], parts[2], parts[3], parts[4], parts[5], parts[6],
                     parts[7], parts[8], parts[9], parts[10], far) = grain_walls(
                        shape, law, tid, n, nt, r1, vp, rw, Rb, mb, ref, wk, wks, sec, og, cells,
                        grain, cg, frames, Fs, Ts, ex, ey, ez, z1, zdp, Lz, (grav, drag),
                        half_skin2, (hw, vhs, shs, wg, wtot, zds, cg, dt))
                else:
                    (parts[0], parts[1], parts[2], parts[3], parts[4], parts[5], parts[6],
                     parts[7], parts[8], parts[9], parts[10], far) = grain_walls(
                        shape, law, tid, n, nt, r1, vp, rw, Rb, mb, ref, wk, wks, sec, og, cells,
                        grain, cg, frames, Fs, Ts, ex, ey, ez, z1, zdp, Lz, (grav, drag),
                        half_skin2, None)
                if cuda.syncthreads_or(1 if far else 0) or first:
                    # the lists anew, from the predicted positions in the box frame (the
                    # springs off the old lists first, back onto the new ones after)
                    if springs and not first:
                        for i in range(tid, n, nt):
                            lost += springs_to_rows(i, n, nb, nc, cap, hsb, spq, spp)
                    first = False
                    for i in range(tid, n, nt):
                        ref[i, 0] = r1[i, 0] - ex * z1
                        ref[i, 1] = r1[i, 1] - ey * z1
                        ref[i, 2] = r1[i, 2] - ez * z1
                    cuda.syncthreads()
                    for i in range(tid, n, nt):
                        m = 0
                        for j in range(n):
                            dx = ref[i, 0] - ref[j, 0]
                            dy = ref[i, 1] - ref[j, 1]
                            dz = ref[i, 2] - ref[j, 2]
                            lim = Rb[i] + Rb[j] + extra
                            if j != i and dx * dx + dy * dy + dz * dz < lim * lim:
                                if m < cap:
                                    nb[m, i] = j
                                m += 1
                        nc[i] = m
                        if m > cap:
                            cuda.atomic.max(status, b, m)
                        if springs:
                            lost += springs_to_list(i, n, nb, nc, cap, hsb, spq, spp)
                    cuda.syncthreads()
                # this thread's grains: pairs, corrector, rotation
                for k in range(_PAIR_SUMS, N_SUMS):
                    parts[k] = 0.0
                for i in range(tid, n, nt):
                    ux, uy, uz = vp[i, 0], vp[i, 1], vp[i, 2]
                    fx, fy, fz = Fs[i, 0], Fs[i, 1], Fs[i, 2]
                    tx, ty, tz = Ts[i, 0], Ts[i, 1], Ts[i, 2]
                    for k in range(min(nc[i], cap)):
                        j = nb[k, i]
                        dx = r1[i, 0] - r1[j, 0]
                        dy = r1[i, 1] - r1[j, 1]
                        dz = r1[i, 2] - r1[j, 2]
                        d2 = dx * dx + dy * dy + dz * dz
                        rs = Rb[i] + Rb[j]
                        if springs:  # (its spring also where it held one: released)
                            hsi = hsb[:, i, :]
                            touch = d2 < rs * rs or held_pair((hsi,), k)
                        else:
                            touch = d2 < rs * rs
                        if touch:
                            _, kk, gg, gs, mu = pair_constants(law, tab, sid[i], sid[j], Rb[i],
                                                               Rb[j], mb[i], mb[j])
                            if springs:
                                gx, gy, gz, cx, cy, cz, e, ln, lf = pair_spring(
                                    law, dx, dy, dz, d2, rs, ux - vp[j, 0], uy - vp[j, 1],
                                    uz - vp[j, 2], rw[i, 0] + rw[j, 0], rw[i, 1] + rw[j, 1],
                                    rw[i, 2] + rw[j, 2], kk, gg, mu, tab[sid[i], sid[j], g_star],
                                    Rb[i] * Rb[j] / rs, (hsi, vhs, shs, ptot, dt), k, i, j)
                            else:
                                gx, gy, gz, cx, cy, cz, e, ln, lf = pair_contact(
                                    law, dx, dy, dz, d2, rs, ux - vp[j, 0], uy - vp[j, 1],
                                    uz - vp[j, 2], rw[i, 0] + rw[j, 0], rw[i, 1] + rw[j, 1],
                                    rw[i, 2] + rw[j, 2], kk, gg, gs, mu)
                            fx += gx
                            fy += gy
                            fz += gz
                            tx -= Rb[i] * cx
                            ty -= Rb[i] * cy
                            tz -= Rb[i] * cz
                            parts[11] += e
                            parts[12] += ln
                            parts[13] += lf
                            if cells:  # each grain of the pair lists it: half each
                                grain[i, 0] += 0.5 * (ln + lf)
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
                        rb[i, c] = r1[i, c]
                    parts[14] += h
                    qw, qx, qy, qz, ok = rotate_series_scalar(qb[i, 0], qb[i, 1], qb[i, 2],
                                                              qb[i, 3], ox, oy, oz, dt)
                    if not ok:
                        qw, qx, qy, qz = rotate_scalar(qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3],
                                                       ox, oy, oz, dt)
                    qb[i, 0], qb[i, 1], qb[i, 2], qb[i, 3] = qw, qx, qy, qz
                if springs:  # a pair's part at half weight (both its grains list it)
                    parts[N_SUMS] = wtot[0] + 0.5 * ptot[0]
                    parts[N_SUMS + 1] = 0.5 * ptot[1]
                    parts[N_SUMS + 2] = wtot[2]
                    parts[N_SUMS + 3] = wtot[3] + 0.5 * ptot[3]
                for k in range(n_sums):
                    red[k, tid] = parts[k]
                block_sum(red, tid, nt, n_sums, False)
                if cells:  # each cell's loss and force, a thread per cell
                    cell_sums(grain[:, 0], bounds, pwc, tid, nt)
                    if spread:
                        cell_sums(grain[:, 1], bounds, bzc, tid, nt)
                    cuda.syncthreads()
                if tid == 0:  # the mount's response, the energy channels, the finite check
                    t1 = sh[0]
                    e_el = red[0, 0] + 0.5 * red[11, 0]
                    pw_n, pw_f, box_z, floor_lid = red[1, 0], red[2, 0], red[3, 0], red[4, 0]
                    n_floor, n_lid = red[5, 0], red[6, 0]
                    n_side = red[7, 0] - n_floor - n_lid
                    pp_n, pp_f = 0.5 * red[12, 0], 0.5 * red[13, 0]
                    zdd1, pw[_IN], pw[_PRIM] = respond_scalar(
                        mount, t1, z1, zdp, y1, ydp, dof_loads(spread, cdof, bzc, box_z, fdof),
                        prow, po, n_lines, xs, xds, acc, tmp)
                    zd1 = zdp if prescribed else zd + 0.5 * dt * (zdd + zdd1)
                    pw[_PPN], pw[_PPF], pw[_PWN], pw[_PWF] = pp_n, pp_f, pw_n, pw_f
                    pw[_DRAG] = drag * red[10, 0]
                    pw[_PW_FLOOR], pw[_PW_LID] = red[8, 0], red[9, 0]
                    pw[_PW_SIDE] = pw_n + pw_f - red[8, 0] - red[9, 0]
                    if not cells:
                        pwc[0] = pp_n + pp_f + pw_n + pw_f
                    health = box_z + e_el + pp_n + pp_f + pw_n + pw_f + z1 + zdp + zdd1
                    health += red[14, 0]
                    if springs:  # the springs' slip and stiffness channels
                        pw[_PP_SLIP] = red[N_SUMS + 1, 0]
                        pw[_PW_SLIP] = red[N_SUMS + 2, 0]
                        pw[_STIFF] = (e_spring - red[N_SUMS, 0]) / dt
                    if not math.isfinite(health):
                        zd = math.nan
                        sh[3] = 1.0
                    else:
                        for c in range(N_CHANNELS):  # (a step's own energies taken whole at
                            src = increment_of[c] if springs else -1  # its end: INCREMENT_OF)
                            inc[c] = 0.5 * dt * (pw[src] - power[src]) if src >= 0 else 0.0
                        for c in range(N_CHANNELS):
                            work[c] = work[c] + 0.5 * dt * (power[c] + pw[c]) + inc[c]
                            power[c] = pw[c]
                        if springs:
                            e_spring = red[N_SUMS + 3, 0]
                        for c in range(K):
                            work_cell[c] = work_cell[c] + 0.5 * dt * (power_cell[c] + pwc[c])
                            power_cell[c] = pwc[c]
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
                           n_lid, n_side, work, work_cell, bounds,
                           cell_frames(cdof, z, zd, yv, ydv, frames))
            cuda.syncthreads()
        if tid == 0:
            row[so.z], row[so.zd], row[so.zdd], row[so.t] = z, zd, zdd, t
            row[so.z_max], row[so.z_min], row[so.step] = zmax, zmin, step
            row[so.e_elastic], row[so.f_floor_lid], row[so.f_box] = e_el, floor_lid, box_z
            row[so.n_floor], row[so.n_lid], row[so.n_side] = n_floor, n_lid, n_side
            if springs:
                row[so.e_spring] = e_spring
        if springs:  # the pairs' springs into the state's rows (the walls' are there)
            for i in range(tid, n, nt):
                lost += springs_to_rows(i, n, nb, nc, cap, hsb, spq, spp)
            if lost:
                cuda.atomic.add(lostd, b, lost)

    return advance


def advance_packed(model, state_packed, params_packed, state_layout, param_layout,
                   n_records: int, record_every: int, threads: bool = True,
                   device: int | None = None):
    """:func:`jaxdamp.engine.native.advance_packed` on the CUDA device: the same packed rows
    in and out, the same samples. The rows travel to the device and back once per call (a
    chunk of thousands of steps: the copies are milliseconds beside seconds of compute).
    ``device``: the CUDA ordinal to run on (default: numba's current device); ``threads``
    (the native kernel's OpenMP switch, the same signature) is unused. In the
    simulator (the CPU tests) the threads hand over the interpreter every 0.1 ms instead of
    every 5 ms, or its barriers cost milliseconds each."""
    import contextlib

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
    dims, so, po, sid, bounds, cg, cdof, width = native.kernel_args(model, state_layout,
                                                                    param_layout)
    n, batch = model.n, st.shape[0]
    sc, size = scratch_layout(n, dims.ndof, dims.cells, model.springs)
    kernel = _kernel(dims.mount, dims.law, dims.shape, MAX_REGISTERS, model.springs)
    cap = NEIGHBOURS
    while True:
        d_st = cuda.to_device(st)
        d_rec = cuda.device_array((batch, int(n_records), width))
        status = cuda.to_device(np.zeros(batch, np.int64))
        lost = cuda.to_device(np.zeros(batch, np.int64))
        kernel[batch, threads_per_block(n)](
            int(n_records), int(record_every), dims, float(model.skin), d_st, cuda.to_device(pm),
            so, po, cuda.to_device(sid), cuda.to_device(bounds), cuda.to_device(cg),
            cuda.to_device(cdof), d_rec,
            cuda.device_array((batch, size)), sc, cuda.device_array((batch, cap, n), np.int32),
            cuda.device_array((batch, n), np.int32), status,
            # the pairs' springs, one per slot of the lists (a placeholder without)
            cuda.device_array((batch, cap, n, 3) if model.springs else (batch, 1, 1, 3)), lost)
        need = int(status.copy_to_host().max())
        if need <= cap:  # lost: springs the state's rows had no room for (larger lists)
            return d_st.copy_to_host(), d_rec.copy_to_host(), lost.copy_to_host()
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
    dims, so, po, sid, bounds, cg, cdof, _ = native.kernel_args(model, native.layout(states),
                                                      native.layout(params))
    sc, _ = scratch_layout(model.n, dims.ndof, dims.cells, model.springs)
    f2 = numba.float64[:, ::1]
    sig = (numba.int64, numba.int64, numba.typeof(dims), numba.float64, f2, f2,
           numba.typeof(so), numba.typeof(po), numba.typeof(sid), numba.typeof(bounds),
           numba.typeof(cg), numba.typeof(cdof), numba.float64[:, :, ::1], f2,
           numba.typeof(sc), numba.int32[:, :, ::1], numba.int32[:, ::1], numba.int64[::1],
           numba.float64[:, :, :, ::1], numba.int64[::1])
    kernel = _kernel(dims.mount, dims.law, dims.shape, springs=model.springs)
    # A function the kernel calls apart (the walls' spring, ``tangential.mindlin_called``) is
    # compiled by numba-cuda for the current device's compute capability; without a device
    # that is ``cc``'s (numba-cuda 0.30 asks the driver, which is absent here).
    from unittest import mock

    from numba.cuda import dispatcher

    target = type("Target", (), {"compute_capability": tuple(cc)})
    with mock.patch.object(dispatcher, "get_current_device", lambda: target):
        ptx, _ = cuda.compile_ptx(kernel.py_func, sig, cc=cc)
    return ptx


def resources(model, states, params, cc: tuple[int, int] = (9, 0),
              max_registers: int | None = None) -> dict:
    """The kernel assembled for ``cc`` without a device: :func:`compile_ptx`, linked by
    nvJitLink with the helper numba-cuda links into kernels that reshape arrays (as it does
    at launch). Returns ``{"registers", "spill_stores", "spill_loads", "stack",
    "shared"}`` (per thread; bytes, shared per block) from ptxas's report — a link error
    (an undefined function) raises. ``max_registers``: the cap of :data:`MAX_REGISTERS`."""
    import re

    import numba_cuda
    from cuda.bindings import nvjitlink, nvrtc

    ptx = compile_ptx(model, states, params, cc).encode()
    src_file = os.path.join(os.path.dirname(numba_cuda.__file__), "numba", "cuda",
                            "reshape_funcs.cu")
    with open(src_file, "rb") as fh:
        src = fh.read()
    _, prog = nvrtc.nvrtcCreateProgram(src, b"reshape_funcs.cu", 0, [], [])
    opts = [f"-arch=compute_{cc[0]}{cc[1]}".encode(), b"-rdc=true"]
    (err,) = nvrtc.nvrtcCompileProgram(prog, len(opts), opts)
    if err != nvrtc.nvrtcResult.NVRTC_SUCCESS:
        raise RuntimeError(f"NVRTC could not compile numba-cuda's {src_file}: {err}")
    _, size = nvrtc.nvrtcGetPTXSize(prog)
    helper = b" " * size
    nvrtc.nvrtcGetPTX(prog, helper)
    helper = helper.rstrip(b"\x00 ")
    link_opts = [f"-arch=sm_{cc[0]}{cc[1]}", "-verbose", "-O3"]
    if max_registers is not None:
        link_opts.append(f"-maxrregcount={max_registers}")
    h = nvjitlink.create(len(link_opts), link_opts)

    def log(size_fn, get_fn):
        buf = bytearray(size_fn(h))
        get_fn(h, buf)
        return buf.decode(errors="replace").rstrip("\x00")

    try:
        nvjitlink.add_data(h, nvjitlink.InputType.PTX, helper, len(helper), "reshape_funcs")
        nvjitlink.add_data(h, nvjitlink.InputType.PTX, ptx, len(ptx), "fused")
        try:
            nvjitlink.complete(h)
        except nvjitlink.nvJitLinkError as err:
            raise RuntimeError("nvJitLink: " + log(nvjitlink.get_error_log_size,
                                                  nvjitlink.get_error_log)) from err
        info = log(nvjitlink.get_info_log_size, nvjitlink.get_info_log)
    finally:
        nvjitlink.destroy(h)
    # the kernel's lines (the helper's come first)
    entry = info[info.rindex("Compiling entry function"):]

    def num(pattern):
        m = re.search(pattern, entry)
        return int(m.group(1)) if m else 0

    return {"registers": num(r"Used (\d+) registers"),
            "spill_stores": num(r"(\d+) bytes spill stores"),
            "spill_loads": num(r"(\d+) bytes spill loads"),
            "stack": num(r"(\d+) bytes stack frame"), "shared": num(r"(\d+) bytes smem")}
