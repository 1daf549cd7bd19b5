"""Nonlinear dynamics of the bed along the FRF of the thesis' optimal damper (fig. 4.1, ch. 4).

    python experiments/bed_dynamics.py            # full mode (see summary.md for its wall time)
    python experiments/bed_dynamics.py --quick    # < 1 min: 3 frequencies, 1.6 s each

``sanchez2012-optimal`` (N = 250, Lz = 0.1225 m, C = 7.6 N s/m) driven at every frequency of
the list in one batched sweep (:func:`jaxdamp.studies.sweep.sweep`, samples every 1 ms). For
each frequency, after a transient, the bed's centre of mass is classified
(:func:`jaxdamp.analysis.dynamics.classify`: periodic-k from the stroboscopic section, else Kantz's
largest Lyapunov exponent and the spectrum decide between quasi-periodic and chaotic). The
observable is the lab-frame ``z_cm`` (the thesis' "trayectoria del centro de masa", fig. 4.2);
``z_cm - z_box`` (the bed relative to its box) is classified too as a cross-check: in S1 the box
position is itself a state variable of the same deterministic system, so both observables
should give the same regime; where they do not, the steady part is too short or the verdict is
marginal. At 5.5, 8, 13, 14.5 and 21 Hz (thesis figs. 4.2–4.7) the full toolbox: Poincaré
section ``(z_cm, v_cm)``, spectrum with the drive's harmonics, mutual-information delay,
false-nearest-neighbour dimension, Kantz curve ``S(Δn)``.

Writes, in ``--out``: ``data.h5`` (base and per-point configurations as JSON, the sweep
summary, the classification per frequency and signal, the detail curves and the steady series
of the five detail frequencies), ``fig4_1.png`` (FRF coloured by regime, Lyapunov exponents),
``fig_details.png`` (per detail frequency: band plot, section, spectrum, embedding, Kantz
curve), and ``summary.md``. The raw sweep file (every time series; resumable after a kill)
goes to ``--out/raw/`` (not committed).
"""

from __future__ import annotations

import json
import os
import time
from collections import Counter

import h5py
import numpy as np

from jaxdamp.analysis import dynamics as dyn
from jaxdamp.analysis.impacts import force_states
from jaxdamp.analysis.response import frf_amplitude
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.figures.response import draw_band
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

#: Frequencies [Hz] of the full mode: the thesis' regions (periodic < 7.5, transition 7.5–11,
#: chaos I 11–14, window 14.5–16, chaos II > 16.5) each sampled, with the five detail ones.
F_FULL = (5.5, 7.0, 8.0, 9.5, 11.0, 12.0, 13.0, 14.0, 14.5, 15.5, 17.0, 21.0)
DETAIL = (5.5, 8.0, 13.0, 14.5, 21.0)
LABELS = ("periodic", "quasi-periodic", "chaotic", "undetermined")
COLORS = {"periodic": "tab:green", "quasi-periodic": "tab:orange", "chaotic": "tab:red",
          "undetermined": "0.55"}
#: thesis fig. 4.1 / ch. 4 regimes by frequency, for the comparison column
THESIS_ZONES = ((0.0, 7.5, "periodic"), (7.5, 11.0, "transition (quasi-periodic / periodic)"),
                (11.0, 14.5, "chaotic (zone I)"),
                (14.5, 16.0, "periodic window (2 impacts/period)"),
                (16.0, 16.5, "edge of window"), (16.5, 99.0, "chaotic (zone II)"))
#: per-observable numbers of the classification (``data.h5``: ``classification/<signal>/<key>``)
CLASS_KEYS = ("period", "exponent", "lyapunov_per_period", "line_fraction", "d1", "dmin",
              "k_loose", "dim", "delay", "peak_ratio", "stretch")
#: of these, the classifier's evidence (NaN where it has none: a periodic verdict)
EVIDENCE = {"lyapunov_per_period": "lyapunov_per_period", "line_fraction": "line_fraction",
            "peak_ratio": "strongest_peak_ratio", "stretch": "section_stretch"}
#: :func:`jaxdamp.analysis.impacts.force_states`' numbers (``data.h5``: ``contacts/<key>``)
CONTACT_KEYS = ("lid_hits_per_period", "floor_hits_per_period", "lid_contact_fraction",
                "floor_contact_fraction", "free_fraction")
#: the detail frequencies' steady series (``data.h5``: ``detail/f<f>/series/<key>``) -> record
SERIES = {"t": "t", "z": "z_cm", "v": "vz_cm", "z_box": "z_box", "z_lowest": "z_lowest",
          "z_highest": "z_highest", "force_box": "force_box"}


def settings(quick: bool):
    if quick:
        return dict(freqs=(5.5, 14.5, 21.0), detail=(5.5, 14.5, 21.0), duration=1.6,
                    transient=0.3, settle=0.15, record_dt=1e-3, R=2)
    # The primary's free oscillation decays as exp(-C t / 2(M + m_p)) = exp(-1.46 t) where the bed
    # rests (low f): after 4 s it is 3e-3 of its start, below the classifier's 1e-2 tolerance.
    # 10 s of steady state = 55 periods at 5.5 Hz, 130 at 13 Hz, 210 at 21 Hz. Cost: 12 x 14 s
    # = 168 system-seconds, ~3 s wall each on 2 free cores (~9 min).
    return dict(freqs=F_FULL, detail=DETAIL, duration=14.0, transient=4.0, settle=1.0,
                record_dt=1e-3, R=3)


def optimal_config(duration, settle, record_dt=1e-3, chunk=0.2):
    """``sanchez2012-optimal`` with a run's numerics (also ``bed_dynamics_long``'s)."""
    return apply_overrides(presets.get("sanchez2012-optimal"), {
        "numerics.duration": duration, "numerics.settle_time": settle,
        "numerics.record_dt": record_dt, "numerics.chunk": chunk})


def classify_one(res, s, i, f, r):
    """One frequency ``i`` and bed ``r``: regime of ``z_cm`` and ``z_cm - z_box`` (the
    classifier given the embedding of :func:`jaxdamp.analysis.dynamics.embedding_parameters`;
    ``k_loose``: the smallest k with ``d_k < 0.05``, the period at a looser section tolerance,
    0 if none) and the contact counts (:func:`jaxdamp.analysis.impacts.force_states`)."""
    rec, k = res.records, res.point(i, r)
    t = rec["t"][k]
    keep = t >= s["transient"]
    row = dict(frequency=float(f), replicate=r)
    for name, x in (("z_cm", rec["z_cm"][k]), ("z_rel", rec["z_cm"][k] - rec["z_box"][k])):
        t0 = time.perf_counter()
        dim, delay, _, _ = dyn.embedding_parameters(x[keep], f, t[1] - t[0])
        c = dyn.classify(t[keep], x[keep], f, embedding=(dim, delay))
        ev, d = c.evidence, c.evidence["return_distances"]
        row[name] = dict(label=c.label, period=c.period or 0,
                         exponent=np.nan if c.exponent is None else c.exponent,
                         d1=float(d[0]), dmin=float(np.min(d)),
                         k_loose=next((j + 1 for j, dj in enumerate(d) if dj < 0.05), 0),
                         dim=ev.get("dim", 0), delay=ev.get("delay", 0),
                         **{key: ev.get(e, np.nan) for key, e in EVIDENCE.items()},
                         seconds=time.perf_counter() - t0)
    row.update(force_states(t[keep], rec["force_box"][k][keep], res.weight, f))
    return row


def details(res, s):
    """Section, spectrum, MI delay, FNN and Kantz curve of ``z_cm`` at the detail frequencies."""
    rec, freqs, out = res.records, list(res.axes["frequency"]), {}
    for f in s["detail"]:
        i = res.point(freqs.index(f), 0)  # bed 0
        keep = rec["t"][i] >= s["transient"]
        d = {k: rec[name][i][keep] for k, name in SERIES.items()}
        t, z = d["t"], d["z"]
        dt = (t[-1] - t[0]) / (len(t) - 1)
        sec = dyn.poincare_section(t, z, f)
        dim, delay, mi, fnn = dyn.embedding_parameters(z, f, dt)
        lyap = dyn.lyapunov_kantz(z, dim, delay, dt=dt,
                                  theiler=max(int(round(1.0 / (f * dt))), dim * delay))
        out[f] = dict(d, sec_t=sec.t, sec_z=sec.x, spec=dyn.power_spectrum(t, z, f), mi=mi,
                      sec_v=dyn.poincare_section(t, d["v"], f).x,  # recorded v at sec_t
                      delay=delay, fnn=fnn, dim=dim, lyap=lyap)
    return out


def _reused_simulation_wall(raw: str, old: str, quick: bool):
    """The simulation wall time kept in ``old`` (the previous ``data.h5`` of the same mode)
    when its finished sweep ``raw`` is only read back now; None otherwise."""
    if not (os.path.exists(raw) and os.path.exists(old)):
        return None
    with h5py.File(raw, "r") as h, h5py.File(old, "r") as g:
        if (h.attrs.get("status") == "finished"
                and g.attrs.get("command", "").endswith("--quick") == quick):
            return float(g.attrs["wall_time_simulation"])
    return None


def compute(quick: bool, log, ctx):
    s = settings(quick)
    raw = ctx.raw(f"sweep_R{s['R']}.h5")
    t0 = time.perf_counter()
    reused = _reused_simulation_wall(raw, os.path.join(ctx.out, "data.h5"), quick)
    cfg = optimal_config(s["duration"], s["settle"], s["record_dt"])
    res = reuse_or_run(cfg, {"frequency": list(s["freqs"])}, raw, progress=ctx.progress,
                       replicates=s["R"])
    wall_sim = time.perf_counter() - t0 if reused is None else reused
    m_p = grain_mass(cfg)
    res.weight = m_p * cfg.gravity
    t1 = time.perf_counter()
    reps = [[classify_one(res, s, i, f, r) for r in range(res.replicates)]  # (frequency, bed)
            for i, f in enumerate(res.axes["frequency"])]
    det = details(res, s)
    wall_analysis = time.perf_counter() - t1
    walls = dict(total=wall_sim + wall_analysis, simulation=wall_sim, analysis=wall_analysis)
    result = dict(result=res, config=cfg, rows=[r[0] for r in reps],  # bed 0: figures, details
                  replicates=reps, details=det, settings=s, grain_mass=m_p)
    return result, lambda out, prov: write(result, walls, out, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(r, walls, out, prov):
    res, cfg, s, reps = r["result"], r["config"], r["settings"], r["replicates"]
    with scaffold.data_file(
            out, prov, base_config=cfg.to_json(),
            configs=json.dumps([c.to_json() for c in res.configs]),
            observable=("z_cm: lab-frame centre of mass of the bed (thesis' choice); "
                        "z_rel = z_cm - z_box: the bed relative to the box floor")) as h:
        h.attrs.update(grain_mass=r["grain_mass"], transient=s["transient"],
                       duration=s["duration"], replicates=res.replicates,
                       **{f"wall_time_{k}": v for k, v in walls.items()})
        h.create_dataset("axes/frequency", data=np.asarray(res.axes["frequency"], float)
                         ).attrs["units"] = "Hz"
        for k, v in res.summary.items():
            if np.ndim(v):
                h.create_dataset(f"summary/{k}", data=v)
        dims = "frequency, replicate"
        for k, v in res.replicate_summary.items():
            h.create_dataset(f"replicate_summary/{k}", data=v).attrs["dims"] = dims

        def grid(fn, dtype=float):  # (frequency, replicate) of one number per bed
            return np.array([[fn(x) for x in rr] for rr in reps], dtype)

        for sig in ("z_cm", "z_rel"):
            g = h.create_group(f"classification/{sig}")
            g.create_dataset("label", data=grid(lambda x: x[sig]["label"], "S16")
                             ).attrs["dims"] = dims
            for k in CLASS_KEYS:
                g.create_dataset(k, data=grid(lambda x: x[sig][k])).attrs.update(
                    units={"exponent": "1/s", "delay": "samples"}.get(k, "1"), dims=dims)
        for k in CONTACT_KEYS:
            h.create_dataset(f"contacts/{k}", data=grid(lambda x: x[k])).attrs["dims"] = dims
        for f, d in r["details"].items():
            g = h.create_group(f"detail/f{f:g}")
            g.attrs["frequency"] = f
            for k in SERIES:
                g.create_dataset(f"series/{k}", data=np.asarray(d[k], np.float32),
                                 compression="gzip")
            for k, v in (("section/t", d["sec_t"]), ("section/z_cm", d["sec_z"]),
                         ("section/vz_cm", d["sec_v"]), ("spectrum/f", d["spec"].f)):
                g.create_dataset(k, data=v)
            g.create_dataset("spectrum/psd", data=d["spec"].psd).attrs["method"] = d["spec"].method
            g.create_dataset("mutual_information", data=d["mi"]).attrs["delay"] = d["delay"]
            g.create_dataset("fnn_fraction", data=d["fnn"]).attrs["dim"] = d["dim"]
            ly = d["lyap"]
            g.create_dataset("kantz/S", data=ly.S).attrs.update(
                exponent=ly.exponent, fit_range=list(ly.fit_range), dt=ly.dt, epsilon=ly.epsilon,
                theiler=ly.theiler, dim=ly.dim, delay=ly.delay)
    _figures(out, r)
    _summary(out, r, walls, prov)


def _figures(out, r):
    res, cfg, rows, det, m_p = (r[k] for k in ("result", "config", "rows", "details",
                                               "grain_mass"))
    p = cfg.primary
    f = np.asarray(res.axes["frequency"], float)
    Z = res.summary["amplitude"]
    ff = np.linspace(min(f.min(), 4.0) * 0.9, max(f.max(), 24.0) * 1.02, 500)
    fig, ax = scaffold.subplots(figsize=(8.5, 5))
    for M, ls, lab in ((p.M, "-", f"no grains, M = {p.M} kg"),
                       (p.M + m_p, "--", f"rigid grains, M + m_p = {p.M + m_p:.3f} kg")):
        ax.plot(ff, frf_amplitude(ff, M, p.K, p.C, p.U) / p.U, ls, color="tab:blue", lw=0.9,
                label=lab)
    for lo, hi, lab in THESIS_ZONES:  # thesis fig. 4.1 shading
        if "chaotic" in lab:
            ax.axvspan(lo, min(hi, ff[-1]), color="0.88", zorder=0)
        elif "transition" in lab:
            ax.axvspan(lo, hi, color="0.72", zorder=0)
    ax.plot(f, Z / p.U, "-", color="0.3", lw=0.8, zorder=2)
    for lab in LABELS:
        m = np.array([r["z_cm"]["label"] == lab for r in rows])
        if m.any():
            ax.scatter(f[m], Z[m] / p.U, s=60, color=COLORS[lab], edgecolor="k", zorder=3,
                       label=f"DEM, z_cm {lab}")
    for fi, zi, r in zip(f, Z, rows):
        c = r["z_cm"]
        txt = (f"P{c['period']}" if c["label"] == "periodic" else "") + (
            "*" if r["z_rel"]["label"] != c["label"] else "")
        if txt:
            ax.annotate(txt, (fi, zi / p.U), textcoords="offset points", xytext=(4, 6), fontsize=7)
    ax.set(yscale="log", xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U")
    ax2 = ax.twinx()
    lam = np.array([r["z_cm"]["exponent"] for r in rows])
    ch = np.array([r["z_cm"]["label"] in ("chaotic", "undetermined") for r in rows])
    ax2.plot(f[ch], lam[ch], "D", color="tab:green", mfc="none", ms=7,
             label="largest Lyapunov exponent λ (non-periodic points)")
    ax2.set_ylabel("λ [1/s]")
    ax2.set_ylim(bottom=min(0.0, np.nanmin(lam[ch]) if ch.any() else 0.0))
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    ax.set_title("sanchez2012-optimal (Lz = 0.1225 m, C = 7.6 N s/m): regime of the bed's "
                 "centre of mass\ngrey: thesis fig. 4.1 zones (dark: transition, light: chaos); "
                 "P-k: period k; *: z_cm − z_box disagrees", fontsize=8)
    scaffold.save_figure(fig, out, "fig4_1.png", dpi=120)

    fig, axs = scaffold.subplots(len(det), 5, figsize=(20, 3.3 * len(det)), squeeze=False)
    row_of = {r["frequency"]: r for r in rows}
    mm = 1e3
    for a, (fq, d) in zip(axs, det.items()):
        r = row_of[fq]["z_cm"]
        w = d["t"] >= d["t"][-1] - 4.0 / fq
        draw_band(a[0], *(d[k][w] for k in ("t", "z_box", "z_lowest", "z_highest", "z")),
                  cfg.box.Lz)
        a[0].set_ylabel(f"f = {fq:g} Hz\nz [mm]")
        a[0].set_title("floor, lid, grain band, z_cm (last 4 periods)", fontsize=8)
        a[1].plot(d["z"] * mm, d["v"], "-", color="0.85", lw=0.3)
        a[1].scatter(d["sec_z"] * mm, d["sec_v"], c=d["sec_t"], s=8, cmap="viridis", zorder=3)
        a[1].set_title(f"Poincaré section ({len(d['sec_t'])} periods): "
                       f"{r['label']}{' P' + str(r['period']) if r['period'] else ''}", fontsize=8)
        a[1].set(xlabel="z_cm [mm]", ylabel="v_cm [m/s]")
        sp = d["spec"]
        band = sp.f <= 6 * fq
        a[2].semilogy(sp.f[band], sp.psd[band], "-", lw=0.8)
        for lab, fl, _ in sp.lines:
            if fl <= 6 * fq:
                a[2].axvline(fl, color="tab:red" if "/" not in lab else "tab:purple", lw=0.5,
                             ls=":" if "/" in lab else "-", alpha=0.6)
        a[2].set_title("PSD of z_cm (red: n f, purple dotted: f/2, f/3, ...)", fontsize=8)
        a[2].set_xlabel("frequency [Hz]")
        tau = d["delay"]
        a[3].plot(d["z"][:-tau] * mm, d["z"][tau:] * mm, "-", lw=0.2, color="tab:blue")
        a[3].set(xlabel="z_cm(t) [mm]", ylabel="z_cm(t + τ) [mm]")
        a[3].set_title(f"delay embedding: τ = {tau} ms (MI), FNN dim = {d['dim']}", fontsize=8)
        ly = d["lyap"]
        a[4].plot(ly.time, ly.S, "-", lw=1)
        tt = ly.time[ly.fit_range[0]:ly.fit_range[1] + 1]
        a[4].plot(tt, ly.intercept + ly.exponent * tt, "r--", lw=1.2)
        a[4].set(xlabel="Δt [s]", ylabel="S(Δt)")
        a[4].set_title(f"Kantz: slope λ = {ly.exponent:.3g} 1/s (λ/f = {ly.exponent / fq:.3g})",
                       fontsize=8)
        for x in a:
            x.grid(alpha=0.3)
            x.tick_params(labelsize=7)
    scaffold.save_figure(fig, out, "fig_details.png", dpi=90)


def regime(c: dict) -> str:
    """``periodic-k`` or the classifier's label of one bed and observable (``label``,
    ``period``: 0 unless periodic)."""
    return f"periodic-{c['period']}" if c["label"] == "periodic" else c["label"]


def tally(items, ones: bool = False) -> str:
    """The distinct ``items`` by count, most common first: ``periodic-1 ×2, chaotic`` (with
    ``ones``: ``chaotic ×1``)."""
    return ", ".join(f"{k} ×{v}" if v > 1 or ones else k for k, v in Counter(items).most_common())


def _over_beds(x, fmt):
    """Mean ± SE over the beds' finite values (the value alone for one bed, — for none)."""
    e = scaffold.across(x)
    return "—" if e.n == 0 else scaffold.pm(e.mean, e.se, fmt, ".2g")


def _summary(out, r, walls, prov):
    res, cfg, s, reps, det = (r[k] for k in ("result", "config", "settings", "replicates",
                                             "details"))
    p = cfg.primary
    f = np.asarray(res.axes["frequency"], float)
    R = res.replicates
    Zr = np.asarray(res.replicate_summary["amplitude"])  # (F, R)
    duration = float(res.records["t"][0][-1])  # whole chunks: may exceed s["duration"]
    steady = duration - s["transient"]
    st = res.steady["amplitude"]
    stationary = np.asarray(st["stationary"], bool)
    late = int(np.sum(stationary & (np.asarray(st["start"], float) > s["transient"])))
    lines = [
        "# Bed dynamics along the FRF of the optimal damper (thesis fig. 4.1, ch. 4)", "",
        f"Command: `{prov['command']}` — wall time {walls['total'] / 60:.1f} min on 2 cores "
        f"(simulation {walls['simulation'] / 60:.1f} min, analysis {walls['analysis']:.0f} s). "
        "Data: `data.h5`; figures: `fig4_1.png`, `fig_details.png` (bed 0).", "",
        f"Runs: `sanchez2012-optimal` (N = 250, Lz = {cfg.box.Lz} m, C = {p.C} N s/m, "
        f"U = {p.U} m, E = 2.03e9 via stiffness_scale 0.01), one batched sweep over "
        f"{len(f)} frequencies × **R = {R} independently poured beds** (seeds 0…{R - 1}), "
        f"{duration:g} s simulated per run after settling, samples every "
        f"{s['record_dt'] * 1e3:g} ms. The first {s['transient']} s are dropped as transient "
        f"(the thesis: ~5 s of 196.83 s); the classifier sees the remaining {steady:g} s, i.e. "
        f"{steady * f.min():.0f} drive periods at {f.min():g} Hz to {steady * f.max():.0f} at "
        f"{f.max():g} Hz (the thesis' series were 15× longer). Stationarity (MSER on the "
        f"per-period amplitude and dissipation): {int(stationary.sum())} of {stationary.size} "
        f"runs detected stationary, {late} of them only after the {s['transient']} s cut (their "
        "first steady periods are still classified). Amplitude Z: half peak-to-peak of the box "
        "over the final 10 % of each run, mean ± SE over the beds. Balance error (max): "
        f"{np.max(res.summary['balance_error']):.1e}.", "",
        "Observable: the lab-frame centre of mass `z_cm` of the bed (what the thesis analyses); "
        "`z_cm − z_box` (the bed in the box's frame) is classified as a cross-check — it is "
        "another observable of the same deterministic system (the box position is a state "
        "variable in S1), so the regimes should agree. Classifier: "
        "`jaxdamp.analysis.dynamics.classify` with its defaults (periodic-k if the stroboscopic "
        "return map repeats after k ≤ 8 periods within 1e-2 of the series' std; otherwise "
        "chaotic if λ/f > 0.02 and the harmonic-masked periodogram is broadband (< 90 % of the "
        "rest in 20 lines), quasi-periodic if λ/f ≤ 0.02 and line spectrum, undetermined if the "
        "two disagree). λ: Kantz, embedding passed to the classifier: delay from the first "
        "minimum of the mutual information of prominence ≥ 0.2 of its range (the plain first "
        "minimum is a spurious one-sample dip on these nearly sinusoidal series), dimension from "
        "false nearest neighbours (< 1 %); Theiler window one drive period. Every bed is "
        "classified on its own: a regime is a verdict of the beds, the table says how many "
        "agree.", "",
        "Contacts (from the interval-averaged force of the grains on the box, over the steady "
        "part): each sample is lid (F > +0.5 m_p g), floor (F < −0.5 m_p g) or free flight "
        "(|F| < 0.2 m_p g); an impact is an entry into lid or floor from another state (a bed "
        "that never leaves the floor has none).", "",
        "Columns (mean ± SE over the beds where numeric): d1 = median distance between section "
        "points one period apart (return map, relative to the series' std; < 0.01 is "
        "periodic-1); 'k at 0.05' = the period k each bed's section shows at a 5× looser "
        "tolerance (a noisy period-k), 0 if none; lines = fraction of the non-harmonic power in "
        "20 spectral lines.", ""]
    rows = []
    for i, (fi, rr) in enumerate(zip(f, reps)):
        a = [x["z_cm"] for x in rr]
        rows.append([
            f"{fi:g}", _over_beds(Zr[i] / p.U, ".2f"), tally(regime(x["z_cm"]) for x in rr),
            *(_over_beds([c[k] for c in a], fmt) for k, fmt in (
                ("exponent", ".3g"), ("lyapunov_per_period", ".3f"), ("d1", ".2g"))),
            ", ".join(str(c["k_loose"]) for c in a),
            _over_beds([c["line_fraction"] for c in a], ".2f"),
            tally(regime(x["z_rel"]) for x in rr),
            *(_over_beds([x[k] for x in rr], ".2f") for k in CONTACT_KEYS[:2]),
            next((lab for lo, hi, lab in THESIS_ZONES if lo <= fi < hi), "")])
    lines += scaffold.table(
        ["f [Hz]", "Z/U", "regime z_cm (beds)", "λ [1/s]", "λ/f", "d1", "k at 0.05", "lines",
         "regime z_cm−z_box (beds)", "lid hits/T", "floor hits/T", "thesis (fig. 4.1)"], rows)
    lines += ["", "Detail frequencies (z_cm): MI delay, FNN dimension, Kantz exponent from the "
              "curve in `fig_details.png` (the classifier's embedding; λ is computed for periodic "
              "points too, where it should be ≈ 0 or negative).", ""]
    lines += scaffold.table(
        ["f [Hz]", "section points", "MI delay [ms]", "FNN dim", "Kantz λ [1/s]", "fit range [s]"],
        [[f"{fq:g}", len(d["sec_t"]), f"{d['delay'] * s['record_dt'] * 1e3:.0f}", d["dim"],
          f"{ly.exponent:.3g}", f"{ly.time[ly.fit_range[0]]:.3f}–{ly.time[ly.fit_range[1]]:.3f}"]
         for fq, d, ly in ((fq, d, d["lyap"]) for fq, d in det.items())])
    lines += ["", "## Comparison with the thesis (SPEC §6), zone by zone", ""]
    want = {"periodic": ("periodic",), "chaotic": ("chaotic",),
            "transition": ("quasi-periodic", "periodic")}
    for lo, hi, zone in THESIS_ZONES:
        sel = [(fi, rr) for fi, rr in zip(f, reps) if lo <= fi < hi]
        if not sel:
            continue
        key = "periodic" if zone.startswith("periodic window") else next(
            (k for k in want if zone.startswith(k)), None)
        found = "; ".join(f"{fi:g} Hz {tally(regime(x['z_cm']) for x in rr)}" for fi, rr in sel)
        hits = [key is not None and x["z_cm"]["label"] in want[key] for _, rr in sel for x in rr]
        verdict = "agrees" if all(hits) else "partly agrees" if any(hits) else "differs"
        lines.append(f"- thesis {zone} ({lo:g}–{hi:g} Hz): {found} — {verdict} "
                     f"({sum(hits)} of {len(hits)} bed-frequencies).")
    lines += ["", "Caveats: the steady series are ~20× shorter than the thesis' (a weak exponent "
              "or a slow drift of a torus is hard to tell from a transient on 50–200 periods); "
              "the modulus is reduced 100× (collision outcomes kept, collisions 6.3× longer); the "
              "thesis' regime boundaries are read from its text (fig. 4.1 itself is an image), "
              "so a frequency next to a boundary may fall on either side. `undetermined` means "
              "the exponent and the spectrum disagree — reported as such, not forced into a "
              "class.", ""]
    scaffold.write_summary(out, lines)


if __name__ == "__main__":
    main()
