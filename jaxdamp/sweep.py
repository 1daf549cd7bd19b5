"""Batched sweeps: many independent simulations of one damper at once (FRFs, ``Lz`` scans).

A sweep varies one or two numeric configuration fields over a grid (e.g. ``frequency`` ×
``box.Lz``). All points share the grains (so one static ``Model``), the time step (the smallest
any point needs) and the sampling; everything else is a per-point ``Params`` array, and the
points run together as one batch through :func:`jaxdamp.simulate.advance`
(``vmap`` for the JAX engine, ``prange`` over cores for the native one).

The bed is settled once per distinct geometry (grains, base, walls, seed — not ``Lz``, not the
excitation). The batch axis is sharded over every device JAX sees
(:func:`jax.sharding.NamedSharding` on a 1-D mesh, batch padded to a multiple of the device
count), so the same code runs on one CPU, several GPUs, or several hosts after
``jax.distributed.initialize()``. Between chunks: progress, overflow handling (in ``advance``)
and a checkpoint; ``resume=True`` skips finished chunks.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import time
from dataclasses import dataclass

import h5py
import jax
import jax.numpy as jnp
import numpy as np

from . import __version__
from . import neighbors as nb
from .analysis import analysis_start, steady_state_summary
from .config import Config, ConfigError, apply_overrides
from .integrate import box_frame
from .io import arrays_to_state, state_to_arrays
from .model import build, config_dt, grain_radii
from .packing import settle
from .runner import initial_box_position, schedule
from .simulate import advance, init_states, resolve_engine, take
from .validation import validate


@dataclass
class SweepResult:
    """``axes``: ``{key: values}``; ``configs``: one per point (grid order, last axis fastest);
    ``summary``: ``{name: array shaped like the grid}``; ``records``: per-point samples
    (dict of arrays ``(P, T)``); ``path``: the HDF5 file or ``None``; ``snapshots``: with
    ``sweep(..., snapshots=k)``, ``{"t": (k,), "r": (P, k, N, 3), "v": (P, k, N, 3), "z_box": (P, k)}`` at the
    ends of the last ``k`` chunks, else ``None``."""

    axes: dict
    configs: list
    summary: dict
    records: dict
    path: str | None
    snapshots: dict | None = None


def grid_configs(config: Config, axes: dict) -> list[Config]:
    """One configuration per grid point (``itertools.product`` order), each validated."""
    keys = list(axes)
    if not 1 <= len(keys) <= 2:
        raise ConfigError(f"a sweep takes one or two axes, got {keys}")
    out = []
    for values in itertools.product(*(axes[k] for k in keys)):
        out.append(validate(apply_overrides(config, dict(zip(keys, map(float, values))))))
    return out


def _geometry_key(cfg: Config) -> str:
    """What the settled bed depends on (not Lz, not the excitation)."""
    d = cfg.to_dict()
    num = d["numerics"]
    keep = {k: num[k] for k in ("seed", "stiffness_scale", "skin", "capacity_multiplier",
                                "settle_time", "settle_speed", "settle_drag", "engine")}
    return json.dumps([d["grains"], d["box"]["Lx"], d["box"]["Ly"], d["box"]["wall"],
                       d["gravity"], d["mixing"], keep], sort_keys=True)


def _mesh_sharding(batch: int):
    devices = jax.devices()
    if len(devices) == 1:
        return None, batch
    mesh = jax.sharding.Mesh(np.array(devices), ("batch",))
    padded = int(math.ceil(batch / len(devices)) * len(devices))
    return jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch")), padded


def _pad_and_shard(tree, padded, sharding):
    def one(x):
        x = jnp.asarray(x)
        if x.shape[0] < padded:  # repeat the last point: padding systems are valid, ignored
            x = jnp.concatenate([x, jnp.repeat(x[-1:], padded - x.shape[0], axis=0)])
        return jax.device_put(x, sharding) if sharding is not None else x

    return jax.tree_util.tree_map(one, tree)


def _axes_json(axes: dict) -> str:
    return json.dumps({k: list(map(float, v)) for k, v in axes.items()})


def write_header(h5, config: Config, axes: dict, configs: list, dt: float, duration: float,
                 engine: str) -> None:
    """The root attributes of a sweep file (``docs/output.md``), shared by every model."""
    h5.attrs["format"] = "jaxdamp-sweep/1"
    h5.attrs["jaxdamp_version"] = __version__
    h5.attrs["base_config"] = config.to_json()
    h5.attrs["axes"] = _axes_json(axes)
    h5.attrs["configs"] = json.dumps([c.to_json() for c in configs])
    h5.attrs["dt"] = dt
    h5.attrs["duration"] = duration
    h5.attrs["engine"] = engine


def holds(path: str, config: Config, axes: dict) -> bool:
    """Whether the sweep file ``path`` exists and holds the sweep ``(config, axes)``."""
    if not os.path.exists(path):
        return False
    try:
        with h5py.File(path, "r") as h5:
            return (h5.attrs.get("base_config") == config.to_json()
                    and h5.attrs.get("axes") == _axes_json(axes) and "checkpoint" in h5)
    except OSError:  # not an HDF5 file (e.g. cut short while being created)
        return False


def reuse_or_run(config: Config, axes: dict, out: str, **kwargs) -> SweepResult:
    """:func:`sweep` into ``out``, reusing what is there: a finished file of the same sweep is
    read back without computing (its compute time kept), a partial one is resumed, anything
    else is replaced. For experiments whose raw sweeps outlive a figure or a kill."""
    return sweep(config, axes, out=out, resume=holds(out, config, axes), **kwargs)


def sweep(config: Config, axes: dict, out: str | None = None, resume: bool = False,
          progress: bool = True, echo=print, shard: bool = True,
          max_chunks: int | None = None, snapshots: int = 0) -> SweepResult | None:
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

    S3 configurations (``system = "impact"``) go to :func:`jaxdamp.impact.sweep` (same result
    and file layout; ``resume``, ``shard`` and ``max_chunks`` do not apply: it runs whole).
    """
    if config.system == "impact":  # S3: the single-particle model of jaxdamp.impact
        from . import impact

        return impact.sweep(config, axes, out=out, progress=progress, echo=echo)
    say = echo or (lambda *a, **k: None)
    configs = grid_configs(config, axes)
    base = configs[0]
    radii = grain_radii(base)
    dt = min(config_dt(c, radii) for c in configs)
    sched = schedule(dataclasses.replace(
        base, numerics=dataclasses.replace(base.numerics, dt=dt)), dt)
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
    engine = resolve_engine(base.numerics.engine)
    if sharding is not None and engine == "native":
        engine = "jax"  # host callbacks do not partition over devices; use the JAX step
    pb_s = _pad_and_shard(pb, padded, sharding)

    h5 = None
    start_chunk = 0
    if resume and out and os.path.exists(out):
        h5 = h5py.File(out, "a")
        if h5.attrs["base_config"] != config.to_json() or h5.attrs["axes"] != _axes_json(axes):
            h5.close()
            raise ConfigError(f"--resume: {out} holds a different sweep")
        g = h5["checkpoint"]
        start_chunk = int(g.attrs["chunk"])
        # compute time already spent on this sweep (older files: the finished summary's)
        wall_before = float(h5.attrs.get("wall_time", h5["summary/wall_time"][()]
                                         if "summary/wall_time" in h5 else 0.0))
        arrays = {}
        g.visititems(lambda n, o: arrays.__setitem__(n, o[()]) if isinstance(o, h5py.Dataset) else None)
        states, nbrs = arrays_to_state(arrays)
        states = _pad_and_shard(states, padded, sharding)
        nbrs = _pad_and_shard(nbrs, padded, sharding)
        for ds in h5["records"].values():
            ds.resize(start_chunk * sched.records_per_chunk, axis=1)
        say(f"resuming sweep at chunk {start_chunk}/{sched.n_chunks}")
    else:
        wall_before = 0.0
        beds = {}
        r0, v0, w0, q0, z0 = [], [], [], [], []
        for c, (m, p) in zip(configs, built):
            key = _geometry_key(c)
            if key not in beds:
                beds[key] = settle(c, m, p)
                say(f"settled bed {len(beds)}: height {beds[key].height:.5g} m")
            bed = beds[key]
            if m.n and bed.height >= c.box.Lz:
                raise ConfigError(f"box.Lz = {c.box.Lz} m: the settled bed ({bed.height:.5g} m) "
                                  "does not fit")
            z = initial_box_position(c, float(np.asarray(p.mass).sum()))
            r0.append(bed.r + np.array([0.0, 0.0, z]))
            v0.append(bed.v), w0.append(bed.w), q0.append(bed.q), z0.append(z)
        states = init_states(model, pb, np.stack(r0), np.stack(v0), np.stack(w0), np.stack(q0),
                             jnp.asarray(z0), jnp.zeros(P))
        nbrs = nb.allocate(model, box_frame(states), base.numerics.capacity_multiplier,
                            radius=pb.radius)
        states = _pad_and_shard(states, padded, sharding)
        nbrs = _pad_and_shard(nbrs, padded, sharding)
        if out:
            h5 = h5py.File(out, "w")
            write_header(h5, config, axes, configs, dt, sched.duration, engine)
            h5.attrs["devices"] = len(jax.devices())
            h5.create_group("records")

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=sched.n_chunks, initial=start_chunk, unit="chunk",
                   desc=f"sweep of {P} points")
    wall0 = time.perf_counter()
    mem: dict = {}
    snaps: dict = {}
    stop = sched.n_chunks if max_chunks is None else min(sched.n_chunks, start_chunk + max_chunks)
    for chunk in range(start_chunk, stop):
        states, nbrs, recs = advance(model, states, nbrs, pb_s, sched.records_per_chunk,
                                     sched.record_every, base.numerics.capacity_multiplier,
                                     engine=engine)
        recs = {k: np.asarray(v)[:P] for k, v in recs.items()}
        bad = [k for k, v in recs.items() if not np.isfinite(np.asarray(v, float)).all()]
        if bad:
            msg = f"sweep went non-finite in chunk {chunk} ({', '.join(bad)}); try a smaller dt"
            if h5 is not None:
                h5.attrs["status"] = msg
                h5.close()
            raise FloatingPointError(msg)
        if h5 is not None:
            g = h5["records"]
            for k, v in recs.items():
                if k not in g:
                    g.create_dataset(k, data=v, maxshape=(P, None) + v.shape[2:], chunks=True)
                else:
                    n0 = g[k].shape[1]
                    g[k].resize(n0 + v.shape[1], axis=1)
                    g[k][:, n0:] = v
            if "checkpoint" in h5:
                del h5["checkpoint"]
            ck = h5.create_group("checkpoint")
            host_states = jax.tree_util.tree_map(lambda x: np.asarray(x)[:P], states)
            host_nbrs = jax.tree_util.tree_map(lambda x: np.asarray(x)[:P], nbrs)
            for k, v in state_to_arrays(host_states, host_nbrs).items():
                ck.create_dataset(k, data=v)
            ck.attrs["chunk"] = chunk + 1
            h5.attrs["wall_time"] = wall_before + time.perf_counter() - wall0
            h5.flush()
        if chunk >= sched.n_chunks - snapshots:
            _keep_snapshot(h5, snaps, states, P)
            if h5 is not None:
                h5.flush()
        for k, v in recs.items():
            mem.setdefault(k, []).append(v)
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    if stop < sched.n_chunks:
        if h5 is not None:
            h5.attrs["status"] = "partial"
            h5.close()
        return None
    wall = wall_before + time.perf_counter() - wall0  # over every session of a resumed sweep
    if h5 is not None:
        records = {k: h5["records"][k][()] for k in h5["records"]}
        if "snapshots" in h5:
            snaps = {k: h5["snapshots"][k][()] for k in h5["snapshots"]}
    else:
        records = {k: np.concatenate(v, axis=1) for k, v in mem.items()}
        snaps = {k: np.stack(v, axis=1 if k != "t" else 0) for k, v in snaps.items()}
    final = jax.tree_util.tree_map(lambda x: np.asarray(x)[:P], states)
    summaries = []
    for i, c in enumerate(configs):
        rec_i = {k: v[i] for k, v in records.items()}
        s, units = steady_state_summary(c, rec_i, take(final, i), t_windows[i], sched.duration)
        summaries.append(s)
    shape = tuple(len(v) for v in axes.values())
    summary = {k: np.array([s[k] for s in summaries]).reshape(shape) for k in summaries[0]}
    summary["wall_time"] = wall
    if h5 is not None:
        sg = h5.require_group("summary")
        for k, v in summary.items():
            if k in sg:
                del sg[k]
            sg.create_dataset(k, data=v).attrs["units"] = units.get(k, "s" if k == "wall_time" else "")
        ag = h5.require_group("axes")
        for k, v in axes.items():
            if k not in ag:
                ag.create_dataset(k, data=np.asarray(v, float))
        h5.attrs["wall_time"] = wall
        h5.attrs["status"] = "finished"
        h5.close()
    return SweepResult(axes=axes, configs=configs, summary=summary, records=records, path=out,
                       snapshots=snaps or None)


def _keep_snapshot(h5, mem: dict, states, P: int) -> None:
    """Append the batch's positions and velocities (and the time) to ``/snapshots`` of the
    file (resumable: the snapshot count follows the chunk count) or to ``mem``."""
    t = float(np.asarray(states.t)[0])
    per_point = {k: np.asarray(getattr(states, f))[:P]
                 for k, f in (("r", "r"), ("v", "v"), ("z_box", "z"))}
    if h5 is None:
        mem.setdefault("t", []).append(t)
        for k, x in per_point.items():
            mem.setdefault(k, []).append(x)
        return
    g = h5.require_group("snapshots")
    if "t" not in g:
        g.create_dataset("t", shape=(0,), maxshape=(None,), dtype="f8").attrs["units"] = "s"
        for k, x in per_point.items():
            g.create_dataset(k, shape=(P, 0) + x.shape[1:], maxshape=(P, None) + x.shape[1:],
                             chunks=True, dtype="f8").attrs["units"] = _SNAPSHOT_UNITS[k]
    n = g["t"].shape[0]
    if n and float(g["t"][n - 1]) >= t:  # a resumed sweep re-running a stored chunk
        n = int(np.searchsorted(g["t"][()], t))
    g["t"].resize(n + 1, axis=0)
    g["t"][n] = t
    for k, x in per_point.items():
        g[k].resize(n + 1, axis=1)
        g[k][:, n] = x


_SNAPSHOT_UNITS = {"r": "m", "v": "m/s", "z_box": "m"}
