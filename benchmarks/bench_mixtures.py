"""Cost of the 2023 paper's driven-box families: µs per system-step and the projected wall time of
an efficiency measurement, and what the size-aware neighbour list saves on mixtures.

    python benchmarks/bench_mixtures.py                       # reference, a/b/c at σ = 0.5 and 0.1
    python benchmarks/bench_mixtures.py --sigma 0.1 0.3 --classes a --batch 9

Each family is driven at A_d = 3 cm for 3 periods first (collect-and-collide, the state the
measurement spends its time in); the timed loop is the production chunk function from that
state (batch of identical copies), with the compiled CPU engine (size-aware pair list) and the
JAX engine with the size-aware list and with a uniform ``2 R_max + skin`` cutoff. Reported per
family: grains, dt, steps per period, list capacity K (neighbours per grain) aware / uniform,
µs per system-step, and the projected wall time of ``jaxdamp efficiency`` (9 amplitudes ×
(10 + 50) periods, native engine, batch of 9). Do not run while other jobs use the cores.
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
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies.runner import run


def driven_state(cfg):
    """The state after 3 periods at A_d = 3 cm, and the model and params of ``cfg``."""
    cfg = ef.protocol(cfg, periods=3, transient=0)
    res = run(cfg, progress=False, echo=None, snapshots=False)
    model, params = build(cfg)
    params = jax.tree_util.tree_map(jnp.asarray, params)
    return cfg, model, params, res.state


def time_chunk(model, params, state, batch, steps, engine, uniform=False, record_every=100):
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    st = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), state)
    nbrs = nb.allocate(model, box_frame(st, pb), 1.5, radius=None if uniform else pb.radius)
    record_every = min(record_every, steps)
    steps -= steps % record_every
    fn = chunk_fn(model, steps // record_every, record_every, engine=engine)
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)  # compile
    if bool(np.any(np.asarray(out[1].overflow))):
        nbrs = nb.allocate(model, box_frame(st, pb), 3.0, radius=None if uniform else pb.radius)
    t0 = time.perf_counter()
    jax.block_until_ready(fn(st, nbrs, pb))
    return (time.perf_counter() - t0) / steps / batch, nb.capacity(nbrs)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sigma", type=float, nargs="+", default=[0.5, 0.1])
    ap.add_argument("--classes", default="abc")
    ap.add_argument("--batch", type=int, default=9)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--jax-steps", type=int, default=300)
    args = ap.parse_args()
    print(f"jaxdamp {jaxdamp.__version__}, jax {jax.__version__}, {jax.devices()}, "
          f"{platform.processor() or platform.machine()}, x64={jax.config.jax_enable_x64}")
    print(f"{'family':>22} {'N':>4} {'dt [s]':>9} {'steps/T':>7} {'K aware':>7} {'K unif':>6} "
          f"{'native us':>9} {'jax aware us':>12} {'jax unif us':>11} {'projected':>10}")
    families = [("varela2023-reference", None)] + [
        (f"varela2023-{k}", s) for s in args.sigma for k in args.classes]
    for name, sigma in families:
        cfg, model, params, state = driven_state(presets.family(name, sigma))
        t_nat, k_aware = time_chunk(model, params, state, args.batch, args.steps, "native")
        t_jax, _ = time_chunk(model, params, state, 1, args.jax_steps, "jax")
        t_uni, k_uni = time_chunk(model, params, state, 1, args.jax_steps, "jax", uniform=True)
        steps_per_period = 1.0 / cfg.frequency / cfg.numerics.dt
        projected = t_nat * 9 * 60 * steps_per_period  # batch of 9 at the measured rate
        label = name.replace("varela2023-", "") + (f" σ={sigma:g}" if sigma else "")
        print(f"{label:>22} {model.n:>4} {cfg.numerics.dt:>9.3g} {steps_per_period:>7.0f} "
              f"{k_aware:>7} {k_uni:>6} {t_nat * 1e6:>9.2f} {t_jax * 1e6:>12.1f} "
              f"{t_uni * 1e6:>11.1f} {projected / 60:>8.1f} min", flush=True)


if __name__ == "__main__":
    main()
