"""The universal response of the optimal damper (thesis fig. 5.2), with replicates: contact
damping on and off, and the single-particle model.

    python experiments/universal_response.py           # full mode
    python experiments/universal_response.py --quick   # minutes

At the optimal box (``sanchez2012-optimal``: Lz = 0.1225 m, C = 7.6 N s/m, N = 250) the thesis
finds the FRF nearly unchanged when either the normal (``γ_n``) or the tangential (``γ_s``)
contact damping is switched off — but not both — and matched by the single-particle impact
damper (S3) with ``e = 0``. Here the four cases ``(γ_n, γ_s)`` in {(3660, 10980), (0, 10980),
(3660, 0), (0, 0)} kg s⁻¹ m^-1/2 (thesis values; the preset's reduced modulus scales them by
0.01^0.6) × every frequency × ``R`` independently poured beds run as **one batch**
(:class:`jaxdamp.studies.grid.Points`), so that every case sees the same beds (seeds
0…R−1). Each run's amplitude and loss per cycle are steady means over the steady state
detected by MSER (:mod:`jaxdamp.analysis.stats`). S3 (``sanchez2012-impact``, e = 0, gap
0.0835 m; deterministic, one realisation is exact) runs with the event-driven model and its
smooth, differentiable version.

Verdicts, each from an interval: per case, the change of the resonant amplitude against the
reference case (Welch 95 %), and at how many frequencies the amplitude differs from the
reference beyond its Welch 95 % interval; for S3, its distance from the reference DEM mean in
units of the DEM's standard error. Writes ``data.h5``, ``fig5_2.png``, ``summary.md``; raw
sweep files in ``--out/raw`` (not committed).
"""

from __future__ import annotations

import json
import math

import numpy as np

from jaxdamp.analysis.response import frf_amplitude, resonance
from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.figures.response import draw_replicates
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points, steady_or_window
from jaxdamp.studies.sweep import reuse_or_run, sweep

CASES = ((3660.0, 10980.0), (0.0, 10980.0), (3660.0, 0.0), (0.0, 0.0))
F_FULL = (10.0, 12.0, 13.5, 14.5, 15.25, 16.0, 18.5, 23.0)
SPLIT = ("pp_normal", "pw_normal", "pp_friction", "pw_friction")


def settings(quick: bool) -> dict:
    if quick:
        return dict(freqs=(14.5, 15.25), duration=0.3, settle=0.15, cases=CASES[:2], R=2,
                    s3_duration=2.0)
    return dict(freqs=F_FULL, duration=1.5, settle=0.3, cases=CASES, R=3, s3_duration=10.0)


def optimal(s: dict, **over):
    """``sanchez2012-optimal`` as run here and in universality_limits, with ``over``."""
    return apply_overrides(presets.get("sanchez2012-optimal"), {
        "numerics.duration": s["duration"], "numerics.settle_time": s["settle"],
        "numerics.record_dt": 1e-3, "numerics.chunk": 0.1, **over})


def run_dem(s: dict, out: str, progress: bool):
    """Every (case, frequency) point × R beds in one batch; returns the sweep and its config."""
    cfg = optimal(s)
    pts = [(gn, gs, f) for gn, gs in s["cases"] for f in s["freqs"]]
    axes = Points({"grains.0.material.gamma_n": [p[0] for p in pts],
                   "grains.0.material.gamma_s": [p[1] for p in pts],
                   "frequency": [p[2] for p in pts]})
    return reuse_or_run(cfg, axes, out, progress=progress, replicates=s["R"]), cfg


def run_s3(method, s) -> dict:
    """S3 (``sanchez2012-impact``) by ``method``: config, amplitude, loss, wall time."""
    cfg = apply_overrides(presets.get("sanchez2012-impact"), {
        "impactor.method": method, "numerics.duration": s["s3_duration"]})
    r = sweep(cfg, {"frequency": list(s["freqs"])}, progress=False).summary
    return dict(cfg=cfg, Z=np.asarray(r["amplitude"]),
                total=np.asarray(r["granular_loss_per_cycle"]), wall=float(r["wall_time"]))


def analyse(res, s) -> dict:
    nc, F, R = len(s["cases"]), len(s["freqs"]), s["R"]
    f = np.asarray(s["freqs"], float)
    Z, fb_Z = steady_or_window(res, "amplitude")
    E, fb_E = steady_or_window(res, "granular_loss_per_cycle")
    Z, E = Z.reshape(nc, F, R), E.reshape(nc, F, R)
    split = {k: np.asarray(res.replicate_summary[f"{k}_per_cycle"]).reshape(nc, F, R)
             for k in SPLIT}
    peaks = np.array([[resonance(f, Z[c, :, r]) for r in range(R)] for c in range(nc)])
    stat = np.asarray(res.steady["amplitude"]["stationary"], bool)
    return dict(Z=Z, E=E, split=split, f_peak=peaks[..., 0], Z_peak=peaks[..., 1],
                fallback=fb_Z + fb_E, stationary=int(stat.sum()), runs=int(stat.size),
                balance=np.asarray(res.summary["balance_error"]).reshape(nc, F))


def verdicts(a, s3, s) -> dict:
    ref = 0
    out = {"cases": []}
    U = a["U"]
    for c, (gn, gs) in enumerate(s["cases"]):
        d_peak, h_peak = welch(a["Z_peak"][c], a["Z_peak"][ref])
        diffs = [welch(a["Z"][c, i], a["Z"][ref, i]) for i in range(len(s["freqs"]))]
        n_sig = sum(abs(d) > h for d, h in diffs)
        out["cases"].append(dict(
            gamma_n=gn, gamma_s=gs, peak=float(a["Z_peak"][c].mean() / U),
            peak_se=float(scaffold.standard_error(a["Z_peak"][c]) / U),
            d_peak_rel=d_peak / float(a["Z_peak"][ref].mean()),
            d_peak_ci_rel=h_peak / float(a["Z_peak"][ref].mean()),
            peak_changed=bool(abs(d_peak) > h_peak) if c != ref else None,
            freqs_differing=int(n_sig) if c != ref else None,
            max_rel_diff=float(max(abs(d) / a["Z"][ref, i].mean() for i, (d, _) in
                                   enumerate(diffs)))))
    zref = a["Z"][ref]
    se = scaffold.standard_error(zref)
    for m, d in s3.items():
        z = (d["Z"] - zref.mean(axis=-1)) / se
        out[f"s3_{m}"] = dict(z=[float(x) for x in z],
                              max_rel_diff=float(np.max(np.abs(d["Z"] / zref.mean(axis=-1) - 1))),
                              beyond_2se=int(np.sum(np.abs(z) > 2)))
    return out


def compute(quick: bool, log, ctx):
    s = settings(quick)
    res, cfg = run_dem(s, ctx.raw(f"sweep_cases_R{s['R']}.h5"), ctx.progress)
    a = analyse(res, s)
    a["U"] = cfg.primary.U
    s3 = {method: run_s3(method, s) for method in ("event", "smooth")}
    v = verdicts(a, s3, s)
    for row in v["cases"][1:]:
        log(f"(γn, γs) = ({row['gamma_n']:g}, {row['gamma_s']:g}): peak change "
            f"{scaffold.pm(row['d_peak_rel'], row['d_peak_ci_rel'], '+.1%', '.1%')}; "
            f"{row['freqs_differing']} of {len(s['freqs'])} frequencies differ at 95 %")
    result = dict(dem=a, s3=s3, verdicts=v, cfg=cfg, m_p=grain_mass(cfg),
                  wall=float(res.summary["wall_time"]) + sum(d["wall"] for d in s3.values()))
    return result, lambda path, prov: write(result, s, path, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(r, s, out, prov):
    a = r["dem"]
    with scaffold.data_file(out, dict(prov, sweep_wall_s=r["wall"]), settings=json.dumps(s),
                            verdicts=json.dumps(r["verdicts"]), config=r["cfg"].to_json()) as h:
        h.create_dataset("frequency", data=np.asarray(s["freqs"])).attrs["units"] = "Hz"
        h.create_dataset("cases", data=np.asarray(s["cases"])).attrs.update(
            units="kg s^-1 m^-1/2", columns="gamma_n, gamma_s (thesis values)")
        dims = "case, frequency, replicate"
        for k, v, u in (("amplitude", a["Z"], "m"), ("granular_loss_per_cycle", a["E"], "J"),
                        ("f_peak", a["f_peak"], "Hz"), ("Z_peak", a["Z_peak"], "m")):
            h.create_dataset(f"dem/{k}", data=v).attrs.update(units=u, dims=dims)
        for k, v in a["split"].items():
            h.create_dataset(f"dem/{k}_per_cycle", data=v).attrs.update(
                units="J", dims=dims, window="final 10 % of the run")
        for m, d in r["s3"].items():
            g = h.create_group(f"s3/{m}")
            g.attrs["config"] = d["cfg"].to_json()
            g.create_dataset("Z", data=d["Z"]).attrs["units"] = "m"
            g.create_dataset("total", data=d["total"]).attrs["units"] = "J"
    _figure(out, r, s)
    _summary(out, r, s, prov)


def _figure(out, r, s):
    a, p, m_p = r["dem"], r["cfg"].primary, r["m_p"]
    f = np.asarray(s["freqs"], float)
    R = s["R"]
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(12, 4.8))
    ff = np.linspace(f.min() * 0.95, f.max() * 1.02, 400)
    a1.plot(ff, frf_amplitude(ff, p.M, p.K, p.C, p.U) / p.U, color="orange", ls="--", lw=0.9,
            label="analytic, M")
    a1.plot(ff, frf_amplitude(ff, p.M + m_p, p.K, p.C, p.U) / p.U, color="brown", ls="--",
            lw=0.9, label="analytic, M + m_p")
    for c, ((gn, gs), mk) in enumerate(zip(s["cases"], "osd^")):
        Z = a["Z"][c] / p.U
        draw_replicates(a1, f, Z, fmt=mk, ms=6, mfc="none", capsize=3,
                        label=f"DEM γn = {gn:g}, γs = {gs:g}")
    a1.plot(f, r["s3"]["event"]["Z"] / p.U, "k-", lw=1.2, label="S3, e = 0 (event-driven)")
    a1.plot(f, r["s3"]["smooth"]["Z"] / p.U, "k:", lw=1.2, label="S3, e = 0 (smooth)")
    a1.set(yscale="log", xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]")
    a1.set_title(f"(a) FRF at the optimal box, mean of R = {R} beds ± 2 SE (thesis fig. 5.2a)",
                 fontsize=9)
    a1.legend(fontsize=7)
    for c, ((gn, gs), col) in enumerate(zip(s["cases"], ("C0", "C1", "C2", "C3"))):
        if gn == 0 and gs == 0:
            continue
        coll = (a["split"]["pp_normal"][c] + a["split"]["pw_normal"][c]).mean(-1)
        fric = (a["split"]["pp_friction"][c] + a["split"]["pw_friction"][c]).mean(-1)
        a2.plot(f, coll, "^-", color=col, ms=4, lw=0.8, label=f"collision, ({gn:g}, {gs:g})")
        a2.plot(f, fric, "s--", color=col, ms=4, lw=0.8, label=f"friction, ({gn:g}, {gs:g})")
        E = a["E"][c]
        draw_replicates(a2, f, E, fmt="o-", color=col, ms=5, mfc="none", lw=1.2, capsize=2,
                        label=f"total, ({gn:g}, {gs:g})")
    a2.plot(f, r["s3"]["event"]["total"], "k-", lw=1.2, label="S3, e = 0")
    a2.set(xlabel="excitation frequency f [Hz]", ylabel="granular loss per cycle [J]")
    a2.set_title("(b) dissipation per cycle, collisional vs frictional (thesis fig. 5.2b)",
                 fontsize=9)
    a2.legend(fontsize=6, ncol=2)
    scaffold.save_figure(fig, out, "fig5_2.png")


def _summary(out, r, s, prov):
    a, v, p, m_p = r["dem"], r["verdicts"], r["cfg"].primary, r["m_p"]
    U, R = p.U, s["R"]
    f = np.asarray(s["freqs"], float)
    s3 = r["s3"]
    lines = [
        "# Universal response at the optimal box, with replicates (thesis fig. 5.2)", "",
        scaffold.provenance_line(prov, r["wall"]) + " Data `data.h5`, figure `fig5_2.png`.", "",
        f"DEM: `sanchez2012-optimal` (N = 250, Lz = 0.1225 m, C = 7.6 N s/m, E = 2.03e9), "
        f"{len(s['cases'])} damping cases × {len(f)} frequencies × **R = {R} independently poured "
        f"beds** in one batch, {s['duration']} s per run after settling. Amplitude and loss per "
        "cycle: steady means after the MSER-detected start "
        f"({a['stationary']} of {a['runs']} runs stationary; {a['fallback']} amplitude/loss "
        "values fell back to the final 10 %); the collisional/frictional split is over the final "
        f"10 % of each run. S3: `sanchez2012-impact` (m = {s3['event']['cfg'].impactor.mass:.4f} "
        f"kg, e = 0, gap = {s3['event']['cfg'].impactor.gap} m), {s['s3_duration']} s per "
        "frequency, deterministic (one realisation is exact).", "",
        "Mean Z/U ± standard error over the beds:", ""]
    lines += scaffold.table(
        ["f [Hz]"] + [f"({gn:g}, {gs:g})" for gn, gs in s["cases"]]
        + ["S3 event", "S3 smooth", "analytic M", "analytic M + m_p"],
        [[f"{fi:g}"] + [scaffold.pm(*scaffold.mean_se(z), ".2f", ".2f") for z in a["Z"][:, i] / U]
         + [f"{s3['event']['Z'][i] / U:.2f}", f"{s3['smooth']['Z'][i] / U:.2f}",
            f"{frf_amplitude(fi, p.M, p.K, p.C, U) / U:.2f}",
            f"{frf_amplitude(fi, p.M + m_p, p.K, p.C, U) / U:.2f}"] for i, fi in enumerate(f)])
    rows = []
    for c, row in enumerate(v["cases"]):
        k = int(np.argmax(a["Z"][c].mean(-1)))
        coll = sum(a["split"][x][c, k].mean() for x in ("pp_normal", "pw_normal"))
        tot = sum(a["split"][x][c, k].mean() for x in SPLIT)
        change = ("reference" if c == 0 else
                  f"{scaffold.pm(row['d_peak_rel'], row['d_peak_ci_rel'], '+.1%', '.1%')} — "
                  + ("**changed**" if row["peak_changed"] else "not significant"))
        rows.append([f"({row['gamma_n']:g}, {row['gamma_s']:g})",
                     scaffold.pm(row["peak"], row["peak_se"], ".2f", ".2f"), change,
                     "–" if c == 0 else f"{row['freqs_differing']} of {len(f)}",
                     f"{coll / tot:.0%}" if tot > 0 else "– (no loss)",
                     f"{float(np.max(a['balance'][c])):.1e}"])
    for m in ("event", "smooth"):
        d = v[f"s3_{m}"]
        rows.append([f"S3 e = 0 ({m})", f"{resonance(f, s3[m]['Z'])[1] / U:.2f}",
                     f"largest \\|Z/Z_ref − 1\\| {d['max_rel_diff']:.1%}",
                     f"{d['beyond_2se']} of {len(f)} beyond 2 SE of the DEM mean", "–", "–"])
    lines += [""] + scaffold.table(
        ["case (γn, γs)", "resonant Z/U (± SE)", "change vs reference (Welch 95 %)",
         "frequencies differing at 95 %", "collision share of loss at the peak", "balance error"],
        rows)
    lines += ["", "**Loss per cycle: the bed against S3's impact loss** (thesis §5.3.2, fig. "
              "5.2b): the granular loss per drive period of every damping case (mean ± SE over the "
              "beds, steady state) and S3's loss at its impacts (e = 0, event-driven; "
              "deterministic); the last column is S3 over the reference case.", ""]
    ratios = np.array([s3["event"]["total"][i] / a["E"][0, i].mean() for i in range(len(f))])
    lines += scaffold.table(
        ["f [Hz]"] + [f"({gn:g}, {gs:g}) [J]" for gn, gs in s["cases"]]
        + ["S3 e = 0 [J]", "S3 / reference"],
        [[f"{fi:g}"] + [scaffold.pm(*scaffold.mean_se(e), 3) for e in a["E"][:, i]]
         + [f"{s3['event']['total'][i]:.3g}",
            f"{ratios[i] if a['E'][0, i].mean() > 0 else math.nan:.2f}"]
         for i, fi in enumerate(f)])
    lines += ["", f"S3's loss per cycle over the reference bed's: {ratios.min():.2f}–"
              f"{ratios.max():.2f} over {f.min():g}–{f.max():g} Hz (median "
              f"{np.median(ratios):.2f})."]
    lines += ["", f"Resonances of the analytic 1-DOF: M → {np.sqrt(p.K / p.M) / 2 / np.pi:.2f} "
              f"Hz, M + m_p → {np.sqrt(p.K / (p.M + m_p)) / 2 / np.pi:.2f} Hz. The reference "
              "and its variants share the beds (seeds 0…R−1); the Welch test treats them as "
              "independent, which is conservative when common beds correlate them."]
    scaffold.write_summary(out, lines)


if __name__ == "__main__":
    main()
