"""Where the universal response holds and where it ends (thesis figs. 5.2c,d, 5.3, 5.4, 5.5;
issue 13 item 8), with replicates.

    python experiments/universality_limits.py            # full mode (~35 min on 2 free cores)
    python experiments/universality_limits.py --quick    # test-sized

``sanchez2012-optimal`` (N = 250, C = 7.6 N s/m), ``R`` independently poured beds per point,
steady means after the MSER-detected start. Four parts:

1. **Contact damping at resonance** (figs. 5.2c, d): at Lz = 0.1225 m and the frequencies
   around the resonance, ``γ_n`` over 0–1e4 with ``γ_s`` at the thesis value, and ``γ_s`` over
   0–1e4 with ``γ_n`` at its value (thesis units, kg s⁻¹ m^-1/2, scaled by the preset's
   reduced modulus as everywhere). The thesis: the total loss per cycle at resonance stays
   constant while its collisional (frictional) part grows with ``γ_n`` (``γ_s``).
2. **A tall box** (fig. 5.5): the same scans at Lz = 0.282 m, where the thesis finds the loss
   depending on ``γ_n, γ_s`` and falling as either rises.
3. **Materials at equal mass ratio** (fig. 5.3): steel, lead and aluminium grains (and walls)
   with the same N and radius; the primary's M, K and C scaled with the density so that
   ``M/m_p``, ``f0`` and the damping ratio stay those of steel (the thesis keeps M/m_p; the
   rest of its protocol is not stated — this is our reading). The FRFs in Z/U should then
   coincide if the response is universal.
4. **Few grains** (fig. 5.4): N = 25, 50, 100 (and 250) at the same total mass (radius
   ∝ N^-1/3) with ``γ_n`` on and off: universality should be lost as N falls.

Every comparison is a Welch 95 % interval across beds. Writes ``data.h5``, ``figure.png``,
``summary.md``; raw sweeps in ``--out/raw`` (not committed).
"""

from __future__ import annotations

import json

import numpy as np

from jaxdamp.analysis.response import resonance
from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.figures.response import draw_replicates
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points, steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

try:
    from .universal_response import SPLIT
    from .universal_response import optimal as base
except ImportError:  # run as a file: python experiments/<name>.py
    from universal_response import SPLIT
    from universal_response import optimal as base

GN, GS = 3660.0, 10980.0  # thesis values
GAMMAS = (0.0, 2500.0, 5000.0, 10000.0)
#: (name, density [kg/m³], E [Pa], ν): steel as the preset; lead and aluminium, handbook values
MATERIALS = (("steel", 8030.0, 2.03e11, 0.28), ("lead", 11340.0, 1.6e10, 0.44),
             ("aluminium", 2700.0, 7.0e10, 0.33))
NS = (25, 50, 100, 250)
#: (part, runs detected stationary, runs), filled by the parts as they read their sweeps
STATIONARITY: list = []


def settings(quick: bool) -> dict:
    if quick:
        return dict(res_freqs=(15.0,), frf_freqs=(14.5, 15.25), gammas=(0.0, 10000.0),
                    lz=(0.1225,), materials=MATERIALS[:2], ns=(50,), duration=0.3, settle=0.15,
                    R=2)
    return dict(res_freqs=(14.5, 15.25), frf_freqs=(12.0, 13.5, 14.5, 15.25, 16.0, 18.5),
                gammas=GAMMAS, lz=(0.1225, 0.282), materials=MATERIALS, ns=NS, duration=1.5,
                settle=0.3, R=3)


def batch(s, ctx, cfg, axes, raw: str, part: str):
    """``axes`` × R beds of ``cfg`` (raw file ``<raw>_R<R>.h5``): the sweep and each run's
    amplitude (steady, else its final 10 %); ``part``'s stationary runs noted in STATIONARITY."""
    res = reuse_or_run(cfg, axes, ctx.raw(f"{raw}_R{s['R']}.h5"), progress=ctx.progress,
                       replicates=s["R"])
    Z, fb = steady_or_window(res, "amplitude")
    STATIONARITY.append((part, Z.size - fb, Z.size))
    return res, Z


def gamma_scan(s, ctx) -> list:
    """Parts 1 and 2: per Lz one batch over (scan, γ value, frequency)."""
    out = []
    for Lz in s["lz"]:
        pts = [(scan, g, f) for scan in ("gamma_n", "gamma_s") for g in s["gammas"]
               for f in s["res_freqs"]]
        axes = Points({"grains.0.material.gamma_n": [g if sc == "gamma_n" else GN
                                                     for sc, g, _ in pts],
                       "grains.0.material.gamma_s": [g if sc == "gamma_s" else GS
                                                     for sc, g, _ in pts],
                       "frequency": [f for *_, f in pts]})
        res, Z = batch(s, ctx, base(s, **{"box.Lz": Lz}), axes, f"gammas_Lz{Lz:g}",
                       f"γ scans at Lz = {Lz} m")
        E, _ = steady_or_window(res, "granular_loss_per_cycle")  # (P, R)
        split = {k: np.asarray(res.replicate_summary[f"{k}_per_cycle"]) for k in SPLIT}
        nf = len(s["res_freqs"])
        for scan in ("gamma_n", "gamma_s"):
            for g in s["gammas"]:
                idx = [i for i, p in enumerate(pts) if p[0] == scan and p[1] == g]
                k = idx[int(np.argmax([Z[i].mean() for i in idx]))]  # the resonant sample
                coll = split["pp_normal"][k] + split["pw_normal"][k]
                fric = split["pp_friction"][k] + split["pw_friction"][k]
                out.append(dict(Lz=Lz, scan=scan, gamma=g, f=pts[k][2], E=E[k], Z=Z[k],
                                coll_share=coll / (coll + fric), n_freqs=nf,
                                wall=float(res.summary["wall_time"])))
    return out


def material_scan(s, ctx) -> list:
    """Part 3: one FRF sweep per material, M, K, C scaled with the density."""
    out = []
    rho0 = MATERIALS[0][1]
    for name, rho, E, nu in s["materials"]:
        k = rho / rho0
        p = presets.get("sanchez2012-optimal").primary
        cfg = base(s, **{"grains.0.material.density": rho, "grains.0.material.E": E,
                         "grains.0.material.nu": nu,  # walls: the grains' material (preset)
                         "primary.M": p.M * k, "primary.K": p.K * k, "primary.C": p.C * k})
        res, Z = batch(s, ctx, cfg, {"frequency": list(s["frf_freqs"])}, f"material_{name}",
                       f"material {name}")  # Z: (F, R)
        peaks = np.array([resonance(s["frf_freqs"], Z[:, r]) for r in range(s["R"])])
        out.append(dict(material=name, density=rho, E=E, nu=nu, scale=k, ZU=Z / p.U,
                        peak=peaks[:, 1] / p.U, f_peak=peaks[:, 0],
                        wall=float(res.summary["wall_time"])))
    return out


def few_grains(s, ctx) -> list:
    """Part 4: N grains of the same total mass, γ_n on and off, at the resonance samples."""
    out = []
    r0 = presets.get("sanchez2012-optimal").grains[0].radius
    for n in s["ns"]:
        radius = r0 * (250 / n) ** (1 / 3)
        cfg = base(s, **{"grains.0.count": n, "grains.0.radius": radius})
        axes = Points({"grains.0.material.gamma_n": [g for g in (GN, 0.0)
                                                     for _ in s["res_freqs"]],
                       "frequency": [f for _ in (GN, 0.0) for f in s["res_freqs"]]})
        res, Z = batch(s, ctx, cfg, axes, f"few_N{n}", f"N = {n}")
        nf = len(s["res_freqs"])
        U = cfg.primary.U
        peak = {g: Z[i * nf:(i + 1) * nf].max(axis=0) / U for i, g in enumerate((GN, 0.0))}
        out.append(dict(N=n, radius=radius, peak_on=peak[GN], peak_off=peak[0.0],
                        wall=float(res.summary["wall_time"])))
    return out


def compute(quick: bool, log, ctx):
    s = settings(quick)
    STATIONARITY.clear()
    r = dict(gammas=gamma_scan(s, ctx), materials=material_scan(s, ctx),
             few=few_grains(s, ctx))
    r["stationarity"] = list(STATIONARITY)
    for row in r["few"]:
        d, h = welch(row["peak_off"], row["peak_on"])
        row.update(d_peak=d, d_peak_ci=h, changed=bool(abs(d) > h) if np.isfinite(h) else None)
        log(f"N = {row['N']}: γ_n off changes the resonant Z/U by "
            f"{scaffold.pm(d, h, '+.2f', '.2f')}")
    ref = r["materials"][0]
    for row in r["materials"]:
        d, h = welch(row["peak"], ref["peak"])
        row.update(d_peak=d, d_peak_ci=h, changed=bool(abs(d) > h) if np.isfinite(h) else None)
    return r, lambda path, prov: write(r, s, path, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(r, s, out, prov):
    wall = sum(x["wall"] for k in ("gammas", "materials", "few") for x in r[k])
    with scaffold.data_file(out, dict(prov, sweep_wall_s=wall), settings=json.dumps(s)) as h:
        for i, row in enumerate(r["gammas"]):
            g = h.create_group(f"gammas/{i:02d}")
            g.attrs.update(Lz=row["Lz"], scan=row["scan"], gamma=row["gamma"], frequency=row["f"])
            g.create_dataset("loss_per_cycle", data=row["E"]).attrs["units"] = "J"
            g.create_dataset("amplitude", data=row["Z"]).attrs["units"] = "m"
            g.create_dataset("collision_share", data=row["coll_share"]).attrs["units"] = "1"
        for row in r["materials"]:
            g = h.create_group(f"materials/{row['material']}")
            g.attrs.update(density=row["density"], E=row["E"], nu=row["nu"], scale=row["scale"])
            g.create_dataset("frequency", data=np.asarray(s["frf_freqs"])).attrs["units"] = "Hz"
            g.create_dataset("Z_over_U", data=row["ZU"]).attrs.update(
                units="1", dims="frequency, replicate")
        for row in r["few"]:
            g = h.create_group(f"few_grains/N{row['N']}")
            g.attrs.update(radius=row["radius"])
            g.create_dataset("peak_on", data=row["peak_on"]).attrs["units"] = "1 (Z/U)"
            g.create_dataset("peak_off", data=row["peak_off"]).attrs["units"] = "1 (Z/U)"
    _figure(r, s, out)
    _summary(r, s, out, prov, wall)


def _figure(r, s, out):
    def se(x):  # the error bars: twice the standard error over the beds
        return 2 * scaffold.standard_error(x)

    fig, axs = scaffold.subplots(1, 3, figsize=(15, 4.4))
    for Lz, ls in zip(s["lz"], ("-", "--")):
        for scan, col in (("gamma_n", "tab:blue"), ("gamma_s", "tab:red")):
            rows = [x for x in r["gammas"] if x["Lz"] == Lz and x["scan"] == scan]
            axs[0].errorbar([x["gamma"] for x in rows], [np.mean(x["E"]) for x in rows],
                            yerr=[se(x["E"]) for x in rows], fmt="o", ls=ls, color=col,
                            capsize=3, label=f"{scan} scanned, Lz = {Lz} m")
    axs[0].set(xlabel="contact damping γ [kg s⁻¹ m^-1/2] (thesis units)",
               ylabel="granular loss per cycle at resonance [J]")
    axs[0].set_title("figs. 5.2(c,d), 5.5: loss at resonance vs γ", fontsize=9)
    axs[0].legend(fontsize=7)
    for row in r["materials"]:
        draw_replicates(axs[1], s["frf_freqs"], row["ZU"], fmt="o-", capsize=3,
                        label=row["material"])
    axs[1].set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]")
    axs[1].set_title("fig. 5.3: materials at equal M/m_p", fontsize=9)
    axs[1].legend(fontsize=7)
    ns = [x["N"] for x in r["few"]]
    for key, lab in (("peak_on", "γ_n on"), ("peak_off", "γ_n = 0")):
        axs[2].errorbar(ns, [np.mean(x[key]) for x in r["few"]],
                        yerr=[se(x[key]) for x in r["few"]], fmt="o-", capsize=3, label=lab)
    axs[2].set(xscale="log", xlabel="number of grains N (same total mass)",
               ylabel="resonant amplitude ratio Z / U  [-]")
    axs[2].set_title("fig. 5.4: universality and the number of grains", fontsize=9)
    axs[2].legend(fontsize=7)
    scaffold.save_figure(fig, out, "figure.png")


def _summary(r, s, out, prov, wall):
    R = s["R"]

    def m(x):  # mean ± SE over the beds
        return scaffold.pm(*scaffold.mean_se(x), 3, 2)

    def change(x):  # the Welch difference of the resonant Z/U and its verdict
        return (f"{scaffold.pm(x['d_peak'], x['d_peak_ci'], '+.2f', '.2f')} — "
                + ("**changed**" if x["changed"] else "not significant"))

    L = [*scaffold.head("Limits of the universal response (thesis figs. 5.2c,d, 5.3, 5.4, "
                         "5.5)", prov, wall),
         f"`sanchez2012-optimal`, R = {R} independently poured beds per point, {s['duration']} "
         "s per run; steady means after the MSER-detected start (collisional share: final "
         "10 % of each run); ± = standard error over the beds, comparisons Welch 95 %.", "",
         "**Stationarity** (runs whose per-period amplitude and dissipation were detected "
         "stationary by MSER; the others are averaged over their final 10 % and weigh as much): "
         + "; ".join(f"{part}: {k} of {n}" for part, k, n in r["stationarity"]) + ". "
         f"{s['duration']} s per run is what two shared cores afforded; where few runs are "
         "stationary, a verdict rests on runs that may still drift.", "",
         "## Contact damping at resonance (figs. 5.2c,d; fig. 5.5 at Lz = 0.282 m)", ""]
    U = presets.get("sanchez2012-optimal").primary.U
    L += scaffold.table(
        ["Lz [m]", "scanned", "γ", "f [Hz]", "loss per cycle [J]", "collisional share", "Z/U"],
        [[x["Lz"], x["scan"], f"{x['gamma']:g}", f"{x['f']:g}", m(x["E"]), m(x["coll_share"]),
          m(x["Z"] / U)] for x in r["gammas"]])
    L += [""]
    for Lz in s["lz"]:
        for scan in ("gamma_n", "gamma_s"):
            rows = [x for x in r["gammas"] if x["Lz"] == Lz and x["scan"] == scan]
            d, h = welch(rows[-1]["E"], rows[0]["E"])
            L.append(f"- Lz = {Lz} m, {scan} from {rows[0]['gamma']:g} to {rows[-1]['gamma']:g}: "
                     f"loss at resonance changes by {scaffold.pm(d, h, '+.3g', '.2g', unit='J')} "
                     "(Welch 95 %) — "
                     + ("**changed**" if abs(d) > h else "constant within the interval") + ".")
    L += ["", "## Materials at equal M/m_p (fig. 5.3)", ""]
    L += scaffold.table(
        ["material", "ρ [kg/m³]", "E [Pa]", "ν", "M, K, C scale", "resonant Z/U", "vs steel"],
        [[x["material"], f"{x['density']:g}", f"{x['E']:.3g}", x["nu"], f"{x['scale']:.3f}",
          m(x["peak"]), "reference" if x is r["materials"][0] else change(x)]
         for x in r["materials"]])
    L += ["", "## Few grains (fig. 5.4)", ""]
    L += scaffold.table(
        ["N", "radius [mm]", "resonant Z/U, γ_n on", "γ_n = 0", "change (Welch 95 %)"],
        [[x["N"], f"{1e3 * x['radius']:.2f}", m(x["peak_on"]), m(x["peak_off"]), change(x)]
         for x in r["few"]])
    scaffold.write_summary(out, L)


if __name__ == "__main__":
    main()
