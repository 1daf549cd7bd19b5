"""Batched FRF throughput of jaxdamp: system-steps/s of the production chunk function.

    python benchmarks/bench_frf.py                    # batch of 32 frequencies, both engines
    python benchmarks/bench_frf.py --engine native --steps 2000

The ``sanchez2012-optimal`` bed (250 grains, settled, on its primary), a batch of 32
frequencies (8–25 Hz) through the production chunk function, per engine. Prints system-steps/s,
particle-steps/s and the projected wall time of a full 30-frequency FRF (5 s simulated each).
The side-by-side comparison with LAMMPS on the same moving bed is ``bench_lammps.py``. Do not
run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn, init_states
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build

def jaxdamp_throughput(engine, steps, batch=32):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.3"])
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    freqs = np.linspace(8, 25, batch)
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    import dataclasses

    pb = dataclasses.replace(pb, omega=jnp.asarray(2 * np.pi * freqs))
    rep = lambda x: np.stack([x] * batch)  # noqa: E731
    z0 = -float(np.asarray(params.mass).sum()) * cfg.gravity / cfg.primary.K
    st = init_states(model, pb, rep(bed.r + [0, 0, z0]), rep(bed.v), rep(bed.w), rep(bed.q),
                     jnp.full(batch, z0), jnp.zeros(batch))
    nbrs = nb.allocate(model, box_frame(st), 1.5)
    every = 100
    fn = chunk_fn(model, max(1, steps // every), every, engine=engine)
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)  # compile; then time from the state after it (bed in motion)
    st, nbrs = out[0], out[1]
    t0 = time.perf_counter()
    jax.block_until_ready(fn(st, nbrs, pb))
    wall = time.perf_counter() - t0
    n_steps = max(1, steps // every) * every
    per_sys_step = wall / (n_steps * batch)
    dt = float(params.dt)
    full = 30 * (5.0 / dt) * per_sys_step
    return per_sys_step, full, model.n, bed, cfg, dt


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--engine", nargs="+", default=["native", "jax"])
    args = ap.parse_args()
    print(f"jax {jax.__version__}, devices {jax.devices()}")
    for engine in args.engine:
        steps = args.steps if engine == "native" else max(200, args.steps // 10)
        per, full, n, bed, cfg, dt = jaxdamp_throughput(engine, steps, args.batch)
        print(f"jaxdamp {engine:>6}: batch {args.batch} x N={n}: {per * 1e6:.2f} us/system-step, "
              f"{1 / per:.4g} system-steps/s, {n / per:.4g} particle-steps/s; "
              f"projected 30-frequency FRF (5 s each, dt = {dt:.3g} s): {full / 60:.1f} min")


if __name__ == "__main__":
    main()
