"""Throughput of the DEM step: µs per step and particle-steps/s (float64, CPU or whatever JAX sees).

    python benchmarks/bench_step.py                 # N = 250 (sanchez2012-optimal) and N = 1000
    python benchmarks/bench_step.py --batch 1 8 32  # batched systems (vmap / prange)
    python benchmarks/bench_step.py --engine native # only the compiled CPU engine

Beds are FCC lattices settled for a short time (realistic contact numbers); the timed loop is
the production chunk function (neighbour-list checks, rebuilds, records every 100 steps), with
the pure-JAX engine and the compiled CPU engine (numba, :mod:`jaxdamp.engine.native`). Also prints the cost of the force kernels alone (pairs, walls) for one system.
Do not run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import platform
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxdamp
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn, init_states
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build
from jaxdamp.physics.pairs import pair_forces
from jaxdamp.physics.walls import wall_forces


def bed(n: int):
    over = [f"grains.0.count={n}", "numerics.settle_time=0.1"]
    if n > 250:
        over.append(f"box.Lz={0.1225 * n / 250:.4f}")
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), over)
    model, params = build(cfg)
    settled = settle(cfg, model, params)
    return cfg, model, params, settled


def time_chunk(model, params, settled, batch: int, steps: int, engine: str, record_every: int = 100):
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    rep = lambda x: np.stack([x] * batch)  # noqa: E731
    st = init_states(model, pb, rep(settled.r), rep(settled.v), rep(settled.w), rep(settled.q),
                     jnp.zeros(batch), jnp.zeros(batch))
    nbrs = nb.allocate(model, box_frame(st, pb), 1.5)
    fn = chunk_fn(model, steps // record_every, record_every, engine=engine)
    jax.block_until_ready(fn(st, nbrs, pb))  # compile
    t0 = time.perf_counter()
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)
    wall = time.perf_counter() - t0
    return wall / steps, nb.capacity(nbrs)


def time_kernel(f, reps=500):
    g = jax.jit(lambda: jax.lax.fori_loop(0, reps, lambda i, c: c + f(c * 1e-30), 0.0))
    g().block_until_ready()
    t0 = time.perf_counter()
    g().block_until_ready()
    return (time.perf_counter() - t0) / reps


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, nargs="+", default=[250, 1000])
    ap.add_argument("--batch", type=int, nargs="+", default=[1, 8])
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--engine", nargs="+", default=["jax", "native"], choices=["jax", "native"])
    args = ap.parse_args()
    print(f"jaxdamp {jaxdamp.__version__}, jax {jax.__version__}, {jax.devices()}, "
          f"{platform.processor() or platform.machine()}, x64={jax.config.jax_enable_x64}")
    print(f"{'engine':>7} {'N':>5} {'batch':>5} {'K':>3} {'us/step':>9} {'us/system-step':>15} "
          f"{'particle-steps/s':>17}")
    for n in args.n:
        cfg, model, params, settled = bed(n)
        for engine in args.engine:
            for b in args.batch:
                per_step, cap = time_chunk(model, params, settled, b, args.steps, engine)
                print(f"{engine:>7} {n:>5} {b:>5} {cap:>3} {per_step * 1e6:>9.1f} "
                      f"{per_step / b * 1e6:>15.1f} {n * b / per_step:>17.3g}")
        r = jnp.asarray(settled.r)
        v = jnp.zeros_like(r) + 0.01
        w = jnp.ones_like(r)
        idx = nb.allocate(model, r[None], 1.5).idx[0]

        def leaves_sum(t):
            return sum(jnp.sum(x) for x in jax.tree_util.tree_leaves(t))

        t_pairs = time_kernel(lambda c: leaves_sum(pair_forces(r + c, v, w, idx, params, model)))
        t_walls = time_kernel(lambda c: leaves_sum(wall_forces(r + c, v, w, 0.0, 0.0, params, model)))
        print(f"      kernels alone (one system): grain pairs {t_pairs * 1e6:.1f} us "
              f"({n * idx.shape[1]} pair slots), walls {t_walls * 1e6:.1f} us ({n * 6} slots)")


if __name__ == "__main__":
    main()
