"""Sweep throughput on whatever device JAX sees: system-steps/s and memory per system.

    python benchmarks/bench_device.py                   # batch of 32, engines auto + jax
    python benchmarks/bench_device.py --engine jax --batch 128 --steps 2000
    JAX_PLATFORMS=cuda python benchmarks/bench_device.py   # the first GPU that runs it

The ``sanchez2012-optimal`` bed (250 grains, settled, on its primary), a batch of frequencies
(8–25 Hz) through the production chunk function (:func:`jaxdamp.engine.simulate.chunk_fn`),
per engine: ``auto`` is what a sweep picks on this device (the native kernel on a CPU, the JAX
engine on an accelerator), ``jax`` the differentiable engine. The bed is in motion when timed
(one chunk first, which also compiles). Prints the device, system-steps/s, particle-steps/s,
the projected wall time of a 30-frequency FRF (5 s simulated each) and the memory per system:
the batch's state, neighbour lists and parameters, and, for the JAX engine, the compiled
chunk's temporary buffers (XLA's memory analysis) divided by the batch. The side-by-side
comparison with LAMMPS on the same moving bed is ``bench_lammps.py``. Do not run while other
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
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn, init_states, resolve_engine
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build


def _nbytes(tree) -> int:
    return int(sum(np.asarray(x).nbytes for x in jax.tree_util.tree_leaves(tree)))


def throughput(engine: str, steps: int, batch: int = 32) -> dict:
    """Seconds per system-step of ``batch`` frequencies of the thesis bed on ``engine``, the
    projected 30-frequency FRF and the memory per system [bytes]."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.3"])
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    freqs = np.linspace(8, 25, batch)
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    pb = dataclasses.replace(pb, omega=jnp.asarray(2 * np.pi * freqs))
    rep = lambda x: np.stack([x] * batch)  # noqa: E731
    z0 = -float(np.asarray(params.mass).sum()) * cfg.gravity / cfg.primary.K
    st = init_states(model, pb, rep(bed.r + [0, 0, z0]), rep(bed.v), rep(bed.w), rep(bed.q),
                     jnp.full(batch, z0), jnp.zeros(batch))
    nbrs = nb.allocate(model, box_frame(st, pb), 1.5)
    every = 100
    n_rec = max(1, steps // every)
    fn = chunk_fn(model, n_rec, every, engine=engine)
    temp = None
    if resolve_engine(engine) == "jax":
        analysis = fn.lower(st, nbrs, pb).compile().memory_analysis()
        temp = getattr(analysis, "temp_size_in_bytes", None)
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)  # compile; then time from the state after it (bed in motion)
    st, nbrs = out[0], out[1]
    t0 = time.perf_counter()
    jax.block_until_ready(fn(st, nbrs, pb))
    per = (time.perf_counter() - t0) / (n_rec * every * batch)
    dt = float(params.dt)
    return dict(per=per, frf_30=30 * (5.0 / dt) * per, n=model.n, dt=dt,
                state=(_nbytes(st) + _nbytes(nbrs) + _nbytes(pb)) / batch,
                temp=None if temp is None else temp / batch)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=3000, help="timed steps (JAX engine: 1/10)")
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--engine", nargs="+", default=["auto", "jax"])
    args = ap.parse_args()
    dev = jax.devices()[0]
    print(f"jax {jax.__version__}, backend {jax.default_backend()}, {len(jax.devices())} "
          f"device(s): {dev.device_kind}; float64 {jax.config.jax_enable_x64}")
    for engine in args.engine:
        used = resolve_engine(engine)
        steps = args.steps if used == "native" else max(200, args.steps // 10)
        r = throughput(engine, steps, args.batch)
        mem = f"{r['state'] / 1e3:.0f} kB state + lists + params"
        if r["temp"] is not None:
            mem += f", {r['temp'] / 1e3:.0f} kB compiled temporaries"
        print(f"{engine} ({used}): batch {args.batch} × N = {r['n']}: {r['per'] * 1e6:.2f} "
              f"µs/system-step, {1 / r['per']:.4g} system-steps/s, {r['n'] / r['per']:.4g} "
              f"particle-steps/s; 30-frequency FRF (5 s each, dt = {r['dt']:.3g} s): "
              f"{r['frf_30'] / 60:.1f} min; memory per system: {mem}")


if __name__ == "__main__":
    main()
