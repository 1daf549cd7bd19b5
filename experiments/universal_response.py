"""The universal response of the optimal damper (thesis fig. 5.2): contact damping on and off.

    python experiments/universal_response.py           # full mode
    python experiments/universal_response.py --quick   # minutes

At the optimal box (``sanchez2012-optimal``: Lz = 0.1225 m, C = 7.6 N s/m, N = 250) the thesis
finds the FRF nearly unchanged when either the normal (``γ_n``) or the tangential (``γ_s``)
contact damping is switched off — but not both — and matched by the single-particle impact
damper (S3) with ``e = 0``. Here: one batched frequency sweep per ``(γ_n, γ_s)`` in
{(3660, 10980), (0, 10980), (3660, 0), (0, 0)} kg s⁻¹ m^-1/2 (thesis values; the preset's
reduced modulus scales them by 0.01^0.6), plus S3 (``sanchez2012-impact``, e = 0, gap 0.0835 m)
with the exact event-driven model and its smooth (differentiable) version.

Reported: the FRF of each case, the granular dissipation per cycle split into collisional
(normal) and frictional (tangential) parts, and how far each case's FRF is from the reference
(3660, 10980). Writes ``data.h5``, ``fig5_2.png``, ``summary.md`` in ``--out``; raw DEM sweeps
in ``--out/raw`` (not committed).
"""

from __future__ import annotations

import argparse
import os
import time

import h5py
import numpy as np

import jaxdamp
from jaxdamp.analysis.response import frf_amplitude, resonance
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies.sweep import reuse_or_run, sweep

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = ((3660.0, 10980.0), (0.0, 10980.0), (3660.0, 0.0), (0.0, 0.0))
F_FULL = (8.0, 10.0, 12.0, 13.0, 13.75, 14.5, 15.25, 16.0, 17.0, 18.5, 20.0, 23.0)


def settings(quick: bool):
    if quick:
        return dict(freqs=(14.5, 15.25), duration=0.3, settle=0.15, cases=CASES[:2],
                    s3_duration=2.0)
    return dict(freqs=F_FULL, duration=2.5, settle=0.3, cases=CASES, s3_duration=10.0)


def _label(gn, gs):
    return f"gn{gn:g}_gs{gs:g}"


def run_dem(gn, gs, s, raw_dir, progress):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "grains.0.material.gamma_n": gn, "grains.0.material.gamma_s": gs,
        "numerics.duration": s["duration"], "numerics.settle_time": s["settle"],
        "numerics.record_dt": 1e-3, "numerics.chunk": 0.1})
    out = os.path.join(raw_dir, f"sweep_{_label(gn, gs)}.h5")
    axes = {"frequency": list(s["freqs"])}
    return reuse_or_run(cfg, axes, out, progress=progress), cfg


def run_s3(method, s):
    cfg = apply_overrides(presets.get("sanchez2012-impact"), {
        "impactor.method": method, "numerics.duration": s["s3_duration"]})
    return sweep(cfg, {"frequency": list(s["freqs"])}, progress=False), cfg


def _split(summary):
    """(collisional, frictional, total) granular loss per cycle [J], arrays over frequency."""
    coll = np.asarray(summary["pp_normal_per_cycle"]) + np.asarray(summary["pw_normal_per_cycle"])
    fric = np.asarray(summary["pp_friction_per_cycle"]) + np.asarray(summary["pw_friction_per_cycle"])
    return coll, fric, np.asarray(summary["granular_loss_per_cycle"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(HERE, "universal_response"))
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    s = settings(args.quick)
    os.makedirs(os.path.join(args.out, "raw"), exist_ok=True)
    f = np.asarray(s["freqs"])
    t0 = time.perf_counter()
    dem = {}
    for gn, gs in s["cases"]:
        res, cfg = run_dem(gn, gs, s, os.path.join(args.out, "raw"), not args.no_progress)
        coll, fric, tot = _split(res.summary)
        dem[(gn, gs)] = dict(cfg=cfg, Z=np.asarray(res.summary["amplitude"]), coll=coll, fric=fric,
                             total=tot, balance=np.asarray(res.summary["balance_error"]),
                             wall=float(res.summary["wall_time"]))
    s3 = {}
    for method in ("event", "smooth"):
        res, cfg = run_s3(method, s)
        s3[method] = dict(cfg=cfg, Z=np.asarray(res.summary["amplitude"]),
                          total=np.asarray(res.summary["granular_loss_per_cycle"]),
                          wall=float(res.summary["wall_time"]))
    elapsed = time.perf_counter() - t0
    # the sweeps' compute time (settling excluded; kept when finished raw DEM sweeps are reused)
    t_dem = sum(d["wall"] for d in dem.values())
    wall = t_dem + sum(d["wall"] for d in s3.values())
    ref = dem[CASES[0]]
    p = ref["cfg"].primary
    m_p = grain_mass(ref["cfg"])
    for d in list(dem.values()) + list(s3.values()):
        d["dev"] = float(np.max(np.abs(d["Z"] / ref["Z"] - 1)))  # vs the reference DEM case
        d["f_peak"], d["Z_peak"] = resonance(f, d["Z"])
    command = "python experiments/universal_response.py" + (" --quick" if args.quick else "")

    with h5py.File(os.path.join(args.out, "data.h5"), "w") as h:
        h.attrs["jaxdamp_version"] = jaxdamp.__version__
        h.attrs["command"] = command
        h.attrs["wall_time"] = wall
        h.attrs["elapsed"] = elapsed
        h.create_dataset("frequency", data=f).attrs["units"] = "Hz"
        for (gn, gs), d in dem.items():
            g = h.create_group(f"dem/{_label(gn, gs)}")
            g.attrs["config"] = d["cfg"].to_json()
            g.attrs.update({"gamma_n": gn, "gamma_s": gs})
            for k, u in (("Z", "m"), ("coll", "J"), ("fric", "J"), ("total", "J"), ("balance", "1")):
                g.create_dataset(k, data=d[k]).attrs["units"] = u
        for method, d in s3.items():
            g = h.create_group(f"s3/{method}")
            g.attrs["config"] = d["cfg"].to_json()
            g.create_dataset("Z", data=d["Z"]).attrs["units"] = "m"
            g.create_dataset("total", data=d["total"]).attrs["units"] = "J"

    _figure(args.out, f, dem, s3, p, m_p)
    _summary(args.out, f, dem, s3, p, m_p, wall, t_dem, s, command)
    return dict(dem=dem, s3=s3)


def _figure(out, f, dem, s3, p, m_p):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    ff = np.linspace(f.min() * 0.95, f.max() * 1.02, 400)
    a1.plot(ff, frf_amplitude(ff, p.M, p.K, p.C, p.U) / p.U, color="orange", ls="--", lw=0.9,
            label="analytic, M")
    a1.plot(ff, frf_amplitude(ff, p.M + m_p, p.K, p.C, p.U) / p.U, color="brown", ls="--", lw=0.9,
            label="analytic, M + m_p")
    for (gn, gs), d, mk in zip(dem, dem.values(), "osd^"):
        a1.plot(f, d["Z"] / p.U, mk, ms=6, mfc="none", label=f"DEM γn = {gn:g}, γs = {gs:g}")
    a1.plot(f, s3["event"]["Z"] / p.U, "k-", lw=1.2, label="S3, e = 0 (event-driven)")
    a1.plot(f, s3["smooth"]["Z"] / p.U, "k:", lw=1.2, label="S3, e = 0 (smooth)")
    a1.set_yscale("log")
    a1.set_xlabel("f [Hz]")
    a1.set_ylabel("Z / U")
    a1.set_title("(a) FRF at the optimal box (thesis fig. 5.2a)", fontsize=9)
    a1.legend(fontsize=7)
    for ((gn, gs), d), col in zip(dem.items(), ("C0", "C1", "C2", "C3")):
        if gn == 0 and gs == 0:
            continue
        a2.plot(f, d["coll"], "^-", color=col, ms=4, lw=0.8, label=f"collision, ({gn:g}, {gs:g})")
        a2.plot(f, d["fric"], "s--", color=col, ms=4, lw=0.8, label=f"friction, ({gn:g}, {gs:g})")
        a2.plot(f, d["total"], "o-", color=col, ms=5, mfc="none", lw=1.2, label=f"total, ({gn:g}, {gs:g})")
    a2.plot(f, s3["event"]["total"], "k-", lw=1.2, label="S3, e = 0")
    a2.set_xlabel("f [Hz]")
    a2.set_ylabel("granular loss per cycle [J]")
    a2.set_title("(b) dissipation per cycle, collisional vs frictional (thesis fig. 5.2b)", fontsize=9)
    a2.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig5_2.png"), dpi=120)
    plt.close(fig)


def _summary(out, f, dem, s3, p, m_p, wall, t_dem, s, command):
    U = p.U
    lines = ["# Universal response at the optimal box (thesis fig. 5.2)", "",
             f"Command: `{command}` — wall time {wall / 60:.1f} min of sweeps on 2 cores ({t_dem / 60:.1f} "
             "min of it DEM; settling excluded). Data `data.h5`, figure `fig5_2.png`.", "",
             f"DEM: `sanchez2012-optimal` (N = 250, Lz = 0.1225 m, C = 7.6 N s/m, E = 2.03e9), "
             f"{s['duration']} s per frequency after settling, amplitude over the final 10 %. "
             f"S3: `sanchez2012-impact` (m = {s3['event']['cfg'].impactor.mass:.4f} kg, e = 0, gap = "
             f"{s3['event']['cfg'].impactor.gap} m), {s['s3_duration']} s per frequency.", "",
             "| f [Hz] | " + " | ".join(f"Z/U ({gn:g}, {gs:g})" for gn, gs in dem)
             + " | Z/U S3 event | Z/U S3 smooth | analytic M | analytic M + m_p |",
             "| --- " * (len(dem) + 5) + "|"]
    for i, fi in enumerate(f):
        lines.append(f"| {fi:g} | " + " | ".join(f"{d['Z'][i] / U:.2f}" for d in dem.values())
                     + f" | {s3['event']['Z'][i] / U:.2f} | {s3['smooth']['Z'][i] / U:.2f} | "
                     f"{frf_amplitude(fi, p.M, p.K, p.C, U) / U:.2f} | "
                     f"{frf_amplitude(fi, p.M + m_p, p.K, p.C, U) / U:.2f} |")
    lines += ["", "| case | max \\|Z/Z_ref − 1\\| over f | resonance [Hz] | peak Z/U | "
              "collision share of loss at peak | balance error |", "| --- | --- | --- | --- | --- | --- |"]
    for (gn, gs), d in dem.items():
        k = int(np.argmax(d["Z"]))
        share = d["coll"][k] / d["total"][k] if d["total"][k] > 0 else float("nan")
        lines.append(f"| DEM ({gn:g}, {gs:g}) | {d['dev']:.1%} | {d['f_peak']:.2f} | "
                     f"{d['Z_peak'] / U:.2f} | {share:.0%} | {float(np.max(d['balance'])):.1e} |")
    for method, d in s3.items():
        lines.append(f"| S3 e = 0 ({method}) | {d['dev']:.1%} | {d['f_peak']:.2f} | "
                     f"{d['Z_peak'] / U:.2f} | – | – |")
    lines += ["", f"Resonances of the analytic 1-DOF: M → {np.sqrt(p.K / p.M) / 2 / np.pi:.2f} Hz, "
              f"M + m_p → {np.sqrt(p.K / (p.M + m_p)) / 2 / np.pi:.2f} Hz."]
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
