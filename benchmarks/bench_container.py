"""The cylinder's cost against the box: µs per particle-step of the same grains in each (issue 35).

    python benchmarks/bench_container.py                  # 250 and 1000 grains, both engines
    python benchmarks/bench_container.py --rounds 20 --json bench_container.json
    python benchmarks/bench_container.py --rounds 1 --steps 200 --large 0   # does it run?

Beds: the thesis bed, ``sanchez2012-optimal`` (250 grains of 3 mm radius in a box of
36.75 × 36.75 mm) against ``sanchez2012-cylinder`` (the same grains, 250 from its mass ratio,
in a cylinder of the box's base area, radius 20.734 mm), and a larger bed of ``--large``
grains in both, the same sections with the lid raised in proportion (``Lz = 0.1225 m ×
N / 250``, as ``bench_step.py``). Each bed is settled (:func:`jaxdamp.engine.packing.settle`)
and started with the box at its static equilibrium (:func:`jaxdamp.engine.driver.start`), as
a run starts; the timed work is the production chunk function
(:func:`jaxdamp.engine.simulate.chunk_fn`, records every 100 steps) of ``--steps`` steps from
that state, ``--batch`` copies, compiled before the rounds: the native (numba) kernel and the
JAX engine.

This host's speed drifts by up to 2× over minutes (``benchmarks/RESULTS.md``), so the two
containers are interleaved as in ``ab_native.py``: every round times, for each bed and engine,
the box and the cylinder in a new random order, seconds apart. Prints per bed and engine the µs
per particle-step (``wall / (steps × N × batch)``) of each container, minimum / median over
the rounds, and the ratio cylinder / box formed in each round: median [min, max] over the
rounds (issue 35's target: ≤ 1.2 in both engines). Also printed: each container's time step
``dt`` — the concave wall's stiffer contact may shorten it — and so the cost per simulated
second, ``ratio × dt_box / dt_cylinder``. Do not run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import json
import platform
import random
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxdamp
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import driver
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.model import build
from jaxdamp.studies.runner import bed_with_box, initial_box_position, initial_box_velocity
from jaxdamp.validation import validate

THESIS_N = 250
CONTAINERS = ("box", "cylinder")


def configs(n: int, settle_time: float | None):
    """The box and the cylinder holding the same ``n`` grains (``n = 250``: the presets as they
    are; otherwise the lid raised to ``0.1225 m × n / 250``)."""
    box, cyl = presets.get("sanchez2012-optimal"), presets.get("sanchez2012-cylinder")
    if n != THESIS_N:
        Lz = f"{0.1225 * n / THESIS_N:.4f}"
        box = apply_overrides(box, [f"grains.0.count={n}", f"box.Lz={Lz}"])
        cyl = apply_overrides(cyl, [f"grains.0.count={n}", "grains.0.mass_ratio=none",
                                    f"container.Lz={Lz}"])
    if settle_time is not None:
        box, cyl = (apply_overrides(c, [f"numerics.settle_time={settle_time}"])
                    for c in (box, cyl))
    box, cyl = validate(box), validate(cyl)
    a, b = box.grains[0], cyl.grains[0]
    if (a.count, a.radius, a.material) != (b.count, b.radius, b.material) or a.count != n:
        raise SystemExit(f"bench_container: the box and the cylinder do not hold the same "
                         f"{n} grains: {a} / {b}")
    return {"box": box, "cylinder": cyl}


def settled(cfg):
    """``(model, params, settled bed)`` of ``cfg``."""
    model, params = build(cfg)
    return model, params, settle(cfg, model, params)


def prepared(cfg, model, params, bed, batch: int, steps: int, engine: str):
    """``(chunk function, states, nbrs, params, dt)``: the settled ``bed`` of ``cfg`` started
    as a run starts, ``batch`` copies, the chunk function of ``steps`` steps compiled."""
    mass = float(np.asarray(params.mass).sum())
    z0, zd0 = initial_box_position(cfg, mass), initial_box_velocity(cfg)
    rep = lambda x: np.repeat(np.asarray(x)[None], batch, 0)  # noqa: E731
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    b = driver.start(model, pb, rep(bed_with_box(cfg, bed.r, z0)), rep(bed.v), rep(bed.w),
                     rep(bed.q), np.full(batch, z0), np.full(batch, zd0), engine=engine,
                     multiplier=cfg.numerics.capacity_multiplier)
    fn = chunk_fn(model, max(1, steps // 100), 100, engine=engine)
    jax.block_until_ready(fn(b.states, b.nbrs, pb))  # compile
    return fn, b.states, b.nbrs, pb, float(params.dt)


def time_once(prep, steps: int, n: int, batch: int) -> float:
    """µs per particle-step of one timed chunk from the prepared start."""
    fn, states, nbrs, pb, _ = prep
    t0 = time.perf_counter()
    jax.block_until_ready(fn(states, nbrs, pb))
    return (time.perf_counter() - t0) / (max(1, steps // 100) * 100 * n * batch) * 1e6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--large", type=int, default=1000,
                    help="grains of the larger bed (0: the thesis bed only; default 1000)")
    ap.add_argument("--engine", nargs="+", default=["native", "jax"], choices=["native", "jax"])
    ap.add_argument("--steps", type=int, default=5000, help="steps per timed chunk")
    ap.add_argument("--batch", type=int, default=1, help="copies of each bed (default 1)")
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--settle-time", type=float, default=None,
                    help="settling time [s] (default: the presets', numerics.settle_time)")
    ap.add_argument("--json", help="write the times here")
    a = ap.parse_args(argv)
    print(f"jaxdamp {jaxdamp.__version__}, jax {jax.__version__}, {jax.devices()}, "
          f"{platform.processor() or platform.machine()}, x64={jax.config.jax_enable_x64}")
    beds = [THESIS_N] + ([a.large] if a.large else [])
    preps, dts = {}, {}
    for n in beds:
        cfgs = configs(n, a.settle_time)
        for c in CONTAINERS:
            model, params, bed = settled(cfgs[c])
            dts[n, c] = float(params.dt)
            for engine in a.engine:
                preps[n, engine, c] = prepared(cfgs[c], model, params, bed, a.batch, a.steps,
                                               engine)
        print(f"N = {n}: settled and compiled; dt box {dts[n, 'box']:.6g} s, cylinder "
              f"{dts[n, 'cylinder']:.6g} s", flush=True)
    times = {key: [] for key in preps}
    for r in range(a.rounds):
        for n in beds:
            for engine in a.engine:
                order = list(CONTAINERS)
                random.shuffle(order)
                for c in order:
                    times[n, engine, c].append(time_once(preps[n, engine, c], a.steps, n,
                                                         a.batch))
        print(f"round {r + 1}/{a.rounds}", flush=True)
    print(f"\nµs per particle-step, min / median of {a.rounds} interleaved rounds ({a.steps} "
          f"steps, batch {a.batch}); cylinder / box per round: median [min, max]; "
          "issue 35's target ≤ 1.2")
    print(f"{'N':>5} {'engine':>7} {'box':>18}{'cylinder':>18}{'cylinder / box':>26}"
          f"{'target':>8}{'per simulated s':>17}")
    out = []
    for n in beds:
        for engine in a.engine:
            tb, tc = times[n, engine, "box"], times[n, engine, "cylinder"]
            ratio = [c / b for b, c in zip(tb, tc)]
            med = statistics.median(ratio)
            per_s = med * dts[n, "box"] / dts[n, "cylinder"]
            print(f"{n:>5} {engine:>7} {min(tb):>8.4f} / {statistics.median(tb):<7.4f}"
                  f"{min(tc):>8.4f} / {statistics.median(tc):<7.4f}"
                  f"{med:>10.3f} [{min(ratio):.3f}, {max(ratio):.3f}]"
                  f"{'ok' if med <= 1.2 else 'OVER':>8}{per_s:>17.3f}")
            out.append({"n": n, "engine": engine, "box_us": tb, "cylinder_us": tc,
                        "ratio": ratio, "dt_box": dts[n, "box"],
                        "dt_cylinder": dts[n, "cylinder"]})
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"steps": a.steps, "batch": a.batch, "rounds": a.rounds,
                       "jaxdamp": jaxdamp.__version__, "jax": jax.__version__,
                       "machine": platform.processor() or platform.machine(), "results": out},
                      fh, indent=1)


if __name__ == "__main__":
    main()
