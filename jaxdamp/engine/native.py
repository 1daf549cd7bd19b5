"""A compiled CPU engine (numba) for forward runs: the step of :mod:`jaxdamp.physics.integrate`, fast.

XLA's CPU backend runs the pure-JAX step at ~150–200 µs per system-step for a 250-grain bed
(``benchmarks/RESULTS.md``): it splits the contact law into many loop passes. This module
implements *the same* step — same velocity-Verlet scheme with predicted velocities, same wall
geometry, same energy channels — as plain loops compiled by numba. The physics is not retyped
here: the contact laws and their constants (:mod:`jaxdamp.physics.contact`: ``contact_scalar``,
``pair_scalar``, the tables ``Params.pair_table`` / ``wall_table`` built once by
:func:`jaxdamp.physics.model.build`), the base and box motion (:mod:`jaxdamp.physics.excitation`) and the body
force, primary and rotation (:mod:`jaxdamp.physics.integrate`) are the numba scalar forms defined next
to their JAX forms, inlined into these loops. State and parameters cross into the kernel as
the two packed float64 arrays of the callback (:func:`pack`); the kernel reads the fields
(:data:`STATE_FIELDS`, :data:`PARAM_FIELDS`) at their offsets and advances one copy of the
state in place (:func:`advance_packed`).

* the law's constants of a pair are looked up and formed once per listed pair when the pair
  list is built, and once per call for the walls, not per contact and step;

* grain pairs come from a half neighbour list (each pair once, Newton's third law applied)
  built inside the kernel on a cell grid from box-frame positions, holding the pairs closer
  than ``R_i + R_j + skin``, and rebuilt whenever a grain moved more than ``skin / 2``; the
  skin is the model's or wider for fast grains (:data:`REBUILD_STEPS`), and the list is
  rebuilt at the start of every call,
  so a call's result is a pure function of its inputs (resume stays bit-identical);
* the batch of independent systems is spread over the CPU cores (``prange``);
* a large bed (:data:`LARGE` grains or more) keeps its grains in cell order inside a call
  (:func:`_reorder` at the start and at every list rebuild: neighbours near in memory, as
  LAMMPS' atom sorting; records and the returned state keep the user's numbering), lists its
  pairs per block of whole cell layers (a half list in CSR form, the pair constants formed
  where a pair touches) and runs a step as one sweep over the blocks: a block's pairs, then
  (its forces whole: a block's pairs reach only into the next block) its corrector and the
  next step's predictor and walls, while its data is in the cache; with fewer systems than
  cores the sweep's chunks of consecutive blocks run over the cores, then the blocks where
  two chunks meet, and its sums are added block after block, so its numbers depend neither on
  the cores nor on the batch.

It is called from JAX through :func:`jax.pure_callback` once per chunk and writes the samples
itself with the scalar form of the record (:func:`jaxdamp.physics.energy.record_row`, next to
``record``), so the runner, checkpoints and sweeps are shared with the JAX engine and a chunk
crosses the JAX/Python boundary once. It is forward-only: gradients use the JAX engine, which
stays the reference; ``tests/test_native.py`` checks that both agree.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
from collections import namedtuple

import numpy as np

from jaxdamp.physics.contact import (
    FASTMATH,
    FASTMATH_STABLE,
    G_STAR,
    GAMMA_S,
    MU,
    contact_scalar,
    pair_scalar,
)
from jaxdamp.physics.containers import (
    CONTAINERS,
    section_scalar,
    side_contacts_scalar,
    side_curvature_scalar,
    side_reach_scalar,
)
from jaxdamp.physics.containers._scalar import add_wall_scalar, held, rows_of
from jaxdamp.physics.energy import cell_bounds, record_row
from jaxdamp.physics.excitation import base_motion_scalar, drive_motion_scalar
from jaxdamp.physics.integrate import body_force_scalar, rotate_scalar, rotate_series_scalar
from jaxdamp.physics.model import CH, INCREMENT_OF, N_CHANNELS, Params, State
from jaxdamp.physics.mounts import DRIVEN, energy_scalar, mount_of, predict_scalar, respond_scalar
from jaxdamp.physics.structure import acceleration_scalar as structure_acceleration_scalar
from jaxdamp.physics.tangential import mindlin_called, mindlin_scalar

# numba's OpenMP threads spin between parallel regions by default; a spinning thread took the
# second core from the single system it was waiting beside (13.4 -> 9.4 µs per step of the
# moving thesis bed with passive waiting, benchmarks/RESULTS.md). Set before numba loads OpenMP.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

try:
    import numba
    from numba import njit, prange

    AVAILABLE = True
except ImportError:  # pragma: no cover - numba is a dependency; keep the JAX engine usable
    AVAILABLE = False

#: Steps a neighbour list should last at the grains' speeds: the native kernel widens the skin
#: for fast grains (``_advance_one``); measured on the 2023 reference box at 3 cm, it cut the
#: rebuilds from 7 to ~2 per 100 steps (benchmarks/RESULTS.md).
REBUILD_STEPS = 40

U = np.uint64
"""In the step's loops, array indices the kernel cannot prove non-negative (block bounds,
list offsets and partners, species) are cast to this: numba wraps a signed index (``a[-1]``),
a compare and an add at every access that also keep a loop from SIMD code (the corrector over
a block: 4.4 against 3.0 ns per grain); it does not wrap an unsigned one. The list builds and
the re-sort keep signed indices (cast, they measured the same). Careful: numba types ``uint64
± int64`` as float64 (write ``U(3) * i``, not ``3 * i``)."""

#: Beds of at least this many grains take the large-bed path of the kernel: grains kept in
#: cell order (re-sorted at every list rebuild, invisible outside the kernel), pairs listed per
#: block of whole cell layers, and a single system's blocks spread over the cores. Measured on
#: the 2-core reference machine after the indices went unsigned (:data:`U`), one driven
#: thesis-like bed, ns per particle-step, small path / large path, one system and a batch of 2
#: (of 4 at 4 000 and 8 000): 34 / 73 and 66 / 66 at 4 000 grains, 39 / 50 and 81 / 76 at 8 000,
#: 43 / 47 and 44 / 38 at 12 000, 43 / 26 and 47 / 38 at 16 000 (benchmarks/RESULTS.md, "Large
#: beds: unsigned indices"): below ~16 000 grains one system waits on the cores' wake-ups
#: between the sweep's two parallel regions more than the large path saves.
LARGE = 16000
#: Grains per block of the large-bed path (the blocks are whole layers of cells, so about).
BLOCK_GRAINS = 512
#: At most this many blocks (enough for the cores of one machine).
MAX_BLOCKS = 512
#: Blocks per chunk of the large-bed path's sweep (at least 2): a step is one sweep over the
#: blocks in order (a block's pairs, then its corrector, then the next step's predictor and
#: walls, while its data is in the cache), the chunks of consecutive blocks over the cores,
#: then the blocks where two chunks meet. The chunks depend on the bed alone (not on the
#: cores), so the numbers do not depend on the cores either.
CHUNK_BLOCKS = 12

#: Fields of ``Params`` and ``State`` in the kernel's packed rows (all of them), read by name.
PARAM_FIELDS = tuple(f.name for f in dataclasses.fields(Params))
STATE_FIELDS = tuple(f.name for f in dataclasses.fields(State))
_DRIVEN = DRIVEN.id
_BOX = CONTAINERS["box"].id

#: The work channels' places (:data:`jaxdamp.physics.model.CHANNELS`, shared with the JAX engine).
_IN, _PRIM, _PPN, _PPF, _PWN, _PWF, _DRAG, _PW_FLOOR, _PW_LID, _PW_SIDE = (
    CH[k] for k in ("input", "primary_damping", "pp_normal", "pp_friction", "pw_normal",
                    "pw_friction", "drag", "pw_floor", "pw_lid", "pw_side"))
_PP_SLIP, _PW_SLIP, _STIFF = (CH[k] for k in ("pp_slip", "pw_slip", "spring_stiffness"))
#: Each channel's part that is a step's own energy over ``dt`` (:data:`INCREMENT_OF`).
_INCREMENT_OF = np.asarray(INCREMENT_OF, np.int64)

#: Where each field starts in a packed row (:func:`offsets`), read by name in the kernel.
StateOffsets = namedtuple("StateOffsets", STATE_FIELDS)
ParamOffsets = namedtuple("ParamOffsets", PARAM_FIELDS)
#: The integers that select the kernel's code paths and size its views: the mount
#: (:data:`jaxdamp.physics.mounts.MOUNTS`), the contact law and the container (their ``id``), the contact tables'
#: species and columns, the random base motion's lines, the structure's degrees of freedom,
#: the container's section numbers, the damper's cells (``Model.cells``) and, for a bed that
#: takes the large-bed path (at least :data:`LARGE` grains), its grains per block
#: (:data:`BLOCK_GRAINS`; 0: the small-bed path) and blocks per chunk (:data:`CHUNK_BLOCKS`),
#: all read when the call is made; with tangential springs, the state's spring slots per grain
#: (``State.spring_partner``'s ``K``; 0 without) and the walls per grain (2 + the sides).
Dims = namedtuple("Dims", ("mount", "law", "shape", "n_species", "n_cols", "n_lines", "ndof",
                           "n_section", "cells", "large", "chunk", "slots", "walls"))

#: The scalar forms the kernels inline (with the forms they call, from the same modules): a
#: change to their source files must recompile the cached kernels (numba's cache only watches
#: the kernel's own file).
_INLINED = (contact_scalar, pair_scalar, side_contacts_scalar, base_motion_scalar,
            drive_motion_scalar, body_force_scalar, predict_scalar, respond_scalar,
            energy_scalar, rotate_scalar, rotate_series_scalar, record_row,
            structure_acceleration_scalar, mindlin_scalar, add_wall_scalar)


def _source_files() -> tuple[str, ...]:
    """This module's file, the files defining :data:`_INLINED` (wherever they live) and every
    container module (the scalar dispatch inlines them all)."""
    import glob

    from jaxdamp.physics import containers

    files = {os.path.abspath(__file__)}
    files.update(os.path.abspath(f) for f in glob.glob(
        os.path.join(os.path.dirname(containers.__file__), "*.py")))
    for f in _INLINED:
        files.add(os.path.abspath(getattr(f, "py_func", f).__code__.co_filename))
    return tuple(sorted(files))


def _source_hash() -> str:
    h = hashlib.sha256()
    for name in _source_files():
        with open(name, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


def _cache_on_sources(dispatcher):
    """Key the on-disk cache of ``dispatcher`` also on the sources of :data:`_INLINED`.

    numba invalidates a cached kernel only when its own file changes; the scalar forms it
    inlines live in other modules, so editing a law would silently keep the old compiled law.
    The index key gets the hash of all of them (:func:`_source_files`), marked for a parallel
    dispatcher (:func:`_over_cores` compiles one function both ways, and numba's own key does
    not tell them apart). Uses numba's cache class (internal API); falls back to no on-disk
    cache if that changes."""
    try:
        from numba.core.caching import FunctionCache

        digest = _source_hash()
        if dispatcher.targetoptions.get("parallel"):
            digest += ":parallel"

        class _SourcesCache(FunctionCache):
            def _index_key(self, sig, codegen):
                return super()._index_key(sig, codegen) + (digest,)

        dispatcher._cache = _SourcesCache(dispatcher.py_func)
    except Exception:  # pragma: no cover - numba internals changed: compile every process
        from numba.core.caching import NullCache

        dispatcher._cache = NullCache()
    return dispatcher


if AVAILABLE:  # the scalar forms the kernel calls (not inlined) cache on the same sources
    _cache_on_sources(mindlin_called)


def _kernel(fastmath=FASTMATH, **flags):
    """``njit`` with the kernel's flags (``fastmath``: :data:`FASTMATH`, or
    :data:`FASTMATH_STABLE`) and the source-keyed cache."""
    def wrap(fn):
        return _cache_on_sources(njit(cache=True, error_model="numpy", fastmath=fastmath,
                                      **flags)(fn))
    return wrap


def _over_cores(fn):
    """``(over the cores, in the calling thread)``: ``fn`` compiled with ``parallel=True`` (its
    ``prange`` loops parallel regions) and without (``prange`` then runs as ``range``). The
    large-bed path calls the first for one system alone and the second inside the batch's own
    parallel loop, where numba would nest a region (which its ``workqueue`` layer refuses)."""
    return _kernel(parallel=True)(fn), _kernel()(fn)


def with_springs(springs, value):
    """``value``, or ``None`` where ``springs`` is ``None``, decided by ``springs``' numba
    type (:func:`_with_springs`): the kernel's spring arguments are a tuple or ``None``,
    never optional, so that the functions they are passed to compile apart, the branches on
    ``None`` folded."""
    return None if springs is None else value


if AVAILABLE:
    from numba.core import types as _types
    from numba.extending import overload

    @overload(with_springs, inline="always")
    def _with_springs(springs, value):
        if isinstance(springs, (_types.NoneType, _types.Omitted)):
            return lambda springs, value: None
        return lambda springs, value: value

if AVAILABLE:

    @_kernel(inline="always")
    def pair_constants(law, table, si, sj, Ri, Rj, mi, mj):
        """The constants of a grain pair's contact, ``(R_i + R_j, k, g, γ_s, μ)``: the row
        ``table[si, sj]`` of the pair table (species ``si``, ``sj``) and the law's radius- and
        mass-dependent part (:func:`jaxdamp.physics.contact.pair_scalar`) at ``R* = R_i R_j /
        (R_i + R_j)``, ``m* = m_i m_j / (m_i + m_j)``. The CPU kernel forms them once per listed
        pair, the device kernel once per touching pair and step."""
        rs = Ri + Rj
        row = table[si, sj]
        stiff, damp = pair_scalar(law, row, Ri * Rj / rs, mi * mj / (mi + mj))
        return rs, stiff, damp, row[GAMMA_S], row[MU]

    @_kernel(inline="always")
    def wall_constants(law, row, Ri, mi, kappa):
        """The constants ``(k, g, γ_s, μ)`` of a grain's contact with a wall of curvature
        ``kappa`` (0: a plane): the row of its species in the wall table, ``R* = R_i / (1 −
        R_i κ)``, ``m* = m_i``."""
        stiff, damp = pair_scalar(law, row, Ri / (1.0 - Ri * kappa), mi)
        return stiff, damp, row[GAMMA_S], row[MU]

    @_kernel(inline="always")
    def pair_contact(law, dx, dy, dz, d2, rs, vx, vy, vz, sx, sy, sz, k, g, gamma_s, mu):
        """The contact of grains ``i, j`` that touch (``d = r_i − r_j``, ``d2 = |d|² < rs²``,
        ``rs = R_i + R_j``; ``v = v_i − v_j``, ``s = R_i ω_i + R_j ω_j``; constants of
        :func:`pair_constants`): ``(F on i, n × F_t, elastic energy, normal loss, friction
        loss)``, ``n = d / |d|``; the torque on each grain ``k`` of the pair is ``−R_k n × F_t``.
        Odd in ``(d, v)``: from ``j``'s side the force is exactly ``−F`` and ``n × F_t`` the
        same, so a full list (the device's, each grain its own) and a half list (the CPU's,
        Newton's third law) give the same forces."""
        d = math.sqrt(d2)
        xi = rs - d
        inv = 1.0 / d
        nx, ny, nz = dx * inv, dy * inv, dz * inv
        fx, fy, fz, tx, ty, tz, e, ln, lf = contact_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx,
                                                           sy, sz, k, g, gamma_s, mu)
        return (fx, fy, fz, ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx, e, ln, lf)

    @_kernel(inline="always")
    def pair_spring(law, dx, dy, dz, d2, rs, vx, vy, vz, sx, sy, sz, k, g, mu, G_star, r_eff, sp,
                    p, i, j):
        """:func:`pair_contact` with the tangential spring of listed pair ``p`` (grains ``i``,
        ``j``; its ``G*`` and ``R*``; :func:`jaxdamp.physics.tangential.mindlin_scalar`), for a
        pair that touches or held a spring after the last step (:func:`held_pair`). ``sp =
        (hp, vh, sh, tot, dt)``: the listed pairs' springs ``hp (P, 3)`` (read and written in
        place), the half-step velocities ``vh`` and spins ``sh = R ω`` with which they grow,
        the step's totals ``tot`` (added to; as the walls',
        :func:`~jaxdamp.physics.containers._scalar.add_wall_scalar`) and the time step."""
        hp, vh, sh, tot, dt = sp
        d = math.sqrt(d2)
        inv = 1.0 / d
        nx, ny, nz = dx * inv, dy * inv, dz * inv
        (fx, fy, fz, tx, ty, tz, e, ln, lf, h0, h1, h2, turned, slip, e_s) = mindlin_scalar(
            law, rs - d, nx, ny, nz, vx, vy, vz, sx, sy, sz, vh[i, 0] - vh[j, 0],
            vh[i, 1] - vh[j, 1], vh[i, 2] - vh[j, 2], sh[i, 0] + sh[j, 0], sh[i, 1] + sh[j, 1],
            sh[i, 2] + sh[j, 2], k, g, G_star, r_eff, mu, dt, hp[p, 0], hp[p, 1], hp[p, 2])
        hp[p, 0], hp[p, 1], hp[p, 2] = h0, h1, h2
        tot[0] += turned
        tot[1] += slip
        tot[3] += e_s
        return (fx, fy, fz, ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx, e, ln, lf)

    @_kernel(inline="always")
    def held_pair(sp, p):
        """Whether listed pair ``p`` held a spring after the last step (``sp``:
        :func:`pair_spring`'s, or ``None``: never)."""
        if sp is None:
            return False
        hp = sp[0]
        return hp[p, 0] != 0.0 or hp[p, 1] != 0.0 or hp[p, 2] != 0.0

    @_kernel(inline="always")
    def half_stencil(o):
        """The offset ``(ox, oy, oz)`` of cell ``o`` (0–13) of the half stencil of a cell grid:
        the cell itself (``o = 0``: partners after the grain only) and the 13 cells ahead of it
        in (x, y, z) order, ``ox ∈ {0, 1}``, so that each pair of cells is visited once and no
        pair twice (x being the slowest axis of the cells' order)."""
        ox = 0 if o < 5 else 1
        q = o if o < 5 else o - 5
        if o == 0:
            oy, oz = 0, 0
        elif o == 1:
            oy, oz = 0, 1
        elif ox == 0:
            oy, oz = 1, q - 3
        else:
            oy, oz = q // 3 - 1, q % 3 - 1
        return ox, oy, oz

    @_kernel(inline="always")
    def listed(ref, R, i, j, extra):
        """Whether grains ``i``, ``j`` (reference positions ``ref``, radii ``R``) belong in a
        neighbour list of skin ``extra``: their surfaces closer than it, ``|r_i − r_j| < R_i +
        R_j + extra`` (both list builds, :func:`_build_pairs` and :func:`_list_block`)."""
        dx = ref[i, 0] - ref[j, 0]
        dy = ref[i, 1] - ref[j, 1]
        dz = ref[i, 2] - ref[j, 2]
        lim = R[i] + R[j] + extra
        return dx * dx + dy * dy + dz * dz < lim * lim

    @_kernel()
    def _build_pairs(r, bx, by, bz, cutoff, pi, pj, pc, ref, R, m, sid, table, law):
        """Half list of the pairs whose surfaces are closer than the skin, ``|r_i - r_j| < R_i +
        R_j + cutoff - 2 R_max`` (box frame; size-aware, as :mod:`jaxdamp.engine.neighbors`), via a
        cell grid of side ``cutoff``, with the pairs' constants ``pc[k] = (R_i + R_j, k, g,
        γ_s, μ)``: the row ``table[sid_i, sid_j]`` of the pair table and the law's radius- and
        mass-dependent part (:func:`jaxdamp.physics.contact.pair_scalar`), once per listed pair;
        stores the reference positions (box frame: the box's corner at ``(bx, by, bz)``).
        Returns the number of pairs, or minus the number needed when the arrays are too
        small."""
        n = r.shape[0]
        extra = cutoff - 2.0 * R.max()
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for i in range(n):
            ref[i, 0] = r[i, 0] - bx
            ref[i, 1] = r[i, 1] - by
            ref[i, 2] = r[i, 2] - bz
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
        # half stencil: a grain's own cell (partners after it) and the 13 cells ahead of it
        # in (x, y, z) order, so each pair of cells is visited once and no pair twice
        for i in range(n):
            c = cell[i]
            cz = c % dims[2]
            cy = (c // dims[2]) % dims[1]
            cx = c // (dims[1] * dims[2])
            for o in range(14):
                ox, oy, oz = half_stencil(o)
                ax, ay, az = cx + ox, cy + oy, cz + oz
                if ay < 0 or ay >= dims[1] or az < 0 or az >= dims[2] or ax >= dims[0]:
                    continue
                cc = (ax * dims[1] + ay) * dims[2] + az
                for s in range(count[cc], count[cc + 1]):
                    j = order[s]
                    if o == 0 and j <= i:
                        continue
                    if listed(ref, R, i, j, extra):
                        if k < cap:
                            pi[k] = i
                            pj[k] = j
                            (pc[k, 0], pc[k, 1], pc[k, 2], pc[k, 3],
                             pc[k, 4]) = pair_constants(law, table, sid[i], sid[j], R[i], R[j],
                                                        m[i], m[j])
                        k += 1
        return k if k <= cap else -k

    @_kernel()
    def _pairs(r, bx, by, bz, cutoff, pi, pj, pc, ref, R, m, sid, table, law):
        """:func:`_build_pairs`, growing the pair arrays when they are too small."""
        k = _build_pairs(r, bx, by, bz, cutoff, pi, pj, pc, ref, R, m, sid, table, law)
        if k < 0:
            pi = np.empty(2 * (-k), np.int64)
            pj = np.empty(2 * (-k), np.int64)
            pc = np.empty((2 * (-k), 5))
            k = _build_pairs(r, bx, by, bz, cutoff, pi, pj, pc, ref, R, m, sid, table, law)
        return k, pi, pj, pc

    # -- contact history: the pairs' springs between the state's rows and the half list -----

    @_kernel(inline="always")
    def _slot(part, rows, cnt, a, b, hx, hy, hz):
        """Put the spring ``h`` of grain ``a`` with partner ``b`` in row ``a``'s next slot;
        returns 1 where the row is full (the spring lost), else 0."""
        k = cnt[a]
        if k >= part.shape[1]:
            return 1
        part[a, k] = b
        rows[a, k, 0], rows[a, k, 1], rows[a, k, 2] = hx, hy, hz
        cnt[a] = k + 1
        return 0

    @_kernel()
    def _springs_out(pi, pj, hp, npairs, part, rows):
        """The springs ``hp`` of the listed pairs ``(pi, pj)`` into the state's rows
        (``State.spring_partner``, ``spring_pair``: per grain its partners in increasing order,
        padded with ``N``, and the spring's force on it, the partner's row holding the
        opposite force), as the JAX engine keeps them (:mod:`jaxdamp.engine.history`).
        Returns the number of springs that did not fit (a row holds ``K`` of them; the runner
        then redoes the chunk with larger lists)."""
        n, K = part.shape
        for i in range(n):
            for k in range(K):
                part[i, k] = n
                rows[i, k, 0] = 0.0
                rows[i, k, 1] = 0.0
                rows[i, k, 2] = 0.0
        cnt = np.zeros(n, np.int64)
        lost = 0
        for p in range(npairs):
            hx, hy, hz = hp[p, 0], hp[p, 1], hp[p, 2]
            if hx != 0.0 or hy != 0.0 or hz != 0.0:
                i, j = pi[p], pj[p]
                lost += _slot(part, rows, cnt, i, j, hx, hy, hz)
                lost += _slot(part, rows, cnt, j, i, -hx, -hy, -hz)
        for i in range(n):  # each row in increasing partner order (insertion sort: rows are short)
            for k in range(1, cnt[i]):
                q = part[i, k]
                h0, h1, h2 = rows[i, k, 0], rows[i, k, 1], rows[i, k, 2]
                m = k - 1
                while m >= 0 and part[i, m] > q:
                    part[i, m + 1] = part[i, m]
                    rows[i, m + 1, 0] = rows[i, m, 0]
                    rows[i, m + 1, 1] = rows[i, m, 1]
                    rows[i, m + 1, 2] = rows[i, m, 2]
                    m -= 1
                part[i, m + 1] = q
                rows[i, m + 1, 0], rows[i, m + 1, 1], rows[i, m + 1, 2] = h0, h1, h2
        return lost

    @_kernel()
    def _csr_pairs(n, ps, pe, pj, perm, hp, ci, cj, ch, to_list):
        """A large bed's listed pairs (the half lists ``ps``, ``pe``, ``pj`` of its grains in
        cell order, :func:`_list_block`) as a flat list in the user's numbering, for
        :func:`_springs_out` and :func:`_springs_in`: the ``q``-th pair's grains ``ci[q] =
        perm[i]``, ``cj[q] = perm[pj[p]]`` and its spring ``ch[q] = hp[p]`` (or, where
        ``to_list``, the other way: ``hp[p] = ch[q]``). Returns the number of pairs."""
        q = 0
        for i in range(n):
            for p in range(ps[i], pe[i]):
                ci[q] = perm[i]
                cj[q] = perm[pj[p]]
                for c in range(3):
                    if to_list:
                        hp[p, c] = ch[q, c]
                    else:
                        ch[q, c] = hp[p, c]
                q += 1
        return q

    @_kernel()
    def _springs_in(pi, pj, hp, pg, npairs, part, rows, table, sid, R):
        """The springs of the state's rows (:func:`_springs_out`'s form, or the JAX engine's:
        rows in increasing partner order, padded with ``N``) onto the listed pairs ``(pi,
        pj)``, by pair identity: ``hp[p]`` the spring's force on ``pi[p]`` (zero for a pair
        without one), and ``pg[p] = (G*, R*)`` (the pair table's column
        :data:`~jaxdamp.physics.contact.G_STAR`, ``R_i R_j / (R_i + R_j)``). Returns the
        number of springs in the rows that no listed pair took (lost: a touching pair is
        always listed, so none unless a list overflowed)."""
        n, K = part.shape
        found = 0
        for p in range(npairs):
            i, j = pi[p], pj[p]
            pg[p, 0] = table[sid[i], sid[j], G_STAR]
            pg[p, 1] = R[i] * R[j] / (R[i] + R[j])
            hp[p, 0] = 0.0
            hp[p, 1] = 0.0
            hp[p, 2] = 0.0
            for k in range(K):
                q = part[i, k]
                if q >= j:
                    if q == j:
                        hp[p, 0], hp[p, 1], hp[p, 2] = rows[i, k, 0], rows[i, k, 1], rows[i, k, 2]
                        found += hp[p, 0] != 0.0 or hp[p, 1] != 0.0 or hp[p, 2] != 0.0
                    break
        held = 0
        for i in range(n):
            for k in range(K):
                q = part[i, k]
                if q > i and q < n and (rows[i, k, 0] != 0.0 or rows[i, k, 1] != 0.0
                                        or rows[i, k, 2] != 0.0):
                    held += 1
        return held - found

    @_kernel()
    def _wall_constants(R, m, sid, wall_table, law, kappa):
        """Per grain, the constants of its contact with a wall of curvature ``kappa`` (0: a
        plane): ``(N, 4)`` array of ``(k, g, γ_s, μ)`` from the row of its species in the wall
        table, ``R* = R_i / (1 − R_i κ)`` (``R_i`` for a plane), ``m* = m_i`` (they depend on
        the grain, the wall's material and its curvature only: formed once per call)."""
        n = R.shape[0]
        wk = np.empty((n, 4))
        for i in range(n):
            wk[i, 0], wk[i, 1], wk[i, 2], wk[i, 3] = wall_constants(law, wall_table[sid[i]], R[i],
                                                                    m[i], kappa)
        return wk

    def _grain_walls(shape, law, lo, n, step, r1, vp, rw, Rb, mb, ref, wk, wks, sec, og, shifted,
                    gs, cg, frames, F, T, ex, ey, ez, z1, zdp, Lz, gd, half_skin2, sp):
        """Pass 1 over the grains ``lo, lo + step, … < n`` (all of them on the CPU; a thread's
        own on the device, :mod:`jaxdamp.engine.fused`: the one definition of a grain's walls
        for both kernels): body force, the floor, the lid and the container's sides
        (number ``shape``, :mod:`jaxdamp.physics.containers`; ``sec``: its section numbers in
        registers, :func:`~jaxdamp.physics.containers.section_scalar`; ``og``: the corner of
        every grain's cell in the box frame, ``Params.origin`` ``(N, 2)``, taken off the
        grain's position where ``shifted``: several cells; then the walls of grain ``i``'s
        cell ``c = cg[i]`` are at ``e frames[c, 0]`` moving at ``e frames[c, 1]`` (each cell on
        its degree of freedom), and ``gs[i, 0]``, ``gs[i, 1]`` are set to the loss power of its
        wall contacts and its force on its container along ``e``, for the cells' sums; the
        lists' frame stays the box's, ``e z1``. At most 30 arguments: numba inlines no more)
        into ``F``, ``T``; returns the
        sums ``(elastic energy, normal loss, friction loss, box_z, floor + lid force, grains on
        the floor, on the lid, wall contacts (all walls), the floor's loss, the lid's loss,
        Σ m v², whether a grain moved more than skin/2 since the list was built)``. Compiled
        where ``shape`` and ``shifted`` are constants (:data:`walls_of`, :data:`grain_walls`),
        their branches fold away: the CPU kernel calls a copy for the one-cell box, one for
        another one-cell container and one for several cells."""
        e_el = 0.0
        pw_n = 0.0
        pw_f = 0.0
        box_z = 0.0
        floor_lid = 0.0
        n_floor = 0.0
        n_lid = 0.0
        n_wall = 0.0
        l_floor = 0.0
        l_lid = 0.0
        pdrag = 0.0
        far = False
        grav, drag = gd
        hw = rows_of(sp)  # the walls' springs (or None): the loop's checks get the one array
        for i in range(lo, n, step):
            x, y, zz = r1[i, 0], r1[i, 1], r1[i, 2]
            ux, uy, uz = vp[i, 0], vp[i, 1], vp[i, 2]
            sx, sy, sz = rw[i, 0], rw[i, 1], rw[i, 2]
            Ri = Rb[i]
            # box frame (the box's corner at e z1) and velocities relative to the walls
            bx = x - ex * z1
            by = y - ey * z1
            floor = zz - ez * z1
            ddx = bx - ref[i, 0]
            ddy = by - ref[i, 1]
            ddz = floor - ref[i, 2]
            far = far | (ddx * ddx + ddy * ddy + ddz * ddz > half_skin2)
            vi = zdp
            if shifted:  # the frame of the grain's cell, on its own degree of freedom
                zi = frames[cg[i], 0]
                vi = frames[cg[i], 1]
                bx = x - ex * zi
                by = y - ey * zi
                floor = zz - ez * zi
            wx = ux - ex * vi
            wy = uy - ey * vi
            wz = uz - ez * vi
            pdrag += mb[i] * (ux * ux + uy * uy + uz * uz)
            fx, fy, fz = body_force_scalar(mb[i], ux, uy, uz, grav, drag)
            tx = 0.0
            ty = 0.0
            tz = 0.0
            # walls: the floor, the lid, then the container's sides (inward normals);
            # most grains touch none, so the common path is a compare per wall; box_z
            # sums the force on the box along the axis e
            acc = (fx, fy, fz, tx, ty, tz, e_el, pw_n, pw_f, box_z, n_wall)
            lost = pw_n + pw_f  # the losses and the force before this grain's walls
            pushed = box_z
            if floor < Ri or held(hw, i, 0):  # (or releasing its spring: sp)
                acc, gz, loss = add_wall_scalar(law, Ri - floor, 0.0, 0.0, 1.0, wx, wy, wz, sx,
                                                sy, sz, Ri, wk[i, 0], wk[i, 1], wk[i, 2],
                                                wk[i, 3], ex, ey, ez, acc, sp, i, 0)
                floor_lid -= gz
                n_floor += 1.0 if floor < Ri else 0.0
                l_floor += loss
            if Lz - floor < Ri or held(hw, i, 1):
                acc, gz, loss = add_wall_scalar(law, Ri - (Lz - floor), 0.0, 0.0, -1.0, wx, wy,
                                                wz, sx, sy, sz, Ri, wk[i, 0], wk[i, 1],
                                                wk[i, 2], wk[i, 3], ex, ey, ez, acc, sp, i, 1)
                floor_lid -= gz
                n_lid += 1.0 if Lz - floor < Ri else 0.0
                l_lid += loss
            cx = bx
            cy = by
            if shifted:  # the sides of the grain's own cell (its corner at og[i], box frame)
                cx = bx - og[i, 0]
                cy = by - og[i, 1]
            if side_reach_scalar(shape, cx, cy, sec, Ri, hw, i):
                acc = side_contacts_scalar(shape, law, cx, cy, sec, Ri, wks, i, wx, wy, wz, sx,
                                           sy, sz, ex, ey, ez, acc, sp, hw)
            fx, fy, fz, tx, ty, tz, e_el, pw_n, pw_f, box_z, n_wall = acc
            F[i, 0], F[i, 1], F[i, 2] = fx, fy, fz
            T[i, 0], T[i, 1], T[i, 2] = tx, ty, tz
            if shifted:
                gs[i, 0] = pw_n + pw_f - lost
                gs[i, 1] = box_z - pushed
        return (e_el, pw_n, pw_f, box_z, floor_lid, n_floor, n_lid, n_wall, l_floor, l_lid,
                pdrag, far)

    #: :func:`_grain_walls` inlined where it is called: the device's threads
    #: (:mod:`jaxdamp.engine.fused`), whose registers it shares, and a large bed's grains
    #: near a wall (:func:`box_walls`, one grain per call: a call apart cost the 50 000-grain
    #: step 1.08×, ``benchmarks/ab_native.py``).
    grain_walls = _kernel(inline="always")(_grain_walls)
    #: :func:`_grain_walls` compiled apart, once per signature: the CPU kernel's, called once
    #: per grain loop. Called with the container ``shape`` and ``shifted`` as constants
    #: (literals), it compiles with their branches folded, as inlined code would; apart, the
    #: kernel's cold compile took 161 s instead of 388 s (five inlined copies of every
    #: container's and law's scalar forms before; one run of ``jaxdamp run --set
    #: numerics.engine=native``, empty numba cache, 2-core AMD host, ``benchmarks/RESULTS.md``).
    walls_of = _kernel()(_grain_walls)

    @_kernel(inline="always")
    def walls_in_cells(shifted, shape, law, g0, g1, r1, vp, rw, Rb, mb, ref, wk, wks, sec, og, gs,
                       cg, frames, F, T, ex, ey, ez, z1, zdp, Lz, gd, half_skin2, sp):
        """:data:`walls_of` of grains ``g0 … g1 − 1`` with ``shifted`` (several cells) as the
        constant it must be for its branches to fold: a copy for each value."""
        if shifted:
            return walls_of(shape, law, g0, g1, U(1), r1, vp, rw, Rb, mb, ref, wk, wks, sec, og,
                            True, gs, cg, frames, F, T, ex, ey, ez, z1, zdp, Lz, gd, half_skin2,
                            sp)
        return walls_of(shape, law, g0, g1, U(1), r1, vp, rw, Rb, mb, ref, wk, wks, sec, og,
                        False, gs, cg, frames, F, T, ex, ey, ez, z1, zdp, Lz, gd, half_skin2, sp)

    @_kernel(inline="always")
    def box_walls(law, g0, g1, r1, vp, rw, Rb, mb, ref, wk, wks, sec, og, gs, cg, frames, F, T,
                  ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2):
        """:func:`grain_walls` of grains ``g0 … g1 − 1`` of a one-cell box (a large bed's
        block, :func:`_walls_block`), the same sums: every grain's body force into ``F``, zero
        into ``T``, ``Σ m v²`` and the largest displacement since the list was built, and only
        the grains within reach of a wall (the floor, the lid, a side: most of a large bed
        touches none) through :func:`grain_walls` itself, one grain at a time (the test is the
        negation of its contact conditions, and its sums for one grain are added in the same
        order). In :func:`grain_walls`' loop the eleven running sums ride through every
        grain's branches; here they change only in the rare branch, and the 50 000-grain
        bed's whole step takes 0.91× the time (``benchmarks/RESULTS.md``, "Large beds: the
        wall pass without the walls' sums per grain")."""
        pdrag = 0.0
        moved = 0.0
        e_el = 0.0
        pw_n = 0.0
        pw_f = 0.0
        box_z = 0.0
        floor_lid = 0.0
        n_floor = 0.0
        n_lid = 0.0
        n_wall = 0.0
        l_floor = 0.0
        l_lid = 0.0
        for i in range(g0, g1):
            ux, uy, uz = vp[i, 0], vp[i, 1], vp[i, 2]
            bx = r1[i, 0] - ex * z1
            by = r1[i, 1] - ey * z1
            floor = r1[i, 2] - ez * z1
            ddx = bx - ref[i, 0]
            ddy = by - ref[i, 1]
            ddz = floor - ref[i, 2]
            moved = max(moved, ddx * ddx + ddy * ddy + ddz * ddz)
            pdrag += mb[i] * (ux * ux + uy * uy + uz * uz)
            F[i, 0], F[i, 1], F[i, 2] = body_force_scalar(mb[i], ux, uy, uz, grav, drag)
            T[i, 0] = 0.0
            T[i, 1] = 0.0
            T[i, 2] = 0.0
            Ri = Rb[i]
            if (floor >= Ri and Lz - floor >= Ri and bx >= Ri and sec[0] - bx >= Ri
                    and by >= Ri and sec[1] - by >= Ri):
                continue
            s = grain_walls(_BOX, law, i, i + U(1), U(1), r1, vp, rw, Rb, mb, ref, wk, wks, sec,
                            og, False, gs, cg, frames, F, T, ex, ey, ez, z1, zdp, Lz,
                            (grav, drag), half_skin2, None)
            e_el += s[0]
            pw_n += s[1]
            pw_f += s[2]
            box_z += s[3]
            floor_lid += s[4]
            n_floor += s[5]
            n_lid += s[6]
            n_wall += s[7]
            l_floor += s[8]
            l_lid += s[9]
        return (e_el, pw_n, pw_f, box_z, floor_lid, n_floor, n_lid, n_wall, l_floor, l_lid,
                pdrag, moved > half_skin2)

    @_kernel(inline="always")
    def cell_frames(cdof, z, zd, y, yd, frames):
        """Each cell's container's position ``frames[c, 0]`` and velocity ``frames[c, 1]``
        along ``e``: its degree of freedom ``cdof[c]`` of ``(z, y)``, ``(z', y')``; returns
        the positions."""
        for c in range(cdof.shape[0]):
            d = cdof[c]
            frames[c, 0] = z if d == 0 else y[d - 1]
            frames[c, 1] = zd if d == 0 else yd[d - 1]
        return frames[:, 0]

    @_kernel(inline="always")
    def _predict(mount, t1, dt, hdt2, z, zd, zdd, prow, po, yv, ydv, yddv, y1, ydp, one_cell,
                 cdof, frames):
        """The prediction of the step that ends at ``t1`` from the last one's ``(z, z', z'')``
        and the structure's ``yv``, ``ydv``, ``yddv``: the box's ``(z1, z1')`` (returned), the
        structure's other degrees of freedom into ``y1``, ``ydp`` and, with several damper
        cells, each cell's position and velocity into ``frames``."""
        z1, zdp = predict_scalar(mount, t1, dt, z, zd, zdd, prow, po)
        for j in range(y1.shape[0]):
            y1[j] = yv[j] + dt * ydv[j] + hdt2 * yddv[j]
            ydp[j] = ydv[j] + dt * yddv[j]
        if not one_cell:
            cell_frames(cdof, z1, zdp, y1, ydp, frames)
        return z1, zdp

    @_kernel(inline="always")
    def dof_loads(spread, cdof, bzc, box_z, fdof):
        """The grains' forces on the degrees of freedom, into ``fdof`` (returned): ``box_z`` on
        the box's (the others stay as they are: zero), or where ``spread`` (cells on several)
        each cell's ``bzc[c]`` on its own ``cdof[c]``."""
        if spread:
            for j in range(fdof.shape[0]):
                fdof[j] = 0.0
            for c in range(cdof.shape[0]):
                fdof[cdof[c]] += bzc[c]
        else:
            fdof[0] = box_z
        return fdof

    @_kernel(inline="always")
    def cell_sums(gl, bounds, out, lo, step):
        """``out[c]`` = the sum of ``gl`` over the grains of cell ``c`` (``bounds``
        ``(S, k + 1)``: :func:`~jaxdamp.physics.energy.cell_bounds`) for the cells ``lo, lo +
        step, …`` (all on the CPU; a thread's own on the device)."""
        for c in range(lo, bounds.shape[1] - 1, step):
            total = 0.0
            for sp in range(bounds.shape[0]):
                for i in range(bounds[sp, c], bounds[sp, c + 1]):
                    total += gl[i]
            out[c] = total

    @_kernel()
    def _pair_forces(law, r, v, rw, R, pi, pj, pc, npairs, F, T, gl, sp):
        """Adds the grain pairs' forces and torques to ``F``, ``T`` (half list: Newton's third
        law); ``rw[i] = R_i ω_i``. Returns ``(elastic energy, normal loss, friction loss)``,
        summed in registers. ``gl``: ``None``, or (several cells: a pair's grains share a cell)
        an array to which each pair's loss is added at its first grain; ``sp``: ``None`` (the
        viscous law), or the pairs' tangential springs (:func:`pair_spring`); numba compiles
        each apart, the branches on ``None`` folded away."""
        e_sum = 0.0
        ln_sum = 0.0
        lf_sum = 0.0
        for p in range(npairs):
            i = U(pi[p])  # unsigned indices (:data:`U`)
            j = U(pj[p])
            dx = r[i, 0] - r[j, 0]
            dy = r[i, 1] - r[j, 1]
            dz = r[i, 2] - r[j, 2]
            d2 = dx * dx + dy * dy + dz * dz
            rs = pc[p, 0]
            if d2 >= rs * rs and not held_pair(sp, p):
                continue
            vx, vy, vz = v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2]
            sx, sy, sz = rw[i, 0] + rw[j, 0], rw[i, 1] + rw[j, 1], rw[i, 2] + rw[j, 2]
            if sp is None:
                fx, fy, fz, cx, cy, cz, e, ln, lf = pair_contact(
                    law, dx, dy, dz, d2, rs, vx, vy, vz, sx, sy, sz, pc[p, 1], pc[p, 2],
                    pc[p, 3], pc[p, 4])
            else:  # sp = (hp, pg, vh, sh, tot, dt): pg the pairs' (G*, R*)
                pg = sp[1]
                fx, fy, fz, cx, cy, cz, e, ln, lf = pair_spring(
                    law, dx, dy, dz, d2, rs, vx, vy, vz, sx, sy, sz, pc[p, 1], pc[p, 2],
                    pc[p, 4], pg[p, 0], pg[p, 1], (sp[0], sp[2], sp[3], sp[4], sp[5]), p, i, j)
            F[i, 0] += fx
            F[i, 1] += fy
            F[i, 2] += fz
            F[j, 0] -= fx
            F[j, 1] -= fy
            F[j, 2] -= fz
            # torque -R_k (n × F_t) on both grains of the pair
            T[i, 0] -= R[i] * cx
            T[i, 1] -= R[i] * cy
            T[i, 2] -= R[i] * cz
            T[j, 0] -= R[j] * cx
            T[j, 1] -= R[j] * cy
            T[j, 2] -= R[j] * cz
            e_sum += e
            ln_sum += ln
            lf_sum += lf
            if gl is not None:
                gl[i] += ln + lf
        return e_sum, ln_sum, lf_sum

    @_kernel(fastmath=FASTMATH_STABLE)
    def _correct(g0, g1, dt, wb, alb, wm, Ff, Tf, im3, iI3, vf, af, wf, alf, rf, r1f, qs, qn):
        """Pass 3 over grains ``g0 … g1 − 1`` (a block, or ``0, n``): the velocity-Verlet
        corrector (new accelerations from the forces ``Ff`` and torques ``Tf``, flat
        ``(3n,)``; velocities, angular velocities and the predicted positions ``r1f`` into the
        state's flat views) and the rotation of the
        quaternions ``qs`` into ``qn`` by the mid-step angular velocity. Returns the step's
        finite check: 0.0 where every new acceleration is finite, else NaN (counted in
        integers, a sum whose order does not matter). A function of its own, compiled apart
        from the kernel's large body, so that its loops compile as loops alone (9 % of the
        step, ``benchmarks/ab_native.py``), and with :data:`FASTMATH_STABLE`: the same bits
        in every caller."""
        bad = 0  # non-finite accelerations (x − x is 0 for a finite x, NaN otherwise)
        u0, u1 = U(g0), U(g1)  # unsigned indices (:data:`U`)
        for i in range(u0, u1):
            # the mid-step angular velocity ω + α dt/2 of the rotation (below)
            wm[0, i] = wb[i, 0] + 0.5 * dt * alb[i, 0]
            wm[1, i] = wb[i, 1] + 0.5 * dt * alb[i, 1]
            wm[2, i] = wb[i, 2] + 0.5 * dt * alb[i, 2]
        for j in range(U(3 * g0), U(3 * g1)):  # the corrector, flat
            a1 = Ff[j] * im3[j]
            bad += a1 - a1 != 0.0
            vf[j] = vf[j] + 0.5 * dt * (af[j] + a1)
            af[j] = a1
        for j in range(U(3 * g0), U(3 * g1)):
            al1 = Tf[j] * iI3[j]
            bad += al1 - al1 != 0.0
            wf[j] = wf[j] + 0.5 * dt * (alf[j] + al1)
            alf[j] = al1
        for j in range(U(3 * g0), U(3 * g1)):
            rf[j] = r1f[j]
        # the rotation, component arrays and no branch: SIMD over the grains; the
        # exact form only for grains where the series do not hold (fast spins)
        exact = 0
        for i in range(u0, u1):
            qn[0, i], qn[1, i], qn[2, i], qn[3, i], ok = rotate_series_scalar(
                qs[0, i], qs[1, i], qs[2, i], qs[3, i], wm[0, i], wm[1, i], wm[2, i], dt)
            exact += not ok
        if exact:
            for i in range(u0, u1):
                if not rotate_series_scalar(qs[0, i], qs[1, i], qs[2, i], qs[3, i],
                                            wm[0, i], wm[1, i], wm[2, i], dt)[4]:
                    qn[0, i], qn[1, i], qn[2, i], qn[3, i] = rotate_scalar(
                        qs[0, i], qs[1, i], qs[2, i], qs[3, i], wm[0, i], wm[1, i],
                        wm[2, i], dt)
        return 0.0 if bad == 0 else np.nan

    # -- large beds: grains in cell order, in blocks, the blocks over the cores ---------------

    @_kernel()
    def _spatial_order(p, bx, by, bz, cutoff, cgw, K):
        """The grains ``p`` ``(n, 3)`` (box frame: minus ``(bx, by, bz)``) in the order of a
        cell grid of side at least ``cutoff``: by damper cell ``cgw`` (of ``K``), then along
        the grid's longest axis (the slowest: its layers become the blocks), then the other two.
        Returns ``(ok, order, key, start, dims)``: ``order[s]`` the grain at place ``s``,
        ``key[s]`` its cell's number ``((c K_0 + a_0) D_1 + a_1) D_2 + a_2`` (cell coordinates
        ``a`` along the axes of ``dims`` = ``(D_0, D_1, D_2)``, the longest first), ``start``
        where each cell's grains begin (``K D_0 D_1 D_2 + 1``); ``ok`` false (and no order) for
        a non-finite or exploded state, which the runner stops on."""
        n = p.shape[0]
        order = np.arange(n)
        key = np.zeros(n, np.int64)
        dims = np.ones(3, np.int64)
        start = np.zeros(2, np.int64)
        q = np.empty((n, 3))
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for i in range(n):
            q[i, 0] = p[i, 0] - bx
            q[i, 1] = p[i, 1] - by
            q[i, 2] = p[i, 2] - bz
            for k in range(3):
                if not math.isfinite(q[i, k]):
                    return False, order, key, start, dims
                lo[k] = min(lo[k], q[i, k])
                hi[k] = max(hi[k], q[i, k])
        for k in range(3):
            if not (hi[k] - lo[k] < 1e3):
                return False, order, key, start, dims
        side = cutoff
        d = np.empty(3, np.int64)
        while True:  # at most ~4 cells per grain (tall, sparse boxes), as _build_pairs
            for k in range(3):
                d[k] = int((hi[k] - lo[k]) / side) + 1
            if float(d[0]) * float(d[1]) * float(d[2]) <= 4 * n + 64:
                break
            side *= 1.5
        a0 = 0
        for k in range(1, 3):
            if d[k] > d[a0]:
                a0 = k
        a1 = 1 if a0 == 0 else 0
        a2 = 3 - a0 - a1
        dims[0], dims[1], dims[2] = d[a0], d[a1], d[a2]
        ncell = dims[0] * dims[1] * dims[2]
        start = np.zeros(K * ncell + 1, np.int64)
        cell = np.empty(n, np.int64)
        for i in range(n):
            c0 = int((q[i, a0] - lo[a0]) / side)
            c1 = int((q[i, a1] - lo[a1]) / side)
            c2 = int((q[i, a2] - lo[a2]) / side)
            cell[i] = ((cgw[i] * dims[0] + c0) * dims[1] + c1) * dims[2] + c2
            start[cell[i] + 1] += 1
        for c in range(K * ncell):
            start[c + 1] += start[c]
        fill = start[:-1].copy()
        for i in range(n):  # a stable counting sort: within a cell, the previous order
            order[fill[cell[i]]] = i
            fill[cell[i]] += 1
        for s in range(n):
            key[s] = cell[order[s]]
        return True, order, key, start, dims

    @_kernel()
    def _blocks(start, K, dims, n, target):
        """Block bounds ``bb`` (``nb + 1``) of grains in cell order: about ``target`` blocks of
        equal size, each made of whole layers (a damper cell's cells of one coordinate along
        the slowest axis). A listed pair spans at most one layer, so the pairs of block ``k``
        reach into blocks ``k`` and ``k + 1`` only (:func:`_sweep_each` builds on it)."""
        plane = dims[1] * dims[2]
        groups = K * dims[0]
        want = max(1, min(target, groups))
        bb = np.empty(want + 1, np.int64)
        bb[0] = 0
        nb = 0
        for g in range(groups):
            end = start[(g + 1) * plane]
            if end > bb[nb] and end * want >= (nb + 1) * n:
                nb += 1
                bb[nb] = end
        if bb[nb] < n:  # pragma: no cover - the last layer ends at n
            nb += 1
            bb[nb] = n
        return bb[:nb + 1]

    @_kernel()
    def _list_block(g0, g1, ref, R, extra, key, start, dims, ps, pe, pj, base, cap):
        """The half list of grains ``g0 … g1 − 1`` (in cell order, :func:`_spatial_order`) into
        ``pj[base:base + cap]``: grain ``i``'s partners are ``pj[ps[i]:pe[i]]``, the grains of
        its own cell after it and of the 13 cells ahead (:func:`half_stencil`) whose surfaces
        are closer than ``extra`` (``|r_i − r_j| < R_i + R_j + extra``, box frame ``ref``).
        Returns the number of pairs (more than ``cap``: the list did not fit)."""
        plane = dims[1] * dims[2]
        cells = dims[0] * plane
        k = base
        end = base + cap
        for i in range(U(g0), U(g1)):  # unsigned indices (:data:`U`)
            c = key[i]
            own = c % cells
            damper = c - own
            c2 = own % dims[2]
            c1 = (own // dims[2]) % dims[1]
            c0 = own // plane
            ps[i] = k
            for o in range(14):
                o0, o1, o2 = half_stencil(o)
                b0, b1, b2 = c0 + o0, c1 + o1, c2 + o2
                if b1 < 0 or b1 >= dims[1] or b2 < 0 or b2 >= dims[2] or b0 >= dims[0]:
                    continue
                cc = U(damper + (b0 * dims[1] + b1) * dims[2] + b2)
                for j in range(U(start[cc]), U(start[cc + U(1)])):
                    if o == 0 and j <= i:
                        continue
                    if listed(ref, R, i, j, extra):
                        if k < end:
                            pj[k] = j
                        k += 1
            pe[i] = min(k, end)
        return k - base

    def _lists_each(bb, per, counts, ref, R, extra, key, start, dims, ps, pe, pj):
        """:func:`_list_block` of every block (:func:`_over_cores`)."""
        for k in prange(bb.shape[0] - 1):
            counts[k] = _list_block(bb[k], bb[k + 1], ref, R, extra, key, start, dims, ps, pe,
                                    pj, bb[k] * per, (bb[k + 1] - bb[k]) * per)

    _lists_par, _lists_ser = _over_cores(_lists_each)

    @_kernel()
    def _permute(order, x, tmp):
        """Rows of ``x`` ``(n, c)`` into the order ``order`` (place ``s`` takes row
        ``order[s]``), through the scratch ``tmp`` (``n c``, of ``x``'s type)."""
        n, c = x.shape
        for s in range(n):
            for k in range(c):
                tmp[s * c + k] = x[order[s], k]
        for s in range(n):
            for k in range(c):
                x[s, k] = tmp[s * c + k]

    @_kernel()
    def _unsort(perm, src, dst):
        """``dst[perm[s]] = src[s]``: rows in cell order back to the user's grain numbers."""
        for s in range(src.shape[0]):
            for k in range(src.shape[1]):
                dst[perm[s], k] = src[s, k]

    @_kernel()
    def _walls_block(k, bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape, law,
                     r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T,
                     ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp):
        """Pass 1 of block ``k`` (grains ``bb[k] … bb[k + 1] − 1``): the predictor and
        :func:`grain_walls` (``F``, ``T`` set to the walls' forces); its sums into ``out[k]``
        (the last: whether a grain moved more than skin/2). ``sp``: ``None`` (the viscous
        law), or the walls' tangential springs ``(hw, vhf, shf, vh, sh, wg, zds)``
        (:func:`~jaxdamp.physics.containers._scalar.add_wall_scalar`; ``vhf``, ``shf`` the flat
        forms of ``vh``, ``sh``, set here for the block's grains), the block's spring totals
        into ``out[k, 12:16]``."""
        g0, g1 = U(bb[k]), U(bb[k + 1])  # unsigned indices (:data:`U`)
        for j in range(U(3) * g0, U(3) * g1):
            r1f[j] = rf[j] + dt * vf[j] + hdt2 * af[j]
            vpf[j] = vf[j] + dt * af[j]
        for j in range(U(3) * g0, U(3) * g1):
            rwf[j] = R3[j] * (wf[j] + dt * alf[j])
        if sp is not None:  # the springs: every grain's walls (a spring held away from them
            # too), the container and the cells as constants
            hw, vhf, shf, vh, sh, wg, zds = sp
            for j in range(U(3) * g0, U(3) * g1):
                vhf[j] = vf[j] + 0.5 * dt * af[j]
                shf[j] = R3[j] * (wf[j] + 0.5 * dt * alf[j])
            tot = out[k, 12:]
            for c in range(4):
                tot[c] = 0.0
            s = walls_in_cells(shifted, shape, law, g0, g1, r1, vp, rw, Rw, mw, ref, wk, wks, sec,
                               ogw, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz, (grav, drag),
                               half_skin2, (hw, vh, sh, wg, tot, zds, cgw, dt))
        # three copies, as in _advance_one: the container and the cells as constants fold the
        # branches of the common damper away (its walls pass: 34 -> 16.7 ns per grain, 50 000)
        elif shape == _BOX and not shifted:
            s = box_walls(law, g0, g1, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, gs, cgw,
                          frames, F, T, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2)
        else:
            s = walls_in_cells(shifted, shape, law, g0, g1, r1, vp, rw, Rw, mw, ref, wk, wks, sec,
                               ogw, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz, (grav, drag),
                               half_skin2, None)
        (out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5], out[k, 6], out[k, 7],
         out[k, 8], out[k, 9], out[k, 10], far) = s
        out[k, 11] = 1.0 if far else 0.0

    def _walls_each(bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape, law, r1,
                    vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T, ex,
                    ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp):
        """:func:`_walls_block` of every block (:func:`_over_cores`)."""
        for k in prange(bb.shape[0] - 1):  # k as int64: one compiled _walls_block for all
            _walls_block(np.int64(k), bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf,
                         shape, law, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs,
                         cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp)

    _walls_par, _walls_ser = _over_cores(_walls_each)

    @_kernel()
    def _walls_sums(nb, out):
        """The sums of pass 1 (:func:`grain_walls`' order) over blocks ``0 … nb − 1`` of
        ``out``, added block after block (the same numbers on any number of cores)."""
        s = np.zeros(12)
        for k in range(nb):
            for c in range(12):
                s[c] += out[k, c]
        return (s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10],
                s[11] > 0.0)

    @_kernel()
    def _block_sums(nb, out, c0):
        """The sums of columns ``c0 … c0 + 3`` of blocks ``0 … nb − 1`` of ``out`` (the
        springs' totals of :func:`_walls_block` and :func:`_pair_block`), block after block."""
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        for k in range(nb):
            s0 += out[k, c0]
            s1 += out[k, c0 + 1]
            s2 += out[k, c0 + 2]
            s3 += out[k, c0 + 3]
        return s0, s1, s2, s3

    @_kernel()
    def _walls_all(inner, bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape, law,
                   r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T, ex,
                   ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp):
        """Pass 1 of a large bed alone (:func:`_walls_block`; at the start of a call and after
        a rebuild: otherwise it runs in the previous step's sweep, :func:`_sweep_all`), the
        blocks over the cores where ``inner``; returns :func:`grain_walls`' sums (``sp``: the
        walls' springs, :func:`_walls_block`; their totals stay in ``out[:, 12:16]``,
        :func:`_block_sums`)."""
        if inner:
            _walls_par(bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape, law,
                       r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T,
                       ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp)
        else:
            _walls_ser(bb, out, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape, law,
                       r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T,
                       ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp)
        return _walls_sums(bb.shape[0] - 1, out)

    @_kernel()
    def _pair_block(k, bb, out, law, r, v, rw, R, m, sid, table, ps, pe, pj, F, T, gl, lossy,
                    sp):
        """Pass 2 of block ``k``: the forces and torques of its grains' listed pairs (half
        list in cell order, :func:`_list_block`; Newton's third law), added to ``F``, ``T``;
        the pair's constants formed where it touches (:func:`pair_constants`, as the device
        kernel does: a large bed's per-pair table would be streamed from memory every step).
        ``out[k]``: ``(elastic energy, normal loss, friction loss)`` and, with springs, the
        block's spring totals (:func:`pair_spring`'s ``tot``) in ``out[k, 3:7]``; where
        ``lossy`` (several damper cells), each grain's pairs' loss added to ``gl`` (as in
        :func:`_pair_forces`). ``sp``: ``None`` (the viscous law), or the tangential springs
        ``(hp, vh, sh, dt)``, ``hp`` a spring per slot of ``pj`` (:func:`pair_spring`)."""
        e_sum = 0.0
        ln_sum = 0.0
        lf_sum = 0.0
        tot = out[k, 3:]
        if sp is not None:
            for c in range(4):
                tot[c] = 0.0
        for i in range(U(bb[k]), U(bb[k + 1])):  # unsigned indices (:data:`U`)
            xi, yi, zi = r[i, 0], r[i, 1], r[i, 2]
            Ri = R[i]
            fxi = 0.0
            fyi = 0.0
            fzi = 0.0
            cxi = 0.0
            cyi = 0.0
            czi = 0.0
            li = 0.0
            for p in range(U(ps[i]), U(pe[i])):
                j = U(pj[p])
                dx = xi - r[j, 0]
                dy = yi - r[j, 1]
                dz = zi - r[j, 2]
                d2 = dx * dx + dy * dy + dz * dz
                rs = Ri + R[j]
                if d2 >= rs * rs and not held_pair(sp, p):
                    continue
                rs, kk, g, gamma_s, mu = pair_constants(law, table, U(sid[i]), U(sid[j]), Ri,
                                                        R[j], m[i], m[j])
                if sp is None:
                    fx, fy, fz, cx, cy, cz, e, ln, lf = pair_contact(
                        law, dx, dy, dz, d2, rs, v[i, 0] - v[j, 0], v[i, 1] - v[j, 1],
                        v[i, 2] - v[j, 2], rw[i, 0] + rw[j, 0], rw[i, 1] + rw[j, 1],
                        rw[i, 2] + rw[j, 2], kk, g, gamma_s, mu)
                else:
                    fx, fy, fz, cx, cy, cz, e, ln, lf = pair_spring(
                        law, dx, dy, dz, d2, rs, v[i, 0] - v[j, 0], v[i, 1] - v[j, 1],
                        v[i, 2] - v[j, 2], rw[i, 0] + rw[j, 0], rw[i, 1] + rw[j, 1],
                        rw[i, 2] + rw[j, 2], kk, g, mu, table[U(sid[i]), U(sid[j]), G_STAR],
                        Ri * R[j] / rs, (sp[0], sp[1], sp[2], tot, sp[3]), p, i, j)
                fxi += fx
                fyi += fy
                fzi += fz
                F[j, 0] -= fx
                F[j, 1] -= fy
                F[j, 2] -= fz
                cxi += cx
                cyi += cy
                czi += cz
                T[j, 0] -= R[j] * cx
                T[j, 1] -= R[j] * cy
                T[j, 2] -= R[j] * cz
                e_sum += e
                ln_sum += ln
                lf_sum += lf
                li += ln + lf
            F[i, 0] += fxi
            F[i, 1] += fyi
            F[i, 2] += fzi
            T[i, 0] -= Ri * cxi
            T[i, 1] -= Ri * cyi
            T[i, 2] -= Ri * czi
            if lossy:
                gl[i] += li
        out[k, 0], out[k, 1], out[k, 2] = e_sum, ln_sum, lf_sum

    @_kernel()
    def _correct_block(k, bb, out, dt, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf, alf, rf, r1f,
                       qs, qn):
        """Pass 3 (:func:`_correct`) of block ``k``'s grains; its finite check into
        ``out[k]``."""
        out[k] = _correct(bb[k], bb[k + 1], dt, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf, alf,
                          rf, r1f, qs, qn)

    @_kernel()
    def _chunks(nb, per):
        """Bounds (``c + 1``) of the sweep's chunks of about ``per`` (at least 2) consecutive
        blocks of ``nb``: a function of the blocks alone."""
        c = max(1, min(MAX_BLOCKS // 2, nb // per))
        cb = np.empty(c + 1, np.int64)
        for i in range(c + 1):
            cb[i] = (i * nb) // c
        return cb

    @_kernel()
    def _done_blocks(k0, k1, bb, nxt, hout, wout, dt, hdt2, w2, al2, wm, Ff, Tf, im3, iI3, vf,
                     af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, law, r1, vp, rw, Rw, mw,
                     ref, wk, wks, sec, ogw, shifted, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp,
                     Lz, grav, drag, half_skin2):
        """Blocks ``k0 … k1 − 1`` done (:func:`_sweep_each`): the corrector
        (:func:`_correct_block`) and, where ``nxt``, the next step's pass 1
        (:func:`_walls_block`)."""
        for k in range(k0, k1):
            _correct_block(k, bb, hout, dt, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf, alf, rf,
                           r1f, qs, qn)
            if nxt:
                _walls_block(k, bb, wout, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf, rwf, shape,
                             law, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw,
                             frames, F, T, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, None)

    def _sweep_each(phase, cb, bb, nxt, pout, hout, wout, law, r1, vp, rw, Rw, mw, sid, table,
                    ps, pe, pj, F, T, gl, dt, hdt2, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf,
                    alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, ref, wk, wks, sec, ogw, shifted,
                    gs, cgw, frames, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp):
        """One phase of a step's sweep (:func:`_sweep_all`; :func:`_over_cores`). A block is
        *done* by its corrector (:func:`_correct_block`) and, where ``nxt``, the next step's
        pass 1 (:func:`_walls_block`), once its forces are whole: after its own pairs and
        those of the block before it (:func:`_pair_block`; a block's pairs reach into the
        next block only). Phase 0, each chunk ``cb[c] … cb[c + 1] − 1`` on its own: block after
        block, its pairs, then the block done — but not a chunk's first block (the block
        before it is another chunk's) nor the pairs of its last (they reach into the next
        chunk). Phase 1, each place where two chunks meet: the pairs left out, then both
        blocks done. The places are two blocks apart at least, so no two threads write one
        grain."""
        nc = cb.shape[0] - 1
        if phase == 0:
            for c in prange(nc):
                s, e = cb[c], cb[c + 1]
                for k in range(s, e):
                    if k == e - 1 and c < nc - 1:
                        break
                    _pair_block(k, bb, pout, law, r1, vp, rw, Rw, mw, sid, table, ps, pe, pj, F,
                                T, gl, shifted, sp)
                    if k > s or c == 0:
                        _done_blocks(k, k + 1, bb, nxt, hout, wout, dt, hdt2, w2, al2, wm, Ff,
                                     Tf, im3, iI3, vf, af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf,
                                     shape, law, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw,
                                     shifted, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz, grav,
                                     drag, half_skin2)
        else:
            for c in prange(nc - 1):
                b = cb[c + 1]
                _pair_block(b - 1, bb, pout, law, r1, vp, rw, Rw, mw, sid, table, ps, pe, pj, F,
                            T, gl, shifted, sp)
                _done_blocks(b - 1, b + 1, bb, nxt, hout, wout, dt, hdt2, w2, al2, wm, Ff, Tf,
                             im3, iI3, vf, af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, law,
                             r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw, shifted, gs, cgw, frames,
                             F, T, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2)

    _sweep_par, _sweep_ser = _over_cores(_sweep_each)

    @_kernel()
    def _sweep_all(inner, cb, bb, nxt, pout, hout, wout, law, r1, vp, rw, Rw, mw, sid, table,
                   ps, pe, pj, F, T, gl, dt, hdt2, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf,
                   alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, ref, wk, wks, sec, ogw, shifted,
                   gs, cgw, frames, ex, ey, ez, z1, zdp, Lz, grav, drag, half_skin2, sp):
        """The rest of a large bed's step after pass 1 (:func:`_sweep_each`, the chunks over
        the cores where ``inner``): pass 2 (the pairs; their loss per grain into ``gl`` where
        ``shifted``), pass 3 (the corrector and the rotation into ``qn``) and, where ``nxt``,
        the next step's pass 1 (positions of the box ``z1``, ``zdp``, ``frames``; the grains'
        wall terms into ``gs``), every block's data read once. Returns the pairs' sums
        ``(elastic energy, normal loss, friction loss)``, the corrector's finite check (0 or
        NaN) and pass 1's sums (:func:`_walls_sums`; zeros where not ``nxt``), each added block
        after block."""
        for phase in range(2):
            if inner:
                _sweep_par(phase, cb, bb, nxt, pout, hout, wout, law, r1, vp, rw, Rw, mw, sid,
                           table, ps, pe, pj, F, T, gl, dt, hdt2, w2, al2, wm, Ff, Tf, im3, iI3,
                           vf, af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, ref, wk, wks,
                           sec, ogw, shifted, gs, cgw, frames, ex, ey, ez, z1, zdp, Lz, grav,
                           drag, half_skin2, sp)
            else:
                _sweep_ser(phase, cb, bb, nxt, pout, hout, wout, law, r1, vp, rw, Rw, mw, sid,
                           table, ps, pe, pj, F, T, gl, dt, hdt2, w2, al2, wm, Ff, Tf, im3, iI3,
                           vf, af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf, shape, ref, wk, wks,
                           sec, ogw, shifted, gs, cgw, frames, ex, ey, ez, z1, zdp, Lz, grav,
                           drag, half_skin2, sp)
        nb = bb.shape[0] - 1
        e = 0.0
        ln = 0.0
        lf = 0.0
        h = 0.0
        for k in range(nb):
            e += pout[k, 0]
            ln += pout[k, 1]
            lf += pout[k, 2]
            h += hout[k]
        return e, ln, lf, h, _walls_sums(nb if nxt else 0, wout)

    @_kernel()
    def _springs_csr(to_rows, n, ps, pe, pj, perm, hp, part, rows, table, sid, R):
        """A large bed's pair springs between its half lists (grains in cell order,
        :func:`_list_block`; ``hp`` a spring per slot of ``pj``) and the state's rows (the
        user's numbering): onto the rows where ``to_rows`` (:func:`_springs_out`), else from
        them onto the lists, by pair identity (:func:`_springs_in`). Returns the springs
        lost (no room in the rows, or no listed pair for a held one)."""
        P = pj.shape[0]
        ci = np.empty(P, np.int64)
        cj = np.empty(P, np.int64)
        ch = np.zeros((P, 3))
        nq = _csr_pairs(n, ps, pe, pj, perm, hp, ci, cj, ch, False)
        if to_rows:
            return _springs_out(ci, cj, ch, nq, part, rows)
        lost = _springs_in(ci, cj, ch, np.empty((P, 2)), nq, part, rows, table, sid, R)
        _csr_pairs(n, ps, pe, pj, perm, hp, ci, cj, ch, True)
        return lost

    @_kernel()
    def _moved(n, rf, vf, af, dt, hdt2, r1f, ref, bx, by, bz, half_skin2):
        """The predictor's positions ``r1f`` (as pass 1's, :func:`_walls_block`) and whether a
        grain moved more than skin/2 since the lists were built (box frame at ``(bx, by,
        bz)``): a large bed with springs decides its rebuild before pass 1, whose walls'
        springs must step once."""
        far = False
        for i in range(n):
            x = rf[3 * i] + dt * vf[3 * i] + hdt2 * af[3 * i]
            y = rf[3 * i + 1] + dt * vf[3 * i + 1] + hdt2 * af[3 * i + 1]
            z = rf[3 * i + 2] + dt * vf[3 * i + 2] + hdt2 * af[3 * i + 2]
            r1f[3 * i], r1f[3 * i + 1], r1f[3 * i + 2] = x, y, z
            dx = x - bx - ref[i, 0]
            dy = y - by - ref[i, 1]
            dz = z - bz - ref[i, 2]
            far = far | (dx * dx + dy * dy + dz * dz > half_skin2)
        return far

    @_kernel(inline="always")
    def _cell_steps(cdof, z, z1, yv, y1, dt, zds):
        """Each damper cell's walls' mean velocity along ``e`` over the step from ``(z, y)``
        to the predicted ``(z1, y1)`` (its degree of freedom ``cdof[c]``), into ``zds``: the
        velocity with which the walls' springs grow (as the JAX engine's ``step_vw``)."""
        for c in range(cdof.shape[0]):
            d = cdof[c]
            zds[c] = ((z1 - z) if d == 0 else (y1[d - 1] - yv[d - 1])) / dt

    @_kernel()
    def _cell_sums_by_grain(x, cg, out):
        """``out[c]`` = the sum of ``x`` over the grains of damper cell ``c`` (``cg``: each
        grain's cell; the large-bed path, whose grains are not stored cell after cell)."""
        for c in range(out.shape[0]):
            out[c] = 0.0
        for i in range(x.shape[0]):
            out[cg[i]] += x[i]

    @_kernel()
    def _reorder(p, bx, by, bz, cutoff, K, curved, r1f, rf, vf, wf, af, alf, qs, R3, im3, iI3,
                 Rw, mw, wk, wks, ogw, sidw, cgw, perm, sp):
        """Put a large bed's grains in cell order (:func:`_spatial_order` of the positions
        ``p``, box frame minus ``(bx, by, bz)``): every per-grain array of the kernel's
        working state is permuted alike (``perm``: the user's number of the grain at each
        place; ``wks`` only where the sides are ``curved``, else it is ``wk``; ``sp``: ``None``,
        or with tangential springs the walls' springs ``(N, 2 + W, 3)`` and the grains' spring
        constants ``wg (N, 3)``). Returns ``(ok, key, start, dims)`` of :func:`_spatial_order`
        (not ``ok``: left as it was)."""
        n = perm.shape[0]
        ok, order, key, start, dims = _spatial_order(p, bx, by, bz, cutoff, cgw, K)
        if not ok:
            return ok, key, start, dims
        tmp = np.empty(4 * n)
        for x in (r1f, rf, vf, wf, af, alf, R3, im3, iI3):
            _permute(order, x.reshape((n, 3)), tmp)
        _permute(order, qs.T, tmp)
        _permute(order, Rw.reshape((n, 1)), tmp)
        _permute(order, mw.reshape((n, 1)), tmp)
        _permute(order, wk, tmp)
        if curved:
            _permute(order, wks, tmp)
        _permute(order, ogw, tmp)
        if sp is not None:
            hw, wg = sp
            _permute(order, wg, tmp)
            wide = hw.reshape((n, hw.shape[1] * 3))
            _permute(order, wide, np.empty(wide.size))
        itmp = np.empty(n, np.int64)
        _permute(order, sidw.reshape((n, 1)), itmp)
        _permute(order, cgw.reshape((n, 1)), itmp)
        _permute(order, perm.reshape((n, 1)), itmp)
        return ok, key, start, dims

    @_kernel()
    def _relist(ok, p, bx, by, bz, extra, key, start, dims, K, R, ref, ps, pe, pj, per, inner,
                block, chunk):
        """The half lists of a large bed in cell order (after :func:`_reorder`), block by block
        (:func:`_blocks` of about ``block`` grains, :func:`_list_block`, over the cores where
        ``inner``), growing ``pj``
        (``per`` pairs per grain) until every block's fit; the reference positions ``ref`` =
        ``p`` in the box frame. Returns ``(block bounds, chunk bounds, per, pj)``: the sweep's
        chunks of about ``chunk`` blocks (:func:`_chunks`); no pairs where not ``ok``."""
        n = p.shape[0]
        for i in range(n):
            ref[i, 0] = p[i, 0] - bx
            ref[i, 1] = p[i, 1] - by
            ref[i, 2] = p[i, 2] - bz
        if not ok:
            bb = np.zeros(2, np.int64)
            bb[1] = n
            for i in range(n):
                ps[i] = 0
                pe[i] = 0
            return bb, _chunks(1, chunk), per, pj
        bb = _blocks(start, K, dims, n, min(MAX_BLOCKS, max(1, n // block)))
        nb = bb.shape[0] - 1
        counts = np.empty(nb, np.int64)
        while True:
            if pj.shape[0] < n * per:
                pj = np.empty(n * per, np.int32)
            if inner:
                _lists_par(bb, per, counts, ref, R, extra, key, start, dims, ps, pe, pj)
            else:
                _lists_ser(bb, per, counts, ref, R, extra, key, start, dims, ps, pe, pj)
            need = 0
            for k in range(nb):
                size = bb[k + 1] - bb[k]
                need = max(need, (counts[k] + size - 1) // size)
            if need <= per:
                return bb, _chunks(nb, chunk), per, pj
            per = need + need // 4 + 1

    @_kernel()
    def _advance_one(b, n_records, record_every, dims, skin, st, pm, so, po, sid, bounds, cg,
                     cdof, rec, inner, springs):
        """Advance system ``b`` of the packed batch by ``n_records × record_every`` steps in
        place, writing a sample after every ``record_every`` steps into ``rec[b]``
        (:func:`jaxdamp.physics.energy.record_row`; ``bounds``: the species' and cells' index
        ranges, :func:`~jaxdamp.physics.energy.cell_bounds`; ``cg``: each grain's cell,
        ``cdof``: each cell's degree of freedom in the engines' order, ``Model.cell_dofs``): row
        ``st[b]`` holds its state (the field NAME of ``State`` at ``so.NAME``), row ``pm[b]``
        its parameters (of ``Params`` at ``po.NAME``); ``dims`` (:data:`Dims`) selects the
        mount, the law and the container and sizes the views; ``sid`` the grains' species.

        The skeleton of :func:`jaxdamp.physics.integrate.step` in loops: the mount
        (:mod:`jaxdamp.physics.mounts`) predicts the box, then two passes over the grains and
        one over the listed pairs: (1) the velocity-Verlet predictor, gravity and drag, the
        floor, the lid and the container's sides (:mod:`jaxdamp.physics.containers`), the drag
        power and the displacement since the last list build (rebuilt from the predicted
        positions when a grain moved more than ``skin / 2``); (2) the pairs; (3) the mount's
        response to the grains' force and the corrector,
        with the finite-check of the new accelerations, then the rotation. Divisions by mass and
        inertia are multiplications by reciprocals computed once per call. The arithmetic
        without branches runs in loops that compile to SIMD code: the predictor and the
        corrector elementwise over the flat ``(3n,)`` views of the per-grain arrays, and the
        rotation (:func:`rotate_series_scalar`) over the quaternions held by component during
        the call (``qs``); the walls, the pairs and the sums stay grain by grain.

        A bed of :data:`LARGE` grains or more keeps its grains in cell order inside the call
        (:func:`_reorder` at the start and at every rebuild; records and the returned state in
        the user's numbering) and its step in one sweep over blocks of whole cell layers
        (:func:`_sweep_all`: the pairs, the corrector and the next step's pass 1 of a block
        while it is in the cache; pass 1 alone, :func:`_walls_all`, at the start and after a
        rebuild) and, where ``inner``, the sweep's chunks over the cores; its sums are added
        block after block, so its numbers do not depend on the cores nor on the batch it runs
        in. Every path predicts the box, the structure and the cells of the next step as soon
        as the mount has responded (the large path's sweep needs them).

        ``springs``: ``None`` (the viscous tangential law: no code for springs is compiled), or
        with tangential springs (:mod:`jaxdamp.physics.tangential`; any bed, any cells)
        ``(B,)`` integers, set to the number of springs a system lost (its state's rows were
        full, :func:`_springs_out`: the runner redoes the chunk with larger lists). The
        pairs' springs ride on the half list by pair identity (:func:`_springs_in` at the
        start and after each rebuild, :func:`_springs_out` before each rebuild and at the
        end), the walls' are the state's own rows, updated in place. A large bed keeps its
        pairs' springs one per slot of its lists (:func:`_springs_csr`) and its walls' in cell
        order (permuted with the grains), and runs pass 1 at the top of each step, after any
        rebuild (:func:`_moved`), not in the last step's sweep: pass 1 steps the walls'
        springs, so it must run once per step (the viscous law redoes it after a rebuild)."""
        n = sid.shape[0]
        row = st[b]  # so.NAME, po.NAME: where the field NAME starts in the rows
        prow = pm[b]
        mount, law, shape = dims.mount, dims.law, dims.shape
        prescribed = mount == _DRIVEN
        S, F, n_lines, ndof, n_section = (dims.n_species, dims.n_cols, dims.n_lines, dims.ndof,
                                          dims.n_section)
        rb = row[so.r:so.r + 3 * n].reshape((n, 3))
        vb = row[so.v:so.v + 3 * n].reshape((n, 3))
        wb = row[so.w:so.w + 3 * n].reshape((n, 3))
        qb = row[so.q:so.q + 4 * n].reshape((n, 4))
        alb = row[so.alpha:so.alpha + 3 * n].reshape((n, 3))
        ab = row[so.a:so.a + 3 * n].reshape((n, 3))
        work = row[so.work:so.work + N_CHANNELS]
        power = row[so.power:so.power + N_CHANNELS]
        K = dims.cells
        work_cell = row[so.work_cell:so.work_cell + K]
        power_cell = row[so.power_cell:so.power_cell + K]
        Rb = prow[po.radius:po.radius + n]
        mb = prow[po.mass:po.mass + n]
        Ib = prow[po.inertia:po.inertia + n]
        tab = prow[po.pair_table:po.pair_table + S * S * F].reshape((S, S, F))
        wtab = prow[po.wall_table:po.wall_table + S * F].reshape((S, F))
        Lz, grav = prow[po.Lz], prow[po.gravity]
        section = prow[po.section:po.section + n_section]  # the container's (containers)
        og = prow[po.origin:po.origin + 2 * n].reshape((n, 2))  # the grains' cells' corners
        one_cell = dims.cells == 1
        dt = prow[po.dt]
        drag, t_win = prow[po.drag], prow[po.t_window]
        ex, ey, ez = prow[po.ex], prow[po.ey], prow[po.ez]  # the excitation axis
        # a multi-DOF structure (ndof > 1): the other DOFs (views) and scratch of its size
        ny = ndof - 1
        yv = row[so.y:so.y + ny]
        ydv = row[so.yd:so.yd + ny]
        yddv = row[so.ydd:so.ydd + ny]
        y1 = np.empty(ny)
        ydp = np.empty(ny)
        xs = np.empty(ndof)
        xds = np.empty(ndof)
        acc = np.zeros(ndof)  # (z'', y''): y'' stays 0 where the mount does not move y
        tmp = np.empty(ndof)
        pi = np.empty(4 * n + 16, np.int64)  # grown by _pairs when a bed lists more
        pj = np.empty(4 * n + 16, np.int64)
        pc = np.empty((4 * n + 16, 5))
        wk = _wall_constants(Rb, mb, sid, wtab, law, 0.0)  # floor and lid: planes
        kappa = side_curvature_scalar(shape, section)
        sec = section_scalar(section)  # in registers for the grain loop, not reloaded per grain
        wks = wk if kappa == 0.0 else _wall_constants(Rb, mb, sid, wtab, law, kappa)
        inv_m = 1.0 / mb
        inv_I = 1.0 / Ib
        ref = np.empty((n, 3))
        z, zd, zdd, t = row[so.z], row[so.zd], row[so.zdd], row[so.t]
        e_start = row[so.e_start]
        zmax, zmin, step = row[so.z_max], row[so.z_min], row[so.step]
        # the skin: at least the model's, wider when grains are fast (a gas), so that a list
        # lasts about REBUILD_STEPS steps at the call's starting speeds (at most 2 R_max); a
        # wider skin lists more pairs but never changes which pairs touch
        v2 = 0.0
        for i in range(n):
            v2 = max(v2, (vb[i, 0] - ex * zd) ** 2 + (vb[i, 1] - ey * zd) ** 2
                     + (vb[i, 2] - ez * zd) ** 2)
        r_max = Rb.max() if n > 0 else 0.0
        skin = max(skin, min(2.0 * REBUILD_STEPS * math.sqrt(v2) * dt, 2.0 * r_max))
        cutoff = 2.0 * r_max + skin
        large = dims.large > 0
        npairs = 0
        if n > 1 and not large:
            npairs, pi, pj, pc = _pairs(rb, ex * z, ey * z, ez * z, cutoff, pi, pj, pc, ref, Rb,
                                        mb, sid, tab, law)
        # the springs: the pairs' on the list, the walls' in the state's rows (sized 0 without)
        ns = n if springs is not None else 0
        KS, NW = dims.slots, dims.walls
        spq = row[so.spring_partner:so.spring_partner + n * KS].reshape((n, KS))
        spp = row[so.spring_pair:so.spring_pair + 3 * n * KS].reshape((n, KS, 3))
        hw = row[so.spring_wall:so.spring_wall + 3 * n * NW].reshape((n, NW, 3))
        hp = np.zeros((pi.shape[0] if ns else 0, 3))
        pg = np.zeros((pi.shape[0] if ns else 0, 2))
        vhf = np.empty(3 * ns)  # the half-step velocities and R ω, with which they grow
        shf = np.empty(3 * ns)
        vh, sh = vhf.reshape((ns, 3)), shf.reshape((ns, 3))
        wg = np.empty((ns, 3))  # per grain (G*, R* of a plane, R* of the sides)
        tot = np.zeros(4)  # a step's turned energy, slip losses (pairs, walls), energy
        zds = np.zeros(K)
        inc = np.zeros(N_CHANNELS)
        lost = 0
        e_spring = 0.0
        if springs is not None:
            if not large:
                lost = _springs_in(pi, pj, hp, pg, npairs, spq, spp, tab, sid, Rb)
            for i in range(n):
                wg[i, 0] = wtab[sid[i], G_STAR]
                wg[i, 1] = Rb[i]
                wg[i, 2] = Rb[i] / (1.0 - Rb[i] * kappa)
            e_spring = row[so.e_spring]
        half_skin2 = 0.25 * skin * skin
        hdt2 = 0.5 * dt * dt
        # per-grain arrays (n, 3) and their flat views (3n): the predictor and the corrector
        # run elementwise over the flat ones, which compiles to SIMD code
        r1f = np.empty(3 * n)
        vpf = np.empty(3 * n)
        rwf = np.empty(3 * n)
        Ff = np.empty(3 * n)
        Tf = np.empty(3 * n)
        r1, vp, rw = r1f.reshape((n, 3)), vpf.reshape((n, 3)), rwf.reshape((n, 3))
        F, T = Ff.reshape((n, 3)), Tf.reshape((n, 3))
        rf, vf, wf = row[so.r:so.r + 3 * n], row[so.v:so.v + 3 * n], row[so.w:so.w + 3 * n]
        af, alf = row[so.a:so.a + 3 * n], row[so.alpha:so.alpha + 3 * n]
        R3 = np.empty(3 * n)
        im3 = np.empty(3 * n)
        iI3 = np.empty(3 * n)
        for j in range(3 * n):
            R3[j], im3[j], iI3[j] = Rb[j // 3], inv_m[j // 3], inv_I[j // 3]
        pw = np.zeros(N_CHANNELS)  # the channels the kernel never sets (springs) stay 0
        # several cells: each grain's loss power and force on its container, then each
        # cell's (pwc, bzc), and each cell's container's position and velocity along e
        gs = np.zeros((n, 2))
        pwc = np.empty(K)
        bzc = np.empty(K)
        frames = np.zeros((K, 2))
        spread = False  # cells on several degrees of freedom (else all on the box's)
        for c in range(K):
            spread = spread | (cdof[c] != 0)
        fdof = np.zeros(ndof)  # the grains' forces on the degrees of freedom
        # the quaternions by component (double-buffered) and the rotation's angular velocities
        qs = np.empty((4, n))
        qn = np.empty((4, n))
        wm = np.empty((3, n))
        for i in range(n):
            for k in range(4):
                qs[k, i] = qb[i, k]
        # the large-bed path (large): the working state in cell order, place s holding the
        # user's grain perm[s]; the parameters' per-grain rows copied (the inputs stay as they
        # are, read-only). A small bed works on the state's rows themselves and the parameters'
        # (perm the identity).
        perm = np.arange(n)
        Rw, mw, sidw, cgw, ogw = Rb.copy(), mb.copy(), sid.copy(), cg.copy(), og.copy()
        bb = np.zeros(2, np.int64)
        bb[1] = n
        cb = bb.copy()
        per = 8
        ps = np.zeros(n, np.int64)
        pe = np.zeros(n, np.int64)
        pl = np.empty(0, np.int32)
        wout = np.zeros((MAX_BLOCKS + 1, 16))  # pass 1's sums per block (and its springs')
        pout = np.zeros((MAX_BLOCKS + 1, 7))  # pass 2's (and its springs')
        # a large bed's springs: the walls' in cell order, the pairs' one per slot of its lists
        hwl = hw.copy() if large and springs is not None else hw
        hpl = np.zeros((0, 3))
        wsp = (0.0, 0.0, 0.0, 0.0)  # the walls' spring totals of the step's pass 1
        hout = np.empty(MAX_BLOCKS + 1)
        gn = np.zeros((n, 2))  # a large bed's gs of the next step (its sweep's pass 1)
        frames_rec = np.zeros((K, 2))
        # the first step's prediction of the box, the structure and the cells; each step
        # predicts the next one's once its own mount has responded (the large path's sweep
        # does the next step's pass 1)
        t1 = t + dt
        z1, zdp = _predict(mount, t1, dt, hdt2, z, zd, zdd, prow, po, yv, ydv, yddv, y1, ydp,
                           one_cell, cdof, frames)
        if springs is not None:
            _cell_steps(cdof, z, z1, yv, y1, dt, zds)
        ws = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False)
        if large:
            rf, vf, wf, af, alf = rf.copy(), vf.copy(), wf.copy(), af.copy(), alf.copy()
            ok, key, start, gdims = _reorder(rf.reshape((n, 3)), ex * z, ey * z, ez * z, cutoff,
                                             K, kappa != 0.0, r1f, rf, vf, wf, af, alf, qs, R3,
                                             im3, iI3, Rw, mw, wk, wks, ogw, sidw, cgw, perm,
                                             with_springs(springs, (hwl, wg)))
            bb, cb, per, pl = _relist(ok, rf.reshape((n, 3)), ex * z, ey * z, ez * z,
                                      cutoff - 2.0 * r_max, key, start, gdims, K, Rw, ref, ps,
                                      pe, pl, per, inner, dims.large, dims.chunk)
            if springs is not None:  # the pairs' springs onto the lists; pass 1 in the step
                hpl = np.zeros((pl.shape[0], 3))
                lost += _springs_csr(False, n, ps, pe, pl, perm, hpl, spq, spp, tab, sid, Rb)
            else:
                ws = _walls_all(inner, bb, wout, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf,
                                rwf, shape, law, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw,
                                not one_cell, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz,
                                grav, drag, half_skin2, None)
        r2, v2 = rf.reshape((n, 3)), vf.reshape((n, 3))
        w2, al2 = wf.reshape((n, 3)), alf.reshape((n, 3))
        e_el = 0.0
        floor_lid = 0.0
        box_z = 0.0
        n_floor = 0.0
        n_lid = 0.0
        n_side = 0.0
        for k_rec in range(n_records):
            imp0 = 0.0
            imp1 = 0.0
            for it in range(record_every):
                last = k_rec == n_records - 1 and it == record_every - 1
                # pass 1: predictor, body force, walls, drag power, displacement since the build
                if large and springs is not None:  # the rebuild first, then pass 1 once (it
                    # steps the walls' springs), never in the last step's sweep
                    if _moved(n, rf, vf, af, dt, hdt2, r1f, ref, ex * z1, ey * z1, ez * z1,
                              half_skin2) and n > 1:
                        lost += _springs_csr(True, n, ps, pe, pl, perm, hpl, spq, spp, tab, sid,
                                             Rb)
                        ok, key, start, gdims = _reorder(
                            r1, ex * z1, ey * z1, ez * z1, cutoff, K, kappa != 0.0, r1f, rf, vf,
                            wf, af, alf, qs, R3, im3, iI3, Rw, mw, wk, wks, ogw, sidw, cgw, perm,
                            (hwl, wg))
                        bb, cb, per, pl = _relist(ok, r1, ex * z1, ey * z1, ez * z1,
                                                  cutoff - 2.0 * r_max, key, start, gdims, K, Rw,
                                                  ref, ps, pe, pl, per, inner, dims.large,
                                                  dims.chunk)
                        if hpl.shape[0] < pl.shape[0]:
                            hpl = np.zeros((pl.shape[0], 3))
                        lost += _springs_csr(False, n, ps, pe, pl, perm, hpl, spq, spp, tab, sid,
                                             Rb)
                    ws = _walls_all(inner, bb, wout, dt, hdt2, rf, vf, af, wf, alf, R3, r1f, vpf,
                                    rwf, shape, law, r1, vp, rw, Rw, mw, ref, wk, wks, sec, ogw,
                                    not one_cell, gs, cgw, frames, F, T, ex, ey, ez, z1, zdp, Lz,
                                    grav, drag, half_skin2, (hwl, vhf, shf, vh, sh, wg, zds))
                    wsp = _block_sums(bb.shape[0] - 1, wout, 12)
                    (e_el, pw_n, pw_f, box_z, floor_lid, n_floor, n_lid, n_wall, l_floor, l_lid,
                     pdrag, far) = ws
                elif large:  # done by the last step's sweep; a rebuild re-sorts the grains and
                    # redoes it
                    if ws[11] and n > 1:
                        ok, key, start, gdims = _reorder(
                            r1, ex * z1, ey * z1, ez * z1, cutoff, K, kappa != 0.0, r1f, rf, vf,
                            wf, af, alf, qs, R3, im3, iI3, Rw, mw, wk, wks, ogw, sidw, cgw, perm,
                            None)
                        bb, cb, per, pl = _relist(ok, r1, ex * z1, ey * z1, ez * z1,
                                                  cutoff - 2.0 * r_max, key, start, gdims, K, Rw,
                                                  ref, ps, pe, pl, per, inner, dims.large,
                                                  dims.chunk)
                        ws = _walls_all(inner, bb, wout, dt, hdt2, rf, vf, af, wf, alf, R3, r1f,
                                        vpf, rwf, shape, law, r1, vp, rw, Rw, mw, ref, wk, wks,
                                        sec, ogw, not one_cell, gs, cgw, frames, F, T, ex, ey,
                                        ez, z1, zdp, Lz, grav, drag, half_skin2, None)
                    (e_el, pw_n, pw_f, box_z, floor_lid, n_floor, n_lid, n_wall, l_floor, l_lid,
                     pdrag, far) = ws
                else:
                    for j in range(3 * n):  # the predicted positions, velocities and R ω
                        r1f[j] = rf[j] + dt * vf[j] + hdt2 * af[j]
                        vpf[j] = vf[j] + dt * af[j]
                    for j in range(3 * n):
                        rwf[j] = R3[j] * (wf[j] + dt * alf[j])
                    if springs is not None:
                        for j in range(3 * n):
                            vhf[j] = vf[j] + 0.5 * dt * af[j]
                            shf[j] = R3[j] * (wf[j] + 0.5 * dt * alf[j])
                        for c in range(4):
                            tot[c] = 0.0
                    sp_w = with_springs(springs, (hw, vh, sh, wg, tot, zds, cg, dt))
                    # the walls compiled apart (walls_of), the container and the cells constants
                    # of the compiled code where they fold the branches: the common damper's box
                    # (its one cell), another one-cell container, several cells
                    if shape == _BOX and one_cell:
                        ws = walls_of(_BOX, law, U(0), U(n), U(1), r1, vp, rw, Rw, mw, ref, wk,
                                      wks, sec, ogw, False, gs, cg, frames, F, T, ex, ey, ez, z1,
                                      zdp, Lz, (grav, drag), half_skin2, sp_w)
                    elif one_cell:
                        ws = walls_of(shape, law, U(0), U(n), U(1), r1, vp, rw, Rw, mw, ref, wk,
                                      wks, sec, ogw, False, gs, cg, frames, F, T, ex, ey, ez, z1,
                                      zdp, Lz, (grav, drag), half_skin2, sp_w)
                    else:  # several cells: each grain's walls are its own cell's
                        ws = walls_of(shape, law, U(0), U(n), U(1), r1, vp, rw, Rw, mw, ref, wk,
                                      wks, sec, ogw, True, gs, cg, frames, F, T, ex, ey, ez, z1,
                                      zdp, Lz, (grav, drag), half_skin2, sp_w)
                    (e_el, pw_n, pw_f, box_z, floor_lid, n_floor, n_lid, n_wall, l_floor, l_lid,
                     pdrag, far) = ws
                    if n > 1 and far:  # a grain moved more than skin/2: list the pairs anew
                        if springs is not None:
                            lost += _springs_out(pi, pj, hp, npairs, spq, spp)
                        npairs, pi, pj, pc = _pairs(r1, ex * z1, ey * z1, ez * z1, cutoff, pi,
                                                    pj, pc, ref, Rb, mb, sid, tab, law)
                        if springs is not None:  # the springs onto the new list, by pair
                            if hp.shape[0] < pi.shape[0]:
                                hp = np.zeros((pi.shape[0], 3))
                                pg = np.zeros((pi.shape[0], 2))
                            lost += _springs_in(pi, pj, hp, pg, npairs, spq, spp, tab, sid, Rb)
                n_side = n_wall - n_floor - n_lid
                # the mount: its response to the grains' forces on the walls (pass 1), which
                # completes the step of the box and the structure
                if spread and large:  # each cell's force on its own degree of freedom
                    _cell_sums_by_grain(gs[:, 1], cgw, bzc)
                elif spread:
                    cell_sums(gs[:, 1], bounds, bzc, 0, 1)
                zdd1, pw[_IN], pw[_PRIM] = respond_scalar(
                    mount, t1, z1, zdp, y1, ydp, dof_loads(spread, cdof, bzc, box_z, fdof), prow,
                    po, n_lines, xs, xds, acc, tmp)
                zd1 = zdp if prescribed else zd + 0.5 * dt * (zdd + zdd1)
                for j in range(ny):
                    ydv[j] = ydv[j] + 0.5 * dt * (yddv[j] + acc[j + 1])
                    yddv[j] = acc[j + 1]
                    yv[j] = y1[j]
                if t1 >= t_win:
                    zmax = max(zmax, z1)
                    zmin = min(zmin, z1)
                z, zd, zdd, t = z1, zd1, zdd1, t1
                # the next step's prediction of the box, the structure and the cells
                t1 = t + dt
                z1, zdp = _predict(mount, t1, dt, hdt2, z, zd, zdd, prow, po, yv, ydv, yddv, y1,
                                   ydp, one_cell, cdof, frames)
                if springs is not None:
                    _cell_steps(cdof, z, z1, yv, y1, dt, zds)
                # pass 2, the grain pairs, and pass 3, the corrector and the rotation; a large
                # bed also does the next step's pass 1 while each block is in the cache (not
                # with springs: see above)
                if large:
                    nxt = not last
                    if springs is not None:
                        nxt = False
                    pp_e, pp_n, pp_f, h, ws = _sweep_all(
                        inner, cb, bb, nxt, pout, hout, wout, law, r1, vp, rw, Rw, mw, sidw, tab,
                        ps, pe, pl, F, T, gs[:, 0], dt, hdt2, w2, al2,
                        wm, Ff, Tf, im3, iI3, vf, af, wf, alf, rf, r1f, qs, qn, R3, vpf, rwf,
                        shape, ref, wk, wks, sec, ogw, not one_cell, gn, cgw, frames, ex, ey, ez,
                        z1, zdp, Lz, grav, drag, half_skin2,
                        with_springs(springs, (hpl, vh, sh, dt)))
                    if springs is not None:  # the step's spring totals: the walls', the pairs'
                        p0, p1, _, p3 = _block_sums(bb.shape[0] - 1, pout, 3)
                        tot[0] = wsp[0] + p0
                        tot[1] = p1
                        tot[2] = wsp[2]
                        tot[3] = wsp[3] + p3
                    if not one_cell:
                        _cell_sums_by_grain(gs[:, 0], cgw, pwc)
                        gs, gn = gn, gs
                else:
                    sp_p = with_springs(springs, (hp, pg, vh, sh, tot, dt))
                    if one_cell:  # its loss is the damper's: formed from the channels
                        pp_e, pp_n, pp_f = _pair_forces(law, r1, vp, rw, Rb, pi, pj, pc, npairs,
                                                        F, T, None, sp_p)
                    else:
                        pp_e, pp_n, pp_f = _pair_forces(law, r1, vp, rw, Rb, pi, pj, pc, npairs,
                                                        F, T, gs[:, 0], sp_p)
                        cell_sums(gs[:, 0], bounds, pwc, 0, 1)
                    h = _correct(np.int64(0), n, dt, w2, al2, wm, Ff, Tf, im3, iI3, vf, af, wf,
                                 alf, rf, r1f, qs, qn)
                qs, qn = qn, qs
                e_el += pp_e
                pw[_PPN], pw[_PPF], pw[_PWN], pw[_PWF] = pp_n, pp_f, pw_n, pw_f
                pw[_DRAG] = drag * pdrag
                pw[_PW_FLOOR], pw[_PW_LID] = l_floor, l_lid
                pw[_PW_SIDE] = pw_n + pw_f - l_floor - l_lid
                if springs is not None:  # the springs' slip and stiffness channels
                    pw[_PP_SLIP], pw[_PW_SLIP] = tot[1], tot[2]
                    pw[_STIFF] = (e_spring - tot[0]) / dt
                    e_spring = tot[3]
                if not math.isfinite(box_z + e_el + pp_n + pp_f + pw_n + pw_f + z + zd + zdd + h):
                    # the state blew up: mark it non-finite and stop; the runner reports it
                    for j in range(3 * n):
                        rf[j] = np.nan
                        vf[j] = np.nan
                    zd = np.nan
                    break
                if springs is None:
                    for c in range(N_CHANNELS):
                        work[c] = work[c] + 0.5 * dt * (power[c] + pw[c])
                        power[c] = pw[c]
                else:  # a step's own energies taken whole at its end (INCREMENT_OF)
                    for c in range(N_CHANNELS):
                        src = _INCREMENT_OF[c]
                        inc[c] = 0.5 * dt * (pw[src] - power[src]) if src >= 0 else 0.0
                    for c in range(N_CHANNELS):
                        work[c] = work[c] + 0.5 * dt * (power[c] + pw[c]) + inc[c]
                        power[c] = pw[c]
                if not one_cell:
                    for c in range(K):
                        work_cell[c] = work_cell[c] + 0.5 * dt * (power_cell[c] + pwc[c])
                        power_cell[c] = pwc[c]
                step += 1
                imp0 += floor_lid
                imp1 += box_z
            if one_cell:
                work_cell[0] = work[_PPN] + work[_PPF] + work[_PWN] + work[_PWF]
                power_cell[0] = power[_PPN] + power[_PPF] + power[_PWN] + power[_PWF]
            e_prim = energy_scalar(mount, t, z, zd, yv, ydv, prow, po, n_lines, xs, xds)
            if large:  # the sample reads the grains in the user's numbering
                _unsort(perm, r2, rb)
                _unsort(perm, v2, vb)
                _unsort(perm, w2, wb)
            record_row(rec[b, k_rec], t, z, zd, yv, e_prim, rb, vb, wb, mb, Ib, Rb, grav, Lz, ez,
                       e_el, e_start, imp0 / record_every, imp1 / record_every, n_floor, n_lid,
                       n_side, work, work_cell, bounds,
                       cell_frames(cdof, z, zd, yv, ydv, frames_rec))
        for i in range(n):
            for k in range(4):
                qb[perm[i], k] = qs[k, i]
        if large:
            for src, dst in ((r2, rb), (v2, vb), (w2, wb), (af.reshape((n, 3)), ab), (al2, alb)):
                _unsort(perm, src, dst)
        row[so.z], row[so.zd], row[so.zdd], row[so.t] = z, zd, zdd, t
        row[so.z_max], row[so.z_min], row[so.step] = zmax, zmin, step
        row[so.e_elastic], row[so.f_floor_lid], row[so.f_box] = e_el, floor_lid, box_z
        row[so.n_floor], row[so.n_lid], row[so.n_side] = n_floor, n_lid, n_side
        if springs is not None:
            if large:  # the pairs' springs and the walls' (cell order) into the state's rows
                if n > 1:
                    lost += _springs_csr(True, n, ps, pe, pl, perm, hpl, spq, spp, tab, sid, Rb)
                _unsort(perm, hwl.reshape((n, 3 * NW)), hw.reshape((n, 3 * NW)))
            elif n > 1:
                lost += _springs_out(pi, pj, hp, npairs, spq, spp)
            springs[b] = lost
            row[so.e_spring] = e_spring

    @_kernel(parallel=True)
    def _advance(n_records, record_every, dims, skin, st, pm, so, po, sid, bounds, cg, cdof, rec,
                 springs):
        """The batch over the cores (OpenMP threads, one system per thread at a time)."""
        inner = dims.large < 0  # False (the systems are over the cores), typed as the flag
        # of _advance_serial, and b as its int64: both share one compiled _advance_one (its
        # compile is most of the kernel's)
        for b in prange(st.shape[0]):
            _advance_one(np.int64(b), n_records, record_every, dims, skin, st, pm, so, po, sid,
                         bounds, cg, cdof, rec, inner, springs)

    @_kernel(nogil=True)
    def _advance_serial(n_records, record_every, dims, skin, st, pm, so, po, sid, bounds, cg, cdof,
                        rec, inner, springs):
        """The batch in the calling thread, without the GIL, one system after the other: for
        sharded chunks, whose host threads (one per local shard) call the kernel side by side,
        and (``inner``) for fewer large beds than cores, each spread over the cores itself."""
        for b in range(st.shape[0]):
            _advance_one(b, n_records, record_every, dims, skin, st, pm, so, po, sid, bounds, cg,
                         cdof, rec, inner, springs)


# -- packing of pytrees (one float64 array per call across the JAX/Python boundary) ---------


def layout(tree):
    """``[(field, shape without batch axis, dtype)]`` of a batched pytree dataclass."""
    return [(f.name, tuple(getattr(tree, f.name).shape[1:]), getattr(tree, f.name).dtype)
            for f in dataclasses.fields(tree)]


def pack(tree):
    """Batched pytree dataclass -> ``(B, total)`` float64 JAX array (integers exactly < 2^53)."""
    import jax.numpy as jnp

    leaves = [getattr(tree, f.name) for f in dataclasses.fields(tree)]
    b = leaves[0].shape[0]
    return jnp.concatenate([jnp.reshape(x, (b, int(np.prod(x.shape[1:], dtype=np.int64))))
                            .astype(jnp.float64) for x in leaves], axis=1)


def unpack_like(packed, tree):
    """Inverse of :func:`pack` in JAX, with ``tree`` giving shapes and dtypes."""
    import jax.numpy as jnp

    out, k = {}, 0
    for f in dataclasses.fields(tree):
        x = getattr(tree, f.name)
        size = int(np.prod(x.shape[1:], dtype=np.int64))
        out[f.name] = jnp.reshape(packed[:, k:k + size], x.shape).astype(x.dtype)
        k += size
    return type(tree)(**out)


def offsets(lay, names) -> np.ndarray:
    """Start of each field ``names`` in a packed row of layout ``lay`` (:func:`layout`)."""
    starts, k = {}, 0
    for name, shape, _ in lay:
        starts[name] = k
        k += int(np.prod(shape, dtype=np.int64))
    return np.array([starts[n] for n in names], np.int64)


def kernel_args(model, state_layout, param_layout):
    """What both kernels take beside the packed rows (this one and the device's,
    :mod:`jaxdamp.engine.fused`): ``(dims, state offsets, param offsets, species index,
    species' and cells' bounds, cell index, cells' degrees of freedom, sample width)``."""
    from jaxdamp.physics.contact import LAWS
    from jaxdamp.physics.energy import record_layout

    shapes = dict((name, shape) for name, shape, _ in param_layout)
    shapes_s = dict((name, shape) for name, shape, _ in state_layout)
    table = shapes["pair_table"]
    width = sum(int(np.prod(shape, dtype=np.int64)) for _, shape in record_layout(model))
    bounds = cell_bounds(model)
    dims = Dims(mount=mount_of(model).id, law=LAWS[model.law].id,
                shape=CONTAINERS[model.container].id, n_species=int(table[0]),
                n_cols=int(table[2]), n_lines=int(shapes["lines"][0]),
                ndof=int(shapes["s_r"][0]), n_section=int(shapes["section"][0]),
                cells=int(model.cells),
                large=int(BLOCK_GRAINS) if model.n >= max(LARGE, 2) else 0,
                chunk=max(2, int(CHUNK_BLOCKS)),
                slots=int(shapes_s["spring_partner"][1]) if model.springs else 0,
                walls=int(shapes_s["spring_wall"][1]) if model.springs else 0)
    return (dims, StateOffsets(*offsets(state_layout, STATE_FIELDS)),
            ParamOffsets(*offsets(param_layout, PARAM_FIELDS)),
            model.species_index().astype(np.int64), bounds,
            model.cell_index().astype(np.int64), model.dofs_of_cells(), width)


def _threads_up() -> bool:
    """Launch numba's threads (once per process) and say whether they run. A large bed alone
    starts its parallel regions from inside the serial :func:`_advance_serial`, which does not
    launch them itself (a parallel kernel called from Python does); a region started before
    they run calls a null pointer (found in this project; the shape of numba issue #8578).
    ``False`` (the blocks then run in the calling thread) if numba's internals moved."""
    try:
        from numba.np.ufunc.parallel import _launch_threads
    except ImportError:  # pragma: no cover - numba internals changed
        return False
    _launch_threads()
    return True


def advance_packed(model, state_packed, params_packed, state_layout, param_layout,
                   n_records: int, record_every: int, threads: bool = True,
                   device: int | None = None):
    """Advance a packed batch (:func:`pack`: ``(B, total)`` float64 rows of ``State`` and
    ``Params`` in the layouts ``state_layout``, ``param_layout``) by ``n_records ×
    record_every`` steps, sampling after every ``record_every``. Returns ``(new packed state,
    samples (B, n_records, width), lost (B,))``, the samples' columns in the order of
    :func:`jaxdamp.physics.energy.record_layout`, ``lost`` the tangential springs each
    system's rows had no room for (``model.springs``; the caller redoes the chunk with larger
    lists; zeros without springs); the inputs are not modified. The kernel
    works in place on one copy of the state: no per-field copies, no re-packing.
    ``threads=False``: the batch runs in the calling thread (no OpenMP), for callers that run
    several batches side by side in their own threads (sharded chunks). ``device``: the GPU
    of :func:`jaxdamp.engine.fused.advance_packed` (the same signature); unused here."""
    st = np.array(state_packed, dtype=np.float64, order="C", copy=True)
    pm = np.ascontiguousarray(params_packed, dtype=np.float64)
    dims, so, po, sid, bounds, cg, cdof, width = kernel_args(model, state_layout, param_layout)
    rec = np.empty((st.shape[0], int(n_records), width))
    lost = np.zeros(st.shape[0], np.int64)
    args = (int(n_records), int(record_every), dims, model.skin, st, pm, so, po, sid, bounds, cg,
            cdof, rec)
    springs = lost if model.springs else None  # None: no spring code compiled in
    # numba's threads up first: a kernel compiled against parallel callees loaded from the
    # cache (the spring form, after the viscous one was cached) links their scheduler, which
    # exists only once the threads are launched ("LLVM ERROR: Symbol not found:
    # allocate_sched" otherwise, found in this project)
    up = _threads_up()
    if threads and (not dims.large or st.shape[0] >= numba.get_num_threads()):
        _advance(*args, springs)  # the systems over the cores
    else:  # one after the other; large beds each over the cores (threads), or in this thread
        _advance_serial(*args, bool(threads and dims.large) and up, springs)
    return st, rec, lost


def compile_note(engine: str, springs: bool = False) -> str | None:
    """A one-line note when ``engine`` is ``"native"`` and the kernel has no on-disk cache yet
    (the first use after an install or an update compiles it: 2.7 minutes on a 2-core AMD EPYC
    for a driven bed's kernel, during which the first progress bar cannot move), or, with
    tangential springs (``springs``), no cached spring form (its own specialisation, about six
    minutes there the first time, ``benchmarks/RESULTS.md``), else ``None``."""
    if engine != "native" or not AVAILABLE:
        return None
    try:
        index = _advance._cache._cache_file  # numba internals
        cached = os.path.exists(index._index_path)
        if cached and springs:  # a cached signature whose last argument (springs) is not None
            digest = _source_hash() + ":parallel"
            cached = any(key[-1] == digest and not isinstance(key[0][-1], numba.types.NoneType)
                         for key in index._load_index())
    except Exception:  # numba's internals moved: say nothing rather than something wrong
        return None
    if cached:
        return None
    if springs:
        return ("compiling the native kernel's tangential-spring form once (about six minutes "
                "on 2 cores; cached for later runs) — the first progress bar starts after it")
    return ("compiling the native kernel once (about three minutes on 2 cores; cached for "
            "later runs) — the first progress bar starts after it")
