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
from . import driver, stats
from .analysis import analysis_start, steady_state_summary
from .config import Config, ConfigError, apply_overrides
from .io import write_steady
from .model import build, config_dt, grain_radii
from .packing import settle_many
from .runner import initial_box_position, schedule
from .simulate import resolve_engine
from .validation import validate


@dataclass
class SweepResult:
    """``axes``: ``{key: values}``; ``configs``: one per point (grid order, last axis fastest);
    ``summary``: ``{name: array shaped like the grid}``; ``records``: per-point samples
    (dict of arrays ``(P, T)``); ``path``: the HDF5 file or ``None``; ``snapshots``: with
    ``sweep(..., snapshots=k)``, ``{"t": (k,), "r": (P, k, N, 3), "v": (P, k, N, 3), "z_box": (P, k)}`` at the
    ends of the last ``k`` chunks, else ``None``.

    With ``R = replicates`` independent beds per grid point, ``records`` and ``snapshots``
    have ``P = grid points × R`` rows (:meth:`point`), ``summary`` holds the mean over the
    replicates of each fixed-window value, ``replicate_summary`` the values of every replicate
    (grid shape + ``(R,)``), and ``steady`` the steady-state estimates over replicates from
    the detected steady state (:func:`jaxdamp.stats.steady`, as :func:`jaxdamp.stats.to_arrays`:
    ``{quantity: {"mean", "se", "ci95", "n", "values", "batch_se", "start", "stationary"}}``)."""

    axes: dict
    configs: list
    summary: dict
    records: dict
    path: str | None
    snapshots: dict | None = None
    replicates: int = 1
    replicate_summary: dict | None = None
    steady: dict | None = None

    def point(self, index: int, replicate: int = 0) -> int:
        """Row of grid point ``index`` (grid order), replicate ``replicate``, in ``records``
        and ``snapshots`` (replicates are the fastest axis)."""
        return index * self.replicates + replicate


def grid_configs(config: Config, axes: dict) -> list[Config]:
    """One configuration per grid point (``itertools.product`` order), each validated."""
    keys = list(axes)
    if len(keys) > 2:
        raise ConfigError(f"a sweep takes at most two axes, got {keys}")
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


def _axes_json(axes: dict, replicates: int = 1) -> str:
    d = {k: list(map(float, v)) for k, v in axes.items()}
    if replicates > 1:
        d["replicates"] = int(replicates)
    return json.dumps(d)


def replicate_configs(grid: list[Config], replicates: int) -> list[Config]:
    """Every grid configuration repeated ``replicates`` times with the seeds of
    :func:`jaxdamp.stats.replicate_seed` (replicates fastest)."""
    if replicates < 1:
        raise ConfigError(f"replicates = {replicates}: need at least 1")
    return [c if k == 0 else dataclasses.replace(
                c, numerics=dataclasses.replace(
                    c.numerics, seed=stats.replicate_seed(c.numerics.seed, k)))
            for c in grid for k in range(replicates)]


def write_header(h5, config: Config, axes: dict, configs: list, dt: float, duration: float,
                 engine: str, replicates: int = 1) -> None:
    """The root attributes of a sweep file (``docs/output.md``), shared by every model."""
    h5.attrs["format"] = "jaxdamp-sweep/1"
    h5.attrs["jaxdamp_version"] = __version__
    h5.attrs["base_config"] = config.to_json()
    h5.attrs["axes"] = _axes_json(axes, replicates)
    h5.attrs["replicates"] = int(replicates)
    h5.attrs["configs"] = json.dumps([c.to_json() for c in configs])
    h5.attrs["dt"] = dt
    h5.attrs["duration"] = duration
    h5.attrs["engine"] = engine


def holds(path: str, config: Config, axes: dict, replicates: int = 1) -> bool:
    """Whether the sweep file ``path`` exists and holds the sweep ``(config, axes)``."""
    if not os.path.exists(path):
        return False
    try:
        with h5py.File(path, "r") as h5:
            return (h5.attrs.get("base_config") == config.to_json()
                    and h5.attrs.get("axes") == _axes_json(axes, replicates) and "checkpoint" in h5)
    except OSError:  # not an HDF5 file (e.g. cut short while being created)
        return False


def reuse_or_run(config: Config, axes: dict, out: str, **kwargs) -> SweepResult:
    """:func:`sweep` into ``out``, reusing what is there: a finished file of the same sweep is
    read back without computing (its compute time kept), a partial one is resumed, anything
    else is replaced. For experiments whose raw sweeps outlive a figure or a kill."""
    return sweep(config, axes, out=out,
                 resume=holds(out, config, axes, kwargs.get("replicates", 1)), **kwargs)


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
        :func:`jaxdamp.stats.replicate_seed` ``(seed, 0..R-1)``, run in the same batch.
      beds: a cache of settled beds by geometry, filled and reused across calls (repeated
        sweeps of one damper, e.g. an optimiser's evaluations, settle each bed once).

    S3 configurations (``system = "impact"``) go to :func:`jaxdamp.impact.sweep` (same result
    and file layout; ``resume``, ``shard`` and ``max_chunks`` do not apply: it runs whole).
    """
    if config.system == "impact":  # S3: the single-particle model of jaxdamp.impact
        from . import impact

        if replicates != 1:
            raise ConfigError(f"replicates = {replicates}: the single-particle model (S3) is "
                              "deterministic, one realisation is exact (use replicates = 1)")

        return impact.sweep(config, axes, out=out, progress=progress, echo=echo)
    say = echo or (lambda *a, **k: None)
    grid = grid_configs(config, axes)
    R = int(replicates)
    configs = replicate_configs(grid, R)
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
    drive = dict(engine=engine, multiplier=base.numerics.capacity_multiplier,
                 place=lambda tree: _pad_and_shard(tree, padded, sharding))

    h5 = None
    start_chunk = 0
    if resume and out and os.path.exists(out):
        h5 = h5py.File(out, "a")
        if (h5.attrs["base_config"] != config.to_json()
                or h5.attrs["axes"] != _axes_json(axes, R)):
            h5.close()
            raise ConfigError(f"--resume: {out} holds a different sweep")
        g = h5["checkpoint"]
        start_chunk = int(g.attrs["chunk"])
        # compute time already spent on this sweep (older files: the finished summary's)
        wall_before = float(h5.attrs.get("wall_time", h5["summary/wall_time"][()]
                                         if "summary/wall_time" in h5 else 0.0))
        arrays = {}
        g.visititems(lambda n, o: arrays.__setitem__(n, o[()]) if isinstance(o, h5py.Dataset) else None)
        batch = driver.restore(model, pb, arrays, **drive).replace(params=pb_s)
        for ds in h5["records"].values():
            ds.resize(start_chunk * sched.records_per_chunk, axis=1)
        say(f"resuming sweep at chunk {start_chunk}/{sched.n_chunks}")
    else:
        wall_before = 0.0
        keys = [_geometry_key(c) for c in configs]
        beds = {} if beds is None else beds
        first = {k: i for i, k in reversed(list(enumerate(keys))) if k not in beds}
        order = sorted(first.values())  # one new bed per geometry, all settled in one batch
        if order:
            settled = settle_many([configs[i] for i in order], model,
                                  [built[i][1] for i in order])
            beds.update({keys[i]: b for i, b in zip(order, settled)})
            say(f"settled {len(order)} bed(s) in one batch: heights "
                + ", ".join(f"{b.height:.5g}" for b in settled) + " m")
        r0, v0, w0, q0, z0 = [], [], [], [], []
        for c, (m, p), key in zip(configs, built, keys):
            bed = beds[key]
            if m.n and bed.height >= c.box.Lz:
                raise ConfigError(f"box.Lz = {c.box.Lz} m: the settled bed ({bed.height:.5g} m) "
                                  "does not fit")
            z = initial_box_position(c, float(np.asarray(p.mass).sum()))
            r0.append(bed.r + np.array([0.0, 0.0, z]))
            v0.append(bed.v), w0.append(bed.w), q0.append(bed.q), z0.append(z)
        batch = driver.start(model, pb, np.stack(r0), np.stack(v0), np.stack(w0), np.stack(q0),
                             np.asarray(z0), np.zeros(P), **drive).replace(params=pb_s)
        if out:
            h5 = h5py.File(out, "w")
            write_header(h5, config, axes, configs, dt, sched.duration, engine, R)
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
        try:
            batch, recs = driver.advance(batch, sched.records_per_chunk, sched.record_every,
                                         systems=P)
        except driver.SimulationDiverged as e:
            if h5 is not None:  # the file keeps every finished chunk and its checkpoint
                h5.attrs["status"] = "diverged"
                h5.attrs["message"] = str(e)
                h5.close()
            raise
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
            for k, v in driver.checkpoint(batch, P).items():
                ck.create_dataset(k, data=v)
            ck.attrs["chunk"] = chunk + 1
            h5.attrs["wall_time"] = wall_before + time.perf_counter() - wall0
            h5.flush()
        if chunk >= sched.n_chunks - snapshots:
            _keep_snapshot(h5, snaps, batch.states, P)
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
    final = jax.tree_util.tree_map(lambda x: np.asarray(x)[:P], batch.states)
    summaries, series = [], []
    for i, c in enumerate(configs):
        rec_i = {k: v[i] for k, v in records.items()}
        s, units = steady_state_summary(c, rec_i, driver.take(final, i), t_windows[i], sched.duration)
        summaries.append(s)
        series.append(stats.per_period(rec_i, c.frequency, channels=stats.CHANNELS))
    shape = tuple(len(v) for v in axes.values())
    per_rep = {k: np.array([s[k] for s in summaries]).reshape(shape + (R,)) for k in summaries[0]}
    summary = {k: v.mean(axis=-1) for k, v in per_rep.items()}
    summary["wall_time"] = wall
    steady = stats.to_arrays(
        [stats.steady(series[g * R:(g + 1) * R]) for g in range(len(grid))], shape)
    if h5 is not None:
        sg = h5.require_group("summary")
        for k, v in summary.items():
            if k in sg:
                del sg[k]
            sg.create_dataset(k, data=v).attrs["units"] = units.get(k, "s" if k == "wall_time" else "")
        write_replicates(h5, per_rep, units, steady, R)
        ag = h5.require_group("axes")
        for k, v in axes.items():
            if k not in ag:
                ag.create_dataset(k, data=np.asarray(v, float))
        h5.attrs["wall_time"] = wall
        h5.attrs["status"] = "finished"
        h5.close()
    return SweepResult(axes=axes, configs=grid, summary=summary, records=records, path=out,
                       snapshots=snaps or None, replicates=R, replicate_summary=per_rep,
                       steady=steady)


def write_replicates(h5, per_rep: dict, units: dict, steady: dict, R: int) -> None:
    """``/replicate_summary/<name>`` (grid + ``(R,)``) and ``/steady/<quantity>/<field>``
    (``docs/output.md``): the replicate values and the steady-state estimates over them."""
    rg = h5.require_group("replicate_summary")
    rg.attrs["replicates"] = R
    for k, v in per_rep.items():
        if k in rg:
            del rg[k]
        rg.create_dataset(k, data=v).attrs["units"] = units.get(k, "")
    write_steady(h5, steady, R, stats.unit)


def steady_or_window(res: SweepResult, key: str) -> tuple[np.ndarray, int]:
    """Per-replicate values of ``key`` (grid shape + ``(R,)``): the steady mean over the
    detected steady state where the replicate became stationary, else its fixed-window
    value (``summary``); and how many replicates fell back to the fixed window."""
    steady = res.steady[key]["values"]
    window = res.replicate_summary[key]
    ok = np.asarray(res.steady[key]["stationary"], bool) & np.isfinite(steady)
    return np.where(ok, steady, window), int((~ok).sum())


def write_fit(h5, fits: dict, used: str) -> None:
    """``/fit`` of an FRF sweep file: ``M_ef``, ``C_ef`` (the ``used`` weighting), their
    standard errors across replicates ``se_M_ef``, ``se_C_ef``, and ``<weighting>/...`` for
    every weighting (:data:`jaxdamp.analysis.RESIDUALS`), one entry per ``Lz``."""
    if "fit" in h5:
        del h5["fit"]
    g = h5.create_group("fit")
    g.attrs["residuals"] = used
    g.attrs["replicates"] = int(fits[used][0]["replicates"])

    def put(grp, fl):
        for name, key, unit in (("M_ef", "M_ef", "kg"), ("C_ef", "C_ef", "N s/m"),
                                ("se_M_ef", "se_M", "kg"), ("se_C_ef", "se_C", "N s/m"),
                                ("M_ef_of_mean", "M_mean_fit", "kg"),
                                ("C_ef_of_mean", "C_mean_fit", "N s/m")):
            grp.create_dataset(name, data=np.array([f[key] for f in fl])).attrs["units"] = unit

    put(g, fits[used])
    for w, fl in fits.items():
        put(g.create_group(w), fl)


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
