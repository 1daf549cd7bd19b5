"""Throughput of one 64-system sweep spread over 1, 2 and 4 devices and over 2 processes
(native engine), against the single-device figure.

    python benchmarks/bench_scaling.py                        # 3 interleaved rounds
    python benchmarks/bench_scaling.py --rounds 1 --duration 0.05 --json out.json

The sweep: ``sanchez2012-optimal`` (250 grains, coupled primary) at 64 frequencies 8–24 Hz,
``--duration`` simulated seconds after the settled bed is dropped in (settling and the first,
compiling sweep excluded: each configuration runs the sweep once to warm up, then times a
second one on the same settled beds). Configurations, each in its own process(es):

* ``1 device``: the plain sweep (the reference);
* ``2 devices``, ``4 devices``: ``XLA_FLAGS=--xla_force_host_platform_device_count=D``, the batch
  sharded over them, the native kernel called once per shard and chunk (``jax.shard_map``);
* ``2 processes × 1 device``, ``2 processes × 2 devices``: ``jax.distributed`` on the loopback
  address, samples gathered to both processes after every chunk (gloo).

On this 2-core machine the devices share the cores: the figure says what sharding and gathering
cost, not what more hardware gains. Every measurement waits until the machine is quiet (less
than 5 % busy, ``bench_lammps.wait_quiet``); rounds are interleaved and the median is reported.
Figures: µs per system-step (wall time of the timed sweep's chunk loop / (64 × steps)) and the
throughput ratio to one device.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from bench_lammps import wait_quiet  # noqa: E402  (one quietness check for all benchmarks)

CONFIGS = {  # name: (processes, devices per process)
    "1 device": (1, 1),
    "2 devices": (1, 2),
    "4 devices": (1, 4),
    "2 processes x 1 device": (2, 1),
    "2 processes x 2 devices": (2, 2),
}

WORKER = """
import json
import numpy as np
import jax
if {processes} > 1:
    jax.distributed.initialize(coordinator_address={address!r}, num_processes={processes},
                               process_id={pid})
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.studies.sweep import sweep
base = apply_overrides(presets.get("sanchez2012-optimal"),
                       ["numerics.chunk={chunk}", "numerics.engine='native'"])
axes = {{"frequency": list(np.linspace(8.0, 24.0, {systems}))}}
beds = {{}}  # settled once, by the warm-up
warm = apply_overrides(base, ["numerics.duration={chunk}"])
sweep(warm, axes, progress=False, echo=None, beds=beds)  # compiles the chunk function
res = sweep(apply_overrides(base, ["numerics.duration={duration}"]), axes, progress=False,
            echo=None, beds=beds)
gather = None
if {processes} > 1:  # one chunk's samples and states gathered to every process, as per chunk
    import time
    from jax.sharding import Mesh, NamedSharding, PartitionSpec
    from jaxdamp.engine.driver import to_host
    per_chunk = sum(v[:, :res.records["t"].shape[1] // {n_chunks}].nbytes
                    for v in res.records.values())
    per_chunk += {systems} * 250 * 20 * 8  # the states: ~20 floats a grain (r, v, w, q, forces)
    n = -(-{systems} // len(jax.devices())) * len(jax.devices())
    mesh = Mesh(np.array(jax.devices()), ("b",))
    x = jax.device_put(np.zeros((n, per_chunk // (8 * {systems}))),
                       NamedSharding(mesh, PartitionSpec("b")))
    to_host(x)
    t0 = time.perf_counter()
    for _ in range(10):
        to_host(x)
    gather = (time.perf_counter() - t0) / 10
print("RESULT", json.dumps(dict(wall=float(res.summary["wall_time"]), gather=gather,
                                 devices=len(jax.devices()))))
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_config(processes: int, devices: int, duration: float, chunk: float, systems: int):
    """Wall time [s] of the timed sweep's chunk loop (process 0) and the devices it used."""
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={devices}")
    address = f"127.0.0.1:{_free_port()}"
    procs = [subprocess.Popen(
        [sys.executable, "-c", WORKER.format(processes=processes, address=address, pid=pid,
                                             duration=duration, chunk=chunk, systems=systems,
                                             n_chunks=max(1, round(duration / chunk)))],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for pid in range(processes)]
    out = []
    for p in procs:
        stdout, stderr = p.communicate(timeout=3600)
        if p.returncode != 0:
            raise RuntimeError(stderr[-3000:])
        out.append(json.loads(stdout.split("RESULT", 1)[1]))
    return out[0]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--systems", type=int, default=64)
    ap.add_argument("--duration", type=float, default=0.1, help="timed simulated seconds")
    ap.add_argument("--chunk", type=float, default=0.025, help="chunk length [s]")
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--json", default=None, help="write the figures to this file")
    args = ap.parse_args(argv)
    from jaxdamp.cases import presets
    from jaxdamp.physics.model import config_dt, grain_radii

    cfg = presets.get("sanchez2012-optimal")
    dt = config_dt(cfg, grain_radii(cfg))
    steps = int(round(args.duration / dt))
    names = [n.strip() for n in args.configs.split(",")]
    times = {n: [] for n in names}
    gathers: dict = {}
    loads = []
    for r in range(args.rounds):
        for n in names:
            loads.append(wait_quiet())
            res = run_config(*CONFIGS[n], args.duration, args.chunk, args.systems)
            times[n].append(res["wall"])
            if res["gather"] is not None:
                gathers.setdefault(n, []).append(res["gather"])
            print(f"round {r + 1}: {n:24s} {res['wall']:.2f} s "
                  f"({res['wall'] / (args.systems * steps) * 1e6:.2f} µs/system-step, "
                  f"{res['devices']} devices)", flush=True)
    ref = float(np.median(times[names[0]]))
    print(f"\n{args.systems}-system sweep, sanchez2012-optimal, {steps} steps of {dt:.3g} s "
          f"timed, {args.rounds} rounds; busiest load before a measurement {max(loads):.0%}; "
          f"machine: {os.cpu_count()} cores, {platform.machine()}")
    print(f"{'configuration':26s} µs/system-step (median [min, max])   throughput vs {names[0]}")
    rows = {}
    for n in names:
        t = np.asarray(times[n])
        us = t / (args.systems * steps) * 1e6
        rows[n] = dict(seconds=t.tolist(), us_per_system_step=float(np.median(us)),
                       ratio=ref / float(np.median(t)))
        print(f"{n:26s} {np.median(us):7.2f} [{us.min():.2f}, {us.max():.2f}]"
              f"{'':16s}{ref / np.median(t):.2f}×")
    n_chunks = max(1, round(args.duration / args.chunk))
    for n in names:
        extra = (float(np.median(times[n])) - ref) / n_chunks
        line = f"{n}: {1e3 * extra:+.1f} ms per chunk against {names[0]}"
        if n in gathers:
            g = float(np.median(gathers[n]))
            line += (f"; of it, gathering one chunk's samples and states to every process "
                     f"(gloo): {1e3 * g:.1f} ms")
            rows[n]["gather_s_per_chunk"] = g
        rows[n]["extra_s_per_chunk"] = extra
        print(line)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(command="python benchmarks/bench_scaling.py "
                           + " ".join(argv if argv is not None else sys.argv[1:]),
                           steps=steps, dt=dt, systems=args.systems, rows=rows,
                           max_load=max(loads), cores=os.cpu_count(),
                           date=time.strftime("%Y-%m-%d")), fh, indent=1)


if __name__ == "__main__":
    main()
