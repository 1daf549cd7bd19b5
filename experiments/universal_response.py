"""Thesis fig. 5.2 with replicates: is the optimal damper's response unchanged with the normal
(γ_n) or the tangential (γ_s) contact damping switched off, but not both, and matched by the
single-particle impact damper (S3) with e = 0?

    python experiments/universal_response.py           # full mode
    python experiments/universal_response.py --quick   # minutes

``sanchez2012-optimal``: the cases (γ_n, γ_s) (thesis values) × frequencies × ``R`` poured beds
in one batch (the same beds, seeds 0…R−1, in every case); amplitude and loss per cycle are MSER
steady means. S3 (``sanchez2012-impact``, e = 0, deterministic) runs event-driven and smooth.
Verdicts: per case, the change of the resonant amplitude against the reference (Welch 95 %) and
at how many frequencies the amplitude differs at 95 %; for S3, its distance from the reference
DEM mean in standard errors. Writes ``data.h5``, then ``fig5_2.png`` and ``summary.md`` from it.
"""

from __future__ import annotations

import json
import math

import numpy as np

from jaxdamp.analysis.response import frf_amplitude, resonance
from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures.response import draw_replicates
from jaxdamp.io.common import put
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points, steady_replicates
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


def run_s3(method, s) -> dict:
    """S3 (``sanchez2012-impact``) by ``method``: config, amplitude, loss, wall time."""
    cfg = apply_overrides(presets.get("sanchez2012-impact"), {
        "impactor.method": method, "numerics.duration": s["s3_duration"]})
    r = sweep(cfg, {"frequency": list(s["freqs"])}, progress=False).summary
    return dict(cfg=cfg, Z=np.asarray(r["amplitude"]),
                total=np.asarray(r["granular_loss_per_cycle"]), wall=float(r["wall_time"]))


def analyse(res, s) -> dict:
    nc, F, R = len(s["cases"]), len(s["freqs"]), s["R"]
    st = steady_replicates(res, "amplitude", "granular_loss_per_cycle")
    Z, E = (v.reshape(nc, F, R) for v in st.values)
    split = {k: np.asarray(res.replicate_summary[f"{k}_per_cycle"]).reshape(nc, F, R)
             for k in SPLIT}
    peaks = np.array([[resonance(np.asarray(s["freqs"], float), z) for z in Zc.T] for Zc in Z])
    return dict(Z=Z, E=E, split=split, f_peak=peaks[..., 0], Z_peak=peaks[..., 1],
                fallback=sum(st.fallback), stationary=int(st.stationary.sum()),
                runs=int(st.stationary.size), wall=st.wall,
                balance=np.asarray(res.summary["balance_error"]).reshape(nc, F))


def verdicts(a, s3, s, ref=0) -> dict:
    zp, U, out = a["Z_peak"], a["U"], {"cases": []}
    for c, (gn, gs) in enumerate(s["cases"]):
        d_peak, h_peak = welch(zp[c], zp[ref])
        diffs = [welch(a["Z"][c, i], a["Z"][ref, i]) for i in range(len(s["freqs"]))]
        out["cases"].append(dict(
            gamma_n=gn, gamma_s=gs, peak=float(zp[c].mean() / U),
            peak_se=float(scaffold.standard_error(zp[c]) / U),
            d_peak_rel=d_peak / float(zp[ref].mean()), d_peak_ci_rel=h_peak / float(zp[ref].mean()),
            peak_changed=bool(abs(d_peak) > h_peak) if c != ref else None,
            freqs_differing=int(sum(abs(d) > h for d, h in diffs)) if c != ref else None,
            max_rel_diff=float(max(abs(d) / a["Z"][ref, i].mean() for i, (d, _) in
                                   enumerate(diffs)))))
    zref, se = a["Z"][ref].mean(axis=-1), scaffold.standard_error(a["Z"][ref])
    for m, d in s3.items():
        z = (d["Z"] - zref) / se
        out[f"s3_{m}"] = dict(z=[float(x) for x in z],
                              max_rel_diff=float(np.max(np.abs(d["Z"] / zref - 1))),
                              beyond_2se=int(np.sum(np.abs(z) > 2)))
    return out


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = optimal(s)  # every (case, frequency) point × R beds in one batch:
    gn, gs, f = zip(*[(gn, gs, f) for gn, gs in s["cases"] for f in s["freqs"]])
    axes = Points({"grains.0.material.gamma_n": list(gn), "grains.0.material.gamma_s": list(gs),
                   "frequency": list(f)})
    res = reuse_or_run(cfg, axes, ctx.raw(f"sweep_cases_R{s['R']}.h5"), progress=ctx.progress,
                       replicates=s["R"])
    a = dict(analyse(res, s), U=cfg.primary.U)
    s3 = {method: run_s3(method, s) for method in ("event", "smooth")}
    v = verdicts(a, s3, s)
    for row in v["cases"][1:]:
        log(f"(γn, γs) = ({row['gamma_n']:g}, {row['gamma_s']:g}): resonant Z changes by "
            f"{scaffold.pm(row['d_peak_rel'], row['d_peak_ci_rel'], '+.1%', '.1%')} (Welch 95 %)")
    result = dict(dem=a, s3=s3, verdicts=v, cfg=cfg, m_p=grain_mass(cfg),
                  wall=a["wall"] + sum(d["wall"] for d in s3.values()))
    return result, lambda path, prov: record(result, s, path, prov)


def record(r, s, out, prov):
    a = r["dem"]
    with scaffold.data_file(out, dict(prov, sweep_wall_s=r["wall"]), settings=json.dumps(s),
                            verdicts=json.dumps(r["verdicts"]), config=r["cfg"].to_json()) as h:
        put(h, "frequency", s["freqs"], "Hz")
        put(h, "cases", s["cases"], "kg s^-1 m^-1/2", columns="gamma_n, gamma_s (thesis values)")
        dims = "case, frequency, replicate"
        for k, v, u in (("amplitude", a["Z"], "m"), ("granular_loss_per_cycle", a["E"], "J"),
                        ("f_peak", a["f_peak"], "Hz"), ("Z_peak", a["Z_peak"], "m")):
            put(h, f"dem/{k}", v, u, dims=dims)
        for k, v in a["split"].items():
            put(h, f"dem/{k}_per_cycle", v, "J", dims=dims, window="final 10 % of the run")
        h["dem"].attrs.update(stationary=a["stationary"], runs=a["runs"], fallback=a["fallback"],
                              balance_error_max=a["balance"].max(-1))  # per case, units 1
        for m, d in r["s3"].items():
            g = h.create_group(f"s3/{m}")
            g.attrs["config"] = d["cfg"].to_json()
            put(g, "Z", d["Z"], "m")
            put(g, "total", d["total"], "J")


def report(data, out):
    s, v, dem = data.attrs["settings"], data.attrs["verdicts"], data["dem"]
    cfg = from_dict(data.attrs["config"])
    p, m_p, R = cfg.primary, grain_mass(cfg), s["R"]
    U, f = p.U, np.asarray(s["freqs"], float)
    Z, E = dem["amplitude"], dem["granular_loss_per_cycle"]
    split = {k: dem[f"{k}_per_cycle"] for k in SPLIT}
    s3, prov, imp = data["s3"], data.attrs, data["s3"]["event"].attrs["config"]["impactor"]
    analytic = [frf_amplitude(f, M, p.K, p.C, U) / U for M in (p.M, p.M + m_p)]
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(12, 4.8))
    ff = np.linspace(f.min() * 0.95, f.max() * 1.02, 400)
    for M, col, lab in ((p.M, "orange", "M"), (p.M + m_p, "brown", "M + m_p")):
        a1.plot(ff, frf_amplitude(ff, M, p.K, p.C, U) / U, color=col, ls="--", lw=0.9,
                label=f"analytic, {lab}")
    for c, (gn, gs) in enumerate(s["cases"]):
        draw_replicates(a1, f, Z[c] / U, fmt="osd^"[c], ms=6, mfc="none", capsize=3,
                        label=f"DEM γn = {gn:g}, γs = {gs:g}")
        if gn == 0 and gs == 0:  # no loss to split
            continue
        for name, keys, fmt in (("collision", SPLIT[:2], "^-"), ("friction", SPLIT[2:], "s--")):
            a2.plot(f, (split[keys[0]][c] + split[keys[1]][c]).mean(-1), fmt, color=f"C{c}",
                    ms=4, lw=0.8, label=f"{name}, ({gn:g}, {gs:g})")
        draw_replicates(a2, f, E[c], fmt="o-", color=f"C{c}", ms=5, mfc="none", lw=1.2,
                        capsize=2, label=f"total, ({gn:g}, {gs:g})")
    a1.plot(f, s3["event"]["Z"] / U, "k-", lw=1.2, label="S3, e = 0 (event-driven)")
    a1.plot(f, s3["smooth"]["Z"] / U, "k:", lw=1.2, label="S3, e = 0 (smooth)")
    a1.set(yscale="log", xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]")
    a1.set_title(f"(a) FRF at the optimal box, mean of R = {R} beds ± 2 SE (thesis fig. 5.2a)",
                 fontsize=9)
    a1.legend(fontsize=7)
    a2.plot(f, s3["event"]["total"], "k-", lw=1.2, label="S3, e = 0")
    a2.set(xlabel="excitation frequency f [Hz]", ylabel="granular loss per cycle [J]")
    a2.set_title("(b) dissipation per cycle, collisional vs frictional (thesis fig. 5.2b)",
                 fontsize=9)
    a2.legend(fontsize=6, ncol=2)
    scaffold.save_figure(fig, out, "fig5_2.png")

    lines = scaffold.head("Universal response at the optimal box, with replicates (thesis fig. "
                          "5.2)", prov, prov["sweep_wall_s"])
    lines[2] += " Data `data.h5`, figure `fig5_2.png`."
    lines += [
        f"DEM: `sanchez2012-optimal` (N = 250, Lz = 0.1225 m, C = 7.6 N s/m, E = 2.03e9), "
        f"{len(s['cases'])} damping cases × {len(f)} frequencies × **R = {R} independently poured "
        f"beds**, {s['duration']} s per run; {dem.attrs['stationary']} of {dem.attrs['runs']} "
        f"runs stationary, {dem.attrs['fallback']} amplitude/loss values fell back to the final "
        "10 %, the window of the collisional/frictional split. S3: `sanchez2012-impact` (m = "
        f"{imp['mass']:.4f} kg, e = 0, gap = {imp['gap']} m), {s['s3_duration']} s per frequency.",
        "", "Mean Z/U ± standard error over the beds:", ""]
    lines += scaffold.table(
        ["f [Hz]"] + [f"({gn:g}, {gs:g})" for gn, gs in s["cases"]]
        + ["S3 event", "S3 smooth", "analytic M", "analytic M + m_p"],
        [[f"{fi:g}"] + [scaffold.pm(*scaffold.mean_se(z), ".2f", ".2f") for z in Z[:, i] / U]
         + [f"{x[i]:.2f}" for x in (s3["event"]["Z"] / U, s3["smooth"]["Z"] / U, *analytic)]
         for i, fi in enumerate(f)])
    rows = []
    for c, row in enumerate(v["cases"]):
        loss = [split[x][c, int(np.argmax(Z[c].mean(-1)))].mean() for x in SPLIT]  # at the peak
        coll, tot = sum(loss[:2]), sum(loss)
        change = ("reference" if c == 0 else
                  f"{scaffold.pm(row['d_peak_rel'], row['d_peak_ci_rel'], '+.1%', '.1%')} — "
                  + ("**changed**" if row["peak_changed"] else "not significant"))
        rows.append([f"({row['gamma_n']:g}, {row['gamma_s']:g})",
                     scaffold.pm(row["peak"], row["peak_se"], ".2f", ".2f"), change,
                     "–" if c == 0 else f"{row['freqs_differing']} of {len(f)}",
                     f"{coll / tot:.0%}" if tot > 0 else "– (no loss)",
                     f"{float(dem.attrs['balance_error_max'][c]):.1e}"])
    rows += [[f"S3 e = 0 ({m})", f"{resonance(f, s3[m]['Z'])[1] / U:.2f}",
              f"largest \\|Z/Z_ref − 1\\| {v['s3_' + m]['max_rel_diff']:.1%}",
              f"{v['s3_' + m]['beyond_2se']} of {len(f)} beyond 2 SE of the DEM mean", "–", "–"]
             for m in ("event", "smooth")]
    lines += [""] + scaffold.table(
        ["case (γn, γs)", "resonant Z/U (± SE)", "change vs reference (Welch 95 %)",
         "frequencies differing at 95 %", "collision share of loss at the peak", "balance error"],
        rows)
    lines += ["", "**Loss per cycle: the bed against S3's impact loss** (thesis §5.3.2, fig. "
              "5.2b), mean ± SE over the beds; the last column is S3 over the reference.", ""]
    ratio = s3["event"]["total"] / E[0].mean(-1)
    lines += scaffold.table(
        ["f [Hz]"] + [f"({gn:g}, {gs:g}) [J]" for gn, gs in s["cases"]]
        + ["S3 e = 0 [J]", "S3 / reference"],
        [[f"{fi:g}"] + [scaffold.pm(*scaffold.mean_se(e), 3) for e in E[:, i]]
         + [f"{s3['event']['total'][i]:.3g}",
            f"{ratio[i] if E[0, i].mean() > 0 else math.nan:.2f}"] for i, fi in enumerate(f)])
    lines += ["", f"S3's loss per cycle over the reference bed's: {ratio.min():.2f}–"
              f"{ratio.max():.2f} over {f.min():g}–{f.max():g} Hz (median {np.median(ratio):.2f}).",
              "", f"Resonances of the analytic 1-DOF: M → {np.sqrt(p.K / p.M) / 2 / np.pi:.2f} "
              f"Hz, M + m_p → {np.sqrt(p.K / (p.M + m_p)) / 2 / np.pi:.2f} Hz. The cases share "
              "the beds; the Welch test treats them as independent (conservative)."]
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
