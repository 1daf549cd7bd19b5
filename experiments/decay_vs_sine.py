"""Free decay against stepped sine on the thesis damper (issue 16: "free decay vs FRF").

    python experiments/decay_vs_sine.py            # ~10 min on 2 cores
    python experiments/decay_vs_sine.py --quick    # ~1 min, test-sized

Two lab tests of the same damper (``sanchez2012-optimal``: 250 grains, Lz = 0.1225 m, on its
1-DOF primary) should give the same damping at the same vibration amplitude if the damper's
loss depends on the amplitude only:

* **free decay** (``jaxdamp decay``): the primary released from ``z0`` with the base at rest,
  ``R`` independently poured beds;
* **stepped sine** (``jaxdamp frf``): base amplitudes ``U`` at frequencies around the
  resonance, ``R`` beds per point, each run's steady state detected from the data (MSER).

Both are reduced to the same quantity, the grains' **energy-equivalent damping ratio**
``ζ_g = ΔW / (2π K Z²)``: the energy ``ΔW`` the grains dissipate in one cycle (the contact work
channels, not a model) at the amplitude ``Z`` of the primary, with the primary's stiffness
``K`` (``jaxdamp/analysis/decay.py``). In the decay a cycle runs from one positive peak to the
next and ``Z = √(X_k X_k+1)``; in the sine runs ΔW is the steady loss per drive period and Z the
steady amplitude. Amplitudes are matched directly (each sine point against the decay curve at
its Z, interpolated in log Z for every decay bed); frequencies are not matched (the decay
cycles run at the damped frequency, 14.4–15.3 Hz; the sine points sit at their drive
frequency). Verdicts: the Welch 95 % interval of ζ_g(sine) − ζ_g(decay) across beds, at each
base amplitude's resonant point (largest Z of its frequencies) and at every point.

Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import os

import h5py
import numpy as np
import scaffold

from jaxdamp.analysis.decay import on_amplitudes
from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.studies import decay
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run


def settings(quick: bool) -> dict:
    if quick:
        return dict(z0=0.035, decay_s=0.6, U=[0.0015, 0.0045], f=[14.5, 15.5], sine_s=0.5,
                    R=2, settle=0.3)
    return dict(z0=0.035, decay_s=3.5, U=[0.00075, 0.0015, 0.003, 0.0045],
                f=[14.0, 14.5, 15.0, 15.5, 16.0], sine_s=2.5, R=3, settle=None)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = presets.get("sanchez2012-optimal")
    if s["settle"] is not None:
        cfg = apply_overrides(cfg, {"numerics.settle_time": s["settle"]})
    K = cfg.primary.K
    log(f"free decay from z0 = {s['z0']} m, {s['decay_s']} s, R = {s['R']}")
    dec = decay.measure(cfg, [s["z0"]], duration=s["decay_s"], replicates=s["R"],
                        out=ctx.raw(f"decay_R{s['R']}.h5"), resume=False,
                        progress=ctx.progress, echo=None)
    per_bed = dec.cycles[0]
    log(f"stepped sine: U = {s['U']} m × f = {s['f']} Hz, {s['sine_s']} s, R = {s['R']}")
    sine_cfg = apply_overrides(cfg, {"numerics.duration": s["sine_s"]})
    axes = {"primary.U": s["U"], "frequency": s["f"]}
    res = reuse_or_run(sine_cfg, axes, ctx.raw(f"sine_R{s['R']}.h5"), progress=ctx.progress,
                       echo=None, replicates=s["R"])
    Z, fb_z = steady_or_window(res, "amplitude")  # (U, F, R)
    W, fb_w = steady_or_window(res, "granular_loss_per_cycle")
    zeta_sine = W / (2 * np.pi * K * Z ** 2)
    stationary = int(np.asarray(res.steady["amplitude"]["stationary"], bool).sum())
    # the decay curve at every sine point's mean amplitude, per decay bed
    Zm = Z.mean(axis=-1)
    at = on_amplitudes(per_bed, Zm.ravel())
    zeta_decay = at["values"]["zeta_g"].T.reshape(Zm.shape + (len(per_bed),))  # (U, F, R_d)
    diff = np.full(Zm.shape, np.nan)
    half = np.full(Zm.shape, np.nan)
    for idx in np.ndindex(Zm.shape):
        diff[idx], half[idx] = welch(zeta_sine[idx], zeta_decay[idx])
    covered = np.isfinite(zeta_decay).sum(axis=-1) >= 2
    result = dict(settings=s, K=K, f=np.asarray(s["f"]), U=np.asarray(s["U"]), Z=Z, W=W,
                  zeta_sine=zeta_sine, zeta_decay=zeta_decay, diff=diff, half=half,
                  covered=covered, stationary=stationary, runs=int(Z.size),
                  fallback=max(fb_z, fb_w), decay=dec, curve=dec.curves[0],
                  zeta_struct=dec.zeta_struct,
                  wall=dict(decay=float(dec.sweep.summary["wall_time"]),
                            sine=float(res.summary["wall_time"])))
    return result, lambda out, prov: write(result, out, prov)


def verdict(d, h, covered) -> str:
    if not covered or not np.isfinite(h):
        return "outside the decay's range"
    return "agree" if abs(d) <= h else ("sine above" if d > 0 else "sine below")


def write(r, out, prov):
    s = r["settings"]
    with h5py.File(os.path.join(out, "data.h5"), "w") as h:
        scaffold.stamp(h, prov)
        h.attrs["convention"] = "zeta_g = dW / (2 pi K Z^2), dW granular loss per cycle"
        for k, unit in (("U", "m"), ("f", "Hz"), ("Z", "m"), ("W", "J"), ("zeta_sine", "1"),
                        ("zeta_decay", "1"), ("diff", "1"), ("half", "1")):
            h.create_dataset(f"sine/{k}", data=r[k]).attrs["units"] = unit
        c = r["curve"]
        for k in ("Z", "zeta", "zeta_se", "zeta_g", "zeta_g_se", "f", "f_se", "n"):
            h.create_dataset(f"decay/{k}", data=c[k]).attrs["units"] = (
                "m" if k == "Z" else "Hz" if k.startswith("f") else "1")
    from jaxdamp.figures import figure

    fig = figure((7.5, 4.5), layout="constrained")
    ax = fig.subplots()
    Zc = np.asarray(c["Z"]) * 1e3
    ax.plot(Zc, 100 * c["zeta_g"], "k-", lw=1.2, label=f"free decay (mean of {s['R']} beds)")
    ok = np.isfinite(c["zeta_g_se"])
    ax.fill_between(Zc[ok], 100 * (c["zeta_g"] - 2 * c["zeta_g_se"])[ok],
                    100 * (c["zeta_g"] + 2 * c["zeta_g_se"])[ok], color="k", alpha=0.2, lw=0)
    for i, U in enumerate(r["U"]):
        zm = r["Z"][i].mean(axis=-1) * 1e3
        ym = 100 * r["zeta_sine"][i].mean(axis=-1)
        ye = 200 * r["zeta_sine"][i].std(axis=-1, ddof=1) / np.sqrt(r["Z"].shape[-1])
        ax.errorbar(zm, ym, yerr=ye, fmt="o", ms=4, capsize=2,
                    label=f"stepped sine, U = {U * 1e3:g} mm ({', '.join(f'{x:g}' for x in r['f'])} Hz)")
    ax.set_xscale("log")
    ax.set_xlabel("amplitude of the primary Z [mm]")
    ax.set_ylabel("grains' damping ratio ζ_g = ΔW/(2πKZ²) [%]")
    ax.set_title("thesis damper: free decay vs stepped sine (± 2 SE over beds)", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.savefig(os.path.join(out, "figure.png"), dpi=120)

    L = ["# Free decay against stepped sine (issue 16)", "",
         scaffold.provenance_line(prov), "",
         f"Damper: `sanchez2012-optimal` (250 grains, Lz = 0.1225 m), K = {r['K']:g} N/m. "
         f"Free decay from z0 = {s['z0']} m, {s['decay_s']} s, base at rest; stepped sine at "
         f"U = {', '.join(f'{u * 1e3:g}' for u in s['U'])} mm × f = "
         f"{', '.join(f'{x:g}' for x in s['f'])} Hz, {s['sine_s']} s per run. "
         f"**{s['R']} independently poured beds** per test and point. Sine runs: steady state "
         f"detected (MSER on per-period amplitude and loss) in {r['stationary']} of "
         f"{r['runs']}; the others use the fixed final window. Compute: decay "
         f"{r['wall']['decay']:.0f} s, sine {r['wall']['sine']:.0f} s (settling excluded).", "",
         "Convention: the grains' energy-equivalent damping ratio ζ_g = ΔW/(2πKZ²) (ΔW the "
         "grains' loss per cycle from the contact work channels), amplitudes matched, "
         "frequencies not (see the script's docstring). Verdict: Welch 95 % interval of "
         "ζ_g(sine) − ζ_g(decay) across beds.", "",
         f"Empty box (grains as dead mass): ζ = {100 * r['zeta_struct']:.3f} %; the decay's "
         f"total ζ over its cycles: {100 * np.nanmin(c['zeta']):.2f}–"
         f"{100 * np.nanmax(c['zeta']):.2f} %, the grains' ζ_g "
         f"{100 * np.nanmin(c['zeta_g']):.2f}–{100 * np.nanmax(c['zeta_g']):.2f} % over "
         f"Z = {1e3 * np.nanmin(c['Z']):.2f}–{1e3 * np.nanmax(c['Z']):.2f} mm.", "",
         "## At each base amplitude's resonant point (largest Z over its frequencies)", "",
         "| U [mm] | f [Hz] | Z [mm] | ζ_g sine [%] | ζ_g decay at Z [%] | difference [%] | verdict |",
         "|---|---|---|---|---|---|---|"]
    agree = total = 0
    for i, U in enumerate(r["U"]):
        Zm = r["Z"][i].mean(axis=-1)
        j = int(np.argmax(Zm))
        zs, zd = r["zeta_sine"][i, j], r["zeta_decay"][i, j]
        v = verdict(r["diff"][i, j], r["half"][i, j], r["covered"][i, j])
        total += v != "outside the decay's range"
        agree += v == "agree"
        dec_txt = diff_txt = "–"
        if np.isfinite(zd).sum() >= 2:
            dec_txt = (f"{100 * np.nanmean(zd):.3f} ± "
                       f"{100 * np.nanstd(zd, ddof=1) / np.sqrt(np.isfinite(zd).sum()):.2g}")
            diff_txt = f"{100 * r['diff'][i, j]:+.3f} ± {100 * r['half'][i, j]:.2g}"
        L.append(f"| {U * 1e3:g} | {r['f'][j]:g} | {1e3 * Zm[j]:.2f} ± "
                 f"{1e3 * r['Z'][i, j].std(ddof=1) / np.sqrt(len(r['Z'][i, j])):.2g} | "
                 f"{100 * zs.mean():.3f} ± {100 * zs.std(ddof=1) / np.sqrt(len(zs)):.2g} | "
                 f"{dec_txt} | {diff_txt} | {v} |")
    every = [verdict(r["diff"][k], r["half"][k], r["covered"][k]) for k in np.ndindex(r["diff"].shape)]
    inside = [v for v in every if v != "outside the decay's range"]
    L += ["", f"Resonant points: {agree} of {total} agree within the 95 % interval. Every sine "
          f"point inside the decay's amplitude range: {inside.count('agree')} of {len(inside)} "
          f"agree, {inside.count('sine above')} above, {inside.count('sine below')} below "
          f"({len(every) - len(inside)} outside the decay's range).", "",
          "Figure: `figure.png` (decay curve ± 2 SE, sine points ± 2 SE). Data: `data.h5`."]
    scaffold.write_summary(out, L)


def main(argv=None):
    return scaffold.main(__doc__, "decay_vs_sine", argv, compute)


if __name__ == "__main__":
    main()
