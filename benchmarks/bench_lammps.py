"""jaxdamp against LAMMPS on the same moving bed, side by side, as ratios.

    python benchmarks/bench_lammps.py                 # both beds, 3 interleaved rounds
    python benchmarks/bench_lammps.py --beds thesis --rounds 5 --json out.json

Two beds, each brought into motion by jaxdamp and then handed to both codes in the same state
(positions, velocities and spins relative to the box, the drive's phase):

* ``thesis``: the ``sanchez2012-optimal`` bed (250 grains, Hertz + viscoelastic damping,
  Coulomb-capped viscous friction, reduced modulus) in its box driven as a prescribed motion at
  the resonant amplitude of the coupled damper (3 cm at 15 Hz; LAMMPS has no coupled 1-DOF
  primary, so both codes drive the box), after 0.4 s of drive;
* ``reference``: the 2023 paper's reference box (``varela2023-reference``: 300 frictionless
  grains, 8 cm cube, 3 cm at 70 Hz), after 10 periods.

Same physics and time step: the contact mapping of :mod:`jaxdamp.peers.lammps`
(checked there and in ``tests/test_lammps_crosscheck.py``), friction by ``tangential
linear_nohistory γ_s/g μ``; LAMMPS runs in the box frame (static walls, gravity plus the box's
inertial force), which has the same contact work; same neighbour skin (0.3 R), checked every
step.

Configurations, each timed over the same number of steps from the same state (µs per
system-step; "aggregate" = the wall time of the whole batch over systems × steps):

* jaxdamp native engine through the production chunk function (one callback per chunk,
  samples every ``--record-every`` steps): one system, and batches of 8 and 32; the JAX
  engine (``lax.scan``, vmapped step) at batch 32 over ``--jax-steps`` steps;
* LAMMPS: one process; two independent processes at once (aggregate: LAMMPS' best use of two
  cores for a sweep); one bed on two MPI processes (``mpirun -np 2``).

Rounds are interleaved (every configuration once per round) and each measurement waits until
the machine is quiet (``/proc/stat``: less than 5 % of the cores busy over 0.5 s); the median
over rounds is reported with the spread. The ratios printed are the issue's: native batched
against two LAMMPS processes, native single system against LAMMPS on two MPI processes; each
as the ratio of the medians and round by round (a round's LAMMPS against the same round's
jaxdamp, seconds apart: this host's speed drifts by tens of percent between rounds).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from jaxdamp.peers import lammps

HERE = os.path.dirname(os.path.abspath(__file__))
BEDS = {
    "thesis": dict(preset="sanchez2012-optimal", frequency=15.0, amplitude=0.03, warm=0.4),
    "reference": dict(preset="varela2023-reference", frequency=70.0, amplitude=0.03,
                      warm=10 / 70.0),
}


def busy_fraction(interval: float = 0.5) -> float:
    """Fraction of all cores busy over ``interval`` [s] (``/proc/stat``)."""
    def read():
        with open("/proc/stat") as fh:
            v = [float(x) for x in fh.readline().split()[1:]]
        idle = v[3] + v[4]
        return idle, sum(v)
    i0, t0 = read()
    time.sleep(interval)
    i1, t1 = read()
    return 1.0 - (i1 - i0) / max(t1 - t0, 1e-9)


def wait_quiet(limit: float = 0.05, timeout: float = 120.0) -> float:
    t0 = time.time()
    while True:
        b = busy_fraction()
        if b < limit or time.time() - t0 > timeout:
            return b


# ------------------------------------------------------------------------------- the moving bed


def moving_bed(name: str, extra: dict | None = None):
    """The driven configuration and its state after the warm-up: (config, model, params,
    state dict of one system); ``extra``: further overrides of the bed (e.g. its fill)."""
    import jax

    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.engine import driver
    from jaxdamp.engine.packing import settle
    from jaxdamp.physics.model import build
    from jaxdamp.studies.runner import initial_box_position

    b = BEDS[name]
    cfg = presets.get(b["preset"])
    over = [f"frequency={b['frequency']}", "system='driven'",
            f"drive.amplitude={b['amplitude']}"]
    cfg = apply_overrides(cfg, over)
    if extra:
        from jaxdamp.validation import validate

        cfg = validate(apply_overrides(cfg, extra))
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    pb = driver.batched(params)
    z0 = initial_box_position(cfg, float(np.asarray(params.mass).sum()))  # the top, t = 0
    one = lambda x: np.asarray(x)[None]  # noqa: E731
    batch = driver.start(model, pb, one(bed.r + [0.0, 0.0, z0]), one(bed.v), one(bed.w),
                         one(bed.q), np.full(1, z0), np.zeros(1), engine="native",
                         multiplier=cfg.numerics.capacity_multiplier)
    dt = float(params.dt)
    every = 100
    n_rec = max(1, int(round(b["warm"] / (dt * every))))
    batch, _ = driver.advance(batch, n_rec, every)
    st = jax.tree_util.tree_map(lambda x: np.asarray(x)[0], batch.states)
    return cfg, model, params, st


# ------------------------------------------------------------------------------- jaxdamp


def time_jaxdamp(model, params, st, batch: int, steps: int, every: int, engine="native"):
    """Wall time [s] of ``steps`` steps of ``batch`` copies of the state through the
    production chunk function (compiled before timing)."""
    import jax
    import jax.numpy as jnp

    from jaxdamp.engine import neighbors as nb
    from jaxdamp.engine.simulate import chunk_fn
    from jaxdamp.physics.integrate import box_frame
    from jaxdamp.physics.model import State

    states = State(**{f.name: jnp.asarray(np.repeat(np.asarray(getattr(st, f.name))[None],
                                                     batch, 0))
                      for f in dataclasses.fields(st)})
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    nbrs = nb.allocate(model, box_frame(states, pb), 1.5)
    fn = chunk_fn(model, max(1, steps // every), every, engine=engine)
    jax.block_until_ready(fn(states, nbrs, pb))  # compile
    t0 = time.perf_counter()
    jax.block_until_ready(fn(states, nbrs, pb))
    return time.perf_counter() - t0, max(1, steps // every) * every


# ------------------------------------------------------------------------------- LAMMPS


def lammps_input(cfg, params, st, steps: int, workdir: str) -> str:
    """Input deck of the same bed, box frame, no output; returns its path."""
    mp = lammps.build_mapping(cfg)
    z_box, v_box = float(st.z), float(st.zd)
    r = np.asarray(st.r) - [0.0, 0.0, z_box]
    v = np.asarray(st.v) - [0.0, 0.0, v_box]
    data = os.path.join(workdir, "bed.data")
    lammps.write_data(data, r, v, mp, cfg.box, w=np.asarray(st.w))
    text = lammps.box_deck(mp, cfg, cfg.drive.amplitude, data, dt=float(params.dt),
                           t0=float(st.t)) + f"thermo 0\nrun {steps}\n"
    path = os.path.join(workdir, "in.bench")
    with open(path, "w") as fh:
        fh.write(text)
    return path


def loop_time(out: str) -> float:
    m = re.search(r"Loop time of ([\d.eE+-]+) on (\d+) procs for (\d+) steps", out)
    if m is None:
        raise RuntimeError("LAMMPS failed:\n" + out[-2000:])
    return float(m.group(1))


def run_lammps(path: str, copies: int = 1, mpi: int = 1) -> list[float]:
    exe = shutil.which("lmp")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    cwd = os.path.dirname(path)
    if mpi > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(mpi), exe,
               "-in", path, "-log", "none", "-nocite"]
    else:
        cmd = [exe, "-in", path, "-log", "none", "-nocite"]
    procs = [subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True) for _ in range(copies)]
    return [loop_time(p.communicate()[0]) for p in procs]


def lammps_us(path: str, steps: int, copies: int = 1, mpi: int = 1) -> float:
    """µs per system-step of ``copies`` LAMMPS runs of ``steps`` steps at once (each on
    ``mpi`` processes): the slowest copy's loop time over all copies' steps."""
    return max(run_lammps(path, copies=copies, mpi=mpi)) / (copies * steps) * 1e6


# ------------------------------------------------------------------------------- main


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--beds", nargs="+", default=list(BEDS), choices=list(BEDS))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=10000, help="steps per measurement")
    ap.add_argument("--record-every", type=int, default=100)
    ap.add_argument("--batches", type=int, nargs="+", default=[8, 32])
    ap.add_argument("--jax-steps", type=int, default=400,
                    help="steps of the JAX engine's batch-32 measurement (0: skip it)")
    ap.add_argument("--json", help="write the measurements here")
    args = ap.parse_args(argv)
    if shutil.which("lmp") is None:
        sys.exit("bench_lammps: `lmp` not found (apt-get install lammps)")
    import jax

    import jaxdamp

    version = lammps.version()
    print(f"jaxdamp {jaxdamp.__version__}, jax {jax.__version__}; {version}; "
          f"{platform.machine()}, {os.cpu_count()} cores")
    results = {}
    for name in args.beds:
        cfg, model, params, st = moving_bed(name)
        tmp = tempfile.mkdtemp(prefix=f"bench_{name}_")
        path = lammps_input(cfg, params, st, args.steps, tmp)
        rows: dict[str, list] = {}
        loads: list[float] = []

        def measure(key, fn):
            loads.append(wait_quiet())
            rows.setdefault(key, []).append(fn())

        for _ in range(args.rounds):
            for B in [1] + args.batches:
                def jd(B=B):
                    wall, n = time_jaxdamp(model, params, st, B, args.steps, args.record_every)
                    return wall / (n * B) * 1e6
                measure(f"jaxdamp native, batch {B}", jd)
            if args.jax_steps:
                def jx():
                    wall, n = time_jaxdamp(model, params, st, 32, args.jax_steps,
                                           args.record_every, engine="jax")
                    return wall / (n * 32) * 1e6
                measure("jaxdamp JAX engine, batch 32", jx)
            measure("LAMMPS, 1 process",
                    lambda: lammps_us(path, args.steps))
            measure("LAMMPS, 2 processes at once (aggregate)",
                    lambda: lammps_us(path, args.steps, copies=2))
            measure("LAMMPS, 1 bed on 2 MPI processes",
                    lambda: lammps_us(path, args.steps, mpi=2))
        med = {k: float(np.median(v)) for k, v in rows.items()}
        print(f"\n{name} bed ({model.n} grains, dt = {float(params.dt):.3g} s, "
              f"{args.steps} steps per measurement, {args.rounds} rounds; busiest load before "
              f"a measurement {max(loads):.0%}): µs per system-step, median [min, max]")
        for k, v in rows.items():
            print(f"  {k:<45} {med[k]:8.2f}  [{min(v):.2f}, {max(v):.2f}]")
        lmp2 = med["LAMMPS, 2 processes at once (aggregate)"]
        lmp_mpi = med["LAMMPS, 1 bed on 2 MPI processes"]
        ratios = {f"native batch {B} / LAMMPS x2": lmp2 / med[f"jaxdamp native, batch {B}"]
                  for B in args.batches}
        ratios["native single / LAMMPS on 2 MPI processes"] = lmp_mpi / med[
            "jaxdamp native, batch 1"]
        ratios["native single / LAMMPS 1 process"] = (med["LAMMPS, 1 process"]
                                                      / med["jaxdamp native, batch 1"])
        # the same ratios round by round (each round's LAMMPS against the same round's
        # jaxdamp, measured seconds apart): this host's speed drifts between rounds
        pairs = {f"native batch {B} / LAMMPS x2": ("LAMMPS, 2 processes at once (aggregate)",
                                                  f"jaxdamp native, batch {B}")
                 for B in args.batches}
        pairs["native single / LAMMPS on 2 MPI processes"] = (
            "LAMMPS, 1 bed on 2 MPI processes", "jaxdamp native, batch 1")
        pairs["native single / LAMMPS 1 process"] = ("LAMMPS, 1 process",
                                                     "jaxdamp native, batch 1")
        per_round = {k: [a / b for a, b in zip(rows[num], rows[den], strict=True)]
                     for k, (num, den) in pairs.items()}
        for k, v in ratios.items():
            r = per_round[k]
            print(f"  throughput ratio {k}: {v:.2f} (of the medians; round by round "
                  f"{float(np.median(r)):.2f} [{min(r):.2f}, {max(r):.2f}])")
        results[name] = dict(n=model.n, dt=float(params.dt), steps=args.steps, runs=rows,
                             median=med, ratios=ratios, ratios_per_round=per_round,
                             max_load=max(loads))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(lammps=version, machine=platform.machine(), cores=os.cpu_count(),
                           results=results), fh, indent=1)


if __name__ == "__main__":
    main()
