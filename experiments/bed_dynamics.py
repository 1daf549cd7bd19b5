"""Nonlinear dynamics of the bed along the FRF of the thesis' optimal damper (fig. 4.1, ch. 4).

    python experiments/bed_dynamics.py            # full mode (see summary.md for its wall time)
    python experiments/bed_dynamics.py --quick    # < 1 min: 3 frequencies, 1.6 s each

``sanchez2012-optimal`` at every frequency in one batched sweep of R independently poured beds.
After a transient, each bed's centre of mass ``z_cm`` (the thesis' observable) is classified
(:func:`jaxdamp.analysis.dynamics.classify`), and ``z_cm - z_box`` as a cross-check (the box is
a state variable of the same system: the regimes should agree). At the detail frequencies
(thesis figs. 4.2–4.7): section, spectrum, mutual-information delay, false-nearest-neighbour
dimension, Kantz curve. Writes ``data.h5``, ``fig4_1.png`` (FRF coloured by regime, Lyapunov
exponents), ``fig_details.png`` and ``summary.md``; the raw sweep (resumable) in ``--out/raw/``.
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
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures.response import draw_run_band
from jaxdamp.io.common import put
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

#: Frequencies [Hz] of the full mode: the thesis' regions (periodic < 7.5, transition 7.5–11,
#: chaos I 11–14, window 14.5–16, chaos II > 16.5) each sampled, with the five detail ones.
F_FULL = (5.5, 7.0, 8.0, 9.5, 11.0, 12.0, 13.0, 14.0, 14.5, 15.5, 17.0, 21.0)
DETAIL = (5.5, 8.0, 13.0, 14.5, 21.0)
COLORS = {"periodic": "tab:green", "quasi-periodic": "tab:orange", "chaotic": "tab:red",
          "undetermined": "0.55"}
#: thesis fig. 4.1 / ch. 4 regimes by frequency, for the comparison column
THESIS_ZONES = (
    (0.0, 7.5, "periodic"), (7.5, 11.0, "transition (quasi-periodic / periodic)"),
    (11.0, 14.5, "chaotic (zone I)"), (14.5, 16.0, "periodic window (2 impacts/period)"),
    (16.0, 16.5, "edge of window"), (16.5, 99.0, "chaotic (zone II)"))
#: per-observable numbers of the classification (``data.h5``: ``classification/<signal>/<key>``)
CLASS_KEYS = ("period", "exponent", "lyapunov_per_period", "line_fraction", "d1", "dmin",
              "k_loose", "dim", "delay", "peak_ratio", "stretch")
UNITS = {"exponent": "1/s", "delay": "samples"}  # of these; the others: 1
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
    # transient 4 s: the free decay exp(-C t / 2(M + m_p)) = exp(-1.46 t) is then 3e-3 (< 1e-2)
    return dict(freqs=F_FULL, detail=DETAIL, duration=14.0, transient=4.0, settle=1.0,
                record_dt=1e-3, R=3)


def optimal_config(duration, settle, record_dt=1e-3, chunk=0.2):
    """``sanchez2012-optimal`` with a run's numerics (also ``bed_dynamics_long``'s)."""
    return apply_overrides(presets.get("sanchez2012-optimal"), {
        "numerics.duration": duration, "numerics.settle_time": settle,
        "numerics.record_dt": record_dt, "numerics.chunk": chunk})


def classify_one(res, s, i, f, r):
    """Frequency ``i``, bed ``r``: regime of ``z_cm`` and ``z_cm - z_box`` (``k_loose``: the
    smallest k with ``d_k < 0.05``, 0 if none) and the contacts (:func:`force_states`)."""
    rec, k = res.records, res.point(i, r)
    t = rec["t"][k]
    keep = t >= s["transient"]
    row = dict(frequency=float(f), replicate=r)
    for name, x in (("z_cm", rec["z_cm"][k]), ("z_rel", rec["z_cm"][k] - rec["z_box"][k])):
        dim, delay, _, _ = dyn.embedding_parameters(x[keep], f, t[1] - t[0])
        c = dyn.classify(t[keep], x[keep], f, embedding=(dim, delay))
        ev, d = c.evidence, c.evidence["return_distances"]
        row[name] = dict(label=c.label, period=c.period or 0,
                         exponent=np.nan if c.exponent is None else c.exponent,
                         d1=float(d[0]), dmin=float(np.min(d)),
                         k_loose=next((j + 1 for j, dj in enumerate(d) if dj < 0.05), 0),
                         dim=ev.get("dim", 0), delay=ev.get("delay", 0),
                         **{key: ev.get(e, np.nan) for key, e in EVIDENCE.items()})
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
    """The simulation wall time in ``old`` (the last ``data.h5``) if ``raw`` is only read back."""
    if os.path.exists(raw) and os.path.exists(old):
        with h5py.File(raw, "r") as h, h5py.File(old, "r") as g:
            if (h.attrs.get("status") == "finished"
                    and g.attrs.get("command", "").endswith("--quick") == quick):
                return float(g.attrs["wall_time_simulation"])


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
    return result, lambda out, prov: record(result, walls, out, prov)


def record(r, walls, out, prov):
    res, cfg, s, reps = r["result"], r["config"], r["settings"], r["replicates"]
    st = res.steady["amplitude"]  # MSER on the per-period amplitude, per run
    stationary = np.asarray(st["stationary"], bool)
    with scaffold.data_file(
            out, prov, base_config=cfg.to_json(),
            configs=json.dumps([c.to_json() for c in res.configs]),
            observable=("z_cm: lab-frame centre of mass of the bed (thesis' choice); "
                        "z_rel = z_cm - z_box: the bed relative to the box floor")) as h:
        h.attrs.update(grain_mass=r["grain_mass"], transient=s["transient"],
                       duration=s["duration"], replicates=res.replicates,
                       stationary_runs=int(stationary.sum()),
                       stationary_late=int(np.sum(stationary & (np.asarray(st["start"], float)
                                                                > s["transient"]))),
                       **{f"wall_time_{k}": v for k, v in walls.items()})
        put(h, "axes/frequency", np.asarray(res.axes["frequency"], float), "Hz")
        for k, v in res.summary.items():
            if np.ndim(v):
                h.create_dataset(f"summary/{k}", data=v)
        dims = "frequency, replicate"
        for k, v in res.replicate_summary.items():
            put(h, f"replicate_summary/{k}", v, dims=dims)

        def grid(fn, dtype=float):  # (frequency, replicate) of one number per bed
            return np.array([[fn(x) for x in rr] for rr in reps], dtype)

        for sig in ("z_cm", "z_rel"):
            g = h.create_group(f"classification/{sig}")
            put(g, "label", grid(lambda x: x[sig]["label"], "S16"), dims=dims)
            for k in CLASS_KEYS:
                put(g, k, grid(lambda x: x[sig][k]), UNITS.get(k, "1"), dims=dims)
        for k in CONTACT_KEYS:
            put(h, f"contacts/{k}", grid(lambda x: x[k]), "1", dims=dims)
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


def regime(label: str, period) -> str:
    """``periodic-k`` or the classifier's label of one bed and observable."""
    return f"periodic-{int(period)}" if label == "periodic" else label


def tally(items, ones: bool = False) -> str:
    """The ``items`` by count, most common first: ``periodic-1 ×2, chaotic`` (``ones``: ``×1``)."""
    return ", ".join(f"{k} ×{v}" if v > 1 or ones else k for k, v in Counter(items).most_common())


def _over_beds(x, fmt):
    """Mean ± SE over the beds' finite values (the value alone for one bed, — for none)."""
    e = scaffold.across(x)
    return "—" if e.n == 0 else scaffold.pm(e.mean, e.se, fmt, ".2g")


def report(data, out):
    cfg, cls = from_dict(data.attrs["base_config"]), data["classification"]
    f = np.asarray(data["axes"]["frequency"], float)
    reg = {sig: [[regime(lab, k) for lab, k in zip(ls, ks)]  # (frequency, bed)
                 for ls, ks in zip(cls[sig]["label"], cls[sig]["period"])] for sig in cls}
    det = dict(sorted((g.attrs["frequency"], g) for g in data["detail"].values()))
    p, m_p, Z = cfg.primary, data.attrs["grain_mass"], data["summary"]["amplitude"]
    lab0 = cls["z_cm"]["label"][:, 0]  # bed 0
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
    for lab in [lab for lab in COLORS if lab in lab0]:
        ax.scatter(f[lab0 == lab], Z[lab0 == lab] / p.U, s=60, color=COLORS[lab], edgecolor="k",
                   zorder=3, label=f"DEM, z_cm {lab}")
    for fi, zi, lab, k, rel in zip(f, Z, lab0, cls["z_cm"]["period"][:, 0],
                                   cls["z_rel"]["label"][:, 0]):
        ax.annotate((f"P{int(k)}" if lab == "periodic" else "") + ("*" if rel != lab else ""),
                    (fi, zi / p.U), textcoords="offset points", xytext=(4, 6), fontsize=7)
    ax.set(yscale="log", xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U")
    ax2 = ax.twinx()
    lam = cls["z_cm"]["exponent"][:, 0]
    ch = np.isin(lab0, ("chaotic", "undetermined"))
    ax2.plot(f[ch], lam[ch], "D", color="tab:green", mfc="none", ms=7,
             label="largest Lyapunov exponent λ (non-periodic points)")
    ax2.set(ylabel="λ [1/s]", ylim=(min(0.0, np.nanmin(lam[ch]) if ch.any() else 0.0), None))
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    ax.set_title("sanchez2012-optimal (Lz = 0.1225 m, C = 7.6 N s/m): regime of the bed's "
                 "centre of mass\ngrey: thesis fig. 4.1 zones (dark: transition, light: chaos); "
                 "P-k: period k; *: z_cm − z_box disagrees", fontsize=8)
    scaffold.save_figure(fig, out, "fig4_1.png", dpi=120)

    fig, axs = scaffold.subplots(len(det), 5, figsize=(20, 3.3 * len(det)), squeeze=False)
    for a, (fq, g) in zip(axs, det.items()):
        i = int(np.flatnonzero(f == fq)[0])
        d, sec, sp = g["series"], g["section"], g["spectrum"]
        draw_run_band(a[0], dict(d, z_cm=d["z"]), cfg.box.Lz, fq, periods=4)
        a[0].set_ylabel(f"f = {fq:g} Hz\nz [mm]")
        a[0].set_title("floor, lid, grain band, z_cm (last 4 periods)", fontsize=8)
        a[1].plot(d["z"] * 1e3, d["v"], "-", color="0.85", lw=0.3)
        a[1].scatter(sec["z_cm"] * 1e3, sec["vz_cm"], c=sec["t"], s=8, cmap="viridis", zorder=3)
        a[1].set_title(f"Poincaré section ({len(sec['t'])} periods): {reg['z_cm'][i][0]}",
                       fontsize=8)
        a[1].set(xlabel="z_cm [mm]", ylabel="v_cm [m/s]")
        band = sp["f"] <= 6 * fq
        a[2].semilogy(sp["f"][band], sp["psd"][band], "-", lw=0.8)
        for fl in fq * np.arange(1, 7):  # the drive's lines, as power_spectrum lists them
            a[2].axvline(fl, color="tab:red", lw=0.5, alpha=0.6)
        for fl in fq * np.array([1 / 2, 1 / 3, 3 / 2, 2 / 3]):
            a[2].axvline(fl, color="tab:purple", lw=0.5, ls=":", alpha=0.6)
        a[2].set_title("PSD of z_cm (red: n f, purple dotted: f/2, f/3, ...)", fontsize=8)
        a[2].set_xlabel("frequency [Hz]")
        tau = g.meta["mutual_information"]["delay"]
        a[3].plot(d["z"][:-tau] * 1e3, d["z"][tau:] * 1e3, "-", lw=0.2, color="tab:blue")
        a[3].set(xlabel="z_cm(t) [mm]", ylabel="z_cm(t + τ) [mm]")
        a[3].set_title(f"delay embedding: τ = {tau} ms (MI), FNN dim = "
                       f"{g.meta['fnn_fraction']['dim']}", fontsize=8)
        ly, S = g["kantz"].meta["S"], g["kantz"]["S"]
        time = np.arange(len(S)) * ly["dt"]
        fit = slice(ly["fit_range"][0], ly["fit_range"][1] + 1)  # lyapunov_kantz's fitted line
        a[4].plot(time, S, "-", lw=1)
        a[4].plot(time[fit], np.polyval(np.polyfit(time[fit], S[fit], 1), time[fit]), "r--", lw=1.2)
        a[4].set(xlabel="Δt [s]", ylabel="S(Δt)")
        a[4].set_title(f"Kantz: slope λ = {ly['exponent']:.3g} 1/s "
                       f"(λ/f = {ly['exponent'] / fq:.3g})", fontsize=8)
        for x in a:
            x.grid(alpha=0.3)
            x.tick_params(labelsize=7)
    scaffold.save_figure(fig, out, "fig_details.png", dpi=90)
    _summary(out, data, cfg, f, reg, det)


def _summary(out, data, cfg, f, reg, det):
    a, p, cz, con = data.attrs, cfg.primary, data["classification"]["z_cm"], data["contacts"]
    R, Zr = a["replicates"], data["replicate_summary"]["amplitude"]  # (frequency, bed)
    duration = float(next(iter(det.values()))["series"]["t"][-1])  # whole chunks
    steady = duration - a["transient"]
    lines = [
        "# Bed dynamics along the FRF of the optimal damper (thesis fig. 4.1, ch. 4)", "",
        scaffold.provenance_line(a) + f" Simulation {a['wall_time_simulation'] / 60:.1f} min, "
        f"analysis {a['wall_time_analysis']:.0f} s. Figures `fig4_1.png`, `fig_details.png`.", "",
        f"`sanchez2012-optimal` (N = 250, Lz = {cfg.box.Lz} m, C = {p.C} N s/m, U = {p.U} m, "
        f"E = 2.03e9 via stiffness_scale 0.01), {len(f)} frequencies × **R = {R} independently "
        f"poured beds** (seeds 0…{R - 1}), {duration:g} s per run after settling, sampled "
        f"every {cfg.numerics.record_dt * 1e3:g} ms; the first {a['transient']} s are dropped "
        f"(the thesis: ~5 s of 196.83 s), leaving {steady:g} s = {steady * f.min():.0f} drive "
        f"periods at {f.min():g} Hz to {steady * f.max():.0f} at {f.max():g} Hz (the thesis: "
        f"15× longer). MSER finds {a['stationary_runs']} of {Zr.size} runs stationary, "
        f"{a['stationary_late']} only after the {a['transient']} s cut. Z: half peak-to-peak of "
        "the box over the last 10 % of a run. Balance error ≤ "
        f"{np.max(data['summary']['balance_error']):.1e}.", "",
        "Classifier: `classify`'s defaults (`undetermined`: exponent and spectrum disagree); "
        "λ: Kantz, delay at the first mutual-information minimum of prominence ≥ 0.2, FNN "
        "dimension, Theiler window one period. Impacts: entries into lid (F > +0.5 m_p g) or "
        "floor (F < −0.5 m_p g) contact. Columns: mean ± SE over the beds, regimes as counts "
        "of beds; d1 = median distance of section points one period apart over the series' std "
        "(< 0.01: periodic-1); 'k at 0.05' = each bed's period at a 5× looser tolerance (0: "
        "none); lines = fraction of the non-harmonic power in 20 spectral lines. Caveats: 50–200 "
        "periods hardly tell a weak exponent or a slow torus drift from a transient; the "
        "thesis' boundaries are read from its text.", ""]
    rows = [[f"{fi:g}", _over_beds(Zr[i] / p.U, ".2f"), tally(reg["z_cm"][i]),
             *(_over_beds(cz[k][i], fmt) for k, fmt in (
                 ("exponent", ".3g"), ("lyapunov_per_period", ".3f"), ("d1", ".2g"))),
             ", ".join(str(int(k)) for k in cz["k_loose"][i]),
             _over_beds(cz["line_fraction"][i], ".2f"), tally(reg["z_rel"][i]),
             *(_over_beds(con[k][i], ".2f") for k in CONTACT_KEYS[:2]),
             next((lab for lo, hi, lab in THESIS_ZONES if lo <= fi < hi), "")]
            for i, fi in enumerate(f)]
    lines += scaffold.table(
        ["f [Hz]", "Z/U", "regime z_cm (beds)", "λ [1/s]", "λ/f", "d1", "k at 0.05", "lines",
         "regime z_cm−z_box (beds)", "lid hits/T", "floor hits/T", "thesis (fig. 4.1)"], rows)
    lines += ["", "Detail frequencies (z_cm, bed 0; periodic points: λ ≈ 0 or negative):", ""]
    lines += scaffold.table(
        ["f [Hz]", "section points", "MI delay [ms]", "FNN dim", "Kantz λ [1/s]", "fit range [s]"],
        [[f"{fq:g}", len(g["section"]["t"]),
          f"{g.meta['mutual_information']['delay'] * cfg.numerics.record_dt * 1e3:.0f}",
          g.meta["fnn_fraction"]["dim"], f"{ly['exponent']:.3g}",
          "–".join(f"{i * ly['dt']:.3f}" for i in ly["fit_range"])]
         for fq, g, ly in ((fq, g, g["kantz"].meta["S"]) for fq, g in det.items())])
    lines += ["", "## Comparison with the thesis (SPEC §6), zone by zone", ""]
    want = {"periodic": ("periodic",), "chaotic": ("chaotic",),
            "transition": ("quasi-periodic", "periodic")}
    for lo, hi, zone in THESIS_ZONES:
        sel = [i for i, fi in enumerate(f) if lo <= fi < hi]
        ok = next((v for k, v in want.items() if zone.startswith(k)), ())
        hits = [lab in ok for i in sel for lab in cz["label"][i]]
        verdict = "agrees" if all(hits) else "partly agrees" if any(hits) else "differs"
        if sel:
            lines.append(f"- thesis {zone} ({lo:g}–{hi:g} Hz): "
                         + "; ".join(f"{f[i]:g} Hz {tally(reg['z_cm'][i])}" for i in sel)
                         + f" — {verdict} ({sum(hits)} of {len(hits)} bed-frequencies).")
    scaffold.write_summary(out, lines + [""])


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
