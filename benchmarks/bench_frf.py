"""Batched FRF throughput of jaxdamp, and LAMMPS on the same bed as a peer.

    python benchmarks/bench_frf.py                    # batch of 32 frequencies + LAMMPS
    python benchmarks/bench_frf.py --no-lammps --steps 2000

jaxdamp: the ``sanchez2012-optimal`` bed (250 grains, settled), a batch of 32 frequencies
(8–25 Hz) through the production chunk function, per engine. Prints system-steps/s,
particle-steps/s and the projected wall time of a full 30-frequency FRF (5 s simulated each).

LAMMPS (``lmp``, GRANULAR package; ``apt-get install lammps``): the same settled positions,
Hertz contacts with viscoelastic damping and Coulomb friction, the box walls as a
``wall/gran/region`` moving sinusoidally at 15 Hz (prescribed motion; LAMMPS has no coupled
1-DOF primary). Two runs at once (one per core), as jaxdamp uses both cores. The damping
constants are not matched to jaxdamp's (different parameterisation): this compares
throughput on the same bed, not physics. Do not run while other jobs use the cores.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import tempfile
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import settle
from jaxdamp.engine.simulate import chunk_fn, init_states
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build

LAMMPS_INPUT = """
units si
atom_style sphere
boundary f f f
newton off
comm_modify vel yes
region sim block -0.001 {Lx1} -0.001 {Ly1} -0.02 {Zt} units box
create_box 1 sim
{atoms}
set type 1 diameter {d} density {rho}
variable zb equal {U}*cos(2*PI*{f}*time)
region cup block 0 {Lx} 0 {Ly} 0 {Lz} side in units box move NULL NULL v_zb
pair_style granular
pair_coeff * * hertz/material {E} {eta} {nu} tangential linear_nohistory 1.0 {mu} damping viscoelastic
fix walls all wall/gran/region granular hertz/material {E} {eta} {nu} tangential linear_nohistory 1.0 {mu} damping viscoelastic region cup
fix integrate all nve/sphere
fix g all gravity 9.8 vector 0 0 -1
neighbor {skin} bin
neigh_modify delay 0 every 1 check yes
timestep {dt}
thermo 0
run {steps}
"""


def jaxdamp_throughput(engine, steps, batch=32):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.3"])
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    freqs = np.linspace(8, 25, batch)
    pb = jax.tree_util.tree_map(lambda x: jnp.stack([x] * batch), params)
    import dataclasses

    pb = dataclasses.replace(pb, omega=jnp.asarray(2 * np.pi * freqs))
    rep = lambda x: np.stack([x] * batch)  # noqa: E731
    z0 = -float(np.asarray(params.mass).sum()) * cfg.gravity / cfg.primary.K
    st = init_states(model, pb, rep(bed.r + [0, 0, z0]), rep(bed.v), rep(bed.w), rep(bed.q),
                     jnp.full(batch, z0), jnp.zeros(batch))
    nbrs = nb.allocate(model, box_frame(st), 1.5)
    every = 100
    fn = chunk_fn(model, max(1, steps // every), every, engine=engine)
    out = fn(st, nbrs, pb)
    jax.block_until_ready(out)  # compile; then time from the state after it (bed in motion)
    st, nbrs = out[0], out[1]
    t0 = time.perf_counter()
    jax.block_until_ready(fn(st, nbrs, pb))
    wall = time.perf_counter() - t0
    n_steps = max(1, steps // every) * every
    per_sys_step = wall / (n_steps * batch)
    dt = float(params.dt)
    full = 30 * (5.0 / dt) * per_sys_step
    return per_sys_step, full, model.n, bed, cfg, dt


def lammps_run(bed, cfg, dt, steps, workdir):
    R = cfg.grains[0].radius
    mat = cfg.grains[0].material
    # the cup starts at z = U (cos 0 = 1): lift the settled bed with it
    atoms = "\n".join(f"create_atoms 1 single {x:.9g} {y:.9g} {z + cfg.primary.U:.9g} units box"
                      for x, y, z in bed.r)
    text = LAMMPS_INPUT.format(
        Lx=cfg.box.Lx, Ly=cfg.box.Ly, Lz=cfg.box.Lz, Lx1=cfg.box.Lx + 0.001,
        Ly1=cfg.box.Ly + 0.001, Zt=cfg.box.Lz + 0.02, atoms=atoms, d=2 * R, rho=mat.density,
        U=cfg.primary.U, f=15.0, E=mat.E * cfg.numerics.stiffness_scale, eta=0.5, nu=mat.nu,
        mu=mat.mu, skin=0.3 * R, dt=dt, steps=steps,
    )
    path = os.path.join(workdir, "in.bed")
    with open(path, "w") as fh:
        fh.write(text)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--engine", nargs="+", default=["native", "jax"])
    ap.add_argument("--no-lammps", action="store_true")
    ap.add_argument("--lammps-steps", type=int, default=20000)
    args = ap.parse_args()
    print(f"jax {jax.__version__}, devices {jax.devices()}")
    best = None
    for engine in args.engine:
        steps = args.steps if engine == "native" else max(200, args.steps // 10)
        per, full, n, bed, cfg, dt = jaxdamp_throughput(engine, steps, args.batch)
        print(f"jaxdamp {engine:>6}: batch {args.batch} x N={n}: {per * 1e6:.2f} us/system-step, "
              f"{1 / per:.4g} system-steps/s, {n / per:.4g} particle-steps/s; "
              f"projected 30-frequency FRF (5 s each, dt = {dt:.3g} s): {full / 60:.1f} min")
        if best is None or per < best:
            best = per
    if args.no_lammps:
        return
    lmp = shutil.which("lmp") or shutil.which("lmp_serial")
    if lmp is None:
        print("LAMMPS: `lmp` not found (apt-get install lammps); skipped")
        return
    with tempfile.TemporaryDirectory() as tmp:
        path = lammps_run(bed, cfg, dt, args.lammps_steps, tmp)
        procs = [subprocess.Popen([lmp, "-in", path, "-log", os.path.join(tmp, f"log{i}")],
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  env=dict(os.environ, OMP_NUM_THREADS="1"))
                 for i in range(2)]
        outs = [p.communicate()[0] for p in procs]
    loops = []
    for o in outs:
        m = re.search(r"Loop time of ([\d.eE+-]+) on \d+ procs for (\d+) steps with (\d+) atoms", o)
        if m is None:
            print("LAMMPS failed:\n" + o[-2000:])
            return
        loops.append((float(m.group(1)), int(m.group(2)), int(m.group(3))))
    per_step = np.mean([t / s for t, s, _ in loops])
    both = 2 / per_step  # two systems advanced concurrently
    print(f"LAMMPS (2 runs at once, {loops[0][2]} atoms): {per_step * 1e6:.2f} us/step each, "
          f"{both:.4g} system-steps/s together")
    print(f"throughput ratio jaxdamp (best engine) / LAMMPS x2: {(1 / best) / both:.3f}")


if __name__ == "__main__":
    main()
