"""Batched sweeps: many independent simulations of one damper at once (FRFs, ``Lz`` scans).

A sweep varies one or two numeric configuration fields over a grid (e.g. ``frequency`` ×
``box.Lz``). All points share the grains (so one static ``Model``), the time step (the smallest
any point needs) and the sampling; everything else is a per-point ``Params`` array, and the
points run together as one batch through the driver (:func:`jaxdamp.engine.driver.advance`:
``vmap`` for the JAX engine, ``prange`` over cores for the native one).

The bed is settled once per distinct geometry (grains, base, walls, seed — not ``Lz``, not the
excitation). The batch axis is sharded over every device JAX sees
(:func:`jax.sharding.NamedSharding` on a 1-D mesh, batch padded to a multiple of the device
count), so the same code runs on one CPU, several GPUs, or several hosts after
``jax.distributed.initialize()``. The native engine runs its kernel on every device's shard.
Across processes every process runs the same call on its own shards; the samples are gathered
to every process after each chunk and only process 0 writes ``out`` (the others return the
same result from memory). Between chunks: progress, overflow handling (in ``advance``)
and a checkpoint; ``resume=True`` skips finished chunks.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp import interrupt
from jaxdamp.analysis import stats
from jaxdamp.analysis.response import analysis_start, steady_state_summary
from jaxdamp.config import Config, ConfigError
from jaxdamp.engine import budget, driver, native
from jaxdamp.engine.choice import choose, stored_choice
from jaxdamp.engine.packing import settle_many
from jaxdamp.io.common import ensure_space, stop_file
from jaxdamp.io.sweepfile import SweepFile, holds
from jaxdamp.physics.containers import container
from jaxdamp.physics.model import build, config_dt, grain_radii
from jaxdamp.studies.grid import (
    SweepResult,
    geometry_key,
    grid_configs,
    grid_shape,
    replicate_configs,
)
from jaxdamp.studies.runner import (
    batch_budget,
    bed_with_box,
    initial_structure,
    schedule,
    schedule_note,
)


def _mesh_sharding(batch: int):
    devices = jax.devices()
    if len(devices) == 1:
        return None, batch
    mesh = jax.sharding.Mesh(np.array(devices), ("batch",))
    padded = int(math.ceil(batch / len(devices)) * len(devices))
    return jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch")), padded


def _pad_and_shard(tree, padded, sharding):
    def one(x):
        if sharding is not None and not getattr(x, "is_fully_addressable", True):
            return x  # already spread over the processes, padded
        xp = jnp if sharding is None else np  # sharded: host data, each process puts its shards
        x = xp.asarray(x)
        if x.shape[0] < padded:  # repeat the last point: padding systems are valid, ignored
            x = xp.concatenate([x, xp.repeat(x[-1:], padded - x.shape[0], axis=0)])
        return jax.device_put(x, sharding) if sharding is not None else x

    return jax.tree_util.tree_map(one, tree)


def _barrier(name: str) -> None:
    """Wait for every process of a sweep across hosts (no-op in one process)."""
    if jax.process_count() > 1:
        from jax.experimental import multihost_utils

        multihost_utils.sync_global_devices(name)


def reuse_or_run(config: Config, axes: dict, out: str, **kwargs) -> SweepResult:
    """:func:`sweep` into ``out``, reusing what is there: a finished file of the same sweep is
    read back without computing (its compute time kept), a partial one is resumed, anything
    else is replaced. For experiments whose raw sweeps outlive a figure or a kill."""
    return sweep(config, axes, out=out,
                 resume=holds(out, config, axes, kwargs.get("replicates", 1)), **kwargs)


def impact_budget(config: Config, points: int, out=None):
    """The :class:`jaxdamp.engine.budget.Budget` of an S3 sweep of ``points`` points: every
    point's samples held until the end — measured 6 MB per point of the thesis' 13.12 s at
    peak (`frf --preset sanchez2012-impact --n 100000`: 10.8 GB after 1 800 points), i.e.
    one copy of its 16 float64 scalars per sample — and about 6 µs of wall per sample (30
    points in about 10 s)."""
    samples = int(config.numerics.duration / config.numerics.record_dt) + 1
    return budget.estimate(systems=points, grains=0, steps=samples, samples=samples,
                           sample_bytes=128, record_copies=1, seconds_per_step=6e-6,
                           out=out is not None)


def sweep(config: Config, axes: dict, out: str | None = None, resume: bool = False,
          progress: bool = True, echo=print, shard: bool = True,
          max_chunks: int | None = None, snapshots: int = 0,
          replicates: int = 1, beds: dict | None = None) -> SweepResult | None:
    """Run every grid point of ``axes`` (``{dotted key: values}``) as one batch.

    Args:
      config: the base configuration.
      axes: one or two swept fields, e.g. ``{"frequency": [10, 12, 14], "box.Lz": [0.07, 0.12]}``.
      out: HDF5 file for the results (and the checkpoint); ``None`` keeps them in memory.
      resume: continue ``out`` from its checkpoint, skipping finished chunks.
      progress: tqdm progress bar over chunks.
      shard: shard the batch over all JAX devices (no-op with one device).
      max_chunks: stop after this many chunks (leaving ``out`` to resume); returns ``None``
        if the sweep is not finished.
      snapshots: keep grain positions and velocities at the ends of the last this many chunks
        (``/snapshots`` in the file; e.g. chunks of a quarter drive period and 4 snapshots give
        the bed at the drive's turning points and at its largest speeds).
      replicates: independent realisations per grid point: beds settled from the seeds
        :func:`jaxdamp.analysis.stats.replicate_seed` ``(seed, 0..R-1)``, run in the same batch.
      beds: a cache of settled beds by geometry, filled and reused across calls (repeated
        sweeps of one damper, e.g. an optimiser's evaluations, settle each bed once).

    S3 configurations (``system = "impact"``) go to :func:`jaxdamp.s3.impact.sweep` (same result
    and file layout; ``resume``, ``shard`` and ``max_chunks`` do not apply: it runs whole).
    """
    if config.system == "impact":  # S3: the single-particle model of jaxdamp.s3.impact
        from jaxdamp.s3 import impact

        if replicates != 1:
            raise ConfigError(f"replicates = {replicates}: the single-particle model (S3) is "
                              "deterministic, one realisation is exact (use replicates = 1)")

        budget.check(impact_budget(config, math.prod(grid_shape(axes)), out), out, echo)
        return impact.sweep(config, axes, out=out, progress=progress, echo=echo)
    say = echo or (lambda *a, **k: None)
    grid = grid_configs(config, axes)
    R = int(replicates)
    if not (resume and out and os.path.exists(out)):  # sized before any system is built
        first = grid[0]
        sched0 = schedule(first, config_dt(first, grain_radii(first)))
        budget.check(batch_budget(first, sched0, len(grid) * R, out, snapshots), out, say)
    interrupt.check()
    configs = replicate_configs(grid, R)
    base = configs[0]
    radii = grain_radii(base)
    dt = min(config_dt(c, radii) for c in configs)
    sched = schedule(dataclasses.replace(
        base, numerics=dataclasses.replace(base.numerics, dt=dt)), dt)
    if (note := schedule_note(base, sched)) is not None:
        say(note)
    built = [build(c, radii) for c in configs]
    model = built[0][0]
    for (m, _), c in zip(built, configs):
        if m != model:
            raise ConfigError("swept fields must not change the grains or the system "
                              f"(point {c.to_json()[:80]}... differs)")
    t_windows = [analysis_start(c, sched.duration) for c in configs]
    params = [dataclasses.replace(p, dt=jnp.asarray(dt), t_window=jnp.asarray(tw))
              for (_, p), tw in zip(built, t_windows)]
    pb = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *params)
    P = len(configs)
    sharding, padded = _mesh_sharding(P) if shard else (None, P)
    # native: one kernel call per shard
    choice = choose(base.numerics.engine, base.numerics.precision, batch=P)
    if resume and out and os.path.exists(out):  # the engine the file was written with
        choice = stored_choice(SweepFile.attrs_of(out), choice)
    engine = choice.engine
    say(f"engine {engine} ({choice.reason})")
    pb_s = _pad_and_shard(pb, padded, sharding)
    drive = dict(engine=engine, multiplier=base.numerics.capacity_multiplier,
                 place=lambda tree: _pad_and_shard(tree, padded, sharding))

    sf = None
    start_chunk = 0
    writer = jax.process_index() == 0  # across hosts, process 0 writes the file
    if resume and out and os.path.exists(out):
        arrays, start_chunk, wall_before = SweepFile.checkpoint_of(out, config, axes, R)
        _barrier("jaxdamp-sweep-resume")  # every process has read before the writer opens
        if writer:
            sf, arrays, start_chunk, wall_before = SweepFile.resume(
                out, config, axes, R, sched.records_per_chunk)
        batch = driver.restore(model, pb, arrays, **drive).replace(params=pb_s)
        say(f"resuming sweep at chunk {start_chunk}/{sched.n_chunks}")
    else:
        wall_before = 0.0
        keys = [geometry_key(c) for c in configs]
        beds = {} if beds is None else beds
        first = {k: i for i, k in reversed(list(enumerate(keys))) if k not in beds}
        order = sorted(first.values())  # one new bed per geometry, all settled in one batch
        if order:
            if (note := native.compile_note(engine)):
                say(note)
            settled = settle_many([configs[i] for i in order], model,
                                  [built[i][1] for i in order],
                                  progress=(f"settling {len(order)} bed(s) of {model.n} grains"
                                            if progress and model.n else None))
            beds.update({keys[i]: b for i, b in zip(order, settled)})
            say(f"settled {len(order)} bed(s) in one batch: heights "
                + ", ".join(f"{b.height:.5g}" for b in settled) + " m")
            moving = [(i, b) for i, b in zip(order, settled) if model.n and not b.settled]
            if moving:
                say(f"warning: {len(moving)} of {len(order)} bed(s): "
                    + moving[0][1].unsettled_note(configs[moving[0][0]])
                    + "; the sweep file says so (/settle/settled)")
        r0, v0, w0, q0, z0, zd0 = [], [], [], [], [], []
        for c, (m, p), key in zip(configs, built, keys):
            bed = beds[key]
            vessel = container(c)
            if m.n and bed.height >= vessel.height(c):
                raise ConfigError(f"{vessel.lid_key} = {vessel.height(c)} m: the settled bed "
                                  f"({bed.height:.5g} m) "
                                  "does not fit")
            x, xd = initial_structure(c, float(np.asarray(p.mass).sum()))
            r0.append(bed_with_box(c, bed.r, x[0]))
            v0.append(bed.v), w0.append(bed.w), q0.append(bed.q), z0.append(x), zd0.append(xd)
        batch = driver.start(model, pb, np.stack(r0), np.stack(v0), np.stack(w0), np.stack(q0),
                             np.stack(z0), np.stack(zd0), **drive).replace(params=pb_s)
        start_arrays = driver.checkpoint(batch, P) if out else None  # a collective
        if out and writer:
            sf = SweepFile.create(out, config, axes, configs, dt, sched.duration, engine, R,
                                  devices=len(jax.devices()), engine_reason=choice.reason)
            sf.write_settle([beds[k] for k in keys], [c.numerics.settle_speed for c in configs])
            sf.write_checkpoint(start_arrays, 0, 0.0)  # resumable from the settled start

    wall0 = time.perf_counter()
    mem: dict = {}
    snaps: dict = {}

    def keep(chunk, batch, recs):
        if out:  # gathered by every process (a collective across hosts), written by one
            arrays = driver.checkpoint(batch, P)
        if sf is not None:
            ensure_space(out, sum(np.asarray(v).nbytes for v in (*recs.values(), *arrays.values())))
            sf.append_records(recs)
            sf.write_checkpoint(arrays, chunk + 1, wall_before + time.perf_counter() - wall0)
        if chunk >= sched.n_chunks - snapshots:
            _keep_snapshot(sf, snaps, batch.states, P)
        for k, v in recs.items():
            mem.setdefault(k, []).append(v)

    def diverged(e):
        if sf is not None:  # the file keeps every finished chunk and its checkpoint
            sf.set_status("diverged", str(e))
            sf.close()

    def interrupted():
        if sf is not None:  # every finished chunk and its checkpoint are in the file
            sf.set_status("interrupted", "stopped by Ctrl-C; --resume continues from the "
                          "last checkpoint")
            sf.close()

    stop = sched.n_chunks if max_chunks is None else min(sched.n_chunks, start_chunk + max_chunks)
    try:
        batch = driver.run_chunks(
            batch, range(start_chunk, stop), sched.records_per_chunk, sched.record_every,
            systems=P, on_chunk=keep, on_diverged=diverged, on_interrupt=interrupted,
            total=sched.n_chunks, progress=f"sweep of {P} systems" if progress else None)
    except OSError as err:  # the disk filled (or went away): keep what the file holds
        if sf is not None:
            stop_file(sf, str(err))
        raise
    if stop < sched.n_chunks:
        if sf is not None:
            sf.set_status("partial")
            sf.close()
        return None
    wall = wall_before + time.perf_counter() - wall0  # over every session of a resumed sweep
    if sf is not None:
        records = sf.records()
        snaps = sf.snapshots() or snaps
    else:
        records = {k: np.concatenate(v, axis=1) for k, v in mem.items()}
        snaps = {k: np.stack(v, axis=1 if k != "t" else 0) for k, v in snaps.items()}
    final = jax.tree_util.tree_map(lambda x: x[:P], driver.to_host(batch.states))
    summaries, series = [], []
    for i, c in enumerate(configs):
        rec_i = {k: v[i] for k, v in records.items()}
        s, units = steady_state_summary(c, rec_i, driver.take(final, i), t_windows[i], sched.duration)
        summaries.append(s)
        series.append(stats.per_period(rec_i, c.frequency, channels=stats.CHANNELS))
    shape = grid_shape(axes)
    per_rep = {k: np.array([s[k] for s in summaries]).reshape(shape + (R,)) for k in summaries[0]}
    summary = {k: v.mean(axis=-1) for k, v in per_rep.items()}
    summary["wall_time"] = wall
    steady = stats.to_arrays(
        [stats.steady(series[g * R:(g + 1) * R]) for g in range(len(grid))], shape)
    if sf is not None:
        sf.write_summary(summary, units, per_rep, steady, R, stats.unit)
        sf.finish(wall)
        sf.close()
    return SweepResult(axes=axes, configs=grid, summary=summary, records=records, path=out,
                       snapshots=snaps or None, replicates=R, replicate_summary=per_rep,
                       steady=steady)


def _keep_snapshot(sf, mem: dict, states, P: int) -> None:
    """The batch's positions, velocities and box heights now: into the file's
    ``/snapshots`` (resumable) or into ``mem``."""
    host = driver.to_host({"t": states.t, "r": states.r, "v": states.v, "z_box": states.z})
    t = float(host.pop("t")[0])
    per_point = {k: x[:P] for k, x in host.items()}
    if sf is not None:
        sf.append_snapshot(t, per_point)
        return
    mem.setdefault("t", []).append(t)
    for k, x in per_point.items():
        mem.setdefault(k, []).append(x)
