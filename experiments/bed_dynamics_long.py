"""Bed dynamics with long series, periodicity levels and twin runs (thesis ch. 4; issue 13
item 3).

    python experiments/bed_dynamics_long.py            # full mode (see summary.md)
    python experiments/bed_dynamics_long.py --quick    # test-sized

``sanchez2012-optimal`` (N = 250, Lz = 0.1225 m, C = 7.6 N s/m) at the thesis' frequencies of
interest — 10 Hz (its period-2), 10.5 and 11 Hz (torus wrinkling and break-up), 13 Hz (chaos
zone I), 14.5 Hz (the periodic window) and 21 Hz (chaos zone II) — each as a **twin pair**
(:func:`jaxdamp.studies.twin.twin_sweep`): two identical runs, one grain of the second moved
by 1e-9 m at ``t_perturb``. Per frequency, on the reference run after the transient:

- **periodicity levels**, not one label: the stroboscopic spread of the section about a
  period-k orbit relative to the orbit's size (:func:`jaxdamp.analysis.dynamics.strobe_spread`,
  k = 1, 2) and the fraction of spectral power at the drive's lines ``n f`` and ``n f/2``
  (:func:`jaxdamp.analysis.dynamics.harmonic_fraction`), each read against two tolerances
  (1 % — the classifier's — and 5 %);
- the classifier's verdict (:func:`jaxdamp.analysis.dynamics.classify`) with its Kantz exponent
  now fitted over more than one drive period (the fit span is reported in periods);
- the **twin divergence** of ``z_box`` and ``z_cm``: exponent of the growth of the pair's
  distance (:func:`jaxdamp.analysis.dynamics.divergence_exponent`), per second and per period,
  and when it saturates.

For both observables: ``z_box`` (the primary: a state variable of the whole system) and
``z_cm`` (the bed's centre of mass, the thesis' observable). The thesis analyses ≈ 197 s
series; this run affords the duration in ``summary.md`` (one realisation per frequency: the
dynamics of one trajectory is the object here, not a steady mean). Writes ``data.h5``,
``figure.png``, ``summary.md``; the raw twin sweep in ``--out/raw`` (not committed).
"""

from __future__ import annotations

import json
import math
import os

import h5py
import numpy as np
import scaffold

from jaxdamp.analysis import dynamics as dyn
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.studies.twin import twin_sweep

HERE = os.path.dirname(os.path.abspath(__file__))
F_FULL = (10.0, 10.5, 11.0, 13.0, 14.5, 21.0)
#: thesis ch. 4 at these frequencies (SPEC §6 / thesis fig. 4.1)
THESIS = {10.0: "period-2", 10.5: "torus, wrinkling", 11.0: "torus break-up → chaos",
          13.0: "chaotic (zone I)", 14.5: "periodic window (2 impacts per period)",
          21.0: "chaotic (zone II)"}
TOLERANCES = (0.01, 0.05)
DELTA = 1e-9  # [m]
SIGNALS = ("z_box", "z_cm")


def settings(quick: bool) -> dict:
    if quick:
        return dict(freqs=(14.5, 21.0), duration=1.2, t_perturb=0.4, transient=0.4, settle=0.15,
                    chunk=0.1)
    return dict(freqs=F_FULL, duration=12.0, t_perturb=5.0, transient=3.0, settle=1.0,
                chunk=0.2)


def analyse_pair(t, ref: dict, twin: dict, f: float, s: dict) -> dict:
    keep = t >= s["transient"]
    out = {}
    for name in SIGNALS:
        x = ref[name][keep]
        scale = float(np.std(x))
        sec = dyn.poincare_section(t[keep], x, f)
        spread = dyn.strobe_spread(sec, scale, max_period=4)
        spec = dyn.power_spectrum(t[keep], x, f, method="periodogram")
        h1, h2 = (dyn.harmonic_fraction(spec, f, k) for k in (1, 2))
        c = dyn.classify(t[keep], x, f)
        lyap = c.lyapunov
        span = ((lyap.fit_range[1] - lyap.fit_range[0]) * lyap.dt * f) if lyap else math.nan
        div = dyn.divergence_exponent(t, ref[name] - twin[name], f, t_start=s["t_perturb"],
                                      d0=DELTA)
        out[name] = dict(scale=scale, spread1=float(spread[0]), spread2=float(spread[1]),
                         harm1=h1, harm2=h2, label=c.label, period=c.period or 0,
                         kantz_per_period=(c.exponent / f) if c.exponent is not None else math.nan,
                         kantz_span_periods=span, div_exponent=div["exponent"],
                         div_per_period=div["per_period"], div_saturated=div["saturated"],
                         div_t_sat=div["t_sat"], div_periods=div["periods_fitted"],
                         div_grew=div["grew"], div_plateau_rel=div["plateau"] / scale,
                         div_bound=div["lower_bound"],
                         D=div["D"], t_D=div["t_D"], n_section=len(sec.t))
    return out


def level(spread: float, harm: float) -> str:
    """Period-k verdict at each tolerance: both measures within it."""
    ok = [tol for tol in TOLERANCES if spread < tol and 1 - harm < tol]
    return f"within {100 * ok[0]:g} %" if ok else "no"


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "numerics.duration": s["duration"], "numerics.settle_time": s["settle"],
        "numerics.record_dt": 1e-3, "numerics.chunk": s["chunk"]})
    res = twin_sweep(cfg, s["freqs"], s["t_perturb"], ctx.raw("twin.h5"), delta=DELTA,
                     progress=ctx.progress)
    rec = res.records
    rows = {}
    for i, f in enumerate(s["freqs"]):
        a, b = 2 * i, 2 * i + 1
        t = rec["t"][a]
        pre = t < s["t_perturb"] - 1e-9
        same = float(np.max(np.abs(rec["z_box"][a][pre] - rec["z_box"][b][pre])))
        r = analyse_pair(t, {k: rec[k][a] for k in SIGNALS}, {k: rec[k][b] for k in SIGNALS},
                         f, s)
        r["identical_before"] = same
        rows[f] = r
        zb = r["z_box"]
        log(f"{f:g} Hz: z_box spread1 {zb['spread1']:.3g}, spread2 {zb['spread2']:.3g}, "
            f"harmonic {zb['harm1']:.4f}; twin exponent {zb['div_exponent']:.3g} 1/s "
            f"(saturated: {zb['div_saturated']}); classify {zb['label']}")
    result = dict(rows=rows, config=cfg, wall=float(res.summary["wall_time"]),
                  balance=np.asarray(res.summary["balance_error"]))
    return result, lambda path, prov: write(result, s, path, prov)


def main(argv=None):
    return scaffold.main(__doc__, "bed_dynamics_long", argv, compute)


def write(r, s, out, prov):
    with h5py.File(os.path.join(out, "data.h5"), "w") as h:
        scaffold.stamp(h, dict(prov, sweep_wall_s=r["wall"]))
        h.attrs["settings"] = json.dumps(s)
        h.attrs["config"] = r["config"].to_json()
        h.attrs["delta"] = DELTA
        for f, row in r["rows"].items():
            g = h.create_group(f"f_{f:g}")
            g.attrs["frequency"] = f
            g.attrs["identical_before_perturbation"] = row["identical_before"]
            for name in SIGNALS:
                d = row[name]
                gg = g.create_group(name)
                gg.attrs.update({k: v for k, v in d.items() if np.ndim(v) == 0})
                gg.create_dataset("twin_distance", data=d["D"]).attrs.update(
                    units="m", what="per-period maximum of |reference − perturbed|")
                gg.create_dataset("twin_t", data=d["t_D"]).attrs["units"] = "s"
    _figure(r, s, out)
    _summary(r, s, out, prov)


def _figure(r, s, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 3, figsize=(15, 4.4))
    for f, row in r["rows"].items():
        for name, ax in zip(SIGNALS, axs[:2]):
            d = row[name]
            ax.semilogy(d["t_D"], d["D"], label=f"{f:g} Hz")
    for name, ax in zip(SIGNALS, axs[:2]):
        ax.axvline(s["t_perturb"], color="k", lw=0.6, ls=":")
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(f"twin distance |Δ{name}| per period (max) [m]")
        ax.set_title(f"{name}: twin runs, one grain moved by {DELTA:g} m at "
                     f"t = {s['t_perturb']:g} s", fontsize=9)
        ax.legend(fontsize=7)
    fs = list(r["rows"])
    x = np.arange(len(fs))
    zb = [r["rows"][f]["z_box"] for f in fs]
    for dx, key, mk in ((-0.1, "spread1", "o"), (0.1, "spread2", "s")):
        axs[2].semilogy(x + dx, [max(d[key], 1e-8) for d in zb], mk,
                        label=f"strobe spread, k = {key[-1]}")
    axs[2].semilogy(x, [max(1 - d["harm1"], 1e-8) for d in zb], "^",
                    label="power off the drive's lines, 1 − h₁")
    for tol in TOLERANCES:
        axs[2].axhline(tol, color="0.5", lw=0.7, ls="--")
    axs[2].set_xticks(x, [f"{f:g}" for f in fs])
    axs[2].set_xlabel("drive frequency f [Hz]")
    axs[2].set_ylabel("periodicity level of z_box [-] (dashed: 1 %, 5 % tolerances)")
    axs[2].set_title("distance from a period-1 / period-2 orbit", fontsize=9)
    axs[2].legend(fontsize=7)
    scaffold.save_figure(fig, out, "figure.png")


def _summary(r, s, out, prov):
    L = ["# Bed dynamics: long series, periodicity levels, twin runs (thesis ch. 4)", "",
         scaffold.provenance_line(prov, r["wall"]), "",
         f"`sanchez2012-optimal`, one twin pair per frequency, {s['duration']:g} s per run "
         f"(the thesis: ≈ 197 s), analysed after t = {s['transient']:g} s "
         f"({(s['duration'] - s['transient']):g} s = "
         + ", ".join(f"{(s['duration'] - s['transient']) * f:.0f}" for f in s["freqs"])
         + " drive periods); one grain moved by "
         f"{DELTA:g} m at t = {s['t_perturb']:g} s in the second run of each pair (before "
         "that the pairs agree to "
         f"{max(row['identical_before'] for row in r['rows'].values()):.1e} m). "
         f"Energy balance error ≤ {float(np.max(r['balance'])):.1e}.", "",
         "Periodicity levels: strobe spread s_k = RMS distance of the stroboscopic section "
         "from a period-k orbit over the orbit's standard deviation; h_k = fraction of the "
         "power at the lines n f/k. A period-k verdict needs s_k and 1 − h_k both below the "
         "tolerance (1 %: the classifier's; 5 %: a looser one). Kantz exponents are fitted "
         "over more than one drive period (span given).", "",
         f"Twin growth is judged from the perturbation itself ({DELTA:g} m of one grain), not "
         "from the first period's distance: where the per-period maximum distance is already "
         "within a factor 10 of its plateau in the first period after the perturbation, the "
         f"pair separated within one period and only a lower bound ln(D₀/{DELTA:g} m)/T is known "
         "(marked ≥). 'Plateau / orbit size' says how far the separation reaches the observable: "
         "a bed whose grains diverge at once while z_box stays within ~1 % of its orbit is "
         "chaotic at the grain level and nearly periodic at the level of the damper.", ""]
    for name in SIGNALS:
        L += [f"## {name}", "",
              "| f [Hz] | thesis | s₁ | s₂ | 1 − h₁ | 1 − h₂ | period-1 | period-2 | "
              "classifier | Kantz λ/f (span [periods]) | twin λ [1/s] | twin λ/f | twin "
              "plateau at [s] | plateau / orbit size |", "| --- " * 14 + "|"]
        for f, row in r["rows"].items():
            d = row[name]
            lab = d["label"] + (f"-{d['period']}" if d["period"] else "")
            L.append(
                f"| {f:g} | {THESIS.get(f, '')} | {d['spread1']:.2g} | {d['spread2']:.2g} | "
                f"{1 - d['harm1']:.2g} | {1 - d['harm2']:.2g} | {level(d['spread1'], d['harm1'])} "
                f"| {level(d['spread2'], d['harm2'])} | {lab} | {d['kantz_per_period']:.3g} "
                f"({d['kantz_span_periods']:.1f}) | {'≥ ' if d['div_bound'] else ''}"
                f"{d['div_exponent']:.3g} | {'≥ ' if d['div_bound'] else ''}"
                f"{d['div_per_period']:.3g} | "
                + ("within the first period" if d["div_bound"] else
                   f"{d['div_t_sat']:.2f}" if d["div_saturated"] else
                   "did not grow" if not d["div_grew"] else "not reached")
                + f" | {d['div_plateau_rel']:.2g} |")
        L.append("")
    L += ["What the twin exponent can and cannot tell: it is the growth rate of a perturbation "
          "of the whole simulated system (6N + 2 ≈ 1500 phase-space dimensions for N = 250), "
          "with no embedding, so unlike Kantz's estimate from one scalar series it is not "
          "limited by the dimension a record can resolve. It is the largest exponent of the "
          "simulation — grains rattling chaotically inside a bed whose box motion is nearly "
          "periodic give a positive twin exponent that reaches z_box only as far as the "
          "grains' forces do (its saturation level says how far). It cannot separate the "
          "physical chaos of the bed from the amplification of round-off: both are the same "
          "process in a chaotic flow."]
    scaffold.write_summary(out, L)


if __name__ == "__main__":
    main()
