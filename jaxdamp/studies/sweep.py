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

A batch that does not fit the memory this process may use runs, with an output file, in waves
of whole grid points (:func:`sweep`, "Waves"; in one process), sized by the one estimator
:mod:`jaxdamp.engine.budget`.
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
from jaxdamp.engine import budget, driver
from jaxdamp.engine.choice import choose, stored_choice
from jaxdamp.engine.packing import settle_many
from jaxdamp.io.common import ensure_space, stop_file
from jaxdamp.io.sweepfile import StoredRecords, SweepFile, holds
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
from jaxdamp.validation import unused_note


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


def wave_budget(config: Config, sched, systems: int, replicates: int, out, snapshots: int = 0):
    """``(wave size, budget)`` of a sweep of ``systems`` systems: every system at once when the
    batch fits the memory this process may use (:func:`jaxdamp.engine.budget.largest`), else —
    with an output file, which holds every sample — the largest wave of whole grid points
    (``replicates`` systems each) that fits; the budget is that wave's memory and the whole
    sweep's file and time."""
    whole = batch_budget(config, sched, systems, out, snapshots)
    fits = budget.largest(lambda n: batch_budget(config, sched, n, out, snapshots), systems)
    if out is None or fits >= systems:
        return systems, whole
    size = max(replicates, fits // replicates * replicates)
    part = batch_budget(config, sched, size, out, snapshots)
    return size, dataclasses.replace(whole, memory=part.memory)


def sweep(config: Config, axes: dict, out: str | None = None, resume: bool = False,
          progress: bool = True, echo=print, shard: bool = True,
          max_chunks: int | None = None, snapshots: int = 0,
          replicates: int = 1, beds: dict | None = None,
          wave: int | None = None) -> SweepResult | None:
    """Run every grid point of ``axes`` (``{dotted key: values}``) as one batch, or in waves.

    Args:
      config: the base configuration.
      axes: one or two swept fields, e.g. ``{"frequency": [10, 12, 14], "box.Lz": [0.07, 0.12]}``.
      out: HDF5 file for the results (and the checkpoint); ``None`` keeps them in memory.
      resume: continue ``out`` from its checkpoint, skipping finished chunks (and waves).
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
      wave: systems per wave (a multiple of ``replicates``); ``None`` sizes it by itself.

    **Waves.** A sweep whose batch does not fit the memory this process may use
    (:func:`wave_budget`, the one estimator of :mod:`jaxdamp.engine.budget`) runs, with an
    output file, in waves of whole grid points, one after another: each wave settles its beds,
    runs every chunk and writes its samples, snapshots and per-system summaries
    (``/system_summary``) into its rows of the file; the checkpoint holds the running wave and
    its index, so ``resume`` continues inside the wave it stopped in. The summaries and the
    steady-state estimates are then made from the file, a wave at a time, and the result's
    ``records`` read rows from the file on demand (:class:`jaxdamp.io.sweepfile.StoredRecords`)
    instead of holding every sample.

    S3 configurations (``system = "impact"``) go to :func:`jaxdamp.s3.impact.sweep` (same result
    and file layout; ``resume``, ``shard``, ``max_chunks`` and ``wave`` do not apply: it runs
    whole).
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
    P = len(grid) * R
    if resume and out:  # across hosts: the writer closed the file before anyone reads it
        _barrier("jaxdamp-sweep-open")
    resuming = bool(resume and out and os.path.exists(out))
    if resuming:  # the waves the file was started with
        W = int(SweepFile.attrs_of(out).get("wave_size", P))
    elif wave is not None:
        W = int(wave)
        if W < R or W % R:
            raise ConfigError(f"wave = {W}: a wave holds whole grid points, a positive "
                              f"multiple of replicates = {R}")
        W = min(W, P)
    if not resuming:  # sized before any system is built
        first = grid[0]
        sched0 = schedule(first, config_dt(first, grain_radii(first)))
        size, cost = wave_budget(first, sched0, P, R, out, snapshots)
        W = size if wave is None else W
        budget.check(cost if W == size else dataclasses.replace(
            cost, memory=batch_budget(first, sched0, W, out, snapshots).memory), out, say)
    interrupt.check()
    configs = replicate_configs(grid, R)
    base = configs[0]
    radii = grain_radii(base)
    dt = min(config_dt(c, radii) for c in configs)
    sched = schedule(dataclasses.replace(
        base, numerics=dataclasses.replace(base.numerics, dt=dt)), dt)
    if (note := schedule_note(base, sched)) is not None:
        say(note)
    if (note := unused_note(base)) is not None:
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
    waves = [range(a, min(a + W, P)) for a in range(0, P, W)]
    if len(waves) > 1:
        say(f"{P} systems in {len(waves)} waves of {W} ("
            + ("wave = " + str(wave) if wave is not None and not resuming else
               "as the file was started" if resuming else
               "the whole batch needs more memory than this process may use") + ")")
    if len(waves) > 1 and jax.process_count() > 1:
        raise ConfigError(f"{P} systems need {len(waves)} waves of {W}, and a sweep in waves "
                          "runs in one process: run it on one host, or split the grid into "
                          "sweeps that fit each host's memory")
    choice = choose(base.numerics.engine, base.numerics.precision, batch=W,
                    tangential=base.tangential_law)
    if resuming:  # the engine the file was written with
        choice = stored_choice(SweepFile.attrs_of(out), choice)
    engine = choice.engine
    say(f"engine {engine} ({choice.reason})")

    sf = None
    writer = jax.process_index() == 0  # across hosts, process 0 writes the file
    start_wave, start_chunk, wall_before, arrays = 0, 0, 0.0, None
    if resuming:
        arrays, start_chunk, wall_before = SweepFile.checkpoint_of(out, config, axes, R)
        start_wave = SweepFile.wave_of(out)
        _barrier("jaxdamp-sweep-resume")  # every process has read before the writer opens
        if writer:
            sf, arrays, start_chunk, wall_before = SweepFile.resume(
                out, config, axes, R, sched.records_per_chunk, rows=waves[start_wave])
        say(f"resuming sweep at chunk {start_chunk}/{sched.n_chunks}"
            + (f" of wave {start_wave + 1}/{len(waves)}" if len(waves) > 1 else ""))
    elif out and writer:
        sf = SweepFile.create(out, config, axes, configs, dt, sched.duration, engine, R,
                              devices=len(jax.devices()), engine_reason=choice.reason,
                              wave_size=W)

    ctx = _Sweep(model=model, configs=configs, built=built, params=params, sched=sched,
                 engine=engine,
                 t_windows=t_windows, out=out, sf=sf, snapshots=snapshots, beds=beds,
                 progress=progress, say=say, shard=shard, P=P, waves=len(waves))
    wall0 = time.perf_counter()
    budget_chunks = math.inf if max_chunks is None else max_chunks
    last = None
    for w in range(start_wave, len(waves)):
        resumed = arrays if w == start_wave else None
        first_chunk = start_chunk if w == start_wave else 0
        done, result = ctx.run_wave(w, waves[w], first_chunk, resumed, budget_chunks,
                                    lambda: wall_before + time.perf_counter() - wall0)
        budget_chunks -= done
        if result is None:  # stopped by max_chunks
            if sf is not None:
                sf.set_status("partial")
                sf.close()
            return None
        last = result
    wall = wall_before + time.perf_counter() - wall0  # over every session of a resumed sweep
    return ctx.finish(grid, axes, R, last, wall)


@dataclasses.dataclass
class _Sweep:
    """What every wave of one sweep shares (:func:`sweep`)."""

    model: object
    configs: list
    built: list
    params: list
    sched: object
    engine: str
    t_windows: list
    out: str | None
    sf: SweepFile | None
    snapshots: int
    beds: dict | None
    progress: bool
    say: object
    shard: bool
    P: int
    waves: int

    def run_wave(self, w: int, rows: range, start_chunk: int, arrays, max_chunks, elapsed):
        """Run wave ``w`` (systems ``rows``) from ``start_chunk`` (``arrays``: its checkpoint,
        or ``None`` to settle and start it) for at most ``max_chunks`` chunks: ``(chunks run,
        in-memory result or None if stopped early)``; the result is ``(records, snapshots,
        final host states)`` of the wave (records and snapshots empty when a file holds
        them)."""
        model, sched, sf, out = self.model, self.sched, self.sf, self.out
        configs = [self.configs[i] for i in rows]
        n = len(configs)
        pb = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *[self.params[i] for i in rows])
        sharding, padded = _mesh_sharding(n) if self.shard else (None, n)
        pb_s = _pad_and_shard(pb, padded, sharding)
        drive = dict(engine=self.engine, multiplier=configs[0].numerics.capacity_multiplier,
                     place=lambda tree: _pad_and_shard(tree, padded, sharding))
        part = rows if self.waves > 1 else None  # the file's rows of this wave
        if arrays is not None:
            batch = driver.restore(model, pb, arrays, **drive).replace(params=pb_s)
        else:
            batch = self._start(rows, pb, pb_s, drive, part, w, elapsed)
        mem: dict = {}
        snaps: dict = {}

        def keep(chunk, batch, recs):
            if out:  # gathered by every process (a collective across hosts), written by one
                arrays = driver.checkpoint(batch, n)
            if sf is not None:
                ensure_space(out, sum(np.asarray(v).nbytes
                                      for v in (*recs.values(), *arrays.values())))
                sf.append_records(recs, at=chunk * sched.records_per_chunk, rows=part,
                                  total=self.P)
                sf.write_checkpoint(arrays, chunk + 1, elapsed(), wave=w)
            if chunk >= sched.n_chunks - self.snapshots:
                _keep_snapshot(sf, snaps, batch.states, n, part, self.P)
            if sf is None:
                for k, v in recs.items():
                    mem.setdefault(k, []).append(v)

        def diverged(e):
            if sf is not None:  # the file keeps every finished chunk and its checkpoint
                sf.set_status("diverged", str(e) + (f" (wave {w + 1}/{self.waves}, systems "
                                                    f"{rows.start}-{rows.stop - 1})"
                                                    if part else ""))
                sf.close()

        def interrupted():
            if sf is not None:  # every finished chunk and its checkpoint are in the file
                sf.set_status("interrupted", "stopped by Ctrl-C; --resume continues from the "
                              "last checkpoint")
                sf.close()

        stop = int(min(sched.n_chunks, start_chunk + max_chunks))
        label = f"sweep of {n} systems" + (f", wave {w + 1}/{self.waves}" if part else "")
        try:
            batch = driver.run_chunks(
                batch, range(start_chunk, stop), sched.records_per_chunk, sched.record_every,
                systems=n, on_chunk=keep, on_diverged=diverged, on_interrupt=interrupted,
                total=sched.n_chunks, progress=label if self.progress else None)
        except OSError as err:  # the disk filled (or went away): keep what the file holds
            if sf is not None:
                stop_file(sf, str(err))
            raise
        if stop < sched.n_chunks:
            return stop - start_chunk, None
        final = jax.tree_util.tree_map(lambda x: x[:n], driver.to_host(batch.states))
        if sf is not None and part is not None:  # this wave's summaries, before the next
            sf.write_system_summary(*self._summaries(rows, sf.records(part), final),
                                    rows=part, total=self.P)
            return stop - start_chunk, ({}, {}, None)
        records = (sf.records() if sf is not None
                   else {k: np.concatenate(v, axis=1) for k, v in mem.items()})
        if sf is not None:
            snaps = sf.snapshots() or snaps
        else:
            snaps = {k: np.stack(v, axis=1 if k != "t" else 0) for k, v in snaps.items()}
        return stop - start_chunk, (records, snaps, final)

    def _start(self, rows, pb, pb_s, drive, part, w, elapsed):
        """Settle the new beds of the wave ``w`` (systems ``rows``, one batch) and start it;
        writes its ``/settle`` rows and the settled checkpoint."""
        model, sf, say = self.model, self.sf, self.say
        configs = [self.configs[i] for i in rows]
        built = [self.built[i] for i in rows]
        keys = [geometry_key(c) for c in configs]
        beds = {} if self.beds is None else self.beds
        first = {k: i for i, k in reversed(list(enumerate(keys))) if k not in beds}
        order = sorted(first.values())  # one new bed per geometry, all settled in one batch
        if order:
            if (note := driver.compile_note(self.engine, model.tangential)):
                say(note)
            settled = settle_many([configs[i] for i in order], model,
                                  [built[i][1] for i in order],
                                  progress=(f"settling {len(order)} bed(s) of {model.n} grains"
                                            if self.progress and model.n else None))
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
            r0.append(bed_with_box(c, bed.r, x))
            v0.append(bed.v), w0.append(bed.w), q0.append(bed.q), z0.append(x), zd0.append(xd)
        batch = driver.start(model, pb, np.stack(r0), np.stack(v0), np.stack(w0), np.stack(q0),
                             np.stack(z0), np.stack(zd0), **drive).replace(params=pb_s)
        start_arrays = driver.checkpoint(batch, len(configs)) if self.out else None
        if sf is not None:
            sf.write_settle([beds[k] for k in keys], [c.numerics.settle_speed for c in configs],
                            rows=part, total=self.P)
            sf.write_checkpoint(start_arrays, 0, elapsed(), wave=w)  # resumable from here
        return batch

    def _summaries(self, rows: range, records: dict, final) -> tuple[list[dict], dict]:
        """Fixed-window summaries of the systems ``rows`` (their records, final host states)
        and their units."""
        out, units = [], {}
        for j, i in enumerate(rows):
            rec = {k: v[j] for k, v in records.items()}
            s, units = steady_state_summary(self.configs[i], rec, driver.take(final, j),
                                            self.t_windows[i], self.sched.duration)
            out.append(s)
        return out, units

    def finish(self, grid, axes, R, last, wall) -> SweepResult:
        """The summaries, steady-state estimates and result of a finished sweep (``last``:
        what :meth:`run_wave` returned for the last wave)."""
        sf, configs = self.sf, self.configs
        shape = grid_shape(axes)
        if last[2] is not None:  # one wave, in memory
            records, snaps, final = last
            summaries, units = self._summaries(range(self.P), records, final)
        else:  # waves: per-system summaries from the file, records read on demand
            summaries, units = sf.system_summaries()
            records, snaps = StoredRecords(self.out), sf.snapshots()
        per_rep = {k: np.array([s[k] for s in summaries]).reshape(shape + (R,))
                   for k in summaries[0]}
        summary = {k: v.mean(axis=-1) for k, v in per_rep.items()}
        summary["wall_time"] = wall
        estimates = []
        for g in range(len(grid)):  # a grid point's replicates, read together
            rows = range(g * R, (g + 1) * R)
            rec = (sf.records(rows) if isinstance(records, StoredRecords)
                   else {k: v[rows.start:rows.stop] for k, v in records.items()})
            estimates.append(stats.steady([
                stats.per_period({k: v[j] for k, v in rec.items()}, configs[i].frequency,
                                 channels=stats.CHANNELS) for j, i in enumerate(rows)]))
        steady = stats.to_arrays(estimates, shape)
        if sf is not None:
            sf.write_summary(summary, units, per_rep, steady, R, stats.unit)
            sf.finish(wall)
            sf.close()
        return SweepResult(axes=axes, configs=grid, summary=summary, records=records,
                           path=self.out, snapshots=snaps or None, replicates=R,
                           replicate_summary=per_rep, steady=steady)


def _keep_snapshot(sf, mem: dict, states, P: int, rows=None, total=None) -> None:
    """The batch's positions, velocities and box heights now: into the file's
    ``/snapshots`` (resumable; ``rows`` of ``total`` systems for a wave) or into ``mem``."""
    host = driver.to_host({"t": states.t, "r": states.r, "v": states.v, "z_box": states.z})
    t = float(host.pop("t")[0])
    per_point = {k: x[:P] for k, x in host.items()}
    if sf is not None:
        sf.append_snapshot(t, per_point, rows=rows, total=total)
        return
    mem.setdefault("t", []).append(t)
    for k, x in per_point.items():
        mem.setdefault(k, []).append(x)
