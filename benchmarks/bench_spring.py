"""The tangential spring's cost: the moving thesis bed with the viscous law and with the spring
(``tangential_law = "mindlin"``) in the native kernel, and LAMMPS' own cost of the same switch,
side by side, as ratios.

    python benchmarks/bench_spring.py                     # 3 interleaved rounds
    python benchmarks/bench_spring.py --rounds 5 --json benchmarks/results/bench_spring.json
    python benchmarks/bench_spring.py --n 50000 --steps 400 --batch 1 --no-lammps
                                                          # a large bed (one system)

The bed is ``bench_lammps.py``'s ``thesis`` bed in motion (250 grains, driven at 3 cm and
15 Hz, after 0.4 s); the spring's copy starts from the same state with fresh springs (they
load within a few steps: the bed is dense). Each configuration runs ``--steps`` steps through
the production chunk function, compiled before timing, one system and a batch of
``--batch``; LAMMPS runs the same bed on one process with ``tangential linear_nohistory``
(the viscous law's mapping, :mod:`jaxdamp.peers.lammps`) and with ``tangential
mindlin_rescale/force`` (its spring with history, the same form as jaxdamp's; the tangential
damping multiplier kept, which changes the physics but not the work per contact). Rounds are
interleaved and each measurement waits for a quiet machine; medians over rounds with the
spread, and the spring's cost over the viscous law's per code (issue 39: at most 1.3× in the
native kernel). Do not run while other jobs use the cores.

With ``--n N`` the bed is ``bench_large.py``'s instead: the thesis bed scaled in base area to
``N`` grains, settled and driven (its warmed state from that benchmark's cache), timed as one
system (the kernel's large-bed path from ``jaxdamp.engine.native.LARGE`` grains on, where the
spring also moves the walls' pass out of the sweep).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import shutil
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from bench_lammps import lammps_input, lammps_us, moving_bed, time_jaxdamp, wait_quiet  # noqa: E402


def with_springs(model, params, st):
    """The model and one system's state of the same bed with tangential springs (fresh)."""
    import jax
    import jax.numpy as jnp

    from jaxdamp.engine import driver
    from jaxdamp.engine import neighbors as nb
    from jaxdamp.engine.simulate import init_states
    from jaxdamp.physics.integrate import box_frame

    m = dataclasses.replace(model, tangential="mindlin")
    pb = driver.batched(params)
    one = lambda x: jnp.asarray(np.asarray(x)[None])  # noqa: E731
    states = init_states(m, pb, one(st.r), one(st.v), one(st.w), one(st.q), one(st.z),
                         one(st.zd), float(st.t),
                         nb.allocate(m, box_frame(jax.tree_util.tree_map(one, st), pb), 1.0).idx)
    return m, jax.tree_util.tree_map(lambda x: np.asarray(x)[0], states)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=10000, help="steps per measurement")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--json", help="write the measurements here")
    ap.add_argument("--n", type=int, help="bench_large.py's bed of N grains instead of the "
                    "thesis bed")
    ap.add_argument("--no-lammps", action="store_true")
    args = ap.parse_args(argv)

    if args.n:
        import bench_large as big

        from jaxdamp.physics.model import build

        cfg = big.bed_config(args.n, 0.03)
        st, _ = big.warm_state(cfg, 0.04, 100, big.DEFAULT_CACHE)
        model, params = build(cfg)
    else:
        cfg, model, params, st = moving_bed("thesis")
    spring_model, spring_st = with_springs(model, params, st)
    every = 100
    work = tempfile.mkdtemp(prefix="bench_spring_")
    lmp = shutil.which("lmp") if not args.no_lammps else None
    decks = {}
    if lmp:
        path = lammps_input(cfg, params, st, args.steps, work)
        text = open(path).read()
        decks["viscous"] = path
        spring = text.replace("tangential linear_nohistory",
                              "tangential mindlin_rescale/force NULL")
        if spring == text:
            raise RuntimeError("bench_spring: the LAMMPS deck has no 'tangential linear_nohistory'")
        decks["mindlin"] = os.path.join(work, "in.spring")
        with open(decks["mindlin"], "w") as fh:
            fh.write(spring)
    cases = {("native", law, b): (m, s) for b in sorted({1, args.batch})
             for law, m, s in (("viscous", model, st), ("mindlin", spring_model, spring_st))}
    runs = {k: [] for k in list(cases) + [("lammps", law, 1) for law in decks]}
    for _ in range(args.rounds):
        for key, (m, s) in cases.items():
            wait_quiet()
            sec, steps = time_jaxdamp(m, params, s, key[2], args.steps, every)
            runs[key].append(sec / (steps * key[2]) * 1e6)
        for law, path in decks.items():
            wait_quiet()
            runs[("lammps", law, 1)].append(lammps_us(path, args.steps))
    med = {k: float(np.median(v)) for k, v in runs.items()}
    print(f"{'thesis bed' if not args.n else 'scaled bed'} in motion ({model.n} grains), "
          f"{args.steps} steps per measurement, {args.rounds} rounds; µs per system-step, "
          "median [min, max]:")
    for (code, law, b), v in runs.items():
        print(f"  {code:7s} {law:8s} batch {b:3d}: {med[(code, law, b)]:8.2f} "
              f"[{min(v):.2f}, {max(v):.2f}]")
    ratios = {}
    for code, b in {(k[0], k[2]) for k in runs}:
        if (code, "mindlin", b) in runs:
            r = [m / v for m, v in zip(runs[(code, "mindlin", b)], runs[(code, "viscous", b)],
                                       strict=True)]
            ratios[f"{code} batch {b}"] = dict(of_medians=med[(code, "mindlin", b)]
                                               / med[(code, "viscous", b)], per_round=r)
    print("the spring's cost over the viscous law's (ratio of medians; round by round):")
    for k, r in sorted(ratios.items()):
        print(f"  {k}: {r['of_medians']:.3f} ({', '.join(f'{x:.3f}' for x in r['per_round'])})")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(command="python benchmarks/" + " ".join(
                [os.path.basename(__file__)] + (argv if argv is not None else sys.argv[1:])),
                machine=platform.processor() or platform.machine(), cpus=os.cpu_count(),
                runs={"|".join(map(str, k)): v for k, v in runs.items()}, ratios=ratios), fh,
                indent=1)


if __name__ == "__main__":
    main()
