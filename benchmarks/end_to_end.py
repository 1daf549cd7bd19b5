"""End-to-end jobs a user runs, timed as the user feels them, against LAMMPS' projected time.

    python benchmarks/end_to_end.py                          # every job at full size (~1.3 h)
    python benchmarks/end_to_end.py --jobs frf efficiency    # some of them
    python benchmarks/end_to_end.py --scale 0.02             # every job 50x shorter (a check)

Each job is the real command line (``jaxdamp frf|efficiency|run``) in a child process, from
start-up to the written file and figure: import, compilation, settling, the drive, analysis.
Its wall time is what a user waits. Its work is counted from the file it wrote: the steps
every system took (``checkpoint/state/step``, settling excluded), summed over the batch.

LAMMPS' time for the same work is projected from its µs per system-step measured in the same
invocation on the same moving beds as :mod:`bench_lammps` (the thesis bed at 3 cm, 15 Hz; the
2023 reference box at 3 cm, 70 Hz): a batched job at two independent LAMMPS processes'
aggregate rate (LAMMPS' best use of two cores for a sweep), a single run at the faster of one
process and one bed on two MPI processes. The projection counts the drive's steps only, not
LAMMPS' start-up, settling or analysis, so it favours LAMMPS; it uses the thesis bed's rate
for the thesis jobs (LAMMPS drives the box; jaxdamp also integrates the coupled primary) and
the reference box's rate at 3 cm for the amplitude sweep (whose time step varies with the
amplitude; the work is counted in steps). Before every measurement the script waits until
the machine is quiet (under 5 % of the cores busy).

Jobs (``--jobs``):

* ``frf``: the thesis' FRF, 30 frequencies 5–25 Hz, 5 s each, one bed;
* ``frf_x4``: the same with 4 independent beds per frequency (120 systems);
* ``gap_scan``: 10 box heights (the gap_scan experiment's) × 12 frequencies 5–25 Hz, 5 s each;
* ``efficiency``: the 2023 amplitude sweep of the reference box, 9 amplitudes 2–4 cm,
  10 + 50 periods at 70 Hz, one bed;
* ``long_run``: one 197 s run of the thesis damper at 14.5 Hz (the length of the thesis'
  bed-dynamics series).

``--scale s`` multiplies every simulated duration (and the amplitude sweep's periods) by s,
for checking the script; the figures recorded in ``RESULTS.md`` are at ``--scale 1``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import bench_lammps as bl  # noqa: E402  (the moving beds, the LAMMPS deck and runner)

#: Box heights [m] of the gap scan: the gap_scan experiment's (experiments/gap_scan.py).
GAP_LZ = (0.042, 0.057, 0.087, 0.1095, 0.117, 0.1225, 0.147, 0.162, 0.282, 0.372)
THESIS = "sanchez2012-optimal"


def jobs(scale: float) -> dict:
    """name -> (description, command-line arguments, LAMMPS bed, batched?)"""
    d = lambda s: f"{s * scale:.6g}"  # noqa: E731
    freqs12 = ",".join(f"{f:.6g}" for f in np.linspace(5.0, 25.0, 12))
    periods = max(1, int(round(50 * scale)))
    transient = max(1, int(round(10 * scale)))
    return {
        "frf": (f"thesis FRF: 30 frequencies × {d(5.0)} s, 1 bed",
                ["frf", "--preset", THESIS, "--n", "30", "--duration", d(5.0)], "thesis", True),
        "frf_x4": (f"thesis FRF: 30 frequencies × {d(5.0)} s, 4 beds each",
                   ["frf", "--preset", THESIS, "--n", "30", "--duration", d(5.0),
                    "--replicates", "4"], "thesis", True),
        "gap_scan": (f"gap scan: 10 heights × 12 frequencies × {d(5.0)} s, 1 bed",
                     ["frf", "--preset", THESIS, "--frequencies", freqs12, "--lz",
                      ",".join(f"{x:g}" for x in GAP_LZ), "--duration", d(5.0)], "thesis",
                     True),
        "efficiency": (f"2023 amplitude sweep: 9 amplitudes × ({transient} + {periods}) "
                       "periods, 1 bed",
                       ["efficiency", "--preset", "varela2023-reference", "--periods",
                        str(periods), "--transient", str(transient)], "reference", True),
        "long_run": (f"one run of {197 * scale:g} s at 14.5 Hz",
                     ["run", "--preset", THESIS, "--frequency", "14.5", "--duration",
                      d(197.0)], "thesis", False),
    }


def system_steps(path: str) -> int:
    """Steps taken after settling, summed over the systems of a written file."""
    import h5py

    with h5py.File(path, "r") as h:
        return int(np.asarray(h["checkpoint/state/step"][()], np.int64).sum())


def run_job(args: list[str], workdir: str) -> tuple[float, int]:
    out = os.path.join(workdir, "out.h5")
    cmd = [shutil.which("jaxdamp") or "jaxdamp"] + args + ["--out", out, "--overwrite",
                                                            "--no-progress"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr[-2000:]}")
    return wall, system_steps(out)


def lammps_rates(beds, steps: int, rounds: int, quiet) -> dict:
    """µs per system-step of LAMMPS on each bed: two processes' aggregate, one process, one bed
    on two MPI processes (medians over ``rounds``)."""
    rates = {}
    for name in beds:
        cfg, model, params, st = bl.moving_bed(name)
        path = bl.lammps_input(cfg, params, st, steps, tempfile.mkdtemp(prefix="e2e_"))
        got = {"x2": [], "one": [], "mpi2": []}
        for _ in range(rounds):
            quiet()
            got["x2"].append(bl.lammps_us(path, steps, copies=2))
            quiet()
            got["one"].append(bl.lammps_us(path, steps))
            quiet()
            got["mpi2"].append(bl.lammps_us(path, steps, mpi=2))
        rates[name] = {k: float(np.median(v)) for k, v in got.items()}
    return rates


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jobs", nargs="+", default=list(jobs(1.0)), choices=list(jobs(1.0)))
    ap.add_argument("--scale", type=float, default=1.0,
                    help="factor on every simulated duration (1: the recorded figures)")
    ap.add_argument("--lammps-steps", type=int, default=10000,
                    help="steps of each LAMMPS rate measurement")
    ap.add_argument("--lammps-rounds", type=int, default=3)
    ap.add_argument("--quiet-timeout", type=float, default=120.0,
                    help="longest wait [s] for a quiet machine before each measurement")
    ap.add_argument("--json", help="write the measurements here")
    args = ap.parse_args(argv)
    quiet = lambda: bl.wait_quiet(timeout=args.quiet_timeout)  # noqa: E731
    if not args.scale > 0:
        ap.error(f"--scale {args.scale}: must be > 0")
    if shutil.which("lmp") is None:
        sys.exit("end_to_end: `lmp` not found (apt-get install lammps)")
    import jaxdamp

    table = jobs(args.scale)
    chosen = {k: table[k] for k in args.jobs}
    print(f"jaxdamp {jaxdamp.__version__}; {bl.lammps.version()}; "
          f"{platform.machine()}, {os.cpu_count()} cores; scale {args.scale:g}", flush=True)
    rates = lammps_rates(sorted({v[2] for v in chosen.values()}), args.lammps_steps,
                         args.lammps_rounds, quiet)
    for name, r in rates.items():
        print(f"LAMMPS on the {name} bed, µs per system-step (median of "
              f"{args.lammps_rounds}): 2 processes aggregate {r['x2']:.2f}, 1 process "
              f"{r['one']:.2f}, 1 bed on 2 MPI processes {r['mpi2']:.2f}", flush=True)
    rows = {}
    for key, (desc, cli, bed, batched) in chosen.items():
        load = quiet()
        with tempfile.TemporaryDirectory(prefix=f"e2e_{key}_") as tmp:
            wall, steps = run_job(cli, tmp)
        rate = rates[bed]["x2"] if batched else min(rates[bed]["one"], rates[bed]["mpi2"])
        lmp = steps * rate * 1e-6
        rows[key] = dict(description=desc, command="jaxdamp " + " ".join(cli), wall_s=wall,
                         system_steps=steps, us_per_system_step=wall / steps * 1e6,
                         lammps_rate=rate, lammps_projected_s=lmp, ratio=lmp / wall,
                         load_before=load)
        print(f"{key}: {wall / 60:.2f} min, {steps:.3e} system-steps "
              f"({wall / steps * 1e6:.2f} µs each, end to end); LAMMPS projected "
              f"{lmp / 60:.2f} min; ratio {lmp / wall:.2f}", flush=True)
    print("\n| job | command | system-steps | jaxdamp wall | µs / system-step (end to end) "
          "| LAMMPS projected | LAMMPS / jaxdamp |\n|---|---|---|---|---|---|---|")
    for r in rows.values():
        print(f"| {r['description']} | `{r['command']}` | {r['system_steps']:.3g} | "
              f"{r['wall_s'] / 60:.1f} min | {r['us_per_system_step']:.2f} | "
              f"{r['lammps_projected_s'] / 60:.1f} min ({r['lammps_rate']:.2f} µs) | "
              f"{r['ratio']:.2f} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(machine=platform.machine(), cores=os.cpu_count(), scale=args.scale,
                           lammps=rates, jobs=rows), fh, indent=1)


if __name__ == "__main__":
    main()
