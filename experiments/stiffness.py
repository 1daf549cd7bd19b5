"""Does the reduced Young's modulus change the damper's response? Resonance at the optimum box.

    python experiments/stiffness.py           # full mode
    python experiments/stiffness.py --quick   # minutes: 2 frequencies, short runs

``sanchez2012-optimal`` (Lz = 0.1225 m, C = 7.6 N s/m) near its resonance, for the thesis'
modulus E = 2.03e11 Pa (``stiffness_scale = 1``, dt 6.3x smaller than the default), the
preset's E = 2.03e9 (``0.01``) and E = 2.03e8 (``0.001``). ``gamma_n``, ``gamma_s`` scale as
``stiffness_scale**0.6`` (:mod:`jaxdamp.physics.restitution`): every binary collision keeps its
restitution and tangential impulse, only collisions last longer (λ^-0.4) and static overlaps
grow (λ^-2/3). What this leaves to measure is the collective effect: longer-lasting contacts in
a dense bed, more overlap, a softer bed. Each modulus is one batched sweep over frequencies;
reported per modulus: amplitude per frequency, the resonant amplitude (largest), granular loss
per cycle, the collision time, dt, the bed height and the wall time.

Writes ``data.h5``, ``figure.png`` and ``summary.md`` in ``--out``; raw sweeps in ``--out/raw``.
"""

from __future__ import annotations

import argparse
import os
import time

import h5py
import numpy as np

import jaxdamp
from jaxdamp.analysis.response import resonance
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics.model import collision_time_limit, grain_radii
from jaxdamp.studies.sweep import reuse_or_run

HERE = os.path.dirname(os.path.abspath(__file__))
SCALES = (1.0, 0.01, 0.001)


def settings(quick: bool):
    if quick:
        return dict(freqs=(14.5, 15.25), duration=0.15, settle=0.1, scales=(1.0, 0.01))
    return dict(freqs=(14.0, 14.5, 15.0, 15.5, 16.0), duration=2.5, settle=0.3, scales=SCALES)


def run_one(scale: float, s: dict, raw_dir: str, progress: bool):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "numerics.stiffness_scale": scale, "numerics.duration": s["duration"],
        "numerics.settle_time": s["settle"], "numerics.record_dt": 1e-3, "numerics.chunk": 0.1})
    out = os.path.join(raw_dir, f"sweep_scale{scale:g}.h5")
    axes = {"frequency": list(s["freqs"])}
    res = reuse_or_run(cfg, axes, out, progress=progress)
    with h5py.File(out, "r") as h:
        dt = float(h.attrs["dt"])
    return res, cfg, dt, float(res.summary["wall_time"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(HERE, "stiffness"))
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    s = settings(args.quick)
    os.makedirs(os.path.join(args.out, "raw"), exist_ok=True)
    t0 = time.perf_counter()
    rows = {}
    for scale in s["scales"]:
        res, cfg, dt, wall = run_one(scale, s, os.path.join(args.out, "raw"), not args.no_progress)
        Z = np.asarray(res.summary["amplitude"])
        fp, zp = resonance(s["freqs"], Z)
        t_c = collision_time_limit(cfg, grain_radii(cfg))
        rows[scale] = dict(config=cfg, Z=Z, f_peak=fp, Z_max=float(Z.max()), Z_peak=zp,
                           loss=np.asarray(res.summary["granular_loss_per_cycle"]),
                           balance=np.asarray(res.summary["balance_error"]),
                           E=cfg.grains[0].material.E * scale, dt=dt, t_c=t_c, wall=wall)
    elapsed = time.perf_counter() - t0
    wall = sum(r["wall"] for r in rows.values())  # the sweeps' compute time (settling excluded)
    command = "python experiments/stiffness.py" + (" --quick" if args.quick else "")

    with h5py.File(os.path.join(args.out, "data.h5"), "w") as h:
        h.attrs["jaxdamp_version"] = jaxdamp.__version__
        h.attrs["command"] = command
        h.attrs["wall_time"] = wall
        h.attrs["elapsed"] = elapsed
        h.create_dataset("frequency", data=np.asarray(s["freqs"])).attrs["units"] = "Hz"
        for scale, r in rows.items():
            g = h.create_group(f"scale_{scale:g}")
            g.attrs["config"] = r["config"].to_json()
            g.attrs.update({"E": r["E"], "dt": r["dt"], "t_c": r["t_c"], "wall_time": r["wall"]})
            g.create_dataset("amplitude", data=r["Z"]).attrs["units"] = "m"
            g.create_dataset("granular_loss_per_cycle", data=r["loss"]).attrs["units"] = "J"
            g.create_dataset("balance_error", data=r["balance"]).attrs["units"] = "1"

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    U = rows[s["scales"][0]]["config"].primary.U
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for scale, r in rows.items():
        a1.plot(s["freqs"], r["Z"] / U, "o-", label=f"E = {r['E']:.3g} Pa (dt = {r['dt']:.2g} s)")
        a2.plot(s["freqs"], r["loss"], "o-", label=f"E = {r['E']:.3g} Pa")
    a1.set_xlabel("f [Hz]")
    a1.set_ylabel("Z / U")
    a2.set_xlabel("f [Hz]")
    a2.set_ylabel("granular loss per cycle [J]")
    a1.set_title("optimal box (Lz = 0.1225 m, C = 7.6 N s/m): response", fontsize=9)
    a2.set_title("energy dissipated by the grains per period", fontsize=9)
    for a in (a1, a2):
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "figure.png"), dpi=120)
    plt.close(fig)

    ref = rows[0.01] if 0.01 in rows else rows[s["scales"][0]]
    k15 = int(np.argmin(np.abs(np.asarray(s["freqs"]) - 15.0)))  # a common frequency near f0
    lines = ["# Stiffness sensitivity at the optimal box", "",
             f"Command: `{command}` — wall time {wall / 60:.1f} min of sweeps on 2 cores (settling "
             "excluded). Data `data.h5`, figure "
             "`figure.png`.", "",
             f"`sanchez2012-optimal` (Lz = 0.1225 m, C = 7.6 N s/m, N = 250), {s['duration']} s per "
             f"frequency after settling, frequencies {list(s['freqs'])} Hz, amplitude over the final 10 %. "
             "gamma_n, gamma_s scaled by stiffness_scale^0.6 (same restitution and tangential impulse per "
             "binary collision).", "",
             f"| E [Pa] | t_c at 1 m/s [s] | dt [s] | Z/U per frequency | max Z/U | Δ vs E = 2.03e9 | "
             f"granular loss per cycle at {s['freqs'][k15]:g} Hz [J] | balance error | wall [s] |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for scale, r in rows.items():
        lines.append(
            f"| {r['E']:.3g} | {r['t_c']:.3g} | {r['dt']:.3g} | "
            f"{', '.join(f'{z / U:.2f}' for z in r['Z'])} | {r['Z_max'] / U:.2f} | "
            f"{(r['Z_max'] / ref['Z_max'] - 1) * 100:+.1f} % | {r['loss'][k15]:.3f} | "
            f"{float(np.max(r['balance'])):.1e} | {r['wall']:.0f} |")
    with open(os.path.join(args.out, "summary.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return rows


if __name__ == "__main__":
    main()
