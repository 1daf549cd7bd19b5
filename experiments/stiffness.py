"""Does the reduced Young's modulus change the damper's response? Resonance at the optimum box,
with replicates: ``python experiments/stiffness.py [--quick]`` (quick: minutes).

``sanchez2012-optimal`` near resonance at the thesis' E = 2.03e11 Pa (``stiffness_scale = 1``),
the preset's 2.03e9 (``0.01``) and 2.03e8 (``0.001``). ``gamma_n``, ``gamma_s`` scale as
``stiffness_scale**0.6`` (:mod:`jaxdamp.physics.restitution`): each binary collision keeps its
restitution and tangential impulse, leaving the collective effect of longer contacts (λ^-0.4)
and larger overlaps (λ^-2/3) to measure. Per modulus, a sweep over frequencies × ``R`` poured
beds (the same seeds for all); steady means after the MSER-detected start. The resonant
amplitude (parabola through the largest sample, per bed) and the loss per cycle near f0 are
compared with the preset's modulus by a Welch 95 % interval ("changed" where it excludes 0).
Writes ``data.h5``, ``figure.png``, ``summary.md`` in ``--out``; raw sweeps in ``--out/raw``.
"""

from __future__ import annotations

import h5py
import numpy as np

from jaxdamp.analysis.stats import replicate_extrema, welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures.response import draw_replicates
from jaxdamp.io.common import put
from jaxdamp.physics.model import collision_time_limit, grain_radii
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_replicates
from jaxdamp.studies.sweep import reuse_or_run

REF = 0.01  # the preset's stiffness_scale: every other modulus is compared with it


def settings(quick: bool):
    if quick:
        return dict(freqs=(14.5, 15.25), duration=0.15, settle=0.1, scales=(1.0, 0.01), R=2)
    return dict(freqs=(14.5, 15.0, 15.5), duration=1.8, settle=0.3, scales=(1.0, 0.01, 0.001), R=3)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    rows = {}
    for scale in s["scales"]:
        cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
            "numerics.stiffness_scale": scale, "numerics.duration": s["duration"],
            "numerics.settle_time": s["settle"], "numerics.record_dt": 1e-3,
            "numerics.chunk": 0.1})
        path = ctx.raw(f"sweep_scale{scale:g}_R{s['R']}.h5")
        res = reuse_or_run(cfg, {"frequency": list(s["freqs"])}, path, progress=ctx.progress,
                           replicates=s["R"])
        with h5py.File(path, "r") as h:
            dt = float(h.attrs["dt"])
        st = steady_replicates(res, "amplitude", "granular_loss_per_cycle")
        Z, loss = st.values  # (F, R)
        peak = replicate_extrema(s["freqs"], Z, "max", log_y=True)  # per bed, parabola in log Z
        rows[scale] = dict(config=cfg, Z=Z, f_peak=peak.x, Z_peak=peak.y, loss=loss, dt=dt,
                           balance=np.asarray(res.summary["balance_error"]),
                           E=cfg.grains[0].material.E * scale,
                           t_c=collision_time_limit(cfg, grain_radii(cfg)), wall=st.wall,
                           fallback=sum(st.fallback), stationary=int(st.stationary.sum()))
        log(f"E = {rows[scale]['E']:.3g} Pa: resonant Z/U "
            f"{peak.y.mean() / cfg.primary.U:.3f} ({st.wall:.0f} s)")
    return rows, lambda path, prov: record(rows, s, path, prov)


def record(rows, s, out, prov):
    wall = sum(r["wall"] for r in rows.values())  # the sweeps' compute time (settling excluded)
    with scaffold.data_file(out, dict(prov, sweep_wall_s=wall), settings=s) as h:
        put(h, "frequency", s["freqs"], "Hz")
        for scale, r in rows.items():
            g = h.create_group(f"scale_{scale:g}")
            g.attrs["config"] = r["config"].to_json()
            g.attrs.update({k: r[k] for k in ("E", "dt", "t_c", "stationary", "fallback")},
                           wall_time=r["wall"])
            put(g, "amplitude", r["Z"], "m", dims="frequency, replicate")
            put(g, "granular_loss_per_cycle", r["loss"], "J", dims="frequency, replicate")
            put(g, "Z_peak", r["Z_peak"], "m")
            put(g, "f_peak", r["f_peak"], "Hz")
            put(g, "balance_error", r["balance"], "1")


def report(data, out):
    s, prov = data.attrs["settings"], data.attrs
    freqs, R = s["freqs"], s["R"]
    k15 = int(np.argmin(np.abs(np.asarray(freqs) - 15.0)))  # a common frequency near f0
    rows = {scale: dict(g.attrs, config=from_dict(g.attrs["config"]), Z=g["amplitude"],
                        loss=g["granular_loss_per_cycle"], Z_peak=g["Z_peak"],
                        balance=g["balance_error"], runs=g["amplitude"].size)
            for scale in s["scales"] for g in [data[f"scale_{scale:g}"]]}
    ref = rows.get(REF, rows[s["scales"][-1]])
    U = ref["config"].primary.U
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(10, 4))
    for r in rows.values():
        draw_replicates(a1, freqs, r["Z"] / U, label=f"E = {r['E']:.3g} Pa (dt = {r['dt']:.2g} s)")
        draw_replicates(a2, freqs, r["loss"], label=f"E = {r['E']:.3g} Pa")
    a1.set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]")
    a2.set(xlabel="excitation frequency f [Hz]", ylabel="granular loss per cycle [J]")
    a1.set_title(f"optimal box (Lz = 0.1225 m, C = 7.6 N s/m): response, R = {R} beds ± 2 SE",
                 fontsize=9)
    a2.set_title("energy dissipated by the grains per period", fontsize=9)
    for a in (a1, a2):
        a.legend(fontsize=7)
    scaffold.save_figure(fig, out)

    def verdict(r, values):
        if r is ref:
            return "reference"
        d, h = (x / np.mean(values(ref)) for x in welch(values(r), values(ref)))
        return (scaffold.pm(d, h, "+.1f", ".1f", scale=100, unit="%") + " — "
                + ("**changed**" if abs(d) > h else "not significant"))

    lines = scaffold.head("Stiffness sensitivity at the optimal box, with replicates", prov,
                          prov["sweep_wall_s"])
    lines += [f"`sanchez2012-optimal` (Lz = 0.1225 m, C = 7.6 N s/m, N = 250), frequencies "
              f"{list(freqs)} Hz × **R = {R} independently poured beds** (seeds 0…{R - 1}, "
              f"the same at every modulus), {s['duration']} s per run after settling; steady "
              "means after the MSER-detected start. ± = standard error over the beds; changes "
              "relative to E = 2.03e9 with their Welch 95 % interval.", "",
              "**Stationarity.** A run not found stationary (MSER) enters with its fixed-window "
              f"value (the last {ref['config'].numerics.analysis_window:.0%} of the run): "
              + "; ".join(f"E = {r['E']:.3g} Pa: {r['runs'] - r['stationary']} of {r['runs']} "
                          f"runs (amplitude), {r['fallback']} fixed-window values in all"
                          for r in rows.values())
              + ". The verdicts rest partly on runs still drifting; longer runs are the remedy "
              "(the thesis modulus costs 6.3× the others).", ""]
    lines += scaffold.table(
        ["E [Pa]", "t_c at 1 m/s [s]", "dt [s]", "Z/U per frequency", "resonant Z/U",
         "change of resonant Z", f"loss per cycle at {freqs[k15]:g} Hz [J]",
         "change of loss", "stationary runs", "balance error", "wall [s]"],
        [[f"{r['E']:.3g}", f"{r['t_c']:.3g}", f"{r['dt']:.3g}",
          ", ".join(f"{z / U:.2f}" for z in r["Z"].mean(-1)),
          scaffold.pm(*scaffold.mean_se(r["Z_peak"] / U), ".3f", ".3f"),
          verdict(r, lambda q: q["Z_peak"]),
          scaffold.pm(*scaffold.mean_se(r["loss"][k15]), ".3f", ".3f"),
          verdict(r, lambda q: q["loss"][k15]),
          f"{r['stationary']} of {r['runs']}", f"{float(np.max(r['balance'])):.1e}",
          f"{r['wall_time']:.0f}"] for r in rows.values()])
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
