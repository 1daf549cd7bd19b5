"""The JAX engine on the moving thesis bed, before and after a change, side by side.

    python benchmarks/bench_jax_engine.py                        # this checkout, float64/32
    python benchmarks/bench_jax_engine.py --checkout /path/old   # and an older checkout
    python benchmarks/bench_jax_engine.py --precision float64 --tangential both  # the spring

The state is ``bench_lammps.py``'s thesis bed in motion (driven at 3 cm, 15 Hz, after 0.4 s,
by the native engine), repeated ``--batch`` times with drive frequencies spread by ±3 %.
With ``--decorrelate S`` the copies are first driven apart for ``S`` seconds by the native
engine with frequencies spread by ±20 % (a sweep's systems are at different phases and
amplitudes, so their grains need new neighbour lists at different steps; identical copies
rebuild together and hide the cost of one system forcing a rebuild of all).
Each measurement runs in a fresh interpreter (``PYTHONPATH`` set to the checkout), compiles a
chunk of ``--steps`` steps, runs it once more from where it ended, and times a third run; the
checkouts and precisions (and with ``--tangential both`` the viscous law and the spring with
history, whose copies start from the moving bed with fresh springs) are interleaved over
``--rounds`` rounds. Prints µs per
system-step, median [min, max], and, from ``--steps`` single steps after the timed run, how
often the lists were rebuilt: the fraction of steps in which any system rebuilt and the mean
fraction of systems rebuilt per step. Do not run while other jobs use the cores.
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
states = State(**{{f.name: jnp.asarray(np.repeat(np.asarray(getattr(st, f.name))[None], B, 0))
                  for f in dataclasses.fields(st)}})
pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * B), params)
spread = 0.2 if {decorrelate} > 0 else 0.03
pb = dataclasses.replace(pb, omega=pb.omega * jnp.linspace(1 - spread, 1 + spread, B))
if {decorrelate} > 0:  # driven apart by the native engine
    from jaxdamp.engine import driver
    nat = driver.attach(model, pb, states, engine="native")
    nat = driver.run_for(nat, {decorrelate}, pieces=4)
    states = jax.tree_util.tree_map(jnp.asarray, nat.states)
if precision != "float64":
    model = dataclasses.replace(model, precision=precision)
if {tangential!r} != "viscous":  # the same bed with fresh springs (the warm-up chunk loads them)
    from jaxdamp.engine.simulate import init_states
    model = dataclasses.replace(model, tangential={tangential!r})
    states = init_states(model, pb, states.r, states.v, states.w, states.q, states.z,
                         states.zd, float(states.t[0]),
                         nb.allocate(model, box_frame(states, pb), 1.0).idx)
nbrs = nb.allocate(model, box_frame(states, pb), 1.5)
every = 100
fn = chunk_fn(model, max(1, steps // every), every, engine="jax")
out = fn(states, nbrs, pb); jax.block_until_ready(out)
out = fn(out[0], out[1], pb); jax.block_until_ready(out)
t0 = time.perf_counter(); jax.block_until_ready(fn(out[0], out[1], pb))
per = (time.perf_counter() - t0) / (max(1, steps // every) * every * B)
one = chunk_fn(model, 1, 1, engine="jax")
st, nbrs = out[0], out[1]
rebuilt = []
for _ in range(steps):  # the reference positions change exactly when a list is rebuilt
    ref = np.asarray(nbrs.reference)
    st, nbrs, _ = one(st, nbrs, pb)
    rebuilt.append(np.any(np.asarray(nbrs.reference) != ref, axis=(-2, -1)))
rebuilt = np.array(rebuilt)  # (steps, B)
print(json.dumps(dict(per=per, capacity=int(nb.capacity(nbrs)),
                      any_rate=float(rebuilt.any(axis=1).mean()),
                      system_rate=float(rebuilt.mean()))))
"""


def measure(checkout: str, precision: str, batch: int, steps: int,
            decorrelate: float = 0.0, tangential: str = "viscous") -> dict:
    code = WORKER.format(bench=HERE, batch=batch, steps=steps, precision=precision,
                         decorrelate=float(decorrelate), tangential=tangential)
    env = dict(os.environ, PYTHONPATH=checkout)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True, cwd=checkout)  # '' on sys.path is the checkout
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
    ap.add_argument("--decorrelate", type=float, default=0.0, metavar="S",
                    help="drive the copies apart for S seconds first (frequencies ±20%%)")
    ap.add_argument("--precision", choices=("float64", "float32", "both", "none"), default="both",
                    help="this checkout's precisions (none: only the --checkout ones)")
    ap.add_argument("--tangential", choices=("viscous", "mindlin", "both"), default="viscous",
                    help="this checkout's tangential laws (Config.tangential_law)")
    args = ap.parse_args(argv)
    here = os.path.dirname(HERE)
    mine = {"both": ["float64", "float32"], "none": []}.get(args.precision, [args.precision])
    laws = ["viscous", "mindlin"] if args.tangential == "both" else [args.tangential]
    cases = ([(c, "float64", "viscous") for c in args.checkout]
             + [(here, p, t) for p in mine for t in laws])
    runs = {c: [] for c in cases}
    for _ in range(args.rounds):
        for c in cases:
            runs[c].append(measure(c[0], c[1], args.batch, args.steps, args.decorrelate, c[2]))
    import numpy as np

    print(f"JAX engine, moving thesis bed (250 grains), batch {args.batch}"
          + (f" driven apart {args.decorrelate} s" if args.decorrelate else "")
          + f", {args.steps} steps timed per round, {args.rounds} rounds; µs per system-step, "
          "median [min, max]; rebuilds: steps with any system rebuilt, systems rebuilt per step:")
    for (path, precision, law), r in runs.items():
        t = 1e6 * np.array([x["per"] for x in r])
        print(f"  {path} ({precision}, {law}): {np.median(t):.1f} [{t.min():.1f}, {t.max():.1f}]; "
              f"rebuilds {r[-1]['any_rate']:.3f}, {r[-1]['system_rate']:.4f}")


if __name__ == "__main__":
    main()
