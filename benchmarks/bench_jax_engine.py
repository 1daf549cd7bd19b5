"""The JAX engine on the moving thesis bed, before and after a change, side by side.

    python benchmarks/bench_jax_engine.py                        # this checkout, float64/32
    python benchmarks/bench_jax_engine.py --checkout /path/old   # and an older checkout

The state is ``bench_lammps.py``'s thesis bed in motion (driven at 3 cm, 15 Hz, after 0.4 s,
by the native engine), repeated ``--batch`` times with drive frequencies spread by ±3 % so
that the systems decorrelate and the batch rebuilds its neighbour lists as a real sweep does.
Each measurement runs in a fresh interpreter (``PYTHONPATH`` set to the checkout), compiles a
chunk of ``--steps`` steps, runs it once more from where it ended, and times a third run; the
checkouts and precisions are interleaved over ``--rounds`` rounds. Prints µs per
system-step, median [min, max]. Do not run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

WORKER = r"""
import dataclasses, json, sys, time
sys.path.insert(0, {bench!r})
import jax, jax.numpy as jnp, numpy as np
from bench_lammps import moving_bed
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import State
B, steps, precision = {batch}, {steps}, {precision!r}
cfg, model, params, st = moving_bed("thesis")
if precision != "float64":
    model = dataclasses.replace(model, precision=precision)
states = State(**{{f.name: jnp.asarray(np.repeat(np.asarray(getattr(st, f.name))[None], B, 0))
                  for f in dataclasses.fields(st)}})
pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * B), params)
pb = dataclasses.replace(pb, omega=pb.omega * jnp.linspace(0.97, 1.03, B))
nbrs = nb.allocate(model, box_frame(states, pb), 1.5)
every = 100
fn = chunk_fn(model, max(1, steps // every), every, engine="jax")
out = fn(states, nbrs, pb); jax.block_until_ready(out)
out = fn(out[0], out[1], pb); jax.block_until_ready(out)
t0 = time.perf_counter(); jax.block_until_ready(fn(out[0], out[1], pb))
per = (time.perf_counter() - t0) / (max(1, steps // every) * every * B)
print(json.dumps(dict(per=per, capacity=int(nb.capacity(nbrs)))))
"""


def measure(checkout: str, precision: str, batch: int, steps: int) -> dict:
    code = WORKER.format(bench=os.path.join(checkout, "benchmarks"), batch=batch, steps=steps,
                         precision=precision)
    env = dict(os.environ, PYTHONPATH=checkout)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--checkout", action="append", default=[],
                    help="another checkout to compare (float64 only if it has no "
                         "numerics.precision); may be repeated")
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    here = os.path.dirname(HERE)
    cases = [(c, "float64") for c in args.checkout] + [(here, "float64"), (here, "float32")]
    times = {c: [] for c in cases}
    for _ in range(args.rounds):
        for c in cases:
            times[c].append(measure(c[0], c[1], args.batch, args.steps)["per"])
    import numpy as np

    print(f"JAX engine, moving thesis bed (250 grains), batch {args.batch}, {args.steps} steps "
          f"timed per round, {args.rounds} rounds; µs per system-step, median [min, max]:")
    for (path, precision), t in times.items():
        t = 1e6 * np.asarray(t)
        print(f"  {path} ({precision}): {np.median(t):.1f} [{t.min():.1f}, {t.max():.1f}]")


if __name__ == "__main__":
    main()
