"""Where the universal response holds and where it ends (thesis figs. 5.2c,d, 5.3, 5.4, 5.5;
issue 13 item 8), with replicates.

    python experiments/universality_limits.py            # full mode (~35 min on 2 free cores)
    python experiments/universality_limits.py --quick    # test-sized

``sanchez2012-optimal``, ``R`` poured beds per point, MSER steady means, Welch 95 % comparisons.
(1) γ_n over 0–1e4 at the thesis γ_s and vice versa, at resonance (figs. 5.2c,d: the loss stays
constant, its collisional (frictional) part grows with γ_n (γ_s)); (2) the same at Lz = 0.282 m
(fig. 5.5: the loss falls as either rises); (3) steel, lead, aluminium grains and walls, M, K, C
scaled with the density (M/m_p, f0, damping ratio those of steel: our reading of fig. 5.3; if
universal, the FRFs in Z/U coincide); (4) N = 25…250 at the same total mass, γ_n on and off
(fig. 5.4: universality lost as N falls). Writes ``data.h5``, then ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.response import resonance
from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.figures.response import draw_replicates
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points, steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

try:
    from .universal_response import SPLIT, optimal
except ImportError:  # run as a file: python experiments/<name>.py
    from universal_response import SPLIT, optimal

GN, GS = 3660.0, 10980.0  # thesis values
#: (name, density [kg/m³], E [Pa], ν): steel as the preset; lead and aluminium, handbook values
MATERIALS = (("steel", 8030.0, 2.03e11, 0.28), ("lead", 11340.0, 1.6e10, 0.44),
             ("aluminium", 2700.0, 7.0e10, 0.33))
STATIONARITY: list = []  # (part, runs detected stationary, runs), filled by the parts


def settings(quick: bool) -> dict:
    if quick:
        return dict(res_freqs=(15.0,), frf_freqs=(14.5, 15.25), gammas=(0.0, 10000.0),
                    lz=(0.1225,), materials=MATERIALS[:2], ns=(50,), duration=0.3, settle=0.15, R=2)
    return dict(res_freqs=(14.5, 15.25), frf_freqs=(12.0, 13.5, 14.5, 15.25, 16.0, 18.5),
                gammas=(0.0, 2500.0, 5000.0, 10000.0), lz=(0.1225, 0.282), materials=MATERIALS,
                ns=(25, 50, 100, 250), duration=1.5, settle=0.3, R=3)


def batch(s, ctx, cfg, axes, raw: str, part: str):
    """The sweep of ``axes`` × R beds of ``cfg`` and its steady amplitudes; notes ``part``'s."""
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
        gn = [g if sc == "gamma_n" else GN for sc, g, _ in pts]
        gs = [g if sc == "gamma_s" else GS for sc, g, _ in pts]
        axes = Points({"grains.0.material.gamma_n": gn, "grains.0.material.gamma_s": gs,
                       "frequency": [f for *_, f in pts]})
        res, Z = batch(s, ctx, optimal(s, **{"box.Lz": Lz}), axes, f"gammas_Lz{Lz:g}",
                       f"γ scans at Lz = {Lz} m")
        E, _ = steady_or_window(res, "granular_loss_per_cycle")  # (P, R)
        split = {k: np.asarray(res.replicate_summary[f"{k}_per_cycle"]) for k in SPLIT}
        nf = len(s["res_freqs"])
        for j, (scan, g, _) in enumerate(pts[::nf]):  # the resonant sample of each (scan, γ):
            k = j * nf + int(np.argmax(Z[j * nf:(j + 1) * nf].mean(-1)))
            coll, fric = (split[a][k] + split[b][k] for a, b in (SPLIT[:2], SPLIT[2:]))
            out.append(dict(Lz=Lz, scan=scan, gamma=g, f=pts[k][2], E=E[k], Z=Z[k], n_freqs=nf,
                            coll_share=coll / (coll + fric), wall=float(res.summary["wall_time"])))
    return out


def material_scan(s, ctx) -> list:
    """Part 3: one FRF sweep per material, M, K, C scaled with the density."""
    out, p = [], presets.get("sanchez2012-optimal").primary
    for name, rho, E, nu in s["materials"]:
        k = rho / MATERIALS[0][1]
        cfg = optimal(s, **{"grains.0.material.density": rho, "grains.0.material.E": E,
                            "grains.0.material.nu": nu,  # walls: the grains' material (preset)
                            "primary.M": p.M * k, "primary.K": p.K * k, "primary.C": p.C * k})
        res, Z = batch(s, ctx, cfg, {"frequency": list(s["frf_freqs"])}, f"material_{name}",
                       f"material {name}")  # Z: (F, R)
        pk = peaks(s["frf_freqs"], Z)
        out.append(dict(material=name, density=rho, E=E, nu=nu, scale=k, ZU=Z / p.U,
                        peak=pk[:, 1] / p.U, f_peak=pk[:, 0], wall=float(res.summary["wall_time"])))
    return out


def few_grains(s, ctx) -> list:
    """Part 4: N grains of the same total mass, γ_n on and off, at the resonance samples."""
    out, r0 = [], presets.get("sanchez2012-optimal").grains[0].radius
    for n in s["ns"]:
        radius = r0 * (250 / n) ** (1 / 3)
        cfg = optimal(s, **{"grains.0.count": n, "grains.0.radius": radius})
        axes = Points({"grains.0.material.gamma_n": [g for g in (GN, 0.0) for _ in s["res_freqs"]],
                       "frequency": list(s["res_freqs"]) * 2})
        res, Z = batch(s, ctx, cfg, axes, f"few_N{n}", f"N = {n}")
        on, off = Z.reshape(2, -1, s["R"]).max(axis=1) / cfg.primary.U  # γ_n on, off
        out.append(dict(N=n, radius=radius, peak_on=on, peak_off=off,
                        wall=float(res.summary["wall_time"])))
    return out


def peaks(f, Z):
    """Per bed of an FRF ``Z`` (F, R): its resonance frequency and peak (:func:`resonance`)."""
    return np.array([resonance(f, Z[:, r]) for r in range(Z.shape[1])])


def compare(materials, few):
    """Each material's resonant Z/U against steel's and, per N, γ_n off against on: the Welch
    difference (``d_peak``), its 95 % half-width and whether it excludes zero (``changed``)."""
    for x, a, b in ([(x, x["peak"], materials[0]["peak"]) for x in materials]
                    + [(x, x["peak_off"], x["peak_on"]) for x in few]):
        d, h = welch(a, b)
        x.update(d_peak=d, d_peak_ci=h, changed=bool(abs(d) > h) if np.isfinite(h) else None)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    STATIONARITY.clear()
    r = dict(gammas=gamma_scan(s, ctx), materials=material_scan(s, ctx), few=few_grains(s, ctx),
             stationarity=list(STATIONARITY))  # filled by the parts, evaluated after them
    compare(r["materials"], r["few"])
    for row in r["few"]:
        log(f"N = {row['N']}: γ_n off: ΔZ/U = {scaffold.pm(row['d_peak'], row['d_peak_ci'])}")
    return r, lambda path, prov: record(r, s, path, prov)


def record(r, s, out, prov):
    wall = sum(x["wall"] for k in ("gammas", "materials", "few") for x in r[k])
    with scaffold.data_file(out, dict(prov, sweep_wall_s=wall), settings=s,
                            stationarity=r["stationarity"]) as h:
        for i, row in enumerate(r["gammas"]):
            g = h.create_group(f"gammas/{i:02d}")
            g.attrs.update(Lz=row["Lz"], scan=row["scan"], gamma=row["gamma"], frequency=row["f"])
            for name, k, u in (("loss_per_cycle", "E", "J"), ("amplitude", "Z", "m"),
                               ("collision_share", "coll_share", "1")):
                put(g, name, row[k], u)
        for row in r["materials"]:
            g = h.create_group(f"materials/{row['material']}")
            g.attrs.update(density=row["density"], E=row["E"], nu=row["nu"], scale=row["scale"])
            g.create_dataset("frequency", data=np.asarray(s["frf_freqs"])).attrs["units"] = "Hz"
            put(g, "Z_over_U", row["ZU"], "1", dims="frequency, replicate")
        for row in r["few"]:
            g = h.create_group(f"few_grains/N{row['N']}")
            g.attrs.update(radius=row["radius"])
            g.create_dataset("peak_on", data=row["peak_on"]).attrs["units"] = "1 (Z/U)"
            g.create_dataset("peak_off", data=row["peak_off"]).attrs["units"] = "1 (Z/U)"


def report(data, out):
    s, prov, U = data.attrs["settings"], data.attrs, presets.get("sanchez2012-optimal").primary.U
    row = lambda g, **kw: dict(g, **g.attrs, **kw)  # noqa: E731 - a group's data and attributes
    gam = [row(g) for _, g in sorted(data["gammas"].items())]
    scans = [gam[i:i + len(s["gammas"])] for i in range(0, len(gam), len(s["gammas"]))]
    mats = [row(data["materials"][m], material=m) for m, *_ in s["materials"]]
    few = [row(data["few_grains"][f"N{n}"], N=n) for n in s["ns"]]
    for x in mats:
        x.update(peak=peaks(s["frf_freqs"], x["Z_over_U"])[:, 1])
    compare(mats, few)

    fig, axs = scaffold.subplots(1, 3, figsize=(15, 4.4))
    for j, rows in enumerate(scans):  # γ_n, then γ_s scanned, per Lz
        draw_replicates(axs[0], [x["gamma"] for x in rows], [x["loss_per_cycle"] for x in rows],
                        fmt="o", ls=("-", "--")[j // 2], color=("tab:blue", "tab:red")[j % 2],
                        label=f"{rows[0]['scan']} scanned, Lz = {rows[0]['Lz']} m")
    axs[0].set(xlabel="contact damping γ [kg s⁻¹ m^-1/2] (thesis units)",
               ylabel="granular loss per cycle at resonance [J]",
               title="figs. 5.2(c,d), 5.5: loss at resonance vs γ")
    for x in mats:
        draw_replicates(axs[1], s["frf_freqs"], x["Z_over_U"], label=x["material"])
    axs[1].set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]",
               title="fig. 5.3: materials at equal M/m_p")
    for key, lab in (("peak_on", "γ_n on"), ("peak_off", "γ_n = 0")):
        draw_replicates(axs[2], s["ns"], [x[key] for x in few], label=lab)
    axs[2].set(xscale="log", xlabel="number of grains N (same total mass)",
               ylabel="resonant amplitude ratio Z / U  [-]",
               title="fig. 5.4: universality and the number of grains")
    for ax in axs:
        ax.title.set_fontsize(9)
        ax.legend(fontsize=7)
    scaffold.save_figure(fig, out, "figure.png")

    m = lambda x: scaffold.pm(*scaffold.mean_se(x), 3, 2)  # noqa: E731 - mean ± SE over beds
    change = lambda x: (f"{scaffold.pm(x['d_peak'], x['d_peak_ci'], '+.2f', '.2f')} — "  # noqa: E731
                        + ("**changed**" if x["changed"] else "not significant"))
    L = [*scaffold.head("Limits of the universal response (thesis figs. 5.2c,d, 5.3, 5.4, "
                         "5.5)", prov, prov["sweep_wall_s"]),
         f"`sanchez2012-optimal`, R = {s['R']} independently poured beds per point, "
         f"{s['duration']} s per run; ± = standard error over the beds, comparisons Welch 95 %; "
         "the collisional share is over the final 10 % of each run.", "",
         "**Stationarity** (runs detected stationary by MSER; the others enter with their final "
         "10 %): " + "; ".join(f"{part}: {k} of {n}" for part, k, n in prov["stationarity"])
         + ". Where few runs are stationary, a verdict rests on runs that may still drift.", "",
         "## Contact damping at resonance (figs. 5.2c,d; fig. 5.5 at Lz = 0.282 m)", ""]
    L += scaffold.table(
        ["Lz [m]", "scanned", "γ", "f [Hz]", "loss per cycle [J]", "collisional share", "Z/U"],
        [[x["Lz"], x["scan"], f"{x['gamma']:g}", f"{x['frequency']:g}", m(x["loss_per_cycle"]),
          m(x["collision_share"]), m(x["amplitude"] / U)] for x in gam])
    L += [""]
    for a, b in ((rows[0], rows[-1]) for rows in scans):
        d, h = welch(b["loss_per_cycle"], a["loss_per_cycle"])
        L.append(f"- Lz = {a['Lz']} m, {a['scan']} from {a['gamma']:g} to {b['gamma']:g}: loss "
                 f"at resonance changes by {scaffold.pm(d, h, '+.3g', '.2g', unit='J')} (Welch "
                 f"95 %) — {'**changed**' if abs(d) > h else 'constant within the interval'}.")
    L += ["", "## Materials at equal M/m_p (fig. 5.3)", ""]
    L += scaffold.table(
        ["material", "ρ [kg/m³]", "E [Pa]", "ν", "M, K, C scale", "resonant Z/U", "vs steel"],
        [[x["material"], f"{x['density']:g}", f"{x['E']:.3g}", x["nu"], f"{x['scale']:.3f}",
          m(x["peak"]), "reference" if x is mats[0] else change(x)] for x in mats])
    L += ["", "## Few grains (fig. 5.4)", ""]
    L += scaffold.table(
        ["N", "radius [mm]", "resonant Z/U, γ_n on", "γ_n = 0", "change (Welch 95 %)"],
        [[x["N"], f"{1e3 * x['radius']:.2f}", m(x["peak_on"]), m(x["peak_off"]), change(x)]
         for x in few])
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
