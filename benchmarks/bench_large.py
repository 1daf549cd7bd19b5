"""Large beds, one system each: jaxdamp against LAMMPS in ns per particle-step (issue 38 item 4).

    python benchmarks/bench_large.py                          # N = 1000, 4000, 16000, 50000
    python benchmarks/bench_large.py --n 1000 4000 --rounds 1 --seconds 2
    python benchmarks/bench_large.py --n 1000 16000 50000 200000 --json large.json
    python benchmarks/bench_large.py --engine jax --precision float32 --no-lammps \\
        --n 1000 4000 16000 50000 200000 1000000             # on a machine with a GPU

**The bed.** The thesis damper ``sanchez2012-optimal`` (3 mm steel grains, Hertz +
viscoelastic damping, Coulomb-capped viscous friction, reduced modulus) scaled in base area at
the same depth: the square base grows with N at the preset's grains per area, side
``L = 0.03675 m × sqrt(N / 250)`` (and the primary's M, K, C × N/250), exactly the beds of
``benchmarks/large_bed.py`` (:func:`scaled_overrides` takes its ``--set`` items). For the timing
the box is *driven* (``system = 'driven'``, 3 cm at 15 Hz, the resonant amplitude of the
coupled damper), as in ``benchmarks/bench_lammps.py``: LAMMPS has no coupled 1-DOF primary.

**The moving state.** The grains are poured on their lattice and settled for only
``--settle`` simulated seconds (a bed whose grains touch, not one at rest: the settling cost
grows with N; :func:`jaxdamp.engine.packing.settle` runs in 20 ms pieces, so 0.03 s is 0.04 s),
then driven for ``--warm`` simulated seconds so that the bed is in motion, on
``--warm-engine`` (default ``auto``: the native kernel on a CPU host), float64. The warmed
state is cached as ``.npz`` under ``--cache`` (default ``~/.cache/jaxdamp-bench/``) keyed by N
and the SHA-256 of the warm-up configuration, the warm time and the record interval, so a
rerun skips the warm-up; its wall time is printed either way. That state is handed to both
codes as ``bench_lammps.py`` does it (positions, velocities and spins relative to the box, the
drive's phase: :func:`bench_lammps.lammps_input`), same dt, same physics (the contact mapping
of :mod:`jaxdamp.peers.lammps`), same neighbour skin.

**Configurations** per N and round, each timed from the same state over the same steps:

* jaxdamp, one system (batch 1), through the production chunk function
  (:func:`bench_lammps.time_jaxdamp`: compiled by one untimed call of the same chunk, then
  timed), engine ``--engine`` (``native`` | ``jax`` | ``fused``) at ``--precision``; the
  JAX engine's neighbour lists are those ``time_jaxdamp`` allocates (1.5× headroom), an
  overflow during the timed chunk is not looked at;
* LAMMPS on 1 process; LAMMPS on 2 MPI processes (``mpirun -np 2``), both
  ``OMP_NUM_THREADS=1`` (:func:`bench_lammps.run_lammps`; its ``Loop time``).

The steps per N are chosen so that the jaxdamp measurement takes about ``--seconds``: a probe
of ``--record-every`` steps (repeated over about a fifth of the target when it took under a
tenth: one chunk's fixed cost) measures the cost per step at that N, so the steps scale as 1/N;
``--steps`` fixes them instead. Rounds are interleaved (round 1 runs every N, smallest first,
then round 2, ...: the host's drift over the session hits every N alike), and every
measurement waits until the machine is quiet (``bench_lammps.wait_quiet``: less than 5 % of
the cores busy; the load found is recorded).

**Printed:** the machine (cores, CPU, versions, LAMMPS' version line), the command, then one
Markdown table — N | jaxdamp ns per particle-step | LAMMPS 1 process | LAMMPS 2 MPI | throughput
ratio LAMMPS-2MPI / jaxdamp (> 1: jaxdamp faster), the best (min) of the rounds' figures and
each round's own ratio (a round's LAMMPS against the same round's jaxdamp, seconds apart; this
host's speed drifts by tens of percent between rounds, see ``bench_lammps.py``) | jaxdamp's
cost per particle-step relative to its figure at the smallest N — and a table of peak
resident memory (Linux ``ru_maxrss``): this process' peak after each N's first round (N
ascending, so the peak of the warm-ups and timings of the N's up to this one) and that of one
LAMMPS process running ``--record-every`` steps of the same deck (under a small wrapper
process: a child of this one would inherit its resident set through fork), each with its
growth per added grain between successive N's (at the first N over this process' peak before
the first warm-up, which includes every compilation). ``--json PATH`` writes every
measurement. Without ``lmp`` (:func:`jaxdamp.peers.lammps.executable`) or with ``--no-lammps``
the LAMMPS columns are skipped (said so); without ``mpirun`` the 2-MPI column.

Per-particle-step cost: ns per particle-step = wall time / (steps × N) × 1e9.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import os
import platform
import resource
import shlex
import shutil
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import bench_lammps as bl  # noqa: E402  (the deck, the LAMMPS runner, quietness, jaxdamp timing)
import large_bed  # noqa: E402  (the scaled thesis bed)

from jaxdamp.peers import lammps  # noqa: E402

DRIVE = {"frequency": 15.0, "drive.amplitude": 0.03}  # bench_lammps' thesis bed: 3 cm at 15 Hz
DEFAULT_CACHE = os.path.join(os.path.expanduser("~"), ".cache", "jaxdamp-bench")
JD, L1, L2 = "jaxdamp", "LAMMPS 1 process", "LAMMPS 2 MPI"


# ------------------------------------------------------------------------------- the bed


def scaled_overrides(n: int) -> tuple[str, list[str]]:
    """``(preset, overrides)`` of the thesis damper scaled to ``n`` grains: the ``--set`` items
    of :func:`large_bed.command` (base side ``L0 sqrt(n/250)``, primary ``M, K, C × n/250``),
    without its run-length settings (settling, duration, chunk)."""
    argv = large_bed.command(n, "unused.h5", 0.0, 0.0, 0.0)
    preset = argv[argv.index("--preset") + 1]
    sets = [b for a, b in zip(argv, argv[1:]) if a == "--set"]
    return preset, [s for s in sets if not s.startswith("numerics.")]


def bed_config(n: int, settle: float, engine: str = "auto", precision: str = "float64"):
    """The driven, scaled thesis bed of ``n`` grains (a validated :class:`Config`):
    ``settle`` [s] of settling, ``numerics.engine = engine`` and ``numerics.precision``.
    Raises ``ConfigError`` for a bad combination (e.g. the native engine in float32)."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.validation import validate

    preset, over = scaled_overrides(n)
    over = over + ["system='driven'", *(f"{k}={v}" for k, v in DRIVE.items()),
                   f"numerics.settle_time={settle!r}", f"numerics.engine='{engine}'",
                   f"numerics.precision='{precision}'"]
    return validate(apply_overrides(presets.get(preset), over))


def cache_key(cfg, warm: float, every: int) -> str:
    """SHA-256 (first 16 hex digits) of the warm-up: the configuration (its JSON), the drive
    time ``warm`` [s] and the record interval ``every`` [steps] (the chunking of the drive)."""
    text = json.dumps(dict(config=json.loads(cfg.to_json()), warm=warm, every=every),
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def cache_path(cache: str, cfg, warm: float, every: int) -> str:
    return os.path.join(cache, f"large_N{cfg.n_grains}_{cache_key(cfg, warm, every)}.npz")


def save_state(path: str, st, meta: dict) -> None:
    """The state ``st`` (one system) and ``meta`` as ``path`` (written whole or not at all)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + ".tmp.npz"
    np.savez(tmp, meta=json.dumps(meta),
             **{f.name: np.asarray(getattr(st, f.name)) for f in dataclasses.fields(st)})
    os.replace(tmp, path)


def load_state(path: str, key: str):
    """``(state, meta)`` stored at ``path`` under ``key``, else ``None``."""
    from jaxdamp.physics.model import State

    if not os.path.exists(path):
        return None
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        if meta.get("key") != key:
            return None
        st = State(**{f.name: z[f.name] for f in dataclasses.fields(State)})
    return st, meta


def warm_state(cfg, warm: float, every: int, cache: str | None, log=print):
    """The state (one system, numpy) of the bed ``cfg`` settled for its
    ``numerics.settle_time`` then driven ``warm`` simulated seconds on its
    ``numerics.engine``, from the cache when stored there under the same key; and a dict of
    what was done (wall times [s], bed height, reused). Drives like
    :func:`bench_lammps.moving_bed`: the settled bed dropped into the box at the top of its
    stroke (t = 0), then ``round(warm / (dt × every))`` records of ``every`` steps."""
    import jax

    from jaxdamp.engine import driver
    from jaxdamp.engine.packing import settle
    from jaxdamp.physics.model import build
    from jaxdamp.studies.runner import initial_box_position

    key = cache_key(cfg, warm, every)
    path = cache_path(cache, cfg, warm, every) if cache else None
    if path is not None and (got := load_state(path, key)) is not None:
        st, meta = got
        log(f"N = {cfg.n_grains}: warm state reused from {path} (it took "
            f"{meta['settle_wall']:.1f} s settling + {meta['warm_wall']:.1f} s driving)")
        return st, dict(meta, reused=True, path=path)
    model, params = build(cfg)
    t0 = time.perf_counter()
    bed = settle(cfg, model, params)
    t1 = time.perf_counter()
    z0 = initial_box_position(cfg, float(np.asarray(params.mass).sum()))  # the top, t = 0
    one = lambda x: np.asarray(x)[None]  # noqa: E731
    batch = driver.start(model, driver.batched(params), one(bed.r + [0.0, 0.0, z0]),
                         one(bed.v), one(bed.w), one(bed.q), np.full(1, z0), np.zeros(1),
                         engine=cfg.numerics.engine, multiplier=cfg.numerics.capacity_multiplier)
    n_rec = max(1, int(round(warm / (float(params.dt) * every))))
    batch, _ = driver.advance(batch, n_rec, every)
    st = jax.tree_util.tree_map(lambda x: np.asarray(x)[0], batch.states)
    t2 = time.perf_counter()
    meta = dict(key=key, n=model.n, settle_time=float(bed.time), settled=bool(bed.settled),
                bed_height=float(bed.height), bed_max_speed=float(bed.max_speed),
                warm=float(st.t), warm_steps=n_rec * every, engine=batch.engine,
                settle_wall=t1 - t0, warm_wall=t2 - t1)
    log(f"N = {model.n}: settled {bed.time:.3g} s simulated in {t1 - t0:.1f} s wall (bed "
        f"{bed.height * 1e3:.1f} mm high, fastest grain {bed.max_speed:.3g} m/s), driven "
        f"{float(st.t):.3g} s ({n_rec * every} steps, {batch.engine}) in {t2 - t1:.1f} s wall")
    if path is not None:
        save_state(path, st, meta)
        log(f"  cached as {path}")
    return st, dict(meta, reused=False, path=path)


# ------------------------------------------------------------------------------- timing


def steps_for(seconds_per_step: float, target: float, every: int) -> int:
    """Steps (a multiple of ``every``, at least ``every``) that take about ``target`` [s] at
    ``seconds_per_step`` [s] per step of the whole bed."""
    if not seconds_per_step > 0:
        raise ValueError(f"seconds per step must be positive, got {seconds_per_step!r}")
    return max(1, int(round(target / seconds_per_step / every))) * every


def ns_per_particle_step(wall: float, steps: int, n: int) -> float:
    return wall / (steps * n) * 1e9


def peak_rss_kb() -> int:
    """Peak resident set [kB] of this process so far (Linux ``ru_maxrss``)."""
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)


#: A tiny process that runs its arguments and prints the child's peak resident set [kB] and
#: output: a child of *this* process would inherit this process' resident set through fork
#: and exec in its ``ru_maxrss`` (as ``benchmarks/large_bed.py`` found), so LAMMPS' own peak
#: is read from under a ~10 MB wrapper instead.
RSS_WRAPPER = ("import json, resource, subprocess, sys\n"
               "p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
               "print(json.dumps({'kb': resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,"
               " 'out': p.stdout + p.stderr}))")


def lammps_peak_kb(cfg, params, st, steps: int, workdir: str) -> int:
    """Peak resident set [kB] of one LAMMPS process (``lmp``, as :func:`bench_lammps.run_lammps`
    starts it) running ``steps`` steps of the bed from ``st``: its own deck in ``workdir``."""
    import subprocess

    deck = bl.lammps_input(cfg, params, st, steps, workdir)
    cmd = [sys.executable, "-c", RSS_WRAPPER, shutil.which("lmp"), "-in", deck, "-log", "none",
           "-nocite"]
    p = subprocess.run(cmd, cwd=workdir, env=dict(os.environ, OMP_NUM_THREADS="1"),
                       capture_output=True, text=True, check=True)
    r = json.loads(p.stdout)
    bl.loop_time(r["out"])  # raises with LAMMPS' output if it failed
    return int(r["kb"])


def machine() -> dict:
    import importlib.metadata

    import jax

    import jaxdamp

    try:
        numba = importlib.metadata.version("numba")
    except importlib.metadata.PackageNotFoundError:
        numba = "absent"

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            names = [ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")]
        cpu = names[0] if names else cpu
    except OSError:
        pass
    dev = jax.devices()[0]
    return dict(cores=os.cpu_count(), cpu=cpu, machine=platform.machine(),
                memory_gib=os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1024**3,
                python=platform.python_version(), jax=jax.__version__,
                numba=numba, jaxdamp=jaxdamp.__version__,
                backend=jax.default_backend(), device=dev.device_kind)


def lammps_status(no_lammps: bool) -> tuple[bool, bool, str]:
    """``(run LAMMPS at all, run it on 2 MPI processes, why not / the version line)``."""
    if no_lammps:
        return False, False, "LAMMPS skipped (--no-lammps)"
    exe = lammps.executable()
    if exe is None:
        return False, False, "LAMMPS skipped: no `lmp` on the PATH"
    if shutil.which("lmp") is None:  # bench_lammps.run_lammps runs `lmp`
        return False, False, f"LAMMPS skipped: only {exe} found, the runner needs `lmp`"
    mpi = shutil.which("mpirun") is not None
    return True, mpi, lammps.version(exe) + ("" if mpi else "; no mpirun: 2-MPI column skipped")


# ------------------------------------------------------------------------------- output


def fmt(x) -> str:
    """Three significant digits, whole numbers from 100 up (no exponents); "-" for none."""
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.3g}"


def summarise(rows: dict, ns: list[int]) -> dict:
    """Per N: the best (min) of the rounds per configuration, the ratio LAMMPS-2MPI / jaxdamp
    (and LAMMPS 1 process / jaxdamp) of the minima and round by round, and jaxdamp's cost
    relative to the smallest N's (of the minima)."""
    out = {}
    base = None
    for n in ns:
        r = rows.get(n, {})
        best = {k: float(min(v)) for k, v in r.items() if v}
        if JD in best and base is None:
            base = best[JD]
        s = dict(best=best, relative=best[JD] / base if JD in best else None)
        for name, other in (("lammps2_over_jaxdamp", L2), ("lammps1_over_jaxdamp", L1)):
            if JD in best and other in best:
                s[name] = best[other] / best[JD]
                s[name + "_per_round"] = [a / b for a, b in zip(r[other], r[JD])]
        out[n] = s
    return out


def table(summary: dict, ns: list[int], n0: int) -> list[str]:
    lines = ["| N | jaxdamp ns/particle-step | LAMMPS 1 proc | LAMMPS 2 MPI | "
             "LAMMPS-2MPI / jaxdamp: best (per round) | jaxdamp cost / its N = "
             f"{n0} |", "| --- | --- | --- | --- | --- | --- |"]
    for n in ns:
        s = summary[n]
        b = s["best"]
        ratio = "-"
        if "lammps2_over_jaxdamp" in s:
            per = ", ".join(f"{x:.2f}" for x in s["lammps2_over_jaxdamp_per_round"])
            ratio = f"{s['lammps2_over_jaxdamp']:.2f} ({per})"
        lines.append(f"| {n} | {fmt(b.get(JD))} | {fmt(b.get(L1))} | {fmt(b.get(L2))} | "
                     f"{ratio} | {fmt(s['relative'])} |")
    return lines


def memory_table(memory: dict, ns: list[int], rss0: int) -> list[str]:
    """Peak RSS by N and the growth per added grain: ``(peak − peak at the previous N) /
    (N − previous N)``, at the first N over the peak ``rss0`` [kB] before the first warm-up
    (that first figure includes every compilation and one-off allocation)."""
    lines = ["| N | jaxdamp process peak RSS [MB] | its growth per added grain [kB] | "
             "LAMMPS process peak RSS [MB] | its growth per added grain [kB] |",
             "| --- | --- | --- | --- | --- |"]
    prev = None
    for n in ns:
        m = memory.get(n)
        if m is None:
            continue
        lm = m.get("lammps_kb")
        if prev is None:
            grow, lgrow = (m["self_kb"] - rss0) / n, None
        else:
            grow = (m["self_kb"] - prev[1]["self_kb"]) / (n - prev[0])
            lgrow = ((lm - prev[1]["lammps_kb"]) / (n - prev[0])
                     if lm and prev[1].get("lammps_kb") else None)
        lines.append(f"| {n} | {m['self_kb'] / 1024:.0f} | {fmt(grow)} | "
                     f"{fmt(lm / 1024 if lm else None)} | {fmt(lgrow)} |")
        prev = (n, m)
    return lines


# ------------------------------------------------------------------------------- main


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, nargs="+", default=[1000, 4000, 16000, 50000],
                    help="grains per bed (one system each)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--engine", default="native", choices=["native", "jax", "fused"])
    ap.add_argument("--precision", default="float64", choices=["float64", "float32"],
                    help="numerics.precision of the timed jaxdamp engine (float32: jax only)")
    ap.add_argument("--warm-engine", default="auto", choices=["auto", "native", "jax", "fused"],
                    help="engine of the (float64) settling and warm-up drive")
    ap.add_argument("--seconds", type=float, default=4.0,
                    help="target wall time of one jaxdamp measurement [s]")
    ap.add_argument("--steps", type=int, help="steps per measurement at every N (no probe)")
    ap.add_argument("--record-every", type=int, default=100, help="steps per record")
    ap.add_argument("--settle", type=float, default=0.03, help="settling [simulated s]")
    ap.add_argument("--warm", type=float, default=0.04, help="drive before timing [simulated s]")
    ap.add_argument("--cache", default=DEFAULT_CACHE, help="directory of the warmed states")
    ap.add_argument("--no-cache", action="store_true", help="warm up afresh, store nothing")
    ap.add_argument("--no-lammps", action="store_true")
    ap.add_argument("--quiet-timeout", type=float, default=120.0,
                    help="longest wait for a quiet machine before a measurement [s]")
    ap.add_argument("--json", help="write every measurement here")
    args = ap.parse_args(argv)
    for name in ("rounds", "record_every"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')} = {getattr(args, name)}: must be >= 1")
    if min(args.n) < 1:
        ap.error(f"--n: every bed needs at least 1 grain, got {min(args.n)}")
    for name in ("seconds", "warm"):
        if not getattr(args, name) > 0:
            ap.error(f"--{name} = {getattr(args, name)}: must be > 0")
    if args.settle < 0:
        ap.error(f"--settle = {args.settle}: must be >= 0")
    if args.steps is not None and args.steps < args.record_every:
        ap.error(f"--steps = {args.steps}: at least --record-every = {args.record_every}")
    ns = sorted(set(args.n))
    from jaxdamp.config import ConfigError
    from jaxdamp.physics.model import build

    # the timed configuration checked before any compute (e.g. native in float32)
    try:
        bed_config(ns[0], args.settle, args.engine, args.precision)
    except ConfigError as e:
        sys.exit(f"bench_large: --engine {args.engine} --precision {args.precision}: {e}")
    run_lmp, run_mpi, lmp_line = lammps_status(args.no_lammps)
    info = machine()
    command = " ".join(shlex.quote(a) for a in
                       ["python", os.path.relpath(os.path.abspath(__file__))]
                       + (sys.argv[1:] if argv is None else list(argv)))
    print(f"machine: {info['cores']} cores, {info['cpu']} ({info['machine']}), "
          f"{info['memory_gib']:.0f} GiB; JAX {info['backend']} ({info['device']}); Python "
          f"{info['python']}, jax {info['jax']}, numba {info['numba']}, jaxdamp "
          f"{info['jaxdamp']}; {lmp_line}")
    print(f"command: {command}")
    print(f"timed: jaxdamp {args.engine} {args.precision}, one system; warm-up: settle "
          f"{args.settle:g} s, drive {args.warm:g} s on {args.warm_engine} (float64)", flush=True)
    cache = None if args.no_cache else os.path.expanduser(args.cache)
    rss0 = peak_rss_kb()
    beds: dict[int, dict] = {}  # what each N's warm-up and step choice were (JSON)
    live: dict[int, tuple] = {}  # N -> what prepare(N) returned
    rows: dict[int, dict[str, list]] = {}
    loads: dict[int, dict[str, list]] = {}
    memory: dict[int, dict] = {}
    failed: dict[int, str] = {}
    tmp = tempfile.mkdtemp(prefix="bench_large_")

    def dump(done_rounds):
        if args.json:
            res = dict(machine=info, lammps=lmp_line, command=command, args=vars(args),
                       rounds_done=done_rounds, beds=beds, runs=rows, loads=loads,
                       memory=memory, failed=failed, summary=summarise(rows, ns))
            with open(args.json, "w") as fh:
                json.dump(res, fh, indent=1, default=str)

    def measure(n, key, fn):
        loads[n].setdefault(key, []).append(bl.wait_quiet(timeout=args.quiet_timeout))
        rows[n].setdefault(key, []).append(fn())
        print(f"  N = {n}: {key:<17} {rows[n][key][-1]:9.3f} ns/particle-step (load before "
              f"{loads[n][key][-1]:.0%})", flush=True)

    def prepare(n):
        """Round 1 of ``n``: the warmed state, the timed model, the steps, the LAMMPS deck."""
        st, meta = warm_state(bed_config(n, args.settle, args.warm_engine), args.warm,
                              args.record_every, cache)
        cfg = bed_config(n, args.settle, args.engine, args.precision)
        model, params = build(cfg)
        probe = None
        if args.steps:
            steps = args.steps
        else:  # the cost per step at this N: one chunk of `every` steps (after its compile),
            # again over ~1/5 of the target when that was short (the chunk's fixed cost)
            k = args.record_every
            while True:
                wall, k = bl.time_jaxdamp(model, params, st, 1, k, args.record_every,
                                          engine=args.engine)
                probe = wall / k
                if wall >= 0.1 * args.seconds or k > args.record_every:
                    break
                k = steps_for(probe, 0.2 * args.seconds, args.record_every)
            steps = steps_for(probe, args.seconds, args.record_every)
        deck = (bl.lammps_input(cfg, params, st, steps, tempfile.mkdtemp(prefix=f"N{n}_", dir=tmp))
                if run_lmp else None)
        beds[n] = dict(meta, steps=steps, probe_s_per_step=probe, dt=float(params.dt))
        rows[n], loads[n] = {}, {}
        print(f"N = {n}: {steps} steps per measurement (dt = {float(params.dt):.4g} s"
              + (f"; probe {probe * 1e3:.3g} ms per step)" if probe else ")"), flush=True)
        return cfg, model, params, st, steps, deck

    def one_round(n, first):
        if n not in live:
            live[n] = prepare(n)
        cfg, model, params, st, steps, deck = live[n]

        def jd():
            wall, k = bl.time_jaxdamp(model, params, st, 1, steps, args.record_every,
                                      engine=args.engine)
            return ns_per_particle_step(wall, k, n)

        measure(n, JD, jd)
        if run_lmp:
            measure(n, L1, lambda: ns_per_particle_step(max(bl.run_lammps(deck)), steps, n))
        if run_mpi:
            measure(n, L2, lambda: ns_per_particle_step(max(bl.run_lammps(deck, mpi=2)), steps,
                                                        n))
        if first:  # N ascending: this process' peak is that of everything up to this N
            memory[n] = dict(self_kb=peak_rss_kb(), lammps_kb=lammps_peak_kb(
                cfg, params, st, args.record_every,
                tempfile.mkdtemp(prefix=f"N{n}_rss_", dir=tmp)) if run_lmp else None)

    try:
        for rnd in range(args.rounds):
            print(f"\nround {rnd + 1} of {args.rounds}", flush=True)
            for n in ns:
                if n in failed:
                    continue
                try:
                    one_round(n, rnd == 0)
                except Exception as e:  # noqa: BLE001  (e.g. out of device memory: go on)
                    failed[n] = f"{type(e).__name__}: {e}"
                    print(f"  N = {n} FAILED, dropped from the rounds: {failed[n][:2000]}",
                          flush=True)
            dump(rnd + 1)
    finally:  # the decks (tens of MB at large N)
        shutil.rmtree(tmp, ignore_errors=True)
    dump(args.rounds)
    done = [n for n in ns if rows.get(n, {}).get(JD)]
    summary = summarise(rows, done)
    busiest = max((max(v) for d in loads.values() for v in d.values()), default=0.0)
    print(f"\nns per particle-step, best of {args.rounds} round(s); ratio > 1: jaxdamp faster "
          f"(jaxdamp {args.engine} {args.precision}, one system; busiest load before a "
          f"measurement {busiest:.0%})")
    if not run_lmp:
        print(lmp_line)
    print("\n".join(table(summary, done, done[0]) if done else ["(nothing measured)"]))
    if memory:
        print(f"\npeak resident memory (ru_maxrss) after each N's first round; growth per "
              f"added grain between successive N's, at the first N over this process' "
              f"{rss0 / 1024:.0f} MB before the first warm-up (compilations included)")
        print("\n".join(memory_table(memory, done, rss0)))
    for n, why in failed.items():
        print(f"N = {n}: failed: {why[:300]}")
    print(f"\ncommand: {command}")
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
