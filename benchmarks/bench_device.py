"""Sweep throughput on whatever device JAX sees: system-steps/s and memory per system.

    python benchmarks/bench_device.py                   # batch of 32: auto, jax, jax float32
    python benchmarks/bench_device.py --engine jax --precision float32 --batch 128
    JAX_PLATFORMS=cuda python benchmarks/bench_device.py   # the first GPU that runs it

The ``sanchez2012-optimal`` bed (250 grains, settled, on its primary), a batch of frequencies
(8–25 Hz) through the production chunk function (:func:`jaxdamp.engine.simulate.chunk_fn`).
The batch is first driven for ``--warm`` simulated seconds (by the fastest engine here: the
native kernel on a CPU), so that every engine is timed on the same bed **in motion** (grains
thrown against the lid, neighbour lists rebuilt), never on a bed at rest. Then per engine and
``numerics.precision``, in ``--rounds`` interleaved rounds from that same state: ``auto`` is
what a sweep picks on this device (the native kernel on a CPU, the JAX engine on an
accelerator), ``jax`` the differentiable engine, in float64 and with its contact laws in
float32. Prints the device, µs per system-step (median and range over rounds),
system-steps/s, particle-steps/s, the projected wall time of a 30-frequency FRF (5 s simulated
each) and the memory per system: the batch's state, neighbour lists and parameters, and, for
the JAX engine, the compiled chunk's temporary buffers (XLA's memory analysis) divided by the
batch. The side-by-side comparison with LAMMPS is ``bench_lammps.py``. Do not run while other
jobs use the cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import driver
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn, resolve_engine
from jaxdamp.physics.model import build
from jaxdamp.studies.runner import initial_box_position


def _nbytes(tree) -> int:
    return int(sum(np.asarray(x).nbytes for x in jax.tree_util.tree_leaves(tree)))


def moving_batch(batch: int, warm: float):
    """``(model, params, batch)``: ``batch`` frequencies of the thesis bed, settled and then
    driven for ``warm`` simulated seconds."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.3"])
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    pb = dataclasses.replace(pb, omega=jnp.asarray(2 * np.pi * np.linspace(8, 25, batch)))
    rep = lambda x: np.stack([x] * batch)  # noqa: E731
    z0 = initial_box_position(cfg, float(np.asarray(params.mass).sum()))
    b = driver.start(model, pb, rep(bed.r + [0.0, 0.0, z0]), rep(bed.v), rep(bed.w),
                     rep(bed.q), np.full(batch, z0), np.zeros(batch), engine="auto",
                     multiplier=cfg.numerics.capacity_multiplier)
    every = 100
    b, _ = driver.advance(b, max(1, int(round(warm / (float(params.dt) * every)))), every)
    return model, params, b


def throughput(model, params, b, engine: str, precision: str, steps: int) -> dict:
    """Seconds per system-step of the batch ``b`` on ``engine`` with ``precision`` from its
    state (compiled before timing), the projected 30-frequency FRF and the memory per system
    [bytes]."""
    model = dataclasses.replace(model, precision=precision)
    batch = int(b.states.t.shape[0])
    st, pb = b.states, b.params
    nbrs = nb.allocate(model, b.nbrs.reference, 1.5, radius=pb.radius)
    every = 100
    n_rec = max(1, steps // every)
    fn = chunk_fn(model, n_rec, every, engine=engine)
    temp = None
    if resolve_engine(engine, precision) == "jax":
        analysis = fn.lower(st, nbrs, pb).compile().memory_analysis()
        temp = getattr(analysis, "temp_size_in_bytes", None)
    jax.block_until_ready(fn(st, nbrs, pb))  # compile (and run once)
    t0 = time.perf_counter()
    jax.block_until_ready(fn(st, nbrs, pb))
    per = (time.perf_counter() - t0) / (n_rec * every * batch)
    dt = float(params.dt)
    return dict(per=per, frf_30=30 * (5.0 / dt) * per, n=model.n, dt=dt,
                state=(_nbytes(st) + _nbytes(nbrs) + _nbytes(pb)) / batch,
                temp=None if temp is None else temp / batch)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=3000,
                    help="timed steps per round (JAX engine: a tenth, at least 200)")
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--warm", type=float, default=0.2,
                    help="simulated seconds of driving before timing [s]")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--engine", nargs="+", default=["auto", "jax"])
    ap.add_argument("--precision", nargs="+", default=["float64", "float32"],
                    help="numerics.precision of the JAX engine (the native kernel: float64)")
    args = ap.parse_args(argv)
    dev = jax.devices()[0]
    print(f"jax {jax.__version__}, backend {jax.default_backend()}, {len(jax.devices())} "
          f"device(s): {dev.device_kind}; float64 {jax.config.jax_enable_x64}")
    model, params, b = moving_batch(args.batch, args.warm)
    print(f"batch of {args.batch} driven for {args.warm} s (8–25 Hz) before timing")
    cases = []
    for engine in args.engine:
        for precision in args.precision:
            used = resolve_engine(engine, precision)
            if used == "native" and precision != "float64":
                continue
            if (used, precision) not in [(u, p) for _, u, p in cases]:
                cases.append((engine, used, precision))
    times = {c: [] for c in cases}
    last = {}
    for _ in range(args.rounds):
        for c in cases:
            engine, used, precision = c
            steps = args.steps if used == "native" else max(200, args.steps // 10)
            last[c] = throughput(model, params, b, engine, precision, steps)
            times[c].append(last[c]["per"])
    for c in cases:
        engine, used, precision = c
        r, per = last[c], float(np.median(times[c]))
        mem = f"{r['state'] / 1e3:.0f} kB state + lists + params"
        if r["temp"] is not None:
            mem += f", {r['temp'] / 1e3:.0f} kB compiled temporaries"
        spread = ", ".join(f"{1e6 * t:.1f}" for t in times[c])
        print(f"{engine} ({used}, {precision}): batch {args.batch} × N = {r['n']}: "
              f"{per * 1e6:.2f} µs/system-step (rounds: {spread}), {1 / per:.4g} "
              f"system-steps/s, {r['n'] / per:.4g} particle-steps/s; 30-frequency FRF (5 s "
              f"each, dt = {r['dt']:.3g} s): {30 * (5.0 / r['dt']) * per / 60:.1f} min; memory "
              f"per system: {mem}")


if __name__ == "__main__":
    main()
