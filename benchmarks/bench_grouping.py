"""Designs of other grain counts in one search: batches grouped by shape against one padded
batch (issue 41, item 2: "group them into batches of equal shape, or pad to a common grain
count with inactive grains — measure which costs less").

    python benchmarks/bench_grouping.py                        # 3 interleaved rounds
    python benchmarks/bench_grouping.py --json benchmarks/results/bench_grouping.json

The thesis bed (3 mm steel, driven at 3 cm and 15 Hz, in motion after ``--warm`` s) filled to
the mass ratios ``--fills`` (the grain counts of a fill search: the damping–mass front's), each
a group of ``--batch`` systems. **Grouped** (what :meth:`jaxdamp.design.space.DesignProblem.
measure` does): one batch per fill, run one after the other; its cost is the sum. **Padded**:
one batch of all ``K × batch`` systems at the largest fill's grain count — the cost of padding
every design to the largest count *if the padding grains cost what real ones do*; the engines
have no inactive grain, so this is the padded batch's upper bound. A padding grain that never
touches anything still costs its integration, its cell-list entry and its neighbour search; its
pair forces are what it saves, at most the pairs' share of the step (36 % of a large bed's
step, ``benchmarks/RESULTS.md``, "the profile"). Each configuration runs ``--steps`` steps
through the production chunk function (compiled before timing), rounds interleaved, each
measurement after the machine is quiet; µs per system-step and the ratios are printed. Do not
run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from bench_lammps import moving_bed, time_jaxdamp, wait_quiet  # noqa: E402

#: the pair forces' share of a step (the fourteenth session's profile of the native kernel):
#: what a padding grain that touches nothing could save at most
PAIR_SHARE = 0.36


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fills", type=float, nargs="+", default=[0.025, 0.05, 0.1, 0.15, 0.2],
                    help="mass ratios of the groups")
    ap.add_argument("--batch", type=int, default=4, help="systems per group")
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--warm", type=float, default=0.2, help="simulated seconds of driving")
    ap.add_argument("--json", help="write the measurements here")
    args = ap.parse_args(argv)

    beds = []
    for mu in args.fills:
        cfg, model, params, st = moving_bed("thesis", {"grains.0.mass_ratio": mu})
        beds.append((mu, model, params, st))
    every = 100
    K, B = len(beds), args.batch
    grouped, padded = [], []
    per = {mu: [] for mu, *_ in beds}
    for _ in range(args.rounds):
        total = 0.0
        for mu, model, params, st in beds:
            wait_quiet()
            sec, steps = time_jaxdamp(model, params, st, B, args.steps, every)
            per[mu].append(sec / (steps * B) * 1e6)
            total += sec
        grouped.append(total / steps * 1e6)
        mu, model, params, st = beds[-1]
        wait_quiet()
        sec, steps = time_jaxdamp(model, params, st, K * B, args.steps, every)
        padded.append(sec / steps * 1e6)
    ns = [m.n for _, m, _, _ in beds]
    print(f"{K} groups of {B} systems (fills {args.fills}: {ns} grains), {args.steps} steps, "
          f"{args.rounds} rounds; median [min, max]")
    for (mu, *_), n in zip(beds, ns):
        v = per[mu]
        print(f"  fill {mu:g} ({n} grains), batch {B}: {np.median(v):8.2f} [{min(v):.2f}, "
              f"{max(v):.2f}] µs per system-step, {1e3 * np.median(v) / n:.1f} ns per "
              "particle-step")
    print(f"  grouped, {K} batches one after the other: {np.median(grouped):9.1f} µs per step "
          f"of all {K * B} systems [{min(grouped):.1f}, {max(grouped):.1f}]")
    print(f"  padded to {ns[-1]} grains, one batch of {K * B}: {np.median(padded):9.1f} µs per "
          f"step [{min(padded):.1f}, {max(padded):.1f}]")
    r = [g / p for g, p in zip(grouped, padded)]
    low = (1 - PAIR_SHARE * (1 - sum(ns) / (K * ns[-1])))
    print(f"grouped / padded (upper bound): {np.median(r):.3f} (rounds: "
          + ", ".join(f"{x:.3f}" for x in r) + f"); against the padded batch's lower bound "
          f"(padding grains without their pairs' share, {PAIR_SHARE:.0%}): "
          f"{np.median(r) / low:.3f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(command="python benchmarks/" + " ".join(
                [os.path.basename(__file__)] + (argv if argv is not None else sys.argv[1:])),
                machine=platform.processor() or platform.machine(), cpus=os.cpu_count(),
                grains=ns, fills=args.fills, batch=B, per_fill={str(k): v for k, v in per.items()},
                grouped=grouped, padded=padded, ratio=r, lower_bound_factor=low), fh, indent=1)


if __name__ == "__main__":
    main()
