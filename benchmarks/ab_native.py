"""Interleaved A/B of the native kernel across git revisions: is a change faster or slower?

    python benchmarks/ab_native.py b50da50 HEAD                  # 30 interleaved rounds
    python benchmarks/ab_native.py b50da50 909caf3 HEAD --rounds 10 --json ab.json

This host's speed drifts by up to 2× over minutes (``benchmarks/RESULTS.md``), so timing one
revision after another compares the host with itself. Here every revision gets its own git
worktree (``/tmp/jaxdamp-ab/<rev>``) and one warm worker process (its own numba cache, the
kernel compiled once), and a coordinator asks the workers in turn, in a new random order every
round, to time one chunk: seconds apart, each revision meets the same host. The workload is
``bench_lammps.py``'s (the thesis bed driven at 15 Hz, 250 grains in motion; the production
chunk of the native engine, 100 steps per sample) at batch 1 (20 000 steps) and batch 8
(5 000 steps). Prints µs per system-step per revision and batch, minimum and median over the
rounds, and the ratio to the first revision. Do not run while other jobs use the cores.

    python benchmarks/ab_native.py 435c3ca HEAD --n 50000 --rounds 5   # one large bed

``--n N``: instead, one system of ``bench_large.py``'s bed of N grains (the thesis damper
scaled in base area, driven, from its cached warm state: the same state for every revision),
``--steps`` steps per timed chunk (default 1000), also in ns per particle-step. ``--large L``
sets ``native.LARGE`` to L in every worker: the large-bed path for a bed smaller than its
threshold (``--n 1000 --large 2``: the large path's cost against the small path's, where the
bed fits in the cache).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
WORK = [(1, 20000), (8, 5000)]  # (batch, steps) per timed chunk

WORKER = r'''
import dataclasses, os, sys, time
import numpy as np
sys.path.insert(0, {bench!r})  # bench_lammps's moving bed, from the tree that runs this
import jax, jax.numpy as jnp
import bench_lammps
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import State

{bed}
ready = {{}}
def prep(B, steps):
    states = State(**{{f.name: jnp.asarray(np.repeat(np.asarray(getattr(st, f.name))[None], B, 0))
                      for f in dataclasses.fields(st)}})
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * B), params)
    nbrs = nb.allocate(model, box_frame(states, pb), 1.5)
    fn = chunk_fn(model, steps // 100, 100, engine="native")
    jax.block_until_ready(fn(states, nbrs, pb))
    return fn, states, nbrs, pb
print("ready", flush=True)
for line in sys.stdin:
    B, steps = map(int, line.split())
    if (B, steps) not in ready:
        ready[B, steps] = prep(B, steps)
    fn, s, nbrs, pb = ready[B, steps]
    t0 = time.perf_counter()
    jax.block_until_ready(fn(s, nbrs, pb))
    print(f"{{(time.perf_counter() - t0) / (steps * B) * 1e6:.4f}}", flush=True)
'''


def bed_code(n: int | None, large: int | None = None) -> str:
    """The worker's lines that make ``(cfg, model, params, st)``: the moving thesis bed of
    ``bench_lammps.py``, or (``n``) the warm large bed of ``bench_large.py``; ``large``: the
    native kernel's large-bed threshold (:data:`jaxdamp.engine.native.LARGE`)."""
    head = ("" if large is None else
            f"from jaxdamp.engine import native\nnative.LARGE = {int(large)}\n")
    if n is None:
        return head + 'cfg, model, params, st = bench_lammps.moving_bed("thesis")'
    return head + ("import bench_large\n"
            "from jaxdamp.physics.model import build\n"
            f"st, _ = bench_large.warm_state(bench_large.bed_config({n}, 0.03), 0.04, 100,\n"
            "                                os.path.expanduser(bench_large.DEFAULT_CACHE),\n"
            "                                log=lambda *a: None)\n"
            f"cfg = bench_large.bed_config({n}, 0.03, 'native')\n"
            "model, params = build(cfg)")


def worktree(rev: str, base: str) -> str:
    """A detached worktree of ``rev`` under ``base`` (made once, reused)."""
    sha = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", rev], check=True,
                         capture_output=True, text=True).stdout.strip()
    path = os.path.join(base, sha)
    if not os.path.exists(path):
        subprocess.run(["git", "-C", ROOT, "worktree", "add", "-f", "--detach", path, sha],
                       check=True, capture_output=True)
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("revs", nargs="+", help="git revisions (the first is the baseline)")
    ap.add_argument("--rounds", type=int, default=30)
    ap.add_argument("--base", default="/tmp/jaxdamp-ab", help="where the worktrees go")
    ap.add_argument("--json", help="write the times here")
    ap.add_argument("--n", type=int, help="one system of bench_large.py's bed of N grains")
    ap.add_argument("--steps", type=int, default=1000, help="steps per chunk with --n")
    ap.add_argument("--large", type=int, help="native.LARGE in the workers (the large-bed "
                    "path from this many grains)")
    a = ap.parse_args(argv)
    os.makedirs(a.base, exist_ok=True)
    code = WORKER.format(bench=HERE, bed=bed_code(a.n, a.large))
    work = WORK if a.n is None else [(1, a.steps)]
    procs = {}
    for rev in a.revs:
        tree = worktree(rev, a.base)
        env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=os.path.join(tree, ".nb"))
        procs[rev] = subprocess.Popen([sys.executable, "-c", code], cwd=tree, env=env, text=True,
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=1)
    for rev, p in procs.items():  # settle, warm up and compile (in parallel: not timed)
        while (line := p.stdout.readline()).strip() != "ready":
            if not line:
                sys.exit(f"ab_native: the worker of {rev} died")

    def once(rev, B, steps):
        procs[rev].stdin.write(f"{B} {steps}\n")
        return float(procs[rev].stdout.readline())

    for rev in a.revs:  # each chunk function compiled before the timed rounds
        for B, steps in work:
            once(rev, B, steps)
    times = {rev: {B: [] for B, _ in work} for rev in a.revs}
    for r in range(a.rounds):
        order = list(a.revs)
        random.shuffle(order)
        for rev in order:
            for B, steps in work:
                times[rev][B].append(once(rev, B, steps))
        print(f"round {r + 1}/{a.rounds}", flush=True)
    for p in procs.values():
        p.stdin.close()
    first = a.revs[0]
    print(f"\nµs per system-step, min and median of {a.rounds} interleaved rounds "
          f"(ratio of the minima to {first}):")
    for rev in a.revs:
        print(f"  {rev:>12}: " + "   ".join(
            f"batch {B}: {min(x):.3f} / {statistics.median(x):.3f} "
            f"({min(x) / min(times[first][B]):.3f}×)" for B, x in times[rev].items())
              + (f"   = {min(times[rev][1]) * 1e3 / a.n:.2f} ns per particle-step (min)"
                 if a.n else ""))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"revs": a.revs, "rounds": a.rounds, "work": work, "n": a.n,
                       "times": times}, fh)


if __name__ == "__main__":
    main()
