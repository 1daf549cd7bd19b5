"""Run one simulation end to end: validate, settle, drive in jitted chunks, write HDF5.

This is the edge of the package where files, progress bars and messages live. The time loop
is the driver's (:mod:`jaxdamp.engine.driver`: neighbour lists, overflow, the non-finite policy);
between its chunks the runner appends samples and a snapshot and writes a checkpoint from which
``resume=True`` continues bit-identically. A run that goes non-finite stops with the driver's
message and keeps the samples before it (file status ``diverged``).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxdamp import interrupt
from jaxdamp.analysis import stats
from jaxdamp.analysis.response import analysis_start, steady_state_summary
from jaxdamp.config import Config, ConfigError, is_stored
from jaxdamp.engine import budget, driver
from jaxdamp.engine.choice import choose, resolve_engine, stored_choice
from jaxdamp.engine.driver import SimulationDiverged  # noqa: F401  (re-exported: runs raise it)
from jaxdamp.engine.packing import SettledBed, settle
from jaxdamp.io import RunFile, write_steady
from jaxdamp.io.common import (
    damaged_checkpoint,
    damaged_message,
    damaged_series,
    ensure_space,
    outdated_checkpoint,
    stop_file,
)
from jaxdamp.physics.containers import container
from jaxdamp.physics.excitation import random_start
from jaxdamp.physics.model import State, build, grain_species
from jaxdamp.validation import unused_note, validate


@dataclass(frozen=True)
class Schedule:
    """How a run is cut into steps, samples and chunks."""

    dt: float
    record_every: int  # steps per sample
    records_per_chunk: int
    n_chunks: int

    @property
    def chunk_steps(self) -> int:
        return self.record_every * self.records_per_chunk

    @property
    def duration(self) -> float:
        return self.n_chunks * self.chunk_steps * self.dt


def schedule(config: Config, dt: float) -> Schedule:
    """Sampling every ``record_dt`` (rounded to whole steps), chunks of ``chunk`` seconds — or
    of the whole ``duration`` when that is shorter — (rounded to whole samples), and whole
    chunks covering ``duration`` (rounded up, but a shortfall below 1 % of a chunk from
    rounding the sampling is accepted). :func:`schedule_note` says when the run so made is
    not the duration asked for."""
    num = config.numerics
    record_every = max(1, int(round(num.record_dt / dt)))
    chunk = min(num.chunk, num.duration)
    per_chunk = max(1, int(round(chunk / (record_every * dt))))
    n_chunks = max(1, int(math.ceil(num.duration / (per_chunk * record_every * dt) - 0.01)))
    return Schedule(dt, record_every, per_chunk, n_chunks)


def schedule_note(config: Config, sched: Schedule) -> str | None:
    """A one-line note when the simulated time of ``sched`` differs from
    ``numerics.duration`` by more than 1 % (whole samples and whole chunks), else ``None``."""
    asked = config.numerics.duration
    if abs(sched.duration - asked) <= 0.01 * asked:
        return None
    return (f"note: numerics.duration = {asked:.6g} s is run as {sched.n_chunks} whole "
            f"chunk(s) of {sched.chunk_steps * sched.dt:.6g} s = {sched.duration:.6g} s "
            f"(whole samples of {sched.record_every * sched.dt:.4g} s; numerics.chunk and "
            "numerics.record_dt set the grain)")


def initial_structure(config: Config, grain_mass: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions [m] and velocities [m/s] ``(dofs,)`` of the structure at t = 0 in the engines'
    order (the box first, :func:`jaxdamp.physics.structure.order`).

    S1: the static equilibrium under the bed's weight (its component along the excitation
    axis, ``grain_mass`` [kg]) on the box's degree of freedom, plus the box's ``primary.z0``,
    ``primary.v0`` and, with random base motion, the empty structure's steady response
    (:func:`jaxdamp.physics.excitation.random_start`). S2: the drive's starting point ``A_d``
    at rest (the top of ``A_d cos ωt``)."""
    if config.system != "primary":
        return np.array([config.drive.amplitude]), np.array([0.0])
    from jaxdamp.physics.model import excitation_axis

    weight = grain_mass * config.gravity * float(excitation_axis(config)[2])
    xs, vs = random_start(config)
    if config.structure is None:  # the 1-DOF primary
        K = config.primary.K
        return (np.array([(-weight / K if K > 0 else 0.0) + config.primary.z0 + xs[0]]),
                np.array([config.primary.v0 + vs[0]]))
    from jaxdamp.physics.structure import attachments, order, static_offset

    x = static_offset(config, -weight) + xs
    v = vs.copy()
    a = attachments(config)[0]  # the box's (cell 0's)
    x[a] += config.primary.z0
    v[a] += config.primary.v0
    o = order(config)
    return x[o], v[o]


def initial_box_position(config: Config, grain_mass: float) -> float:
    """The box's position along the excitation axis at t = 0 [m]: the box's entry of
    :func:`initial_structure`."""
    return float(initial_structure(config, grain_mass)[0][0])


def initial_box_velocity(config: Config) -> float:
    """The box's velocity at t = 0 [m/s]: the box's entry of :func:`initial_structure` (it does
    not depend on the bed's mass)."""
    return float(initial_structure(config, 0.0)[1][0])


def bed_with_box(config: Config, r, box_position) -> np.ndarray:
    """Grain positions ``r`` of a bed settled in the box at rest, moved with the box to its
    starting position: by ``e z0`` along the excitation axis ``e``. ``box_position``: the box's
    ``z0`` [m], or the structure's degrees of freedom in the engines' order
    (:func:`initial_structure`), each cell's grains moving with their cell's
    (:func:`jaxdamp.physics.structure.cell_dofs`)."""
    from jaxdamp.physics.model import cell_of, excitation_axis
    from jaxdamp.physics.structure import cell_dofs

    x = np.atleast_1d(np.asarray(box_position, np.float64))
    r = np.asarray(r)
    dofs = cell_dofs(config)
    if not dofs.any():  # every cell on the box's degree of freedom
        return r + excitation_axis(config) * x[0]
    shift = x[dofs][cell_of([config.cells * sp.count for sp in config.grains], config.cells)]
    return r + excitation_axis(config) * shift[:, None]


def batch_budget(config: Config, sched: Schedule, systems: int = 1, out: str | None = None,
                 snapshots: int = 0):
    """The :class:`jaxdamp.engine.budget.Budget` of ``systems`` systems of ``config`` on
    schedule ``sched``: settling and the run, every sample kept (a sample holds 24 scalars,
    4 per species and one per structural degree of freedom, in float64). Needs nothing built."""

    num = config.numerics
    s = config.structure
    dofs = 1 if s is None else len(s.M if s.M is not None else s.frequencies)
    steps = int(num.settle_time / sched.dt) + sched.n_chunks * sched.chunk_steps
    return budget.estimate(
        systems=systems, grains=config.n_grains, steps=steps,
        samples=sched.n_chunks * sched.records_per_chunk,
        sample_bytes=8 * (24 + 4 * len(config.grains) + dofs),
        engine=resolve_engine(num.engine, num.precision, systems,
                              tangential=config.tangential_law), snapshots=snapshots,
        out=out is not None, tangential=config.tangential_law)


@dataclass
class RunResult:
    """What :func:`run` returns: the output path (or ``None``), the summary scalars (fixed
    analysis window), the samples (dict of numpy arrays), the settled bed, the final state,
    and the steady-state estimates from the detected steady state (one replicate:
    :func:`jaxdamp.analysis.stats.summarise`; the replicate error needs ``replicates > 1``, which runs
    as a sweep of one point)."""

    path: str | None
    summary: dict
    records: dict
    bed: SettledBed
    state: State
    steady: dict | None = None


def run(
    config: Config,
    out: str | None = None,
    resume: bool = False,
    progress: bool = True,
    echo=print,
    snapshots: bool = True,
    max_chunks: int | None = None,
) -> RunResult:
    """Simulate ``config`` and (with ``out``) write an HDF5 run file.

    Args:
      config: the simulation; validated before any compute.
      out: output path; ``None`` keeps everything in memory.
      resume: continue from the checkpoint in ``out`` (must hold the same configuration).
      progress: show a tqdm progress bar.
      echo: where one-line messages go (``None`` for silence).
      snapshots: store grain positions after every chunk.
      max_chunks: stop after this many chunks in this call, leaving a file to ``resume``
        (for time-limited jobs); the summary then covers the part simulated so far.
    """
    say = echo or (lambda *a, **k: None)
    config = validate(config)  # counts from mass ratios and fill fractions
    if config.system == "impact":
        raise ConfigError(
            "system = 'impact' (S3, the single-particle model) has no DEM run file: use "
            "`jaxdamp frf --preset sanchez2012-impact` (any number of frequencies, seconds) or "
            "jaxdamp.s3.impact.simulate(config) from Python")
    model, params = build(config)
    sched = schedule(config, float(params.dt))
    if (note := schedule_note(config, sched)) is not None:
        say(note)
    if (note := unused_note(config)) is not None:
        say(note)
    if not resume:
        cost = batch_budget(config, sched, 1, out, sched.n_chunks if snapshots else 0)
        budget.check(cost, out, say)
        settling = int(config.numerics.settle_time / sched.dt) / max(cost.steps, 1)
        if cost.seconds > budget.ANNOUNCE_SECONDS and settling > 0.05:
            say(f"  of it settling up to {budget.duration(settling * cost.seconds)} "
                f"(numerics.settle_time = {config.numerics.settle_time:g} s simulated; it ends "
                f"sooner once every grain is slower than numerics.settle_speed = "
                f"{config.numerics.settle_speed:g} m/s)")
    interrupt.check()
    t_window = analysis_start(config, sched.duration)
    params = dataclasses.replace(params, t_window=jnp.asarray(t_window))
    pb = driver.batched(params)
    choice = choose(config.numerics.engine, config.numerics.precision, batch=1,
                    tangential=config.tangential_law)
    radii = np.asarray(params.radius)
    masses = np.asarray(params.mass)
    m_grains = float(masses.sum())

    rf = None
    start_chunk = 0
    if resume:
        if out is None or not os.path.exists(out):
            raise ConfigError(f"--resume: no run file at {out!r} to resume from")
        rf = RunFile(out, "a")
        stored = rf.h5.attrs["config"]
        if not is_stored(stored, config):
            rf.close()
            raise ConfigError(
                f"--resume: {out} was written with a different configuration; "
                "resume with the same preset, file and --set options"
            )
        ck = rf.read_checkpoint()
        if ck is None:
            rf.close()
            raise ConfigError(f"--resume: {out} has no checkpoint (the run never finished a chunk)")
        arrays, attrs = ck
        start_chunk = int(attrs["chunk"])
        choice = stored_choice(rf.h5.attrs, choice)
        series = rf.h5["series"]
        why = damaged_checkpoint(arrays) or (
            damaged_series(series["t"][()] if "t" in series else np.zeros(0),
                           int(attrs["n_records"])))
        if why is not None:
            rf.close()
            raise ConfigError(damaged_message(out, why))
        if (refusal := outdated_checkpoint(arrays, out, series.keys())) is not None:
            rf.close()
            raise ConfigError(refusal)
        engine = dict(engine=choice.engine, multiplier=config.numerics.capacity_multiplier)
        batch = driver.restore(model, pb, arrays, **engine)
        rf.truncate(int(attrs["n_records"]), int(attrs["n_snapshots"]))
        s = rf.h5["settle"]
        bed = SettledBed(s["r0"][()], None, None, None, float(s.attrs["bed_height"]),
                  float(s.attrs["time"]), float(s.attrs["max_speed"]),
                  bool(s.attrs.get("settled", True)))
        say(f"resuming {out} at chunk {start_chunk}/{sched.n_chunks} "
            f"(t = {float(batch.states.t[0]):.6g} s), engine {choice.engine} ({choice.reason})")
    else:
        engine = dict(engine=choice.engine, multiplier=config.numerics.capacity_multiplier)
        say(f"engine {choice.engine} ({choice.reason})")
        if (note := driver.compile_note(choice.engine, config.tangential_law)):
            say(note)
        t0 = time.perf_counter()
        bed = settle(config, model, params,
                     progress=f"settling {model.n} grains" if progress and model.n else None)
        say(
            f"settled {model.n} grains in {bed.time:.3g} s simulated "
            f"({time.perf_counter() - t0:.1f} s wall): bed height {bed.height:.5g} m"
        )
        if model.n and not bed.settled:
            say("warning: " + bed.unsettled_note(config) + "; the run file says so "
                "(/settle attribute 'settled' = false)")
        vessel = container(config)
        if model.n and bed.height >= vessel.height(config):
            raise ConfigError(
                f"{vessel.lid_key} = {vessel.height(config)} m: the settled bed is "
                f"{bed.height:.5g} m high and does not fit under the lid"
            )
        x0, xd0 = initial_structure(config, m_grains)
        r0 = bed_with_box(config, bed.r, x0)
        batch = driver.start(model, pb, r0[None], bed.v[None], bed.w[None], bed.q[None],
                             x0[None], xd0[None], **engine)
        if out is not None:
            rf = RunFile.create(out, config, radii, masses, grain_species(config), bed,
                                extra_attrs={"dt": sched.dt, "duration": sched.duration,
                                             "engine": choice.engine,
                                             "engine_reason": choice.reason})
            # resumable from its first moment: the settled start is checkpoint 0
            rf.write_checkpoint({k: v[0] for k, v in driver.checkpoint(batch, 1).items()},
                                {"chunk": 0, "n_records": 0, "n_snapshots": 0})

    all_recs: list[dict] = []
    if rf is not None and start_chunk > 0:
        all_recs.append({k: rf.h5["series"][k][()] for k in rf.h5["series"]})

    def realloc(old, new):
        say(f"neighbour list overflow: capacity {old} -> {new}, chunk redone")

    def keep(chunk, batch, recs):
        recs = {k: v[0] for k, v in recs.items()}
        all_recs.append(recs)
        if rf is not None:
            ck = {k: v[0] for k, v in driver.checkpoint(batch, 1).items()}  # one system
            ensure_space(out, sum(np.asarray(v).nbytes for v in (*recs.values(), *ck.values()))
                         + (np.asarray(batch.states.r[0]).nbytes * 7 // 3 if snapshots else 0))
            rf.append_records(recs)
            if snapshots:
                rf.append_snapshot(float(batch.states.t[0]), batch.states.r[0],
                                   batch.states.q[0])
            rf.write_checkpoint(
                ck, {"chunk": chunk + 1, "n_records": rf.n_records(),
                     "n_snapshots": rf.h5["snapshots"]["t"].shape[0] if snapshots else 0})

    def diverged(e):
        if rf is not None:
            rf.append_records({k: v[0] for k, v in e.records.items()}, e.index)
            rf.set_status("diverged", str(e))

    def interrupted():
        if rf is not None:
            rf.set_status("interrupted", "stopped by Ctrl-C; --resume continues from the "
                          "last checkpoint")
            rf.close()

    wall0 = time.perf_counter()
    stop = sched.n_chunks if max_chunks is None else min(sched.n_chunks, start_chunk + max_chunks)
    try:
        batch = driver.run_chunks(
            batch, range(start_chunk, stop), sched.records_per_chunk, sched.record_every,
            on_chunk=keep, on_diverged=diverged, on_realloc=realloc, on_interrupt=interrupted,
            total=sched.n_chunks,
            progress=f"{config.name} f={config.frequency:g} Hz" if progress else None)
    except OSError as err:  # the disk filled (or went away): keep what the file holds
        if rf is not None:
            stop_file(rf, str(err))
        raise
    steps_done = (stop - start_chunk) * sched.chunk_steps
    wall = time.perf_counter() - wall0

    records = {k: np.concatenate([r[k] for r in all_recs]) for k in all_recs[0]} if all_recs else {}
    final = batch.system(0)
    summary, units = steady_state_summary(config, records, final, t_window, sched.duration)
    summary.update(bed_height=bed.height, dt=sched.dt, steps=int(final.step),
                   wall_time=wall, steps_per_second=steps_done / wall if wall > 0 else 0.0)
    units.update(bed_height="m", dt="s", steps="1", wall_time="s", steps_per_second="1/s")
    steady = stats.summarise([records], config.frequency) if records else None
    if rf is not None:
        rf.write_summary(summary, units)
        if steady is not None:
            write_steady(rf.h5, steady, 1, stats.unit)
        rf.set_status("finished" if int(final.step) >= sched.n_chunks * sched.chunk_steps else "partial")
        rf.close()
    return RunResult(path=out, summary=summary, records=records, bed=bed, state=final,
                     steady=steady)
