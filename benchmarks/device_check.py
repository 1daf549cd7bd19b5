"""Device check: agreement with the CPU, then throughput by path, batch and precision — one
command, under 5 minutes on an accelerator.

    python benchmarks/device_check.py                     # on the machine with the device
    python benchmarks/device_check.py --quick             # a smoke test of the script (CPU)
    python benchmarks/device_check.py --budget 200 --batches 1,256,4096
    python benchmarks/device_check.py --tangential-law mindlin --precisions float64
                                                          # the spring with history

1. **A moving state made on the CPU.** The ``sanchez2012-optimal`` bed (250 grains), settled,
   32 copies at 8–25 Hz driven ``--warm`` seconds by the native kernel on the host (grains
   thrown against the lid, neighbour lists rebuilt), so that every path is timed on a bed in
   motion. Larger batches repeat the 32 systems.
2. **Agreement.** From that state, ``--agree-steps`` steps of 4 systems through the XLA step
   on the CPU (the reference), on the default device, through the native kernel and through
   the fused device step (:mod:`jaxdamp.engine.fused`, when numba-cuda finds a GPU); the
   largest position difference from the reference [m] per path and precision.
3. **Throughput.** µs per system-step of the production chunk
   (:func:`jaxdamp.engine.simulate.chunk_fn`, compiled before timing, best of two timed
   chunks) for every path (``xla``: the JAX engine on the default device, by precision;
   ``native``: the compiled kernel on the host's cores, float64; ``fused``: the fused step,
   float64) and batch, in increasing batch until ``--budget`` seconds are spent or the
   device runs out of memory.
4. **The crossovers** of :mod:`jaxdamp.engine.choice`: the smallest batch from which the
   device's float64 XLA step, and its fused step, beat the native kernel at the same batch
   (the native kernel's largest measured batch standing in for larger ones; the fused step
   only if it agreed with the CPU to 1e-9 m), printed as the
   :data:`jaxdamp.engine.choice.MEASURED` entry for this device. With ``--tangential-law
   mindlin`` every path runs the tangential spring with history (its springs loaded by the
   warm-up): agreement and cost of the spring on the device; ``auto``'s table stays the
   viscous law's (it does not pick the fused step for the spring).

5. **The scan** (``--scan``): the 30-frequency × 10-height × 8-replicate thesis scan (2 400
   systems) as the one command a user types (``jaxdamp frf ... --replicates 8``), over
   ``--scan-duration`` simulated seconds (settling included), on ``--scan-engine``; its wall
   time split into settling and driving (the file's ``wall_time``) and projected to 5 s per
   system.

Writes one JSON (``--json``; default ``benchmarks/results/device_<device>_<date>.json``)
whose ``rows`` name the path, batch, precision and µs per system-step. Do not run while
other jobs use the cores (the native rows time the host). This replaces ``bench_device.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import re
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import driver
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.choice import Crossover
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.model import build
from jaxdamp.studies.runner import initial_box_position

HERE = os.path.dirname(os.path.abspath(__file__))
EVERY = 100  # steps per sample: the production chunk's record interval


def moving_state(copies: int, warm: float, tangential: str = "viscous"):
    """``(model, host states, host params, host reference positions)``: ``copies`` systems of
    the thesis bed at 8–25 Hz, settled and driven ``warm`` s by the native kernel (on the
    host, whatever the default device), under the tangential law ``tangential``."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.3",
                                                               "numerics.engine='native'",
                                                               f"tangential_law={tangential!r}"])
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * copies), params)
    pb = dataclasses.replace(pb, omega=jnp.asarray(2 * np.pi * np.linspace(8, 25, copies)))
    z0 = initial_box_position(cfg, float(np.asarray(params.mass).sum()))
    rep = lambda x: np.stack([x] * copies)  # noqa: E731
    b = driver.start(model, pb, rep(bed.r + [0.0, 0.0, z0]), rep(bed.v), rep(bed.w),
                     rep(bed.q), np.full(copies, z0), np.zeros(copies), engine="native",
                     multiplier=cfg.numerics.capacity_multiplier)
    if warm > 0:
        b, _ = driver.advance(b, max(1, round(warm / (float(params.dt) * EVERY))), EVERY)
    host = lambda t: jax.tree_util.tree_map(np.asarray, driver.to_host(t))  # noqa: E731
    return model, host(b.states), host(b.params), np.asarray(driver.to_host(b.nbrs.reference))


def batch_of(tree, batch: int):
    """``batch`` systems cycling through the host pytree's systems."""
    idx = np.arange(batch) % jax.tree_util.tree_leaves(tree)[0].shape[0]
    return jax.tree_util.tree_map(lambda x: x[idx], tree)


def advance(model, states, params, ref, steps: int, path: str, precision: str, device):
    """``(final states, seconds of the last call, seconds of the first)``: ``steps`` steps
    (whole samples) of the batch through ``path`` (``xla``: the JAX engine on ``device``;
    ``native``: the kernel on the host; ``fused``: the CUDA kernel), the first call
    compiling."""
    model = dataclasses.replace(model, precision=precision)
    n_rec = max(1, steps // EVERY)
    engine = {"xla": "jax"}.get(path, "fused" if path.startswith("fused") else path)
    fn = chunk_fn(model, n_rec, EVERY, engine=engine)
    put = (lambda t: jax.device_put(t, device)) if path == "xla" else jax.device_put
    st, pb = put(states), put(params)
    nbrs = put(nb.allocate(model, jnp.asarray(ref), 1.5, radius=jnp.asarray(params.radius)))
    t0 = time.perf_counter()
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)
    again = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)
    best = min(again, time.perf_counter() - t0)
    return out[0], best, first, n_rec * EVERY


def fused_usable() -> tuple[bool, str]:
    """Whether the fused step runs here (numba-cuda and a GPU; not the CPU simulator, far too
    slow for this bed), and why not."""
    from jaxdamp.engine import fused

    ok, why = fused.available()
    if ok and fused.simulated():
        return False, "NUMBA_ENABLE_CUDASIM is set (the simulator is for the tests' tiny beds)"
    return ok, why


def agreement(model, states, params, ref, steps: int, precisions) -> list[dict]:
    """Max |Δr| [m] after ``steps`` steps of 4 systems: every path against the XLA step on
    the CPU, by precision (the native and fused kernels: float64 only)."""
    cpu, dev = jax.devices("cpu")[0], jax.devices()[0]
    s4, p4, r4 = batch_of(states, 4), batch_of(params, 4), ref[np.arange(4) % ref.shape[0]]
    rows = []
    for precision in precisions:
        base = np.asarray(advance(model, s4, p4, r4, steps, "xla", precision, cpu)[0].r)
        paths = [("xla", dev)] + ([("native", None)] if precision == "float64" else [])
        if precision == "float64" and fused_usable()[0]:
            paths.append(("fused", None))
        for path, device in paths:
            got = np.asarray(advance(model, s4, p4, r4, steps, path, precision, device)[0].r)
            rows.append({"path": path, "precision": precision, "steps": steps,
                         "device": {"native": "host", "fused": "cuda:0"}.get(
                             path, getattr(device, "device_kind", "")),
                         "max_abs_dr_m": float(np.max(np.abs(got - base))),
                         "finite": bool(np.isfinite(got).all())})
            print(f"agreement {path:6} {precision} after {steps} steps: max |Δr| = "
                  f"{rows[-1]['max_abs_dr_m']:.3g} m against the XLA step on the CPU",
                  flush=True)
    return rows


#: The fused step's largest |Δr| from the CPU's XLA step, 1000 steps after the same state,
#: for ``auto`` to use it (the XLA step on a device agreed to 2e-15 m, issue 32).
FUSED_AGREES = 1e-9


def crossover(rows: list[dict], kind: str, source: str, agree: list[dict]) -> Crossover:
    """The :data:`jaxdamp.engine.choice.MEASURED` entry from the throughput rows (the fused
    step's only where it agreed with the CPU, :data:`FUSED_AGREES`)."""
    def by_batch(path):
        return {r["batch"]: r["us"] for r in rows if r["path"] == path
                and r["precision"] == "float64" and "us" in r}

    nat = by_batch("native")

    def first_faster(dev: dict):
        if not nat:
            return None
        top = max(nat)
        return next((b for b in sorted(dev) if dev[b] < nat.get(b, nat[top])), None)

    xla, fz = by_batch("xla"), by_batch("fused")
    ok = [r for r in agree if r["path"] == "fused"]
    trusted = bool(ok) and all(r["finite"] and r["max_abs_dr_m"] <= FUSED_AGREES for r in ok)
    return Crossover(kind, os.cpu_count() or 1, xla, nat, first_faster(xla), source, fz,
                     first_faster(fz) if trusted else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--batches", default="1,32,256,1024,4096,16384",
                    help="batches of the device's XLA step (comma-separated)")
    ap.add_argument("--native-batches", default="1,32,256,1024",
                    help="batches of the native kernel on the host")
    ap.add_argument("--fused-batches", default="1,32,256,1024,4096,16384",
                    help="batches of the fused device step (when numba-cuda finds a GPU)")
    ap.add_argument("--fused-registers", default="0",
                    help="register caps of the fused kernel to time (0: none, the default "
                         "kernel; e.g. 0,128: also two blocks per SM, more spills); rows of a "
                         "cap are path 'fused-r<cap>'")
    ap.add_argument("--precisions", default="float64,float32")
    ap.add_argument("--steps", type=int, default=1000, help="steps per timed chunk")
    ap.add_argument("--native-steps", type=int, default=3000,
                    help="steps per timed chunk of the native kernel (its per-call cost: a "
                         "list rebuild and one callback, amortised)")
    ap.add_argument("--agree-steps", type=int, default=1000)
    ap.add_argument("--warm", type=float, default=0.2, help="simulated seconds driven first")
    ap.add_argument("--budget", type=float, default=240.0,
                    help="seconds of throughput rows; larger batches are skipped after it")
    ap.add_argument("--scan", action="store_true",
                    help="also time the 2 400-system thesis scan (jaxdamp frf, one command)")
    ap.add_argument("--scan-only", action="store_true", help="only the scan")
    ap.add_argument("--scan-duration", type=float, default=0.25,
                    help="simulated seconds per system of the scan (settling comes first)")
    ap.add_argument("--scan-engine", default="auto", help="numerics.engine of the scan")
    ap.add_argument("--tangential-law", default="viscous", choices=("viscous", "mindlin"),
                    help="the tangential law of every path (mindlin: the spring with history)")
    ap.add_argument("--quick", action="store_true",
                    help="tiny settings: a check that the script runs (any machine)")
    ap.add_argument("--json", help="output (default benchmarks/results/device_<device>_<date>"
                                   ".json)")
    a = ap.parse_args(argv)
    if a.quick:
        a.batches, a.native_batches, a.steps, a.native_steps = "1,4", "1,2", 100, 100
        a.fused_batches = "1,4"
        a.agree_steps, a.warm, a.budget = 100, 0.01, 60.0
    precisions = a.precisions.split(",")
    dev = jax.devices()[0]
    kind = dev.device_kind
    info = {"jax": jax.__version__, "backend": jax.default_backend(), "device": kind,
            "devices": len(jax.devices()), "host_cores": os.cpu_count(),
            "tangential_law": a.tangential_law,
            "date": datetime.date.today().isoformat(),
            "command": "python benchmarks/device_check.py " + " ".join(argv or [])}
    print(json.dumps(info), flush=True)
    t_start = time.perf_counter()
    if a.scan_only:
        scan = thesis_scan(a.scan_duration, a.scan_engine, a.quick)
        _write(a, kind, info, {"scan": scan}, t_start)
        return
    model, states, params, ref = moving_state(32 if not a.quick else 4, a.warm,
                                              a.tangential_law)
    print(f"moving state: {states.t.shape[0]} systems of {model.n} grains driven {a.warm} s "
          f"({time.perf_counter() - t_start:.0f} s)", flush=True)
    agree = agreement(model, states, params, ref, a.agree_steps, precisions)
    if fused_usable()[0]:  # the fused kernel's registers and spills, from its assembly
        from jaxdamp.engine import fused

        try:
            cc = tuple(int(x) for x in jax.devices()[0].compute_capability.split("."))
            info["fused_resources"] = fused.resources(model, states, params, cc)
        except Exception as e:  # noqa: BLE001 - a report, not a reason to stop the check
            info["fused_resources"] = {"error": f"{type(e).__name__}: {e}"[:400]}
        print(f"fused kernel: {info['fused_resources']}", flush=True)
    rows: list[dict] = []
    t_rows = time.perf_counter()
    cases = [("native", "float64", int(b)) for b in a.native_batches.split(",")]
    usable, why = fused_usable()
    if usable:
        for cap in (int(x) for x in a.fused_registers.split(",")):
            path = "fused" if cap == 0 else f"fused-r{cap}"
            cases += [(path, "float64", int(b)) for b in a.fused_batches.split(",")]
    else:
        print(f"fused: not timed ({why})", flush=True)
    cases += [("xla", p, int(b)) for p in precisions for b in a.batches.split(",")]
    skip: set = set()
    for path, precision, b in cases:
        if (path, precision) in skip:
            continue
        if time.perf_counter() - t_rows > a.budget:
            print(f"{path} {precision} batch {b}: skipped (--budget {a.budget:.0f} s spent)")
            continue
        steps = a.native_steps if path == "native" else a.steps
        if path.startswith("fused"):
            from jaxdamp.engine import fused

            fused.MAX_REGISTERS = int(path[7:]) if path.startswith("fused-r") else None
        try:
            _, best, first, n = advance(model, batch_of(states, b), batch_of(params, b),
                                        ref[np.arange(b) % ref.shape[0]], steps, path,
                                        precision, dev)
        except Exception as e:  # noqa: BLE001 - out of memory ends this path's batches
            rows.append({"path": path, "precision": precision, "batch": b,
                         "error": f"{type(e).__name__}: {e}"[:400]})
            print(f"{path} {precision} batch {b}: {rows[-1]['error'][:200]}", flush=True)
            skip.add((path, precision))
            continue
        us = best / (n * b) * 1e6
        rows.append({"path": path, "precision": precision, "batch": b, "us": us,
                     "steps": n, "compile_and_first_s": first,
                     "particle_steps_per_s": model.n * b * n / best})
        print(f"{path:6} {precision} batch {b:>6}: {us:8.3f} µs per system-step "
              f"({model.n * b * n / best:.3g} particle-steps/s; first call {first:.1f} s)",
              flush=True)
    entry = crossover(rows, kind, f"benchmarks/device_check.py, {info['date']}, jax "
                                  f"{info['jax']}", agree)
    if a.tangential_law == "viscous":
        print("\njaxdamp.engine.choice.MEASURED entry for this device:\n  "
              f"{entry.device_kind!r}: {entry!r},")
    else:  # auto's table is the viscous law's
        print(f"\ncrossovers under tangential_law = {a.tangential_law!r} (not an entry of "
              f"jaxdamp.engine.choice.MEASURED): {entry!r}")
    result = {"agreement": agree, "rows": rows, "crossover": entry._asdict()}
    if a.scan:
        result["scan"] = thesis_scan(a.scan_duration, a.scan_engine, a.quick)
    _write(a, kind, info, result, t_start)


def thesis_scan(duration: float, engine: str, quick: bool = False) -> dict:
    """Time the thesis scan as a user runs it: ``jaxdamp frf`` over 30 frequencies × 10 box
    heights × 8 replicates (2 400 systems; ``quick``: 3 × 2 × 2 at 20–25 Hz) for ``duration``
    simulated
    seconds after settling, in a process of its own. Returns the wall times (total, driving
    from the file's ``wall_time``, settling and start-up the rest) and the projection to 5 s
    simulated per system."""
    import subprocess
    import sys
    import tempfile

    import h5py

    n, lz, reps = (3, "0.09,0.1225", 2) if quick else (
        30, ",".join(f"{x:.4g}" for x in np.linspace(0.07, 0.16, 10)), 8)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "scan.h5")
        cmd = [sys.executable, "-m", "jaxdamp", "frf", "--preset", "sanchez2012-optimal", "--n", str(n), "--lz", lz,
               *(["--fmin", "20", "--fmax", "25"] if quick else []),
               "--replicates", str(reps), "--duration", str(duration), "--set",
               f"numerics.engine='{engine}'", "--out", out, "--no-progress"]
        print("scan: " + " ".join(cmd), flush=True)
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        total = time.perf_counter() - t0
        print(done.stdout[-3000:], done.stderr[-3000:], flush=True)
        if done.returncode != 0:
            return {"command": " ".join(cmd), "error": done.stderr[-2000:], "seconds": total}
        with h5py.File(out, "r") as h5:
            driving = float(h5.attrs["wall_time"])
            used = str(h5.attrs.get("engine", "?"))
    systems = n * len(lz.split(",")) * reps
    projected = (total - driving) + driving * 5.0 / duration
    row = {"command": " ".join(cmd), "systems": systems, "duration_s": duration,
           "engine": used, "wall_s": total, "driving_s": driving,
           "settling_and_startup_s": total - driving, "projected_5s_min": projected / 60}
    print(f"scan: {systems} systems × {duration} s on {used}: {total:.0f} s "
          f"({driving:.0f} s driving); projected to 5 s each: {projected / 60:.1f} min",
          flush=True)
    return row


def _write(a, kind: str, info: dict, result: dict, t_start: float) -> None:
    out = a.json or os.path.join(HERE, "results", "device_" + re.sub(r"[^A-Za-z0-9]+", "_",
                                 kind).strip("_") + f"_{info['date']}"
                       + ("" if a.tangential_law == "viscous" else f"_{a.tangential_law}")
                       + ".json")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as fh:
        json.dump({"info": info, **result, "seconds": time.perf_counter() - t_start}, fh,
                  indent=1)
    print(f"wrote {out} ({time.perf_counter() - t_start:.0f} s in all)")


if __name__ == "__main__":
    main()
