"""Box-height scan of the thesis' optimal damper, with replicates: FRFs, effective mass and
damping, the optimum with an interval (thesis figs. 3.6–3.9; issue 13 items 1–2).

    python experiments/gap_scan.py            # full mode (see summary.md for its wall time)
    python experiments/gap_scan.py --quick    # minutes: 3 heights x 4 frequencies, 2 beds

Per primary damping ``C`` (7.6, 26.3 N s/m) one batched sweep of ``sanchez2012-optimal`` over
(frequency, ``Lz``) × ``R`` poured beds; a run's amplitude is its steady mean after the MSER start
(else its final window). Per ``Lz`` and bed the 1-DOF FRF is fitted, ``U, K`` fixed, with
``absolute`` (``(Z_model − Z)/U``, the thesis' fit) and ``relative`` (``Z_model/Z − 1``)
residuals; ``M_ef``, ``C_ef`` are t-tested against ``M``, ``M + m_p`` and refitted on 8–23 Hz.
**The optimum**: per bed the largest ``C_ef`` and the smallest resonant amplitude by a parabola
in ``log Lz``; its t-interval holds the thesis' 0.1225 m or not. **Mechanism** (fig. 3.9): the
first harmonic of the grains' force on the box against its motion, near resonance.

Writes ``data.h5``, ``fig3_6.png`` (FRFs), ``fig3_7_3_8.png`` (``C_ef/C``, ``M_ef`` vs ``Lz``),
``fig3_9.png``, ``summary.md`` in ``--out``; raw sweeps (resumable) in ``--out/raw/``.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np

from jaxdamp.analysis import response
from jaxdamp.analysis.response import RESIDUALS, crossings, fit_frf_scan, resonances
from jaxdamp.analysis.stats import replicate_extrema, t_quantile
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures import figure, frf_figure
from jaxdamp.figures.response import draw_interval, draw_replicates, draw_run_band
from jaxdamp.io.common import put
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

LZ_FULL = (0.042, 0.057, 0.087, 0.1095, 0.117, 0.1225, 0.147, 0.162, 0.282, 0.372)  # [m], SPEC §5
#: Frequencies [Hz]: denser between the resonances of M + m_p (14.5 Hz) and M (15.2 Hz).
F_FULL = (5.0, 10.0, 12.0, 13.5, 14.5, 15.25, 16.0, 18.5, 25.0)
F_NARROW = (8.0, 23.0)  # the range of the earlier, single-bed scan: refitted on it
FIG36_LZ = (0.057, 0.1225, 0.372)
FIG39_LZ = (0.042, 0.057, 0.087, 0.1095, 0.1225, 0.147, 0.162)
THESIS_OPTIMUM = 0.1225  # [m]
THESIS_WEIGHTING = "absolute"  # the weighting the thesis describes, named in every verdict
OPT = f"max_C_ef_{THESIS_WEIGHTING}"  # the thesis' optimum: largest C_ef of its fit
BAND = ("t", "z_box", "z_lowest", "z_highest", "force_box")  # a run of fig. 3.9, as stored


def settings(quick: bool) -> dict:
    if quick:
        return dict(lz=(0.057, 0.1225, 0.372), freqs=(12.0, 14.5, 15.25, 18.0), C=(7.6,),
                    duration=0.4, settle=0.15, R=2)
    return dict(lz=LZ_FULL, freqs=F_FULL, C=(7.6, 26.3), duration=2.5, settle=0.3, R=3)


def near(f, f_peak) -> list[int]:
    """Per height, the frequency sample nearest its mean resonance (``f_peak`` ``(L, R)``)."""
    return [int(np.argmin(np.abs(f - np.mean(fp)))) for fp in f_peak]


def analyse(res, cfg, s) -> dict:
    """Fits of both weightings, resonances and optima per replicate; see the module doc."""
    f, lz = (np.asarray(res.axes[k], float) for k in ("frequency", "box.Lz"))
    Zr, fallback = steady_or_window(res, "amplitude")  # (F, L, R)
    p, m_p = cfg.primary, grain_mass(cfg)
    fits = {w: fit_frf_scan(f, Zr, p, w) for w in RESIDUALS}
    f_peak, Z_peak = resonances(f, Zr)  # (L, R)
    C_reps = {w: np.array([fi["C_reps"] for fi in fits[w]]) for w in RESIDUALS}  # (L, R)
    optimum = {f"max_C_ef_{w}": _optimum_row(replicate_extrema(lz, C_reps[w], "max", True), lz)
               for w in RESIDUALS}
    optimum["min_peak"] = _optimum_row(replicate_extrema(lz, Z_peak, "min", True, True), lz)
    # the vertices of parabolas in Lz itself: a systematic error not in the replicates' interval
    optimum["model_check"] = {
        OPT: float(np.mean(replicate_extrema(lz, C_reps[THESIS_WEIGHTING], "max").x)),
        "min_peak": float(np.mean(replicate_extrema(lz, Z_peak, "min").x))}
    q = t_quantile(0.975, s["R"] - 1) if s["R"] >= 2 else math.nan
    tests = {}
    for w in RESIDUALS:
        M, se = (np.array([fi[k] for fi in fits[w]]) for k in ("M_ef", "se_M"))
        tests[w] = dict(below_M=[(float(L), float((m - p.M) / e)) for L, m, e in zip(lz, M, se)
                                 if m < p.M - q * e],
                        above_Mmp=[(float(L), float((m - p.M - m_p) / e))
                                   for L, m, e in zip(lz, M, se) if m > p.M + m_p + q * e],
                        crossings=crossings(lz, M, p.M))
    stationary = np.asarray(res.steady["amplitude"]["stationary"], bool)
    starts = np.asarray(res.steady["amplitude"]["start"], float)
    force = force_coefficients(res, np.where(stationary, starts, s["duration"] / 2))
    k, band = near(f, f_peak), {}
    for j in (j for j, L in enumerate(lz) if L in FIG39_LZ):  # fig. 3.9: bed 0, last 3 periods
        run = {q: np.asarray(res.records[q][res.point(k[j] * len(lz) + j, 0)]) for q in BAND}
        band[lz[j]] = {q: v[run["t"] >= run["t"][-1] - 3 / f[k[j]]] for q, v in run.items()}
    return dict(Zr=Zr, fallback=fallback, fits=fits, f_peak=f_peak, Z_peak=Z_peak,
                stationary_by_lz=stationary.sum(axis=(0, 2)),  # (L,) of F x R runs each
                optimum=optimum, tests=tests, m_p=m_p, force=force, band=band,
                stationary=int(stationary.sum()), runs=int(stationary.size),
                start_range=(float(np.nanmin(starts)), float(np.nanmax(starts)))
                if stationary.any() else (math.nan, math.nan))


def force_coefficients(res, t0) -> dict:
    """Per run ``(F, L, R)``, the grains' force on the box as added mass, damping and impact
    phase (:func:`~jaxdamp.analysis.response.grain_force_coefficients`) from ``t0`` [s] on."""
    f, rec, L = np.asarray(res.axes["frequency"], float), res.records, t0.shape[1]
    rows = [(i, res.point(i * L + j, r), t0[i, j, r]) for i, j, r in np.ndindex(t0.shape)]
    c = [response.grain_force_coefficients(  # force samples: means over the sample spacing
        rec["t"][k], rec["z_box"][k], rec["force_box"][k], f[i], t_start=t,
        interval=float(rec["t"][k][1] - rec["t"][k][0])) for i, k, t in rows]
    return {q: np.reshape([x[q] for x in c], t0.shape) for q in ("m_add", "c_add", "phase")}


def _optimum_row(e, lz) -> dict:
    """An optimum of :func:`replicate_extrema` as stored (with whether it holds the thesis')."""
    m, ci = e.estimate.mean, e.estimate.ci95
    return dict(vertices=[float(x) for x in e.x], grid_best=[float(lz[k]) for k in e.best],
                mean=m, se=e.estimate.se, ci95=ci,
                contains_thesis=bool(abs(THESIS_OPTIMUM - m) <= ci) if np.isfinite(ci) else None)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    results = {}
    for C in s["C"]:  # one batched (frequency x Lz x bed) sweep per C, reused or resumed
        cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
            "primary.C": C, "numerics.duration": s["duration"], "numerics.record_dt": 1e-3,
            "numerics.settle_time": s["settle"], "numerics.chunk": 0.1})
        path = ctx.raw(f"sweep_C{C:g}_R{s['R']}.h5")
        res = reuse_or_run(cfg, {"frequency": list(s["freqs"]), "box.Lz": list(s["lz"])}, path,
                           progress=ctx.progress, replicates=s["R"])
        with h5py.File(path, "r") as h:  # the R settled beds (the same at every grid point)
            heights = np.asarray(h["settle/bed_height"][()])[:s["R"]]
        r = results[C] = dict(res=res, cfg=cfg, bed_heights=heights, **analyse(res, cfg, s))
        log(f"C = {C}: {r['stationary']}/{r['runs']} runs stationary")
    return results, lambda path, prov: record(results, s, path, prov)


def record(results, s, out, prov):
    prov = dict(prov, sweep_wall_s=sum(float(r["res"].summary["wall_time"])
                                       for r in results.values()))
    runs = "frequency, box.Lz, replicate"
    with scaffold.data_file(out, prov, settings=json.dumps(s),
                            thesis_weighting=THESIS_WEIGHTING) as h:
        for C, r in results.items():
            g = h.create_group(f"C_{C:g}")
            hm, hse = scaffold.mean_se(r["bed_heights"])
            g.attrs.update(base_config=r["cfg"].to_json(), optimum=json.dumps(r["optimum"]),
                           tests=json.dumps(r["tests"]), grain_mass=r["m_p"],
                           stationary=r["stationary"], runs=r["runs"], fallback=r["fallback"],
                           stationary_by_lz=r["stationary_by_lz"], bed_heights=r["bed_heights"],
                           bed_height_mean=hm, bed_height_se=hse,
                           steady_start_range=r["start_range"])
            for k, v in r["res"].axes.items():
                put(g, f"axes/{k}", np.asarray(v, float), "Hz" if k == "frequency" else "m")
            put(g, "amplitude", r["Zr"], "m", dims=runs,
                what="steady mean over the MSER-detected steady state")
            put(g, "f_peak", r["f_peak"], "Hz")
            put(g, "Z_peak", r["Z_peak"], "m")
            for w in RESIDUALS:
                for k, unit in (("M", "kg"), ("C", "N s/m")):
                    for q in (f"{k}_reps", f"{k}_ef", f"se_{k}"):
                        put(g, f"fit_{w}/{q}", [fi[q] for fi in r["fits"][w]], unit)
            for k, u in (("m_add", "kg"), ("c_add", "N s/m"), ("phase", "rad")):
                put(g, f"force/{k}", r["force"][k], u, dims=runs, what="first harmonic of the "
                    "grains' force on the box against the box motion over the steady state")
            for k, v in r["res"].summary.items():
                if np.ndim(v):
                    g.create_dataset(f"summary/{k}", data=v)
            for L, run in r["band"].items():
                for k, unit in zip(BAND, ("s", "m", "m", "m", "N")):
                    put(g, f"band/{L:g}/{k}", run[k], unit, what="bed 0, the last 3 periods")


def report(data, out):
    s = data.attrs["settings"]
    lz, R = list(s["lz"]), s["R"]
    groups = {C: data[f"C_{C:g}"] for C in s["C"]}
    C0, g = s["C"][0], groups[s["C"][0]]
    p, m_p = from_dict(g.attrs["base_config"]).primary, g.attrs["grain_mass"]
    cols = [lz.index(L) for L in FIG36_LZ if L in lz]
    Zr, fw = g["amplitude"][:, cols], g[f"fit_{THESIS_WEIGHTING}"]
    scaffold.save_figure(frf_figure(
        g["axes"]["frequency"], Zr.mean(axis=-1), [lz[j] for j in cols], p, m_p,
        [(fw["M_ef"][j], fw["C_ef"][j]) for j in cols], Z_se=scaffold.standard_error(Zr),
        title=f"sanchez2012-optimal, C = {C0} N s/m, mean of R = {R} beds ± 2 SE; dotted: "
        f"{THESIS_WEIGHTING}-residual 1-DOF fits (thesis fig. 3.6)"), out, "fig3_6.png")

    fig, (a1, a2) = scaffold.subplots(2, 1, figsize=(7.5, 7.5), sharex=True)
    for C, gc in groups.items():
        for w, ls in zip(RESIDUALS, ("-", "--")):
            kw = dict(fmt="o", ls=ls, capsize=3, ms=4, label=f"C = {C} N s/m, {w} residuals")
            draw_replicates(a1, lz, gc[f"fit_{w}"]["C_reps"] / C, **kw)  # C_ef/C ± 2 SE
            draw_replicates(a2, lz, gc[f"fit_{w}"]["M_reps"], **kw)
        o = gc.attrs["optimum"][OPT]
        draw_interval(a1, o["mean"], o["ci95"], alpha=0.12, color=a1.lines[-1].get_color())
    a1.axhline(1, color="0.5", lw=0.8)
    a1.set_ylabel("C_ef / C  [-]")
    a1.set_title(f"effective damping and mass from the FRF fit, mean of R = {R} beds ± 2 SE "
                 "(thesis figs. 3.7, 3.8); band: 95 % interval of the optimum", fontsize=8)
    a2.axhline(p.M, color="r", lw=0.8, ls="--", label="M")
    a2.axhline(p.M + m_p, color="r", lw=0.8, ls=":", label="M + m_p")
    a2.set(ylabel="M_ef [kg]", xlabel="box height Lz [m]")
    for a in (a1, a2):
        a.set_xscale("log")
        a.axvline(THESIS_OPTIMUM, color="g", lw=0.6, ls="-.", label="thesis optimum, 0.1225 m")
        a.legend(fontsize=6)
    scaffold.save_figure(fig, out, "fig3_7_3_8.png")
    if "band" in g:  # files before 2026-12-05 hold no runs: their fig3_9.png stays as it is
        _figure_3_9(out, g, lz, p.M, m_p,
                    f"thesis fig. 3.9: C = {C0} N s/m, mean of R = {R} beds ± 2 SE")
    _summary(out, groups, s, data.attrs)


def _figure_3_9(out, g, lz, M, m_p, title):
    """Bed band and grain force against the box motion at the heights of the thesis' fig. 3.9
    (bed 0 near resonance, the last three periods); impact phase and effective mass vs Lz."""
    f = g["axes"]["frequency"]
    show, k = [L for L in FIG39_LZ if L in lz], near(f, g["f_peak"])
    ncol = max(len(show), 4)
    fig = figure((2.3 * ncol, 7.5))
    gs = fig.add_gridspec(2, ncol, height_ratios=[1.2, 1])
    for c, L in enumerate(show):
        i, ax, run = k[lz.index(L)], fig.add_subplot(gs[0, c]), g["band"][f"{L:g}"]
        m = draw_run_band(ax, run, L, f[i], centre=False, fontsize=7)
        axf = ax.twinx()
        axf.plot(run["t"][m], run["force_box"][m], "-", color="tab:blue", lw=0.7)
        axf.tick_params(labelsize=6, colors="tab:blue")
        ax.tick_params(labelsize=6)
        ax.set_title(f"Lz = {L} m, {f[i]:g} Hz", fontsize=7)
        if c == 0:
            ax.legend(fontsize=6, loc="upper left")
        else:
            ax.set_ylabel("")
        if c == len(show) - 1:
            axf.set_ylabel("grains' force on the box [N] (blue)", fontsize=7, color="tab:blue")
    at = (k, np.arange(len(lz)))  # per height, its frequency nearest the resonance
    a1, a2 = fig.add_subplot(gs[1, : ncol // 2]), fig.add_subplot(gs[1, ncol // 2:])
    draw_replicates(a1, lz, np.degrees(g["force"]["phase"][at]))
    a1.axhline(0, color="0.6", lw=0.6)
    a1.axhline(-90, color="0.6", lw=0.6, ls=":")
    a1.set_ylabel("impact phase arg(F̂/Ẑ) [deg]")
    a1.set_title("phase of the grains' force against the box motion, near resonance "
                 "(0°: mass, −90°: damper)", fontsize=8)
    draw_replicates(a2, lz, M + g["force"]["m_add"][at], label="M + m_add from the force phase")
    draw_replicates(a2, lz, g[f"fit_{THESIS_WEIGHTING}"]["M_reps"], fmt="s--",
                    label=f"M_ef from the FRF fit ({THESIS_WEIGHTING})")
    a2.axhline(M, color="r", lw=0.8, ls="--", label="M")
    a2.axhline(M + m_p, color="r", lw=0.8, ls=":", label="M + m_p")
    a2.set_ylabel("effective mass [kg]")
    a2.legend(fontsize=7)
    for a in (a1, a2):
        a.set(xscale="log", xlabel="box height Lz [m]")
    fig.suptitle(title, fontsize=9)
    scaffold.save_figure(fig, out, "fig3_9.png", dpi=110)


def _fmt_opt(o) -> str:
    verdict = {None: "cannot judge (fewer than 2 finite vertices)", True: "contains",
               False: "excludes"}[o["contains_thesis"]]
    return (f"{scaffold.pm(o['mean'], o['se'], '.4f', '.4f', unit='m')} (95 %: ± "
            f"{o['ci95']:.4f}; replicates' vertices {', '.join(f'{x:.4f}' for x in o['vertices'])}"
            f"; best grid heights {', '.join(f'{x:g}' for x in o['grid_best'])}) — {verdict} the "
            "thesis' 0.1225 m")


def _pm(x, spec: str) -> str:  # mean ± SE over the beds (their finite values), both to spec
    e = scaffold.across(x)
    return scaffold.pm(e.mean, e.se, spec, spec)


def _summary(out, groups, s, prov):
    g0, R = groups[s["C"][0]], s["R"]
    a0, p0 = g0.attrs, from_dict(g0.attrs["base_config"]).primary
    lines = [
        *scaffold.head("Box-height scan with replicates: FRFs, effective mass and damping, the "
                       "optimum (thesis figs. 3.6–3.8)", prov, prov["sweep_wall_s"]),
        f"**Runs.** {len(s['freqs'])} frequencies {min(s['freqs'])}–{max(s['freqs'])} Hz × "
        f"{len(s['lz'])} heights × **R = {R} independently poured beds** (seeds 0…{R - 1}), "
        f"{s['duration']} s per run after settling (thesis: 13.12 s). Settled bed heights: "
        + ", ".join(f"{x:.6f}" for x in a0["bed_heights"])
        + f" m (mean {scaffold.pm(a0['bed_height_mean'], a0['bed_height_se'], '.6f', '.6f')} m, "
        "SE; thesis ≈ 0.039 m).", "",
        "**Stationarity** (MSER): " + "; ".join(
            f"C = {C}: {g.attrs['stationary']} of {g.attrs['runs']} runs stationary (steady from "
            "t = {:.2f}–{:.2f} s), ".format(*g.attrs["steady_start_range"])
            + f"{g.attrs['fallback']} fell back to the final 10 %" for C, g in groups.items())
        + ".", "",
        f"**Uncertainty.** ± = SE over the R = {R} beds' own fits; Student-t tests at 95 % with "
        f"{R - 1} degrees of freedom (t = {t_quantile(0.975, max(R - 1, 1)):.2f}). `absolute` "
        "residuals are **the fit the thesis describes**; verdicts name their weighting.", "",
        f"Reference masses: M = {p0.M} kg, M + m_p = {p0.M + a0['grain_mass']:.4f} kg.", ""]
    for C, g in groups.items():
        fa, fr, o, fo = g["fit_absolute"], g["fit_relative"], g.attrs["optimum"], g["force"]
        p, f = from_dict(g.attrs["base_config"]).primary, g["axes"]["frequency"]
        lines += [f"## C = {C} N s/m", ""] + scaffold.table(
            ["Lz [m]", "M_ef abs. [kg]", "C_ef/C abs.", "M_ef rel. [kg]", "C_ef/C rel.",
             "resonance [Hz]", "peak Z/U", "stationary runs"],
            [[L, _pm(fa["M_reps"][j], ".3f"), _pm(fa["C_reps"][j] / C, ".2f"),
              _pm(fr["M_reps"][j], ".3f"), _pm(fr["C_reps"][j] / C, ".2f"),
              _pm(g["f_peak"][j], ".2f"), _pm(g["Z_peak"][j] / p0.U, ".2f"),
              f"{g.attrs['stationary_by_lz'][j]} of {len(s['freqs']) * R}"]
             for j, L in enumerate(s["lz"])])
        lines += ["", "**The optimum** (parabola in log Lz per bed, mean ± SE, t-interval):", ""]
        lines += [f"- largest C_ef, {w} residuals" + " (the thesis' fit)" * (w == THESIS_WEIGHTING)
                  + f": {_fmt_opt(o[f'max_C_ef_{w}'])}." for w in RESIDUALS]
        lines += [f"- smallest resonant amplitude (no fit): {_fmt_opt(o['min_peak'])}.",
                  f"- parabolas in Lz instead of log Lz: {o['model_check'][OPT]:.4f} m (largest "
                  f"C_ef, {THESIS_WEIGHTING}), {o['model_check']['min_peak']:.4f} m (smallest "
                  "peak); a systematic error of the grid, not in the beds' interval.", "",
                  "**Effective mass against M and M + m_p** (95 % t-test per height):", ""]
        for w in RESIDUALS:
            t = g.attrs["tests"][w]
            below, above = (", ".join(f"{L:g} ({z:+.1f} SE)" for L, z in t[k]) or "none"
                            for k in ("below_M", "above_Mmp"))
            cross = ", ".join(f"{x:.4f}" for x in t["crossings"]) or "none"
            lines.append(f"- {w} residuals: M_ef significantly below M at Lz = {below}; above "
                         f"M + m_p at Lz = {above}; the mean M_ef(Lz) crosses M at {cross} m.")
        lines += ["", "**Mechanism (thesis fig. 3.9, `fig3_9.png`)** near each height's resonance: "
                  "impact phase φ = arg(F̂/Ẑ) (0°: a mass, −90°: a damper), M + m_add and C + c_add "
                  f"without a fit, beside the {THESIS_WEIGHTING}-residual fit:", ""]
        fw = g[f"fit_{THESIS_WEIGHTING}"]
        lines += scaffold.table(
            ["Lz [m]", "f [Hz]", "φ [deg]", "M + m_add [kg]", "M_ef fit [kg]",
             "C + c_add [N s/m]", "C_ef fit [N s/m]"],
            [[L, f"{f[i]:g}", _pm(np.degrees(fo["phase"][i, j]), ".0f"),
              _pm(p.M + fo["m_add"][i, j], ".3f"), _pm(fw["M_reps"][j], ".3f"),
              _pm(p.C + fo["c_add"][i, j], ".1f"), _pm(fw["C_reps"][j], ".1f")]
             for j, (L, i) in enumerate(zip(s["lz"], near(f, g["f_peak"])))])
        narrow = (f >= F_NARROW[0]) & (f <= F_NARROW[1])  # the widened range: refit without it
        star = lambda e: "*" * bool(np.isfinite(e.ci95) and abs(e.mean) > e.ci95)  # noqa: E731
        if not narrow.all():
            lines += ["", f"**Widened range.** Full − refit on {F_NARROW[0]:g}–{F_NARROW[1]:g} Hz, "
                      "paired per bed, mean (* = significant at 95 %):", ""]
        for w in () if narrow.all() else RESIDUALS:
            refit = fit_frf_scan(f[narrow], g["amplitude"][narrow], p, w)
            dM, dC = ([scaffold.across(a - b[f"{k}_reps"]) for a, b in zip(
                g[f"fit_{w}"][f"{k}_reps"], refit)] for k in ("M", "C"))
            lines.append(f"- {w}: " + "; ".join(
                f"{L:g}: ΔM {m.mean:+.3f}{star(m)} kg, ΔC {c.mean:+.2f}{star(c)}"
                for L, m, c in zip(s["lz"], dM, dC)) + ".")
        lines.append("")
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
