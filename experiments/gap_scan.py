"""Box-height scan of the thesis' optimal damper, with replicates: FRFs, effective mass and
damping, the optimum with an interval (thesis figs. 3.6–3.8; issue 13 items 1–2).

    python experiments/gap_scan.py            # full mode (see summary.md for its wall time)
    python experiments/gap_scan.py --quick    # minutes: 3 heights x 4 frequencies, 2 beds

For each primary damping ``C`` (7.6 and 26.3 N s/m) one batched sweep runs every
(frequency, ``Lz``) point of ``sanchez2012-optimal`` with ``R`` independently poured beds
(replicates; :func:`jaxdamp.studies.sweep.sweep`). The amplitude of every run is its steady
mean over the steady state detected by MSER on the per-period amplitude and dissipation
(:mod:`jaxdamp.analysis.stats`); a run that never became stationary is counted and falls back
to its final-window amplitude.

Per ``Lz`` and replicate the analytic 1-DOF FRF is fitted with ``U, K`` fixed
(:func:`jaxdamp.analysis.response.fit_frf_replicates`), with **both** residual weightings:
``absolute`` (``(Z_model − Z)/U``: dominated by the largest amplitudes — the fit the thesis
describes, §3.2.1) and ``relative`` (``Z_model/Z − 1``: every frequency weighs the same).
``M_ef`` and ``C_ef`` are means over the replicates ± their standard error; every comparison
(``M_ef`` against ``M`` and ``M + m_p``) is a Student-t test at 95 % with ``R − 1`` degrees
of freedom. The widened range (5 and 25–30 Hz added to the thesis-era 8–23 Hz) is checked by
refitting on 8–23 Hz only: the paired change of ``M_ef``, ``C_ef`` per replicate.

**The optimum with an interval.** For each replicate the largest ``C_ef(Lz)`` and the smallest
resonant amplitude ``Z_peak(Lz)`` are located by a parabola in ``log Lz`` through the best
height and its two neighbours (:func:`jaxdamp.analysis.response.parabolic_extremum`); the
replicates' vertices give mean ± SE and a t-interval. The thesis' 0.1225 m is then inside the
interval or not — a verdict from the interval, not from which grid point is best.

Writes, in ``--out``: ``data.h5`` (per ``C``: per-replicate amplitudes, fits of both
weightings, optima, configuration), ``fig3_6.png`` (FRFs at Lz = 0.057, 0.1225, 0.372 m for
C = 7.6, ± 2 SE, with the thesis' absolute fit), ``fig3_7_3_8.png`` (``C_ef/C`` and ``M_ef``
versus ``Lz``, both weightings, the optimum's interval) and ``summary.md``. Raw sweep files
(every time series; resumable after a kill) go to ``--out/raw/`` (not committed).
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
from jaxdamp.config import apply_overrides
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

#: Box heights [m] of the thesis' scan (SPEC §5), its 0.117 and 0.282 m included.
#: (0.072 and 0.222 m, on the earlier single-bed grid, are left out to afford three beds per
#: point on two shared cores.)
LZ_FULL = (0.042, 0.057, 0.087, 0.1095, 0.117, 0.1225, 0.147, 0.162, 0.282, 0.372)
#: Frequencies [Hz]: denser between the resonances of M + m_p (14.5 Hz) and M (15.2 Hz); the
#: thesis' wider range (0.5–30 Hz) approached by 5 and 25 Hz.
F_FULL = (5.0, 10.0, 12.0, 13.5, 14.5, 15.25, 16.0, 18.5, 25.0)
#: The range of the earlier, single-bed scan: the fit is repeated on it to see what widening did.
F_NARROW = (8.0, 23.0)
#: Primary damping [N s/m] of the full mode: the thesis' two values (figs. 3.6–3.8).
C_VALUES = (7.6, 26.3)
FIG36_LZ = (0.057, 0.1225, 0.372)
#: Heights of the thesis' fig. 3.9 on this grid (band plots and impact phase near resonance).
FIG39_LZ = (0.042, 0.057, 0.087, 0.1095, 0.1225, 0.147, 0.162)
THESIS_OPTIMUM = 0.1225  # [m]
#: The weighting the thesis describes (largest amplitudes dominate), named in every verdict.
THESIS_WEIGHTING = "absolute"
OPT = f"max_C_ef_{THESIS_WEIGHTING}"  # the thesis' optimum: largest C_ef of its fit


def settings(quick: bool) -> dict:
    if quick:
        return dict(lz=(0.057, 0.1225, 0.372), freqs=(12.0, 14.5, 15.25, 18.0), C=(7.6,),
                    duration=0.4, settle=0.15, R=2)
    return dict(lz=LZ_FULL, freqs=F_FULL, C=C_VALUES, duration=2.5, settle=0.3, R=3)


def _pm(x, spec: str) -> str:
    """Mean ± SE of the replicates' finite values (:func:`scaffold.across`), both ``spec``."""
    e = scaffold.across(x)
    return scaffold.pm(e.mean, e.se, spec, spec)


def _fit(fi, k: str, spec: str, scale: float = 1.0) -> str:
    """A fit's ``k``_ef (``k``: ``"M"``, ``"C"``) ± its SE over the replicates, ÷ ``scale``."""
    return scaffold.pm(fi[f"{k}_ef"] / scale, fi[f"se_{k}"] / scale, spec, spec)


def analyse(res, cfg, s) -> dict:
    """Fits of both weightings, resonances and optima per replicate; see the module doc."""
    f = np.asarray(res.axes["frequency"], float)
    lz = np.asarray(res.axes["box.Lz"], float)
    Zr, fallback = steady_or_window(res, "amplitude")  # (F, L, R)
    p, m_p = cfg.primary, grain_mass(cfg)
    fits = {w: fit_frf_scan(f, Zr, p, w) for w in RESIDUALS}
    f_peak, Z_peak = resonances(f, Zr)  # (L, R)
    C_reps = {w: np.array([fi["C_reps"] for fi in fits[w]]) for w in RESIDUALS}  # (L, R)
    optimum = {f"max_C_ef_{w}": _optimum_row(replicate_extrema(lz, C_reps[w], "max", True), lz)
               for w in RESIDUALS}
    optimum["min_peak"] = _optimum_row(replicate_extrema(lz, Z_peak, "min", True, True), lz)
    # the same vertices with the parabola in Lz itself: how much the interpolation model moves
    # them (a systematic error the replicates' interval does not contain)
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
    narrow = (f >= F_NARROW[0]) & (f <= F_NARROW[1])
    widen = {}
    for w in () if narrow.all() else RESIDUALS:
        pairs = list(zip(fits[w], fit_frf_scan(f[narrow], Zr[narrow], p, w)))
        widen[w] = {f"d{k}": [scaffold.across(a[f"{k}_reps"] - b[f"{k}_reps"])
                              for a, b in pairs] for k in ("M", "C")}
    stationary = np.asarray(res.steady["amplitude"]["stationary"], bool)
    starts = np.asarray(res.steady["amplitude"]["start"], float)
    force = force_coefficients(res, np.where(stationary, starts, s["duration"] / 2))
    return dict(Zr=Zr, fallback=fallback, fits=fits, f_peak=f_peak, Z_peak=Z_peak,
                stationary_by_lz=stationary.sum(axis=(0, 2)),  # (L,) of F x R runs each
                optimum=optimum, tests=tests, widen=widen, m_p=m_p, force=force,
                # per height, the frequency sample nearest its mean resonance
                near=[int(np.argmin(np.abs(f - np.mean(f_peak[j])))) for j in range(len(lz))],
                stationary=int(stationary.sum()), runs=int(stationary.size),
                start_range=(float(np.nanmin(starts)), float(np.nanmax(starts)))
                if stationary.any() else (math.nan, math.nan))


def force_coefficients(res, t0) -> dict:
    """Per run, the grains' force on the box as added mass, damping and impact phase
    (:func:`jaxdamp.analysis.response.grain_force_coefficients`) from ``t0`` [s] on (its
    detected steady state; the second half of the run where none was detected): arrays
    ``(F, L, R)`` like ``t0``."""
    f = np.asarray(res.axes["frequency"], float)
    rec, out = res.records, {k: np.full(t0.shape, np.nan) for k in ("m_add", "c_add", "phase")}
    for i, j, r in np.ndindex(t0.shape):
        row = res.point(i * t0.shape[1] + j, r)
        c = response.grain_force_coefficients(rec["t"][row], rec["z_box"][row],
                                              rec["force_box"][row], f[i], t_start=t0[i, j, r])
        for k in out:
            out[k][i, j, r] = c[k]
    return out


def _optimum_row(e, lz) -> dict:
    """An optimum of :func:`replicate_extrema` as stored: the replicates' vertices and best
    grid heights, mean, SE, 95 % half-width, and whether that interval holds the thesis'."""
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
        ci = lambda o: scaffold.pm(o["mean"], o["ci95"], ".4f", ".4f", unit="m")  # noqa: E731
        log(f"C = {C}: optimum (largest C_ef, {THESIS_WEIGHTING} fit) {ci(r['optimum'][OPT])}; "
            f"smallest peak {ci(r['optimum']['min_peak'])}; {r['stationary']}/{r['runs']} runs "
            "stationary")
    return results, lambda path, prov: write(results, s, path, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(results, s, out, prov):
    prov = dict(prov, sweep_wall_s=sum(float(r["res"].summary["wall_time"])
                                       for r in results.values()))
    with scaffold.data_file(out, prov, settings=json.dumps(s),
                            thesis_weighting=THESIS_WEIGHTING) as h:
        for C, r in results.items():
            g = h.create_group(f"C_{C:g}")
            g.attrs.update(base_config=r["cfg"].to_json(), optimum=json.dumps(r["optimum"]),
                           tests=json.dumps(r["tests"]), grain_mass=r["m_p"],
                           stationary=r["stationary"], runs=r["runs"], fallback=r["fallback"])
            for k, v in r["res"].axes.items():
                g.create_dataset(f"axes/{k}", data=np.asarray(v, float)).attrs["units"] = (
                    "Hz" if k == "frequency" else "m")
            g.create_dataset("amplitude", data=r["Zr"]).attrs.update(
                units="m", dims="frequency, box.Lz, replicate",
                what="steady mean over the MSER-detected steady state")
            g.create_dataset("f_peak", data=r["f_peak"]).attrs["units"] = "Hz"
            g.create_dataset("Z_peak", data=r["Z_peak"]).attrs["units"] = "m"
            for w in RESIDUALS:
                for k, unit in (("M", "kg"), ("C", "N s/m")):
                    for q in (f"{k}_reps", f"{k}_ef", f"se_{k}"):
                        g.create_dataset(f"fit_{w}/{q}", data=np.array(
                            [fi[q] for fi in r["fits"][w]])).attrs["units"] = unit
            for k, u in (("m_add", "kg"), ("c_add", "N s/m"), ("phase", "rad")):
                g.create_dataset(f"force/{k}", data=r["force"][k]).attrs.update(
                    units=u, dims="frequency, box.Lz, replicate",
                    what="first harmonic of the grains' force on the box against the box "
                         "motion over the steady state")
            for k, v in r["res"].summary.items():
                if np.ndim(v):
                    g.create_dataset(f"summary/{k}", data=v)
    _figures(out, results, s)
    _figure_3_9(out, results, s)
    _summary(out, results, s, prov)


def _fit_bars(ax, lz, fits, k: str, scale: float = 1.0, **kwargs):
    """The fits' ``k``_ef (``"M"``, ``"C"``) ± 2 SE over the replicates versus ``lz``,
    ÷ ``scale``."""
    return ax.errorbar(lz, np.array([fi[f"{k}_ef"] for fi in fits]) / scale,
                       yerr=2 * np.array([fi[f"se_{k}"] for fi in fits]) / scale, **kwargs)


def _figures(out, results, s):
    from jaxdamp.figures import frf_figure
    from jaxdamp.figures.response import draw_interval

    C0, lz = s["C"][0], list(s["lz"])
    r = results[C0]
    p = r["cfg"].primary
    cols = [lz.index(L) for L in FIG36_LZ if L in lz]
    Zr, fw = r["Zr"][:, cols], r["fits"][THESIS_WEIGHTING]
    scaffold.save_figure(frf_figure(
        np.asarray(r["res"].axes["frequency"], float), Zr.mean(axis=-1), [lz[j] for j in cols],
        p, r["m_p"], [(fw[j]["M_ef"], fw[j]["C_ef"]) for j in cols],
        Z_se=scaffold.standard_error(Zr),
        title=f"sanchez2012-optimal, C = {C0} N s/m, mean of R = {s['R']} beds ± 2 SE; dotted: "
        f"{THESIS_WEIGHTING}-residual 1-DOF fits (thesis fig. 3.6)"), out, "fig3_6.png")

    fig, (a1, a2) = scaffold.subplots(2, 1, figsize=(7.5, 7.5), sharex=True)
    for C, rc in results.items():
        for w, ls in zip(RESIDUALS, ("-", "--")):
            kw = dict(fmt="o", ls=ls, capsize=3, ms=4, label=f"C = {C} N s/m, {w} residuals")
            _fit_bars(a1, lz, rc["fits"][w], "C", C, **kw)
            _fit_bars(a2, lz, rc["fits"][w], "M", **kw)
        o = rc["optimum"][OPT]
        draw_interval(a1, o["mean"], o["ci95"], alpha=0.12, color=a1.lines[-1].get_color())
    a1.axhline(1, color="0.5", lw=0.8)
    a1.set_ylabel("C_ef / C  [-]")
    a1.set_title(f"effective damping and mass from the FRF fit, mean of R = {s['R']} beds ± 2 SE "
                 "(thesis figs. 3.7, 3.8); band: 95 % interval of the optimum", fontsize=8)
    a2.axhline(r["cfg"].primary.M, color="r", lw=0.8, ls="--", label="M")
    a2.axhline(r["cfg"].primary.M + r["m_p"], color="r", lw=0.8, ls=":", label="M + m_p")
    a2.set(ylabel="M_ef [kg]", xlabel="box height Lz [m]")
    for a in (a1, a2):
        a.set_xscale("log")
        a.axvline(THESIS_OPTIMUM, color="g", lw=0.6, ls="-.", label="thesis optimum, 0.1225 m")
        a.legend(fontsize=6)
    scaffold.save_figure(fig, out, "fig3_7_3_8.png")


def _figure_3_9(out, results, s):
    """Bed band and grain force against the box motion at the heights of the thesis' fig. 3.9
    (the frequency nearest each height's resonance, bed 0, the last three periods), and the
    impact phase and force-derived effective mass versus Lz."""
    from jaxdamp.figures import figure
    from jaxdamp.figures.response import draw_replicates, draw_run_band

    C0, lz = s["C"][0], list(s["lz"])
    r = results[C0]
    res, near, f = r["res"], r["near"], np.asarray(r["res"].axes["frequency"], float)
    show = [L for L in FIG39_LZ if L in lz]
    ncol = max(len(show), 4)
    fig = figure((2.3 * ncol, 7.5))
    gs = fig.add_gridspec(2, ncol, height_ratios=[1.2, 1])
    for c, (L, j) in enumerate((L, lz.index(L)) for L in show):
        i, ax = near[j], fig.add_subplot(gs[0, c])
        run = {k: v[res.point(i * len(lz) + j, 0)] for k, v in res.records.items()}
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
    at = (near, np.arange(len(lz)))  # per height, its frequency nearest the resonance
    a1, a2 = fig.add_subplot(gs[1, : ncol // 2]), fig.add_subplot(gs[1, ncol // 2:])
    draw_replicates(a1, lz, np.degrees(r["force"]["phase"][at]))
    a1.axhline(0, color="0.6", lw=0.6)
    a1.axhline(-90, color="0.6", lw=0.6, ls=":")
    a1.set_ylabel("impact phase arg(F̂/Ẑ) [deg]")
    a1.set_title("phase of the grains' force against the box motion, near resonance "
                 "(0°: mass, −90°: damper)", fontsize=8)
    draw_replicates(a2, lz, r["cfg"].primary.M + r["force"]["m_add"][at],
                    label="M + m_add from the force phase")
    _fit_bars(a2, lz, r["fits"][THESIS_WEIGHTING], "M", fmt="s--", capsize=3,
              label=f"M_ef from the FRF fit ({THESIS_WEIGHTING})")
    a2.axhline(r["cfg"].primary.M, color="r", lw=0.8, ls="--", label="M")
    a2.axhline(r["cfg"].primary.M + r["m_p"], color="r", lw=0.8, ls=":", label="M + m_p")
    a2.set_ylabel("effective mass [kg]")
    a2.legend(fontsize=7)
    for a in (a1, a2):
        a.set(xscale="log", xlabel="box height Lz [m]")
    fig.suptitle(f"thesis fig. 3.9: C = {C0} N s/m, mean of R = {s['R']} beds ± 2 SE", fontsize=9)
    scaffold.save_figure(fig, out, "fig3_9.png", dpi=110)


def _fmt_opt(o) -> str:
    verdict = ("cannot judge (fewer than 2 finite vertices)" if o["contains_thesis"] is None
               else "contains" if o["contains_thesis"] else "excludes")
    return (f"{scaffold.pm(o['mean'], o['se'], '.4f', '.4f', unit='m')} (95 %: ± {o['ci95']:.4f}; "
            f"replicates' vertices {', '.join(f'{x:.4f}' for x in o['vertices'])}; "
            "best grid heights "
            f"{', '.join(f'{x:g}' for x in o['grid_best'])}) — {verdict} the thesis' 0.1225 m")


def _summary(out, results, s, prov):
    r0, R = results[s["C"][0]], s["R"]
    p0 = r0["cfg"].primary
    lines = [
        "# Box-height scan with replicates: FRFs, effective mass and damping, the optimum "
        "(thesis figs. 3.6–3.8)", "",
        scaffold.provenance_line(prov, prov["sweep_wall_s"]) + " Native engine. Data `data.h5`; "
        "figures `fig3_6.png`, `fig3_7_3_8.png`.", "",
        f"**Runs.** `sanchez2012-optimal` (N = 250, E = 2.03e9 via stiffness_scale 0.01), "
        f"{len(s['freqs'])} frequencies {min(s['freqs'])}–{max(s['freqs'])} Hz × {len(s['lz'])} "
        f"heights × **R = {R} independently poured beds** (seeds 0…{R - 1}), {s['duration']} s "
        f"simulated per run after settling (thesis: 13.12 s). Settled bed heights: "
        + ", ".join(f"{x:.6f}" for x in r0["bed_heights"])
        + f" m (mean {scaffold.pm(*scaffold.mean_se(r0['bed_heights']), '.6f', '.6f')} m, SE; "
        "thesis ≈ 0.039 m).", "",
        "**Stationarity.** The amplitude of a run is its mean over the steady state detected by "
        "MSER on the per-period amplitude and dissipation, not a fixed window. "
        + "; ".join(f"C = {C}: {r['stationary']} of {r['runs']} runs stationary (steady from "
                    f"t = {r['start_range'][0]:.2f}–{r['start_range'][1]:.2f} s), "
                    f"{r['fallback']} fell back to the final 10 %" for C, r in results.items())
        + ".", "",
        "**Uncertainty.** Each replicate's FRF is fitted on its own (U, K fixed); M_ef, C_ef are "
        f"means over the R = {R} fits ± their standard error s/√R; comparisons are Student-t at "
        f"95 % with {R - 1} degrees of freedom (t = {t_quantile(0.975, max(R - 1, 1)):.2f}).", "",
        "**Weighting.** Both residual weightings are reported: `absolute` ((Z_model − Z)/U, "
        "dominated by the largest amplitudes — **the fit the thesis describes**) and `relative` "
        "(Z_model/Z − 1). Verdicts name the weighting they depend on.", "",
        f"Reference masses: M = {p0.M} kg, M + m_p = {p0.M + r0['m_p']:.4f} kg.", "",
    ]
    fq = np.asarray(r0["res"].axes["frequency"], float)
    for C, r in results.items():
        fa, fr, o, fo, p = (r["fits"]["absolute"], r["fits"]["relative"], r["optimum"],
                            r["force"], r["cfg"].primary)
        lines += [f"## C = {C} N s/m", ""] + scaffold.table(
            ["Lz [m]", "M_ef abs. [kg]", "C_ef/C abs.", "M_ef rel. [kg]", "C_ef/C rel.",
             "resonance [Hz]", "peak Z/U", "stationary runs"],
            [[L, _fit(fa[j], "M", ".3f"), _fit(fa[j], "C", ".2f", C), _fit(fr[j], "M", ".3f"),
              _fit(fr[j], "C", ".2f", C), _pm(r["f_peak"][j], ".2f"),
              _pm(r["Z_peak"][j] / p0.U, ".2f"),
              f"{int(r['stationary_by_lz'][j])} of {len(s['freqs']) * R}"]
             for j, L in enumerate(s["lz"])])
        lines += ["", "± = standard error over the replicates.", "",
                  "**The optimum (parabola in log Lz per replicate, mean ± SE, t-interval):**", ""]
        lines += [f"- largest C_ef, {w} residuals" + " (the thesis' fit)" * (w == THESIS_WEIGHTING)
                  + f": {_fmt_opt(o[f'max_C_ef_{w}'])}." for w in RESIDUALS]
        lines += [f"- smallest resonant amplitude (no fit): {_fmt_opt(o['min_peak'])}.",
                  f"- the interval is the beds' spread only. The interpolation is a model too: "
                  f"the same parabolas in Lz instead of log Lz put the vertices at "
                  f"{o['model_check'][OPT]:.4f} m (largest C_ef, {THESIS_WEIGHTING}) and "
                  f"{o['model_check']['min_peak']:.4f} m (smallest peak); a difference of that "
                  "size between the two is a systematic error of the grid, not covered by the "
                  "interval.", "",
                  "**Effective mass against M and M + m_p** (95 % t-test per height):", ""]
        for w in RESIDUALS:
            t = r["tests"][w]
            below, above = (", ".join(f"{L:g} ({z:+.1f} SE)" for L, z in t[k]) or "none"
                            for k in ("below_M", "above_Mmp"))
            cross = ", ".join(f"{x:.4f}" for x in t["crossings"]) or "none"
            lines.append(f"- {w} residuals: M_ef significantly below M at Lz = {below}; above "
                         f"M + m_p at Lz = {above}; the mean M_ef(Lz) crosses M at {cross} m.")
        lines += ["", "**Mechanism (thesis fig. 3.9, `fig3_9.png`).** The grains' force on the box "
                  "against the box motion, first harmonics over the steady state, at the "
                  "frequency nearest each height's resonance: impact phase φ = arg(F̂/Ẑ) "
                  "(0°: the grains act as a mass, −90°: as a damper), and the effective mass "
                  "M + m_add and damping C + c_add measured without a fit (mean ± SE over the "
                  f"beds), beside the {THESIS_WEIGHTING}-residual fit:", ""]
        fw = r["fits"][THESIS_WEIGHTING]
        lines += scaffold.table(
            ["Lz [m]", "f [Hz]", "φ [deg]", "M + m_add [kg]", "M_ef fit [kg]",
             "C + c_add [N s/m]", "C_ef fit [N s/m]"],
            [[L, f"{fq[i]:g}", _pm(np.degrees(fo["phase"][i, j]), ".0f"),
              _pm(p.M + fo["m_add"][i, j], ".3f"), _fit(fw[j], "M", ".3f"),
              _pm(p.C + fo["c_add"][i, j], ".1f"), _fit(fw[j], "C", ".1f")]
             for j, (L, i) in enumerate(zip(s["lz"], r["near"]))])
        if r["widen"]:
            lines += ["", f"**Widened range.** Refitting on {F_NARROW[0]:g}–{F_NARROW[1]:g} Hz "
                      "only (the earlier scan's range) changes the fits by (full − narrow, "
                      "paired per replicate, mean ± SE; * = significant at 95 %):", ""]
            star = lambda e: "*" * bool(np.isfinite(e.ci95) and abs(e.mean) > e.ci95)  # noqa: E731
            lines += [f"- {w}: " + "; ".join(
                f"{L:g}: ΔM {m.mean:+.3f}{star(m)} kg, ΔC {c.mean:+.2f}{star(c)}"
                for L, m, c in zip(s["lz"], r["widen"][w]["dM"], r["widen"][w]["dC"])) + "."
                for w in RESIDUALS]
        lines.append("")
    scaffold.write_summary(out, lines)


if __name__ == "__main__":
    main()
