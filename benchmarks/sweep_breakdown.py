"""Where a sweep's wall time goes: phases of the real command, and each system's cost per step.

    python benchmarks/sweep_breakdown.py                      # thesis FRF, 30 frequencies x 1 s
    python benchmarks/sweep_breakdown.py --duration 0.3 --probe-steps 500   # a quick look

The end-to-end jobs (``end_to_end.py``) run at more µs per system-step than the kernel
benchmarks (``bench_lammps.py``, ``device_check.py``). This script says why, in two parts:

1. **Phases.** ``jaxdamp frf --preset sanchez2012-optimal --n N --duration D`` runs in this
   process with every chunk of the time loop timed (:func:`jaxdamp.engine.driver.call_chunk`,
   wrapped) and, for the native engine, the kernel's own time inside each chunk
   (:func:`jaxdamp.engine.native.advance_packed`, wrapped). Printed: start-up, settling and
   compilation (up to the first chunk of the whole sweep), the drive's chunks (kernel time,
   and the process' CPU time against the wall time: how busy the cores were), and analysis,
   file and figure after the last chunk.
2. **Each system's cost.** The packed batch entering the middle chunk of the drive is kept;
   each system is then advanced alone on one thread for ``--probe-steps`` steps (the least of
   ``--rounds`` passes), giving its µs per step, next to the kernel benchmark's moving thesis
   bed (``bench_lammps.moving_bed``) timed the same way.

The wrappers only time and copy; the command computes what it computes without them. Do not run
while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def run_sweep(n: int, duration: float, workdir: str) -> dict:
    """Run the FRF command with the chunk loop timed; returns the phases and the packed batch
    entering the middle drive chunk (native engine)."""
    t0 = time.perf_counter()
    from jaxdamp.cli import main as cli_main
    from jaxdamp.engine import driver, native

    t_import = time.perf_counter() - t0
    chunks, calls = [], []
    orig_chunk, orig_adv = driver.call_chunk, native.advance_packed

    def call_chunk(fn, *args):
        import jax

        start, cpu = time.perf_counter(), time.process_time()
        out = jax.block_until_ready(orig_chunk(fn, *args))
        chunks.append(dict(start=start - t0, wall=time.perf_counter() - start,
                           cpu=time.process_time() - cpu, batch=int(args[0].t.shape[0])))
        return out

    def advance_packed(model, state, params, *rest, **kw):
        start = time.perf_counter()
        out = orig_adv(model, state, params, *rest, **kw)
        calls.append(dict(start=start - t0, wall=time.perf_counter() - start,
                          packed=(model, np.array(state), np.array(params), rest)))
        return out

    driver.call_chunk, native.advance_packed = call_chunk, advance_packed
    try:
        out = os.path.join(workdir, "frf.h5")
        cli_main(["frf", "--preset", "sanchez2012-optimal", "--n", str(n), "--duration",
                  str(duration), "--out", out, "--no-progress"])
    finally:
        driver.call_chunk, native.advance_packed = orig_chunk, orig_adv
    total = time.perf_counter() - t0
    drive = [c for c in chunks if c["batch"] == max(c["batch"] for c in chunks)]
    first = drive[0]["start"]
    end = drive[-1]["start"] + drive[-1]["wall"]
    kernel = sum(c["wall"] for c in calls if c["start"] >= first - 1e-9)
    mid = [c for c in calls if c["start"] >= first - 1e-9]
    return dict(total=total, import_s=t_import, before_drive=first,
                drive=sum(c["wall"] for c in drive), drive_kernel=kernel,
                drive_cpu=sum(c["cpu"] for c in drive),
                after_drive=total - end, n_chunks=len(drive), batch=drive[0]["batch"],
                packed=mid[len(mid) // 2]["packed"] if mid else None)


def per_system(packed, steps: int, rounds: int = 1) -> np.ndarray:
    """µs per step of each system of a packed batch, advanced alone on one thread; the least
    over ``rounds`` passes through the batch (this host's speed drifts by tens of percent
    over seconds)."""
    from jaxdamp.engine import native

    model, st, pm, (sl, pl) = packed[0], packed[1], packed[2], packed[3][:2]
    native.advance_packed(model, st[:1], pm[:1], sl, pl, 1, 2, threads=False)  # compiled
    every = 100
    rec = max(1, steps // every)
    out = np.full(st.shape[0], np.inf)
    for _ in range(rounds):
        for b in range(st.shape[0]):
            t = time.perf_counter()
            native.advance_packed(model, st[b:b + 1], pm[b:b + 1], sl, pl, rec, every,
                                  threads=False)
            out[b] = min(out[b], (time.perf_counter() - t) / (rec * every) * 1e6)
    return out


def benchmark_bed(steps: int, rounds: int) -> float:
    """µs per step of ``bench_lammps``' moving thesis bed, packed and advanced exactly as
    :func:`per_system` advances each system of the sweep."""
    import jax
    from bench_lammps import moving_bed

    from jaxdamp.engine import native

    _, model, params, st = moving_bed("thesis")
    one = lambda tree: jax.tree_util.tree_map(lambda x: np.asarray(x)[None], tree)  # noqa: E731
    states, pb = one(st), one(params)
    packed = (model, np.asarray(native.pack(states)), np.asarray(native.pack(pb)),
              (native.layout(states), native.layout(pb)))
    return float(per_system(packed, steps, rounds)[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=30, help="frequencies of the FRF (default 30)")
    ap.add_argument("--duration", type=float, default=1.0, help="seconds per frequency")
    ap.add_argument("--probe-steps", type=int, default=2000,
                    help="steps per system in part 2 (default 2000)")
    ap.add_argument("--rounds", type=int, default=3,
                    help="passes in part 2; each system's least time is kept (default 3)")
    ap.add_argument("--json", help="write the figures here")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        ph = run_sweep(args.n, args.duration, tmp)
    B = ph["batch"]
    print(f"\njaxdamp frf --preset sanchez2012-optimal --n {args.n} --duration {args.duration}: "
          f"{ph['total']:.1f} s wall on {platform.machine()}, {os.cpu_count()} cores")
    rows = [("import", ph["import_s"]),
            ("start-up, settling, compilation (to the first drive chunk)",
             ph["before_drive"] - ph["import_s"]),
            (f"drive: {ph['n_chunks']} chunks of {B} systems", ph["drive"]),
            ("  of which in the native kernel", ph["drive_kernel"]),
            (f"  (CPU time of the drive: {ph['drive_cpu'] / ph['drive']:.2f} cores busy "
             f"on average)", ph["drive_cpu"]),
            ("analysis, HDF5, figure (after the last chunk)", ph["after_drive"])]
    for name, s in rows:
        print(f"  {name:<62s} {s:8.1f} s  {100 * s / ph['total']:5.1f} %")

    result = dict(command=f"jaxdamp frf --preset sanchez2012-optimal --n {args.n} "
                          f"--duration {args.duration}",
                  machine=f"{platform.machine()}, {os.cpu_count()} cores",
                  phases={k: v for k, v in ph.items() if k != "packed"})
    if ph["packed"] is not None:
        us = per_system(ph["packed"], args.probe_steps, args.rounds)
        bed = benchmark_bed(args.probe_steps, args.rounds)
        f = np.linspace(5.0, 25.0, B)
        print(f"\neach system of the middle drive chunk alone, one thread, {args.probe_steps} "
              f"steps, least of {args.rounds} passes: µs per step")
        print("  " + " ".join(f"{x:.1f}" for x in us))
        print(f"  median {np.median(us):.1f}, mean {us.mean():.1f}, min {us.min():.1f} "
              f"({f[us.argmin()]:.1f} Hz), max {us.max():.1f} ({f[us.argmax()]:.1f} Hz)")
        print(f"  the kernel benchmark's moving thesis bed, same way: {bed:.1f} µs per step; "
              f"sweep mean / benchmark bed = {us.mean() / bed:.2f}")
        result.update(per_system_us=us.tolist(), frequencies_hz=f.tolist(),
                      benchmark_bed_us=bed, probe_steps=args.probe_steps, rounds=args.rounds)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=1)
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
