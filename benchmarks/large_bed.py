"""Large beds: peak memory and wall time of `jaxdamp run` from start-up (lattice, settling,
neighbour lists, initial forces) through a short drive with records, snapshots and checkpoints.

    python benchmarks/large_bed.py                        # N = 2000, 5000, 20000, 50000
    python benchmarks/large_bed.py --n 50000 --settle 0.05 --duration 0.02

Each bed is the thesis' optimal damper (sanchez2012-optimal, 3 mm steel grains) scaled up: the
square base grows with N at the preset's grains per area (so the bed keeps its height), and
the primary's M, K and C grow with it (the same f0 and mass ratio). Every N runs as its own
child process, the real command line, under a fresh wrapper process: its peak resident memory
is the wrapper's ``RUSAGE_CHILDREN`` ``ru_maxrss`` (that one child's; Linux carries the RSS
of the forking process through exec into it, which is why the wrapper is a tiny process of
~10 MB and not this one), its wall time the child's. Settling is cut short
(``--settle`` simulated seconds: the bed is flagged as not settled, which is the point — it is
the memory of the start-up that is measured, not a settled bed) and the drive is
``--duration`` simulated seconds in chunks of ``--chunk`` (a snapshot and a checkpoint after
each). Prints one Markdown row per N with the command and the machine.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile

PRESET_GRAINS = 250
PRESET_SIDE = 0.03675  # m, the preset's Lx = Ly
PRESET_PRIMARY = {"M": 2.37, "K": 21500.0, "C": 7.6}


def command(n: int, out: str, settle: float, duration: float, chunk: float) -> list[str]:
    scale = n / PRESET_GRAINS
    side = PRESET_SIDE * math.sqrt(scale)
    sets = {"grains.0.count": n, "box.Lx": round(side, 6), "box.Ly": round(side, 6),
            "numerics.settle_time": settle, "numerics.duration": duration,
            "numerics.chunk": chunk}
    sets.update({f"primary.{k}": round(v * scale, 6) for k, v in PRESET_PRIMARY.items()})
    argv = ["jaxdamp", "run", "--preset", "sanchez2012-optimal"]
    for k, v in sets.items():
        argv += ["--set", f"{k}={v}"]
    return argv + ["--out", out, "--overwrite", "--no-progress"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[2000, 5000, 20000, 50000])
    ap.add_argument("--settle", type=float, default=0.05, help="settling [simulated s]")
    ap.add_argument("--duration", type=float, default=0.02, help="drive [simulated s]")
    ap.add_argument("--chunk", type=float, default=0.01, help="chunk [simulated s]")
    args = ap.parse_args(argv)
    import jax

    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, "
          f"{os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 1024**3:.0f} GiB, "
          f"{platform.processor() or platform.platform()}; Python {platform.python_version()}, "
          f"jax {jax.__version__}")
    print("| N | peak RSS [GB] | wall [s] | settling wall [s] | drive steps | steps/s | exit |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.n:
            cmd = command(n, os.path.join(tmp, f"bed_{n}.h5"), args.settle, args.duration,
                          args.chunk)
            # each N in a fresh wrapper process: RUSAGE_CHILDREN is then this child's alone
            wrapper = ("import json, resource, subprocess, sys, time\n"
                       "t = time.perf_counter(); p = subprocess.run(sys.argv[1:], "
                       "capture_output=True, text=True)\n"
                       "print(json.dumps({'code': p.returncode, 'wall': time.perf_counter() - t,"
                       " 'kb': resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,"
                       " 'out': p.stdout, 'err': p.stderr}))")
            p = subprocess.run([sys.executable, "-c", wrapper, *cmd], capture_output=True,
                               text=True, check=False)
            r = json.loads(p.stdout)
            settle = re.search(r"settled \d+ grains in [\d.e+-]+ s simulated \(([\d.]+) s wall\)",
                               r["out"])
            rate = re.search(r"(\d+) steps of [\d.e+-]+ s at ([\d.e+-]+) steps/s", r["out"])
            print(f"| {n} | {r['kb'] / 1024**2:.2f} | {r['wall']:.0f} | "
                  f"{float(settle.group(1)) if settle else math.nan:.0f} | "
                  f"{rate.group(1) if rate else '-'} | "
                  f"{float(rate.group(2)) if rate else math.nan:.3g} | {r['code']} |",
                  flush=True)
            if r["code"] != 0:
                print("    " + r["err"].strip().splitlines()[-1] if r["err"].strip() else "")
    print("command (N = 50000): " + " ".join(command(50000, "bed.h5", args.settle,
                                                        args.duration, args.chunk)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
