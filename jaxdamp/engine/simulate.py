"""Batched, jitted chunks of the time loop: ``lax.scan`` over steps, records every few steps.

Everything here works on a *batch* of ``B`` independent systems (``B = 1`` for a single run):
states, params and neighbour lists carry a leading batch axis. The physics step is
``vmap``-ed; each system's neighbour list is rebuilt when its own grains moved (:mod:`jaxdamp.engine.neighbors`).

A chunk runs ``n_records × record_every`` steps and returns the states, neighbour lists and
``n_records`` samples per system (:func:`jaxdamp.physics.energy.record`). Allocating the
neighbour lists, redoing a chunk whose lists overflowed and every other host-side step of the
time loop is the driver's (:mod:`jaxdamp.engine.driver`).
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.engine import history
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.choice import resolve_engine
from jaxdamp.physics.energy import record
from jaxdamp.physics.integrate import box_frame, initial_state, step
from jaxdamp.physics.model import Model, Params, State


@functools.lru_cache(maxsize=64)
def chunk_fn(model: Model, n_records: int, record_every: int, remat: bool = False,
             engine: str = "jax", sharding: jax.sharding.NamedSharding | None = None):
    """Jitted ``(states, nbrs, params) -> (states, nbrs, records)`` for a batch.

    ``records`` is a dict of arrays shaped ``(B, n_records, ...)``. With ``remat`` each
    inner block of ``record_every`` steps is rematerialised in reverse mode (bounded memory for
    gradients through long scans). ``engine="native"`` advances the whole chunk in the compiled
    CPU kernel, samples included, in one host callback (forward only; the neighbour lists in
    ``nbrs`` then only set the springs' layout); ``engine="fused"`` the same through the CUDA
    kernel of :mod:`jaxdamp.engine.fused` (one launch per chunk). ``sharding``: the batch's
    sharding over several devices (the batch axis split over a mesh axis); the JAX engine's
    jit partitions by itself, the kernels advance every local shard in its own host thread
    and put the results back on the shards' devices.
    """
    resolved = resolve_engine(engine, model.precision, tangential=model.tangential)
    if resolved in ("native", "fused"):
        return _packed_chunk(model, n_records, record_every, sharding, resolved)
    block = _jax_block(model, record_every)
    if remat:
        block = jax.checkpoint(block)
    record_b = jax.vmap(record, in_axes=(0, 0, None, 0))

    def outer(carry, _, params):
        states, nbrs = carry
        states, nbrs, mean_forces = block(states, nbrs, params)
        return (states, nbrs), record_b(states, params, model, mean_forces)

    @jax.jit
    def run(states, nbrs, params):
        if model.springs:  # springs written against other lists (a start, a re-allocation)
            states, nbrs = _rekeyed(states, nbrs)
        (states, nbrs), recs = jax.lax.scan(
            functools.partial(outer, params=params), (states, nbrs), None, length=n_records
        )
        recs = jax.tree_util.tree_map(lambda x: jnp.swapaxes(x, 0, 1), recs)
        return states, nbrs, recs

    return run


def _rekeyed(states, nbrs):
    """The states' springs carried over to the lists ``nbrs`` by pair identity
    (:func:`jaxdamp.engine.history.rekey`); a history the lists would lose marks them
    overflowed (the driver redoes the chunk with larger lists)."""
    states, lost = history.rekey(states, nbrs.idx)
    return states, dataclasses.replace(nbrs, overflow=nbrs.overflow | (lost > 0))


def _rekeyed_fresh(model, states, nbrs, params):
    """:func:`_rekeyed` onto lists brought up to the states' positions first
    (:func:`jaxdamp.engine.neighbors.update`): the compiled kernels keep their own lists, so
    the JAX lists they are handed are those of the chunk before or older. Rekeyed onto a stale
    list, the springs of pairs that met since were counted lost, every chunk redone with
    lists 1.5× larger each time (a resonant thesis bed went from 18 to 222 slots per grain in
    0.8 s, its chunks 10× the viscous law's instead of 3×)."""
    nbrs = nb.update(model, nbrs, box_frame(states, params, params.dt), params.radius)
    return _rekeyed(states, nbrs)


def _jax_block(model: Model, record_every: int):
    """``(states, nbrs, params) -> (states, nbrs, mean forces)``: ``record_every`` steps of
    the pure-JAX step; the mean forces are the grains' vertical forces on floor + lid and on
    the whole box averaged over the block. With tangential springs a rebuilt list takes their
    history over by pair identity (:func:`jaxdamp.engine.history.rekey`); a history the new
    list would lose counts as an overflow (the driver redoes the chunk with larger lists)."""
    step_b = jax.vmap(step, in_axes=(0, 0, 0, None))

    def block(states, nbrs, params):
        def inner(carry, _):
            states, nbrs, impulse = carry
            nbrs = nb.update(model, nbrs, box_frame(states, params, params.dt), params.radius)
            if model.springs:
                states, nbrs = _rekeyed(states, nbrs)
            states = step_b(states, nbrs.idx, params, model)
            impulse = impulse + jnp.stack([states.f_floor_lid, states.f_box], axis=-1)
            return (states, nbrs, impulse), None

        b = states.t.shape[0]
        (states, nbrs, impulse), _ = jax.lax.scan(
            inner, (states, nbrs, jnp.zeros((b, 2))), None, length=record_every
        )
        return states, nbrs, impulse / record_every

    return block


def _packed_chunk(model: Model, n_records: int, record_every: int,
                  sharding: jax.sharding.NamedSharding | None = None, kernel: str = "native"):
    """The chunk through a kernel on packed rows, the numba CPU kernel
    (:mod:`jaxdamp.engine.native`, ``kernel="native"``) or the CUDA one
    (:mod:`jaxdamp.engine.fused`, ``"fused"``, which copies the rows to its device and back
    inside the callback, once per chunk): one host callback
    advances the whole chunk and writes the samples itself
    (:func:`jaxdamp.physics.energy.record_row`, the scalar form of ``record``), so a chunk
    crosses the JAX/Python boundary once, not once per sample. State and parameters cross as
    two packed float64 arrays (:func:`jax.pure_callback` costs ~35 µs per array); the
    neighbour lists are passed through (the kernel keeps its own; with tangential springs they
    give the springs' rows their layout, and a spring the rows had no room for flags them
    overflowed, so that the driver redoes the chunk with larger ones).

    With ``sharding`` (batch split over devices, possibly over processes) there is no callback:
    the packed batch is computed sharded, every local shard is copied to the host and advanced
    by the kernel in its own thread without OpenMP (``threads=False``: the shards run side by
    side, one core each; a process with a single local device keeps the OpenMP kernel), and
    the results are put back on the shards' devices. (A ``pure_callback`` inside ``shard_map``
    puts its operands on CPU device 0 first; with two devices that transfer waited on device
    0's own callback and deadlocked about one run in two.)"""
    from jaxdamp.engine import native
    from jaxdamp.physics.energy import INT_RECORDS, record_layout

    if kernel == "fused":
        from jaxdamp.engine import fused as module
    else:
        module = native
    rec_layout = record_layout(model)
    width = sum(int(np.prod(shape, dtype=np.int64)) for _, shape in rec_layout)

    def advance(sp, pp, state_layout, param_layout, threads=True, device=None):
        return module.advance_packed(model, sp, pp, state_layout, param_layout, n_records,
                                     record_every, threads=threads, device=device)

    def unpack(new, flat, states):
        recs, k = {}, 0
        for name, shape in rec_layout:
            size = int(np.prod(shape, dtype=np.int64))
            x = jnp.reshape(flat[:, :, k:k + size], (flat.shape[0], n_records) + shape)
            recs[name] = x.astype(jnp.int32) if name in INT_RECORDS else x
            k += size
        return native.unpack_like(new, states), recs

    def lost_springs(nbrs, lost):  # springs the kernel had no room for: larger lists
        return dataclasses.replace(nbrs, overflow=nbrs.overflow | (lost > 0))

    if sharding is None:
        def run(states, nbrs, params):
            if model.springs:  # the springs in the layout of these lists (as the JAX engine's)
                states, nbrs = _rekeyed_fresh(model, states, nbrs, params)
            lay = native.layout(states), native.layout(params)
            sp, pp = native.pack(states), native.pack(params)
            shapes = (jax.ShapeDtypeStruct(sp.shape, sp.dtype),
                      jax.ShapeDtypeStruct((sp.shape[0], n_records, width), jnp.float64),
                      jax.ShapeDtypeStruct((sp.shape[0],), jnp.int64))
            # the callback may hand over jax Arrays: np.asarray once (slicing them would
            # dispatch JAX ops); the kernel reads the fields at their offsets in the rows
            new, flat, lost = jax.pure_callback(
                lambda a, b: advance(np.asarray(a), np.asarray(b), *lay), shapes, sp, pp)
            states, recs = unpack(new, flat, states)
            return states, lost_springs(nbrs, lost), recs

        return jax.jit(run)

    import concurrent.futures

    threads = len(sharding.addressable_devices) == 1
    pack = jax.jit(lambda states, params: (native.pack(states), native.pack(params)),
                   out_shardings=(sharding, sharding))
    finish = jax.jit(unpack, out_shardings=(sharding, sharding))
    pool = concurrent.futures.ThreadPoolExecutor(len(sharding.addressable_devices))

    rekeyed = jax.jit(functools.partial(_rekeyed_fresh, model))

    def run_sharded(states, nbrs, params):
        if model.springs:
            states, nbrs = rekeyed(states, nbrs, params)
        lay = native.layout(states), native.layout(params)
        sp, pp = pack(states, params)
        pairs = list(zip(sp.addressable_shards, pp.addressable_shards, strict=True))
        # the fused kernel runs each shard on the shard's own GPU (numba's ordinal)
        done = list(pool.map(lambda ab: advance(
            np.asarray(ab[0].data), np.asarray(ab[1].data), *lay, threads=threads,
            device=(ab[0].device.local_hardware_id if ab[0].device.platform == "gpu"
                    else None)), pairs))
        devices = [a.device for a, _ in pairs]
        new, flat = (jax.make_array_from_single_device_arrays(
            (sp.shape[0],) + done[0][i].shape[1:], sharding,
            [jax.device_put(d[i], dev) for d, dev in zip(done, devices, strict=True)])
            for i in (0, 1))
        states, recs = finish(new, flat, states)
        lost = np.concatenate([d[2] for d in done])
        if lost.any():
            nbrs = lost_springs(nbrs, jax.device_put(lost, nbrs.overflow.sharding))
        return states, nbrs, recs

    return run_sharded


def init_states(model: Model, params: Params, r, v, w, q, z, zd, t=0.0, idx=None) -> State:
    """Batched initial states, forces evaluated once over the neighbour blocks ``idx``
    ``(B, N, K)`` (any superset of the touching pairs gives the same forces; the driver passes
    lists built on the host, linear in ``N``). ``idx=None``: every pair, the brute-force
    reference — ``O(N²)`` memory, for small beds only."""
    if idx is None:
        one = _all_pairs_idx(model)
        f = jax.vmap(lambda r_, v_, w_, q_, z_, zd_, p_: initial_state(
            r_, v_, w_, q_, z_, zd_, t, one, p_, model))
        return jax.jit(f)(r, v, w, q, z, zd, params)
    f = jax.vmap(lambda r_, v_, w_, q_, z_, zd_, p_, i_: initial_state(
        r_, v_, w_, q_, z_, zd_, t, i_, p_, model))
    return jax.jit(f)(r, v, w, q, z, zd, params, jnp.asarray(idx))


def _all_pairs_idx(model: Model):
    from jaxdamp.physics.pairs import all_pairs

    return all_pairs(model.n) if model.n >= 2 else jnp.zeros((model.n, 0), jnp.int32)
